"""Batch sweeps and Monte Carlo robustness studies of the ACMM closed loop (issue 7).

A sweep (:mod:`acmm.sweep_config`) varies plant parameters of one or more base configs and
runs one nonlinear closed-loop simulation (ch. 6) per case.

Cases
    Case ``i`` of a Monte Carlo sweep draws its parameters from
    ``numpy.random.default_rng(SeedSequence([seed, i]))``, so every case is reproducible from
    (base config, case index, seed) alone, whatever the order or the machine that runs it.  The
    seed does not involve the base: case ``i`` of every base gets the same draws (common random
    numbers) unless resampling of an unphysical inertia makes them differ.  Grid case ``i`` is
    the ``i``-th point of the Cartesian product (last parameter fastest).

Perturbed plant
    I_pert = s · (I_nom ∘ (1 + δ)) element by element (δ = dI11 … dI23 symmetric, s =
    ``inertia_scale``), the same factors at every design point/level of a schedule.  An inertia
    that is not positive definite or violates the triangle inequality is redrawn (``unphysical:
    resample``; the number of draws is recorded) or recorded as verdict ``unphysical``.  The bias
    *torque* (ft·lbf) is external and is held at its nominal value (plus ``bias_*``), so the
    plant's true TEA moves with the inertia; it is re-solved on the physical branch
    (:func:`acmm.tea.solve_tea`).  No equilibrium → verdict ``no_equilibrium`` (not simulated).

Controller
    ``design: fixed`` keeps the nominal gain schedule.  Its TEA estimate θ̂* is the nominal one
    (``tea_estimate: nominal``, the default: the controller does not know the perturbation) or
    the perturbed plant's own TEA (``true``: exact mass properties, report ch. 5.1); a scheduled
    gain is evaluated at that estimate.  ``design: redesign`` re-runs TEA → linearization →
    sector LQR (→ schedule) for the perturbed plant.  The run starts at the plant's true TEA plus
    the initial offset, with the LVLH rate.

Metrics (one row per case)
    verdict, time to divergence, peak and steady (second half of the run) attitude error about
    the plant's true TEA per axis, peak |h_i| per axis, time spent torque- or momentum-saturated.

Execution and results
    Cases run on a ``concurrent.futures`` executor: in-process for one worker, a process pool
    otherwise, or a Dask cluster (``scheduler=ADDRESS``).  Every finished case is appended to
    ``<run dir>/sweep.journal`` (one JSON line, flushed and fsynced) and ``sweep.h5`` is rebuilt
    atomically from the journal every few seconds and at the end, so a killed sweep leaves a
    valid journal (a torn last line is ignored) and a valid, possibly partial ``sweep.h5``
    (root attribute ``complete``).  ``resume=True`` skips the cases already in the journal.
"""
from __future__ import annotations

import concurrent.futures as cf
import dataclasses
import json
import math
import os
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Optional

import numpy as np

from common.outputs import owns_outputs
from common.results import write_text
from common.runlock import locked_stage

from common.errors import AcmmError, ConfigError, ConvergenceError, DesignError, NoEquilibriumError
from acmm.sweep_config import MAP_EXTRAS, PARAMETERS, SHORTHANDS, Sweep, load_sweep, swept_parameters

AXES = ("roll", "pitch", "yaw")

#: Verdict codes stored in ``verdict_code``.
VERDICTS = ("bounded", "not_settled", "diverged", "no_equilibrium", "unphysical", "design_failed",
            "tea_failed")

JOURNAL_VERSION = 1


class SweepInterrupted(AcmmError):
    """A sweep was stopped before all cases finished (the journal keeps what was done)."""


# ---------------------------------------------------------------------------------------------
# physical inertia and case parameters
# ---------------------------------------------------------------------------------------------
def unphysical_reason(inertia: np.ndarray) -> Optional[str]:
    """Why a symmetric 3×3 inertia (slug·ft²) is not a rigid body's, or ``None`` if it is.

    Same test as :class:`acmm.config.Inertia`: positive definite and the principal moments
    satisfy the triangle inequality a + b ≥ c.
    """
    if not np.all(np.isfinite(inertia)):
        return "non-finite inertia"
    eig = np.linalg.eigvalsh(inertia)
    if eig[0] <= 0:
        return f"not positive definite (smallest principal moment {eig[0]:.4g})"
    if eig[0] + eig[1] < eig[2] * (1 - 1e-12):
        return f"triangle inequality violated ({eig[0]:.4g} + {eig[1]:.4g} < {eig[2]:.4g})"
    return None


def perturb_inertia(inertia: np.ndarray, values: dict) -> np.ndarray:
    """I_pert = s·(I ∘ (1 + δ)) with δ from ``dI11 … dI23`` and s = ``inertia_scale``."""
    d = {k: values.get(k, 0.0) for k in ("dI11", "dI22", "dI33", "dI12", "dI13", "dI23")}
    f = np.array([[d["dI11"], d["dI12"], d["dI13"]],
                  [d["dI12"], d["dI22"], d["dI23"]],
                  [d["dI13"], d["dI23"], d["dI33"]]])
    return values.get("inertia_scale", 1.0) * np.asarray(inertia, float) * (1.0 + f)


def _draw(rng: np.random.Generator, spec) -> dict:
    """One draw of every Monte Carlo parameter, in the order the config lists them."""
    out = {}
    for key, dist in spec.monte_carlo.items():
        for name in SHORTHANDS.get(key, [key]):
            p = PARAMETERS[name]
            if dist.uniform is not None:
                out[name] = float(rng.uniform(*dist.uniform))
            elif dist.normal is not None:
                out[name] = float(rng.normal(*dist.normal))
            else:
                h = dist.percent / 100.0
                out[name] = float(rng.uniform(p.neutral - h, p.neutral + h))
    return out


