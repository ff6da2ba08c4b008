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
* the sector proof splits φ_i = y_i·g + ρ (the additive terms y_i divides, their ratio exact) and
  encloses ρ/y alone, so a feature of ρ narrower than any grid costs g nothing (the 1e-9 slope
  spike's sector is proved intact);
* the nominal loop ż = A_z z + B_z [r_o; 0] bounded without an integrator (:func:`nominal_bounds`):
  loop and r_o's exosystem as one autonomous system between r_o's switches, x at the cell edges by
  its matrix exponential, the integrals of β4 exactly by Van Loan's block exponential, and between
  the edges the exponential series' remainder; then (:func:`proved_m`) m bounded from below and
  E/m from above for every truncation time T' ∈ (0, T], and y_o ± β_o inside y_range on every cell;
* β3 per time group: the sinusoidal form's k·sup|sin ωt| in closed form, an expression's slopes
  proved per group by its interval bisection (the sampled slopes when the premise slope fails, as
  the tool reads them), the polar arm's over the sphere (:func:`arm_beta3`: sympy's Jacobian of
  eq 14.2 as a polynomial in the rates, its coefficients' sup proved by interval bisection);
* the scenarios by ``scipy.integrate.solve_ivp`` (LSODA, rtol 1e-10) of
  ż = A_z z + B_z [r; d + φ(C_z z, t)] from the stored A_z, B_z, C_z (eq 10.7), and the nominal
  output the same way for the trapezoid estimate ``m_sampled`` that the proved m must not exceed;
* m = β_o / (β_i + β_o β3 + β4) of the consistent reading, smallest over T' ≤ T, and the
  premises: stable, sector, circle, β1 < m, γ∞ max E/m ≤ 1, y_o ± β_o inside y_range.
"""
from __future__ import annotations

import numpy as np
import sympy
from mpmath import iv
from scipy.integrate import solve_ivp
from scipy.linalg import expm, matrix_balance


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
            # φ = y_i·g + ρ: the additive terms of φ that y_i divides go to g (their ratio exact),
            # the rest ρ (ρ(0) = φ(0) = 0) by its own ratio — a feature of ρ then costs g nothing
            g, rest = sympy.Integer(0), sympy.Integer(0)
            for term in sympy.Add.make_args(sympy.expand(e)):
                q = sympy.cancel(term / yi)
                if yi in sympy.denom(q).free_symbols:
                    rest += term
                else:
                    g += q
            g, rest = sympy.factor_terms(g), sympy.factor_terms(rest)
            if rest == 0:
                fr, box, _ = on_box(sympy.Abs(g))
                sector_ok &= prove_below(fr, box, float(k[i]) * (1 + 1e-9))
                continue
            _, box, syms = on_box(e, need=(yi,))
            fg = iv_function(g, syms)
            frest = iv_function(rest, syms)
            fd = iv_function(sympy.diff(rest, yi), syms)
            j = syms.index(yi)

            def ratio(*b, j=j, fg=fg, frest=frest, fd=fd):
                Y = b[j]
                hull = [*b[:j], iv.mpf([min(Y.a, 0), max(Y.b, 0)]), *b[j + 1:]]
                rr = iv.mpf(fd(*hull))                           # ρ(y)/y = ρ'(ξ), ξ between 0 and y
                if Y.a > 0 or Y.b < 0:
                    direct = iv.mpf(frest(*b)) / Y               # (at a point: the value itself)
                    lo, hi = max(rr.a, direct.a), min(rr.b, direct.b)
                    rr = iv.mpf([lo, hi]) if lo <= hi else direct
                return _iv_abs(iv.mpf(fg(*b)) + rr)
            sector_ok &= prove_below(ratio, box, float(k[i]) * (1 + 1e-9))
        return bool(sector_ok), bool(slope_ok)

    def coupling(self, p):
        """Per φ channel, whether φ_i depends on outputs other than y_i (then |φ_i| ≤ k_i |y|₂):
        an expression's symbols, the off-diagonal entries of N·F_unc, none for the polar arm (its
        sector is stated per channel)."""
        r = self.N.shape[0]
        if self.kind == "sinusoidal":
            Mx = self.N @ np.asarray(self.nl["F_unc"], float)
            return [bool(np.any(np.delete(Mx[i], i) != 0.0)) if i < Mx.shape[1] else True for i in range(r)]
        if self.kind != "expression":
            return [False] * r
        ph, ys, *_ = self.phi_exprs(p)
        return [i >= p or bool(sympy.sympify(e).free_symbols & (set(ys) - {ys[i]})) for i, e in enumerate(ph)]

    def slope_groups(self, p, spans):
        """Per time span (t_a, t_b) of ``spans``, an upper bound of the supremum over y in y_range,
        the parameters' box and t in the span of (Σ_i g_i²)^½, g_i = Σ_j |∂φ_i/∂y_j| — each g_i
        proved by :func:`sup_enclose` (to 1e-4 relative); once for every span when φ does not
        depend on t."""
        ph, ys, t, ths, thbox = self.phi_exprs(p)
        yr = [tuple(map(float, r)) for r in self.y_range]
        ranges = dict(zip([*ys, *ths], [*yr, *thbox]))
        out = np.zeros((len(ph), len(spans)))
        for i, e in enumerate(ph):
            e = sympy.factor_terms(sympy.expand(sympy.sympify(e)))
            slope = sum(sympy.Abs(sympy.factor_terms(sympy.expand(sympy.diff(e, y)))) for y in ys
                        if y in e.free_symbols)
            if slope == 0:
                continue
            syms = [s_ for s_ in ranges if s_ in slope.free_symbols]
            if t not in slope.free_symbols:
                fn = iv_function(slope, syms)
                out[i] = sup_enclose(fn, [ranges[s_] for s_ in syms], rtol=1e-4)[1]
                continue
            fn = iv_function(slope, [*syms, t])
            for q, span in enumerate(spans):
                out[i, q] = sup_enclose(fn, [*(ranges[s_] for s_ in syms), tuple(map(float, span))], rtol=1e-4)[1]
        return np.maximum.accumulate(np.sqrt(np.sum(out ** 2, axis=0)))

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


# ----------------------------------------------------------------------------- the nominal loop, bounded
def _switches(ro, T):
    """Times in (0, T) where a step or ramp of r_o switches on or off (s)."""
    out = set()
    for ch in ro:
        for s in ch:
            if s["kind"] in ("step", "ramp"):
                for key in ("t_on", "t_off"):
                    x = s.get(key)
                    if x is not None and 0.0 < float(x) < T:
                        out.add(float(x))
    return sorted(out)


def _exo(ro, t_a, t_b):
    """r_o on [t_a, t_b) (no switch inside) as the output of a linear exosystem: (S, Q, w(t_a)),
    w' = S w, r_o = Q w; per sine the pair (sin, cos) of its argument times its amplitude, per
    channel an offset and its slope (steps and ramps active at the middle of the interval)."""
    p = len(ro)
    sines = [(i, s) for i, ch in enumerate(ro) for s in ch if s["kind"] == "sin"]
    n = 2 * len(sines) + 2 * p
    S, Q, w = np.zeros((n, n)), np.zeros((p, n)), np.zeros(n)
    mid = 0.5 * (t_a + t_b)
    for q, (i, s) in enumerate(sines):
        amp, om, ph = float(s.get("amplitude", 1.0)), float(s.get("omega", 1.0)), float(s.get("phase", 0.0))
        S[2 * q, 2 * q + 1], S[2 * q + 1, 2 * q] = om, -om
        Q[i, 2 * q] = 1.0
        w[2 * q], w[2 * q + 1] = amp * np.sin(om * t_a + ph), amp * np.cos(om * t_a + ph)
    for i, ch in enumerate(ro):
        c = 2 * len(sines) + 2 * i
        S[c, c + 1] = 1.0
        Q[i, c] = 1.0
        w[c] = signal([s for s in ch if s["kind"] != "sin"], t_a)       # the offset at t_a
        for s in ch:
            if s["kind"] == "ramp":
                on = float(s.get("t_on") or 0.0)
                off = s.get("t_off")
                if on <= mid and (off is None or mid < float(off)):
                    w[c + 1] += float(s.get("amplitude", 1.0))
    return S, Q, w


def nominal_bounds(Az, Br, z0, ro, T, *, cells=4096, stiff=0.5):
    """The nominal loop ż = A_z z + B_r r_o(t), z(0) = z0 on [0, T], written as the autonomous
    x' = M x of the loop and r_o's exosystem between r_o's switches, and bounded without any
    integrator:

    * x at the cell edges by x_{j+1} = e^{Mh} x_j;
    * the integral ∫ x(t)ᵀ W x(t) dt over a cell exactly as x_jᵀ (∫₀^h e^{Mᵀs} W e^{Ms} ds) x_j, the
      bracket by Van Loan's block exponential (``integral``);
    * on a cell, x(t_j + s) = x_j + s M x_j + ρ with ‖ρ‖₂ ≤ ‖M x_j‖₂ (e^{‖M‖h} − 1 − ‖M‖h)/‖M‖ (the
      exponential series from its second term on; ‖M‖ the spectral norm), so an output row c lies
      between the ends of c x_j + s c M x_j widened by ‖c‖₂‖ρ‖ (``box``).

    All of this runs in the coordinates x = D x̃ of LAPACK's balancing (``scipy.linalg.matrix_balance``,
    D diagonal with powers of 2, so the similarity is exact): a loop with large gains has ‖M‖ many
    orders above its largest |eigenvalue| (ch. 13's certified design: 1e11 against 1e4), and the
    cells the remainder needs follow ‖D⁻¹MD‖.

    Returns a dict: edges (K + 1,), x (n, K + 1) at the edges, and the functions ``box(Crow)`` →
    (lo, hi) per cell and ``integral(W)`` → ∫₀^{t_j} xᵀ W x at every edge (W on the loop's states)."""
    Az, Br = np.asarray(Az, float), np.atleast_2d(np.asarray(Br, float))
    N, p = Az.shape[0], Br.shape[1]
    cuts = [0.0, *_switches(ro, T), float(T)]
    segs = []
    x = np.asarray(z0, float)
    for t_a, t_b in zip(cuts[:-1], cuts[1:]):
        S, Q, w = _exo(ro, t_a, t_b)
        M0 = np.block([[Az, Br @ Q], [np.zeros((S.shape[0], N)), S]])
        M, (D, _) = matrix_balance(M0, permute=False, separate=True)       # M = D⁻¹ M0 D
        nM = float(np.linalg.norm(M, 2))
        # as many cells as the unscaled norm asks where that is affordable (finer boxes), else as
        # the balanced one asks
        count = [int(np.ceil(max((t_b - t_a) / (T / cells), (t_b - t_a) * v / stiff) - 1e-9))
                 for v in (float(np.linalg.norm(M0, 2)), nM)]
        n = count[0] if count[0] <= 400_000 else count[1]
        if n > 400_000:
            raise ValueError("loop too stiff for the verifier's cells")
        h = (t_b - t_a) / n
        Phi = expm(M * h)
        X = np.empty((M.shape[0], n + 1))
        X[:, 0] = np.concatenate([x[:N], w]) / D
        for j in range(n):
            X[:, j + 1] = Phi @ X[:, j]
        x = X[:N, -1] * D[:N]
        segs.append((t_a, h, n, M, nM, X, D))
    edges = np.concatenate([[0.0]] + [t_a + h * np.arange(1, n + 1) for t_a, h, n, *_ in segs])
    edges[-1] = T

    def box(c):
        c = np.asarray(c, float)
        lo, hi = [], []
        for t_a, h, n, M, nM, X, D in segs:
            cx = np.concatenate([c, np.zeros(M.shape[0] - N)]) * D
            v0 = cx @ X[:, :-1]
            v1 = v0 + h * (cx @ M @ X[:, :-1])
            rem = np.linalg.norm(M @ X[:, :-1], axis=0) * (np.expm1(nM * h) - nM * h) / max(nM, 1e-300)
            rad = np.linalg.norm(cx) * rem * (1 + 1e-9) + 1e-9 * (np.abs(v0) + np.abs(v1)) + 1e-300
            lo.append(np.minimum(v0, v1) - rad)
            hi.append(np.maximum(v0, v1) + rad)
        return np.concatenate(lo), np.concatenate(hi)

    def integral(W):
        out = [0.0]
        for t_a, h, n, M, nM, X, D in segs:
            d = M.shape[0]
            Wx = np.zeros((d, d))
            Wx[:N, :N] = W * np.outer(D[:N], D[:N])
            F = expm(np.block([[-M.T, Wx], [np.zeros((d, d)), M]]) * h)
            G = F[d:, d:].T @ F[:d, d:]                                   # ∫₀^h e^{Mᵀs} W e^{Ms} ds
            G = 0.5 * (G + G.T)
            inc = np.einsum("ij,ik,kj->j", X[:, :-1], G, X[:, :-1])
            out.extend(out[-1] + np.cumsum(np.maximum(inc, 0.0)))
        return np.asarray(out) * (1 + 1e-9)

    return {"edges": edges, "x": np.hstack([s[5][:N, :-1] * s[6][:N, None] for s in segs] + [x[:, None]]), "box": box,
            "integral": integral}


def proved_m(nb, Cz, k, coupled, a, beta_o, beta_i, b3):
    """m = β_o/(β_i + β_o β3 + β4) bounded from below for every truncation time T' ∈ (0, T], and
    γ∞-free max E/m bounded from above, from :func:`nominal_bounds`.

    The integrand of β4 is f = Σ_i k_i² y_o,i² (k_i² |y_o|² for a coupled channel), f = yᵀ D y.
    For T' = t_j + x in a cell of width h: I(T') ≤ I(t_j) + x F_j (F_j ≥ sup f on the cell, from the
    boxes), E(T')² ≥ E(t_j)² + x (dE²/dt = e^{2at} ≥ 1), and (I + xF)/(E² + x) is monotone in x, so
    β4(T') ≤ e^{a t_{j+1}} (the larger of its values at x = 0, h)^½; β3(T') ≤ ``b3[j]`` (a bound of the
    supremum over [0, t_{j+1}]).  E/m = [E (β_i + β_o β3) + e^{aT'} I(T')^½] / β_o is nondecreasing in
    T', so its largest value is at T (I(T) exact)."""
    edges = nb["edges"]
    p = Cz.shape[0]
    k = np.asarray(k, float)
    dvec = np.zeros(p)
    for i in range(k.size):
        if coupled[i] or i >= p:
            dvec += k[i] ** 2
        else:
            dvec[i] += k[i] ** 2
    I = nb["integral"](Cz.T @ np.diag(dvec) @ Cz)
    F = np.zeros(edges.size - 1)
    for i in range(p):
        if dvec[i] > 0:
            lo, hi = nb["box"](Cz[i])
            F += dvec[i] * np.maximum(lo ** 2, hi ** 2)
    F *= 1 + 1e-9
    h = np.diff(edges)
    E2 = np.where(a * edges < 1e-8, edges, np.expm1(2 * a * edges) / (2 * a if a else 1.0)) * (1 - 1e-9)
    with np.errstate(divide="ignore", invalid="ignore"):
        r0 = np.where(E2[:-1] > 0, I[:-1] / E2[:-1], 0.0)
    r1 = (I[:-1] + h * F) / (E2[:-1] + h)
    b4 = np.exp(a * edges[1:]) * np.sqrt(np.maximum(r0, r1))
    m_cells = beta_o / (beta_i + beta_o * np.asarray(b3, float) + b4)
    j = int(np.argmin(m_cells))
    T = edges[-1]
    E_T = np.sqrt(np.expm1(2 * a * T) / (2 * a)) if a * T > 1e-8 else np.sqrt(T * (1 + a * T))
    e_over_m = (E_T * (beta_i + beta_o * float(b3[-1])) + np.exp(a * T) * np.sqrt(I[-1])) / beta_o
    return {"m": float(m_cells[j]), "beta3": float(b3[j]), "beta4": float(b4[j]), "T_worst": float(edges[j + 1]),
            "E_over_m": float(e_over_m) * (1 + 1e-9)}


# ----------------------------------------------------------------------------- β3 per time group
def sinusoid_beta3(kk, omega, ends):
    """(Σ k_i²)^½ sup_{[0, t]} |sin ωt| at the times ``ends``, in closed form."""
    wt = omega * np.asarray(ends, float)
    return np.sqrt(np.sum(np.asarray(kk, float) ** 2)) * np.where(wt >= np.pi / 2, 1.0, np.abs(np.sin(wt)))


def _groups(edges, n):
    """Cells split into ``n`` consecutive groups: (index of the group of every cell, group ends)."""
    K = edges.size - 1
    parts = np.array_split(np.arange(K), min(n, K))
    gid = np.concatenate([np.full(g.size, q) for q, g in enumerate(parts)])
    return gid, np.array([edges[g[-1] + 1] for g in parts]), [(edges[g[0]], edges[g[-1] + 1]) for g in parts]


def arm_beta3(cfg, nb, Cz, An, Bz, beta_o, gam, n_groups=32):
    """The polar arm's β3 over the sphere, written from eq 14.2 (f1 = [R/(μ+M) x4²; −2 R x3 x4 / I],
    R = μ x1 + M (x1 + a), I = J1 + J2 + μ x1² + M (x1 + a)², y = (x1, x2), z = [x; x_c; x̂]):
    sympy differentiates φ = N (f1(M) − f1(M°)) in y and writes each entry of the Jacobian as a
    polynomial in the rates x3, x4 whose coefficients are rational in (x1, M); every coefficient's
    sup |·| over x1 ∈ y_o,1 ± β_o and M ∈ [M_min, M_max] is proved by the interval bisection
    :func:`sup_enclose`, the monomials' sup over the rates' box per time group (the nominal rates'
    bounds ± ρ_v, ρ_v = γ_v β_o / γ∞, γ_v the L2-to-peak gain to the rates), and the spectral norm
    is bounded by the Frobenius norm.  Returns (bound per cell, nondecreasing; ρ_v)."""
    nl = cfg["nonlinearity"]
    B = np.atleast_2d(np.asarray(cfg["plant"]["B"], float))
    G = np.atleast_2d(np.asarray(cfg["plant"]["G"], float))
    N = np.linalg.lstsq(G, B, rcond=None)[0]
    x1, x2, x3, x4, M = sympy.symbols("x1 x2 x3 x4 M", real=True)
    mu, a, J = (sympy.nsimplify(float(nl[k])) for k in ("mu", "a", "J1"))
    J = J + sympy.nsimplify(float(nl["J2"]))
    M0 = sympy.nsimplify(0.5 * (float(nl["M_min"]) + float(nl["M_max"])))

    def f1(m):
        R = mu * x1 + m * (x1 + a)
        inertia = J + mu * x1 ** 2 + m * (x1 + a) ** 2
        return [R / (mu + m) * x4 ** 2, -2 * R * x3 * x4 / inertia]

    d = [u - v for u, v in zip(f1(M), f1(M0))]
    phi = [sum(sympy.nsimplify(float(N[i, k])) * d[k] for k in range(2)) for i in range(N.shape[0])]
    n_st = An.shape[0]
    Cv = np.zeros((2, n_st))
    Cv[0, 2] = Cv[1, 3] = 1.0
    rho_v = l2_to_peak(An, Bz, Cv) * beta_o / gam
    lo1, hi1 = nb["box"](Cz[0])
    x1box = (float(lo1.min() - beta_o), float(hi1.max() + beta_o))
    mbox = (float(nl["M_min"]), float(nl["M_max"]))
    terms = []                                  # per Jacobian entry: [(C = sup|coefficient|, (i3, i4))]
    for e in phi:
        for y in (x1, x2):
            entry = sympy.cancel(sympy.together(sympy.diff(e, y)))
            if entry == 0:
                continue
            num, den = sympy.fraction(entry)
            assert not den.free_symbols & {x3, x4}
            row = []
            for (i3, i4), c in sympy.Poly(num, x3, x4).terms():
                coef = sympy.factor(c / den)
                up = sup_enclose(iv_function(sympy.Abs(coef), [x1, M]), [x1box, mbox], rtol=1e-4)[1]
                row.append((up, i3, i4))
            terms.append(row)
    gid, ends, _ = _groups(nb["edges"], n_groups)
    l3, h3 = nb["box"](Cv[0])
    l4, h4 = nb["box"](Cv[1])
    g = np.zeros(ends.size)
    for q in range(ends.size):
        sel = gid == q
        r3 = max(abs(l3[sel].min() - rho_v), abs(h3[sel].max() + rho_v))
        r4 = max(abs(l4[sel].min() - rho_v), abs(h4[sel].max() + rho_v))
        g[q] = np.sqrt(sum(sum(c * r3 ** i3 * r4 ** i4 for c, i3, i4 in row) ** 2 for row in terms))
    return np.maximum.accumulate(g * (1 + 1e-9))[gid], rho_v


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
    beta_i = np.sqrt(p) * beta_ri + np.sqrt(r) * d_inf
    coupled = phi.coupling(p)
    # β3 and β4 bounded for every truncation time T' ∈ (0, T]: the nominal loop by the matrix
    # exponential of loop and exosystem with Van Loan's integrals and a series remainder on each cell
    nb = nominal_bounds(Az, Bz[:, :p], z0, [ro[i] for i in range(p)], T)
    edges = nb["edges"]
    gid, ends, spans = _groups(edges, 128)
    if phi.kind == "sinusoidal":
        k_s, _ = phi.sector_and_slopes(tt)
        kk = np.maximum(k, k_s)
        b3_cells = sinusoid_beta3(kk, float(phi.nl["omega"]), edges[1:])
    elif phi.kind == "expression" and not out["slope_proved"]:
        # the premise slope fails: m read with the sampled slopes it could not prove (as the
        # tool's; each premise is decided given the others, and no certificate follows anyway)
        _, prof = phi.sector_and_slopes(tt)
        b3_cells = np.interp(edges[1:], tt, prof)
    elif phi.kind == "expression":
        b3_cells = phi.slope_groups(p, [(0.0, e) if q == 0 else (spans[q][0], e) for q, e in enumerate(ends)])[gid]
    else:
        b3_cells, out["rho_v"] = arm_beta3(cfg, nb, Cz, An, Bz, beta_o, gam)
    pm = proved_m(nb, Cz, k, coupled, a, beta_o, beta_i, b3_cells)
    m, peak = pm["m"], gam * pm["E_over_m"]
    out.update(beta3=pm["beta3"], beta4=pm["beta4"], T_worst=pm["T_worst"])
    # cross-check: the trapezoid rule on the LSODA samples (an estimate m bounds from below)
    ynorm = np.sqrt(np.sum(yo ** 2, axis=0))
    bound2 = sum((k[i] * (ynorm if (coupled[i] or i >= p) else np.abs(yo[i]))) ** 2 for i in range(k.size))
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (bound2[1:] + bound2[:-1]) * np.diff(tt))])
    E = np.sqrt(np.expm1(2 * a * tt) / (2 * a)) if a * T > 1e-8 else np.sqrt(tt * (1 + a * tt))
    b3_t = b3_cells[np.clip(np.searchsorted(edges, tt, side="left") - 1, 0, b3_cells.size - 1)]
    with np.errstate(divide="ignore", invalid="ignore"):
        b4_t = np.exp(a * tt[1:]) * np.sqrt(cum[1:]) / E[1:]
    out["m_sampled"] = float(np.min(beta_o / (beta_i + beta_o * b3_t[1:] + b4_t)))
    prem = {"stable": stable, "sector": sector_ok, "circle": circle, "contraction": beta1 < m, "peak": peak <= 1.0}
    if phi.kind == "expression":
        prem["slope"] = out["slope_proved"]
        rng = phi.y_range
        ok = True
        for i in range(p):           # y_o ± β_o inside y_range on every cell
            lo, hi = nb["box"](Cz[i])
            ok &= bool(lo.min() - beta_o >= rng[i, 0] and hi.max() + beta_o <= rng[i, 1])
        prem["range"] = ok
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
