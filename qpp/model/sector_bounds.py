"""The sampled sector bounds of a user's nonlinearity made tight and checked (ch. 10.1, lemma 1).

:meth:`qpp.model.nonlin.ExpressionNonlinearity.sector_info` samples φ on a grid of Y × Θ × [0, t_range];
a grid under-estimates a supremum that falls between its points (φ = δm·y·sin 2t, |δm| ≤ 0.1
sampled on 256 times gives the sector ±0.09999976 instead of ±0.1), and a sector that is too
small by any amount is not a certificate.  Hence :func:`refine` (a local climb from the best grid
points), :func:`global_search` (the whole box) and :func:`verify` (random points, whose violations
are climbed from again).  Bounds are only ever widened, never narrowed.
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import differential_evolution, minimize
from acmm_qpp.errors import ConfigError

#: Nelder–Mead iterations per variable for each start point of :func:`refine`
REFINE_ITER_PER_DIM = 200


def _box(model, i: int) -> tuple[list, np.ndarray, list]:
    """(lo, hi) of each variable x = (y_1 … y_p, t, θ_1 … θ_k), the mask of those that can
    change φ channel ``i``, and their (lo, hi)."""
    ranges = [tuple(r) for r in model.y_range] + [(0.0, model.t_range if model.t_varies else 0.0)]
    ranges += list(zip(model.lo, model.hi))
    free = np.array([hi > lo for lo, hi in ranges])
    free[:model.p] &= np.isin(np.arange(model.p), model.channel_outputs(i))
    return ranges, free, [r for r, f in zip(ranges, free) if f]


#: which way each bound is climbed: α down, β, the slope and the gain up
_SIGN = {"alpha": -1.0, "beta": 1.0, "slope": 1.0, "gain": 1.0}


def _value(model, i: int, kind: str, x) -> float:
    """:func:`_values` at one point x = (y, t, θ)."""
    return float(_values(model, i, kind, np.asarray(x, float)[:, None])[0])


def _values(model, i: int, kind: str, X) -> np.ndarray:
    """φ_i / y_i (``"alpha"``, ``"beta"``), Σ_j |∂φ_i/∂y_j| (``"slope"``) or |φ_i| / ‖y‖∞
    (``"gain"``, a lower bound of the slope since φ(0) = 0) at each column x = (y, t, θ) of X
    (p + 1 + k, S); NaN for a ratio at y_i ≈ 0 or a gain at y ≈ 0."""
    p = model.p
    Y, t, TH = list(X[:p]), X[p], list(X[p + 1:])
    S = X.shape[1]
    with np.errstate(all="ignore"):
        if kind == "slope":
            return np.broadcast_to(model._slope_sum(i, Y, t, TH), (S,)).astype(float)
        ph = np.broadcast_to(model._phi_i(i, Y, t, TH), (S,))
        if kind == "gain":
            ymax = np.max(np.abs(X[:p]), axis=0)
            return np.where(ymax > 1e-12, np.abs(ph) / np.where(ymax > 1e-12, ymax, 1.0), np.nan)
        yi = X[i]
        ok = np.abs(yi) > 1e-9 * float(np.ptp(model.y_range[i]))
        return np.where(ok, ph / np.where(ok, yi, 1.0), np.nan)


#: generations and population (per free variable) of :func:`global_search`'s differential evolution
GLOBAL_GENERATIONS, GLOBAL_POPULATION = 60, 15


def global_search(model, i: int, kinds: tuple, bounds: dict) -> dict:
    """Search the whole box of channel ``i``'s variables (y, t, θ) for each bound in ``kinds``
    (differential evolution, vectorized, a fixed seed: the same numbers every run), then climb
    from the best point found (:func:`refine`): an extremum in a basin the grid's best point
    does not lead to (φ/y = −(c − 1)y² + (sin wt − sin 2t)/2 peaks at one (w, t) among many
    local maxima) is found, and the bounds widened to it.

    Parameters
    ----------
    model : qpp.model.nonlin.ExpressionModel
        The nonlinearity.
    i : int
        The φ channel.
    kinds : tuple of str
        The bounds to search: ``"alpha"``, ``"beta"``, ``"slope"``.
    bounds : dict
        ``kind → value`` so far (dimensionless gains).

    Returns
    -------
    dict
        The bounds, each widened to the best extremum found (never narrowed).
    """
    ranges, free, lo_hi = _box(model, i)
    out = dict(bounds)
    if not free.any():
        return out
    base = np.array([0.5 * (lo + hi) for lo, hi in ranges])
    for kind in kinds:
        def cost(Z, kind=kind):
            X = np.repeat(base[:, None], Z.shape[1], axis=1)
            X[free] = Z
            c = -_SIGN[kind] * _values(model, i, kind, X)
            return np.where(np.isfinite(c), c, np.inf)

        res = differential_evolution(cost, lo_hi, vectorized=True, updating="deferred", seed=185644,
                                     maxiter=GLOBAL_GENERATIONS, popsize=GLOBAL_POPULATION, tol=0.0,
                                     polish=False, init="sobol")
        if np.isfinite(res.fun):
            x = base.copy()
            x[free] = res.x
            out = refine(model, i, {kind: x}, out)
    return out


def climb_from(model, i: int, x, kinds: tuple, bounds: dict) -> dict:
    """:func:`refine` the bounds ``kinds`` of channel ``i`` from a point ``x`` = (y, t, θ) near a
    feature the grid missed: each from x with θ set to the parameter sample (of
    :meth:`~qpp.model.sector_grid.SampleGrid.theta_samples`, or x's own) that is best for that bound
    there (the random point that found the feature drew θ for one bound; the other bound of the
    same bump usually lies at another corner of Θ).

    Parameters
    ----------
    model : qpp.model.nonlin.ExpressionModel
        The nonlinearity.
    i : int
        The φ channel.
    x : (p + 1 + k,) array
        The point, in the config's units.
    kinds : tuple of str
        The bounds to climb: ``"alpha"``, ``"beta"``, ``"slope"``, ``"gain"`` (|φ_i| / ‖y‖∞).
    bounds : dict
        ``kind → value`` so far (dimensionless gains).

    Returns
    -------
    dict
        The bounds, each widened to the best extremum found (never narrowed).
    """
    x = np.asarray(x, float)
    p1 = model.p + 1
    candidates = [x] + [np.concatenate([x[:p1], th]) for th in model.theta_samples()] if model.names else [x]
    starts = {}
    for kind in kinds:
        vals = np.array([_SIGN[kind] * _value(model, i, kind, c) for c in candidates])
        starts[kind] = candidates[int(np.argmax(np.where(np.isfinite(vals), vals, -np.inf)))]
    at: dict = {}
    out = refine(model, i, starts, bounds, at)
    if "slope" in kinds and "gain" in at:     # the largest |φ|/‖y‖ lies by a steep part: climb the slope there too
        out = refine(model, i, {"slope": at["gain"]}, out)
    return out


def refine(model, i: int, starts: dict, bounds: dict, at: dict | None = None) -> dict:
    """Climb from the grid's best points of channel ``i`` to the local extrema and widen the
    bounds to them.

    Parameters
    ----------
    model : qpp.model.nonlin.ExpressionNonlinearity
        The nonlinearity (its φ, gradients and ranges).
    i : int
        The φ channel.
    starts : dict
        ``kind → x`` (x = (y, t, θ) in the config's units), the grid point of each bound:
        ``"alpha"`` (smallest φ_i/y_i), ``"beta"`` (largest φ_i/y_i), ``"slope"`` (largest
        Σ_j |∂φ_i/∂y_j|); a kind absent is not refined.
    bounds : dict
        ``kind → value`` on the grid (dimensionless gains, in the units of d per unit of y).
    at : dict, optional
        Filled with ``kind → x`` of each extremum found (whether it widened the bound or not).

    Returns
    -------
    dict
        The same kinds, each value widened to the best extremum found (never narrowed).
    """
    _, free, lo_hi = _box(model, i)
    out = dict(bounds)
    if not free.any():
        return out
    for kind, x0 in starts.items():
        base = np.asarray(x0, float)

        def cost(z, kind=kind, base=base):
            x = base.copy()
            x[free] = z
            v = _value(model, i, kind, x)
            return np.inf if not np.isfinite(v) else -_SIGN[kind] * v

        res = minimize(cost, base[free], method="Nelder-Mead", bounds=lo_hi,
                       options={"maxiter": REFINE_ITER_PER_DIM * int(free.sum()), "xatol": 1e-12,
                                "fatol": 1e-15})
        if np.isfinite(res.fun):
            if at is not None:
                at[kind] = base.copy()
                at[kind][free] = res.x
            found = -_SIGN[kind] * res.fun
            # a widening by round-off (the grid point already is the extremum) is not taken:
            # only what exceeds the bound by 1e-12 of the bounds' size
            tol = 1e-12 * max([abs(v) for v in bounds.values() if np.isfinite(v)] + [1e-300])
            if (found < out[kind] - tol) if kind == "alpha" else (found > out[kind] + tol):
                out[kind] = found
    return out


def verify(model, alpha, beta, slope, diag) -> tuple[bool, list]:
    """Random points of Y × Θ × [0, t_range]: φ_i inside [α_i y_i, β_i y_i] (or the slope bound);
    on a violation the bounds are widened in place to cover it (+1 %) and the violating point is
    returned, for :func:`refine` to climb from (the random point only lies near the extremum the
    grid missed).

    Parameters
    ----------
    model : qpp.model.nonlin.ExpressionNonlinearity
        The nonlinearity.
    alpha, beta, slope : (r,) ndarray
        The bounds (widened in place on a violation), dimensionless gains.
    diag : (r,) bool ndarray
        Whether φ_i depends on y_i only (ratio bounds) or not (slope bound), dimensionless.

    Returns
    -------
    ok : bool
        True when no random point violates the bounds.
    starts : list of dict
        Per channel, ``kind → x`` (x = (y, t, θ) in the config's units) of the worst violating
        point of each violated bound (``"alpha"``, ``"beta"`` or ``"slope"``); empty when none.

    Raises
    ------
    ConfigError
        φ is not finite at a random point (singular on the stated ranges).
    """
    rng = np.random.default_rng(20240529)
    K = 4000
    Y = [rng.uniform(lo, hi, K) for lo, hi in model.y_range]
    t = rng.uniform(0.0, model.t_range, K)
    TH = [rng.uniform(lo, hi, K) for lo, hi in zip(model.lo, model.hi)]
    ph = model.phi_at(Y, t, TH)
    X = np.column_stack([*Y, t, *TH])                     # the points as x = (y, t, θ)
    starts: list = [{} for _ in range(len(model.phi))]
    for i in range(len(model.phi)):
        if not np.all(np.isfinite(ph[i])):
            raise ConfigError(f"nonlinearity.f1 (φ channel {i + 1}): singular (non-finite value) on the "
                              "stated ranges")
        if diag[i]:
            yi = Y[i]
            nz = np.abs(yi) > 1e-12
            ratio = np.where(nz, ph[i] / np.where(nz, yi, 1.0), np.nan)
            lo, hi = np.nanmin(ratio), np.nanmax(ratio)
            tol = 1e-9 * max(1.0, abs(alpha[i]), abs(beta[i]))
            if lo < alpha[i] - tol:
                starts[i]["alpha"] = X[np.nanargmin(ratio)]
            if hi > beta[i] + tol:
                starts[i]["beta"] = X[np.nanargmax(ratio)]
            if starts[i]:
                w = 0.01 * max(abs(beta[i] - alpha[i]), 1e-12)
                alpha[i] = min(alpha[i], lo - w)
                beta[i] = max(beta[i], hi + w)
        else:
            ymax = np.max(np.abs(np.array(Y)), axis=0)
            nz = ymax > 1e-12
            gain = np.where(nz, np.abs(ph[i]) / np.where(nz, ymax, 1.0), 0.0)
            k = float(gain.max())
            if k > slope[i] * (1 + 1e-9) + 1e-12:
                starts[i]["slope"] = X[int(np.argmax(gain))]
                alpha[i], beta[i] = -1.01 * k, 1.01 * k
    return not any(starts), starts
