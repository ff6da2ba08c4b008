"""Guarantee certificate of fixed gains (CR-185644 ch. 12.1, theorem 2, lemma 1): β1 for both
B_z readings, the threshold m of eq 12.1 in each bookkeeping, the circle criterion and the
settling time of the nominal loop.  The bookkeepings are described in :mod:`qpp.design.procedure`
(``docs/ERRATA.md`` § QPP thresholds).

The thresholds m and β3, β4 along the nominal loop are computed by :mod:`qpp.design.thresholds`.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from acmm_qpp.errors import DesignError
from qpp.design import circle as circle_mod
from qpp.design.circle import KypResult, circle_kyp
from qpp.design import spheres
from qpp.io.config import ExpressionNonlinearity, QppConfig, SinusoidalNonlinearity
from qpp.design.hinf import HinfGains
from qpp.model.lure import channels, closed_loop
from qpp.simulate.closed_loop import eval_signal, initial_state
from qpp.design.thresholds import NORM, Consistent, Thresholds, consistent, nominal_output, thresholds


@dataclass
class DesignResult:
    """Everything ``qpp design`` reports and stores.

    Attributes
    ----------
    K1 : (m, n) array
        State-feedback gain, plant input units per state unit.
    Kc : (m, q) array
        Compensator gain, plant input units per compensator-state unit.
    H : (n, p) array
        Observer gain, state units per output unit per s.
    gains_source : str
        Where the gains come from (``given``, ``published``, ``hinf``, ...).
    hinf : qpp.design.hinf.HinfGains or None
        The ch. 11 solution the gains come from, if any.
    a : float
        Exponential weighting a, 1/s (10.27).
    T : float
        Truncation time T, s.
    Az, Bz : dict
        B_z reading (``eq10.7``, ``printed``) → closed-loop A_z (1/s) and B_z matrices.
    Cz : (k, N) array
        Closed-loop output matrix, units of the output per state unit.
    beta1 : dict
        B_z reading → :func:`qpp.design.spheres.beta1` (``value`` dimensionless, ``omega_peak`` rad/s).
    thresholds : list of Thresholds
        m (12.1) in each bookkeeping.
    circle : qpp.design.circle.CircleResult
        Circle criterion on H(−a + jω).
    sector : (r, 2) array
        Sector [α, β] per channel used in the circle check, dimensionless gains.
    E : float
        E = [(e^{2aT} − 1)/(2a)]^½ of eq 10.44, units of s^½.
    y_o_t : (S,) array
        Sample times of the nominal output on [0, T], s.
    y_o : (p, S) array
        Nominal output on [0, T], in the plant's output units.
    iterations : list of dict
        Every evaluation of the procedure.
    bookkeeping : str
        Threshold the design iterates against.
    bz : str
        B_z reading of the design inequality.
    T_settle : float
        Settling time of the nominal loop, s.
    settled : bool
        Whether the nominal loop settles within its horizon (else ``T_settle`` is the horizon).
    T_modal : float or None
        Settling time of the loop's slowest mode (:func:`modal_settling_time`), s, when it gave
        ``T_settle`` (a nominal loop with nothing to track); None otherwise.
    late_slope : tuple or None
        (sup slope of φ on [0, T], sup after T up to the horizon), units of φ per unit of y, when
        φ is markedly stiffer after T than within it (:func:`late_slope`); else None.
    certified : bool
        β1 ≤ m (bookkeeping, bz) and circle criterion.
    verdict : str
        The outcome in words.
    limiting : str
        Why an uncertified design fails (:func:`qpp.design.procedure.limiting_factor`).
    hint : str
        Which settings to change for a certificate (:func:`qpp.design.procedure.limiting_factor`;
        empty when certified or when none is known to help).
    ws_scale : list of float
        Weights w of W_s = diag(w)·S_c of the gains, dimensionless.
    hinf_history : list of dict
        ch. 11 passes (ρ, ν, δ, tests).
    published : DesignResult or None
        Certificate of the printed gains (report examples).
    consistent : qpp.design.thresholds.Consistent or None
        The certificate's threshold in one sector and one norm (:data:`qpp.design.thresholds.NORM`).
    gamma_inf : float
        L2-to-peak gain of C_z (sI − A_n)⁻¹ B_z (:func:`qpp.design.spheres.l2_to_peak_gain`),
        output units per input unit per s^½; γ∞·E ≤ m closes the step 10.45.
    premises : dict
        Premise name → (holds, statement in words); ``certified`` is their conjunction.
    norm : str
        The certificate's signal norm in words (:data:`qpp.design.thresholds.NORM`).
    circle_proof : qpp.design.circle.KypResult or None
        The circle criterion decided by the KYP lemma (premise ``circle``); ``circle`` is the
        frequency grid's check, kept for the figures and as a cross-check.
    proved : list of str
        What the certificate proves, in words (:func:`scope`).
    assumed : list of str
        What it assumes, not proved, in words (:func:`scope`).
    """

    K1: np.ndarray
    Kc: np.ndarray
    H: np.ndarray
    gains_source: str
    hinf: HinfGains | None
    a: float
    T: float
    Az: dict                      #: reading → A_z (same for both readings)
    Bz: dict                      #: reading → B_z
    Cz: np.ndarray
    beta1: dict                   #: reading → dict of spheres.beta1
    thresholds: list
    circle: circle_mod.CircleResult
    sector: np.ndarray
    E: float
    y_o_t: np.ndarray
    y_o: np.ndarray
    iterations: list = field(default_factory=list)
    bookkeeping: str = ""             #: threshold the design iterates against
    bz: str = "eq10.7"                #: B_z reading of the design inequality
    T_settle: float = np.nan          #: settling time of the nominal loop, s
    settled: bool = True              #: the nominal loop settles within its horizon (else T_settle is the horizon)
    late_slope: tuple | None = None   #: (sup slope on [0, T], sup slope after T) when φ is stiffer after T
    T_modal: float | None = None      #: settling time of the slowest mode, s, when it set T_settle
    certified: bool = False           #: β1 ≤ m (bookkeeping, bz) and circle criterion
    verdict: str = ""
    limiting: str = ""
    hint: str = ""
    ws_scale: list = field(default_factory=list)   #: W_s = diag(w)·S_c of the gains
    hinf_history: list = field(default_factory=list)  #: ch. 11 passes (ρ, ν, δ, tests)
    published: "DesignResult | None" = None  #: certificate of the printed gains (report examples)
    consistent: Consistent | None = None     #: the certificate's threshold (one sector, one norm)
    gamma_inf: float = np.nan                #: L2-to-peak gain of C_z (sI − A_n)⁻¹ B_z
    premises: dict = field(default_factory=dict)  #: premise → (holds, statement)
    norm: str = NORM                         #: the certificate's signal norm
    circle_proof: KypResult | None = None    #: the circle criterion decided by the KYP lemma
    proved: list = field(default_factory=list)   #: what the certificate proves (:func:`scope`)
    assumed: list = field(default_factory=list)  #: what it assumes, not proved (:func:`scope`)

    @property
    def scope_text(self) -> str:
        """What is proved and what is assumed, in one line (:func:`scope_text`)."""
        return scope_text(self.proved, self.assumed)

    @property
    def horizon_note(self) -> str:
        """One line when T ends before the nominal loop settles (T fixed by ``spheres.adapt_T:
        false``, or the procedure kept a design evaluated at the configured T after step 3 moved
        T to the settling time): what the certificate, or the evaluation, covers; else ""."""
        if not (self.settled and self.T < 0.9 * self.T_settle):
            return ""
        what = ("the certificate covers [0, T] only, not the settling" if self.certified else
                "the premises were evaluated on [0, T] only")
        return (f"T = {self.T:.4g} s ends before the nominal loop settles ({self.T_settle:.4g} s): {what} "
                f"(12.1 step 3 takes T near the settling time)")

    @property
    def m_ref(self) -> float:
        """Threshold m of the design's bookkeeping (the consistent m for ``consistent``), dimensionless."""
        if self.bookkeeping == "consistent":
            return self.consistent.m
        return self.threshold(self.bookkeeping).m

    @property
    def lhs_ref(self) -> float:
        """What the design compares with ``m_ref``: β1 of the design's B_z reading, and for the
        ``consistent`` bookkeeping max(β1, γ∞·m·max E/m) (both must be ≤ m), dimensionless."""
        if self.bookkeeping == "consistent":
            return float(max(self.beta1_ref, self.gamma_inf * self.consistent.E_over_m * self.consistent.m))
        return self.beta1_ref

    @property
    def beta1_ref(self) -> float:
        """β1 of the design's B_z reading, dimensionless."""
        return float(self.beta1[self.bz]["value"])

    def threshold(self, name: str) -> Thresholds:
        """The thresholds of one bookkeeping.

        Parameters
        ----------
        name : str
            Bookkeeping name (:class:`Thresholds`).

        Returns
        -------
        Thresholds
            The first entry of ``thresholds`` with that name.
        """
        return next(t for t in self.thresholds if t.name == name)

    def verdicts(self) -> dict:
        """(reading, bookkeeping) → β1 ≤ m.

        Returns
        -------
        dict
            ``{(reading, bookkeeping): bool}`` for every B_z reading and bookkeeping.
        """
        return {(r, t.name): bool(self.beta1[r]["value"] <= t.m) for r in self.beta1 for t in self.thresholds}


