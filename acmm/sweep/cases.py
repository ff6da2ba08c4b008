"""Pure case generation: physical inertia checks, Monte Carlo draws, grid points and the
perturbed inertia of case ``i`` (reproducible from base, index and seed alone)."""
from __future__ import annotations

from typing import Optional

import numpy as np

from acmm.sweep.parameters import PARAMETERS, SHORTHANDS


AXES = ("roll", "pitch", "yaw")

#: Verdict codes stored in ``verdict_code``.
VERDICTS = ("bounded", "not_settled", "diverged", "no_equilibrium", "unphysical", "design_failed",
            "tea_failed")



# ---------------------------------------------------------------------------------------------
# physical inertia and case parameters
# ---------------------------------------------------------------------------------------------
def unphysical_reason(inertia: np.ndarray) -> Optional[str]:
    """Why a symmetric 3×3 inertia (slug·ft²) is not a rigid body's, or ``None`` if it is.

    Same test as :class:`acmm.io.config.Inertia`: finite, within the physical range
    (:data:`acmm_qpp.limits.PHYSICAL_MAX`), positive definite, and the principal moments satisfy the
    triangle inequality a + b ≥ c.

    Parameters
    ----------
    inertia : (3, 3) array
        Inertia, slug·ft².

    Returns
    -------
    str or None
        The reason, or None for a physical inertia.
    """
    from acmm_qpp.limits import PHYSICAL_MAX

    if not np.all(np.isfinite(inertia)):
        return "non-finite inertia"
    if np.max(np.abs(inertia)) > PHYSICAL_MAX["inertia"]:     # as the config refuses it
        return f"beyond the physical range (an element {np.max(np.abs(inertia)):.3g} > {PHYSICAL_MAX['inertia']:.0e} slug·ft²)"
    eig = np.linalg.eigvalsh(inertia)
    if eig[0] <= 0:
        return f"not positive definite (smallest principal moment {eig[0]:.4g})"
    if eig[0] + eig[1] < eig[2] * (1 - 1e-12):
        return f"triangle inequality violated ({eig[0]:.4g} + {eig[1]:.4g} < {eig[2]:.4g})"
    return None


def physical_mask(inertias: np.ndarray) -> np.ndarray:
    """:func:`unphysical_reason` is None, for a stack of inertias at once (the sweep's draw pilot).

    Parameters
    ----------
    inertias : (k, 3, 3) array
        Symmetric inertias, slug·ft².

    Returns
    -------
    (k,) bool array
        True where the inertia is a rigid body's within the physical range.
    """
    from acmm_qpp.limits import PHYSICAL_MAX

    m = np.array(inertias, dtype=float)
    with np.errstate(all="ignore"):
        ok = np.all(np.isfinite(m), axis=(1, 2))
        m[~ok] = np.eye(3)
        ok &= np.max(np.abs(m), axis=(1, 2)) <= PHYSICAL_MAX["inertia"]
        eig = np.linalg.eigvalsh(m)
    return ok & (eig[:, 0] > 0) & (eig[:, 0] + eig[:, 1] >= eig[:, 2] * (1 - 1e-12))


def perturb_inertia(inertia: np.ndarray, values: dict) -> np.ndarray:
    """I_pert = s·(I ∘ (1 + δ)) with δ from ``dI11 … dI23`` and s = ``inertia_scale``.

    Parameters
    ----------
    inertia : (3, 3) array
        Nominal inertia, slug·ft².
    values : dict
        Case parameters; the relative changes ``dI11`` … ``dI23`` and ``inertia_scale`` are
        dimensionless (missing ones: 0 and 1).

    Returns
    -------
    (3, 3) array
        Perturbed inertia, slug·ft².
    """
    d = {k: values.get(k, 0.0) for k in ("dI11", "dI22", "dI33", "dI12", "dI13", "dI23")}
    f = np.array([[d["dI11"], d["dI12"], d["dI13"]],
                  [d["dI12"], d["dI22"], d["dI23"]],
                  [d["dI13"], d["dI23"], d["dI33"]]])
    return values.get("inertia_scale", 1.0) * np.asarray(inertia, float) * (1.0 + f)


def _draw(rng: np.random.Generator, spec) -> dict:
    """One draw of every Monte Carlo parameter, in the order the config lists them."""
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
        names = list(spec.grid)
        shape = [len(spec.grid[k]) for k in names]
        idx = np.unravel_index(index, shape)
        values = {k: float(spec.grid[k][j]) for k, j in zip(names, idx)}
        return values, 1, _why(values, inertias)
    rng = np.random.default_rng(np.random.SeedSequence([spec.seed, index]))
    draws = 0
    while True:
        values = _draw(rng, spec)
        draws += 1
        why = _why(values, inertias)
        if why is None or spec.unphysical == "reject" or draws >= spec.max_draws:
            return values, draws, why


def _why(values: dict, inertias: np.ndarray) -> Optional[str]:
    for k, inertia in enumerate(inertias):
        why = unphysical_reason(perturb_inertia(inertia, values))
        if why is not None:
            return f"inertia {why}" + (f" at design point {k}" if len(inertias) > 1 else "")
    return None

