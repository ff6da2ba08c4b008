"""Design procedure of ch. 12.1 and the guarantee certificate (theorem 2, lemma 1).

Steps (the iteration target is the bookkeeping ``design.bookkeeping``), see :func:`design`:
(1) a, T and the threshold m from β_o, β_ri, ‖d‖∞, β3, β4 (12.1); (2) H∞ gains (ch. 11, with the
steps 1–8 search when ``hinf.search``) and β1 = ‖C_z (sI − A_n)⁻¹ B_z‖∞; (3) T adapted to the
closed loop's settling time, m recomputed; β1 > m → ρ decreased; (4) circle criterion on
H(−a + jω), a adjusted both ways within [a_min, a_max] when it fails; (5) repeat until β1 ≤ m and
the circle criterion holds.  When that loop fails, a wider search (other W_s = w·S_c weights, a
bracketing search over ρ) runs before the verdict "no certified design".

Thresholds are reported in three bookkeepings (``docs/ERRATA.md`` § QPP thresholds):

* ``"printed"``: the report's printed β3, β4 (when given in the config);
* ``"report"``: the report's arithmetic — sector half-width without the factor N of B = G N
  (0.05 in ch. 13), β3 = k‖(sin ωt)_T‖₂ (10.54), β4 = k‖(y_o)_T‖₂ (10.55);
* ``"circle"``: the same formulas with the half-width of the sector used in the circle check
  (N·γ_max = 0.5 in ch. 13), i.e. one consistent sector for both conditions.
For the polar arm, β3 and β4 are evaluated along the nominal trajectory (sup over M at the
bounds) by central differences; ``"report"`` and ``"circle"`` then coincide.
"""
from __future__ import annotations

import numpy as np

from acmm_qpp.errors import ConfigError, ConvergenceError, DesignError
from qpp.design import circle as circle_mod
from qpp.design import spheres
from qpp.design.certificate import DesignResult, certify, default_sector, sector_coupling
from qpp.io.config import QppConfig
from qpp.design.hinf import HinfGains, closed_loop_norm, existence_tests, hinf_gains, hinf_search
from qpp.model.lure import LurePlant, channels, closed_loop, structural_obstacles
from acmm_qpp.limits import how_to_raise, limit
from qpp import LIMITS
from qpp.simulate.closed_loop import check_work


# ---------------------------------------------------------------------- the wider search
#: Points of the wider search's scan of log10 ρ over [design.rho_min, design.rho_max]: the grid
#: point of smallest β1 and its two neighbours bracket the ρ minimizing β1.
WIDER_GRID_POINTS = 21
#: Golden-section steps refining that bracket, a fixed count (no tolerance test): 10 steps shrink
#: the bracket (two grid cells, one at an end of the grid) by 0.618¹⁰ ≈ 0.008, to about 8e-4 of
#: the scanned range of log10 ρ.
GOLDEN_STEPS = 10
#: Factors of the per-channel weightings tried when the servo-compensator has several outputs.
CHANNEL_FACTORS = (3.0, 1 / 3.0)
#: The inverse golden ratio (√5 − 1)/2 ≈ 0.618 of the golden-section interior points.
_INV_GOLDEN = (np.sqrt(5) - 1) / 2


# ---------------------------------------------------------------------- procedure 12.1
def weighted_plant(P: LurePlant, ws) -> LurePlant:
    """The plant with the H∞ output weight W_s = diag(ws)·S_c (z = [ρu; W_s e], eq 13.5).

    Parameters
    ----------
    P : qpp.model.lure.LurePlant
        Lure plant with servo-compensator (eqs 10.1, 13.1), in the config's units.
    ws : float or (k,) array
        Weight w per compensator output, dimensionless (a scalar applies to all).

    Returns
    -------
    qpp.model.lure.LurePlant
        The same plant with the compensator output matrix C_c replaced by diag(w)·C_c.
    """
    w = np.broadcast_to(np.asarray(ws, float), (P.Cc.shape[0],))
    return LurePlant(P.A, P.B, P.C, P.G, P.Ac, P.Bc, np.diag(w) @ P.Cc)