def case_values(spec, index: int, inertias: np.ndarray) -> tuple[dict, int, Optional[str]]:
    """Parameters of case ``index`` (per-base) of a sweep.

    Parameters
    ----------
    spec : SweepSpec
    index : int
        Case index within the base (0 … n_cases − 1).
    inertias : (P, 3, 3) array
        The base's inertia at every design point/level (slug·ft²); the perturbed inertia must
        be physical at all of them.

    Returns
    -------
    values : dict
        Parameter name → value (swept parameters only).
    n_draws : int
        Monte Carlo draws used (1 unless an unphysical inertia was resampled).
    unphysical : str or None
        Why the final draw is unphysical (``None`` when it is physical).
    """
    if spec.grid is not None:
        names = list(spec.grid)
        shape = [len(spec.grid[k]) for k in names]
        idx = np.unravel_index(index, shape)
        values = {k: float(spec.grid[k][j]) for k, j in zip(names, idx)}
        return values, 1, _why(values, inertias)
    rng = np.random.default_rng(np.random.SeedSequence([spec.seed, index]))
    draws = 0
    while True:
        values = _draw(rng, spec)
        draws += 1
        why = _why(values, inertias)
        if why is None or spec.unphysical == "reject" or draws >= spec.max_draws:
            return values, draws, why


def _why(values: dict, inertias: np.ndarray) -> Optional[str]:
    for k, inertia in enumerate(inertias):
        why = unphysical_reason(perturb_inertia(inertia, values))
        if why is not None:
            return f"inertia {why}" + (f" at design point {k}" if len(inertias) > 1 else "")
    return None


# ---------------------------------------------------------------------------------------------
# one case
# ---------------------------------------------------------------------------------------------
@dataclass
class BaseContext:
    """What a worker needs for every case of one base (picklable)."""

    label: str
    config: object          # acmm.config.Config
    table: object           # acmm.stages.DesignTable (nominal design)
    scenario: object        # acmm.simulate.Scenario of the nominal config (orbits of the sweep)
    spec: object            # SweepSpec
    orbits: float


def prepare_base(base, spec) -> BaseContext:
    """Design the base config once (nominal design) and build its nominal scenario."""
    from acmm.simulate import scenario_from_config
    from acmm.stages import compute_design

    cfg = base.config
    orbits = spec.orbits if spec.orbits is not None else cfg.simulation.orbits
    table = compute_design(cfg).table
    sc = scenario_from_config(cfg, table, orbits=orbits)
    return BaseContext(base.label, cfg, table, sc, spec, float(orbits))


def _redesigned_config(cfg, values: dict, biases: np.ndarray):
    """The base config with the perturbed inertia and explicit (held) bias torques."""
    from acmm.config import parse_config

    d = cfg.model_dump(mode="json")

    def inertia_dict(m):
        m = perturb_inertia(m, values)
        return {"I11": m[0, 0], "I22": m[1, 1], "I33": m[2, 2], "I12": m[0, 1], "I13": m[0, 2], "I23": m[1, 2]}

    def dist(dd, bias):
        return {"bias": [float(b) for b in bias], "A": dd["A"], "B": dd["B"]}

    d["inertia"] = inertia_dict(cfg.inertia.matrix())
    d["disturbance"] = dist(d["disturbance"], biases[0])
    if cfg.schedule is not None:
        from acmm.tea import resolve_bias

        added = biases[0] - resolve_bias(cfg.disturbance, cfg.inertia.matrix(), cfg.orbit_rate)
        entries = ([(d["schedule"]["to"], cfg.schedule.to)] if cfg.schedule.to is not None else []) + \
            list(zip(d["schedule"]["points"], cfg.schedule.points))
        for dd, point in entries:
            m = point.inertia.matrix()
            dd["inertia"] = inertia_dict(m)
            dd["disturbance"] = dist(dd["disturbance"], resolve_bias(point.disturbance, m, cfg.orbit_rate) + added)
    return parse_config(d, source="perturbed config")


def _empty_row(n_levels: int) -> dict:
    nan3 = [math.nan] * 3
    return {"verdict": "", "reason": "", "time_to_divergence": math.nan,
            "peak_attitude_error": nan3, "steady_attitude_error": nan3, "peak_momentum": nan3,
            "torque_saturation_time": math.nan, "momentum_saturation_time": math.nan,
            "tea_true": nan3, "tea_estimate": nan3, "inertia": [[math.nan] * 3] * 3, "bias": nan3,
            "n_steps": 0}