def default_sector(cfg: QppConfig) -> np.ndarray:
    """Sector of φ = N (f1 − f1o) for the circle check: config value, else ±N·γ_max·|F_unc| (diagonal).

    Parameters
    ----------
    cfg : qpp.io.config.QppConfig
        Validated config (units: s, rad/s, the plant's own units).

    Returns
    -------
    (r, 2) array
        [α, β] per disturbance channel, dimensionless gains.

    Raises
    ------
    DesignError
        A polar-arm nonlinearity without ``design.sector``.
    """
    if cfg.design.sector is not None:
        return np.asarray(cfg.design.sector, float)
    nl = cfg.nonlinearity
    if isinstance(nl, SinusoidalNonlinearity):
        k = cfg.sinusoidal_half_widths()
        k = np.where(k > 0, k, 1e-12)
        return np.column_stack([-k, k])
    if isinstance(nl, ExpressionNonlinearity):
        if nl.sector is not None:
            return np.asarray(nl.sector, float)
        s = np.array(cfg.expression_model().proof.sector, float)   # the sampled sector, widened to the proved one
        # a sampled φ ≡ 0 (or exactly linear) gives [α, α]: widened by 1e-12 (as a zero sinusoidal one, above)
        flat = ~(s[:, 0] < s[:, 1])
        pad = 1e-12 * np.maximum(1.0, np.abs(s[flat]).max(axis=1))
        s[flat, 0] -= pad
        s[flat, 1] += pad
        return s
    raise DesignError("design.sector must be given for a polar_arm nonlinearity")