class _Procedure:
    """State of one run of procedure 12.1 (every evaluation is recorded)."""

    def __init__(self, cfg: QppConfig):
        self.cfg = cfg
        self.hc, self.dc = cfg.hinf, cfg.design
        self.P = cfg.lure_plant()
        a0 = self.hc.a
        self.a_min = min(a0, self.dc.a_min if self.dc.a_min is not None else a0 * 1e-4)
        self.a_max = max(a0, self.dc.a_max if self.dc.a_max is not None else a0)
        self.records: list[dict] = []
        self.hist: list[dict] = []
        self.best: DesignResult | None = None
        self.work = 0.0          # integration work of the nominal loops so far (qpp.simulate.closed_loop.check_work)

    # -- gains -----------------------------------------------------------------
    def gains(self, rho, a, ws, target=None) -> HinfGains | None:
        hc, dc = self.hc, self.dc
        Pw = weighted_plant(self.P, ws)
        try:
            if hc.search:
                g = hinf_search(Pw, rho=rho, a=a, nu=None, weight=hc.weight, observer=hc.observer, bz=dc.bz,
                                rho_factor=dc.rho_factor, rho_min=dc.rho_min, target=target)
                passes = g.history
            else:
                g = hinf_gains(Pw, rho=rho, a=a, nu=hc.nu, weight=hc.weight, observer=hc.observer)
                tests = existence_tests(g)
                passes = [{"rho": rho, "nu": hc.nu, "delta": closed_loop_norm(Pw, g, bz=dc.bz), **tests,
                           "admissible": bool(tests["k_psd"] and tests["h_psd"] and tests["spectral"]),
                           "action": "fixed nu"}]
            self.hist.extend({**h, "a": a, "ws": float(np.mean(ws))} for h in passes)
            return g
        except (DesignError, ConvergenceError) as exc:
            self.records.append(self._rec("riccati", rho, a, ws, note=str(exc)))
            return None

    def beta1_only(self, rho, a, ws) -> float:
        """β1 of the fixed-ν gains at (ρ, a, W_s) — cheap, for the bracketing search."""
        try:
            g = hinf_gains(weighted_plant(self.P, ws), rho=rho, a=a, nu=self.hc.nu, weight=self.hc.weight,
                           observer=self.hc.observer)
            Az, Bz, Cz = closed_loop(self.P, g.K1, g.Kc, g.H, bz=self.dc.bz)
            An = Az + a * np.eye(len(Az))
            return np.inf if np.linalg.eigvals(An).real.max() >= 0 else spheres.hinf_norm(An, Bz, Cz)[0]
        except Exception:                              # noqa: BLE001 - any failure: not a candidate
            return np.inf

    # -- evaluation --------------------------------------------------------------
    @staticmethod
    def _rec(stage, rho, a, ws, nu=np.nan, T=np.nan, delta=np.nan, b1=np.nan, m=np.nan, circle=False, cert=False,
             note=""):
        return {"stage": stage, "rho": float(rho), "nu": float(nu), "a": float(a), "T": float(T),
                "delta": float(delta), "beta1": float(b1), "m": float(m), "circle": bool(circle),
                "certified": bool(cert), "ws": [float(x) for x in np.atleast_1d(ws)], "note": note}

    def evaluate(self, g: HinfGains, a, T, ws, stage) -> DesignResult:
        """Step 1/3: β1, m (recomputed at this a, T and these gains), circle criterion."""
        self._budget(g, T)
        res = certify(self.cfg, g.K1, g.Kc, g.H, a, "hinf", g, T=T)
        res.ws_scale = [float(x) for x in np.atleast_1d(ws)]

        delta = closed_loop_norm(weighted_plant(self.P, ws), g, bz=self.dc.bz)
        self.records.append(self._rec(stage, g.rho, a, ws, g.nu, T, delta, res.beta1_ref, res.m_ref,
                                      res.circle.passed, res.certified))
        if self.best is None or _score(res) < _score(self.best):
            self.best = res
        return res

    def _budget(self, g: HinfGains, T) -> None:
        """Each evaluation integrates the nominal loop over max(T, simulation.t_final) (for its
        thresholds): the work of all of them is bounded by ``QPP_WORK`` (issue 13), so that a long
        horizon is refused in seconds instead of running for hours through the wider search."""
        horizon = max(float(T), self.cfg.simulation.t_final)
        try:
            self.work += check_work(self.cfg, g.K1, g.Kc, g.H, runs=1, horizon=horizon)
        except ConfigError:
            self.work = np.inf
        if self.work > limit("QPP_WORK", LIMITS):
            given, tf = self.cfg.spheres.T, self.cfg.simulation.t_final
            field, value = (("spheres.T", f"{given:g} s" + (f" (adapted to {T:g} s)" if T != given else ""))
                            if T > tf else ("simulation.t_final", f"{tf:g} s"))
            raise ConfigError(f"{field}: {value} is too long for the design: "
                              f"each of its candidate loops is integrated over max(spheres.T, t_final) = "
                              f"{horizon:g} s, {len(self.records) + 1} so far (work {self.work:.3g}); shorten "
                              f"t_final or spheres.T ({how_to_raise('QPP_WORK', LIMITS)})")

    def adapt_T(self, g, a, T, ws, res, stage) -> tuple[DesignResult, float]:
        """Step 3: T ← settling time of the closed loop until they agree within 10 %."""
        if not self.cfg.spheres.adapt_T:
            return res, T
        T_hi = max(self.cfg.simulation.t_final, self.cfg.spheres.T)
        for _ in range(4):
            Ts = float(np.clip(res.T_settle, 1e-3 * T_hi, T_hi))
            if abs(Ts - T) <= 0.1 * T:
                break
            T = Ts
            res = self.evaluate(g, a, T, ws, stage + " T")
        return res, T

    def circle_a(self, g, a) -> float | None:
        """Step 4: an a passing the circle criterion with these gains, searched both ways from the
        current a on a geometric grid of [a_min, a_max] (nearest first); None when none passes."""
        _, dcols = channels(self.P)
        Az, Bz, Cz = closed_loop(self.P, g.K1, g.Kc, g.H, bz="eq10.7")
        sector, coupled = default_sector(self.cfg), sector_coupling(self.cfg)
        lo = max(self.a_min, 1e-14)
        grid = np.unique(np.concatenate([np.geomspace(lo, max(self.a_max, lo), 13), [self.a_min, self.a_max]]))
        grid = sorted(grid[grid != a], key=lambda x: abs(np.log(max(x, 1e-300)) - np.log(max(a, 1e-300))))
        for cand in grid:
            ok = circle_mod.circle_criterion(Az, Bz[:, dcols], Cz, sector, a=float(cand), coupled=coupled).passed
            self.records.append(self._rec("circle a", g.rho, cand, [1.0], nu=g.nu, circle=ok,
                                          note="circle criterion with fixed gains"))
            if ok:
                return float(cand)
        return None

    # -- the loops -----------------------------------------------------------------
    def report_loop(self, ws=(1.0,), stage="12.1") -> DesignResult | None:
        """Steps 1–5 of 12.1 from the configured ρ, a, T and the output weight W_s = diag(ws)·S_c."""
        dc = self.dc
        rho, a, T = self.hc.rho, self.hc.a, self.cfg.spheres.T
        ws = np.asarray(ws, float)
        prev_b1, m_est = np.inf, None
        tried_a = set()
        if self.hc.search:                                      # step 1: m from a first fixed-nu design
            try:
                g0 = hinf_gains(weighted_plant(self.P, ws), rho=rho, a=a, nu=self.hc.nu, weight=self.hc.weight,
                                observer=self.hc.observer)
                r0 = self.evaluate(g0, a, T, ws, stage + " step 1")
                r0, T = self.adapt_T(g0, a, T, ws, r0, stage + " step 1")
                m_est = r0.m_ref
            except (DesignError, ConvergenceError):
                m_est = None
        for _ in range(dc.max_iter):
            g = self.gains(rho, a, ws, target=m_est)
            if g is None:
                rho *= dc.rho_factor
                if rho < dc.rho_min:
                    return None
                continue
            res = self.evaluate(g, a, T, ws, stage)
            res, T = self.adapt_T(g, a, T, ws, res, stage)
            m_est = res.m_ref
            if res.lhs_ref > res.m_ref:                       # step 3: decrease rho
                if res.lhs_ref >= prev_b1 * (1 - 1e-9) or g.rho * dc.rho_factor < dc.rho_min:
                    return None
                prev_b1 = res.lhs_ref
                rho = g.rho * dc.rho_factor
                continue
            if not res.circle.passed:                           # step 4: adjust a, back to step 1
                tried_a.add(a)
                a_new = self.circle_a(g, a)
                if a_new is None or a_new in tried_a:
                    return None
                a = a_new
                continue
            return self.raise_a(g, res, a, T, ws, stage)       # certified (step 5)
        return None

    def raise_a(self, g, res, a, T, ws, stage) -> DesignResult:
        """'a adjusted both ways': with a certified design, try a larger a (a faster guaranteed
        exponential rate, 10.27) up to a_max while β1 ≤ m and the circle criterion still hold."""
        while a < self.a_max * (1 - 1e-12):
            a_up = min(self.a_max, max(a, 1e-12) / self.dc.a_factor)
            g2 = self.gains(g.rho, a_up, ws, target=res.m_ref)
            if g2 is None:
                break
            r2 = self.evaluate(g2, a_up, T, ws, stage + " a up")
            if not _meets(r2):
                break
            g, res, a = g2, r2, a_up
        return res

    def wider(self) -> DesignResult | None:
        """The wider search after steps 1–5 failed (ch. 15: a controller exists when min over ρ, W_s of
        β1 < m): per W_s of :func:`_ws_candidates`, the ρ minimizing β1, finished by steps 2–4, all at
        the best design's a; the first design meeting its target, else None."""
        a = self.best.a
        for ws in _ws_candidates(self.P.Cc.shape[0], self.dc.ws_scales):
            rho = self._rho_minimizing_beta1(a, ws)
            if rho is None:
                self.records.append(self._rec("wider", np.nan, a, ws, b1=np.inf,
                                              note="no stabilizing gains for any rho"))
                continue
            res = self._finish_candidate(rho, a, ws)
            if res is not None and _meets(res):
                return res
        return None

    def _rho_minimizing_beta1(self, a, ws) -> float | None:
        """Step 2 over all ρ for one W_s (a in 1/s): β1 of the fixed-ν gains scanned on
        WIDER_GRID_POINTS points of log10 ρ in [rho_min, rho_max], the bracket of the best point
        golden-section refined; the ρ of the smallest β1 evaluated, None when none stabilizes."""
        dc = self.dc
        lr = np.linspace(np.log10(dc.rho_min), np.log10(dc.rho_max), WIDER_GRID_POINTS)
        vals = np.array([self.beta1_only(10 ** x, a, ws) for x in lr])
        if not np.isfinite(vals).any():
            return None
        k = int(np.argmin(vals))
        lo, hi = lr[max(k - 1, 0)], lr[min(k + 1, lr.size - 1)]
        refined = _golden_section(lambda x: self.beta1_only(10 ** x, a, ws), lo, hi)
        return 10 ** min([(vals[k], lr[k]), *refined])[1]

    def _finish_candidate(self, rho, a, ws) -> DesignResult | None:
        """Steps 2–4 once at the wider search's ρ, W_s (a in 1/s): gains (target: the best m), β1 and m
        from the best design's T, T adapted; β1 ≤ m with the circle failing → one retry at another a.
        The evaluated design, None when no gains exist at this ρ."""
        g = self.gains(rho, a, ws, target=self.best.m_ref)
        if g is None:
            return None
        res = self.evaluate(g, a, self.best.T, ws, "wider")
        res, T = self.adapt_T(g, a, res.T, ws, res, "wider")
        if res.lhs_ref <= res.m_ref and not res.circle.passed:
            # step 4 ("otherwise adjust a"); res kept when no a passes or no gains exist there
            a_new = self.circle_a(g, a)
            g2 = None if a_new is None else self.gains(rho, a_new, ws)
            if g2 is not None:
                res = self.evaluate(g2, a_new, T, ws, "wider a")
        return res


