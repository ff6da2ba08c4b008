"""Stage runners: config in, results file out; the glue between the pure library modules and
the CLI.  Here the TEA (eqs 4.1–4.3) and the design model (eqs 4.46–4.47); the sector LQR per
design point (ch. 5.2) with its gain schedule (ch. 5.3) in :mod:`acmm.stages.design`, the
nonlinear simulation (ch. 6) in :mod:`acmm.stages.simulate`.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from acmm.model import controllability as ctrb_mod, linearize as lin, tea as tea_mod
from acmm.io.config import Config
from acmm.stages.common import AXES, UNIT_A, UNIT_B, UNIT_STATE, as_config, in_system, write_results
from acmm_qpp.outputs import stage
from acmm_qpp.results import Dataset


@dataclass
class TeaResult:
    """The TEA of a config.

    Attributes
    ----------
    config : acmm.io.config.Config
        The validated config.
    tea : acmm.model.tea.TEA
        Its torque-equilibrium attitude on the physical branch (θ* in rad, eqs 4.1–4.3).
    others : list of acmm.model.tea.TEA
        Other equilibria (filled by ``run_tea(all_roots=True)``).
    """

    config: Config
    tea: tea_mod.TEA
    others: list = field(default_factory=list)


def _compute_tea(config) -> TeaResult:
    """The :class:`TeaResult` of a config (or config file / packaged name): TEA of its own inertia
    and bias (physical branch)."""
    cfg = as_config(config)
    inertia = cfg.inertia.matrix()
    bias = tea_mod.resolve_bias(cfg.disturbance, inertia, cfg.orbit_rate)
    return TeaResult(cfg, tea_mod.solve_tea(inertia, cfg.orbit_rate, bias,
                                            expected=cfg.disturbance.requested_tea()))


@stage(("tea.h5",), as_config)
def run_tea(config, all_roots: bool = False, *, out: Path) -> tuple[TeaResult, Path]:
    """Compute the TEA and write ``runs/<name>/tea.h5``.

    Parameters
    ----------
    config : acmm.io.config.Config or path-like or str
        The config, or a config file / packaged name to load.
    all_roots : bool, optional
        Also search the other equilibria (multi-start Newton) and write them.
    out : pathlib.Path
        The folder its files are written in (the staging folder :func:`acmm_qpp.outputs.stage` gives).

    Returns
    -------
    tuple
        (:class:`TeaResult`, pathlib.Path of ``tea.h5``).
    """
    result = _compute_tea(config)
    cfg, t = result.config, result.tea
    inertia = cfg.inertia.matrix()
    if all_roots:
        result.others = [r for r in tea_mod.all_equilibria(inertia, cfg.orbit_rate, t.bias)
                         if np.max(np.abs(r.theta - t.theta)) > 1e-6]
    items = {
        "theta": Dataset(t.theta, "rad", "torque-equilibrium attitude θ* (eq 4.1)", AXES, dims=("axis",)),
        "omega": Dataset(t.omega, "rad/s", "ω* at θ* (eq 4.3)", AXES, dims=("axis",)),
        "bias": Dataset(t.bias, "ft*lbf", "bias torque balanced at θ* (eq 4.1)", AXES, dims=("axis",)),
        "inertia": Dataset(inertia, "slug*ft^2", "inertia matrix (eq 3.2)", AXES, dims=("axis", "axis_col")),
        "orbit_rate": Dataset(cfg.orbit_rate, "rad/s", "orbital rate n"),
        "residual": Dataset(t.residual, "ft*lbf", "max |τ_gyro + τ_gg + bias| at θ*"),
    }
    if result.others:
        items["other_roots"] = Dataset(np.array([o.theta for o in result.others]), "rad",
                                       "other equilibria found by multi-start Newton", AXES,
                                       dims=("root", "axis"))
    write_results(out / "tea.h5", items, cfg, {"stage": "tea"})
    return result, cfg.run_dir() / "tea.h5"


@dataclass
class LinearizeResult:
    """The design model of a config at its TEA.

    Attributes
    ----------
    config : acmm.io.config.Config
        The validated config.
    tea : acmm.model.tea.TEA
        Its TEA (θ* in rad).
    model : acmm.model.linearize.LinearModel
        The 24-state model of eqs 4.46–4.47 (report units).
    controllability : acmm.model.linearize.Controllability
        PBH controllability test of the model.
    eigenvalues : (24,) complex array or None
        Open-loop eigenvalues of A, rad/s.
    """

    config: Config
    tea: tea_mod.TEA
    model: object
    controllability: object
    eigenvalues: np.ndarray | None = None

    def eigenvalues_over_n(self) -> np.ndarray:
        """The open-loop eigenvalues divided by the orbit rate n, sorted by real then imaginary part.

        Returns
        -------
        (24,) complex array
            λ / n, dimensionless.
        """
        eig = self.eigenvalues / self.model.n
        return eig[np.lexsort((eig.imag, eig.real))]


@stage(("linearize.h5",), as_config)
def run_linearize(config, *, out: Path) -> tuple[LinearizeResult, Path]:
    """TEA, then the design model of ``design.model``; writes ``runs/<name>/linearize.h5``.

    Parameters
    ----------
    config : acmm.io.config.Config or path-like or str
        The config, or a config file / packaged name to load.
    out : pathlib.Path
        The folder its files are written in (the staging folder :func:`acmm_qpp.outputs.stage` gives).

    Returns
    -------
    tuple
        (:class:`LinearizeResult`, pathlib.Path of ``linearize.h5``).
    """
    tr = _compute_tea(config)
    cfg = tr.config
    model = lin.design_point(cfg.inertia.matrix(), tr.tea.theta, cfg.orbit_rate,
                             model=cfg.design.model, drf_mode=cfg.design.drf_mode)
    ctrb = ctrb_mod.controllability(model)
    eig = np.linalg.eigvals(model.A)
    names = list(model.state_names)
    items = {
        "A": Dataset(model.A, UNIT_A, "state matrix of eq 4.46 (x' = A x + B u + G w)",
                     names, dims=("state", "state_col")),
        "B": Dataset(model.B, UNIT_B, "control input matrix (u enters ω' as −u, h' as +u)",
                     names, dims=("state", "axis")),
        "G": Dataset(model.G, UNIT_B, "disturbance input matrix", names, dims=("state", "axis")),
        "state_names": Dataset(np.array(names, dtype="S"), "1", "state order of eq 4.47", dims=("state",)),
        "state_units": Dataset(np.array(model.state_units, dtype="S"), "1", "unit of each state", dims=("state",)),
        "scales": Dataset(model.scales, UNIT_STATE, "nominal state magnitudes", names, dims=("state",)),
        "theta_star": Dataset(model.theta_star, "rad", "linearization attitude", AXES, dims=("axis",)),
        "omega_star": Dataset(model.omega_star, "rad/s", "ω* at the linearization attitude (eq 4.3)", AXES,
                              dims=("axis",)),
        "tea": Dataset(tr.tea.theta, "rad", "TEA of the full inertia", AXES, dims=("axis",)),
        "inertia_design": Dataset(model.inertia, "slug*ft^2", "inertia of the design model", AXES,
                                  dims=("axis", "axis_col")),
        "inertia": Dataset(cfg.inertia.matrix(), "slug*ft^2", "full inertia", AXES, dims=("axis", "axis_col")),
        "eigenvalues": Dataset(eig, "rad/s", "open-loop eigenvalues of A", dims=("eigenvalue",)),
        "controllability_min_ratio": Dataset(ctrb.min_ratio, "1",
                                             "min σmin([A−sI, B])/σmax over eigenvalues and s=0, scaled"),
        "controllability_rank": Dataset(ctrb.rank, "1", f"PBH rank with tolerance {ctrb.tol:g}"),
    }
    items = in_system(items, cfg, {"A": "A", "B": "B", "G": "G", "scales": "scales"})
    write_results(out / "linearize.h5", items, cfg,
                  {"stage": "linearize", "variant": model.variant, "drf_mode": model.drf_mode})
    return LinearizeResult(cfg, tr.tea, model, ctrb, eig), cfg.run_dir() / "linearize.h5"
