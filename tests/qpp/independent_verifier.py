"""An independent check of a stored ``qpp_design.h5`` (issue 33 item 3), written from the report and
``docs/qpp-certificates.md`` alone: it imports nothing of ``qpp`` (no β1, circle, sector, threshold
or simulation code), only numpy, scipy and sympy.

* β1 = sup_ω σ̄(C_z (jωI − A_n)⁻¹ B_z), A_n = A_z + aI (eq 10.36): Hamiltonian bisection
  (Boyd–Balakrishnan), started from a dense frequency sweep;
* γ∞ = (λ_max(C_z P C_zᵀ))^½ with the Gramian P from a Kronecker-product linear solve;
* the circle criterion for symmetric sectors [−k_i, k_i] and a Hurwitz A_n by the KYP lemma
  (‖D diag(k) H D⁻¹‖∞ < 1 by its own Hamiltonian bisection, D searched on a grid), and as a
  cross-check lemma 1 with α < 0 < β (each Gershgorin mean band inside the disc of radius 1/k_i
  about 0) on 80 000 frequencies;
* the sector, the slopes (β3) of φ = N (f1(θ) − f1(θ°)) sampled by evaluating the user's
  expression with ``sympy.lambdify`` on a dense grid (or the sinusoidal form directly); the stored
  sector must contain that one (premise ``sector``; the polar arm's assumed sector never does);
* then both PROVED by its own interval bisection (mpmath's outward-rounded ``iv`` functions
  substituted into ``sympy.lambdify``): |φ_i / y_i| ≤ k_i of the stored sector on y_range ×
  θ box × [0, t_range] (the cancelled ratio, or φ_i(Y)/Y and the derivative over the hull of 0 and
  Y — the mean value theorem, φ_i(0) = 0), and sup Σ_j |∂φ_i/∂y_j| on [0, T] within 1e-3 of its
  sampled value (premise ``slope`` of an expression); the sinusoidal form as an expression in γ;
* the nominal output y_o and the scenarios by ``scipy.integrate.solve_ivp`` (LSODA, rtol 1e-10)
  of ż = A_z z + B_z [r; d + φ(C_z z, t)] from the stored A_z, B_z, C_z (eq 10.7);
* m = β_o / (β_i + β_o β3 + β4) of the consistent reading, smallest over T' ≤ T, and the
  premises: stable, sector, circle, β1 < m, γ∞ max E/m ≤ 1, y_o ± β_o inside y_range.
"""
from __future__ import annotations

import numpy as np
import sympy
from mpmath import iv
from scipy.integrate import solve_ivp


# ----------------------------------------------------------------------------- norms
def _sigma(A, B, C, w):
    G = C @ np.linalg.solve(1j * w * np.eye(A.shape[0]) - A, B)
    return np.linalg.svd(G, compute_uv=False)[0]


def hinf(A, B, C, rtol=1e-12):
    """sup_ω σ̄(C (jωI − A)⁻¹ B) for Hurwitz A: sweep, then Hamiltonian bisection."""
    lam = np.linalg.eigvals(A)
    mags = np.abs(lam[np.abs(lam) > 0])
    ws = np.concatenate([[0.0], np.logspace(np.log10(mags.min()) - 3, np.log10(mags.max()) + 3, 4000),
                         np.abs(lam.imag)])
    lo = max(_sigma(A, B, C, w) for w in ws)
    hi = 2 * lo + 1e-12

    def has_crossing(g):
        Hm = np.block([[A, (B @ B.T) / g], [-(C.T @ C) / g, -A.T]])
        ev = np.linalg.eigvals(Hm)
        return bool(np.any(np.abs(ev.real) < 1e-9 * max(1.0, np.abs(ev).max())))

    while has_crossing(hi):
        hi *= 2
    while hi - lo > rtol * hi:
        g = 0.5 * (lo + hi)
        if has_crossing(g):
            lo = g
        else:
            hi = g
    return 0.5 * (lo + hi)