def _ws_candidates(p_w: int, ws_scales) -> list[np.ndarray]:
    """The weights w (dimensionless, per compensator output, in the order tried) of W_s = diag(w)·S_c in
    the wider search: w·(1, …, 1) per ``design.ws_scales``; for p_w > 1 outputs also each channel
    alone times each factor of CHANNEL_FACTORS."""
    weights = [np.full(p_w, w) for w in ws_scales]
    if p_w > 1:
        weights += [np.where(np.arange(p_w) == i, w, 1.0) for i in range(p_w) for w in CHANNEL_FACTORS]
    return weights


def _golden_section(f, lo, hi, steps: int = GOLDEN_STEPS) -> tuple[tuple, tuple]:
    """Golden-section refinement of a minimum of f(x = log10 ρ) bracketed by [lo, hi]: a fixed ``steps``
    (no tolerance test; ties keep the lower point); the two last interior points ((f1, x1), (f2, x2))."""
    x1, x2 = hi - _INV_GOLDEN * (hi - lo), lo + _INV_GOLDEN * (hi - lo)
    f1, f2 = f(x1), f(x2)
    for _ in range(steps):
        if f1 <= f2:
            hi, x2, f2 = x2, x1, f1
            x1 = hi - _INV_GOLDEN * (hi - lo)
            f1 = f(x1)
        else:
            lo, x1, f1 = x1, x2, f2
            x2 = lo + _INV_GOLDEN * (hi - lo)
            f2 = f(x2)
    return (f1, x1), (f2, x2)