def sector_coupling(cfg: QppConfig) -> np.ndarray:
    """Per φ channel, whether φ_i depends on outputs other than y_i (the circle check then takes
    its small-gain form, :mod:`qpp.design.circle`): for an ``expression`` its symbolic dependence
    (:attr:`qpp.model.nonlin.SectorInfo.diagonal`), for the ``sinusoidal`` kind the off-diagonal entries
    of N·F_unc; a ``polar_arm`` sector is the config's own, stated per channel (diagonal).

    Parameters
    ----------
    cfg : qpp.io.config.QppConfig
        Validated config.

    Returns
    -------
    (r,) bool ndarray
        True for a coupled channel (dimensionless flags).
    """
    nl = cfg.nonlinearity
    if isinstance(nl, ExpressionNonlinearity):
        return ~np.asarray(cfg.expression_model().sector_info.diagonal, bool)
    P = cfg.lure_plant()
    if isinstance(nl, SinusoidalNonlinearity):
        M = P.N() @ np.asarray(nl.F_unc, float)
        return np.any((M != 0.0) & ~np.eye(*M.shape, dtype=bool), axis=1)
    return np.zeros(P.r, bool)


def settling_time(t, y_o, r_o, band: float) -> float:
    """Settling time of the nominal loop, s: the last time |y_o − r_o| (largest channel) exceeds
    ``band`` × its peak; 0 when the loop tracks from the start, t[-1] when it never settles.

    Parameters
    ----------
    t : (S,) array
        Sample times, s.
    y_o : (p, S) array
        Nominal output, output units.
    r_o : (p, S) array
        Reference, output units.
    band : float
        Settling band as a fraction of the peak error, dimensionless.

    Returns
    -------
    float
        Settling time, s.
    """
    e = np.max(np.abs(np.atleast_2d(y_o) - np.atleast_2d(r_o)), axis=0)
    peak = float(e.max()) if e.size else 0.0
    if peak <= 1e-12:
        return 0.0
    idx = np.nonzero(e > band * peak)[0]
    return float(t[idx[-1]]) if idx.size else 0.0


