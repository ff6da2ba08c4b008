"""Batch sweeps and Monte Carlo robustness studies of the ACMM closed loop (issue 7).

A sweep (:mod:`acmm.sweep.config`) varies plant parameters of one or more base configs and
runs one nonlinear closed-loop simulation (ch. 6) per case.  Case ``i`` of a Monte Carlo sweep
draws from ``numpy.random.default_rng(SeedSequence([seed, i]))``, so every case is reproducible
from (base config, case index, seed) alone; grid case ``i`` is the ``i``-th point of the
Cartesian product (last parameter fastest).  The perturbed plant, the controller, the metrics of
a row, the journal and ``--resume`` are described in docs/howto/sweeps.md.

Package layout
    :mod:`~acmm.sweep.config` (the sweep file and its validation), :mod:`~acmm.sweep.cases`
    (pure case generation: draws, grids, perturbation), :mod:`~acmm.sweep.case` (running one case
    and the margin search), :mod:`~acmm.sweep.dask_settings` (the recommended Dask configuration
    of a sweep cluster), :mod:`~acmm.sweep.journal` (the group-commit journal),
    :mod:`~acmm.sweep.output` (HDF5, CSV, figures) and :mod:`~acmm.sweep.run` (the driver, its
    executors, tasks and chunks).
"""
