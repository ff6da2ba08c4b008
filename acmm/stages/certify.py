"""The stair-case's dwell-time certificate of a config (report ch. 5.3, ch. 6): its levels' frozen
closed loops gathered from the scenario (:func:`acmm.simulate.scenario.scenario_from_config`), the
certificate of :mod:`acmm.design.dwell`, and its ``design.h5`` group ``dwell``.

The plant of each level is the coupled linearization (eq 4.46) about the level's TEA
(eqs 4.1–4.3) — the station itself, whatever design model variant the gains were designed on —
closed by the gain in use there (the scheduled gain, eq 5.1).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np

from acmm.design.dwell import NOT_COVERED, DwellCertificate, DwellProof, dwell_certificate
from acmm.io.config import Config
from acmm.io.design_file import DesignTable
from acmm.model import kinematics, linearize
from acmm.simulate.scenario import scenario_from_config
from acmm.stages.common import AXES, UNIT_A, UNIT_STATE
from acmm_qpp import __version__
from acmm_qpp.provenance import git_commit, git_dirty
from acmm_qpp.results import Dataset, h5_text

#: the ``design.h5`` datasets of the ``dwell`` group converted per state (:func:`acmm.stages.common.in_system`)
UNIT_ROLES = {"dwell/closed_loop": "A", "dwell/scales": "scales", "dwell/jump": "x"}

#: indices of h1, h2, h3 and of δω1, δω3, δθ1..3 in the state of eq 4.47
H_INDEX = (6, 7, 8)
_RATE_INDEX = (0, 2)
_ATTITUDE_INDEX = (3, 4, 5)


@dataclass(frozen=True)
class StairCertificate:
    """A config's dwell-time certificate and the levels it is about.

    Attributes
    ----------
    certificate : acmm.design.dwell.DwellCertificate
        The certificate.
    names : list of str
        The design point of each level.
    theta2 : (L,) array
        Pitch TEA of each level, rad.
    closed_loops : (L, 24, 24) array
        A_k − B_k K_k of each level, 1/s (physical units of eq 4.46).
    jumps : (L-1, 24) array
        Change of the equilibrium state at each switch, state units.
    n : float
        Orbital rate, rad/s.
    """

    certificate: DwellCertificate
    names: list
    theta2: np.ndarray
    closed_loops: np.ndarray
    jumps: np.ndarray
    n: float

    @property
    def orbit(self) -> float:
        """One orbit, s."""
        return 2 * np.pi / self.n


def _level_closed_loops(cfg: Config, table: DesignTable) -> tuple:
    """(Acl = A_k − B_k K_k 1/s, gains K_k ft·lbf per state unit, the first level's state magnitudes
    (the certificate's common scaling), the dwell of each level but the last s, the equilibrium of
    level k minus that of k+1 in k+1's coordinates (rad, rad/s), each level's design point index,
    the scenario (its torque and momentum limits)) of the config's stair-case levels."""
    sc = scenario_from_config(cfg, table)
    n = sc.n
    models = [linearize.design_point(sc.inertia[k], sc.theta_est[k], n, model="coupled", drf_mode=sc.drf_mode)
              for k in range(len(sc.level_start))]
    Acl = np.array([m.A - m.B @ sc.gain[k] for k, m in enumerate(models)])
    jumps = np.array([_deviation(sc.theta_est[k], sc.theta_est[k + 1], n, Acl.shape[1])
                      for k in range(len(models) - 1)]).reshape(len(models) - 1, Acl.shape[1])
    idx = [int(np.argmin([np.max(np.abs(t - th)) for t in table.tea])) for th in sc.theta_est]
    return Acl, sc.gain, models[0].scales, np.diff(sc.level_start), jumps, np.array(idx), sc


def _deviation(theta: np.ndarray, theta_eq: np.ndarray, n: float, nx: int) -> np.ndarray:
    """The state of eq 4.47 of a body at rest in LVLH at attitude ``theta`` about the equilibrium
    at ``theta_eq``: δθ = θ − θ*, δω1 and δω3 the change of the LVLH rate C_BL(0, −n, 0)
    (θ̇2 = 0, and h, ∫h and the filter states are zero at every equilibrium)."""
    x = np.zeros(nx)
    x[list(_ATTITUDE_INDEX)] = np.asarray(theta, float) - np.asarray(theta_eq, float)
    x[list(_RATE_INDEX)] = (kinematics.lvlh_rate_in_body(theta, n) - kinematics.lvlh_rate_in_body(theta_eq, n))[[0, 2]]
    return x


def _hard(parent, name: str, kind, shape: tuple | None = None):
    """``parent[name]`` when it is a hard link to a ``kind`` (a float dataset of ``shape`` whose
    data is in the file where given: checked before anything is read), else KeyError (a soft or
    external link, an external raw file or a virtual dataset could lead anywhere: a FIFO,
    itself)."""
    if not isinstance(parent.get(name, getlink=True), h5py.HardLink):
        raise KeyError(name)
    obj = parent[name]
    if not isinstance(obj, kind) or (kind is h5py.Dataset and (
            obj.dtype.kind != "f" or obj.shape != shape or obj.is_virtual
            or obj.id.get_create_plist().get_external_count() != 0)):
        raise KeyError(name)
    return obj


def _same_program(attrs) -> bool:
    """Whether a file's root attributes (:func:`acmm_qpp.results.write_h5`) say this process's
    program wrote it: the same package version and git commit, both known, and neither checkout
    with uncommitted changes (else the version alone would not say what code ran)."""
    ours = {"package_version": __version__, "git_commit": git_commit(), "git_dirty": git_dirty()}
    return ours["git_commit"] != "unknown" and ours["git_dirty"] == "no" and all(
        k in attrs and h5_text(attrs[k]) == v for k, v in ours.items())


def _stored_proof(path: Path, orbit: float, closed_loops: np.ndarray, exact: bool = False) -> DwellProof | None:
    """The :class:`acmm.design.dwell.DwellProof` (Lyapunov matrices, decay rate, dwells) of a
    ``design.h5``'s ``dwell`` group for the levels of ``closed_loops`` (A_k − B_k K_k, 1/s; the stored
    matrices must have their shape), ``orbit`` s; None when the file or group cannot be read as
    written (links, types, shapes) or, with ``exact``, is not in the report's units from
    :func:`_same_program` on element-wise equal closed loops (whose bisection finds the same dwells)."""
    if not path.is_file():          # a regular file (a FIFO or a device there would block)
        return None
    try:
        with h5py.File(path, "r") as f:
            if exact and (h5_text(f.attrs.get("unit_system", "imperial")) != "imperial"
                          or not _same_program(f.attrs)):
                return None
            g = _hard(f, "dwell", h5py.Group)
            if exact and not np.array_equal(_hard(g, "closed_loop", h5py.Dataset, closed_loops.shape)[()],
                                            closed_loops):
                return None
            tau = _hard(g, "tau_star", h5py.Dataset, ())
            if tau.attrs.get_id("not_certified_below_orbit").shape != ():
                return None
            return DwellProof(float(_hard(g, "decay_rate", h5py.Dataset, ())[()]), float(tau[()]) * orbit,
                              float(tau.attrs["not_certified_below_orbit"]) * orbit,
                              np.asarray(_hard(g, "lyapunov", h5py.Dataset, closed_loops.shape)[()], float))
    except Exception:       # noqa: BLE001 -- a file that cannot be read as written holds no proof
        return None


def compute_certificate(cfg: Config, table: DesignTable, previous: Path | None = None,
                        exact: bool = False) -> StairCertificate:
    """The dwell-time certificate of a config's stair-case (:func:`acmm.design.dwell.dwell_certificate`).

    Parameters
    ----------
    cfg : acmm.io.config.Config
        The config.
    table : acmm.io.design_file.DesignTable
        Its design.
    previous : pathlib.Path, optional
        A ``design.h5`` whose stored proof (:func:`_stored_proof`) is reused where it holds for
        these levels, checked again (``acmm certify`` on the design it certifies).
    exact : bool
        Reuse it only from the same program on the same closed loops (:func:`_stored_proof`'s
        ``exact``): a new design replacing ``previous`` then solves no dwell-time program when
        it designs the same stair-case again.

    Returns
    -------
    StairCertificate
        The certificate with its levels.
    """
    Acl, gains, scale, dwell, jumps, idx, sc = _level_closed_loops(cfg, table)
    proof = None if previous is None else _stored_proof(previous, 2 * np.pi / sc.n, Acl, exact)
    cert = dwell_certificate(Acl, gains, scale, dwell, jumps, H_INDEX, sc.torque_limit, sc.momentum_limit,
                             start=_deviation(sc.x0[3:6], sc.theta_est[0], sc.n, Acl.shape[1]), proof=proof)
    return StairCertificate(cert, [table.names[i] for i in idx], sc.theta_est[:, 1], Acl, jumps, sc.n)


def certificate_items(sc: StairCertificate) -> dict:
    """The ``dwell`` group of ``design.h5``: everything an independent check needs (the closed
    loops, the scaling, the Lyapunov matrices, λ) and the certificate's numbers.

    Parameters
    ----------
    sc : StairCertificate
        The certificate.

    Returns
    -------
    dict
        Name → :class:`acmm_qpp.results.Dataset` (imperial units, stated per dataset).
    """
    c = sc.certificate
    orbit = sc.orbit
    items = {
        "closed_loop": Dataset(sc.closed_loops, UNIT_A, "A_k - B_k K_k of each level's frozen loop (eq 4.46, coupled, "
                               "about the level's TEA)", dims=("level", "state", "state_col")),
        "scales": Dataset(c.scale, UNIT_STATE, "state scaling D of the Lyapunov matrices (x = D x~)", dims=("state",)),
        "lyapunov": Dataset(c.P, "1", "P_k > 0: (A~_k + lambda I)' P_k + P_k (A~_k + lambda I) < 0 and "
                            "expm(A~_k' tau*) P_j expm(A~_k tau*) < exp(-2 lambda tau*) P_k for j = k +- 1, "
                            "scaled states", dims=("level", "state", "state_col")),
        "jump": Dataset(sc.jumps, "state_units[j]", "equilibrium state of level k minus that of level k+1",
                        dims=("switch", "state")),
        "decay_rate": Dataset(c.decay, "1/s", "decay rate lambda the certificate proves (1/64 of the slowest "
                              "level's)"),
        "jump_up": Dataset(c.jump_up, "1", "mu(k+1 <- k) = lambda_max(P_k^-1 P_k+1)", dims=("switch",)),
        "jump_down": Dataset(c.jump_down, "1", "mu(k <- k+1) = lambda_max(P_k+1^-1 P_k)", dims=("switch",)),
        "tau_star": Dataset(c.tau_star / orbit if np.isfinite(c.tau_star) else np.inf, "orbit",
                            "certified minimum dwell time (Geromel-Colaneri LMIs, bisection)",
                            attrs={"certified": bool(c.certified), "within_limits": bool(c.within_limits),
                                   "unstable_levels": list(c.unstable_levels), "not_covered": NOT_COVERED,
                                   "statement": "certificate of the linearized switched system",
                                   "not_certified_below_orbit": c.tau_lower / orbit}),
        "dwell": Dataset(c.dwell / orbit, "orbit", "time each level but the last is held", dims=("switch",)),
        "transient": Dataset(c.transient, "1", "bound on sqrt(V_k) of the deviation while level k holds",
                             dims=("level",)),
        "u_bound": Dataset(c.u_bound, "ft*lbf", "bound on |u| while each level holds", AXES,
                           dims=("level", "axis"), attrs={"torque_limit_ft_lbf": c.torque_limit}),
        "h_bound": Dataset(c.h_bound, "ft*lbf*s", "bound on the deviation of |h| while each level holds",
                           AXES, dims=("level", "axis"),
                           attrs={"momentum_limit_ft_lbf_s": c.momentum_limit}),
    }
    if not len(sc.jumps):          # one level: no switch, no jump, no ratios
        for key in ("jump", "jump_up", "jump_down", "dwell"):
            del items[key]
    return items


def certificate_lines(sc: StairCertificate) -> list[str]:
    """The certificate in words, one line each (what ``acmm certify`` prints).

    Parameters
    ----------
    sc : StairCertificate
        The certificate.

    Returns
    -------
    list of str
        The lines.
    """
    c = sc.certificate
    L = len(sc.names)
    if c.unstable_levels:
        bad = ", ".join(sc.names[k] for k in c.unstable_levels)
        return [f"  no certificate: the frozen closed loop of level(s) {bad} is not stable"]
    lines = [f"  {L} level(s); proved decay rate lambda = {c.decay / sc.n:.4f} n"]
    if L > 1:
        shortest = float(np.min(c.dwell)) / sc.orbit
        below = (f"not certified at {c.tau_lower / sc.orbit:.3f}" if c.tau_lower > 0 else
                 "the first step of the search's grid: a shorter dwell may hold")
        lines.append(f"  certified minimum dwell tau* = {c.tau_star / sc.orbit:.3f} orbit (Geromel-Colaneri LMIs "
                     f"per level, switches checked both ways; {below}); "
                     f"shortest level {shortest:.2f} orbit: {'CERTIFIED' if c.certified else 'NOT certified'}")
        lines.append(f"  TEA-step transient: |u| <= {np.max(c.u_bound):.3g} ft*lbf (limit {c.torque_limit:g}), "
                     f"|h - h*| <= {np.max(c.h_bound):.4g} ft*lbf*s (limit {c.momentum_limit:g}): "
                     f"{'within the limits' if c.within_limits else 'NOT within the limits (the ellipsoid bound is conservative)'}")
    lines.append("  a certificate of the linearized switched system; not covered: " + NOT_COVERED)
    return lines
