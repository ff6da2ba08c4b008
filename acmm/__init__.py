"""acmm — attitude control / momentum management of Space Station Freedom.

Implements Part II of NASA CR-185644 (Parlos & Jayasuriya, 1990): the nonlinear
rigid-body model (eqs 3.1–3.9), the torque-equilibrium attitude (eqs 4.1–4.3),
the 24-state linearization (eqs 4.4–4.50), sector-constrained LQR (ch. 5.2),
quadratic gain schedules (ch. 5.3) and the nonlinear stair-case simulation (ch. 6).

Subpackages: :mod:`acmm.model` (the plant), :mod:`acmm.design` (the controller),
:mod:`acmm.simulate` (the nonlinear closed loop), :mod:`acmm.sweep`, :mod:`acmm.plots`,
:mod:`acmm.io` (configs and stage files), :mod:`acmm.stages` (config in, results out),
:mod:`acmm.report` and :mod:`acmm.cli`.  The Python API is :mod:`acmm.api`
(``load_config``, ``design``, ``Design``, ``linearize``, ``simulate``).
"""
__version__ = "0.1.0"

#: The data package of the configs shipped with the distribution (the source tree's ``configs/``
#: folder, mapped by ``pyproject.toml``), looked up by name with importlib.resources.
PACKAGED_CONFIGS = "acmm.configs"
#: The packaged config ``acmm`` reads when none is named: the report's stair-case.
DEFAULT_CONFIG = "staircase"

#: acmm's work limits (issue 13: nothing hangs), each raised through ``ACMM_LIMIT_<NAME>``
#: (:func:`acmm_qpp.limits.limit`):
#:
#: =====================  ============  =======================================================
#: name                   default       what it bounds
#: =====================  ============  =======================================================
#: SIM_SAMPLES            2 000 000     output samples of one acmm simulation
#: DESIGN_POINTS          400           design points of one acmm schedule (one sector LQR each)
#: SWEEP_DRAWS            2 000 000     expected Monte Carlo draws of a sweep (resampling included)
#: SWEEP_CASES            1 000 000     cases of a sweep (all bases)
#: SWEEP_ORBITS           100 000       simulated orbits of a sweep (cases × orbits per run)
#: SWEEP_DESIGNS          50 000        LQR designs of a ``design: redesign`` sweep (cases × points)
#: DASK_CONNECT_SECONDS   5             how long ``--scheduler`` waits for a Dask scheduler, s
#: =====================  ============  =======================================================
LIMITS = {
    "SIM_SAMPLES": 2_000_000,
    "DESIGN_POINTS": 400,
    "SWEEP_DRAWS": 2_000_000,
    "SWEEP_CASES": 1_000_000,
    "SWEEP_ORBITS": 100_000,
    "SWEEP_DESIGNS": 50_000,
    "DASK_CONNECT_SECONDS": 5,
}
