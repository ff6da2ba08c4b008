"""General sector-bounded nonlinearities written by the user (CR-185644 ch. 10.1, 10.4, lemma 1).

A channel of the matched nonlinearity f1 (f = B f1, eq 10.1) is an expression in the outputs
``y1 … yp`` (``y`` when p = 1), the time ``t`` and named uncertain parameters with stated
ranges, parsed **without eval** into a :mod:`sympy` expression by :mod:`qpp.model.expression_parser`
(whitelisted functions, and the library forms ``sat``, ``deadzone`` and ``cubic`` — the cubic is
sector-bounded only on a bounded set: the stated ``y_range``).

With θ the parameters and θ° their nominal values, the controller cancels f1o = f1(y, t, θ°) and
the loop sees φ = N (f1(y, t, θ) − f1(y, t, θ°)) through G (B = G N, assumption iii).  From φ this
module computes, over the stated ranges y ∈ Y, θ ∈ Θ, t ∈ [0, t_range]:

* the sector [α_i, β_i] of φ_i (ratio φ_i / y_i when φ_i depends on y_i only; else the symmetric
  bound ±Σ_j sup|∂φ_i/∂y_j|), sampled on a grid and verified at random points;
* β3 (10.54) = max_i ‖(g_i)_T‖₂ with g_i(t) = sup_{y, θ} Σ_j |∂φ_i/∂y_j (y, θ, t)|;
* β4 (14.8)  = sup_θ max_i ‖(φ_i(y_o(t), θ, t))_T‖₂ along the nominal output y_o.

A bad expression (unknown symbol, unsupported syntax, singular or not sector-bounded on the stated
range) raises :class:`acmm_qpp.errors.ConfigError` naming the channel and the cause.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property, lru_cache

import numpy as np

from acmm_qpp.errors import ConfigError
from qpp.model.expression_parser import FUNCTIONS, parse_expression, sympy_module
from qpp.model.sector_bounds import climb_from, global_search, refine, verify
from qpp.model.sector_grid import SampleGrid
from qpp.model.sector_proof import SLOPE_CELLS, ProvedBounds, prove, slope_cells
from scipy.optimize import minimize_scalar
from qpp.design.spheres import truncated_l2
from scipy.stats import qmc


@dataclass
class SectorInfo:
    """Sector and derivative bounds of φ computed from the expression.

    Attributes
    ----------
    sector : (r, 2) array
        The sector [α_i, β_i] of each φ_i, in units of φ per unit of y.
    slope_bound : (r,) array
        sup Σ_j |∂φ_i/∂y_j| over the ranges, in units of φ per unit of y.
    diagonal : (r,) bool array
        Whether φ_i depends on y_i only.
    verified : bool
        Whether the random-point verification passed without widening.
    n_samples : int
        Number of sample points used.
    """

    sector: np.ndarray       #: (r, 2) [α_i, β_i]
    slope_bound: np.ndarray  #: (r,) sup Σ_j |∂φ_i/∂y_j| over the ranges
    diagonal: np.ndarray     #: (r,) φ_i depends on y_i only
    verified: bool           #: random-point verification passed without widening
    n_samples: int


class ExpressionModel(SampleGrid):
    """Compiled f1(y, t, θ) and φ(y, t, θ) of an expression nonlinearity.

    Parameters
    ----------
    exprs : list of str
        One expression per control channel (m).
    p : int
        Number of outputs (symbols y1 … yp).
    params : dict
        name → (min, max, nominal) of each uncertain parameter, in the config's units.
    y_range : (p, 2) array
        Range of each output on which the sector and slopes are computed, in the units of y.
    N : (r, m) array
        B = G N (assumption iii), dimensionless.
    t_range : float
        Time horizon sampled for the sector, s.
    n_grid : int
        Grid points per output axis.
    n_t : int
        Time samples on [0, t_range].
    """

    def __init__(self, exprs, p, params, y_range, N, t_range, *, n_grid: int = 41, n_t: int = 256):
        sp = sympy_module()
        self.p = int(p)
        self.names = list(params)
        # (min, max, nominal) of each parameter
        self.lo, self.hi, self.nom = (np.array([params[k][c] for k in self.names], float) for c in range(3))
        self.y_range = np.asarray(y_range, float).reshape(self.p, 2)
        self.N = np.atleast_2d(np.asarray(N, float))
        self.t_range = float(t_range)
        self._cell_width = None            # proved_slope_cells: the cells' width (s) and their bounds
        self._cells = []
        self.n_grid, self.n_t = int(n_grid), int(n_t)
        self.ys = sp.symbols([f"y{i + 1}" for i in range(self.p)], real=True)
        self.t = sp.Symbol("t", real=True)
        self.th = [sp.Symbol(k, real=True) for k in self.names]
        syms = {str(s): s for s in [*self.ys, self.t, *self.th]}
        if self.p == 1 and "y" not in syms:
            syms["y"] = self.ys[0]                        # single output: y is y1
        for k in self.names:
            if k in FUNCTIONS or k in ("pi", "t", "y") or (k.startswith("y") and k[1:].isdigit()):
                raise ConfigError(f"nonlinearity.parameters: name {k!r} is reserved")
        self.texts = list(exprs)
        self.f = [parse_expression(e, syms, f"nonlinearity.f1.{i}") for i, e in enumerate(exprs)]
        nom_sub = dict(zip(self.th, [sp.Float(v) for v in self.nom]))
        dphi = [fi - fi.subs(nom_sub) for fi in self.f]
        self.phi = [sum(self.N[i, k] * dphi[k] for k in range(len(dphi))) for i in range(self.N.shape[0])]
        args = (*self.ys, self.t, *self.th)
        self._f = [sp.lambdify(args, fi, modules="numpy") for fi in self.f]
        self._phi = [sp.lambdify(args, ph, modules="numpy") for ph in self.phi]
        self.dep = [[self.ys[j] in ph.free_symbols for j in range(self.p)] for ph in self.phi]

        def derivative(ph, y):
            try:
                return sp.lambdify(args, sp.diff(ph, y), modules="numpy")
            except Exception:                     # noqa: BLE001 - None: finite differences (_grad)
                return None
        self._dphi = [[derivative(ph, y) for y in self.ys] for ph in self.phi]

    # ------------------------------------------------------------------ evaluation
    @staticmethod
    def _call(fn, Y, t, TH):
        with np.errstate(all="ignore"):
            v = fn(*Y, t, *TH)
        return np.broadcast_to(np.asarray(v, float), np.broadcast(*Y, t, *TH, np.zeros(1)).shape)

    def f1(self, y, t, theta) -> np.ndarray:
        """f1 ∈ R^m at one output y (p,), time t, parameters θ.

        Parameters
        ----------
        y : (p,) array
            The output, in the units of y.
        t : float
            Time, s.
        theta : (k,) array or None
            Parameter values, in the config's units; None: the nominal values.

        Returns
        -------
        (m,) ndarray
            f1, in the units of u.
        """
        th = self.nom if theta is None else np.atleast_1d(np.asarray(theta, float))
        return np.array([float(np.asarray(fn(*y, t, *th))) for fn in self._f])

    def phi_at(self, Y, t, TH) -> np.ndarray:
        """φ on broadcast arrays.

        Parameters
        ----------
        Y : list of p arrays
            The outputs, in the units of y.
        t : array
            Times, s.
        TH : list of k arrays
            Parameter values, in the config's units.

        Returns
        -------
        (r, ...) ndarray
            φ on the broadcast shape, in the units of d.
        """
        return np.array([self._call(fn, Y, t, TH) for fn in self._phi])

    def _phi_i(self, i, Y, t, TH):
        """φ_i alone on broadcast arrays (the sector's climbs need one channel, not all r)."""
        return self._call(self._phi[i], Y, t, TH)

    def _slope_sum(self, i, Y, t, TH):
        """Σ_j |∂φ_i/∂y_j| on broadcast arrays (0 when φ_i depends on no output)."""
        return sum(np.abs(self._grad(i, j, Y, t, TH)) for j in range(self.p) if self.dep[i][j])

    def _grad(self, i, j, Y, t, TH):
        fn = self._dphi[i][j]
        g = None
        if fn is not None:
            try:
                g = self._call(fn, Y, t, TH)
            except Exception:                     # noqa: BLE001
                g = None
        if g is None or not np.all(np.isfinite(g)):
            h = 1e-6 * max(1.0, float(np.ptp(self.y_range[j])))
            Yp = [y + h if k == j else y for k, y in enumerate(Y)]
            Ym = [y - h if k == j else y for k, y in enumerate(Y)]
            g = (self._call(self._phi[i], Yp, t, TH) - self._call(self._phi[i], Ym, t, TH)) / (2 * h)
        return g

    # ------------------------------------------------------------------ sector
    @cached_property
    def sector_info(self) -> SectorInfo:
        """Sector [α_i, β_i] and slope bounds of φ (see module docstring); raises ConfigError."""
        self._check_continuity()
        tg = self._t_grid()
        ths = self.theta_samples()
        r = len(self.phi)
        alpha = np.full(r, np.inf)
        beta = np.full(r, -np.inf)
        slope = np.zeros(r)
        diag = self.diagonal
        n = 0
        starts = [{} for _ in range(r)]                       # the grid point of each bound
        for i in range(r):
            # a channel without t is the same at every time: sampled at t = 0 only (the count of
            # sector_points, which the QPP_SECTOR_POINTS budget bounds)
            tg_i = tg if self.t in self.phi[i].free_symbols else tg[:1]
            tt = tg_i[None, :]                                # (1, Nt)
            Yf = self._channel_grid(i)                        # (Ny, 1) or (1, 1) each
            outs = self.channel_outputs(i)
            where = f"nonlinearity.f1 (φ channel {i + 1}: {self.phi[i]})"
            for th in ths:
                TH = [np.full((1, 1), v) for v in th]
                ph = self._call(self._phi[i], Yf, tt, TH)     # (Ny, Nt)
                n += ph.size
                if not np.all(np.isfinite(ph)):
                    raise ConfigError(f"{where}: singular (non-finite value) on the stated ranges")
                gsum = self._slope_sum(i, Yf, tt, TH)
                if not np.all(np.isfinite(gsum)):
                    raise ConfigError(f"{where}: not sector-bounded (unbounded slope) on the stated ranges")
                if np.max(gsum) > slope[i]:
                    gb = np.broadcast_to(gsum, ph.shape)
                    starts[i]["slope"] = self._point(Yf, tg_i, th, np.argmax(gb), gb.shape)
                    slope[i] = float(np.max(gsum))
                y0 = np.ones(ph.shape[0], bool)               # the channel's outputs all 0
                for j in outs:
                    y0 &= np.broadcast_to(Yf[j][:, 0] == 0, y0.shape)
                if y0.any():
                    v0 = np.abs(ph[y0]).max()
                    if v0 > 1e-9 * max(1.0, np.abs(ph).max()):
                        raise ConfigError(f"{where}: not sector-bounded: φ(y = 0) = {v0:.3g} ≠ 0")
                if diag[i]:
                    self._ratio_bounds(i, ph, Yf, tg_i, th, alpha, beta, slope, starts[i], where)
        for i in range(r):            # grid extrema → local extrema (widened only)
            kinds = {k: x for k, x in starts[i].items() if k == "slope" or diag[i]}
            got = refine(self, i, kinds, {"alpha": alpha[i], "beta": beta[i], "slope": slope[i]})
            got = global_search(self, i, tuple(kinds), got)
            alpha[i], beta[i], slope[i] = got["alpha"], got["beta"], got["slope"]
            if not diag[i]:
                alpha[i], beta[i] = -slope[i], slope[i]
        verified, missed = verify(self, alpha, beta, slope, diag)
        for i, kinds in enumerate(missed):
            if kinds:    # the grid missed a feature: climb every bound from the point that found it
                got = climb_from(self, i, next(iter(kinds.values())),
                                 ("alpha", "beta", "slope") if diag[i] else ("slope", "gain"),
                                 {"alpha": alpha[i], "beta": beta[i], "slope": slope[i], "gain": slope[i]})
                alpha[i], beta[i], slope[i] = got["alpha"], got["beta"], max(got["slope"], got["gain"])
        for i in range(r):
            # φ(0) = 0, so sup Σ_j |∂φ_i/∂y_j| ≥ sup |φ_i| / ‖y‖∞: the slope bound (β3) is never below
            # the sector (beyond round-off), and the sector of a coupled channel is ±slope
            half = max(abs(alpha[i]), abs(beta[i]))
            if half > slope[i] * (1 + 1e-9):
                slope[i] = half
            if not diag[i]:
                alpha[i], beta[i] = -slope[i], slope[i]
            if not alpha[i] < beta[i]:        # φ_i ≡ 0: a sector of width 2e-12 about its value
                c = 0.5 * (alpha[i] + beta[i])
                alpha[i], beta[i] = c - 1e-12, c + 1e-12
        return SectorInfo(np.column_stack([alpha, beta]), slope, diag, verified, n)

    @cached_property
    def proof(self) -> ProvedBounds:
        """The sampled sector and slope bounds (:attr:`sector_info`) proved by interval branch and
        bound over Y × Θ × [0, t_range], or the premises that could not be proved
        (:func:`qpp.model.sector_proof.prove`; one time budget per model)."""
        return prove(self)

    @lru_cache(maxsize=8)
    def proved_slope_cells(self, T: float) -> tuple:
        """(cell edges covering [0, T] in s, (r, K) proved bounds of sup_{y, θ} Σ_j |∂φ_i/∂y_j| on
        each cell, units of φ per unit of y), read-only (:func:`qpp.model.sector_proof.slope_cells`).

        The cells have one width for the model's life, T / :data:`~qpp.model.sector_proof.SLOPE_CELLS`
        of the first call's T (the last cell may reach past T: its bound holds on the part inside),
        and each cell is proved once: procedure 12.1 asks for many T.

        Parameters
        ----------
        T : float
            End of the interval, s.

        Returns
        -------
        tuple
            (edges, G).
        """
        if self._cell_width is None:
            self._cell_width = float(T) / SLOPE_CELLS
        w = self._cell_width
        K = max(1, int(np.ceil(float(T) / w - 1e-9)))
        have = len(self._cells)                     # the cells proved so far: [0, have·w]
        if K > have:
            self._cells.extend(slope_cells(self, w * np.arange(have, K + 1, dtype=float), self.proof).T)
        edges = w * np.arange(K + 1, dtype=float)
        G = np.column_stack(self._cells[:K])
        edges.flags.writeable = G.flags.writeable = False
        return edges, G

    def _ratio_bounds(self, i, ph, Yf, tg, th, alpha, beta, slope, starts, where) -> None:
        """Widen α_i, β_i (in place) to the ratios φ_i / y_i of one parameter sample ``ph``
        (Ny, Nt) on channel ``i``'s grid ``Yf``, recording the grid point of each new bound in
        ``starts``; raises ConfigError when φ_i / y_i grows without bound as y_i → 0."""
        yi = np.broadcast_to(Yf[i], ph.shape)
        nz = np.abs(yi) > 0
        ratio = ph[nz] / yi[nz]
        full = np.where(nz, ph / np.where(nz, yi, 1.0), np.nan)
        if ratio.min() < alpha[i]:
            starts["alpha"] = self._point(Yf, tg, th, np.nanargmin(full), full.shape)
            alpha[i] = ratio.min()
        if ratio.max() > beta[i]:
            starts["beta"] = self._point(Yf, tg, th, np.nanargmax(full), full.shape)
            beta[i] = ratio.max()
        span = float(np.ptp(self.y_range[i]))
        small = nz & (np.abs(yi) <= 2e-9 * span)
        mid = (np.abs(yi) > 2e-9 * span) & (np.abs(yi) <= 2e-6 * span)
        if small.any() and mid.any():
            rs = np.abs(ph[small] / yi[small]).max()
            rm = np.abs(ph[mid] / yi[mid]).max()
            # growing towards 0 over the grid's last decades: unbounded only if it goes on growing
            # three decades deeper (a saturation's corner between the two grid points is not that)
            if rs > 3.0 * rm + 1e-12 * max(1.0, slope[i]) and self._ratio_at(i, 1e-12 * span, tg, th) > 3.0 * rs:
                raise ConfigError(f"{where}: not sector-bounded near y = 0 "
                                  f"(φ/y grows from {rm:.3g} to {rs:.3g} as y → 0)")

    def _ratio_at(self, i: int, y: float, tg, th) -> float:
        """max |φ_i / y_i| at y_i = ±``y`` (the other outputs 0) over the times ``tg``, parameters ``th``."""
        Y = [np.zeros((2, 1)) for _ in range(self.p)]
        Y[i] = np.array([[y], [-y]])
        ph = self._call(self._phi[i], Y, tg[None, :], [np.full((1, 1), v) for v in th])
        return float(np.max(np.abs(np.broadcast_to(ph, (2, tg.size)) / Y[i])))

    def _point(self, Yf, tg, th, flat: int, shape: tuple) -> np.ndarray:
        """x = (y, t, θ) of grid entry ``flat`` of an (Ny, Nt) array (:func:`qpp.model.sector_bounds.refine`)."""
        iy, it = np.unravel_index(int(flat), shape)
        return np.concatenate([[Y[min(iy, Y.shape[0] - 1), 0] for Y in Yf], [tg[it]], np.asarray(th, float)])

    def _check_continuity(self) -> None:
        """Every f1 channel continuous and finite on the stated ranges, decided in bounded time:
        each sub-expression that can make f1 singular (:func:`_singular_argument`) evaluated on a
        grid (:func:`_on_grid`), a zero, sign change (tan at π/2 between grid points) or negative
        argument refused naming the symbol; then f1 itself, a value not finite or beyond
        :data:`VALUE_LIMIT` refused as an overflow.  (sympy's ``continuous_domain`` decided this
        symbolically, but took minutes for ``tan(100*y1)``.)"""
        sp = sympy_module()
        ranges = {**{s: tuple(r) for s, r in zip(self.ys, self.y_range)}, self.t: (0.0, self.t_range),
                  **{s: (lo, hi) for s, lo, hi in zip(self.th, self.lo, self.hi)}}
        for k, f in enumerate(self.f):
            where = f"nonlinearity.f1.{k}"
            for node in sp.preorder_traversal(f):
                check = _singular_argument(sp, node)
                if check is None:
                    continue
                arg, kind = check
                syms = sorted(arg.free_symbols & set(ranges), key=str)
                if not syms:
                    continue
                grid, vals = _on_grid(sp, arg, syms, ranges)
                bad = _singular_axis(vals, kind)
                if bad is None and kind in ("pole", "tan"):
                    bad = _touches_zero(sp, arg, syms, ranges, grid, vals)
                if bad is not None:
                    sym = syms[bad]
                    lo, hi = ranges[sym]
                    raise ConfigError(f"{where}: singular on the stated range: {self.texts[k]!r} is not continuous "
                                      f"in {sym} on [{lo:g}, {hi:g}] ({_WHY[kind]} {arg})")
            syms = sorted(f.free_symbols & set(ranges), key=str)
            if syms:
                grid, vals = _on_grid(sp, f, syms, ranges)
                big = ~np.isfinite(vals) | (np.abs(np.nan_to_num(vals, nan=np.inf)) > VALUE_LIMIT)
                if big.any():
                    at = ", ".join(f"{s} = {g.reshape(-1)[int(np.argmax(big.reshape(-1)))]:.4g}"
                                   for s, g in zip(syms, grid))
                    raise ConfigError(f"{where}: overflow: {self.texts[k]!r} is not a finite number below "
                                      f"{VALUE_LIMIT:.0e} on the stated ranges (at {at})")

    # ------------------------------------------------------------------ β3, β4
    def beta3(self, T: float) -> float:
        """β3 (10.54): max_i ‖(sup_{y, θ} Σ_j |∂φ_i/∂y_j|)_T‖₂ (sampled on the grid; for a φ
        independent of t, the slope bound of :attr:`sector_info`, refined between grid points).

        Parameters
        ----------
        T : float
            Truncation time, s.

        Returns
        -------
        float
            β3, in units of φ per unit of y times s^½.
        """
        tg, g = self.slope_profile(T)
        if tg.size == 1:    # φ independent of t: g_i is its slope bound, refined beyond the grid
            return float(max(np.max(g), np.max(self.sector_info.slope_bound)) * np.sqrt(T))
        return truncated_l2(tg, g, T)

    @lru_cache(maxsize=8)    # each evaluation of 12.1 asks again (β3, the late-slope check)
    def slope_profile(self, T: float):
        """(t, g), read-only: g_i(t) = sup_{y, θ} Σ_j |∂φ_i/∂y_j| on the time grid of [0, T], the β3 integrand.

        Parameters
        ----------
        T : float
            End of the time grid, s.

        Returns
        -------
        tuple
            ((N,) times in s, (r, N) slopes in units of φ per unit of y).
        """
        tg = self._t_grid(T)
        g = np.zeros((len(self.phi), tg.size))
        for i in range(len(self.phi)):
            if not any(self.dep[i]):
                continue
            Yf = self._channel_grid(i)
            ny = max(Y.shape[0] for Y in Yf)
            for th in self.theta_samples():
                TH = [np.full((1, 1), v) for v in th]
                s = self._slope_sum(i, Yf, tg[None, :], TH)
                g[i] = np.maximum(g[i], np.max(np.broadcast_to(s, (ny, tg.size)), axis=0))
        tg.flags.writeable = g.flags.writeable = False
        return tg, g

    def beta4(self, t, y_o, T: float) -> float:
        """β4 (10.53/14.8): sup_θ max_i ‖(φ_i(y_o(t), θ, t))_T‖₂ along the nominal output.

        Parameters
        ----------
        t : (N,) array
            Sample times, s.
        y_o : (p, N) array
            Nominal output, in the units of y.
        T : float
            Truncation time, s.

        Returns
        -------
        float
            β4, in units of φ times s^½.
        """
        t = np.asarray(t, float)
        y_o = np.atleast_2d(np.asarray(y_o, float))
        best = 0.0
        for th in self.theta_samples():
            ph = self.phi_at([y_o[j] for j in range(self.p)], t, [np.full(t.shape, v) for v in th])
            best = max(best, truncated_l2(t, ph, T))
        return best


#: evaluations of one sub-expression by the continuity check (:meth:`ExpressionModel._check_continuity`)
SINGULARITY_POINTS = 2 ** 18

#: a denominator (or the cosine under tan) whose refined local minimum is this small relative to its
#: largest value on the range is taken to reach 0 there (a double root, |y − c|; Brent's search
#: locates the minimum to ~1e-8 relative, so an exact zero shows as ≲ 1e-9)
NEAR_ZERO = 1e-7

#: largest |f1| accepted on the stated ranges: beyond it products of f1 overflow floating point
VALUE_LIMIT = 1e150

_WHY = {"pole": "zero of the denominator", "tan": "pole of tan where cos is 0:",
        "log": "logarithm of a non-positive value:", "root": "fractional power of a negative value:"}


def _singular_argument(sp, node):
    """(argument, kind) of a sub-expression that is singular where its argument is 0 (``pole``,
    ``tan``) or negative (``log``, ``root``); None for one that is continuous everywhere."""
    if isinstance(node, sp.Pow) and node.exp.is_number:
        if node.exp.is_negative:
            return node.base, "pole"
        if not node.exp.is_integer:
            return node.base, "root"
    elif isinstance(node, sp.tan):
        return sp.cos(node.args[0]), "tan"
    elif isinstance(node, sp.log):
        return node.args[0], "log"
    return None


def _on_grid(sp, expr, syms, ranges):
    """``expr`` on a grid of at most :data:`SINGULARITY_POINTS` points spanning the ranges of
    ``syms`` (each axis the same number of points, the ends included): (grid arrays, values).
    With more symbols than a grid of 3 points per axis allows, a scrambled Sobol sample of
    :data:`SINGULARITY_POINTS` points (seeded: the same every run) plus the box's corners if they
    fit, as one axis (zeros and signs are then judged pointwise)."""
    d = len(syms)
    per_axis = int(SINGULARITY_POINTS ** (1.0 / d))
    if per_axis >= 3:
        axes = [np.linspace(*ranges[s], per_axis) for s in syms]
        grid = np.meshgrid(*axes, indexing="ij")
    else:
        u = qmc.Sobol(d, scramble=True, seed=0).random(SINGULARITY_POINTS)
        lo, hi = np.array([ranges[s] for s in syms], float).T
        grid = list((lo + u * (hi - lo)).T)
    fn = sp.lambdify(syms, expr, modules="numpy")
    with np.errstate(all="ignore"):
        vals = np.broadcast_to(np.asarray(fn(*grid), dtype=float), grid[0].shape)
    return grid, vals


def _singular_axis(vals: np.ndarray, kind: str):
    """The axis along which ``vals`` shows a singularity of ``kind`` — a zero, a non-finite value
    or a change of sign for a pole, a negative value (zero too for a logarithm) for a logarithm or
    a root — else None."""
    nonfinite = ~np.isfinite(vals)
    if kind in ("log", "root"):
        bad = nonfinite | ((vals <= 0) if kind == "log" else (vals < 0))
        return _varying_axis(vals) if bad.any() else None
    if nonfinite.any() or np.any(vals == 0):
        return _varying_axis(vals)
    for ax in range(vals.ndim):
        v = np.moveaxis(vals, ax, 0)
        if np.any(np.sign(v[1:]) != np.sign(v[:-1])):
            return ax
    return None


def _varying_axis(vals: np.ndarray) -> int:
    """The axis along which ``vals`` varies most (the symbol a singularity is named after)."""
    v = np.nan_to_num(vals, nan=0.0, posinf=1e300, neginf=-1e300)
    return int(np.argmax([np.max(np.ptp(np.moveaxis(v, ax, 0), axis=0)) for ax in range(v.ndim)]))


def _touches_zero(sp, arg, syms, ranges, grid, vals):
    """The axis (index into ``syms``) along which ``arg`` reaches 0 between grid points without
    changing sign — a double root, |y − c|: its local minimum nearest 0 refined along each axis by
    a bounded Brent search — else None."""
    a = np.abs(vals)
    top = float(np.max(a)) if a.size else 0.0
    if not top > 0:
        return None
    at = np.unravel_index(int(np.argmin(a)), a.shape)
    point = [float(g[at]) for g in grid]
    fn = sp.lambdify(syms, sp.Abs(arg), modules="numpy")
    for ax, sym in enumerate(syms):
        lo, hi = ranges[sym]
        n = a.shape[ax] if a.ndim == len(syms) else 2 ** 10
        h = (hi - lo) / max(n - 1, 1)
        x0 = point[ax]

        def f(x, ax=ax):
            q = list(point)
            q[ax] = x
            with np.errstate(all="ignore"):
                return float(np.asarray(fn(*q), dtype=float))

        got = minimize_scalar(f, bounds=(max(lo, x0 - h), min(hi, x0 + h)), method="bounded",
                              options={"xatol": 1e-15 * max(1.0, abs(x0))})
        if got.fun <= NEAR_ZERO * top:
            return ax
    return None
