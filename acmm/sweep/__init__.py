"""Batch sweeps and Monte Carlo robustness studies of the ACMM closed loop (issue 7).

A sweep (:mod:`acmm.sweep.config`) varies plant parameters of one or more base configs and
runs one nonlinear closed-loop simulation (ch. 6) per case.

Cases
    Case ``i`` of a Monte Carlo sweep draws its parameters from
    ``numpy.random.default_rng(SeedSequence([seed, i]))``, so every case is reproducible from
    (base config, case index, seed) alone, whatever the order or the machine that runs it.  The
    seed does not involve the base: case ``i`` of every base gets the same draws (common random
    numbers) unless resampling of an unphysical inertia makes them differ.  Grid case ``i`` is
    the ``i``-th point of the Cartesian product (last parameter fastest).

Perturbed plant
    I_pert = s · (I_nom ∘ (1 + δ)) element by element (δ = dI11 … dI23 symmetric, s =
    ``inertia_scale``), the same factors at every design point/level of a schedule.  An inertia
    that is not positive definite or violates the triangle inequality is redrawn (``unphysical:
    resample``; the number of draws is recorded) or recorded as verdict ``unphysical``.  The bias
    *torque* (ft·lbf) is external and is held at its nominal value (plus ``bias_*``), so the
    plant's true TEA moves with the inertia: at each level it is the equilibrium connected to
    the level's design TEA as the plant moves from nominal to perturbed
    (:mod:`acmm.sweep.case`); where that branch folds, the root continued from
    LVLH (:func:`acmm.model.tea.solve_tea`'s physical branch).  No equilibrium → verdict
    ``no_equilibrium`` (not simulated).

Controller
    ``design: fixed`` keeps the nominal gain schedule.  Its TEA estimate θ̂* is the nominal one
    (``tea_estimate: nominal``, the default: the controller does not know the perturbation) or
    the perturbed plant's own TEA (``true``: exact mass properties, report ch. 5.1); a scheduled
    gain is evaluated at that estimate.  ``design: redesign`` re-runs TEA → linearization →
    sector LQR (→ schedule) for the perturbed plant.  The run starts at the plant's true TEA plus
    the initial offset, with the LVLH rate.

Metrics (one row per case)
    verdict, time to divergence, peak and steady (second half of the run) attitude error about
    the plant's true TEA per axis, peak |h_i| per axis, time spent torque- or momentum-saturated.

Execution and results
    Cases run on a ``concurrent.futures`` executor: in-process for one worker, a process pool
    otherwise, or a Dask cluster (``scheduler=ADDRESS``).  Every finished case is appended to
    ``<run dir>/sweep.journal`` (one JSON line, flushed and fsynced) and ``sweep.h5`` is rebuilt
    atomically from the journal every few seconds and at the end, so a killed sweep leaves a
    valid journal (a torn last line is ignored) and a valid, possibly partial ``sweep.h5``
    (root attribute ``complete``).  ``resume=True`` skips the cases already in the journal.

Package layout
    :mod:`~acmm.sweep.config` (the sweep file and its validation), :mod:`~acmm.sweep.cases`
    (pure case generation: draws, grids, perturbation), :mod:`~acmm.sweep.case` (running one case
    and the margin search), :mod:`~acmm.sweep.dask_settings` (the recommended Dask configuration
    of a sweep cluster), :mod:`~acmm.sweep.journal` (the group-commit journal),
    :mod:`~acmm.sweep.output` (HDF5, CSV, figures) and :mod:`~acmm.sweep.run` (the driver, its
    executors, tasks and chunks).
"""