def simulate_values(ctx: BaseContext, values: dict) -> dict:
    """Simulate the base with the given parameter values; returns the metrics row (no case info)."""
    from acmm import dynamics as dyn
    from acmm import simulate as sm
    sc0, table, cfg, spec = ctx.scenario, ctx.table, ctx.config, ctx.spec
    L = sc0.inertia.shape[0]
    row = _empty_row(L)
    inertia = np.array([perturb_inertia(m, values) for m in sc0.inertia])
    bias = sc0.bias + np.array([values.get(f"bias_{a}", 0.0) for a in AXES])
    row["inertia"] = inertia[0].tolist()
    row["bias"] = bias[0].tolist()
    why = _why(values, sc0.inertia)
    if why is not None:
        row.update(verdict="unphysical", reason=why)
        return row
    n = sc0.n
    hs = values.get("harmonic_scale", 1.0)
    offset = np.radians(np.asarray(cfg.simulation.initial_offset)
                        + np.array([values.get(f"offset_{a}", 0.0) for a in AXES]))
    try:
        if spec.design == "redesign":
            from acmm.stages import compute_design

            pcfg = _redesigned_config(cfg, values, bias)
            ptable = compute_design(pcfg).table
            sc = sm.scenario_from_config(pcfg, ptable, orbits=ctx.orbits)
            true = sc.theta_est.copy()
            # the redesign's bias per point is the held nominal bias (+ offsets); the schedule's
            # levels are the perturbed design points
            sc = dataclasses.replace(sc, harmonic_a=sc0.harmonic_a * hs, harmonic_b=sc0.harmonic_b * hs)
        else:
            true = perturbed_tea(sc0, inertia, bias)
            if spec.tea_estimate == "true":
                est = true
                gain = np.array([table.gain_at(true[k, 1], k) for k in range(L)])
            else:
                est, gain = sc0.theta_est, sc0.gain
            sc = dataclasses.replace(sc0, inertia=inertia, bias=bias, theta_est=est, gain=gain,
                                     harmonic_a=sc0.harmonic_a * hs, harmonic_b=sc0.harmonic_b * hs)
    except NoEquilibriumError as exc:
        row.update(verdict="no_equilibrium", reason=str(exc).split(":")[0])
        return row
    except DesignError as exc:
        row.update(verdict="design_failed", reason=str(exc)[:200])
        return row
    except ConvergenceError as exc:
        row.update(verdict="tea_failed", reason=str(exc)[:200])
        return row
    theta0 = true[0] + offset
    x0 = np.concatenate([dyn.lvlh_rate_in_body(theta0, n), theta0, np.zeros(18)])
    sc = dataclasses.replace(sc, x0=x0)
    r = sm.simulate(sc)
    err = np.degrees(np.abs(r.state[:, 3:6] - true[r.level]))
    half = r.t >= 0.5 * sc.t_end
    if not half.any():
        half = np.zeros_like(half)
        half[-1] = True
    dt = np.diff(r.t)
    orbit = 2 * np.pi / n
    reason = r.reason
    gap = np.abs(true - sc.theta_est).max()
    if r.stop_code == sm.STOP_ANGLE and gap >= sc.divergence:
        reason += f" (the plant's TEA is {np.degrees(gap):.1f} deg from the controller's estimate)"
    steady = err[half].max(axis=0)
    verdict = r.verdict
    if verdict == "bounded" and steady.max() > spec.settle_deg:
        # within the divergence bound of the controller's estimate, but not at the plant's TEA
        verdict = "not_settled"
        reason = (f"bounded, but the steady attitude error from the plant's TEA is {steady.max():.1f} deg "
                  f"(> settle_deg {spec.settle_deg:g})")
    row.update(
        verdict=verdict, reason=reason,
        time_to_divergence=r.stop_time / orbit if r.diverged else math.nan,
        peak_attitude_error=err.max(axis=0).tolist(),
        steady_attitude_error=steady.tolist(),
        peak_momentum=np.abs(r.state[:, 6:9]).max(axis=0).tolist(),
        torque_saturation_time=float(dt @ r.torque_saturated[:-1].any(axis=1)) / orbit,
        momentum_saturation_time=float(dt @ r.momentum_saturated[:-1].any(axis=1)) / orbit,
        tea_true=np.degrees(true[0]).tolist(), tea_estimate=np.degrees(sc.theta_est[0]).tolist(),
        n_steps=int(r.n_steps))
    return row


def perturbed_tea(sc0, inertia: np.ndarray, bias: np.ndarray) -> np.ndarray:
    """The perturbed plant's TEA per level (rad) on the physical branch of :mod:`acmm.tea`.

    The continuation of :func:`acmm.tea.solve_tea`, compiled (:mod:`acmm.tea_compiled`: same
    root, ~100× cheaper; any fold falls back to :func:`acmm.tea.solve_tea` and its errors).  A
    case's TEA depends only on its plant, never on the cases run before, so its row is the same
    whatever executor, chunking or order runs it.
    """
    from acmm.tea_compiled import solve_tea_fast

    return np.array([solve_tea_fast(inertia[k], sc0.n, bias[k]).theta for k in range(inertia.shape[0])])


def run_case(ctx: BaseContext, index: int) -> dict:
    """Case ``index`` of a base: draw (or look up) its parameters, simulate, return its row."""
    values, draws, _ = case_values(ctx.spec, index, ctx.scenario.inertia)
    row = simulate_values(ctx, values)
    row.update(kind="case", base=ctx.label, index=int(index), values=values, n_draws=int(draws))
    return row


# ---------------------------------------------------------------------------------------------
# margin search on a uniform inertia scaling
# ---------------------------------------------------------------------------------------------
def margin_search(ctx: BaseContext, direction: str) -> dict:
    """Largest (``up``) or smallest (``down``) uniform inertia scaling s the design tolerates.

    Geometric scan from s = 1 towards ``margin.high`` (``low``) in ``scan_points`` steps, then
    bisection in log s between the last bounded and the first failing point until their ratio is
    below 1 + ``rel_tol``.  Assumes the bounded set is an interval around 1 between scanned
    points (a failure hidden between two bounded scan points would be missed).
    """
    m = ctx.spec.margin
    end = m.high if direction == "up" else m.low
    evaluated: list[tuple[float, str, str]] = []

    def ok(s: float) -> bool:
        row = simulate_values(ctx, {"inertia_scale": s})
        evaluated.append((s, row["verdict"], row["reason"]))
        return row["verdict"] == "bounded"

    nominal = ok(1.0)
    good, bad = 1.0, None
    if nominal:
        for k in range(1, m.scan_points + 1):
            s = end ** (k / m.scan_points)
            if ok(s):
                good = s
            else:
                bad = s
                break
        if bad is not None:
            while max(good, bad) / min(good, bad) > 1 + m.rel_tol:
                mid = math.sqrt(good * bad)
                if ok(mid):
                    good = mid
                else:
                    bad = mid
    fail = next((e for e in evaluated if e[0] == bad), None)
    return {"kind": "margin", "base": ctx.label, "direction": direction,
            "limit": good if nominal else math.nan, "first_failure": math.nan if bad is None else bad,
            "failure_verdict": fail[1] if fail else "", "failure_reason": fail[2] if fail else "",
            "reached_end": bool(nominal and bad is None), "search_end": end,
            "evaluated_s": [e[0] for e in evaluated], "evaluated_verdict": [e[1] for e in evaluated]}


