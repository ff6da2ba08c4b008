"""SIGTERM and SIGHUP unwind a command like Ctrl-C (:mod:`acmm_qpp.signals`).  Before: SIGTERM
killed the command at once, and the lock file and a rollback folder stayed behind."""
from __future__ import annotations

import hashlib
import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from tests.conftest import REPO as ROOT

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="POSIX signals, Linux prctl")


ENV = {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg"}


def _acmm(*args, cwd):
    return subprocess.Popen([sys.executable, "-c", "from acmm.cli.app import main; main()", *args], cwd=cwd,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, env=ENV)


def _digest(folder: Path) -> dict:
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() if p.is_file() else "folder"
            for p in sorted(folder.iterdir())}


#: a run that stops at a named point of the stage, says so on stdout and waits there (on stdin)
#: for the test's signal: each point is reached deterministically, no timing involved
_STOP_AT = textwrap.dedent("""
    import sys
    point = sys.argv[1]

    def stop(*args, **kwargs):
        print("at", point, flush=True)
        sys.stdin.readline()                        # the signal arrives while this waits
        raise SystemExit("the signal never came")

    if point == "design":
        from acmm.design import schedule as target; name = "design_one"
    elif point == "simulation":
        from acmm.simulate import kernel as target; name = "simulate"
    elif point == "figures":
        from acmm.plots import simulation as target; name = "summary"
    else:
        from acmm.stages import simulate as target; name = "write_results"
    setattr(target, name, stop)
    sys.argv = ["acmm", *sys.argv[2:]]
    from acmm.cli.app import main
    main()
""")


@pytest.mark.slow           # two `acmm simulate` subprocesses each, 4–6 s
@pytest.mark.parametrize("sig, point", [(signal.SIGTERM, "design"), (signal.SIGTERM, "simulation"),
                                        (signal.SIGTERM, "figures"), (signal.SIGHUP, "results")])
def test_a_terminated_run_rolls_back_like_ctrl_c_and_leaves_no_process(tmp_path, sig, point):
    """SIGTERM/SIGHUP at each step of ``acmm simulate`` (designing, integrating, drawing, writing
    the results) exits 128 + N with one line and leaves no lock, no staging folder, no half
    file: the earlier complete run as it was, or the new design stage whole."""
    first = subprocess.run([sys.executable, "-c", "from acmm.cli.app import main; main()", "simulate", "mb3",
                            "simulation.orbits=1"], cwd=tmp_path, capture_output=True, text=True, env=ENV,
                           timeout=300, check=False)
    assert first.returncode == 0, first.stderr
    run = tmp_path / "runs" / "mb3"
    before = _digest(run)
    proc = subprocess.Popen([sys.executable, "-c", _STOP_AT, point, "simulate", "mb3", "simulation.orbits=1",
                             "design.sector.sigma=0.6"], cwd=tmp_path, stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=ENV)
    assert proc.stdout.readline().split() == ["at", point]
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 128 + sig, err
    assert err.strip().splitlines()[-1] == f"terminated by signal {int(sig)}" and "Traceback" not in err
    after = _digest(run)
    if point == "design":
        assert after == before
    else:       # the nested design stage had finished (docs/howto/results.md, "Run folders"): kept, whole, with its
        # config.yaml; the simulation's files are gone (the earlier ones described the old design)
        assert after["design.h5"] != before["design.h5"] and after["config.yaml"] != before["config.yaml"]
        assert sorted(after) == ["config.yaml", "design.h5", "design_poles.png"], sorted(after)
    assert not [p for p in tmp_path.rglob("*") if p.name.startswith(".")]


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_after_the_run_finished_neither_prints_a_traceback_nor_kills_it(tmp_path, sig):
    """A Ctrl-C landing in the exit path of a finished run (an atexit handler, the teardown)
    printed a KeyboardInterrupt traceback with exit 0, or killed the finished run by the signal
    (a review, rarely).  The signal arrives here inside an atexit handler, deterministically."""
    script = tmp_path / "app.py"
    script.write_text(textwrap.dedent(f"""
        import atexit, os, signal, time, typer
        from acmm_qpp.cli.plumbing import run_app
        from acmm_qpp.signals import terminate_like_ctrl_c

        app = typer.Typer()

        @app.command()
        def run() -> None:
            def late():
                os.kill(os.getpid(), {int(sig)})
                time.sleep(0.2)                     # the signal is handled here, if at all
                print("atexit done", flush=True)
            atexit.register(late)
            print("finished", flush=True)

        terminate_like_ctrl_c()
        run_app(app)
        """))
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    p = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, env=env, timeout=60)
    assert p.returncode == 0, (p.returncode, p.stderr)
    assert p.stdout.split() == ["finished", "atexit", "done"] and "Traceback" not in p.stderr, p.stderr


_SIGNAL_IN = {
    # typer builds the command before the group's main runs
    "building": "import typer.main as tm\n"
                "def build(app):\n    raise Terminated(signal.SIGTERM)\n"
                "tm.get_command = build\n",
    # click parses the subcommand's options (typer mapped this to a silent exit 130)
    "parsing": "try:\n    import typer._click.core as cc\nexcept ImportError:\n    import click.core as cc\n"
               "parse = cc.Command.parse_args\n"
               "def parse_then_signal(self, ctx, args):\n"
               "    if self.name == 'validate':\n        raise Terminated(signal.SIGHUP)\n"
               "    return parse(self, ctx, args)\n"
               "cc.Command.parse_args = parse_then_signal\n",
}


