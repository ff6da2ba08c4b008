"""Stage runners for ``qpp design`` / ``qpp simulate``: config in, HDF5 (+ figures) out.

The design is procedure 12.1 (ch. 12.1; gains of eqs 10.5–10.6), the simulations those of
ch. 13–14.

``qpp simulate`` takes K1, Kc and H from ``<run>/qpp_design.h5`` (:class:`StoredDesign`, issue 16:
it used to run the whole design of ch. 12.1 again, the H∞ search of ch. 11 included) when that
file was written from the same resolved config (``config_hash``) by the same package version and
git commit, the source is that commit without uncommitted changes (an edited or unknown source may
compute something else), and the gains read back hash to the ``gains_sha256`` the design stored
with them (an edited file is designed again); otherwise it designs.  The gains are stored as
float64, so the simulation is the same bit for bit either way.
"""
from __future__ import annotations

from functools import partial
from pathlib import Path

import numpy as np

from acmm_qpp.outputs import stage
from acmm_qpp.results import Dataset, draw_figures, h5_text, redraw_stored, write_h5
from qpp.io.config import ExpressionNonlinearity, PolarArmNonlinearity, QppConfig, load_config, parse_config
from qpp.design.certificate import DesignResult
from qpp.design.procedure import design
from qpp.plots import plot_cartesian, plot_circle, plot_iterations, plot_scenario
from qpp.simulate.closed_loop import simulate
import types
import h5py
import hashlib
import yaml
from dataclasses import dataclass
from acmm_qpp import __version__
from acmm_qpp.errors import ConfigError
from acmm_qpp.provenance import config_hash, git_commit, git_dirty


#: units of the gains of eq 10.5–10.6 in the results (text: the config's own units, not UDUNITS)
GAIN_UNITS = {"K1": "input units per state unit", "Kc": "input units per servo-state unit",
              "H": "state units per output unit per s"}


def _resolve(config) -> QppConfig:
    """The config itself, or the one a config file / packaged name loads."""
    return config if isinstance(config, QppConfig) else load_config(config)