def l2_to_peak(A, B, C):
    """(λ_max(C P Cᵀ))^½, A P + P Aᵀ + B Bᵀ = 0 solved as (I⊗A + A⊗I) vec P = −vec BBᵀ."""
    n = A.shape[0]
    K = np.kron(np.eye(n), A) + np.kron(A, np.eye(n))
    P = np.linalg.solve(K, -(B @ B.T).reshape(-1, order="F")).reshape(n, n, order="F")
    P = 0.5 * (P + P.T)
    return float(np.sqrt(np.linalg.eigvalsh(C @ P @ C.T).max()))


def circle_symmetric(A, Bphi, C, k, n_freq=80_000):
    """Lemma 1 for sectors [−k_i, k_i] (Hurwitz A): |h_ii| + (d_i + d'_i)/2 < 1/k_i on the grid."""
    lam = np.abs(np.linalg.eigvals(A))
    lam = lam[lam > 0]
    w = np.concatenate([[0.0], np.logspace(np.log10(lam.min()) - 4, np.log10(lam.max()) + 4, n_freq)])
    ok = True
    for wi in w:
        H = C @ np.linalg.solve(1j * wi * np.eye(A.shape[0]) - A, Bphi)
        Ha = np.abs(H)
        for i in range(H.shape[0]):
            if k[i] == 0:
                continue
            d_row = Ha[i].sum() - Ha[i, i]
            d_col = Ha[:, i].sum() - Ha[i, i]
            if Ha[i, i] + 0.5 * (d_row + d_col) >= 1.0 / k[i]:
                ok = False
                break
        if not ok:
            break
    return ok


def circle_kyp_symmetric(A, Bphi, C, k):
    """The circle criterion for sectors [−k_i, k_i] (Hurwitz A) by the KYP lemma: the small gain
    ‖D diag(k) C (sI − A)⁻¹ B D⁻¹‖∞ < 1 decided by the Hamiltonian bisection :func:`hinf`, D a
    positive diagonal scaling searched on a grid of 10^-6 … 10^6 per channel beyond the first (a
    diagonal φ commutes with D); no frequency grid decides it."""
    k = np.asarray(k, float)
    m = k.size
    if m == 1:
        return bool(hinf(A, Bphi, k[0] * C) < 1.0)
    best = np.inf
    for logd in np.linspace(-6, 6, 49) if m == 2 else [0.0]:
        d = np.array([1.0] + [10.0 ** logd] * (m - 1))
        best = min(best, hinf(A, Bphi / d[None, :], (d * k)[:, None] * C))
        if best < 1.0:
            break
    return bool(best < 1.0)


# ----------------------------------------------------------------------------- signals
def signal(terms, t):
    """Σ of sin/step/ramp terms (the config's r_o, delta_r), at time t (s)."""
    v = 0.0
    for s in terms:
        amp = float(s.get("amplitude", 1.0))
        on, off = float(s.get("t_on", 0.0)), s.get("t_off")
        if s["kind"] == "sin":
            v += amp * np.sin(float(s.get("omega", 1.0)) * t + float(s.get("phase", 0.0)))
        elif s["kind"] == "step":
            v += amp if (t >= on and (off is None or t < float(off))) else 0.0
        elif s["kind"] == "ramp":
            end = t if off is None else min(t, float(off))
            v += amp * max(end - on, 0.0)
    return v


