"""Pure case generation: physical inertia checks, Monte Carlo draws, grid points and the
perturbed inertia of case ``i`` (reproducible from base, index and seed alone)."""
from __future__ import annotations

import itertools
from typing import Optional

import numpy as np

from acmm.model.inertia import perturb_inertia, unphysical_reason
from acmm.sweep.spec import AXES, PARAMETERS, SHORTHANDS

#: Verdict codes stored in ``verdict_code``.
VERDICTS = ("bounded", "not_settled", "diverged", "no_equilibrium", "unphysical", "design_failed",
            "tea_failed")


def draw_parameters(rng: np.random.Generator, spec) -> dict:
    """One draw of every Monte Carlo parameter, in the order the config lists them.

    Parameters
    ----------
    rng : numpy.random.Generator
        The case's random generator.
    spec : SweepSpec
        The sweep's spec (its ``monte_carlo`` section).

    Returns
    -------
    dict
        Parameter name → drawn value (in the parameter's units, see :data:`PARAMETERS`).
    """
    out = {}
    for key, dist in spec.monte_carlo.items():
        for name in SHORTHANDS.get(key, [key]):
            p = PARAMETERS[name]
            if dist.uniform is not None:
                out[name] = float(rng.uniform(*dist.uniform))
            elif dist.normal is not None:
                out[name] = float(rng.normal(*dist.normal))
            else:
                h = dist.percent / 100.0
                out[name] = float(rng.uniform(p.neutral - h, p.neutral + h))
    return out


def case_values(spec, index: int, inertias: np.ndarray) -> tuple[dict, int, Optional[str]]:
    """Parameters of case ``index`` (per-base) of a sweep.

    Parameters
    ----------
    spec : SweepSpec
    index : int
        Case index within the base (0 … n_cases − 1).
    inertias : (P, 3, 3) array
        The base's inertia at every design point/level (slug·ft²); the perturbed inertia must
        be physical at all of them.

    Returns
    -------
    values : dict
        Parameter name → value (swept parameters only).
    n_draws : int
        Monte Carlo draws used (1 unless an unphysical inertia was resampled).
    unphysical : str or None
        Why the final draw is unphysical (``None`` when it is physical).
    """
    if spec.grid is not None:
        idx = np.unravel_index(index, [len(v) for v in spec.grid.values()])
        values = {k: float(v[j]) for (k, v), j in zip(spec.grid.items(), idx)}
        return values, 1, unphysical_draw_reason(values, inertias)
    rng = np.random.default_rng(np.random.SeedSequence([spec.seed, index]))
    for draws in itertools.count(1):
        values = draw_parameters(rng, spec)
        why = unphysical_draw_reason(values, inertias)
        if why is None or spec.unphysical == "reject" or draws >= spec.max_draws:
            return values, draws, why


def unphysical_draw_reason(values: dict, inertias: np.ndarray) -> Optional[str]:
    """Why a draw makes an unphysical inertia at one of the design points, or None.

    Parameters
    ----------
    values : dict
        The drawn parameters (their units, :data:`PARAMETERS`).
    inertias : ndarray
        The inertia of each design point (k×3×3), slug·ft².

    Returns
    -------
    str or None
        The reason, naming the design point when there are several.
    """
    for k, inertia in enumerate(inertias):
        why = unphysical_reason(perturb_inertia(inertia, values))
        if why is not None:
            return f"inertia {why}" + (f" at design point {k}" if len(inertias) > 1 else "")
    return None

