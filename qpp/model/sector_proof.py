"""The sector and slope bounds of an expression nonlinearity proved, or refused (issue 43).

:attr:`qpp.model.nonlin.ExpressionModel.sector_info` samples φ (a grid, climbing, a random check):
a fast first pass whose bounds can be wrong by a feature narrower than its grid.  Here the
sampled bounds, widened by :data:`REL_GAP` of their size, are proved over the whole box
Y × Θ × [0, t_range] by branch and bound on interval enclosures
(:mod:`qpp.model.interval_bounds`), channel by channel:

* φ_i(0, t, θ) = 0 (symbolically, or its enclosure is exactly 0);
* a ratio (diagonal) channel: α_i ≤ φ_i / y_i ≤ β_i, the ratio enclosed on a box as the
  intersection of φ_i(box) / Y_i (when 0 ∉ Y_i) and ∂φ_i/∂y_i over the hull of 0 and Y_i (the
  mean value of the slope between 0 and y_i, since φ_i(0) = 0);
* every channel: Σ_j |∂φ_i/∂y_j| ≤ its slope bound (β3, eq 10.40); a coupled channel's sector
  ±slope follows from it by the mean value theorem on the segment from 0 (which needs 0 in
  y_range).

All proofs of one model share one time budget (:data:`PROOF_BUDGET_S`): a premise not proved in
it is "not proved in the limit", and no certificate is printed.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from mpmath import iv

from qpp.model.expression_parser import sympy_module
from qpp.model.interval_bounds import NotEnclosable, compile_interval, maximize

#: relative widening of a sampled bound that the proof must establish (the enclosure's allowed gap)
REL_GAP = 1e-6
#: wall-time budget of all the interval proofs of one nonlinearity, s
PROOF_BUDGET_S = 30.0
#: boxes of one branch and bound
MAX_BOXES = 400_000
#: time cells of [0, T] on which the slope is bounded for β3 (a t-dependent φ)
SLOPE_CELLS = 128
#: boxes of one time cell's slope bound (a cell that does not converge keeps the global bound)
CELL_BOXES = 3000


@dataclass
class ProvedBounds:
    """Sector and slope bounds of φ proved by interval branch and bound (or the reasons why not).

    Attributes
    ----------
    sector : (r, 2) ndarray
        The sector proved (the sampled one widened by :data:`REL_GAP`), units of φ per unit of y.
    slope : (r,) ndarray
        sup Σ_j |∂φ_i/∂y_j| proved over Y × Θ × [0, t_range], units of φ per unit of y.
    sector_ok, slope_ok : bool
        Whether every channel's sector, resp. slope bound, is proved.
    sector_text, slope_text : str
        The outcome in words: "proved" with the enclosure's gap, or what could not be proved.
    seconds : float
        Wall time of the proofs, s.
    boxes : int
        Boxes enclosed, dimensionless.
    """

    sector: np.ndarray
    slope: np.ndarray
    sector_ok: bool
    slope_ok: bool
    sector_text: str
    slope_text: str
    seconds: float
    boxes: int


#: largest number of terms the distribution of products may create in :func:`_tidy`
TIDY_TERMS = 2000


def _terms(e) -> int:
    """Terms of ``e`` once its products of sums are distributed (powers of sums kept), estimated."""
    if e.is_Add:
        return sum(_terms(a) for a in e.args)
    if e.is_Mul:
        n = 1
        for a in e.args:
            n *= _terms(a)
            if n > TIDY_TERMS:
                return n
        return n
    return 1 + sum(_terms(a) - 1 for a in e.args if not a.is_Atom)


def _tidy(expr):
    """``expr`` with products distributed and common factors taken out (sympy's ``expand`` without
    expanding powers of sums, then ``factor_terms``), so that an interval enclosure does not count
    a variable twice where the expression cancels: φ = (dm + 1.5)·y·sin t − 1.5·y·sin t becomes
    dm·y·sin t, −k·sat(y) + 4·sat(y) becomes (4 − k)·sat(y).  Left as it is when the distribution
    would create more than TIDY_TERMS terms."""
    sp = sympy_module()
    if _terms(expr) > TIDY_TERMS:
        return expr
    return sp.factor_terms(sp.expand(expr, multinomial=False, power_exp=False, power_base=False, log=False))


def _ranges(model, syms, t_hi: float) -> list:
    rng = {**{s: tuple(r) for s, r in zip(model.ys, model.y_range)}, model.t: (0.0, float(t_hi)),
           **{s: (lo, hi) for s, lo, hi in zip(model.th, model.lo, model.hi)}}
    return [tuple(map(float, rng[s])) for s in syms]


def _fmt(x) -> str:
    return ", ".join(f"{s} = {v:.10g}" for s, v in x)


class _Prover:
    """The proofs of one model, sharing its deadline."""

    def __init__(self, model):
        self.model = model
        self.sp = sympy_module()
        self.deadline = getattr(model, "proof_deadline", None)
        if self.deadline is None:
            self.deadline = model.proof_deadline = time.monotonic() + PROOF_BUDGET_S
        self.boxes = 0

    def run(self, f, box, share: int = 1, **kw):
        """:func:`maximize` until the model's deadline, or 1/``share`` of the time left."""
        kw.setdefault("max_boxes", MAX_BOXES)
        now = time.monotonic()
        res = maximize(f, box, deadline=min(self.deadline, now + max(self.deadline - now, 0.0) / share), **kw)
        self.boxes += res.boxes
        return res

    def phi0(self, i):
        """None when φ_i(0, t, θ) = 0 is proved, else the reason."""
        M = self.model
        z = M.phi[i].subs({y: 0 for y in M.ys})
        if z == 0:
            return None
        syms = sorted(z.free_symbols, key=str)
        try:
            enc = compile_interval(z, syms)(*(iv.mpf(list(r)) for r in _ranges(M, syms, M.t_range)))
        except NotEnclosable as exc:
            return f"phi(0) = 0 not proved ({exc})"
        return None if enc.a == 0 and enc.b == 0 else f"phi(0) = 0 not proved (enclosure [{enc.a}, {enc.b}])"

    def slope_fn(self, i):
        """(enclosure of Σ_j |∂φ_i/∂y_j|, its variables): only the symbols the sum depends on are
        split (a variable it ignores would multiply the boxes for nothing)."""
        sp, M = self.sp, self.model
        terms = [sp.Abs(_tidy(sp.diff(_tidy(M.phi[i]), M.ys[j]))) for j in range(M.p) if M.dep[i][j]]
        g = sp.Add(*terms)
        syms = sorted(g.free_symbols, key=str)
        return compile_interval(g, syms), syms

    def ratio_fns(self, i, syms):
        sp, M = self.sp, self.model
        ph = _tidy(M.phi[i])
        f = compile_interval(_tidy(ph / M.ys[i]), syms)      # φ_i / y_i, cancelled where it can be
        k = syms.index(M.ys[i])
        lo, hi = M.y_range[i]
        try:
            d = compile_interval(_tidy(sp.diff(ph, M.ys[i])), syms)
        except NotEnclosable:
            d = None

        def ratio(*env):
            Y = env[k]
            lo_b, hi_b = -np.inf, np.inf
            if Y.a > 0 or Y.b < 0:
                r = f(*env)
                lo_b, hi_b = r.a, r.b
            if d is not None and lo <= 0 <= hi:
                e = list(env)
                e[k] = iv.mpf([min(0, Y.a), max(0, Y.b)])          # the hull of 0 and Y
                r = d(*e)
                if r.a == r.a and r.b == r.b:
                    lo_b, hi_b = max(lo_b, r.a), min(hi_b, r.b)
            if lo_b > hi_b:                     # both enclose the same values: round-off only
                lo_b, hi_b = min(lo_b, hi_b), max(lo_b, hi_b)
            return iv.mpf([lo_b, hi_b])
        return ratio, lambda *env: -ratio(*env)