def _rel(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return np.abs(a - b) / np.maximum(np.abs(b), 1e-12)


def printed_H_difference(cfg: QppConfig, r: DesignResult) -> float | None:
    """Largest |H − H_printed| / |H_printed| over the non-zero printed entries of the observer gain
    (dimensionless); None when the config gives no printed H.

    Parameters
    ----------
    cfg : qpp.io.config.QppConfig
        The config (``published.H``).
    r : qpp.design.certificate.DesignResult
        The design (``H``).

    Returns
    -------
    float or None
        The largest relative difference, dimensionless (None also when every printed entry is 0).
    """
    pub = cfg.published.H
    if pub is None or not np.any(np.asarray(pub, float)):
        return None
    return float(_rel(r.H, pub)[np.abs(np.asarray(pub, float)) > 0].max())


def _thresholds(ts, what: str) -> Dataset:
    """Half-width, β3, β4, m (eq 12.1, dimensionless) per bookkeeping of ``ts``, described as ``what``."""
    return Dataset(np.array([[t.half_width, t.beta3, t.beta4, t.m] for t in ts]), "1",
                   what + " per bookkeeping: " + ", ".join(t.name for t in ts), ["half_width", "beta3", "beta4", "m"],
                   dims=("bookkeeping", "threshold"))


def _gains(K1, Kc, H, k1: str, kc: str, h: str) -> dict:
    """Datasets of the gains K1, Kc, H (eqs 10.5–10.6, :data:`GAIN_UNITS`) with their descriptions."""
    return {"K1": Dataset(K1, GAIN_UNITS["K1"], k1, dims=("input", "state")),
            "Kc": Dataset(Kc, GAIN_UNITS["Kc"], kc, dims=("input", "servo_state")),
            "H": Dataset(H, GAIN_UNITS["H"], h, dims=("state", "output"))}


def _published_certificate_items(pb) -> dict:
    """Datasets of the certificate of the printed gains (β1 both readings, β3/β4/m, circle)."""
    return {
        "beta1_eq10_7": Dataset(pb.beta1["eq10.7"]["value"], "1", "beta1 of the printed gains, B_z eq 10.7"),
        "beta1_printed": Dataset(pb.beta1["printed"]["value"], "1", "beta1 of the printed gains, printed B_z"),
        "thresholds": _thresholds(pb.thresholds, "β3, β4, m of the printed gains"),
        "circle_passed": Dataset(np.int8(pb.circle.passed), "1", "circle criterion with the printed gains (1: passed)"),
        "T": Dataset(pb.T, "s", "truncation time used"),
    }


def _printed_gain_items(pub, H) -> dict:
    """Datasets of the printed gains of the config's ``published`` section ({} when absent)."""
    if pub.K1 is None or pub.Kc is None:
        return {}
    items = _gains(*(None if g is None else np.asarray(g, float) for g in (pub.K1, pub.Kc, pub.H)),
                   "printed K1", "printed Kc", "printed H")
    if pub.H is None:
        del items["H"]
    else:
        items["H_rel_diff"] = Dataset(
            np.where(np.abs(np.asarray(pub.H)) > 0, _rel(H, pub.H), 0.0), "1", "|H − H_printed|/|H_printed|",
            dims=("state", "output"))
    return items


def sector_verified(cfg: QppConfig) -> bool | None:
    """Whether the sector computed for an ``expression`` nonlinearity held at the random check
    points (:func:`qpp.model.sector_bounds.verify`; False: the grid missed part of φ's range and the
    sector was widened to the extremum climbed from them); None when the sector is not computed
    from an expression.

    Parameters
    ----------
    cfg : qpp.io.config.QppConfig
        The config.

    Returns
    -------
    bool or None
        The verification's outcome.
    """
    nl = cfg.nonlinearity
    if cfg.design.sector is not None or not isinstance(nl, ExpressionNonlinearity) or nl.sector is not None:
        return None
    return bool(cfg.expression_model().sector_info.verified)


def design_items(cfg: QppConfig, r: DesignResult) -> dict:
    """Datasets of qpp_design.h5.

    Parameters
    ----------
    cfg : qpp.io.config.QppConfig
        The config.
    r : qpp.design.certificate.DesignResult
        The design.

    Returns
    -------
    dict
        Name → :class:`acmm_qpp.results.Dataset` (each with its units), for
        :func:`acmm_qpp.results.write_h5`.
    """
    items = {
        **_gains(r.K1, r.Kc, r.H, "observer-state gain K1 (eq 10.6; u = K1 x̂ + Kc x_c − f1o)",
                 "servo-state gain Kc (eq 10.6)", "observer gain H, report's sign (L = −H, eq 10.5)"),
        "Cz": Dataset(r.Cz, "output units per loop-state unit", "C_z (eq 10.7)", dims=("output", "loop_state")),
        "a": Dataset(r.a, "1/s", "exponential weighting a (10.27)"),
        "T": Dataset(r.T, "s", "truncation time T"),
        "E": Dataset(r.E, "s^0.5", "E = [(e^{2aT} − 1)/(2a)]^{1/2} (10.44)"),
        "sector": Dataset(r.sector, "1", "sector [α_i, β_i] of φ for the circle check", ["alpha", "beta"],
                          dims=("channel", "bound")),
        "y_o_T": {"t": Dataset(r.y_o_t, "s", "time on [0, T]", dims=("t",)),
                  "y_o": Dataset(np.asarray(r.y_o).T if np.ndim(r.y_o) == 2 and np.shape(r.y_o)[-1] == np.size(r.y_o_t)
                                 else r.y_o, "output units", "nominal output y_o on [0, T], (t, output)",
                                 dims=("t", "output") if np.ndim(r.y_o) == 2 else ("t",))},
        "iterations": _iterations(r),
    }
    if r.hinf_history:
        keys = ["rho", "nu", "delta", "k_psd", "h_psd", "lambda_kh_scaled", "spectral", "admissible", "a", "ws"]
        items["hinf_search"] = Dataset(np.array([[float(h.get(k, np.nan)) for k in keys] for h in r.hinf_history]),
                                       "column_units[j]", "ch. 11 passes: rho, nu, delta = ||T_wy||inf (a-shifted, = beta1), "
                                       "tests k1 >= 0, h >= 0, lambda_max(k1 h)/nu^2 < 1 (1 = true), admissible, "
                                       "a (1/s), mean W_s scale", keys, dims=("hinf_pass", "hinf_quantity"),
                                       attrs={"actions": "; ".join(str(h.get("action", "")) for h in r.hinf_history),
                                              "column_units": ",".join("1/s" if k == "a" else "1" for k in keys)})
    c = r.consistent
    items["certificate"] = {
        "certified": Dataset(int(r.certified), "1", "1: every premise of the consistent certificate holds "
                             "(one sector, the circle criterion's; one norm: " + r.norm + ")"),
        "beta1": Dataset(r.beta1_ref, "1", f"beta1 = H-infinity norm sigma_max of C_z (sI - A_n)^-1 B_z (B_z {r.bz})"),
        "m": Dataset(c.m, "1", "threshold m = beta_o/(beta_i + beta_o beta3 + beta4), consistent reading: a lower "
                     "bound for every T' in (0, T] from the nominal loop enclosed on cells"),
        "m_sampled": Dataset(c.m_sampled, "1", "m of the trapezoid rule on the nominal loop's samples (an estimate "
                             "m bounds from below; their difference is the enclosure's gap)"),
        "beta_i": Dataset(c.beta_i, "output units", "Euclidean input radius sqrt(p) beta_ri + sqrt(r) d_inf"),
        "beta3": Dataset(c.beta3, "1", "sup over t <= T of the spectral norm of grad_y phi (eq 10.40)"),
        "beta4": Dataset(c.beta4, "output units", "e^{aT} ||(phi(y_o) - phi_o)_T||_2 / E, sector bound (10.53, 10.55)"),
        "gamma_inf": Dataset(r.gamma_inf, "output units per input unit per s^1/2",
                             "L2-to-peak gain of C_z (sI - A_n)^-1 B_z; gamma_inf E <= m closes eq 10.45"),
        "peak_ratio": Dataset(r.gamma_inf * c.E_over_m, "1", "gamma_inf times an upper bound of max over T' <= T of E/m "
                              "(<= 1: eq 10.45 closed)"),
        "m_bookkeeping": Dataset(r.m_ref, "1", f"m of the iteration target, bookkeeping {r.bookkeeping} "
                                 "(a bookkeeping of the report is a reproduction, not a certificate)"),
        "T_settle": Dataset(r.T_settle, "s", "settling time of the nominal closed loop"),
        "ws_scale": Dataset(np.asarray(r.ws_scale or [1.0], float), "1", "W_s = diag(w)·S_c of the gains",
                            dims=("ws_entry",)),
    }
    if "rho_v" in c.note:
        items["certificate"]["rho_v"] = Dataset(c.note["rho_v"], "state units (m/s, rad/s)",
                                                "the polar arm's rates within rho_v = gamma_v beta_o / gamma_inf of the "
                                                "nominal ones: the box of its beta3 (with y_o +- beta_o)")
    if r.published is not None:
        items["published_certificate"] = _published_certificate_items(r.published)
    for reading, b in r.beta1.items():
        key = reading.replace(".", "_")
        items[f"Bz_{key}"] = Dataset(r.Bz[reading], "loop-state units per s per exogenous unit", f"B_z, {reading} reading (columns [r, d])",
                                     dims=("loop_state", "exogenous"))
        items[f"beta1_{key}"] = Dataset(b["value"], "1", f"β1 exact (SLICOT L∞ norm), B_z {reading}",
                                        attrs={"omega_peak_rad_s": b["omega_peak"], "grid_value": b["grid_value"]})
    items["Az"] = Dataset(r.Az["eq10.7"], "1/s", "A_z (eq 10.7; 13.6 / Table 14.1)",
                         dims=("loop_state", "loop_state_col"))
    items["thresholds"] = _thresholds(r.thresholds, "β3, β4, m (12.1)")
    verified = sector_verified(cfg)
    if verified is not None:
        items["sector_verified"] = Dataset(int(verified), "1", "1: φ within the grid's sector at 4000 random points "
                                           "of the ranges; 0: some were outside, and the sector was widened to the "
                                           "extremum climbed from them")
    items["circle"] = _circle_items(r.circle)
    printed = _printed_gain_items(cfg.published, r.H)
    if printed:
        items["published"] = printed
    return items


def _circle_items(c) -> dict:
    """The circle check's datasets (grid, bands, margins, scales; the small-gain terms of a coupled φ)."""
    out = {
        "omega": Dataset(c.omega, "rad/s", "frequency grid", dims=("omega",)),
        "centres": Dataset(c.centres, "1", "h_ii(−a + jω), complex", dims=("channel", "omega")),
        "radii": Dataset(c.radii, "1", "Gershgorin mean radii (d_i + d'_i)/2", dims=("channel", "omega")),
        "margins": Dataset(c.margins, "1", "distance of band to disc boundary (>0 passes)", dims=("channel",)),
        "encirclements": Dataset(c.encirclements, "1", "N_ci (clockwise)", dims=("channel",)),
        "alpha": Dataset(np.asarray(c.alpha, float), "1", "lower sector gain α_i of the critical disc", dims=("channel",)),
        "beta": Dataset(np.asarray(c.beta, float), "1", "upper sector gain β_i of the critical disc", dims=("channel",)),
        "max_scale": Dataset(c.max_scale, "1", "largest s with sector s·[α, β] passing"),
        "min_scale": Dataset(c.min_scale, "1", "smallest s with sector s·[α, β] passing (0: every "
                             "smaller sector passes; > 0: an unstable H(s) needs a sector this wide)"),
    }
    if c.method == "small_gain":          # a coupled φ: the small-gain form (qpp.design.circle)
        out["margins"] = Dataset(c.margins, "1", "1 − ρ·sup σ̄(H_c), small-gain form for a coupled φ "
                                             "(>0 passes)", dims=("channel",))
        out["gain_bound"] = Dataset(c.gain_bound, "1", "ρ: ‖φ − C_0 y‖₂ ≤ ρ‖y‖₂ (small-gain form)")
        out["peak_gain"] = Dataset(c.peak_gain, "1", "sup_ω σ̄(H_c(−a + jω)), H_c = (I − H C_0)⁻¹ H")
    return out


_ITER_KEYS = ["rho", "nu", "a", "T", "delta", "beta1", "m", "circle", "certified"]
#: per column (units "column_units[j]", like the per-state arrays' state_units[j]); flags 1/0
_ITER_UNITS = ["1", "1", "1/s", "s", "1", "1", "1", "1", "1"]


def _iterations(r: DesignResult) -> Dataset:
    rows = [[float(it.get(k, np.nan)) for k in _ITER_KEYS] for it in r.iterations]
    return Dataset(np.array(rows) if rows else np.zeros((0, len(_ITER_KEYS))), "column_units[j]",
                   "procedure 12.1, one row per evaluation: rho, nu, a (1/s), T (s), delta = ||T_wy||inf, "
                   "beta1, m (recomputed), circle passed, certified",
                   _ITER_KEYS, dims=("iteration", "quantity"),
                   attrs={"column_units": ",".join(_ITER_UNITS),
                                      "stages": ";".join(str(it.get("stage", "")) for it in r.iterations),
                                      "ws": ";".join(",".join(f"{w:g}" for w in it.get("ws", [1.0]))
                                                     for it in r.iterations),
                                      "notes": ";".join(str(it.get("note", "")).replace(";", ",")
                                                        for it in r.iterations)})


@stage(("qpp_design.h5", "qpp_circle*.png", "qpp_iterations.png"), _resolve)
def run_design(config, figures: bool | None = None, *, out: Path) -> tuple[QppConfig, DesignResult, Path]:
    """Design (ch. 12.1) and write ``<root>/<name>/qpp_design.h5`` (+ circle and iteration figures).

    An uncertified design is still written (root attributes ``certified = 0``, ``label =
    "uncertified"``, ``verdict``); the caller decides the exit code (:class:`DesignError`, 3).
    The root attributes ``proved``, ``assumed`` and ``scope`` (their one line, which a certified
    verdict ends with) come from :func:`qpp.design.certificate.scope`; ``horizon_note`` says when T
    ends before the nominal loop settles (empty otherwise), as ``qpp design`` prints it.

    Parameters
    ----------
    config : qpp.io.config.QppConfig or path-like or str
        The config, or a config file / packaged name to load.
    figures : bool, optional
        Write the figures (default: ``output.figures``).
    out : pathlib.Path
        The folder its files are written in (the staging folder :func:`acmm_qpp.outputs.stage` gives).

    Returns
    -------
    tuple
        (config, :class:`qpp.design.certificate.DesignResult`, path of ``qpp_design.h5``).
    """
    cfg = config                # resolved by the stage decorator
    r = design(cfg)
    verdicts = {f"beta1_le_m[{rd},{bk}]": bool(v) for (rd, bk), v in r.verdicts().items()}
    write_h5(out / "qpp_design.h5", design_items(cfg, r), cfg.to_yaml(),
             {"stage": "qpp design", "circle_passed": bool(r.circle.passed), **verdicts,
              "certified": bool(r.certified), "label": "certified" if r.certified else "uncertified",
              "verdict": r.verdict, "bookkeeping": r.bookkeeping, "norm": r.norm,
              "sector_of_certificate": "the circle criterion's (dataset sector)",
              **{f"premise[{k}]": bool(ok) for k, (ok, _) in r.premises.items()},
              **{f"premise_statement[{k}]": text for k, (_, text) in r.premises.items()},
              "proved": "; ".join(r.proved), "assumed": "; ".join(r.assumed), "scope": r.scope_text,
              "horizon_note": r.horizon_note,
              "gains_sha256": _gains_sha256(r.K1, r.Kc, r.H), "unit_system": cfg.output.units})
    if cfg.output.figures if figures is None else figures:
        draw_figures(figure_calls_from_file(out / "qpp_design.h5", out))
    return cfg, r, cfg.run_dir() / "qpp_design.h5"


@dataclass
class StoredDesign:
    """A design read back from ``qpp_design.h5``: what a simulation needs of it.

    Attributes
    ----------
    K1 : (m, n) array
        State-feedback gain (eq 10.6), plant input units per state unit.
    Kc : (m, q) array
        Compensator gain (eq 10.6), plant input units per compensator-state unit.
    H : (n, p) array
        Observer gain (eq 10.5, report's sign), state units per output unit per s.
    certified : bool
        Whether the design was certified (β1 ≤ m and the circle criterion).
    verdict : str
        The design's verdict line.
    path : pathlib.Path
        The file read.
    horizon_note : str
        The design's note when T ends before the nominal loop settles, "" otherwise
        (:attr:`qpp.design.certificate.DesignResult.horizon_note`).
    """

    K1: np.ndarray
    Kc: np.ndarray
    H: np.ndarray
    certified: bool
    verdict: str
    path: Path
    horizon_note: str = ""


def _source_unchanged() -> bool:
    """Whether the code running is exactly a commit: a git checkout whose tracked files have no
    uncommitted change (:func:`acmm_qpp.provenance.git_dirty`); False when dirty, not a checkout,
    or git is missing."""
    return git_commit() != "unknown" and git_dirty() == "no"


def _load_stored_design(path: Path, config_text: str) -> StoredDesign | None:
    """The gains in ``path`` (a ``qpp_design.h5``, maybe missing) when it was written from
    ``config_text`` (the resolved config's YAML) by this code; None when missing, unreadable, from
    another config, version or commit, from a changed source, or with edited gains."""
    if not Path(path).is_file():
        return None
    try:
        with h5py.File(path, "r") as f:
            a = f.attrs
            same = (a.get("stage") == "qpp design" and a.get("config_hash") == config_hash(config_text)
                    and a.get("package_version") == __version__
                    and a.get("git_commit") == git_commit())
            if not same or not _source_unchanged():
                return None
            K1, Kc, H = (np.array(f[k][()], dtype=float) for k in ("K1", "Kc", "H"))
            if a.get("gains_sha256") != _gains_sha256(K1, Kc, H):
                return None
            return StoredDesign(K1, Kc, H, bool(a["certified"]), str(a["verdict"]), Path(path),
                                h5_text(a.get("horizon_note", "")))
    except (OSError, KeyError, ValueError):
        return None


def _gains_sha256(K1, Kc, H) -> str:
    """Hex SHA-256 of the gains' float64 bytes with their shapes (eqs 10.5–10.6; any units: the
    bytes are hashed), stored by ``qpp design``."""
    h = hashlib.sha256()
    for g in (K1, Kc, H):
        g = np.ascontiguousarray(g, dtype=float)
        h.update(f"{g.shape}|".encode())
        h.update(g.tobytes())
    return h.hexdigest()


@stage(("qpp_sim.h5", "qpp_sim_*.png"), _resolve)
def run_simulate(config, figures: bool | None = None, progress=None, *, out: Path):
    """Design (or reuse the design), simulate every scenario, write ``<root>/<name>/qpp_sim.h5``
    (+ figures).

    The gains of ``qpp_design.h5`` in the run directory are used when ``qpp design`` wrote it from
    the same resolved config with this code (the module's docstring says when);
    otherwise the design of ch. 12.1 runs first.  ``progress(done, total, name)`` is called after
    each scenario.

    Parameters
    ----------
    config : qpp.io.config.QppConfig or path-like or str
        The config, or a config file / packaged name to load.
    figures : bool, optional
        Write the figures (default: ``output.figures``).
    progress : callable, optional
        ``progress(done, total, name)``.
    out : pathlib.Path
        The folder its files are written in (the staging folder :func:`acmm_qpp.outputs.stage` gives).

    Returns
    -------
    tuple
        (config, the design — :class:`qpp.design.certificate.DesignResult`, or
        :class:`StoredDesign` when reused; both have ``K1``, ``Kc``, ``H``,
        ``certified``, ``verdict`` —, list of :class:`qpp.simulate.closed_loop.SimResult`, path of
        ``qpp_sim.h5``).
    """
    cfg = config                # resolved by the stage decorator
    r = _load_stored_design(cfg.run_dir() / "qpp_design.h5", cfg.to_yaml()) or design(cfg)
    sims = simulate(cfg, r.K1, r.Kc, r.H, progress=progress)
    items = _gains(r.K1, r.Kc, r.H, "gain K1 used", "gain Kc used", "observer gain H used (report's sign)")
    for s in sims:
        # time first: (t, channel), as in acmm's files
        items[s.name] = {
            "t": Dataset(s.t, "s", "time", dims=("t",)),
            "r": Dataset(np.asarray(s.r).T, "output units", "reference r", dims=("t", "output")),
            "r_o": Dataset(np.asarray(s.r_o).T, "output units", "nominal reference r_o", dims=("t", "output")),
            "y": Dataset(np.asarray(s.y).T, "output units", "output y", dims=("t", "output")),
            "y_o": Dataset(np.asarray(s.y_o).T, "output units", "nominal output y_o (eq 10.29)", dims=("t", "output")),
            "u": Dataset(np.asarray(s.u).T, "control units", "control u = K1 x̂ + Kc x_c − f1o", dims=("t", "input")),
            "x": Dataset(np.asarray(s.x).T, "state units", "plant state", dims=("t", "state")),
            "error_inf": Dataset(s.error_inf, "output units", "‖y − y_o‖∞",
                                 # γ of the sinusoidal kind, the payload of the polar arm; an
                                 # expression's parameters are param_<name> (not "gamma")
                                 attrs={"beta_o": s.beta_o, "passed": bool(s.passed),
                                        "premises_held": bool(not s.broken_premises(
                                            cfg.spheres.beta_ri, getattr(cfg.nonlinearity, "y_range", None))),
                                        **({} if s.parameters else {"gamma": s.gamma}),
                                        **({} if s.diverged_at is None else {"diverged_at_s": s.diverged_at}),
                                        **{f"param_{k}": v for k, v in (s.parameters or {}).items()}}),
            "error_per_output": Dataset(s.error_per_output, "output units", "sup_t |y_i − y_oi|", dims=("output",)),
        }
    write_h5(out / "qpp_sim.h5", items, cfg.to_yaml(),
             {"stage": "qpp simulate", "all_passed": int(all(s.passed for s in sims)),
              "design_certified": int(r.certified), "design_verdict": r.verdict, "unit_system": cfg.output.units})
    if cfg.output.figures if figures is None else figures:
        draw_figures(figure_calls_from_file(out / "qpp_sim.h5", out))
    return cfg, r, sims, cfg.run_dir() / "qpp_sim.h5"


def figure_calls_from_file(path: Path, out_dir: Path) -> list:
    """The figures of ``qpp design`` (``qpp_design.h5``: circle criterion per channel, procedure
    12.1's evaluations) or of ``qpp simulate`` (``qpp_sim.h5``: one figure per scenario, the
    Cartesian load path of the polar arm) drawn from the file alone (``qpp plot``): nothing is
    designed or simulated again.

    Parameters
    ----------
    path : pathlib.Path
        A ``qpp_design.h5`` or ``qpp_sim.h5`` (root attribute ``stage``).
    out_dir : pathlib.Path
        Folder of the figures (the file names the stage writes).

    Returns
    -------
    list of functools.partial
        The figure calls, for :func:`acmm_qpp.results.draw_figures`.

    Raises
    ------
    acmm_qpp.errors.ConfigError
        The file is not a qpp result.
    """
    with h5py.File(path, "r") as f:
        stage = h5_text(f.attrs.get("stage", ""))
        if stage not in ("qpp design", "qpp simulate"):
            raise ConfigError(f"{path}: not a qpp result file (stage {stage or 'unknown'!r}; qpp plot draws "
                              "qpp_design.h5 and qpp_sim.h5)")
        cfg = parse_config(yaml.safe_load(h5_text(f.attrs["config"])), source=f"{path} (stored config)")
        if stage == "qpp design":
            c = f["circle"]
            sector = np.asarray(f["sector"][()], float)
            circle = types.SimpleNamespace(
                passed=bool(f.attrs["circle_passed"]), margins=np.asarray(c["margins"][()]),
                centres=np.asarray(c["centres"][()]), radii=np.asarray(c["radii"][()]),
                alpha=np.asarray(c["alpha"][()]) if "alpha" in c else sector[:, 0],
                beta=np.asarray(c["beta"][()]) if "beta" in c else sector[:, 1],
                method="small_gain" if "gain_bound" in c else "gershgorin")
            rows = np.asarray(f["iterations"][()], float).reshape(-1, len(_ITER_KEYS))
            iterations = [dict(zip(_ITER_KEYS, row)) for row in rows]
            for it in iterations:
                it["circle"], it["certified"] = bool(it["circle"]), bool(it["certified"])
            res = types.SimpleNamespace(circle=circle, iterations=iterations, certified=bool(f.attrs["certified"]),
                                        beta1_ref=float(f["certificate/beta1"][()]),
                                        m_ref=float(f["certificate/m_bookkeeping"][()]))
            return [partial(plot_circle, res, out_dir / "qpp_circle.png"),
                    partial(plot_iterations, res, out_dir / "qpp_iterations.png")]
        order = [sc.name for sc in cfg.simulation.scenarios]
        groups = sorted((k for k in f if isinstance(f[k], h5py.Group)),
                        key=lambda k: (order.index(k) if k in order else len(order), k))
        sims = []
        for name in groups:
            g = f[name]
            e = g["error_inf"]
            # the expression's order (the attributes are listed by name), as the stage's titles had it
            params = {k: float(e.attrs[f"param_{k}"]) for k in getattr(cfg.nonlinearity, "parameters", {})
                      if f"param_{k}" in e.attrs}
            sims.append(types.SimpleNamespace(
                name=name, t=np.asarray(g["t"][()]), **{k: np.asarray(g[k][()]).T for k in ("r", "r_o", "y", "y_o", "u")},
                error_inf=float(e[()]), error_per_output=np.asarray(g["error_per_output"][()]),
                beta_o=float(e.attrs["beta_o"]), passed=bool(e.attrs["passed"]), parameters=params or None,
                gamma=float(e.attrs.get("gamma", np.nan))))
    calls = [partial(plot_scenario, sm, out_dir / f"qpp_sim_{sm.name}.png") for sm in sims]
    if isinstance(cfg.nonlinearity, PolarArmNonlinearity) and sims:
        calls.append(partial(plot_cartesian, sims, cfg.nonlinearity.a, out_dir / "qpp_sim_cartesian.png"))
    return calls


#: results file → the stage that writes it (root attribute ``stage``), in the order ``qpp plot``
#: redraws a run folder's figures
FIGURE_SOURCES = {"qpp_design.h5": "qpp design", "qpp_sim.h5": "qpp simulate"}
#: stage → the reader of its results file's figures (:func:`acmm_qpp.results.redraw_stored`)
READERS = {"qpp design": figure_calls_from_file, "qpp simulate": figure_calls_from_file}


def redraw_figures(target, out=None) -> list[Path]:
    """Redraw a qpp run's figures from ``qpp_design.h5`` / ``qpp_sim.h5`` alone (``qpp plot``;
    :func:`figure_calls_from_file`).

    Parameters
    ----------
    target : path-like
        A run folder or one of its qpp results files.
    out : path-like, optional
        Folder of the figures (created if missing; default: the results file's folder).

    Returns
    -------
    list of pathlib.Path
        The figures written.

    Raises
    ------
    acmm_qpp.errors.ConfigError
        ``target`` is missing or holds no qpp results file (exit 2).
    acmm_qpp.errors.FigureError
        A figure could not be drawn or written (exit 4).
    """
    return redraw_stored(target, FIGURE_SOURCES, READERS, out)