def _meets(res: DesignResult) -> bool:
    """The design's target (procedure 12.1, step 5): ``lhs_ref`` ≤ m of its bookkeeping and the
    circle criterion.  The verdict ``certified`` is the consistent certificate's (all premises)."""
    return bool(res.lhs_ref <= res.m_ref and res.circle.passed)


def _score(res: DesignResult) -> tuple:
    """Order of designs: certified first, then target met, then circle passed, then smaller β1/m."""
    return (not res.certified, not _meets(res), not res.circle.passed, res.lhs_ref / max(res.m_ref, 1e-300))


def limiting_factor(cfg: QppConfig, res: DesignResult) -> tuple[str, str]:
    """Why the best design is not certified, in words and numbers, and which setting to change.

    Parameters
    ----------
    cfg : qpp.io.config.QppConfig
        The config (its ``spheres`` section: β_o, β_ri, ‖d‖∞ in the config's units).
    res : DesignResult
        The best, uncertified design.

    Returns
    -------
    text : str
        The failing condition (circle criterion, or β1 > m of eq 12.1 with its largest term).
    hint : str
        Which settings of the qpp config to change (empty when none is known to help).
    """
    sp = cfg.spheres
    worst = float(np.max(np.linalg.eigvals(res.Az["eq10.7"]).real))
    if worst >= 0:                  # nothing else matters: the loop of these gains diverges
        return (f"the closed loop of these gains is unstable (largest Re λ(A_z) = {worst:.4g} 1/s): β1 is "
                f"infinite and no circle criterion holds", _UNSTABLE_HINT)
    if not res.circle.passed:
        c = res.circle
        if np.isnan(c.min_scale):
            why = "no sector scale s·[α, β] passes (scanned 1e-12 … 1e12)"
        elif c.min_scale > 1.0:     # an unstable H(s): the sector must be wide enough to stabilize
            why = f"smallest admissible sector scale {c.min_scale:.3g} > 1"
        elif c.max_scale < 1.0:
            why = f"largest admissible sector scale {c.max_scale:.3g} < 1"
        else:
            why = f"admissible sector scales {c.min_scale:.3g} … {c.max_scale:.3g}, but not 1"
        return f"circle criterion fails for every a tried ({why} at a = {res.a:g})", _CIRCLE_HINT
    c = res.consistent
    failed = [k for k, (ok, _) in res.premises.items() if not ok]
    for key, what, hint in (("range", "the output sphere leaves the range the sector holds on", ""),
                            ("sector", "phi is not proved to lie in the sector the certificate uses", ""),
                            ("slope", "the slope bound of beta3 is not proved", ""),
                            ("circle", "the circle criterion is not proved", _CIRCLE_HINT)):
        if key in failed:
            return f"{what}: {res.premises[key][1]}", hint
    terms = {"β_i": c.beta_i, "β_o·β3": sp.beta_o * c.beta3, "β4": c.beta4}
    dom = max(terms, key=terms.get)
    lead = ("β1 > m" if "contraction" in failed else
            f"γ∞·max E/m = {res.gamma_inf * res.consistent.E_over_m:.4g} > 1 (the L2 sphere does not bound the L∞ "
            f"sphere, 10.45)")
    txt = (f"{lead} (consistent reading): β1 = {float(res.beta1['eq10.7']['value']):.4g}, m = β_o/(β_i + β_o·β3 + β4) = {sp.beta_o:g}/("
           + " + ".join(f"{v:.4g}" for v in terms.values()) + f") = {c.m:.4g}, largest term {dom} = {terms[dom]:.4g}")
    hint = ("widen spheres.beta_o, narrow spheres.beta_ri or the nonlinearity's parameter ranges, or allow a "
            "smaller design.rho_min (with design.wider_search)" if "contraction" in failed else "")
    if c.m < 1.0:
        txt += ("; m < 1 at this T while β1 ≥ 1 for a loop that tracks r_o (gain 1 at the servo "
                "frequencies)")
        hint = "no tracking loop meets these spheres: widen spheres.beta_o or narrow spheres.beta_ri"
    return txt, hint


