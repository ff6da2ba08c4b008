"""Work and size limits shared by ``acmm`` and ``qpp`` (issue 13: nothing hangs).

Every limit has a default here and can be changed without editing code through an environment
variable ``ACMM_LIMIT_<NAME>`` (e.g. ``ACMM_LIMIT_CONFIG_BYTES=4000000``).  A config that would
exceed a limit is refused at validation with one line naming the field, the limit and the
variable that raises it (QPP_RHS_EVALS, which only the integration can see, when it is reached).

=====================  ============  ==========================================================
name                   default       what it bounds
=====================  ============  ==========================================================
CONFIG_BYTES           1 000 000     size of a YAML config file, bytes
YAML_DEPTH             32            nesting depth of mappings/lists in a YAML config
YAML_NODES             20 000        scalars + collections in a YAML config (aliases expanded)
SIM_SAMPLES            2 000 000     output samples of one acmm simulation
DESIGN_POINTS          400           design points of one acmm schedule (one sector LQR each)
QPP_PERIODS            10 000        periods of a qpp signal or nonlinearity (ω·t_final/2π)
QPP_WORK               50 000        qpp simulation work: t_final × fastest closed-loop rate (1/s)
                                     × (scenarios + 1); ~2.4 ms per unit, so ~2 min at the limit
QPP_RHS_EVALS          3 000 000     evaluations of a qpp loop's right-hand side in one run (~40 µs
                                     each, so ~2 min): the runtime bound where QPP_WORK cannot see
                                     the rate (a t inside an expression nonlinearity); the shipped
                                     examples take ~15 000
QPP_SAMPLES            2 000 000     qpp output samples × (scenarios + 1)
QPP_SECTOR_POINTS      5 000 000     points at which a qpp expression's sector is sampled
                                     (per channel: parameter samples × the grid of the outputs
                                     it depends on × times; ~3 µs each)
SWEEP_DRAWS            2 000 000     expected Monte Carlo draws of a sweep (resampling included)
SWEEP_CASES            1 000 000     cases of a sweep (all bases)
SWEEP_ORBITS           100 000       simulated orbits of a sweep (cases × orbits per run)
SWEEP_DESIGNS          50 000        LQR designs of a ``design: redesign`` sweep (cases × points)
DASK_CONNECT_SECONDS   5             how long ``--scheduler`` waits for a Dask scheduler, s
=====================  ============  ==========================================================
"""
from __future__ import annotations

import os

from acmm_qpp.errors import ConfigError

DEFAULTS: dict[str, float] = {
    "CONFIG_BYTES": 1_000_000,
    "YAML_DEPTH": 32,
    "YAML_NODES": 20_000,
    "SIM_SAMPLES": 2_000_000,
    "DESIGN_POINTS": 400,
    "QPP_PERIODS": 10_000,
    "QPP_WORK": 50_000,
    "QPP_RHS_EVALS": 3_000_000,
    "QPP_SAMPLES": 2_000_000,
    "QPP_SECTOR_POINTS": 5_000_000,
    "SWEEP_DRAWS": 2_000_000,
    "SWEEP_CASES": 1_000_000,
    "SWEEP_ORBITS": 100_000,
    "SWEEP_DESIGNS": 50_000,
    "DASK_CONNECT_SECONDS": 5,
}

#: Physical plausibility ranges (report units) beyond which a value is refused as a typo or an
#: overflow hazard: |value| ≤ bound.  The Space Station is ~1e7–1e8 slug·ft², bias torques are a
#: few ft·lbf, CMG momentum ~1e4 ft·lbf·s; the bounds leave orders of magnitude of headroom while
#: keeping every derived quantity (ω²·I, I·ω·h, Riccati products) far from float overflow.
PHYSICAL_MAX = {
    "inertia": 1e13,      # slug·ft²
    "torque": 1e9,        # ft·lbf
    "momentum": 1e12,     # ft·lbf·s
    "qpp": 1e12,          # any qpp matrix entry, gain, amplitude or weight
}


def limit(name: str) -> float:
    """The value of limit ``name`` (``ACMM_LIMIT_<name>`` overrides the default).

    Parameters
    ----------
    name : str
        A key of :data:`DEFAULTS`.

    Returns
    -------
    float
        The limit, in the unit of the table above (bytes, samples, 1, s, ...).

    Raises
    ------
    ConfigError
        The variable is set to something else than a positive finite number (it was ignored
        without a word: a review).
    """
    raw = os.environ.get(f"ACMM_LIMIT_{name}")
    if raw is None or not raw.strip():
        return DEFAULTS[name]
    try:
        value = float(raw)
    except ValueError:
        value = float("nan")
    if not 0 < value < float("inf"):
        raise ConfigError(f"ACMM_LIMIT_{name}: must be a positive number (got {raw!r}); unset it for the "
                          f"default {DEFAULTS[name]:.6g}")
    return value


def how_to_raise(name: str) -> str:
    """The hint appended to a refusal: which environment variable raises the limit.

    Parameters
    ----------
    name : str
        A key of :data:`DEFAULTS`.

    Returns
    -------
    str
        The hint, with the current value of the limit.
    """
    return f"limit {limit(name):.6g}; set ACMM_LIMIT_{name} to change it"
