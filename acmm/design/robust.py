"""One gain for a family of inertias, certified plant by plant (report ch. 7: "stable for up to
±30 % variations in the SSF inertia matrix").

The report designs each gain for the nominal plant and claims, from simulations, that the loop
stays stable for ±30 % inertia variations.  Here the claim is designed for and proved per plant:

1. **The family** (:func:`_plant_family`): the nominal plant, ``samples`` element draws
   I ∘ (1 + δ), δ_ij ~ U(±p) independently (p = ``inertia_percent``/100; only rigid bodies,
   :func:`acmm.model.inertia.unphysical_reason`), and the uniform scalings (1 ± p)·I at the
   family's ends; each plant linearized (eq 4.46) about **its own** equilibrium connected to the
   design TEA (:func:`acmm.model.tea.solve_tea_connected`: where the station goes as its
   inertia moves from the nominal one; the bias is held, as in the sweep).  A draw whose design
   branch folds before it (no connected equilibrium) is not a member and is counted.
2. **The gain** (:func:`_robust_gain`): the worst spectral abscissa over the family,
   f(K) = max_i max Re λ(A_i − B_i K), minimized from the route's nominal gain by BFGS on the
   scaled gain (Lewis & Overton 2013 observe that BFGS with a weak line search works well on
   such nonsmooth spectral functions, without a convergence proof; HIFOO, Burke et al. 2006,
   designs multi-model fixed-order controllers this way, and MATLAB's ``systune`` optimizes the
   worst case over plants alike).  The objective is the abscissa alone: the cone is left free,
   and the route's gain is kept when every plant is already certified in the sector with it.
   BFGS is restarted from its last point until a restart lowers f by less than
   :data:`RESTART_TOL` (units of n), at most :data:`MAX_RESTARTS` times (then ``stop`` says so).
   A common Lyapunov matrix for the whole family — the convex route — is infeasible for these
   stations (the directions of total momentum the CMGs cannot change rotate with the inertia),
   and dilated LMIs with one matrix per plant grow as (300·plants)³; the nonsmooth search costs
   one eigendecomposition per plant and step.
3. **The proof, per plant** (:func:`_region_certificate`): with K fixed, X_i = Re(V_i V_iᴴ) (V_i
   the eigenvectors of A_i − B_i K) satisfies the LMIs of the half-plane Re λ ≤ −a and of the
   cone |arg(−λ)| ≤ φ for the a and φ its poles allow; they are re-checked, not assumed, on the
   whitened loop Z = L⁻¹(A_i − B_i K)L (X = LLᵀ) by symmetric eigenvalues, less a first-order
   rounding allowance (as :func:`acmm.design.regional_lmi.certified_margin`).  So each plant's
   certified decay a_i and cone φ_i are proofs about its linear model; the family keeps the
   region Re λ ≤ −min a_i, |arg(−λ)| ≤ max φ_i, and the sector of Fig 5.2 when min a_i ≥ σ and
   max φ_i ≤ φ.

The cores take arrays and :class:`RobustSettings`; the config is read in
:mod:`acmm.design.settings`.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import scipy.optimize as so

from acmm.design.regional_lmi import scaled_model, whitened_loop
from acmm.model import linearize as lin
from acmm.model.inertia import ELEMENTS, perturb_inertia, unphysical_reason
from acmm.model.tea import solve_tea_connected

#: a BFGS restart that lowers the worst spectral abscissa by less than this (units of n) ends the search
RESTART_TOL = 1e-7

#: the most BFGS restarts; reaching it is stated in the record (``stop``)
MAX_RESTARTS = 40

#: BFGS iterations per restart (each a line search on the nonsmooth function; a restart resets
#: the inverse Hessian, which is what lets BFGS leave a kink it has stalled on)
BFGS_MAXITER = 3000

#: the family is reached by continuation: the search runs on the plants I0 + t(I − I0) (each at its
#: connected equilibrium) for these t in turn, each from the last gain, so that it starts near a
#: gain that already stabilizes the plants (a nonsmooth search from far outside stalls)
CONTINUATION = (0.25, 0.5, 0.75, 1.0)

#: the draws of the family stop after this many per wanted member (a family of unphysical or
#: folded draws is reported short, not drawn for ever)
DRAWS_PER_MEMBER = 200


@dataclass(frozen=True)
class RobustSettings:
    """The family a robust gain is designed for (``design.robust``).

    Attributes
    ----------
    inertia_percent : float
        Half-width p of the element draws and of the uniform scalings, % (dimensionless).
    samples : int
        Element draws in the family (besides the nominal plant and the two scalings).
    seed : int
        Seed of the draws (``numpy.random.SeedSequence([seed])``).
    """

    inertia_percent: float
    samples: int = 20
    seed: int = 1


@dataclass(frozen=True)
class PlantFamily:
    """The plants a robust gain is designed for (see the module docstring, step 1).

    Attributes
    ----------
    labels : tuple of str
        ``"nominal"``, ``"draw <k>"`` (k: index of the draw among all draws) or ``"scale <s>"``.
    inertia : (P, 3, 3) array
        Inertia of each plant, slug·ft².
    theta : (P, 3) array
        Its equilibrium connected to the design TEA, rad.
    draws : int
        Element draws taken.
    unphysical : int
        Draws that were not a rigid body's inertia.
    folded : int
        Physical draws whose design branch folds before them: no member.
    scalings_folded : tuple of float
        The uniform scalings (dimensionless factors) whose design branch folds before them: no member.
    """

    labels: tuple
    inertia: np.ndarray
    theta: np.ndarray
    draws: int
    unphysical: int
    folded: int
    scalings_folded: tuple = ()


@dataclass(frozen=True)
class RegionCertificate:
    """A Lyapunov certificate of one plant's closed loop (see the module docstring, step 3).

    Attributes
    ----------
    X : (N, N) array
        The certificate in the scaled coordinates x̃ (dimensionless, time in 1/n).
    decay : float
        Certified decay, units of n: every pole has Re λ ≤ −decay·n (≤ 0: stability not proved).
    cone_deg : float
        Certified cone, deg: every pole has |arg(−λ)| ≤ cone_deg (90 when only the half-plane is
        proved; NaN when not even that is: no certificate).
    max_real : float
        Largest real part of the computed poles, units of n (for comparison, not a proof).
    """

    X: np.ndarray
    decay: float
    cone_deg: float
    max_real: float


@dataclass(frozen=True)
class RobustDesign:
    """A gain designed for a family of plants, with one certificate per plant.

    Attributes
    ----------
    K : (M, N) array
        The robust gain, u = −K x, physical units.
    nominal_K : (M, N) array
        The route's gain for the nominal plant it started from, physical units.
    family : PlantFamily
        The plants.
    certificates : tuple of RegionCertificate
        One per plant, in the order of ``family``.
    worst_abscissa : float
        max_i max Re λ(A_i − B_i K) at the end, units of n.
    start_abscissa : float
        The same for ``nominal_K``, units of n.
    restarts : int
        BFGS restarts used.
    stop : str
        Why the search stopped.
    solve_time : float
        Wall time of the search and the certificates, s.
    sector : tuple of float
        The design's sector (σ in units of n, half-angle φ in deg) the plants are judged against.
    """

    K: np.ndarray
    nominal_K: np.ndarray
    family: PlantFamily
    certificates: tuple
    worst_abscissa: float
    start_abscissa: float
    restarts: int
    stop: str
    solve_time: float
    sector: tuple = (0.5, 45.0)

    @property
    def decay(self) -> float:
        """The decay rate every plant of the family is certified to keep, units of n."""
        return float(min(c.decay for c in self.certificates))

    @property
    def cone_deg(self) -> float:
        """The cone half-angle every plant of the family is certified to keep, deg (NaN when a
        plant has no certificate)."""
        cones = [c.cone_deg for c in self.certificates]
        return float("nan") if any(np.isnan(cones)) else float(max(cones))

    def unproved(self) -> list[str]:
        """The plants whose stability is not certified (decay ≤ 0).

        Returns
        -------
        list of str
            Their labels.
        """
        return [lab for lab, c in zip(self.family.labels, self.certificates) if not c.decay > 0]

    def sector_held(self) -> np.ndarray:
        """Per plant: certified in the sector Re λ ≤ −σn, |arg(−λ)| ≤ φ (Fig 5.2, :attr:`sector`).

        Returns
        -------
        (P,) bool array
            Certified decay ≥ σ and certified cone ≤ φ.
        """
        sigma, phi = self.sector
        return np.array([c.decay >= sigma and c.cone_deg <= phi for c in self.certificates], bool)


def _plant_family(inertia, bias, theta, n: float, st: RobustSettings) -> PlantFamily:
    """Nominal plant (inertia slug·ft², bias ft·lbf held, TEA ``theta`` rad, n rad/s), ``st.samples``
    element draws and the two uniform scalings at their TEAs connected to ``theta`` (module
    docstring, step 1); fewer draws when :data:`DRAWS_PER_MEMBER` per member ran out."""
    I0, b0, th0 = (np.asarray(x, float) for x in (inertia, bias, theta))
    h = st.inertia_percent / 100.0
    members = [("nominal", I0, th0)]                                # (label, inertia, connected TEA)
    rng = np.random.default_rng(np.random.SeedSequence([st.seed]))
    draws = unphysical = folded = 0
    while len(members) <= st.samples and draws < DRAWS_PER_MEMBER * st.samples:      # the nominal and the draws
        values = {k: float(rng.uniform(-h, h)) for k in ELEMENTS}
        draws += 1
        I = perturb_inertia(I0, values)
        if unphysical_reason(I) is not None:
            unphysical += 1
            continue
        tea = solve_tea_connected(th0, I0, b0, I, n, b0)
        if tea is None:
            folded += 1
            continue
        members.append((f"draw {draws - 1}", I, tea.theta))
    scalings_folded = []
    for s in (1.0 - h, 1.0 + h):
        tea = solve_tea_connected(th0, I0, b0, s * I0, n, b0)
        if tea is None:
            scalings_folded.append(float(s))
            continue
        members.append((f"scale {s:.6g}", s * I0, tea.theta))
    labels, inertias, thetas = zip(*members)
    return PlantFamily(labels, np.array(inertias), np.array(thetas), draws, unphysical, folded, tuple(scalings_folded))


def _worst_abscissa(Ks: np.ndarray, models) -> tuple[float, np.ndarray]:
    """max_i max Re λ(Ã_i − B̃_i K̃) and its gradient with respect to K̃ (that of the active
    eigenvalue: ∂λ/∂K̃ = −(w_jᴴ B̃)ᵀ v_jᵀ, W V = I), units of n."""
    best, grad = -np.inf, np.zeros_like(Ks)
    for As, Bs in models:
        lam, V = np.linalg.eig(As - Bs @ Ks)
        j = int(np.argmax(lam.real))
        if lam[j].real > best:
            try:
                w = np.linalg.solve(V.T, np.eye(V.shape[0])[:, j])   # row j of V⁻¹
            except np.linalg.LinAlgError:
                w = np.linalg.lstsq(V.T, np.eye(V.shape[0])[:, j], rcond=None)[0]
            best = float(lam[j].real)
            grad = -np.outer(w @ Bs, V[:, j]).real
    return best, grad


def _robust_gain(models, K0: np.ndarray) -> tuple[np.ndarray, float, int, str]:
    """From scaled ``K0``, the scaled gain minimizing the worst spectral abscissa over the scaled
    ``models`` (Ã, B̃) (module docstring, step 2): (K̃, worst abscissa in n, BFGS restarts, stop)."""
    M, N = K0.shape
    S = np.abs(K0) + 1e-3 * np.max(np.abs(K0))          # each element moved relative to its size

    def f(x):
        val, g = _worst_abscissa(K0 + x.reshape(M, N) * S, models)
        return val, (g * S).ravel()

    x = np.zeros(M * N)
    best = f(x)[0]
    stop = f"{MAX_RESTARTS} restarts (the limit) without settling to {RESTART_TOL:g} n"
    for restarts in range(1, MAX_RESTARTS + 1):
        res = so.minimize(f, x, jac=True, method="BFGS", options={"maxiter": BFGS_MAXITER, "gtol": 0.0})
        if res.fun < best:
            x = res.x
        if not best - res.fun >= RESTART_TOL:
            stop = f"a restart lowered the worst abscissa by less than {RESTART_TOL:g} n"
            break
        best = float(res.fun)
    Ks = K0 + x.reshape(M, N) * S
    return Ks, _worst_abscissa(Ks, models)[0], restarts, stop


def _region_certificate(As: np.ndarray, Bs: np.ndarray, Ks: np.ndarray) -> RegionCertificate:
    """The :class:`RegionCertificate` of the scaled loop Ã − B̃K̃ (time in 1/n; module docstring,
    step 3).  With X = LLᵀ and Z = L⁻¹(Ã − B̃K̃)L: He(A_cl X) + 2aX ⪯ 0 for a = −λ_max(Z + Zᵀ)/2, and
    the cone LMI [[sin φ He Z, cos φ (Z − Zᵀ)], [cos φ (Zᵀ − Z), sin φ He Z]] ⪯ 0 for every φ ≥ φ*
    (monotone: tan φ·diag(He Z, He Z) + [[0, S], [−S, 0]] decreases with φ when He Z ⪯ 0), φ* by
    bisection to 1e-9 rad; both less the rounding allowance of
    :func:`acmm.design.regional_lmi.whitened_loop`."""
    lam, V = np.linalg.eig(As - Bs @ Ks)
    max_real = float(np.max(lam.real))
    X = (V @ V.conj().T).real
    X = 0.5 * (X + X.T)
    X = X / np.max(np.abs(np.diag(X)))
    whitened = whitened_loop(As, Bs, Ks, X)
    if whitened is None:
        return RegionCertificate(X, float("-inf"), float("nan"), max_real)
    Z, delta = whitened
    H, Sk = Z + Z.T, Z - Z.T
    decay = -0.5 * float(np.max(np.linalg.eigvalsh(H))) - delta
    if not decay > 0:
        return RegionCertificate(X, decay, float("nan"), max_real)

    def holds(phi: float) -> bool:
        t = np.tan(phi)
        Lm = np.block([[t * H, Sk], [-Sk, t * H]])
        return float(np.max(np.linalg.eigvalsh(Lm))) <= -2 * delta * (t + 1)

    lo, hi = 0.0, np.pi / 2 - 1e-9
    if not holds(hi):
        return RegionCertificate(X, decay, 90.0, max_real)
    while hi - lo > 1e-9:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if holds(mid) else (mid, hi)
    return RegionCertificate(X, decay, float(np.degrees(hi)), max_real)


def robust_design(inertia, bias, theta, n: float, K_nominal, scales, input_scale: float, st: RobustSettings,
                  model: str = "coupled", drf_mode: str = "attitude_hold",
                  sector: tuple = (0.5, 45.0)) -> RobustDesign:
    """One gain for the family of ``st`` around a design point, certified per plant.

    Parameters
    ----------
    inertia : (3, 3) array
        Nominal inertia, slug·ft².
    bias : (3,) array
        Bias torque, ft·lbf.
    theta : (3,) array
        The nominal TEA, rad.
    n : float
        Orbital rate, rad/s.
    K_nominal : (M, N) array
        The route's gain for the nominal plant (the start), physical units.
    scales : (N,) array
        State scales D of the design model, in the units of each state.
    input_scale : float
        Torque unit e of the scaled input, ft·lbf.
    st : RobustSettings
        The family.
    model : str
        Design model (:func:`acmm.model.linearize.design_point`).
    drf_mode : str
        DRF mode.
    sector : tuple of float
        (σ in units of n, half-angle in deg): the sector each plant is judged against.

    Returns
    -------
    RobustDesign
        The gain, the family and one certificate per plant.
    """
    t0 = time.perf_counter()
    fam = _plant_family(inertia, bias, theta, n, st)
    d = np.asarray(scales, float)
    I0, th0, b0 = (np.asarray(x, float) for x in (inertia, theta, bias))

    def models_at(step: float):
        out = []
        for I, th in zip(fam.inertia, fam.theta):
            if step < 1.0:
                Is = I0 + step * (I - I0)
                tea = solve_tea_connected(th0, I0, b0, Is, n, b0)
                # (an intermediate plant only guides the search; the certificates are of the family)
                I, th = Is, (tea.theta if tea is not None else th0 + step * (th - th0))
            m = lin.design_point(I, th, n, model=model, drf_mode=drf_mode)
            out.append(scaled_model(m.A, m.B, n, d, input_scale))
        return out

    models = models_at(1.0)
    K_nom = np.asarray(K_nominal, float)
    K0s = K_nom * d[None, :] / input_scale
    start = _worst_abscissa(K0s, models)[0]
    sector = (float(sector[0]), float(sector[1]))
    start_certs = tuple(_region_certificate(As, Bs, K0s) for As, Bs in models)
    kept = RobustDesign(K_nom, K_nom, fam, start_certs, start, start, 0,
                        "the route's gain is certified in the sector for every plant: kept",
                        time.perf_counter() - t0, sector)
    if np.all(kept.sector_held()):
        return kept
    Ks, restarts, limited = K0s, 0, []
    for step in CONTINUATION:
        Ks, worst, r, stop = _robust_gain(models if step == 1.0 else models_at(step), Ks)
        restarts += r
        if stop.startswith(f"{MAX_RESTARTS} restarts"):
            limited.append(f"{step:g}")
    stop = (f"every continuation step settled (a restart lowered the worst abscissa by less than "
            f"{RESTART_TOL:g} n)" if not limited else
            f"the restart limit ({MAX_RESTARTS}) was reached at continuation step(s) {', '.join(limited)}")
    certs = tuple(_region_certificate(As, Bs, Ks) for As, Bs in models)
    K = Ks * input_scale / d[None, :]
    return RobustDesign(K, K_nom, fam, certs, worst, start, restarts, stop, time.perf_counter() - t0, sector)