@pytest.mark.parametrize("app", ["acmm", "qpp"])
@pytest.mark.parametrize("where, code", [("building", 143), ("parsing", 129)])
def test_a_signal_before_the_command_runs_is_one_line_and_its_exit_code(tmp_path, app, where, code):
    """A SIGTERM/SIGHUP that arrives while the command line is still being turned into a command
    (a review: a traceback with exit 1, or exit 130 without a word) exits 128 + N with one line."""
    script = ("import signal\nfrom acmm_qpp.errors import Terminated\n" + _SIGNAL_IN[where]
              + f"from {'acmm.cli.app' if app == 'acmm' else 'qpp.cli'} import main\nmain()\n")
    done = subprocess.run([sys.executable, "-c", script, "validate", "qpp_siso" if app == "qpp" else "mb3"],
                          cwd=tmp_path, capture_output=True, text=True, env=ENV, timeout=120, check=False)
    assert done.returncode == code, done.stderr
    assert done.stderr.strip() == f"terminated by signal {code - 128}"
    assert not list(tmp_path.iterdir())


def test_an_interrupt_in_a_deferred_step_is_raised_at_its_end(tmp_path):
    """Ctrl-C, SIGTERM or SIGHUP arriving inside :func:`acmm_qpp.signals.interrupts_deferred`
    (a finished stage's files being moved into place) is raised when the step is whole, by the
    handler in force before it; outside, SIGTERM raises at once."""
    script = textwrap.dedent("""
        import os, signal, time
        from acmm_qpp import signals
        signals.terminate_like_ctrl_c()
        for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
            try:
                with signals.interrupts_deferred():
                    os.kill(os.getpid(), sig)
                    time.sleep(0.1)
                    print("step finished", flush=True)
            except KeyboardInterrupt as exc:
                print("raised at the end:", type(exc).__name__, getattr(exc, "exit_code", 130), flush=True)
        try:
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(5)
        except KeyboardInterrupt:
            print("raised at once", flush=True)
    """)
    done = subprocess.run([sys.executable, "-c", script], cwd=tmp_path, capture_output=True, text=True, env=ENV,
                          timeout=60, check=False)
    assert done.stdout.splitlines() == ["step finished", "raised at the end: KeyboardInterrupt 130",
                                        "step finished", "raised at the end: Terminated 143",
                                        "step finished", "raised at the end: Terminated 129",
                                        "raised at once"], done.stdout + done.stderr
    assert done.returncode == 0 and done.stderr == ""


def test_only_the_first_interrupt_unwinds(tmp_path):
    """A command's process (``terminate_like_ctrl_c(once=True)``): Ctrl-C twice in a
    row, or Ctrl-C then SIGTERM, raise once; the cleanup that follows runs whole (the second Ctrl-C
    of a terminal had skipped a sweep's pool shutdown: a hang at exit)."""
    script = textwrap.dedent("""
        import os, signal, time
        from acmm_qpp import signals
        signals.terminate_like_ctrl_c(once=True)
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(1)
            print("not interrupted", flush=True)
        except KeyboardInterrupt:
            os.kill(os.getpid(), signal.SIGINT)
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(0.2)
            print("cleanup whole", flush=True)
    """)
    done = subprocess.run([sys.executable, "-c", script], cwd=tmp_path, capture_output=True, text=True, env=ENV,
                          timeout=60, check=False)
    assert done.returncode == 0 and done.stdout.splitlines() == ["cleanup whole"], (done.stdout, done.stderr)


@pytest.mark.skipif(not hasattr(signal, "pthread_sigmask"), reason="POSIX signal masks")
def test_handlers_are_switched_with_their_signals_blocked():
    """switch_handlers blocks the signals it switches during every signal.signal and restores the
    mask after: a Ctrl-C landing in a switch to SIG_IGN is discarded, one landing in a switch to a
    handler reaches that handler, and none is reported on stderr as a race by CPython."""
    code = textwrap.dedent("""
        import os, signal
        from acmm_qpp.signals import TERMINATING, ignore_interrupts, switch_handlers
        real, masks = signal.signal, []
        def spy(sig, handler):
            masks.append(signal.pthread_sigmask(signal.SIG_BLOCK, []))
            return real(sig, handler)
        signal.signal = spy
        before = signal.pthread_sigmask(signal.SIG_BLOCK, [])
        got = []
        switch_handlers({signal.SIGINT: lambda s, f: got.append("first")})
        ignore_interrupts()
        assert signal.pthread_sigmask(signal.SIG_BLOCK, []) == before
        switched = {signal.SIGINT, *TERMINATING}
        assert len(masks) == 1 + len(switched) and all(switched <= m for m in masks[1:]), masks
        assert signal.SIGINT in masks[0] and all(signal.getsignal(s) is signal.SIG_IGN for s in switched)
        signal.pthread_sigmask(signal.SIG_BLOCK, [signal.SIGINT])
        switch_handlers({signal.SIGINT: lambda s, f: got.append("third")})
        os.kill(os.getpid(), signal.SIGINT)                 # pending (blocked) ...
        ignore_interrupts()                                 # ... and discarded when ignored
        switch_handlers({signal.SIGINT: lambda s, f: got.append("fourth")})
        os.kill(os.getpid(), signal.SIGINT)                 # pending: the new handler takes it
        assert got == []
        signal.pthread_sigmask(signal.SIG_UNBLOCK, [signal.SIGINT])
        assert got == ["fourth"], got
        print("ok")
    """)
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, cwd=ROOT)
    assert (r.returncode, r.stdout.strip(), r.stderr) == (0, "ok", "")
