"""Bounds of an expression nonlinearity PROVED by interval arithmetic (issue 43; lemma 1, eq 10.40).

The sampled sector and slope bounds of :mod:`qpp.model.sector_bounds` can miss a feature narrower
than the grid.  This module encloses a sympy expression (the tree :mod:`qpp.model.expression_parser`
builds) over a box of its variables with mpmath's interval context (:data:`mpmath.iv`, outward
rounded, so every enclosure contains the exact range of the expression on the box) and runs a
branch and bound (:func:`maximize`) that either proves ``sup f ≤ target`` on the box, or finds a
point where f exceeds the target (a refutation), or stops at its budget of time and boxes
("could not be proved in the limit").

Supported nodes: numbers, π, e, symbols, +, ×, powers (integer, and fractional of a non-negative
base), sin cos tan exp log sqrt tanh atan, Abs, sign, Min, Max, Heaviside (the derivative sympy
gives of Min, Max and Abs).  ``tanh`` is enclosed by its monotonicity from mpmath's interval
``exp``; ``atan`` (absent from mpmath's interval context) by its monotonicity from mpmath's
``atan`` at 113 bits widened by 2⁻¹⁰⁰ relative (not an outward-rounded operation, but 47 bits
beyond the double precision it guards).  Anything else — a DiracDelta from differentiating a
jump, an unevaluated derivative — raises :class:`NotEnclosable`: no proof.
"""
from __future__ import annotations

import functools
import heapq
import itertools
import operator
import time
from dataclasses import dataclass

import mpmath
from mpmath import iv

from qpp.model.expression_parser import sympy_module

_WHOLE = iv.mpf([-mpmath.inf, mpmath.inf])


class NotEnclosable(ValueError):
    """An expression node the interval evaluation cannot enclose (no proof is possible)."""


def _sign(x):
    if x.a > 0 or x.b < 0:
        return iv.mpf(1 if x.a > 0 else -1)
    return iv.mpf([-1 if x.a < 0 else 0, 1 if x.b > 0 else 0])


def _heaviside(x):
    return iv.mpf([1 if x.a > 0 else 0, 0 if x.b < 0 else 1])     # H(0) is 1/2 in sympy: inside [0, 1]


def _ends(pick, xs):
    """Min (``pick`` = min) or Max (max) of intervals: the pick of their lower ends and of their upper ends."""
    return iv.mpf([pick(x.a for x in xs), pick(x.b for x in xs)])


def _tanh_point(v):
    e = iv.exp(2 * iv.mpf(v))
    return 1 - 2 / (e + 1)


def _tanh(x):
    lo, hi = _tanh_point(x.a), _tanh_point(x.b)
    return iv.mpf([max(lo.a, -1), min(hi.b, 1)])


def _atan(x):
    with mpmath.workprec(113):
        lo, hi = mpmath.atan(x.a), mpmath.atan(x.b)
        lo, hi = lo - abs(lo) * mpmath.mpf(2) ** -100, hi + abs(hi) * mpmath.mpf(2) ** -100
    return iv.mpf([lo, hi])


def _sqrt(x):
    return _WHOLE if x.a < 0 else iv.sqrt(x)


def _log(x):
    return iv.log(x) if x.a > 0 else _WHOLE


def _pow_frac(x, e):
    if x.a < 0:
        return _WHOLE
    if x.b == 0:
        return iv.mpf(0) if e > 0 else _WHOLE
    if x.a == 0:
        if e < 0:
            return _WHOLE
        return iv.mpf([0, iv.exp(e * iv.log(iv.mpf(x.b))).b])
    return iv.exp(e * iv.log(x))


def _finite(x):
    """``x`` with a NaN end replaced by the whole line (mpmath gives NaN for inf − inf)."""
    return _WHOLE if x.a != x.a or x.b != x.b else x


def compile_interval(expr, symbols):
    """An interval function of ``expr``: called with one :data:`mpmath.iv` interval per symbol (in
    the order of ``symbols``) it returns an interval containing every value of ``expr`` for
    arguments in those intervals.

    Parameters
    ----------
    expr : sympy.Expr
        The expression (in the units of the nonlinearity).
    symbols : sequence of sympy.Symbol
        Its variables, in the order of the arguments.

    Returns
    -------
    callable
        ``f(*intervals) -> mpmath.iv.mpf``.

    Raises
    ------
    NotEnclosable
        A node no interval rule covers (a DiracDelta from differentiating a jump, say).
    """
    sp = sympy_module()
    index = {s: i for i, s in enumerate(symbols)}
    unary = {sp.sin: iv.sin, sp.cos: iv.cos, sp.tan: iv.tan, sp.exp: iv.exp, sp.log: _log,
             sp.tanh: _tanh, sp.atan: _atan, sp.Abs: abs, sp.sign: _sign}

    def build(node):
        if node.is_Symbol:
            if node not in index:
                raise NotEnclosable(f"free symbol {node} without a range")
            k = index[node]
            return lambda env: env[k]
        if node is sp.pi or node is sp.E:
            c = iv.pi if node is sp.pi else iv.e
            return lambda env: c
        if node.is_Rational or node.is_Float:              # integers and fractions exactly
            c = (iv.mpf(int(node)) if node.is_Integer else iv.mpf(float(node)) if node.is_Float
                 else iv.mpf(int(node.p)) / int(node.q))
            return lambda env: c
        if node.is_Add or node.is_Mul:
            parts = [build(a) for a in node.args]
            op = operator.add if node.is_Add else operator.mul
            return lambda env: _finite(functools.reduce(op, (f(env) for f in parts)))
        if node.is_Pow:
            base, e = node.args
            fb = build(base)
            if e.is_Integer:
                n = int(e)
                if n >= 0:
                    return lambda env: fb(env) ** n
                return lambda env: _finite(1 / (fb(env) ** (-n)))
            if e.is_Rational and e == sp.Rational(1, 2):
                return lambda env: _sqrt(fb(env))
            if e.is_number:
                ev = float(e)
                return lambda env: _pow_frac(fb(env), ev)
            fe = build(e)                                     # x**y = exp(y log x), x > 0
            return lambda env: _finite(iv.exp(fe(env) * _log(fb(env))))
        if isinstance(node, sp.Heaviside):
            fa = build(node.args[0])
            return lambda env: _heaviside(fa(env))
        if isinstance(node, (sp.Min, sp.Max)):
            parts = [build(a) for a in node.args]
            pick = min if isinstance(node, sp.Min) else max
            return lambda env: _ends(pick, [f(env) for f in parts])
        fn = unary.get(node.func)
        if fn is not None and len(node.args) == 1:
            fa = build(node.args[0])
            return lambda env: _finite(fn(fa(env)))
        raise NotEnclosable(f"{node.func.__name__} has no interval enclosure"
                            + (" (a jump of the nonlinearity: its slope is unbounded)"
                               if node.func.__name__ == "DiracDelta" else ""))

    f = build(expr)
    return lambda *env: f(env)


