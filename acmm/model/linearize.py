"""Fully coupled 24-state linearization about a torque-equilibrium attitude (eqs 4.4–4.50).

State order (eq 4.47)::
    x = [δω1, θ̇2, δω3, δθ1, δθ2, δθ3 | h1, h2, h3, ∫h1, ∫h2, ∫h3 |
         α̇1, α1, α̇2, α2, α̇3, α3, β̇1, β1, β̇2, β2, β̇3, β3]

with ẋ = A x + B u + G w (eq 4.46).  The model is assembled from closed-form partials:

* kinematics (eq 4.4): δθ̇ = f(θ*) δω + ∂(f(θ)ω*)/∂θ δθ;
* gyroscopic torque (eqs 4.8–4.10): ∂τ_gyro/∂ω = [(Iω*)×] − [ω*×] I;
* gravity-gradient torque (eqs 4.12–4.14, corrected, ``docs/ERRATA.md`` § Linearization):
  column k is 3n²(d_k × I c + c × I d_k), d_k = ∂c/∂θ_k;
* the change of variable δω2 → θ̇2 of eq 4.26: x1 = M z with z = (δω, δθ) and M the identity
  except its second row, the linearized θ̇2.  Then ẋ1 = M A_z M⁻¹ x1, which is E1⁻¹A1 of
  eqs 4.27–4.29 (4.28: the 1/cos θ1 factor scales rows 1–3 only; 4.29: column 6, rows 1–3
  carry τ_gyr²·n·sin θ3);
* CMG momentum (eqs 4.31–4.34): ḣ = −[ω*×] h + u; A2(3,1) is −n cos θ1 cos θ3 (printed +);
* u enters ω̇ as −u and ḣ as +u; w enters ω̇ as +w (eqs 3.1, 3.8; the printed 4.30/4.33/4.49
  signs are wrong);
* disturbance-rejection filters (eqs 4.35–4.45) at n and 2n on deviations; in attitude hold
  δθ2 and δθ3 drive rows 9 and 11 of x3 (the β̇2, β̇3 rows; printed 4.44 says 10 and 12).

The misprints named here are listed, with the tests that establish them, in ``docs/ERRATA.md``
§ Linearization and § Momentum balance; the state scaling in § Scaling.  The PBH
controllability test of the model is in :mod:`acmm.model.controllability`.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from acmm.model import dynamics as dyn
from acmm.model import kinematics as kin
from acmm.model.state_scaling import NOMINAL_ANGLE, momentum_scale
from acmm.model.tea import resolve_bias, solve_tea

STATE_NAMES = [
    "domega1", "theta2_dot", "domega3", "dtheta1", "dtheta2", "dtheta3",
    "h1", "h2", "h3", "int_h1", "int_h2", "int_h3",
    "alpha1_dot", "alpha1", "alpha2_dot", "alpha2", "alpha3_dot", "alpha3",
    "beta1_dot", "beta1", "beta2_dot", "beta2", "beta3_dot", "beta3",
]
INPUT_NAMES = ["u1", "u2", "u3"]
DISTURBANCE_NAMES = ["w1", "w2", "w3"]

#: index of each DRF's input in x, per DRF mode (report ch. 4.5.3 and 5.1)
DRF_INPUTS = {
    "attitude_hold": (6, 4, 5),   # h1, δθ2, δθ3
    "momentum_hold": (6, 7, 5),   # h1, h2, δθ3
}

@dataclass(frozen=True)
class LinearModel:
    """ẋ = A x + B u + G w about a TEA (eq 4.46).

    Attributes
    ----------
    A, B, G : arrays (24×24, 24×3, 24×3)
        In the report's physical units (rad, rad/s, ft·lbf·s, ft·lbf·s², …).
    n : float
        Orbital rate, rad/s.
    theta_star, omega_star : (3,) arrays
        Linearization point θ* (rad) and ω* (rad/s, eq 4.3).
    inertia : (3, 3) array
        Inertia used in the design model, slug·ft².
    variant, drf_mode : str
        Design-model variant and DRF mode.
    scales : (24,) array
        Nominal state magnitudes for scaling (x = diag(scales) x̃), in the units of each state
        (:func:`state_units`; ``docs/ERRATA.md`` § Scaling).
    state_names : tuple of str
        Names of the 24 states of eq 4.47 (:data:`STATE_NAMES`).
    """

    A: np.ndarray
    B: np.ndarray
    G: np.ndarray
    n: float
    theta_star: np.ndarray
    omega_star: np.ndarray
    inertia: np.ndarray
    variant: str = "coupled"
    drf_mode: str = "attitude_hold"
    scales: np.ndarray = field(default=None)
    state_names: tuple = tuple(STATE_NAMES)

    @property
    def state_units(self) -> list[str]:
        """Unit of each state of eq 4.47 for this model's DRF mode (see :func:`state_units`)."""
        return state_units(self.drf_mode)

    def scaled(self):
        """(Ã, B̃, G̃) of the state-scaled model x = D x̃, D = diag(scales).

        See ``docs/ERRATA.md`` § Scaling.

        Returns
        -------
        A_scaled : (24, 24) array
            D⁻¹ A D, 1/s.
        B_scaled : (24, 3) array
            D⁻¹ B, scaled state units per ft·lbf.
        G_scaled : (24, 3) array
            D⁻¹ G, scaled state units per ft·lbf.
        """
        d = self.scales
        return self.A * (1.0 / d)[:, None] * d[None, :], self.B / d[:, None], self.G / d[:, None]

    def to_statespace(self):
        """A python-control ``StateSpace`` with inputs [u1..u3, w1..w3] and all states as outputs.

        Returns
        -------
        control.StateSpace
            ``ẋ = A x + [B G] [u; w]``, ``y = x`` (eq 4.46), in the report's physical units
            (torques ft·lbf; states as :func:`state_units`).
        """
        import control  # deferred: python-control start-up (~1.5 s), only for a StateSpace

        return control.ss(self.A, np.hstack([self.B, self.G]), np.eye(24), np.zeros((24, 6)),
                          states=list(STATE_NAMES), inputs=INPUT_NAMES + DISTURBANCE_NAMES,
                          outputs=list(STATE_NAMES), name=f"acmm_{self.variant}")