def prove(model) -> ProvedBounds:
    """Prove the sampled sector and slope bounds of ``model`` (widened by :data:`REL_GAP`).

    Parameters
    ----------
    model : qpp.model.nonlin.ExpressionModel
        The nonlinearity, with its sampled :attr:`~qpp.model.nonlin.ExpressionModel.sector_info`.

    Returns
    -------
    ProvedBounds
        The bounds proved, or the sampled ones with the reasons they are not proved.
    """
    t0 = time.monotonic()
    P = _Prover(model)
    info = model.sector_info
    s = np.array(info.sector, float)
    slope_s = np.array(info.slope_bound, float)
    r = len(model.phi)
    sector = s.copy()
    slope = slope_s.copy()
    sec_fail, slo_fail, sec_gap, slo_gap = [], [], [], []
    for i in range(r):
        ph = model.phi[i]
        size = max(abs(s[i, 0]), abs(s[i, 1]), slope_s[i])
        tol = REL_GAP * size + 1e-300
        ch = f"channel {i + 1}"
        if ph == 0:
            continue
        why0 = P.phi0(i)
        if why0:
            sec_fail.append(f"{ch}: {why0}")
        # the slope bound, over the whole box (needed by β3 and a coupled channel's sector)
        if any(model.dep[i]):
            try:
                fn, syms = P.slope_fn(i)
                g = P.run(fn, _ranges(model, syms, model.t_range), share=3 * (r - i), target=slope_s[i] + tol)
            except NotEnclosable as exc:
                g = None
                slo_fail.append(f"{ch}: {exc}")
            if g is not None:
                if g.status == "proved":
                    slope[i] = slope_s[i] + tol
                    slo_gap.append(tol)
                elif g.status == "refuted":
                    slo_fail.append(f"{ch}: the slope sum |dphi/dy| reaches {g.lower:.6g} > the sampled bound "
                                    f"{slope_s[i]:.6g} at {_fmt(zip(syms, g.at))}")
                else:
                    slo_fail.append(f"{ch}: slope bound {slope_s[i]:.6g} could not be proved in the limit "
                                    f"({g.boxes} boxes, {g.seconds:.1f} s; enclosure up to {g.upper:.6g})")
        if info.diagonal[i]:
            syms = sorted(ph.free_symbols | {model.ys[i]}, key=str)
            box = _ranges(model, syms, model.t_range)
            try:
                ratio, neg = P.ratio_fns(i, syms)
            except NotEnclosable as exc:
                sec_fail.append(f"{ch}: {exc}")
                continue
            lo_t, hi_t = s[i, 0] - tol, s[i, 1] + tol
            for n_left, (name, fn, target, sign) in enumerate((("upper", ratio, hi_t, 1.0), ("lower", neg, -lo_t, -1.0))):
                b = P.run(fn, box, share=3 * (r - i) - 1 - n_left, target=target)
                if b.status == "proved":
                    sec_gap.append(tol)
                    continue
                if b.status == "refuted":
                    sec_fail.append(f"{ch}: phi/y reaches {sign * b.lower:.6g}, outside the sampled sector "
                                    f"[{s[i, 0]:.6g}, {s[i, 1]:.6g}], at {_fmt(zip(syms, b.at))}")
                else:
                    sec_fail.append(f"{ch}: the {name} sector bound {sign * target:.6g} could not be proved in the "
                                    f"limit ({b.boxes} boxes, {b.seconds:.1f} s)")
            sector[i] = (lo_t, hi_t)
        else:
            if not all(model.y_range[j, 0] <= 0 <= model.y_range[j, 1] for j in range(model.p) if model.dep[i][j]):
                sec_fail.append(f"{ch}: y_range does not contain 0 (the sector ±slope needs the segment from 0)")
            if slo_fail and slo_fail[-1].startswith(ch + ":"):
                sec_fail.append(f"{ch}: the sector ±slope rests on the slope bound, not proved")
            sector[i] = (-slope[i], slope[i])
    sec_ok, slo_ok = not sec_fail, not slo_fail
    secs = time.monotonic() - t0
    how = f"interval branch and bound, {P.boxes} boxes, {secs:.2g} s"
    # the sampled extremum is a value phi reaches; the proved bound lies REL_GAP beyond it: the
    # supremum is enclosed in [sampled, proved], of width the gap
    sector_text, slope_text = (f"proved ({how}; enclosure gap {max(gap, default=0.0):.2g}, {REL_GAP:g} relative)"
                               if not fail else "not proved: " + "; ".join(fail)
                               for gap, fail in ((sec_gap, sec_fail), (slo_gap, slo_fail)))
    return ProvedBounds(sector, slope, sec_ok, slo_ok, sector_text, slope_text, secs, P.boxes)


