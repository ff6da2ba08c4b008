"""Stage runners: config in, results file out.  The glue between the pure library
modules and the CLI (I/O at the edge; the mathematics lives in the library modules)."""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from acmm import tea as tea_mod
from acmm.config import Config, load_config
from acmm.results import Dataset, write_h5

AXES = ["roll", "pitch", "yaw"]


@dataclass
class TeaResult:
    config: Config
    tea: tea_mod.TEA
    others: list = field(default_factory=list)


def _as_config(config) -> Config:
    return config if isinstance(config, Config) else load_config(config)


def compute_tea(config) -> TeaResult:
    """TEA of a config's own inertia and bias (physical branch)."""
    cfg = _as_config(config)
    inertia = cfg.inertia.matrix()
    bias = tea_mod.resolve_bias(cfg.disturbance, inertia, cfg.orbit_rate)
    return TeaResult(cfg, tea_mod.solve_tea(inertia, cfg.orbit_rate, bias))


def run_tea(config, all_roots: bool = False) -> tuple[TeaResult, Path]:
    """Compute the TEA and write ``runs/<name>/tea.h5``."""
    result = compute_tea(config)
    cfg, t = result.config, result.tea
    inertia = cfg.inertia.matrix()
    if all_roots:
        result.others = [r for r in tea_mod.all_equilibria(inertia, cfg.orbit_rate, t.bias)
                         if np.max(np.abs(r.theta - t.theta)) > 1e-6]
    items = {
        "theta": Dataset(t.theta, "rad", "torque-equilibrium attitude θ* (eq 4.1)", AXES),
        "theta_deg": Dataset(t.theta_deg, "deg", "θ* in degrees", AXES),
        "omega": Dataset(t.omega, "rad/s", "ω* at θ* (eq 4.3)", AXES),
        "bias": Dataset(t.bias, "ft*lbf", "bias torque balanced at θ* (eq 4.1)", AXES),
        "inertia": Dataset(inertia, "slug*ft^2", "inertia matrix (eq 3.2)", AXES),
        "orbit_rate": Dataset(cfg.orbit_rate, "rad/s", "orbital rate n"),
        "residual": Dataset(t.residual, "ft*lbf", "max |τ_gyro + τ_gg + bias| at θ*"),
    }
    if result.others:
        items["other_roots"] = Dataset(np.array([o.theta for o in result.others]), "rad",
                                       "other equilibria found by multi-start Newton", AXES)
    path = write_h5(cfg.run_dir() / "tea.h5", items, cfg.to_yaml(), {"stage": "tea"})
    return result, path


@dataclass
class LinearizeResult:
    config: Config
    tea: tea_mod.TEA
    model: object
    controllability: object


def run_linearize(config) -> tuple[LinearizeResult, Path]:
    """TEA, then the design model of ``design.model``; writes ``runs/<name>/linearize.h5``."""
    from acmm import linearize as lin

    tr = compute_tea(config)
    cfg = tr.config
    model = lin.design_point(cfg.inertia.matrix(), tr.tea.theta, cfg.orbit_rate,
                             model=cfg.design.model, drf_mode=cfg.design.drf_mode)
    ctrb = lin.controllability(model)
    result = LinearizeResult(cfg, tr.tea, model, ctrb)
    names = list(model.state_names)
    eig = np.linalg.eigvals(model.A)
    items = {
        "A": Dataset(model.A, "per-state (see state_units)", "state matrix of eq 4.46 (x' = A x + B u + G w)",
                     names, {"state_units": np.array(model.state_units, dtype="S")}),
        "B": Dataset(model.B, "state unit per ft*lbf", "control input matrix (u enters ω' as −u, h' as +u)",
                     names),
        "G": Dataset(model.G, "state unit per ft*lbf", "disturbance input matrix", names),
        "state_names": Dataset(np.array(names, dtype="S"), "1", "state order of eq 4.47"),
        "state_units": Dataset(np.array(model.state_units, dtype="S"), "1", "unit of each state"),
        "scales": Dataset(model.scales, "per-state (see state_units)", "nominal state magnitudes", names),
        "theta_star": Dataset(model.theta_star, "rad", "linearization attitude", AXES),
        "omega_star": Dataset(model.omega_star, "rad/s", "ω* at the linearization attitude (eq 4.3)", AXES),
        "tea": Dataset(tr.tea.theta, "rad", "TEA of the full inertia", AXES),
        "inertia_design": Dataset(model.inertia, "slug*ft^2", "inertia of the design model", AXES),
        "inertia": Dataset(cfg.inertia.matrix(), "slug*ft^2", "full inertia", AXES),
        "eigenvalues": Dataset(eig, "rad/s", "open-loop eigenvalues of A"),
        "controllability_min_ratio": Dataset(ctrb.min_ratio, "1",
                                             "min σmin([A−sI, B])/σmax over eigenvalues and s=0, scaled"),
        "controllability_rank": Dataset(ctrb.rank, "1", f"PBH rank with tolerance {ctrb.tol:g}"),
    }
    path = write_h5(cfg.run_dir() / "linearize.h5", items, cfg.to_yaml(),
                    {"stage": "linearize", "variant": model.variant, "drf_mode": model.drf_mode})
    return result, path