# ---------------------------------------------------------------------------------------------
# executors
# ---------------------------------------------------------------------------------------------
class SerialExecutor(cf.Executor):
    """Runs each task in the calling process when it is submitted (one worker)."""

    def submit(self, fn, /, *args, **kwargs):
        fut: cf.Future = cf.Future()
        try:
            fut.set_result(fn(*args, **kwargs))
        except BaseException as exc:  # noqa: BLE001 (re-raised by Future.result())
            if isinstance(exc, KeyboardInterrupt):
                raise
            fut.set_exception(exc)
        return fut


def make_executor(workers: int = 1, scheduler: Optional[str] = None):
    """(executor, close) for ``workers`` local processes or a Dask scheduler address.

    Raises
    ------
    ConfigError
        ``scheduler`` given but ``distributed`` is not installed, or it cannot be reached.
    """
    if scheduler:
        try:
            import distributed
        except ImportError:
            raise ConfigError("--scheduler needs the optional Dask dependency: pip install 'acmm-qpp[dask]'") from None
        try:
            from common.limits import limit

            client = distributed.Client(scheduler, timeout=f"{limit('DASK_CONNECT_SECONDS'):g}s")
        except (OSError, TimeoutError, ValueError) as exc:
            raise ConfigError(f"cannot connect to the Dask scheduler at {scheduler}: {exc}") from None
        return client.get_executor(pure=False), client.close
    if workers <= 1:
        return SerialExecutor(), lambda: None
    import multiprocessing

    ctx = multiprocessing.get_context("fork") if sys.platform.startswith("linux") else None
    from common.workers import die_with_parent

    pool = cf.ProcessPoolExecutor(max_workers=workers, mp_context=ctx, initializer=die_with_parent,
                                  initargs=(os.getpid(),))
    return pool, lambda: pool.shutdown(wait=True, cancel_futures=True)


# ---------------------------------------------------------------------------------------------
# journal (append-only, one JSON line per finished task)
# ---------------------------------------------------------------------------------------------
def read_journal(path: Path, key: str) -> list[dict]:
    """Records of a journal written for results key ``key`` (a torn last line is ignored).

    Raises
    ------
    ConfigError
        The journal belongs to a different sweep configuration.
    """
    records = []
    with open(path, "rb") as f:
        lines = f.read().split(b"\n")
    for k, line in enumerate(lines):
        if not line.strip():
            continue
        try:
            rec = json.loads(line)
        except ValueError:
            if k == len(lines) - 1:       # torn final line of a killed writer
                continue
            raise ConfigError(f"{path}: corrupt journal line {k + 1}; delete it or run without --resume") from None
        if k == 0:
            if rec.get("kind") != "header" or rec.get("version") != JOURNAL_VERSION:
                raise ConfigError(f"{path}: not a sweep journal; delete it or run without --resume")
            if rec.get("key") != key:
                raise ConfigError(f"{path}: the journal was written by a different sweep configuration; "
                                  "run without --resume to start over")
            continue
        records.append(rec)
    return records


class Journal:
    """Append-only JSON-lines file; each record is flushed and fsynced before returning."""

    def __init__(self, path: Path, key: str, fresh: bool):
        try:
            self._open(path, key, fresh)
        except OSError as exc:
            from common.results import output_error

            raise output_error(exc, "the sweep journal", path) from None

    def _open(self, path: Path, key: str, fresh: bool) -> None:
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        if fresh or not self.path.exists():
            tmp = self.path.with_name(f".{self.path.name}.tmp")
            try:
                with open(tmp, "w") as f:
                    f.write(json.dumps({"kind": "header", "version": JOURNAL_VERSION, "key": key}) + "\n")
                    f.flush()
                    os.fsync(f.fileno())
                os.replace(tmp, self.path)       # only under the run lock: no sweep is using it
            except BaseException:
                try:
                    os.unlink(tmp)
                except OSError:
                    pass
                raise
        else:
            # drop a torn final line before appending
            data = self.path.read_bytes()
            if data and not data.endswith(b"\n"):
                with open(self.path, "r+b") as f:
                    f.truncate(data.rfind(b"\n") + 1)
        self._f = open(self.path, "a")

    def append(self, record: dict) -> None:
        try:
            self._f.write(json.dumps(record) + "\n")
            self._f.flush()
            os.fsync(self._f.fileno())
        except OSError as exc:
            from common.results import output_error

            raise output_error(exc, "the sweep journal", self.path) from None

    def close(self) -> None:
        try:
            self._f.close()
        except OSError:          # every record was already flushed and fsynced
            pass


class GroupCommitJournal(Journal):
    """A :class:`Journal` that flushes every record at once but fsyncs at most every
    ``sync_interval`` seconds (and on close): group commit (issue 16).

    A flushed line is in the operating system's cache, so a killed sweep (SIGKILL, Ctrl-C) keeps
    every record, as before; only a machine crash can lose the records of the last
    ``sync_interval``, which ``--resume`` recomputes (a torn line is ignored).  An fsync costs
    ~1–6 ms here, as much as a 10-orbit case, so one per record would dominate a sweep.
    """

    sync_interval = 0.5

    def __init__(self, path: Path, key: str, fresh: bool):
        super().__init__(path, key, fresh)
        self._last_sync = time.monotonic()

    def append(self, record: dict) -> None:
        self.append_many([record])

    def append_many(self, records: list) -> None:
        """Append records (one write, one flush; an fsync when the last is older than the interval)."""
        if not records:
            return
        self._f.write("".join(json.dumps(r) + "\n" for r in records))
        self._f.flush()
        if time.monotonic() - self._last_sync >= self.sync_interval:
            os.fsync(self._f.fileno())
            self._last_sync = time.monotonic()

    def close(self) -> None:
        if not self._f.closed:
            self._f.flush()
            os.fsync(self._f.fileno())
        super().close()


