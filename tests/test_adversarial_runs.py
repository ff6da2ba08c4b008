"""Killed, concurrent and starved runs (issue 13): kill -9 at random instants, two runs of one
name, a full disk, stale temporary files.  These need real processes, so they use subprocesses
(the `acmm` script of this environment)."""
from __future__ import annotations

import errno
import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest
import yaml

ACMM = str(Path(sys.executable).parent / "acmm")
ENV = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "MPLBACKEND": "Agg"}

HOLD_LOCK = """
import sys, time
from acmm_qpp.outputs import run_lock
with run_lock(sys.argv[1]):
    print("locked", flush=True)
    sys.stdin.read()
"""


def _sweep_config(tmp: Path, name: str = "swk", n_runs: int = 24, orbits: float = 1.0) -> Path:
    p = tmp / f"{name}.yaml"
    p.write_text(yaml.safe_dump({
        "name": name,
        "sweep": {"base": "ac", "monte_carlo": {"inertia": {"percent": 10}, "offset_pitch": {"uniform": [-2, 2]}},
                  "n_runs": n_runs, "seed": 11, "orbits": orbits},
        "output": {"root": "runs", "figures": False}}))
    return p


def _processes_running(marker: str) -> list[int]:
    """pids of live (non-zombie) processes whose command line contains ``marker``."""
    out = []
    for d in Path("/proc").iterdir():
        if not d.name.isdigit():
            continue
        try:
            cmd = (d / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
            state = (d / "stat").read_text().rsplit(")", 1)[1].split()[0]
        except OSError:
            continue
        if marker in cmd and state != "Z":
            out.append(int(d.name))
    return out


def _h5_all_open(directory: Path) -> int:
    n = 0
    for p in directory.rglob("*.h5"):
        with h5py.File(p, "r") as f:
            f.visit(lambda name: None)
        n += 1
    return n


def _sweep_data(path: Path) -> dict:
    out = {}
    with h5py.File(path, "r") as f:
        f.visititems(lambda k, v: out.__setitem__(k, v[()]) if isinstance(v, h5py.Dataset) else None)
        out["complete"] = bool(f.attrs["complete"])
    return out


def _temps(directory: Path) -> list[str]:
    return sorted(p.name for p in directory.rglob("*.tmp"))


def test_kill9_at_random_instants_then_resume_reproduces_uninterrupted(tmp_runs):
    """Workers die with their parent; every .h5 opens after each kill; resume gives the very
    data of an uninterrupted sweep."""
    from acmm.sweep.run import run_sweep

    cfg = _sweep_config(tmp_runs, n_runs=48)
    ref_dir = tmp_runs / "ref"
    ref_dir.mkdir()
    ref_cfg = _sweep_config(ref_dir, n_runs=48)
    os.chdir(ref_dir)
    ref = _sweep_data(run_sweep(ref_cfg, workers=1).path)
    os.chdir(tmp_runs)
    rng = random.Random(185644)
    run_dir = tmp_runs / "runs" / "swk"
    kills = 0
    for attempt in range(3):
        proc = subprocess.Popen([ACMM, "sweep", str(cfg), "-j", "2", "--resume"], env=ENV, cwd=tmp_runs,
                                stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        # a random instant once cases are being recorded (independent of start-up time and speed)
        journal = run_dir / "sweep.journal"
        deadline = time.monotonic() + 60
        while proc.poll() is None and time.monotonic() < deadline and not (
                journal.exists() and len(journal.read_bytes().splitlines()) >= 2 + 4 * attempt):
            time.sleep(0.01)
        time.sleep(rng.uniform(0.0, 0.25))
        if proc.poll() is None:
            proc.send_signal(signal.SIGKILL)
            kills += 1
        proc.wait()
        deadline = time.monotonic() + 5
        while _processes_running(str(cfg)) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert _processes_running(str(cfg)) == [], "orphan workers outlived the killed sweep"
        if run_dir.exists():
            _h5_all_open(run_dir)
    assert kills >= 1
    r = subprocess.run([ACMM, "sweep", str(cfg), "-j", "2", "--resume"], env=ENV, cwd=tmp_runs,
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    got = _sweep_data(run_dir / "sweep.h5")
    assert got["complete"] and set(got) == set(ref)
    for k in ref:
        if k in ("wall_time",):
            continue
        np.testing.assert_array_equal(got[k], ref[k], err_msg=k)
    assert _temps(tmp_runs) == [] and not (run_dir / ".lock").exists()


def test_second_run_of_same_name_refused_naming_the_holder(tmp_runs):
    from typer.testing import CliRunner

    from acmm.cli.app import app

    holder = subprocess.Popen([sys.executable, "-c", HOLD_LOCK, str(tmp_runs / "runs" / "mb3")], env=ENV,
                              stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "locked"
        before = sorted(p.name for p in (tmp_runs / "runs" / "mb3").iterdir())
        r = CliRunner().invoke(app, ["tea", "mb3"])
        assert r.exit_code == 4 and len(r.stderr.splitlines()) == 1, r.stderr
        assert f"pid {holder.pid}" in r.stderr and "in use by another run" in r.stderr
        assert sorted(p.name for p in (tmp_runs / "runs" / "mb3").iterdir()) == before
    finally:
        holder.stdin.close()
        holder.wait(timeout=10)
    r = CliRunner().invoke(app, ["tea", "mb3"])
    assert r.exit_code == 0, r.stderr
    assert sorted(p.name for p in (tmp_runs / "runs" / "mb3").iterdir()) == ["config.yaml", "tea.h5"]  # config.yaml: the resolved config of the run


def test_lock_of_a_killed_holder_does_not_block(tmp_runs):
    from typer.testing import CliRunner

    from acmm.cli.app import app

    holder = subprocess.Popen([sys.executable, "-c", HOLD_LOCK, str(tmp_runs / "runs" / "mb3")], env=ENV,
                              stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    assert holder.stdout.readline().strip() == "locked"
    holder.kill()
    holder.wait()
    assert (tmp_runs / "runs" / "mb3" / ".lock").exists()          # stale file, no holder
    r = CliRunner().invoke(app, ["tea", "mb3"])
    assert r.exit_code == 0, r.stderr
    assert not (tmp_runs / "runs" / "mb3" / ".lock").exists()


HOLD_SWEEP = """
import sys
from acmm.sweep.run import run_sweep
paused = []
def pause(done, total, rec):
    if not paused:                      # hold the run (and its lock) after the first case
        paused.append(1)
        print("running", flush=True)
        sys.stdin.read()
run_sweep(sys.argv[1], workers=1, progress=pause)
print("done", flush=True)
"""


def test_two_concurrent_sweeps_and_resumes_one_refused(tmp_runs):
    """A second fresh sweep or a concurrent --resume is refused (exit 4) instead of replacing the
    journal under the running sweep; the running sweep completes every case exactly once.  The
    first sweep is held after its first case (independent of the machine's speed)."""
    cfg = _sweep_config(tmp_runs, n_runs=16)
    a = subprocess.Popen([sys.executable, "-c", HOLD_SWEEP, str(cfg)], env=ENV, cwd=tmp_runs,
                         stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert a.stdout.readline().strip() == "running", a.stderr.read() if a.poll() is not None else ""
        for extra in ([], ["--resume"]):
            b = subprocess.run([ACMM, "sweep", str(cfg), "-j", "1", *extra], env=ENV, cwd=tmp_runs,
                               capture_output=True, text=True, timeout=60)
            assert a.poll() is None
            assert b.returncode == 4, b.stderr
            assert b.stderr.splitlines() == [b.stderr.strip()] and f"pid {a.pid}" in b.stderr
    finally:
        a.stdin.close()                 # lets the held sweep go on
        a.wait(timeout=120)
    out, err = a.stdout.read(), a.stderr.read()
    assert a.returncode == 0 and out.strip().endswith("done"), err
    lines = (tmp_runs / "runs" / "swk" / "sweep.journal").read_text().splitlines()
    assert len(lines) == 1 + 16                                       # header + each case once
    assert _sweep_data(tmp_runs / "runs" / "swk" / "sweep.h5")["complete"]


@pytest.fixture
def small_tmpfs(tmp_path):
    """A 256 KiB tmpfs; skipped where mounting one is not permitted."""
    d = tmp_path / "small"
    d.mkdir()
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=256k", "tmpfs", str(d)], capture_output=True)
    if r.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here (needs root or CAP_SYS_ADMIN): "
                    f"{r.stderr.decode().strip() or r.returncode}")
    yield d
    subprocess.run(["umount", str(d)], check=False)


def test_full_disk_one_line_exit_4_no_temp_no_crash(tmp_runs, small_tmpfs):
    cfg = tmp_runs / "full.yaml"
    cfg.write_text(yaml.safe_dump({"name": "full", "inertia": {"I11": 1.0e7, "I22": 2.0e7, "I33": 2.5e7},
                                   "simulation": {"orbits": 8},
                                   "output": {"root": str(small_tmpfs / "runs"), "figures": True}}))
    r = subprocess.run([ACMM, "simulate", str(cfg)], env=ENV, capture_output=True, text=True, timeout=120)
    assert r.returncode == 4, (r.returncode, r.stderr)               # not 139 (segfault in HDF5)
    assert len(r.stderr.splitlines()) == 1 and "No space left on device" in r.stderr, r.stderr
    assert _temps(small_tmpfs) == [] and not (small_tmpfs / "runs" / "full" / ".lock").exists()
    _h5_all_open(small_tmpfs)                                         # whatever was written is whole
    # a completely full disk: even the run lock cannot be written
    (small_tmpfs / "filler").write_bytes(b"")
    with open(small_tmpfs / "filler", "ab") as f:
        try:
            while True:
                f.write(b"\0" * 65536)
                f.flush()
        except OSError:
            pass
    sw = _sweep_config(tmp_runs, n_runs=2, orbits=0.5)
    data = yaml.safe_load(sw.read_text())
    data["output"]["root"] = str(small_tmpfs / "runs")
    sw.write_text(yaml.safe_dump(data))
    for args in (["tea", str(cfg)], ["sweep", str(sw), "-j", "1"]):
        r = subprocess.run([ACMM, *args], env=ENV, capture_output=True, text=True, timeout=120)
        assert r.returncode == 4 and len(r.stderr.splitlines()) == 1, (args, r.returncode, r.stderr)
        assert "No space left on device" in r.stderr
        assert _temps(small_tmpfs) == []


def test_stale_temp_files_of_killed_runs_are_removed(tmp_runs):
    from typer.testing import CliRunner

    from acmm.cli.app import app

    d = tmp_runs / "runs" / "mb3"
    d.mkdir(parents=True)
    stale = [".sim_summary.png.k2j3h4.tmp", ".sim.h5.abcdef.tmp", ".sweep.journal.tmp"]
    for name in stale:
        (d / name).write_bytes(b"partial")
    (d / "keep.txt").write_text("user file")
    r = CliRunner().invoke(app, ["tea", "mb3"])
    assert r.exit_code == 0, r.stderr
    assert sorted(p.name for p in d.iterdir()) == ["config.yaml", "keep.txt", "tea.h5"]


def test_a_closed_stdout_is_not_an_output_failure(tmp_path):
    """`acmm tea mb3 | true`: the reader is gone when the command prints its summary; the results
    are written and kept, nothing is printed to stderr, exit 141 (128 + SIGPIPE), not 4."""
    proc = subprocess.Popen([ACMM, "tea", "mb3", f"output.root={tmp_path}"], env=ENV, cwd=tmp_path,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    proc.stdout.close()
    err = proc.stderr.read()
    assert proc.wait(timeout=120) == 141, err
    assert err == b""
    assert (tmp_path / "mb3" / "tea.h5").is_file() and (tmp_path / "mb3" / "config.yaml").is_file()


def test_a_refused_report_leaves_no_empty_output_folder(tmp_path):
    """`acmm report --out new/` whose stages cannot write (the results root is a file): one line,
    exit 4, and the folders it had created for the report are gone again."""
    (tmp_path / "afile").write_text("")
    r = subprocess.run([ACMM, "report", "--fast", "--root", str(tmp_path / "afile"), "--out", str(tmp_path / "out")],
                       env=ENV, cwd=tmp_path, capture_output=True, text=True, timeout=300)
    errors = [ln for ln in r.stderr.splitlines() if ln.startswith("error:")]
    assert r.returncode == 4 and len(errors) == 1 and "Traceback" not in r.stderr, r.stderr
    assert not (tmp_path / "out").exists()


#: `acmm simulate` that stops where its figures are drawn (its results written in its staging
#: folder, the nested design stage finished), says so, and waits there to be killed
_STOP_AT_FIGURES = """
import sys
import acmm.stages.simulate as target

def stop(*args, **kwargs):
    print("at figures", flush=True)
    sys.stdin.readline()
    raise SystemExit("not killed")

target.draw_figures = stop
sys.argv = ["acmm", *sys.argv[1:]]
from acmm.cli.app import main
main()
"""


def _hidden(directory: Path) -> list[str]:
    return sorted(str(p.relative_to(directory)) for p in directory.rglob(".*"))


def test_a_stage_killed_with_sigkill_leaves_nothing_the_next_run_does_not_remove(tmp_runs):
    """kill -9 while `acmm simulate` draws its figures: its staging folder (with sim.h5) and the
    lock file stay behind, the finished design is whole beside its config.yaml; the next run of
    that name removes both, and no sim.h5 of the killed run ever reaches the folder."""
    proc = subprocess.Popen([sys.executable, "-c", _STOP_AT_FIGURES, "simulate", "mb3", "simulation.orbits=0.5"],
                            env=ENV, cwd=tmp_runs, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    try:
        assert proc.stdout.readline().strip() == "at figures", proc.stderr.read()
        run = tmp_runs / "runs" / "mb3"
        staging = [p for p in run.iterdir() if p.name.startswith(".staging-")]
        assert len(staging) == 1 and (staging[0] / "sim.h5").is_file()
    finally:
        proc.kill()
        proc.wait(timeout=30)
    assert sorted(p.name for p in run.iterdir() if not p.name.startswith(".")) == ["config.yaml", "design.h5",
                                                                                  "design_poles.png"]
    assert (run / ".lock").exists()
    _h5_all_open(run)
    r = subprocess.run([ACMM, "tea", "mb3"], env=ENV, cwd=tmp_runs, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert _hidden(tmp_runs / "runs") == []
    assert sorted(p.name for p in run.iterdir()) == ["config.yaml", "design.h5", "design_poles.png", "tea.h5"]


def test_a_report_killed_with_sigkill_leaves_nothing_the_next_run_does_not_remove(tmp_path):
    """kill -9 of `acmm report` while its first stage runs: its figure staging folder
    (``.figures-<pid>-…``), its lock file and the stage's staging folder stay behind; the next
    report in that folder removes its own (here one refused at once: the results root is a
    file), the next run of the stage its own."""
    from acmm_qpp.outputs import run_lock

    out = tmp_path / "out"
    proc = subprocess.Popen([ACMM, "report", "--fast", "--jobs", "1", "--out", str(out)], env=ENV, cwd=tmp_path,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 120
        while not list((out / "results").glob("*/.staging-*")) and time.monotonic() < deadline:
            time.sleep(0.05)
    finally:
        proc.kill()
        proc.wait(timeout=30)
    left = _hidden(out)
    assert any(n.startswith(".figures-") for n in left) and ".lock" in left, left
    stages = sorted({p.parent for p in (out / "results").glob("*/.staging-*")})
    assert stages, left
    (tmp_path / "afile").write_text("")
    r = subprocess.run([ACMM, "report", "--fast", "--root", str(tmp_path / "afile"), "--out", str(out)],
                       env=ENV, cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert r.returncode == 4 and r.stderr.startswith("error: --root") and len(r.stderr.splitlines()) == 1, r.stderr
    assert [n for n in _hidden(out) if "/" not in n] == []
    for run in stages:                      # what the next run of each stage does first
        with run_lock(run):
            pass
    assert _hidden(out) == []


def test_a_report_meeting_a_full_disk_is_one_error_line_exit_4(tmp_path, small_tmpfs):
    """A report whose stages (in its pool workers) run out of space stops at the first: one
    `error:` line on stderr and exit 4, not a section per failed stage (44 lines, a review)."""
    r = subprocess.run([ACMM, "report", "--fast", "--out", str(small_tmpfs / "out")], env=ENV, cwd=tmp_path,
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 4, (r.returncode, r.stderr)
    assert len(r.stderr.splitlines()) == 1 and r.stderr.startswith("error: "), r.stderr
    assert "No space left on device" in r.stderr and "Traceback" not in r.stderr
    assert not list(small_tmpfs.rglob("*.tmp")) and not list(small_tmpfs.rglob(".figures-*"))


def _disk_full(*args, **kwargs):
    raise OSError(errno.ENOSPC, "No space left on device")


@pytest.mark.parametrize("args", [["tea", "mb3"], ["design", "mb3", "--no-figures"],
                                  ["sweep", "SWEEP", "-j", "1"]])
def test_a_full_disk_in_a_stage_is_one_error_line_exit_4(tmp_runs, monkeypatch, args):
    """Every file a stage writes is synced (os.fsync, acmm_qpp.outputs; the sweep's journal
    too), where a full disk shows at the latest: one `error:` line, exit 4, no result and nothing
    hidden left in the run folder."""
    from typer.testing import CliRunner

    from acmm.cli.app import app
    import acmm_qpp.outputs as outputs

    if "SWEEP" in args:
        args = [str(_sweep_config(tmp_runs, n_runs=2, orbits=0.5)) if a == "SWEEP" else a for a in args]
    monkeypatch.setattr(outputs.os, "fsync", _disk_full)
    r = CliRunner().invoke(app, args)
    assert r.exit_code == 4, (r.exit_code, r.output)
    assert r.stderr.count("\n") == 1 and r.stderr.startswith("error: ") and "No space left on device" in r.stderr
    assert list(tmp_runs.rglob("*.h5")) == [] and _hidden(tmp_runs) == []