def state_units(drf_mode: str = "attitude_hold") -> list[str]:
    """Unit of each state of eq 4.47 (the DRF units follow their inputs).

    Parameters
    ----------
    drf_mode : {"attitude_hold", "momentum_hold"}
        DRF inputs (h1, δθ2, δθ3) or (h1, h2, δθ3) (report ch. 5.1).

    Returns
    -------
    list of str
        24 unit strings (``"rad/s"``, ``"rad"``, ``"ft*lbf*s"``, …) in the order of
        :data:`STATE_NAMES`.
    """
    base = ["rad/s"] * 3 + ["rad"] * 3 + ["ft*lbf*s"] * 3 + ["ft*lbf*s^2"] * 3
    in_units = {4: "rad", 5: "rad", 6: "ft*lbf*s", 7: "ft*lbf*s"}
    drf = [f"{in_units[idx]}*s{p}" for idx in DRF_INPUTS[drf_mode] for p in ("", "^2")]
    return base + drf * 2          # the filters at n, then at 2n


def kinematics_jacobian(theta: np.ndarray, n: float) -> np.ndarray:
    """∂(f(θ) ω*)/∂θ at θ = θ* (rad/s per rad), the δθ terms of eq 4.4.

    Closed form: [[0, 0, n/cos θ3], [0, 0, −n tan θ3], [−n cos θ3, 0, 0]].

    Parameters
    ----------
    theta : (3,) array
        Linearization attitude θ*, rad.
    n : float
        Orbital rate, rad/s.

    Returns
    -------
    (3, 3) array
        ∂(f(θ) ω*)/∂θ, rad/s per rad.
    """
    c3, s3 = np.cos(theta[2]), np.sin(theta[2])
    return np.array([[0.0, 0.0, n / c3], [0.0, 0.0, -n * s3 / c3], [-n * c3, 0.0, 0.0]])


