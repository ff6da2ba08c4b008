"""LQR with every closed-loop pole in a sector (report ch. 5.2, eqs 5.2–5.4, Fig 5.2).

The sector of Fig 5.2, for orbital rate n::

    S = {λ : Re λ ≤ −σ·n  and  |Im λ| ≤ tan φ · |Re λ|}        (σ = 0.5, φ = 45° in the report)

The Sunkel–Shieh algorithm the report cites is not publicly available (`docs/ERRATA.md` § Sector LQR).
:func:`sector_lqr` instead returns an R, a Q ⪰ 0 and the gain K (u = −K x) that is the *exact*
LQR gain of the α-shifted problem ::

    minimize ∫ e^{2αt} (x'Qx + u'Ru) dt   ⇔   LQR of (A + αI, B, Q, R),   α = σ·n,

with every closed-loop pole of A − BK verified to lie in S.

``method="shift"`` (default)
    1. minimum-energy (Q = Q0, default 0) LQR on A + αI: every pole ends with Re ≤ −α;
    2. the poles still outside the φ lines (the disturbance-rejection-filter poles) are moved by
       *optimal pole shifting* (Amin 1985): for the left invariant subspace U1 of the selected
       poles (ordered real Schur form A_cl' = U T U', selected first) solve the Q = 0 Riccati
       equation of (T11' + hI, U1'B), which mirrors those poles about Re = −h while leaving all
       others unchanged; P ← P + U1 P̃ U1', K = R⁻¹B'P.  The Q making K exact for the shifted
       problem is Q ← Q + 2(h − α) U1 P̃ U1' ⪰ 0 (h ≥ α), checked through the Riccati residual.
``method="uniform"``
    The smallest uniform shift α ≥ σn (bisection) for which the LQR of (A + αI, B, Q0, R) puts
    every pole in S; Q = Q0.  Simpler, but moves every pole further than needed.

All computations are done on the state-scaled model x = D x̃ (``scale``), where the Riccati
residual is checked; K, P and Q are returned in physical units.

Conditioning (the shipped configs; README "Sector design and gain schedule").  With Q0 = 0 the
shifted LQR mirrors repeated open-loop modes — the three DRF pairs at ±jn and ±j2n, the Jordan
chains h → ∫h at 0 — onto identical points: near-defective clusters with eigenvalue condition
numbers ~1e9, "in the sector" only to rounding.  The configs therefore use a small fixed diagonal
Q0 on the scaled states (7e-6 rates, 7e-7 attitudes, 5e-6 momentum, 2e-4 momentum integral, 0 DRF;
``Q0_groups``), which splits the Jordan chains, and ``min_margin = 0.1`` (n), so every pole is
≥ 0.1n inside: largest eigenvalue condition ≤ 5.4e4 at MB3, AC and every stair-case point (the
former 1e-5/1e-6/5e-6/5e-5 reached 9.99e4).  The weights were chosen by measurement among ~60
candidates (README) for the condition number *and*
for a second-order gain schedule that can be made stable along the whole path; larger weights lower
the condition number further but make the scheduled loop unstable.  ``line_spacing`` > 0 mirrors
stray poles one real-Schur block at a time about distinct lines (distinct poles; it did not help
the stair-case).  Every result carries the eigenvalue condition numbers (:func:`eigen_conditioning`),
the sector robustness radius (:func:`sector_robustness`) and the CARE condition estimate.
"""
from __future__ import annotations

from acmm.design.lqr_methods import _problem, _sector_shift, _sector_uniform
from acmm.design.sector import SectorLQR


def sector_lqr(A, B, R, n: float, *, sigma: float = 0.5, half_angle_deg: float = 45.0,
               Q0=None, scale=None, method: str = "shift", riccati_method: str = "scipy",
               residual_tol: float = 1e-12, min_margin: float = 0.01,
               max_uniform_shift: float = 100.0, line_spacing: float = 0.0,
               input_scale: float = 1.0) -> SectorLQR:
    """LQR gain with every closed-loop pole in the sector of Fig 5.2 (module docstring).

    Parameters
    ----------
    A : (N, N) array
        Open-loop state matrix (eq 4.46), 1/s.
    B : (N, M) array
        Control input matrix, state units per ft·lbf (e.g. rad/s² per ft·lbf).
    R : float or (M, M) array
        Control weight, e.g. 1e-4 = 1/(100 ft·lbf)² per axis; a float r means r·I.
    n : float
        Orbital rate, rad/s (the sector's unit).
    sigma : float
        Minimum decay rate σ in units of n (Re λ ≤ −σn).
    half_angle_deg : float
        Sector half-angle φ, deg (|Im λ| ≤ tan φ |Re λ|).
    Q0 : None, float or (N, N) array
        Initial state weight in the coordinates the problem is solved in — the scaled states x̃
        when ``scale`` is given (dimensionless), else physical.  None or 0: minimum energy.
        A float q means q·I.
    scale : (N,) array or None
        Nominal state magnitudes d (x = diag(d) x̃); strongly recommended (`docs/ERRATA.md` § Scaling).
        Units of each state (rad, rad/s, ft·lbf·s, ...).
    method : {"shift", "uniform"}
        Optimal pole shifting of the stray poles, or the smallest uniform shift.
    riccati_method : {"scipy", "sign", "slycot"}
        Solver used for every Riccati equation (:func:`acmm.design.riccati.solve_care`).
    residual_tol : float
        Largest accepted Riccati backward error after refinement
        (:func:`acmm.design.riccati.care_backward_error`), dimensionless.
    min_margin : float
        Required :func:`sector_margin` of every pole, units of n; moved poles are placed with
        1.5× this margin.
    max_uniform_shift : float
        Largest α/n tried by ``method="uniform"``, dimensionless (units of n).
    line_spacing : float
        ``method="shift"``: 0 mirrors every stray pole of a group about one line (the poles of
        a group stay clustered); δ > 0 mirrors them one real-Schur block at a time, the k-th
        about h + kδn (raised further until it lands ≥ δn from every other pole), so the
        moved poles are distinct (units of n).
    input_scale : float
        Unit of the input in which the problem is solved, in units of the input (e.g. ft·lbf):
        B·e and R·e², K and R mapped back.  The stations of :func:`acmm.model.linearize.momentum_scale`
        beyond its band pass their momentum scale over the nominal one, so that a station k
        times smaller (torques k times smaller, R k² times larger) is the same scaled problem.

    Returns
    -------
    SectorLQR
        The verified design (K, P, Q in physical units).

    Raises
    ------
    ValueError
        ``method`` is unknown, or n, sigma, half_angle_deg or min_margin is out of range.
    DesignError
        A pole cannot be brought into the sector (or Q would be indefinite).
    ConvergenceError
        A Riccati solve failed or its backward error exceeds ``residual_tol``.
    """
    if method not in ("shift", "uniform"):
        raise ValueError(f"method must be 'shift' or 'uniform', got {method!r}")
    if not (n > 0 and sigma > 0 and 0 < half_angle_deg < 90 and min_margin >= 0):
        raise ValueError("need n > 0, sigma > 0, 0 < half_angle_deg < 90 and min_margin ≥ 0")
    if not (0 < input_scale < float("inf")):
        raise ValueError("need input_scale > 0")
    p = _problem(A, B, R, n, sigma, half_angle_deg, Q0, scale, method, riccati_method, residual_tol,
                 min_margin, input_scale)
    if method == "uniform":
        return _sector_uniform(p, max_uniform_shift)
    return _sector_shift(p, line_spacing)
