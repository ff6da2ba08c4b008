"""``acmm report``: every table and figure of CR-185644 regenerated and compared, in one page.

The report covers both products (``acmm``, Part II, and ``qpp``, Part III) and sits above them:
it imports both, neither imports it.

:func:`build_report` gathers the results it needs (:mod:`acmm.report.gather`: reusing
``<root>/<name>/*.h5`` whose ``design_hash`` / ``config_hash`` match the packaged configs, else
running the stage; ``root`` is the report's own, ``<out>/results`` by default, never a user's
``runs/<name>/``), writes one section per module of :mod:`acmm.report.sections` (each with declared
inputs), keeps the printed-number ledger (:mod:`acmm.report.ledger`), draws the figures
(:mod:`acmm.report.figures`, style :mod:`acmm.report.figure_style`: vector PDF + PNG) and writes

* ``<out>/index.html`` — self-contained (PNG figures embedded as base64; no server needed),
* ``<out>/report.md`` — the same content in Markdown (figures as relative files),
* ``<out>/figures/*.pdf|png`` — every figure,
* ``<out>/manifest.json`` — SHA-256 of every HDF5 dataset used (timing datasets excluded),
  compared with the previous report's manifest when one exists (:mod:`acmm.report.manifest`).

Sections: Table 1; gain schedules and pole maps (Figs 5.3–5.26); claim 1 (Figs 6.2–6.13); the
130-orbit stair-case (Figs 6.14–6.30); ±30 % robustness; QPP ch. 13 and 14; errata; printed
numbers; determinism; provenance.  Every printed number the project reproduces is marked
"matched to printed precision" (|computed − printed| ≤ half a unit of the last printed digit),
"consistent with the printed bound", or carries its explanation.
"""
from __future__ import annotations

from acmm.report.build import ReportResult, build_report
from acmm.report.constants import FAST_ORBITS, SECTIONS, TIMING_DATASETS
from acmm.report.context import SectionWriter
from acmm.report.document import Doc, render_html, render_markdown
from acmm.report.figures_qpp import fig_circle, fig_qpp
from acmm.report.figures import fig_claim1, fig_gain_schedule, fig_pole_maps, fig_robustness
from acmm.report.figures_staircase import fig_staircase
from acmm.report.gather import (FAST_SWEEP_ORBITS, FAST_SWEEP_RUNS, SWEEP_CONFIG, Gathered, gather, robustness_result)
from acmm.report.stage_results import (StageRun, acmm_config, ensure_acmm_design, ensure_acmm_simulation, ensure_qpp, qpp_config)
from acmm.report.ledger import (STATUS_BOUND, STATUS_EXPLAINED, STATUS_MATCHED, STATUS_UNEXPLAINED, PrintedNumber,
                           check_printed, matches_printed, printed_decimals)
from acmm.report.manifest import build_manifest, compare_manifests, dataset_hashes
from acmm.report.sections.errata import errata_rows


class _Report(SectionWriter):
    """Compatibility: one writer whose methods run single sections that need no other section's output."""

    def robustness(self):
        from acmm.report.sections import robustness

        robustness.build(self)

    def staircase(self):
        from acmm.report.sections import staircase

        staircase.build(self)


__all__ = [
    "FAST_ORBITS", "FAST_SWEEP_ORBITS", "FAST_SWEEP_RUNS", "SECTIONS", "STATUS_BOUND", "STATUS_EXPLAINED",
    "STATUS_MATCHED", "STATUS_UNEXPLAINED", "SWEEP_CONFIG", "TIMING_DATASETS", "Doc", "Gathered",
    "PrintedNumber", "ReportResult", "SectionWriter", "StageRun", "acmm_config", "build_manifest",
    "build_report", "check_printed", "compare_manifests", "dataset_hashes", "ensure_acmm_design",
    "ensure_acmm_simulation", "ensure_qpp", "errata_rows", "fig_circle", "fig_claim1", "fig_gain_schedule",
    "fig_pole_maps", "fig_qpp", "fig_robustness", "fig_staircase", "gather", "matches_printed",
    "printed_decimals", "qpp_config", "render_html", "render_markdown", "robustness_result",
]