def state_scales(n: float, drf_mode: str = "attitude_hold", inertia=None) -> np.ndarray:
    """Nominal magnitude of every state (same units as the state).

    Angles 0.01 rad, rates n·0.01 rad/s, momentum 1000 ft·lbf·s (:func:`momentum_scale`: scaled
    with the station beyond :data:`MOMENTUM_BAND`), its integral that over n, and each DRF state
    its input's scale divided by (filter frequency)^k (``docs/ERRATA.md`` § Scaling).

    Parameters
    ----------
    n : float
        Orbital rate, rad/s.
    drf_mode : {"attitude_hold", "momentum_hold"}
        DRF inputs (h1, δθ2, δθ3) or (h1, h2, δθ3).
    inertia : (3, 3) or (L, 3, 3) array, optional
        The station's inertia, slug·ft² (:func:`momentum_scale`).

    Returns
    -------
    (24,) array
        Nominal magnitudes, in the units of :func:`state_units` for the same ``drf_mode``.
    """
    ang, mom = NOMINAL_ANGLE, momentum_scale(n, inertia)
    s = np.empty(24)
    s[0:3] = n * ang
    s[3:6] = ang
    s[6:9] = mom
    s[9:12] = mom / n
    k = 12
    for wf in (n, 2 * n):
        for idx in DRF_INPUTS[drf_mode]:
            s[k] = s[idx] / wf          # α̇ ~ input / ω_f
            s[k + 1] = s[idx] / wf ** 2  # α ~ input / ω_f²
            k += 2
    return s


def linearize(inertia: np.ndarray, theta_star: np.ndarray, n: float, *,
              drf_mode: str = "attitude_hold", variant: str = "coupled") -> LinearModel:
    """The 24-state model of eq 4.46 about θ* for a given (design) inertia.

    Parameters
    ----------
    inertia : (3, 3) array
        Design-model inertia, slug·ft² (for the ``no_cross_inertia`` variant pass the
        diagonal part; θ* still comes from the full inertia).
    theta_star : (3,) array
        Linearization attitude, rad (the TEA, or zero for ``small_angle``).
    n : float
        Orbital rate, rad/s.
    drf_mode : {"attitude_hold", "momentum_hold"}
        DRF inputs (h1, δθ2, δθ3) or (h1, h2, δθ3).
    variant : str
        Label stored with the model.

    Returns
    -------
    LinearModel
        A (24×24), B and G (24×3, state units per ft·lbf) of eq 4.46 in the report's physical
        units (:func:`state_units`), with the state scales of :func:`state_scales`.

    Raises
    ------
    ValueError
        When ``drf_mode`` is not one of the two modes.
    """
    if drf_mode not in DRF_INPUTS:
        raise ValueError(f"drf_mode must be one of {sorted(DRF_INPUTS)}")
    inertia = np.asarray(inertia, float)
    theta = np.asarray(theta_star, float)
    omega = kin.lvlh_rate_in_body(theta, n)
    i_inv = np.linalg.inv(inertia)

    # z = (δω, δθ): eqs 4.4, 4.7-4.14 (4.12-4.14 corrected, see module docstring)
    f = kin.kinematics_matrix(theta)
    a_z = np.block([
        [i_inv @ dyn.gyroscopic_torque_jacobian(omega, inertia),
         i_inv @ dyn.gravity_gradient_jacobian(theta, inertia, n)],
        [f, kinematics_jacobian(theta, n)],
    ])
    # x1 = M z: replace δω2 by the linearized θ̇2 (eq 4.26); ẋ1 = M A_z M⁻¹ x1 is E1⁻¹A1 (4.27-4.29)
    m = np.eye(6)
    m[1] = a_z[4]
    b_z = np.vstack([-i_inv, np.zeros((3, 3))])   # u enters ω̇ as −u (eq 3.1; printed 4.30 sign wrong)
    g_z = np.vstack([i_inv, np.zeros((3, 3))])    # w enters ω̇ as +w

    A = np.zeros((24, 24))
    B = np.zeros((24, 3))
    G = np.zeros((24, 3))
    A[0:6, 0:6] = m @ a_z @ np.linalg.inv(m)
    B[0:6] = m @ b_z
    G[0:6] = m @ g_z
    # CMG momentum and its integral, eqs 4.31-4.34 (A2(3,1) = −n cos θ1 cos θ3, printed +)
    A[6:9, 6:9] = -kin.skew(omega)
    A[9:12, 6:9] = np.eye(3)
    B[6:9] = np.eye(3)                             # u enters ḣ as +u (eq 3.8)
    # DRFs, eqs 4.35-4.45: α̈ + ω_f² α = input, states (α̇, α) per filter
    k = 12
    for wf in (n, 2 * n):
        for idx in DRF_INPUTS[drf_mode]:
            A[k, k + 1] = -wf * wf
            A[k, idx] = 1.0
            A[k + 1, k] = 1.0
            k += 2
    return LinearModel(A=A, B=B, G=G, n=n, theta_star=theta, omega_star=omega, inertia=inertia,
                       variant=variant, drf_mode=drf_mode, scales=state_scales(n, drf_mode, inertia))