# ---------------------------------------------------------------------------------------------
# the sweep driver
# ---------------------------------------------------------------------------------------------
@dataclass
class SweepResult:
    """What :func:`run_sweep` did."""

    sweep: Sweep
    path: Path
    rows: list
    margins: list
    n_new: int
    n_resumed: int
    wall_time: float
    complete: bool
    figures: list = field(default_factory=list)

    def summary(self) -> dict:
        """Per base: counts of cases by verdict."""
        out = {}
        for b in self.sweep.bases:
            rows = [r for r in self.rows if r["base"] == b.label]
            out[b.label] = {v: sum(r["verdict"] == v for r in rows) for v in VERDICTS}
            out[b.label]["total"] = len(rows)
        return out


def _tasks(sweep: Sweep):
    n = sweep.spec.n_cases()
    for b in sweep.bases:
        for i in range(n):
            yield ("case", b.label, i)
    if sweep.spec.margin is not None:
        for b in sweep.bases:
            for d in ("up", "down"):
                yield ("margin", b.label, d)


def _task_key(rec_or_task) -> tuple:
    if isinstance(rec_or_task, dict):
        r = rec_or_task
        return ("case", r["base"], r["index"]) if r["kind"] == "case" else ("margin", r["base"], r["direction"])
    return tuple(rec_or_task)


def _call(task, ctx):
    kind, _, arg = task
    return run_case(ctx, arg) if kind == "case" else margin_search(ctx, arg)


#: most cases in one task: a chunk of ~64 10-orbit cases is ~0.3 s of work, so progress, the
#: journal and load balancing stay live while the per-task cost (pickling the base context,
#: scheduling, a round trip: ~1–5 ms on Dask) is amortized over many cases
MAX_CHUNK = 64
#: chunks per worker aimed at, so that the last chunks do not leave workers idle
CHUNKS_PER_WORKER = 8

_WARM = False