def modal_settling_time(Az, band: float) -> float:
    """Time for the slowest mode of the closed loop to decay to ``band`` of its start, s:
    ln(1/band) / min(−Re λ(Az)); 0 when a mode does not decay (an unstable loop is refused
    elsewhere).  The settling time of a nominal loop with nothing to track (r_o ≡ 0), whose
    :func:`settling_time` is 0 although a perturbation still takes this long to die out.

    Parameters
    ----------
    Az : (N, N) array
        Closed-loop state matrix (eq 10.7), 1/s.
    band : float
        Settling band, dimensionless fraction.

    Returns
    -------
    float
        Settling time, s.
    """
    decay = float(np.min(-np.linalg.eigvals(np.asarray(Az, float)).real))
    return float(np.log(1.0 / band) / decay) if decay > 0 else 0.0


def late_slope(cfg: QppConfig, T: float, horizon: float) -> tuple | None:
    """(sup slope on [0, T], sup slope on (T, horizon]) of a φ that depends on t, when the later one
    exceeds the earlier by half; else None.  β3 and β4 (10.53–10.54) see φ only up to T: a
    nonlinearity that stiffens (or switches on) after T gives a certificate the simulation beyond
    T may contradict (a review's φ = k·y·(sat(10(t − 3)) + 1)/2 with T = 2.3 s; the sinusoidal form
    of ch. 13, whose slope k·|sin ωt| is small on a short [0, T]).

    Parameters
    ----------
    cfg : QppConfig
        The config.
    T : float
        Truncation time, s.
    horizon : float
        End of the simulation, s.

    Returns
    -------
    tuple or None
        The two slope bounds, units of φ per unit of y; or None.
    """
    nl = cfg.nonlinearity
    if horizon <= T:
        return None
    if isinstance(nl, SinusoidalNonlinearity):     # slope k·|sin ωt|, k = |N F_unc|·γ_max (closed form)
        k = float(np.linalg.norm(cfg.sinusoidal_half_widths()))
        before, after = (k * float(spheres.sup_abs_sin(nl.omega, t0, t1)) for t0, t1 in ((0.0, T), (T, horizon)))
    elif isinstance(nl, ExpressionNonlinearity) and cfg.expression_model().t_varies:
        tg, g = cfg.expression_model().slope_profile(horizon)
        g = np.max(g, axis=0)
        before, after = float(np.max(g[tg <= T], initial=0.0)), float(np.max(g[tg > T], initial=0.0))
    else:
        return None
    return (before, after) if after > 1.5 * before + 1e-12 else None