@dataclass
class Bound:
    """Outcome of :func:`maximize`.

    Attributes
    ----------
    status : str
        ``"proved"`` (sup f ≤ target, or within ``tol`` of a value attained, on the whole box),
        ``"refuted"`` (a point where f > target) or ``"limit"`` (the budget ran out first).
    upper : float
        An upper bound of sup f over the box (``inf`` when none was reached), units of f.
    lower : float
        A value f is proved to reach (a lower bound of sup f), units of f.
    at : tuple or None
        The point of ``lower``, one value per variable, in the variables' units.
    boxes : int
        Boxes enclosed, dimensionless.
    seconds : float
        Wall time, s.
    """

    status: str
    upper: float
    lower: float
    at: tuple | None
    boxes: int
    seconds: float

    @property
    def gap(self) -> float:
        """upper − lower: the width of the enclosure of sup f, units of f."""
        return float(self.upper - self.lower)


def maximize(enclose, box, *, target: float | None = None, tol: float = 0.0, deadline: float,
             max_boxes: int = 200_000) -> Bound:
    """Branch and bound for sup f over ``box``: prove ``sup f ≤ target``, or find a point above it.

    The box of largest upper bound is bisected along its widest side (relative to the initial
    box); each part is enclosed (``enclose``) and its midpoint evaluated as a degenerate interval,
    whose lower end is a value f reaches.  With ``target``: proved when the largest upper bound
    left is ≤ target, refuted when a value reached exceeds it.  Without: proved when the largest
    upper bound is within ``tol`` of the largest value reached (the supremum enclosed to ``tol``).

    Parameters
    ----------
    enclose : callable
        ``enclose(*intervals) -> mpmath.iv.mpf``, an enclosure of f on a box.
    box : sequence of (float, float)
        The range of each variable, in its units.
    target : float, optional
        The bound to prove, units of f.
    tol : float
        Width of the enclosure of sup f accepted without a target, units of f.
    deadline : float
        :func:`time.monotonic` time at which the search stops (status ``"limit"``), s.
    max_boxes : int
        Largest number of boxes enclosed, dimensionless.

    Returns
    -------
    Bound
        The outcome.
    """
    t0 = time.monotonic()
    width0 = [max(hi - lo, 0.0) for lo, hi in box]
    count = itertools.count()
    best = [-mpmath.inf, None]

    def evaluate(b):
        enc = enclose(*(iv.mpf([lo, hi]) for lo, hi in b))
        mid = tuple(0.5 * (lo + hi) for lo, hi in b)
        val = enclose(*(iv.mpf(x) for x in mid))
        if val.a == val.a and val.a > best[0]:
            best[0], best[1] = val.a, mid
        return enc.b if enc.b == enc.b else mpmath.inf

    def done(status, up, n):
        return Bound(status, float(up), float(best[0]), best[1], n, time.monotonic() - t0)

    box = [tuple(map(float, b)) for b in box]
    heap = [(-evaluate(box), next(count), box)]
    n = 1
    while True:
        neg_up, _, b = heap[0]
        up = -neg_up
        if target is not None and best[0] > target:
            return done("refuted", up, n)
        if (up <= target) if target is not None else (up - best[0] <= tol):
            return done("proved", up, n)
        if n >= max_boxes or time.monotonic() > deadline:
            return done("limit", up, n)
        heapq.heappop(heap)
        rel = [(hi - lo) / w if w > 0 else 0.0 for (lo, hi), w in zip(b, width0)]
        k = max(range(len(b)), key=rel.__getitem__) if b else 0
        if not b or rel[k] == 0.0 or b[k][0] == b[k][1] or not b[k][0] < 0.5 * (b[k][0] + b[k][1]) < b[k][1]:
            return done("limit", up, n)        # a box that cannot be split further (a point)
        lo, hi = b[k]
        mid = 0.5 * (lo + hi)
        for part in ((lo, mid), (mid, hi)):
            c = list(b)
            c[k] = part
            heapq.heappush(heap, (-evaluate(c), next(count), c))
            n += 1
