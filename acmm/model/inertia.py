"""Rigid-body inertia: whether a 3×3 matrix is a rigid body's (positive definite, principal moments
obeying the triangle inequality) and the element-wise perturbation I ∘ (1 + δ) of ch. 7's ±30 %
study, shared by the sweep's draws and the robust design's sampled plants
(:mod:`acmm.design.robust`)."""
from __future__ import annotations

from typing import Optional

import numpy as np

#: Largest |element| of a plausible inertia, slug·ft²: the Space Station is ~1e7–1e8 slug·ft²; the
#: bound leaves orders of magnitude of headroom while keeping every derived quantity (ω²·I, I·ω·h,
#: Riccati products) far from float overflow (the config refuses beyond it too,
#: :mod:`acmm.io.config`).
MAX_INERTIA = 1e13

#: the six independent elements of an inertia, in the order the draws take them
ELEMENTS = ("dI11", "dI22", "dI33", "dI12", "dI13", "dI23")


def unphysical_reason(inertia: np.ndarray) -> Optional[str]:
    """Why a symmetric 3×3 inertia (slug·ft²) is not a rigid body's, or ``None`` if it is.

    Same test as :class:`acmm.io.config.Inertia`: finite, within the physical range
    (:data:`MAX_INERTIA`), positive definite, and the principal moments satisfy the
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
    if not np.all(np.isfinite(inertia)):
        return "non-finite inertia"
    if np.max(np.abs(inertia)) > MAX_INERTIA:     # as the config refuses it
        return f"beyond the physical range (an element {np.max(np.abs(inertia)):.3g} > {MAX_INERTIA:.0e} slug·ft²)"
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
    m = np.array(inertias, dtype=float)
    with np.errstate(all="ignore"):
        ok = np.all(np.isfinite(m), axis=(1, 2))
        m[~ok] = np.eye(3)
        ok &= np.max(np.abs(m), axis=(1, 2)) <= MAX_INERTIA
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
    d = {k: values.get(k, 0.0) for k in ELEMENTS}
    f = np.array([[d["dI11"], d["dI12"], d["dI13"]],
                  [d["dI12"], d["dI22"], d["dI23"]],
                  [d["dI13"], d["dI23"], d["dI33"]]])
    return values.get("inertia_scale", 1.0) * np.asarray(inertia, float) * (1.0 + f)