#: The hint of gains whose closed loop is unstable.
_UNSTABLE_HINT = "these gains do not stabilize the plant: let the procedure find gains (design.gains: design)"
#: The hint of a circle criterion that fails: which settings of the qpp config to change.
_CIRCLE_HINT = ("narrow the nonlinearity's sector (its parameter ranges or y_range), or widen the search of a "
                "(design.a_min, design.a_max)")


def design(cfg: QppConfig) -> DesignResult:
    """Procedure 12.1 (or certification of the printed gains when ``design.gains = published``).

    Steps 1–5 of the module docstring (a adjusted both ways on a geometric grid of [a_min, a_max];
    after the first certified design, a raised towards a_max), then the wider search when they fail.
    Every evaluation is in ``iterations``; the result's ``certified``/``verdict`` say the outcome.

    Parameters
    ----------
    cfg : qpp.io.config.QppConfig
        Validated config (plant, nonlinearity, ``hinf``, ``spheres``, ``design`` sections).

    Returns
    -------
    DesignResult
        The certified design, or the best uncertified one (``certified`` False, ``limiting``).

    Raises
    ------
    DesignError
        No stabilizing H∞ gains for any ρ, a or weight tried.
    """
    hc, dc = cfg.hinf, cfg.design
    if dc.gains == "published":
        p = cfg.published
        res = certify(cfg, p.K1, p.Kc, p.H, hc.a, "published")
        res.iterations = [_Procedure._rec("published", np.nan, hc.a, [1.0], T=res.T, b1=res.beta1_ref, m=res.m_ref,
                                          circle=res.circle.passed, cert=res.certified)]
        _finish(cfg, res)
        return res
    proc = _Procedure(cfg)
    res = proc.report_loop(ws=(hc.w,))
    if res is None and dc.wider_search and proc.best is not None:
        res = proc.wider()
    if res is None:
        res = proc.best
    if res is None:
        why = structural_obstacles(cfg.lure_plant())
        raise DesignError("procedure 12.1: no stabilizing H∞ gains for any rho, a or weight tried"
                          + (f": {'; '.join(why)}" if why else ""),
                          hint="change hinf.rho or hinf.nu, or set hinf.search: true")
    res.iterations = proc.records
    res.hinf_history = proc.hist
    _finish(cfg, res)
    pub = cfg.published
    if pub.K1 is not None and pub.Kc is not None and pub.H is not None:
        res.published = certify(cfg, pub.K1, pub.Kc, pub.H, res.a, "published", T=res.T)
    return res


def _finish(cfg: QppConfig, res: DesignResult) -> None:
    """The verdict in words (``certified``, set by :func:`qpp.design.certificate.certify`, holds only when
    every premise of the consistent certificate holds; a bookkeeping of the report never certifies by itself)."""
    c = res.consistent
    if res.certified:
        res.verdict = (f"certified (one sector, Euclidean norm): beta1 = {res.beta1_ref:.5g} <= m = {c.m:.5g}, "
                       f"gamma_inf*max E/m = {res.gamma_inf * c.E_over_m:.5g} <= 1, circle criterion satisfied at "
                       f"a = {res.a:g}; the output sphere holds on [0, T], T = {res.T:.4g} s; {res.scope_text}")
        res.limiting = ""
    else:
        res.limiting, res.hint = limiting_factor(cfg, res)
        res.verdict = (f"no certified design: best beta1 = {res.beta1_ref:.5g}, m = {c.m:.5g} "
                       f"(consistent), circle {'passed' if res.circle.passed else 'failed'}, "
                       f"limiting factor: {res.limiting}")