def slope_cells(model, edges, proved: ProvedBounds) -> np.ndarray:
    """Proved upper bounds of g_i = sup_{y, θ} Σ_j |∂φ_i/∂y_j| on the time cells between
    ``edges`` (a t-dependent channel), else the channel's proved slope bound on every cell.

    A cell whose own branch and bound does not converge (to :data:`REL_GAP`) within
    :data:`CELL_BOXES` keeps the global bound (itself proved), so the result is proved whenever
    ``proved.slope_ok``.

    Parameters
    ----------
    model : qpp.model.nonlin.ExpressionModel
        The nonlinearity.
    edges : (K + 1,) array
        Cell edges, s.
    proved : ProvedBounds
        The model's :func:`prove` outcome.

    Returns
    -------
    (r, K) ndarray
        The bounds, units of φ per unit of y.
    """
    edges = np.asarray(edges, float)
    K = edges.size - 1
    P = _Prover(model)
    G = np.repeat(np.asarray(proved.slope, float)[:, None], K, axis=1)
    for i, ph in enumerate(model.phi):
        if model.t not in ph.free_symbols or not any(model.dep[i]) or not proved.slope_ok:
            continue
        fn, syms = P.slope_fn(i)
        if model.t not in syms:
            continue
        kt = syms.index(model.t)
        for k in range(K):
            box = _ranges(model, syms, model.t_range)
            box[kt] = (edges[k], edges[k + 1])
            b = P.run(fn, box, tol=REL_GAP * max(proved.slope[i], 1e-300), max_boxes=CELL_BOXES)
            if b.status == "proved":
                G[i, k] = min(G[i, k], b.upper)
    return G