def chunk_size(n_tasks: int, workers: int) -> int:
    """Cases per task for ``n_tasks`` cases on ``workers`` workers (a pool or a Dask cluster;
    the in-process executor runs one case per task).

    ⌈n / (8·workers)⌉ clipped to [1, :data:`MAX_CHUNK`]: about 8 tasks per worker (the tail
    imbalance is then ≤ 1/8 of a worker's share) and never more than ~0.3 s per task.  The cost of
    one task on a scheduler is a fixed few ms, so once a chunk holds more than a few cases that
    cost is a small fraction whatever the number of workers; see README *Performance*.
    """
    return max(1, min(MAX_CHUNK, -(-n_tasks // (CHUNKS_PER_WORKER * max(1, workers)))))


def make_chunks(tasks: list, size: int) -> list[list]:
    """Consecutive case tasks of one base in lists of ``size``; each margin search alone."""
    chunks: list[list] = []
    for t in tasks:
        if (t[0] == "case" and chunks and len(chunks[-1]) < size and chunks[-1][0][0] == "case"
                and chunks[-1][0][1] == t[1]):
            chunks[-1].append(t)
        else:
            chunks.append([t])
    return chunks


def _warm_worker() -> None:
    """Load the compiled kernels once per worker process (from numba's cache: no compile); a
    long-lived Dask cluster can be warmed ahead with ``client.run(acmm.sweep._warm_worker)``."""
    global _WARM
    if not _WARM:
        from acmm.warmup import warm_up

        warm_up()
        _WARM = True


_LOCAL: dict = {}


def _local_context(ctx: BaseContext) -> BaseContext:
    """``ctx`` with writable arrays, made once per worker and context.

    Dask hands a task its (scattered) context deserialized from shared buffers, i.e. with
    read-only arrays; numba types read-only arrays differently, so the simulator would be
    compiled afresh on every Dask worker (~10 s) instead of loaded from the cache.
    """
    hit = _LOCAL.get(id(ctx))
    if hit is not None and hit[0] is ctx:
        return hit[1]
    sc = ctx.scenario
    fix = {f.name: np.array(getattr(sc, f.name)) for f in dataclasses.fields(sc)
           if isinstance(getattr(sc, f.name), np.ndarray) and not getattr(sc, f.name).flags.writeable}
    local = dataclasses.replace(ctx, scenario=dataclasses.replace(sc, **fix)) if fix else ctx
    if len(_LOCAL) > 16:
        _LOCAL.clear()
    _LOCAL[id(ctx)] = (ctx, local)
    return local


def _call_chunk(chunk, ctx) -> list[dict]:
    """Run the tasks of one chunk in order; returns their records."""
    _warm_worker()
    ctx = _local_context(ctx)
    return [_call(t, ctx) for t in chunk]


def _scheduler_workers(executor, default: int) -> int:
    """Number of workers (threads) of the Dask cluster behind ``executor``, else ``default``."""
    client = getattr(executor, "_client", None)
    if client is None:
        return max(1, default)
    try:
        return max(1, sum(int(v) for v in client.nthreads().values()))
    except (AttributeError, KeyError, OSError, TypeError, ValueError):
        return max(1, default)


def _remote_contexts(executor, contexts: dict) -> dict:
    """The base contexts as the executor's tasks take them: on a Dask cluster scattered once to
    every worker (a task then carries a reference, not a pickled design); else as they are."""
    client = getattr(executor, "_client", None)
    if client is None or not contexts:
        return contexts
    try:
        return {k: client.scatter(v, broadcast=True, hash=False) for k, v in contexts.items()}
    except (AttributeError, TypeError, ValueError):
        return contexts


def _as_sweep(sweep) -> Sweep:
    return sweep if isinstance(sweep, Sweep) else load_sweep(sweep)


@locked_stage(_as_sweep)
@owns_outputs("sweep", lambda s: _as_sweep(s))
def run_sweep(sweep: Sweep | str | Path, *, workers: Optional[int] = None, scheduler: Optional[str] = None,
              resume: bool = False, progress: Optional[Callable[[int, int, dict], None]] = None,
              after_record: Optional[Callable[[int], None]] = None, figures: Optional[bool] = None,
              snapshot_interval: float = 5.0, executor=None, chunk: Optional[int] = None) -> SweepResult:
    """Run (or resume) a sweep; writes ``sweep.journal``, ``sweep.h5``, ``sweep.csv`` and figures.

    Parameters
    ----------
    sweep : Sweep or path
    workers : int, optional
        Local workers (1: in-process); default ``sweep.workers`` or the CPU count.
    scheduler : str, optional
        Dask scheduler address; the cases then run on that cluster.
    resume : bool
        Keep the journal's finished cases and run only the others.
    progress : callable(done, total, record), optional
        Called after each finished task.
    after_record : callable(n_new), optional
        Called after each record is committed (tests use it to interrupt a sweep).
    executor : concurrent.futures.Executor, optional
        Use this executor instead of making one (it is not shut down).
    chunk : int, optional
        Cases per task (default :func:`chunk_size`: ~8 tasks per worker, ≤ :data:`MAX_CHUNK`;
        1 in-process).  The results do not depend on it.
    """
    if not isinstance(sweep, Sweep):
        sweep = load_sweep(sweep)
    spec = sweep.spec
    t0 = time.perf_counter()
    key = sweep.results_key()
    run_dir = sweep.run_dir()
    jpath = run_dir / "sweep.journal"
    done: dict[tuple, dict] = {}
    if resume and jpath.exists():
        for rec in read_journal(jpath, key):
            done[_task_key(rec)] = rec
    n_resumed = len(done)
    tasks = [t for t in _tasks(sweep) if t not in done]
    total = n_resumed + len(tasks)
    contexts = {b.label: prepare_base(b, spec) for b in sweep.bases} if tasks else {}
    for ctx in contexts.values():          # warm up (and load the compiled simulator) before forking
        simulate_values(ctx, {})
    if workers is None:
        workers = spec.workers or os.cpu_count() or 1
    close = lambda: None  # noqa: E731
    if executor is None and tasks:        # before the journal: an unreachable scheduler writes nothing
        executor, close = make_executor(workers if not scheduler else 0, scheduler)
    try:
        journal = GroupCommitJournal(jpath, key, fresh=not resume)
    except BaseException:
        close()
        raise
    serial = isinstance(executor, SerialExecutor)
    n_workers = 1 if serial else _scheduler_workers(executor, workers)
    size = chunk if chunk is not None else (1 if serial else chunk_size(len(tasks), n_workers))
    chunks = make_chunks(tasks, size)
    window = 1 if serial else max(4, 2 * n_workers)
    remote = _remote_contexts(executor, contexts)
    n_new = 0
    last_snap = time.monotonic()
    complete = False
    pending: dict = {}
    try:
        it = iter(chunks)
        exhausted = False
        while True:
            while not exhausted and len(pending) < window:
                c = next(it, None)
                if c is None:
                    exhausted = True
                    break
                pending[executor.submit(_call_chunk, c, remote[c[0][1]])] = c
            if not pending:
                break
            finished, _ = cf.wait(list(pending), return_when=cf.FIRST_COMPLETED)
            for fut in finished:
                pending.pop(fut)
                recs = fut.result()
                journal.append_many(recs)
                for rec in recs:
                    done[_task_key(rec)] = rec
                    n_new += 1
                    if progress is not None:
                        progress(len(done), total, rec)
                    if after_record is not None:
                        after_record(n_new)
            if time.monotonic() - last_snap > snapshot_interval:
                write_results(sweep, list(done.values()), complete=False)
                last_snap = time.monotonic()
        complete = True
    finally:
        journal.close()
        if not complete:
            try:
                for fut in list(pending):
                    fut.cancel()
            finally:
                close()
                if done:
                    write_results(sweep, list(done.values()), complete=False)
    close()
    path, figs = write_results(sweep, list(done.values()), complete=True,
                               figures=sweep.file.output.figures if figures is None else figures,
                               wall_time=time.perf_counter() - t0)
    rows, margins = _split(sweep, list(done.values()))
    return SweepResult(sweep, path, rows, margins, n_new, n_resumed, time.perf_counter() - t0, True, figs)


# ---------------------------------------------------------------------------------------------
# results: sweep.h5, sweep.csv, figures
# ---------------------------------------------------------------------------------------------
def _split(sweep: Sweep, records: list[dict]):
    order = {b.label: k for k, b in enumerate(sweep.bases)}
    rows = sorted((r for r in records if r["kind"] == "case"), key=lambda r: (order[r["base"]], r["index"]))
    margins = sorted((r for r in records if r["kind"] == "margin"),
                     key=lambda r: (order[r["base"]], r["direction"] != "up"))
    return rows, margins


def table_arrays(sweep: Sweep, rows: list[dict]) -> dict:
    """Column arrays of the case rows (sorted by base then index)."""
    names = swept_parameters(sweep.spec)
    labels = [b.label for b in sweep.bases]
    N = len(rows)

    def col(k, shape=()):
        return np.array([r[k] for r in rows], float).reshape((N,) + shape)

    out = {
        "base": np.array([labels.index(r["base"]) for r in rows], np.int64),
        "index": np.array([r["index"] for r in rows], np.int64),
        "case": np.array([labels.index(r["base"]) * sweep.spec.n_cases() + r["index"] for r in rows], np.int64),
        "parameters": {k: np.array([r["values"].get(k, PARAMETERS[k].neutral) for r in rows], float)
                       for k in names},
        "verdict": [r["verdict"] for r in rows],
        "verdict_code": np.array([VERDICTS.index(r["verdict"]) for r in rows], np.int64),
        "reason": [r["reason"] for r in rows],
        "stable": np.array([r["verdict"] == "bounded" for r in rows], bool),
        "time_to_divergence": col("time_to_divergence"),
        "peak_attitude_error": col("peak_attitude_error", (3,)),
        "steady_attitude_error": col("steady_attitude_error", (3,)),
        "peak_momentum": col("peak_momentum", (3,)),
        "torque_saturation_time": col("torque_saturation_time"),
        "momentum_saturation_time": col("momentum_saturation_time"),
        "tea_true": col("tea_true", (3,)),
        "tea_estimate": col("tea_estimate", (3,)),
        "inertia": col("inertia", (3, 3)),
        "bias": col("bias", (3,)),
        "n_draws": np.array([r["n_draws"] for r in rows], np.int64),
    }
    return out


def _nominal_tea_deg(sweep: Sweep) -> dict:
    from acmm.schedule import point_specs
    from acmm.tea import solve_tea

    out = {}
    for b in sweep.bases:
        s = point_specs(b.config)[0]
        try:
            out[b.label] = np.degrees(solve_tea(s.inertia, b.config.orbit_rate, s.bias).theta)
        except AcmmError:
            out[b.label] = np.full(3, np.nan)
    return out


def write_results(sweep: Sweep, records: list[dict], complete: bool, figures: bool = False,
                  wall_time: float | None = None) -> tuple[Path, list]:
    """Build ``sweep.h5`` (atomically, via :func:`acmm.results.write_h5`) and ``sweep.csv`` from
    the records; with ``figures`` also the stability map and the peak-error distributions."""
    from common.results import Dataset, write_h5

    rows, margins = _split(sweep, records)
    a = table_arrays(sweep, rows)
    spec = sweep.spec
    labels = [b.label for b in sweep.bases]
    S = lambda xs: np.array([x.encode() for x in xs], dtype="S") if len(xs) else np.zeros(0, "S1")  # noqa: E731
    items = {
        "case": Dataset(a["case"], "1", "global case index = base_index·n_cases + index"),
        "base": Dataset(a["base"], "1", "index into base_names"),
        "base_names": Dataset(S(labels), "1", "base config names", dims=("base_name",)),
        "index": Dataset(a["index"], "1", "case index within its base (seeds SeedSequence([seed, index]))"),
        "parameters": {k: Dataset(v, PARAMETERS[k].unit, PARAMETERS[k].description)
                       for k, v in a["parameters"].items()},
        "verdict": Dataset(S(a["verdict"]), "1", "bounded | not_settled | diverged | no_equilibrium | unphysical | "
                                                 "design_failed | tea_failed"),
        "verdict_code": Dataset(a["verdict_code"], "1", "index into the root attribute 'verdicts'"),
        "reason": Dataset(S(a["reason"]), "1", "why the run stopped or was not run"),
        "stable": Dataset(a["stable"], "1", "verdict == bounded"),
        "time_to_divergence": Dataset(a["time_to_divergence"], "orbit", "stop time of a diverged run (NaN if not)"),
        "peak_attitude_error": Dataset(a["peak_attitude_error"], "deg",
                                       "max |θ − θ*_true| over the run (θ*_true: the plant's TEA)", list(AXES)),
        "steady_attitude_error": Dataset(a["steady_attitude_error"], "deg",
                                         "max |θ − θ*_true| over the second half of the run", list(AXES)),
        "peak_momentum": Dataset(a["peak_momentum"], "ft*lbf*s", "max |h_i| over the run", list(AXES)),
        "torque_saturation_time": Dataset(a["torque_saturation_time"], "orbit",
                                          "time with any axis torque-limited (sample resolution)"),
        "momentum_saturation_time": Dataset(a["momentum_saturation_time"], "orbit",
                                            "time with any CMG axis at its momentum limit (sample resolution)"),
        "tea_true": Dataset(a["tea_true"], "deg", "TEA of the perturbed plant (first level)", list(AXES)),
        "tea_estimate": Dataset(a["tea_estimate"], "deg", "TEA estimate used by the controller (first level)",
                                list(AXES)),
        "inertia": Dataset(a["inertia"], "slug*ft^2", "perturbed inertia (first level)"),
        "bias": Dataset(a["bias"], "ft*lbf", "bias torque (first level)", list(AXES)),
        "n_draws": Dataset(a["n_draws"], "1", "Monte Carlo draws used (resampling of unphysical inertia)"),
    }
    if margins:
        items["margin"] = {
            m["base"] + "_" + m["direction"]: {
                "limit": Dataset(m["limit"], "1", "tolerated uniform inertia scaling (bounded up to here)"),
                "first_failure": Dataset(m["first_failure"], "1", "first failing scaling (NaN: none up to search_end)"),
                "search_end": Dataset(m["search_end"], "1", "end of the searched range"),
                "evaluated_s": Dataset(np.array(m["evaluated_s"]), "1", "scalings evaluated, in order",
                                       dims=("evaluation",)),
                "evaluated_verdict": Dataset(S(m["evaluated_verdict"]), "1", "verdict at each", dims=("evaluation",)),
                "failure_reason": Dataset(m["failure_reason"] or "-", "1", "why the first failure failed"),
            } for m in margins}
    summary = {}
    for k, lab in enumerate(labels):
        sel = a["base"] == k
        summary[lab] = {v: int(np.sum(sel & (a["verdict_code"] == j))) for j, v in enumerate(VERDICTS)}
    attrs = {"stage": "sweep", "sweep_name": sweep.name, "complete": bool(complete),
             "n_cases_expected": spec.n_cases() * len(labels), "n_cases_done": len(rows),
             "design": spec.design, "tea_estimate": spec.tea_estimate, "seed": spec.seed,
             "method": "grid" if spec.grid is not None else "monte_carlo",
             "verdicts": json.dumps(list(VERDICTS)), "summary": json.dumps(summary),
             "results_key": sweep.results_key()}
    if wall_time is not None:
        attrs["wall_time_s"] = float(wall_time)
    run_dir = sweep.run_dir()
    from common.netcdf_layout import with_leading_dim

    items = with_leading_dim(items, "case", len(a["case"]))   # one row per case (netCDF dimension)
    path = write_h5(run_dir / "sweep.h5", items, sweep.to_yaml(), attrs, units=sweep.file.output.units)
    _write_csv(run_dir / "sweep.csv", labels, a, sweep.file.output.units)
    figs = []
    if figures and rows:
        figs = plot_sweep(sweep, a, run_dir)
    return path, figs


def _write_csv(path: Path, labels, a, units: str = "imperial") -> None:
    from common.units import display_unit, shown

    cols = ["case", "base", "index"] + [f"{k}[{display_unit(PARAMETERS[k].unit, units)}]" for k in a["parameters"]] + [
        "verdict", "time_to_divergence[orbit]"]
    for what, unit in (("peak_attitude_error", "deg"), ("steady_attitude_error", "deg"),
                       ("peak_momentum", display_unit("ft*lbf*s", units)), ("tea_true", "deg")):
        cols += [f"{what}_{ax}[{unit}]" for ax in AXES]
    a = dict(a)
    a["parameters"] = {k: shown(np.asarray(v, float), PARAMETERS[k].unit, units)[0] for k, v in a["parameters"].items()}
    a["peak_momentum"] = shown(np.asarray(a["peak_momentum"], float), "ft*lbf*s", units)[0]
    cols += ["torque_saturation_time[orbit]", "momentum_saturation_time[orbit]", "n_draws", "reason"]
    lines = [",".join(cols)]
    for i in range(len(a["case"])):
        vals = [str(a["case"][i]), labels[a["base"][i]], str(a["index"][i])]
        vals += [repr(float(v[i])) for v in a["parameters"].values()]
        vals += [a["verdict"][i], repr(float(a["time_to_divergence"][i]))]
        for what in ("peak_attitude_error", "steady_attitude_error", "peak_momentum", "tea_true"):
            vals += [repr(float(x)) for x in a[what][i]]
        vals += [repr(float(a["torque_saturation_time"][i])), repr(float(a["momentum_saturation_time"][i])),
                 str(a["n_draws"][i]), '"' + a["reason"][i].replace('"', "'") + '"']
        lines.append(",".join(vals))
    write_text(path, "\n".join(lines) + "\n")


def plot_sweep(sweep: Sweep, a: dict, run_dir: Path) -> list[Path]:
    """Stability map over two swept quantities and distributions of the peak attitude error."""
    from acmm.plots import _save
    from common.plot_style import stage_pyplot as _plt

    plt = _plt()
    labels = [b.label for b in sweep.bases]
    names = list(a["parameters"])
    axes_names = list(sweep.spec.map) if sweep.spec.map else (names[:2] if len(names) >= 2 else names[:1])
    nominal = _nominal_tea_deg(sweep)

    from common.units import shown

    system = sweep.file.output.units

    def values(name, sel, lab):
        if name in a["parameters"]:
            return shown(np.asarray(a["parameters"][name][sel], float), PARAMETERS[name].unit, system)[0]
        ax = MAP_EXTRAS.index(name)
        return a["tea_true"][sel, ax] - nominal[lab][ax]

    colors = {"bounded": "tab:green", "not_settled": "gold", "diverged": "tab:red", "no_equilibrium": "tab:purple",
              "unphysical": "tab:gray", "design_failed": "tab:orange", "tea_failed": "tab:brown"}
    B = len(labels)
    fig, axs = plt.subplots(1, B, figsize=(4.6 * B, 4.0), squeeze=False)
    for k, lab in enumerate(labels):
        ax = axs[0, k]
        sel = a["base"] == k
        x = values(axes_names[0], sel, lab)
        if len(axes_names) > 1:
            y = values(axes_names[1], sel, lab)
        else:
            y = np.nanmax(a["peak_attitude_error"][sel], axis=1)
        verdicts = np.array(a["verdict"], dtype=object)[sel]
        for v in VERDICTS:
            m = verdicts == v
            if m.any():
                ax.scatter(x[m], y[m], s=14, c=colors[v], label=f"{v} ({int(m.sum())})", alpha=0.8)
        ax.set_xlabel(_label(axes_names[0], system))
        ax.set_ylabel(_label(axes_names[1], system) if len(axes_names) > 1 else "peak attitude error (deg)")
        ax.set_title(f"{lab}: {int(np.sum(verdicts == 'bounded'))}/{int(sel.sum())} bounded")
        ax.legend(fontsize=7)
    fig.suptitle(f"{sweep.name}: stability map ({sweep.spec.design} design)")
    out = _save(fig, run_dir / "sweep_map.png")
    fig, axs = plt.subplots(1, B, figsize=(4.6 * B, 3.6), squeeze=False)
    for k, lab in enumerate(labels):
        ax = axs[0, k]
        sel = (a["base"] == k) & a["stable"]
        err = a["peak_attitude_error"][sel]
        if len(err):
            hi = max(float(np.nanmax(err)), 1e-3)
            bins = np.linspace(0, hi * 1.02, 25)
            for j, axn in enumerate(AXES):
                ax.hist(err[:, j], bins=bins, histtype="step", label=axn)
            ax.legend(fontsize=7)
        ax.set_xlabel("peak attitude error |θ − θ*_true| of bounded cases (deg)")
        ax.set_ylabel("number of cases (count)")
        ax.set_title(f"{lab}: {int(sel.sum())} bounded of {int(np.sum(a['base'] == k))}")
    fig.suptitle(f"{sweep.name}: peak attitude error")
    out += _save(fig, run_dir / "sweep_peak_error.png")
    return out


def _label(name: str, units: str = "imperial") -> str:
    """Axis label: quantity and unit in the output system ``units`` (a relative change is
    dimensionless: 0.1 = +10 %)."""
    if name in PARAMETERS:
        p = PARAMETERS[name]
        if p.kind == "relative":
            return f"{name}: relative change of {name[1:]} (1, 0.1 = +10 %)"
        if p.kind == "scale":
            return f"{name}: {p.description.split(':')[0].split('(')[0].strip()} (1, × nominal)"
        from common.units import display_unit

        unit = display_unit(p.unit, units).replace("*", "·")
        return f"{name}: {p.description.split('(')[0].split(',')[0].strip()} ({unit})"
    return f"{name}: plant's {name.rsplit('_', 1)[-1]} TEA − nominal TEA (deg)"
