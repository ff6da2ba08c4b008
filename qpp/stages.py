"""Stage runners for ``qpp design`` / ``qpp simulate``: config in, HDF5 (+ figures) out."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from acmm.results import Dataset, write_h5
from acmm.runlock import locked_stage
from qpp.config import PolarArmNonlinearity, QppConfig, load_config
from qpp.design import DesignResult, design
from qpp.simulate import simulate


def _cfg(config) -> QppConfig:
    return config if isinstance(config, QppConfig) else load_config(config)


def _rel(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return np.abs(a - b) / np.maximum(np.abs(b), 1e-12)


def design_items(cfg: QppConfig, r: DesignResult) -> dict:
    """Datasets of qpp_design.h5."""
    items = {
        "K1": Dataset(r.K1, "1", "observer-state gain K1 (eq 10.6; u = K1 x̂ + Kc x_c − f1o)"),
        "Kc": Dataset(r.Kc, "1", "servo-state gain Kc (eq 10.6)"),
        "H": Dataset(r.H, "1", "observer gain H, report's sign (L = −H, eq 10.5)"),
        "Cz": Dataset(r.Cz, "1", "C_z (eq 10.7)"),
        "a": Dataset(r.a, "1/s", "exponential weighting a (10.27)"),
        "T": Dataset(r.T, "s", "truncation time T"),
        "E": Dataset(r.E, "s^0.5", "E = [(e^{2aT} − 1)/(2a)]^{1/2} (10.44)"),
        "sector": Dataset(r.sector, "1", "sector [α_i, β_i] of φ for the circle check", ["alpha", "beta"]),
        "y_o_T": {"t": Dataset(r.y_o_t, "s", "time on [0, T]"),
                  "y_o": Dataset(r.y_o, "output units", "nominal output y_o on [0, T]")},
        "iterations": Dataset(np.array([[it["rho"], it["a"], it["beta1"], it["m"], float(it["circle"])]
                                        for it in r.iterations]) if r.iterations else np.zeros((0, 5)),
                              "mixed", "ch. 12.1 iterations", ["rho", "a_1/s", "beta1", "m", "circle_passed"]),
    }
    for reading in r.beta1:
        key = reading.replace(".", "_")
        b = r.beta1[reading]
        items[f"Bz_{key}"] = Dataset(r.Bz[reading], "1", f"B_z, {reading} reading (columns [r, d])")
        items[f"beta1_{key}"] = Dataset(b["value"], "1", f"β1 exact (SLICOT L∞ norm), B_z {reading}",
                                        attrs={"omega_peak_rad_s": b["omega_peak"], "grid_value": b["grid_value"]})
    items["Az"] = Dataset(r.Az["eq10.7"], "1/s", "A_z (eq 10.7; 13.6 / Table 14.1)")
    items["thresholds"] = Dataset(np.array([[t.half_width, t.beta3, t.beta4, t.m] for t in r.thresholds]),
                                  "1", "β3, β4, m (12.1) per bookkeeping: " + ", ".join(t.name for t in r.thresholds),
                                  ["half_width", "beta3", "beta4", "m"])
    c = r.circle
    items["circle"] = {
        "omega": Dataset(c.omega, "rad/s", "frequency grid"),
        "centres": Dataset(c.centres, "1", "h_ii(−a + jω), complex"),
        "radii": Dataset(c.radii, "1", "Gershgorin mean radii (d_i + d'_i)/2"),
        "margins": Dataset(c.margins, "1", "distance of band to disc boundary (>0 passes)"),
        "encirclements": Dataset(c.encirclements, "1", "N_ci (clockwise)"),
        "max_scale": Dataset(c.max_scale, "1", "largest s with sector s·[α, β] passing"),
    }
    pub = cfg.published
    if pub.K1 is not None and pub.Kc is not None:
        items["published"] = {
            "K1": Dataset(np.asarray(pub.K1, float), "1", "printed K1"),
            "Kc": Dataset(np.asarray(pub.Kc, float), "1", "printed Kc"),
        }
        if pub.H is not None:
            items["published"]["H"] = Dataset(np.asarray(pub.H, float), "1", "printed H")
            items["published"]["H_rel_diff"] = Dataset(
                np.where(np.abs(np.asarray(pub.H)) > 0, _rel(r.H, pub.H), 0.0), "1", "|H − H_printed|/|H_printed|")
    return items


@locked_stage(_cfg)
def run_design(config, figures: bool | None = None) -> tuple[QppConfig, DesignResult, Path]:
    """Design (ch. 12.1) and write ``<root>/<name>/qpp_design.h5`` (+ circle-criterion figures)."""
    cfg = _cfg(config)
    r = design(cfg)
    verdicts = {f"beta1_le_m[{rd},{bk}]": int(v) for (rd, bk), v in r.verdicts().items()}
    path = write_h5(cfg.run_dir() / "qpp_design.h5", design_items(cfg, r), cfg.to_yaml(),
                    {"stage": "qpp design", "circle_passed": int(r.circle.passed), **verdicts})
    if cfg.output.figures if figures is None else figures:
        from qpp.plots import plot_circle

        plot_circle(r, cfg.run_dir() / "qpp_circle.png")
    return cfg, r, path


@locked_stage(_cfg)
def run_simulate(config, figures: bool | None = None):
    """Design, simulate every scenario, write ``<root>/<name>/qpp_sim.h5`` (+ figures)."""
    cfg = _cfg(config)
    r = design(cfg)
    sims = simulate(cfg, r.K1, r.Kc, r.H)
    items = {"K1": Dataset(r.K1, "1", "gain K1 used"), "Kc": Dataset(r.Kc, "1", "gain Kc used"),
             "H": Dataset(r.H, "1", "observer gain H used (report's sign)")}
    for s in sims:
        items[s.name] = {
            "t": Dataset(s.t, "s", "time"),
            "r": Dataset(s.r, "output units", "reference r"),
            "r_o": Dataset(s.r_o, "output units", "nominal reference r_o"),
            "y": Dataset(s.y, "output units", "output y"),
            "y_o": Dataset(s.y_o, "output units", "nominal output y_o (eq 10.29)"),
            "u": Dataset(s.u, "control units", "control u = K1 x̂ + Kc x_c − f1o"),
            "x": Dataset(s.x, "state units", "plant state"),
            "error_inf": Dataset(s.error_inf, "output units", "‖y − y_o‖∞",
                                 attrs={"beta_o": s.beta_o, "passed": int(s.passed), "gamma": s.gamma}),
            "error_per_output": Dataset(s.error_per_output, "output units", "sup_t |y_i − y_oi|"),
        }
    path = write_h5(cfg.run_dir() / "qpp_sim.h5", items, cfg.to_yaml(),
                    {"stage": "qpp simulate", "all_passed": int(all(s.passed for s in sims))})
    if cfg.output.figures if figures is None else figures:
        from qpp.plots import plot_cartesian, plot_scenario

        for s in sims:
            plot_scenario(s, cfg.run_dir() / f"qpp_sim_{s.name}.png")
        if isinstance(cfg.nonlinearity, PolarArmNonlinearity):
            plot_cartesian(sims, cfg.nonlinearity.a, cfg.run_dir() / "qpp_sim_cartesian.png")
    return cfg, r, sims, path