def certify(cfg: QppConfig, K1, Kc, H, a: float, gains_source: str = "given",
            hinf: HinfGains | None = None, T: float | None = None) -> DesignResult:
    """β1 for both B_z readings, thresholds at T (default ``spheres.T``), the circle criterion and
    the settling time of the nominal loop, for fixed gains.

    Parameters
    ----------
    cfg : qpp.io.config.QppConfig
        Validated config (units: s, rad/s, the plant's own units).
    K1 : (m, n) array
        State-feedback gain, input units per state unit.
    Kc : (m, q) array
        Compensator gain, input units per compensator-state unit.
    H : (n, p) array
        Observer gain, state units per output unit per s.
    a : float
        Exponential weighting a, 1/s (10.27).
    gains_source : str
        Label of the gains' origin, stored in the result.
    hinf : qpp.design.hinf.HinfGains, optional
        The ch. 11 solution the gains come from.
    T : float, optional
        Truncation time, s (default ``spheres.T``).

    Returns
    -------
    DesignResult
        The certificate (``certified``: β1 ≤ m and circle criterion).
    """
    P = cfg.lure_plant()
    K1, Kc = (np.atleast_2d(np.asarray(x, float)) for x in (K1, Kc))
    H = np.asarray(H, float).reshape(P.n, P.p)
    Azd, Bzd, b1 = {}, {}, {}
    for reading in ("eq10.7", "printed"):
        Az, Bz, Cz = closed_loop(P, K1, Kc, H, bz=reading)
        Azd[reading], Bzd[reading] = Az, Bz
        b1[reading] = spheres.beta1(Az, Bz, Cz, a)
    sector, coupled = default_sector(cfg), sector_coupling(cfg)
    _, dcols = channels(P)
    circ = circle_mod.circle_criterion(Az, Bzd["eq10.7"][:, dcols], Cz, sector, a=a, coupled=coupled)
    T = cfg.spheres.T if T is None else float(T)
    horizon = max(T, cfg.simulation.t_final)
    n = int(min(20001, max(801, 801 * horizon / T)))
    t, y_o, x_o = nominal_output(cfg, K1, Kc, H, horizon, n, extra=(T,))
    r_o = np.array([eval_signal(cfg.simulation.r_o, tt) for tt in t]).T
    Ts, T_modal = settling_time(t, y_o, r_o, cfg.spheres.settle_band), None
    if Ts == 0.0:   # the nominal loop tracks from the start (r_o ≡ 0, say): its modes still settle
        T_modal = modal_settling_time(Azd["eq10.7"], cfg.spheres.settle_band)
        Ts = min(T_modal, float(t[-1]))
    keep = t <= T + 1e-12
    th = thresholds(cfg, t, y_o, x_o, sector, T)
    res = DesignResult(K1, Kc, H, gains_source, hinf, a, T, Azd, Bzd, Cz, b1, th, circ, sector,
                       spheres.E_factor(a, T), t[keep], y_o[:, keep])
    res.circle_proof = circle_kyp(Az, Bzd["eq10.7"][:, dcols], Cz, sector, a=a, coupled=coupled)
    res.T_settle = Ts
    res.settled = bool(Ts < float(t[-1]))
    res.T_modal = T_modal
    res.late_slope = late_slope(cfg, T, horizon)
    # the design iterates against design.bookkeeping when available, else the stated values, else
    # the last (most specific) bookkeeping
    names, bk = [x.name for x in th], cfg.design.bookkeeping
    res.bookkeeping = bk if bk == "consistent" or bk in names else ("stated" if "stated" in names else names[-1])
    res.bz = cfg.design.bz
    loop = (Azd["eq10.7"], Bzd["eq10.7"], Cz, initial_state(cfg, P, K1, Kc))
    res.consistent = consistent(cfg, t, y_o, sector, coupled, T, a, loop)
    # the certificate is of the loop that runs (B_z of eq 10.7, as simulated), whatever design.bz
    # says; the printed B_z reading stays in the bookkeeping
    An = Azd["eq10.7"] + a * np.eye(len(Azd["eq10.7"]))
    res.gamma_inf = spheres.l2_to_peak_gain(An, Bzd["eq10.7"], Cz)
    res.premises = premises(cfg, res)
    res.certified = bool(all(ok for ok, _ in res.premises.values()))
    res.proved, res.assumed = scope(cfg, res)
    return res


#: what every certificate assumes, whatever φ (issue 43; docs/qpp-certificates.md "Still assumed")
ASSUMED_ALWAYS = ("floating-point evaluation (eigenvalues, H-infinity norm, Gramian, the nominal loop's "
                  "matrix exponential)",)
#: what every certificate whose premises hold proves of the time integrals (:func:`qpp.design.thresholds.consistent`)
PROVED_INTEGRALS = "beta4 and m for every T' in (0, T] (the nominal loop enclosed on cells)"