def design_point(inertia_full: np.ndarray, theta_tea: np.ndarray, n: float, *,
                 model: str = "coupled", drf_mode: str = "attitude_hold") -> LinearModel:
    """The design model of a config variant (``design.model``).

    ``coupled``: full inertia about the TEA; ``no_cross_inertia``: I12 = I13 = I23 = 0 in the
    model, TEA still from the full inertia (report ch. 6); ``small_angle``: θ* = 0 (LVLH).
    The variants are those named after eq 4.46 (``docs/ERRATA.md`` § Claim 1).

    Parameters
    ----------
    inertia_full : (3, 3) array
        Full inertia of the plant, slug·ft².
    theta_tea : (3,) array
        Torque-equilibrium attitude of the full inertia (eqs 4.1–4.3), rad.
    n : float
        Orbital rate, rad/s.
    model : {"coupled", "no_cross_inertia", "small_angle"}
        Design-model variant.
    drf_mode : {"attitude_hold", "momentum_hold"}
        DRF inputs (h1, δθ2, δθ3) or (h1, h2, δθ3).

    Returns
    -------
    LinearModel
        The 24-state model of eq 4.46 for that variant.

    Raises
    ------
    ValueError
        When ``model`` is not one of the three variants.
    """
    if model not in ("coupled", "no_cross_inertia", "small_angle"):
        raise ValueError(f"unknown design model {model!r}")
    inertia = np.asarray(inertia_full, float)
    return linearize(np.diag(np.diag(inertia)) if model == "no_cross_inertia" else inertia,
                     np.zeros(3) if model == "small_angle" else theta_tea, n, drf_mode=drf_mode, variant=model)


def linearize_config(cfg) -> LinearModel:
    """TEA of a :class:`acmm.io.config.Config` (physical branch), then its design model.

    Eqs 4.1–4.3 (:func:`acmm.model.tea.solve_tea`), then eq 4.46 (:func:`design_point`).

    Parameters
    ----------
    cfg : acmm.io.config.Config
        Validated config; its inertia (slug·ft²), orbital rate (rad/s), disturbance bias
        (ft·lbf) and ``design.model`` / ``design.drf_mode`` are used.

    Returns
    -------
    LinearModel
        The design model of eq 4.46 about the config's TEA.
    """
    inertia = cfg.inertia.matrix()
    t = solve_tea(inertia, cfg.orbit_rate, resolve_bias(cfg.disturbance, inertia, cfg.orbit_rate),
                  expected=cfg.disturbance.requested_tea())        # the root bias_from_tea names
    return design_point(inertia, t.theta, cfg.orbit_rate, model=cfg.design.model,
                        drf_mode=cfg.design.drf_mode)