# ----------------------------------------------------------------------------- the nonlinearity
class Phi:
    """φ(y, t, θ) = N (f1(y, t, θ) − f1(y, t, θ°)) of a config (sinusoidal or expression)."""

    def __init__(self, cfg: dict):
        nl = cfg["nonlinearity"]
        B = np.atleast_2d(np.asarray(cfg["plant"]["B"], float))
        G = np.atleast_2d(np.asarray(cfg["plant"]["G"], float))
        self.N = np.linalg.lstsq(G, B, rcond=None)[0]          # B = G N
        self.kind = nl["kind"]
        self.nl = nl
        if self.kind == "expression":
            p = np.atleast_2d(cfg["plant"]["C"]).shape[0]
            self.ys = sympy.symbols(" ".join(f"y{i + 1}" for i in range(p)) + " ,", real=True)[:p]
            self.t = sympy.Symbol("t", real=True)
            pars = nl.get("parameters", {})
            self.pnames = list(pars)
            self.ps = [sympy.Symbol(n, real=True) for n in self.pnames]
            self.lo = np.array([float(pars[n]["min"]) for n in self.pnames])
            self.hi = np.array([float(pars[n]["max"]) for n in self.pnames])
            self.nom = np.array([float(pars[n].get("nominal", 0.5 * (pars[n]["min"] + pars[n]["max"])))
                                 for n in self.pnames])
            loc = {str(s): s for s in (*self.ys, self.t, *self.ps)}
            loc.update({"sat": lambda x, L: sympy.Min(sympy.Max(x, -L), L), "max": sympy.Max, "min": sympy.Min,
                        "abs": sympy.Abs})
            exprs = [self._text(e) for e in nl["f1"]]
            self.f = [sympy.sympify(e, locals=loc) for e in exprs]
            self.fn = [sympy.lambdify((*self.ys, self.t, *self.ps), f, "numpy") for f in self.f]
            self.dfn = [[sympy.lambdify((*self.ys, self.t, *self.ps), sympy.diff(f, y), "numpy") for y in self.ys]
                        for f in self.f]
            self.y_range = np.asarray(nl["y_range"], float)

    @staticmethod
    def _text(e):
        if isinstance(e, str):
            return e
        y = f"y{int(e['output'])}"
        gain = e.get("gain", "1")
        form = e["form"]
        if form == "saturation":
            return f"({gain})*sat({y}, {e['level']})"
        if form == "cubic":
            return f"({gain})*{y}**3"
        raise NotImplementedError(form)

    def phi_exprs(self, p):
        """(φ_i as sympy expressions, output symbols, t, parameter symbols, their boxes): an
        expression's N (f1(θ) − f1(θ°)), the sinusoidal form's N γ F_unc y sin ωt with γ ∈ ±γ_max."""
        t = sympy.Symbol("t", real=True)
        if self.kind == "sinusoidal":
            ys = sympy.symbols(" ".join(f"y{i + 1}" for i in range(p)) + " ,", real=True)[:p]
            g = sympy.Symbol("gamma", real=True)
            F = np.asarray(self.nl["F_unc"], float)
            w = float(self.nl["omega"])
            ph = [sum(float(self.N[i, k]) * g * float(F[k, j]) * ys[j] for k in range(F.shape[0]) for j in range(p))
                  * sympy.sin(w * t) for i in range(self.N.shape[0])]
            gm = float(self.nl["gamma_max"])
            return ph, list(ys), t, [g], [(-gm, gm)]
        nom = dict(zip(self.ps, map(float, self.nom)))
        df = [f - f.subs(nom) for f in self.f]
        ph = [sum(float(self.N[i, k]) * df[k] for k in range(len(df))) for i in range(self.N.shape[0])]
        return ph, list(self.ys), self.t, list(self.ps), list(zip(map(float, self.lo), map(float, self.hi)))

    def prove(self, k, t_hi, p, y_range=None, T=None):
        """Interval proofs of the sector |φ_i/y_i| ≤ k_i (a channel in y_i alone; another's
        sector is Σ_j sup|∂φ_i/∂y_j| ≤ k_i by the mean value theorem) and, with ``T``, of the
        slopes: sup of Σ_j |∂φ_i/∂y_j| on [0, T] proved within 1e-3 of its sampled value (which the
        verifier's β3 uses): (sector proved, slope proved)."""
        ph, ys, t, ths, thbox = self.phi_exprs(p)
        yr = [(-1.0, 1.0)] * p if y_range is None else [tuple(map(float, r)) for r in y_range]
        ranges = dict(zip([*ys, t, *ths], [*yr, (0.0, float(t_hi)), *thbox]))

        def on_box(expr, need=()):
            """(interval function, box) over the symbols ``expr`` (and ``need``) depends on: a
            variable it ignores would only be split in vain."""
            syms = [s for s in ranges if s in expr.free_symbols or s in need]
            return iv_function(expr, syms), [ranges[s] for s in syms], syms

        sector_ok = slope_ok = True
        for i, e in enumerate(ph):
            # distributed, common factors out: an interval counts a variable once where φ cancels
            # ((1.5 + dm)·y·sin t − 1.5·y·sin t is dm·y·sin t)
            e = sympy.factor_terms(sympy.expand(sympy.sympify(e)))
            if not e.free_symbols & set(ys):
                continue
            slope = sum(sympy.Abs(sympy.factor_terms(sympy.expand(sympy.diff(e, y)))) for y in ys if y in e.free_symbols)
            fs, box, syms = on_box(slope)
            if T is not None:
                # the slope premise: the sampled slope (β3 here) is within 1e-3 of the sup proved on [0, T]
                bt = [(0.0, float(T)) if s_ is t else b for s_, b in zip(syms, box)]
                axes = [np.linspace(lo, hi, 401 if s_ in ys and p == 1 else 61 if s_ in ys else
                                    200 if s_ is t else 5) for s_, (lo, hi) in zip(syms, bt)]
                grid = np.meshgrid(*axes, indexing="ij")
                sampled = float(np.max(np.broadcast_to(np.asarray(
                    sympy.lambdify(syms, slope, "numpy")(*grid), float), grid[0].shape)))
                upper = sup_enclose(fs, bt, target=sampled * (1 + 1e-3) + 1e-12)[1]
                slope_ok &= bool(upper <= sampled * (1 + 1e-3) + 1e-12)
            others = [y for y in ys if y in e.free_symbols and (i >= len(ys) or y is not ys[i])]
            if i >= len(ys) or others:
                sector_ok &= prove_below(fs, box, float(k[i]) * (1 + 1e-9))
                continue
            yi = ys[i]
            r = sympy.factor_terms(sympy.cancel(sympy.together(e / yi)))
            if yi not in sympy.denom(r).free_symbols:
                fr, box, _ = on_box(sympy.Abs(r))
                sector_ok &= prove_below(fr, box, float(k[i]) * (1 + 1e-9))
                continue
            fphi, box, syms = on_box(e)
            fd = iv_function(sympy.diff(e, yi), syms)
            j = syms.index(yi)

            def ratio(*b, j=j, fphi=fphi, fd=fd):
                Y = b[j]
                hull = [*b[:j], iv.mpf([min(Y.a, 0), max(Y.b, 0)]), *b[j + 1:]]
                up = _iv_abs(fd(*hull)).b                         # φ(y)/y = φ'(ξ), ξ between 0 and y
                if not (Y.a > 0 or Y.b < 0):
                    return iv.mpf([0, up])
                direct = _iv_abs(fphi(*b) / Y)                   # (at a point: the value itself)
                return iv.mpf([min(direct.a, up), min(up, direct.b)])
            sector_ok &= prove_below(ratio, box, float(k[i]) * (1 + 1e-9))
        return bool(sector_ok), bool(slope_ok)

    def f1(self, y, t, theta):
        return np.array([np.broadcast_to(np.asarray(fn(*y, t, *theta), float), np.shape(y[0])) for fn in self.fn])

    def __call__(self, y, t, theta):
        if self.kind == "sinusoidal":
            F = float(theta) * np.asarray(self.nl["F_unc"], float)
            return self.N @ (F @ np.asarray(y, float)) * np.sin(float(self.nl["omega"]) * t)
        return self.N @ (self.f1(y, t, theta) - self.f1(y, t, self.nom))

    def thetas(self):
        if self.kind == "sinusoidal":
            g = float(self.nl["gamma_max"])
            return [-g, g]
        return [np.array(c) for c in np.array(np.meshgrid(*[np.linspace(a, b, 5) for a, b in
                                                                zip(self.lo, self.hi)])).reshape(len(self.lo), -1).T]

    def own_sector(self, n=2001):
        """Half-widths k_i with |φ_i| ≤ k_i |y_i|: the sinusoidal form's structural ±N·γ·|F_unc|, an
        expression's sup of |φ_i/y_i| sampled on y_range (every θ corner and nominal value, 64
        times in a period of t), None for the polar arm (its sector is an assumption)."""
        if self.kind == "sinusoidal":
            return np.abs(self.N @ np.asarray(self.nl["F_unc"], float)).sum(axis=1) * float(self.nl["gamma_max"])
        if self.kind != "expression":
            return None
        p = len(self.ys)
        axes = [np.linspace(a, b, n if p == 1 else 81) for a, b in self.y_range]
        Y = np.array([y.ravel() for y in np.meshgrid(*axes, indexing="ij")])
        k = np.zeros(len(self.f))
        for th in self.thetas():
            for tq in np.linspace(0.0, 2 * np.pi, 64):
                ph = np.atleast_2d(self(list(Y), tq, th))
                for i in range(min(len(k), p)):
                    nz = np.abs(Y[i]) > 1e-9
                    k[i] = max(k[i], float(np.max(np.abs(ph[i, nz] / Y[i, nz]))))
        return k

    def sector_and_slopes(self, tt, n=401):
        """(k_i sampled on a dense y grid; per time of ``tt`` the sup over y, θ of
        (Σ_i (Σ_j |∂φ_i/∂y_j|)²)^½ from sympy's derivative), or (k, None) for the sinusoidal form."""
        if self.kind == "sinusoidal":
            k = np.abs(self.N @ np.asarray(self.nl["F_unc"], float)).sum(axis=1) * float(self.nl["gamma_max"])
            return k, None
        if self.kind != "expression":
            return None, None
        p = len(self.ys)
        axes = [np.linspace(a, b, n if p == 1 else 61) for a, b in self.y_range]
        Y = [y.ravel() for y in np.meshgrid(*axes, indexing="ij")]
        tcoarse = tt[:: max(1, tt.size // 400)]
        prof = np.zeros(tcoarse.size)
        for th in self.thetas():
            for q, tq in enumerate(tcoarse):
                rows = []
                for i in range(len(self.f)):
                    J = [np.broadcast_to(np.asarray(df(*Y, tq, *th), float) - np.asarray(df(*Y, tq, *self.nom), float),
                                         Y[0].shape) for df in self.dfn[i]]
                    rows.append(sum(np.abs(j) for j in J))
                rows = np.abs(self.N) @ np.array(rows)
                prof[q] = max(prof[q], float(np.sqrt(np.sum(rows ** 2, axis=0)).max()))
        return None, np.interp(tt, tcoarse, np.maximum.accumulate(prof))


# ----------------------------------------------------------------------------- interval proofs
def _iv_min(*xs):
    xs = [iv.mpf(x) for x in xs]
    return iv.mpf([min(x.a for x in xs), min(x.b for x in xs)])


def _iv_max(*xs):
    xs = [iv.mpf(x) for x in xs]
    return iv.mpf([max(x.a for x in xs), max(x.b for x in xs)])


def _iv_abs(x):
    lo = 0 if x.a <= 0 <= x.b else min(abs(x.a), abs(x.b))
    return iv.mpf([lo, max(abs(x.a), abs(x.b))])


def _iv_heaviside(x, *_):
    return iv.mpf(1) if x.a > 0 else iv.mpf(0) if x.b < 0 else iv.mpf([0, 1])


def _iv_sign(x):
    return iv.mpf(1) if x.a > 0 else iv.mpf(-1) if x.b < 0 else iv.mpf([-1 if x.a < 0 else 0, 1 if x.b > 0 else 0])


#: the names sympy's lambdify prints, bound to interval functions (every one outward rounded)
IV_NAMES = {"sin": iv.sin, "cos": iv.cos, "tan": iv.tan, "exp": iv.exp, "log": iv.log, "sqrt": iv.sqrt,
            "abs": _iv_abs, "Abs": _iv_abs, "min": _iv_min, "max": _iv_max, "Min": _iv_min, "Max": _iv_max,
            "Heaviside": _iv_heaviside, "sgn": _iv_sign, "pi": iv.pi, "E": iv.e}


def iv_function(expr, syms):
    """An interval function of a sympy expression: called with mpmath ``iv`` intervals it returns an
    interval containing every value on their box (a name IV_NAMES lacks raises NameError)."""
    expr = sympy.sympify(expr).replace(sympy.sign, sympy.Function("sgn"))   # (printed as copysign otherwise)
    return sympy.lambdify(syms, expr, modules=[IV_NAMES])


def sup_enclose(fn, box, *, target=None, rtol=1e-3, budget=40_000):
    """Best-first bisection for sup fn on ``box`` (the widest side relative to the box split first):
    (lower, upper) with lower a value fn reaches (at a box's midpoint) and upper ≥ sup fn.  It stops
    when upper ≤ ``target`` or lower > ``target`` (with a target), or when upper ≤ lower·(1 + rtol)
    + 1e-12 (without), or when the budget of boxes runs out."""
    import heapq

    w0 = [max(hi - lo, 1e-300) for lo, hi in box]
    best = [-np.inf]

    def enc(b):
        v = fn(*(iv.mpf(0.5 * (lo + hi)) for lo, hi in b)).a
        best[0] = max(best[0], float(v))
        return float(fn(*(iv.mpf([lo, hi]) for lo, hi in b)).b)

    heap, n = [(-enc(list(box)), 0, list(box))], 1
    while True:
        up = -heap[0][0]
        if target is not None and (up <= target or best[0] > target):
            return best[0], up
        if target is None and up <= best[0] * (1 + rtol) + 1e-12:
            return best[0], up
        if n >= budget:
            return best[0], up
        _, _, b = heapq.heappop(heap)
        k = max(range(len(b)), key=lambda i: (b[i][1] - b[i][0]) / w0[i])
        lo, hi = b[k]
        mid = 0.5 * (lo + hi)
        if not lo < mid < hi:
            return best[0], up
        for part in ((lo, mid), (mid, hi)):
            c = b[:k] + [part] + b[k + 1:]
            heapq.heappush(heap, (-enc(c), n, c))
            n += 1


def prove_below(fn, box, bound):
    """sup fn ≤ bound on ``box``, proved by :func:`sup_enclose` (False: a point above it, or the budget)."""
    return sup_enclose(fn, box, target=bound)[1] <= bound


# ----------------------------------------------------------------------------- the verifier
def verify(cfg: dict, d: dict, *, simulate: bool = True) -> dict:
    """The certificate of a stored design, recomputed.

    Parameters
    ----------
    cfg : dict
        The config (as YAML data).
    d : dict
        ``acmm_qpp.results.read_h5`` of its ``qpp_design.h5`` (A_z, B_z, C_z, a, T, sector).

    Returns
    -------
    dict
        beta1, gamma_inf, m, premises, certified, and (certified designs) the scenario errors.
    """
    # the loop that runs: B_z of eq 10.7, whatever design.bz names for the report's bookkeeping
    Az, Bz, Cz = (np.asarray(d[k], float) for k in ("Az", "Bz_eq10_7", "Cz"))
    a, T = float(d["a"]), float(d["T"])
    p = Cz.shape[0]
    r = Bz.shape[1] - p
    An = Az + a * np.eye(Az.shape[0])
    stable = bool(np.linalg.eigvals(An).real.max() < 0)
    out = {"stable": stable}
    if not stable:
        out.update(certified=False, beta1=np.inf)
        return out
    beta1 = hinf(An, Bz, Cz)
    gam = l2_to_peak(An, Bz, Cz)
    phi = Phi(cfg)
    sector = np.asarray(d["sector"], float)
    k = np.max(np.abs(sector), axis=1)
    own = phi.own_sector()            # φ's sector found here, not read from the tool
    sector_ok = own is not None and bool(np.all(k >= own * (1 - 1e-9)))     # (rounding of k − k°)
    k = k if own is None else np.maximum(k, own)
    sp = cfg["spheres"]
    t_hi = float(cfg["nonlinearity"].get("t_range") or max(float(cfg["simulation"].get("t_final", 10.0)), T))
    if phi.kind in ("sinusoidal", "expression"):     # the sampled sector and slopes, then proved
        sec_proved, slope_proved = phi.prove(np.max(np.abs(sector), axis=1), t_hi, p,
                                             phi.y_range if phi.kind == "expression" else None, T)
        sector_ok = sector_ok and sec_proved
        out["slope_proved"] = slope_proved
    # the premise is decided by the KYP lemma (a Hamiltonian test), the grid kept as a cross-check
    circle = circle_kyp_symmetric(An, Bz[:, p:], Cz, k)
    out["circle_grid"] = circle_symmetric(An, Bz[:, p:], Cz, k)
    beta_o, beta_ri, d_inf = float(sp["beta_o"]), float(sp.get("beta_ri", 0.0)), float(sp.get("d_inf", 0.0))
    # nominal loop ż = A_z z + B_z [r_o; 0] (φ = 0 at θ°)
    sim = cfg["simulation"]
    z0 = np.zeros(Az.shape[0])
    x0 = cfg["plant"].get("x0")
    if x0 is not None:
        n = len(x0)
        z0[:n] = x0
        z0[-n:] = x0
        K1, Kc = np.atleast_2d(d["K1"]), np.atleast_2d(d["Kc"])
        if cfg["plant"].get("xc0") == "equilibrium":
            z0[n:-n] = np.linalg.lstsq(Kc, -K1 @ np.asarray(x0, float), rcond=None)[0]
    ro = sim["r_o"]

    def rhs_nom(t, z):
        return Az @ z + Bz[:, :p] @ np.array([signal(ro[i], t) for i in range(p)])

    tt = np.linspace(0.0, T, 4001)
    sol = solve_ivp(rhs_nom, (0, T), z0, method="LSODA", t_eval=tt, rtol=1e-10, atol=1e-12)
    yo = Cz @ sol.y
    # β3 per T' and β4 per T' (Euclidean; sector bound |φ_i| ≤ k_i |y_o,i|)
    k_s, slope = phi.sector_and_slopes(tt)
    kk = np.maximum(k, k_s) if phi.kind == "sinusoidal" else k
    if phi.kind == "sinusoidal":
        w = float(phi.nl["omega"])
        b3 = np.sqrt(np.sum(kk ** 2)) * np.maximum.accumulate(np.abs(np.sin(w * tt)))
    elif phi.kind == "expression":
        b3 = slope
    else:
        b3 = np.zeros(tt.size)          # polar arm: β3 ≥ 0 left out, so m is an upper bound
    bound2 = sum((k[i] * np.abs(yo[i])) ** 2 for i in range(min(r, p)))
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (bound2[1:] + bound2[:-1]) * np.diff(tt))])
    E = np.sqrt(np.expm1(2 * a * tt) / (2 * a)) if a * T > 1e-8 else np.sqrt(tt * (1 + a * tt))
    with np.errstate(divide="ignore", invalid="ignore"):
        b4 = np.where(tt > 0, np.exp(a * tt) * np.sqrt(cum) / E, 0.0)
    beta_i = np.sqrt(p) * beta_ri + np.sqrt(r) * d_inf
    m_t = beta_o / (beta_i + beta_o * b3 + b4)
    m = float(np.min(m_t[1:]))
    peak = gam * float(np.max(E[1:] / m_t[1:]))
    prem = {"stable": stable, "sector": sector_ok, "circle": circle, "contraction": beta1 < m, "peak": peak <= 1.0}
    if phi.kind == "expression":
        prem["slope"] = out["slope_proved"]
        rng = phi.y_range
        prem["range"] = bool(np.all(yo.min(axis=1) - beta_o >= rng[:, 0]) and np.all(yo.max(axis=1) + beta_o <= rng[:, 1]))
    out.update(beta1=beta1, gamma_inf=gam, m=m, peak=peak, premises=prem, certified=all(prem.values()), y_o=yo, t=tt)
    if out["certified"] and simulate:
        out["errors"] = _scenarios(cfg, phi, Az, Bz, Cz, z0, yo, tt, p, r)
    return out


def _scenarios(cfg, phi, Az, Bz, Cz, z0, yo, tt, p, r):
    """max_t≤T |y − y_o|_∞ per scenario, the nonlinear loop ż = A_z z + B_z [r; φ(C_z z, t, θ)]."""
    sim = cfg["simulation"]
    errs = {}
    for sc in sim["scenarios"]:
        if phi.kind == "expression":
            th = phi.nom.copy()
            for name, v in sc.get("parameters", {}).items():
                th[phi.pnames.index(name)] = float(v)
        else:
            th = float(sc.get("gamma", 0.0))
        dr = sc.get("delta_r", [[] for _ in range(p)])

        def rhs(t, z):
            rr = np.array([signal(sim["r_o"][i], t) + signal(dr[i], t) for i in range(p)])
            y = Cz @ z
            ph = phi(list(y) if phi.kind == "expression" else y, t, th)
            return Az @ z + Bz @ np.concatenate([rr, np.ravel(ph)[:r]])

        sol = solve_ivp(rhs, (tt[0], tt[-1]), z0, method="LSODA", t_eval=tt, rtol=1e-10, atol=1e-12)
        errs[sc["name"]] = float(np.max(np.abs(Cz @ sol.y - yo)))
    return errs