def scope(cfg: QppConfig, res: DesignResult) -> tuple:
    """What a certificate proves and what it assumes, in words, from its premises and the kind of
    φ: the single source of the verdict's last clause, the root attributes ``proved`` and
    ``assumed`` of ``qpp_design.h5`` and docs/qpp-certificates.md's "What is proved".

    A premise enters ``proved`` only when it holds and rests on a proof: an expression's sector
    and slope (interval branch and bound, :mod:`qpp.model.sector_proof`) and its range (the
    enclosure of the nominal loop), the sinusoidal form's (closed form, |sin| ≤ 1), the circle
    criterion (KYP lemma, :func:`qpp.design.circle.circle_kyp`), β4 and m for every truncation time
    (:data:`PROVED_INTEGRALS`, :mod:`qpp.design.nominal_enclosure`) and the polar arm's β3 over the
    sphere (:mod:`qpp.model.arm_bounds`).  Everything rests on :data:`ASSUMED_ALWAYS`; the polar
    arm's sector is assumed.

    Parameters
    ----------
    cfg : qpp.io.config.QppConfig
        Validated config.
    res : DesignResult
        The certificate, with ``premises`` and ``T`` (s).

    Returns
    -------
    tuple
        (proved, assumed): two lists of str; what is proved holds for t in [0, T].
    """
    holds = {k: ok for k, (ok, _) in res.premises.items()}
    nl = cfg.nonlinearity
    proved, assumed = [], []
    if isinstance(nl, ExpressionNonlinearity):
        which = [k for k in ("sector", "slope") if holds.get(k)]
        if which:
            proved.append(" and ".join(which) + " (interval branch and bound)")
        if holds.get("range"):
            proved.append("y_o +- beta_o inside y_range (enclosure)")
    elif isinstance(nl, SinusoidalNonlinearity):
        if holds.get("sector"):
            proved.append("sector and slope (closed form, |sin| <= 1)")
    else:
        if holds.get("peak"):       # (the rates' box rests on the step 10.45 the premise peak closes)
            proved.append("the polar arm's beta3 over the sphere around the nominal trajectory (interval branch and bound)")
        assumed.append("the polar arm's sector (the config's; phi depends on the rates, not on y alone)")
    if holds.get("circle"):
        proved.append("circle criterion (KYP lemma)")
    if holds.get("contraction") and holds.get("peak"):
        proved.append(PROVED_INTEGRALS)
    return proved, assumed + list(ASSUMED_ALWAYS)


def scope_text(proved, assumed) -> str:
    """One line: ``proved for t in [0, T]: …; assumed: …`` (:func:`scope`; an empty list is left
    out).

    Parameters
    ----------
    proved, assumed : list of str
        :func:`scope`.

    Returns
    -------
    str
        The clause the certified verdict ends with.
    """
    parts = [f"proved for t in [0, T]: {', '.join(proved)}"] if proved else []
    return "; ".join(parts + ([f"assumed: {', '.join(assumed)}"] if assumed else []))


def sector_premise(cfg: QppConfig, sector: np.ndarray) -> tuple:
    """Whether φ lies in the sector the certificate uses (premise ``sector``).

    The sinusoidal form's sector is structural, ±N·γ_max·|F_unc| (row sums): a stated
    ``design.sector`` must contain it.  An expression's sector is proved by interval branch and bound
    (:attr:`qpp.model.nonlin.ExpressionModel.proof`: the sampled sector widened by
    :data:`qpp.model.sector_proof.REL_GAP`), which a stated ``nonlinearity.sector`` must contain.  The
    polar arm's sector is the config's assumption (φ depends on the rates, not on y alone): not a
    premise this tool proves; its β3 is proved over the sphere (:func:`qpp.design.thresholds.consistent`).

    Parameters
    ----------
    cfg : qpp.io.config.QppConfig
        Validated config.
    sector : (r, 2) array
        The sector [α, β] per channel the circle criterion and β4 use, dimensionless.

    Returns
    -------
    tuple
        (holds, statement).
    """
    nl = cfg.nonlinearity
    s = np.asarray(sector, float)
    if isinstance(nl, SinusoidalNonlinearity):
        k = cfg.sinusoidal_half_widths()
        ok = bool(np.all(s[:, 0] <= -k) and np.all(s[:, 1] >= k))
        return ok, (f"the sector contains phi's own, ±N·gamma_max·|F_unc| = ±{np.round(k, 6).tolist()}"
                    + ("" if ok else " (design.sector is narrower)"))
    if isinstance(nl, ExpressionNonlinearity):
        proof = cfg.expression_model().proof
        own = proof.sector
        ok = bool(np.all(s[:, 0] <= own[:, 0]) and np.all(s[:, 1] >= own[:, 1]))
        return ok and proof.sector_ok, (
            f"phi in the sector {np.round(own, 6).tolist()} on y_range x parameters x [0, t_range]: "
            f"{proof.sector_text}" + ("" if ok else " (nonlinearity.sector is narrower than it)"))
    return False, ("the polar arm's sector is assumed by the config, not proved (phi depends on the rates x3, x4, "
                   "not on y alone); its beta3 is proved over the sphere around the nominal trajectory")


