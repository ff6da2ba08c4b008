"""Section determinism: dataset hashes compared with the previous report."""
from __future__ import annotations

from acmm.report.constants import TIMING_DATASETS
from acmm.report.context import SectionWriter


def build(rep: SectionWriter, cmp: dict, manifest: dict) -> None:
    """The manifest summary and its comparison with the previous report (``cmp``).

    Parameters
    ----------
    rep : acmm.report.context.SectionWriter
        The section's inputs and output.
    cmp : dict
        :func:`acmm.report.manifest.compare_manifests` of this and the previous manifest.
    manifest : dict
        This report's manifest (:func:`acmm.report.manifest.build_manifest`).
    """
    rep.section("determinism")
    n_ds = sum(len(f["datasets"]) for f in manifest["files"].values())
    rep.doc.p(f"{len(manifest['files'])} HDF5 files, {n_ds} datasets hashed (SHA-256 of dtype, shape and bytes; "
              f"timing datasets {', '.join(TIMING_DATASETS)} and file attributes such as the creation time excluded); "
              "hashes are stored in manifest.json next to this page.")
    if cmp["status"] == "no previous report":
        rep.doc.p("No previous report in this directory: nothing to compare yet. Run the report again "
                  "(with --rerun to recompute every stage) to compare.")
    else:
        rec = cmp["recomputed"]
        rep.doc.p(f"Compared with the previous report of {cmp['previous']}: {cmp['compared']} datasets, "
                  f"{rec} of {len(manifest['files'])} files recomputed since then "
                  f"({'the others reused, identical by construction' if rec < len(manifest['files']) else 'none reused'}). "
                  f"Result: {cmp['status'].upper()}"
                  + (f" ({len(cmp['differences'])} datasets differ: {', '.join(cmp['differences'][:10])})"
                     if cmp["differences"] else " — every dataset has the same hash." if cmp["compared"]
                     else " — no file of the previous report has the same name and config.")
                  + (f" Not compared (new or changed config): {', '.join(cmp['missing'][:10])}." if cmp["missing"] else ""))
