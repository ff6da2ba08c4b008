"""Section printed numbers: the whole ledger, reproduced or explained."""
from __future__ import annotations

from acmm.report.context import SectionWriter
from acmm.report.ledger import status_text


def build(ctx: SectionWriter, ledger: list) -> None:
    """Every printed number of ``ledger`` (all sections before this one) with its status.

    Parameters
    ----------
    ctx : acmm.report.context.SectionWriter
        The section's inputs and output.
    ledger : list of acmm.report.ledger.PrintedNumber
        The entries of every earlier section.
    """
    ctx.section("printed")
    counts = {}
    for pn in ledger:
        counts[pn.status] = counts.get(pn.status, 0) + 1
    ctx.doc.p("Every printed number this report compares, with its status. Matched: |computed − printed| ≤ "
              "half a unit of the last printed digit. Summary: " +
              "; ".join(f"{v} {k}" for k, v in sorted(counts.items())) + ".")
    ctx.doc.table(["section", "quantity", "printed", "computed", "unit", "status"],
                  [[p.section, p.quantity, p.printed, "—" if p.computed is None else f"{p.computed:.6g}",
                    p.unit, status_text(p)] for p in ledger])