def premises(cfg: QppConfig, res: DesignResult) -> dict:
    """Every premise of the consistent certificate (``docs/qpp-certificates.md``), each with
    whether it holds and the numbers in words.

    Parameters
    ----------
    cfg : qpp.io.config.QppConfig
        Validated config.
    res : DesignResult
        The design, with ``consistent``, ``gamma_inf`` and ``circle_proof`` computed.

    Returns
    -------
    dict
        ``{name: (bool, str)}`` for ``stable``, ``sector`` (:func:`sector_premise`), ``circle``,
        ``contraction`` (β1 < m),
        ``peak`` (γ∞·E(T')/m(T') ≤ 1 for every T' ≤ T, eq 10.45) and, for an expression, ``range`` (y_o ± β_o inside y_range)
        and ``slope`` (the slope bound of β3 proved by interval branch and bound).
    """
    c = res.consistent
    worst = float(np.max(np.linalg.eigvals(res.Az["eq10.7"] + res.a * np.eye(len(res.Az["eq10.7"]))).real))
    b1 = float(res.beta1["eq10.7"]["value"])
    peak = res.gamma_inf * c.E_over_m
    out = {
        "stable": (worst < 0, f"A_z + aI Hurwitz, B_z of eq 10.7 (largest Re λ = {worst:.4g} 1/s)"),
        "sector": sector_premise(cfg, res.sector),
        "circle": (bool(res.circle_proof.proved), f"circle criterion with the sector {np.round(res.sector, 6).tolist()}"
                   f" at a = {res.a:g}: {res.circle_proof.text} (frequency grid: "
                   f"{'passes' if res.circle.passed else 'fails'})"),
        "contraction": (bool(b1 < c.m), f"beta1 = {b1:.6g} < m = {c.m:.6g} (eqs 10.43, 10.57 in the Euclidean "
                        f"norm, B_z of eq 10.7; m a lower bound for every T' in (0, T], least in the cell ending at "
                        f"T' = {c.T_worst:.4g} s; the trapezoid rule on the samples gives {c.m_sampled:.6g}: "
                        f"enclosure gap {max(c.m_sampled - c.m, 0.0) / c.m_sampled:.2g} relative)"
                        + (f"; beta3 = {c.beta3:.4g} over the sphere y_o +- beta_o, rates within "
                           f"{c.note['rho_v']:.4g} of the nominal ones" if "rho_v" in c.note else "")
                        + (f"; m not bounded: {c.note['unbounded']}" if "unbounded" in c.note else "")),
        "peak": (bool(peak <= 1.0), f"gamma_inf * max E/m = {peak:.6g} <= 1 (the L2 sphere bounds the L-infinity "
                 f"sphere on [0, T], eq 10.45)"),
    }
    nl = cfg.nonlinearity
    if isinstance(nl, ExpressionNonlinearity):
        rng = np.asarray(nl.y_range, float)
        if c.enclosure is None:                     # (not enclosed: nothing is proved of y_o)
            lo, hi, ok = np.full(len(rng), -np.inf), np.full(len(rng), np.inf), False
        else:
            ylo, yhi = c.enclosure.box(res.Cz)      # every t of [0, T], not the samples only
            lo = ylo.min(axis=1) - cfg.spheres.beta_o
            hi = yhi.max(axis=1) + cfg.spheres.beta_o
            ok = bool(np.all(lo >= rng[:, 0]) and np.all(hi <= rng[:, 1]))
        out["range"] = (ok, f"y_o ± beta_o within nonlinearity.y_range on [0, T] ({np.round(lo, 4).tolist()} … "
                            f"{np.round(hi, 4).tolist()}; the nominal loop enclosed on cells)")
        proof = cfg.expression_model().proof
        out["slope"] = (bool(proof.slope_ok), f"sum_j |dphi_i/dy_j| <= {np.round(proof.slope, 6).tolist()} on "
                        f"y_range x parameters x [0, t_range] (beta3, eq 10.40): {proof.slope_text}")
    return out
