"""``acmm report``: every table and figure of CR-185644 regenerated and compared, in one page.

The report covers both products (``acmm``, Part II, and ``qpp``, Part III) and sits above them:
it imports both, neither imports it.

:func:`build_report` gathers the results it needs (:mod:`acmm.report.gather`: reusing
``<root>/<name>/*.h5`` whose ``design_hash`` / ``config_hash`` match the packaged configs, else
running the stage; ``root`` is the report's own, ``<out>/results`` by default, never a user's
``runs/<name>/``), writes one section per module of :mod:`acmm.report.sections` (each with declared
inputs), keeps the printed-number ledger (:mod:`acmm.report.ledger`), draws the figures
(in the section that shows each, style :mod:`acmm.report.figure_style`: vector PDF + PNG) and writes

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
