"""What a stage leaves in its run folder when it fails (acmm_qpp.outputs): no result beside a
config.yaml of another run; files of earlier runs, of other run folders and of nested stages that
completed are left alone; the sweep keeps its self-describing partial tables."""
import pytest

from acmm_qpp.outputs import stage_outputs
from acmm_qpp.atomic_write import write_text


class _Boom(Exception):
    pass


def _earlier_run(run):
    run.mkdir(parents=True)
    write_text(run / "config.yaml", "name: old\n")
    write_text(run / "design.h5", "old results")
    write_text(run / "design_gains.png", "old figure")


def test_a_stage_failing_after_writing_removes_what_it_wrote(tmp_path):
    run = tmp_path / "run"
    _earlier_run(run)
    with pytest.raises(_Boom):
        with stage_outputs(run, "design", config_text="name: new\n"):
            write_text(run / "design.h5", "new results")      # replaces the earlier run's file
            write_text(run / "design_poles.png", "new figure")
            raise _Boom                                         # e.g. the next figure cannot be written
    # nothing of the failed run is left; the earlier run's files, the one it replaced included,
    # and its config.yaml are as before the command
    assert sorted(p.name for p in run.iterdir()) == ["config.yaml", "design.h5", "design_gains.png"]
    assert (run / "config.yaml").read_text() == "name: old\n"
    assert (run / "design.h5").read_text() == "old results"


def test_a_stage_whose_config_yaml_cannot_be_written_removes_its_results(tmp_path):
    run = tmp_path / "run"
    (run / "config.yaml").mkdir(parents=True)                  # config.yaml cannot be written
    with pytest.raises(OSError):
        with stage_outputs(run, "design", config_text="name: new\n"):
            write_text(run / "design.h5", "new results")
    assert sorted(p.name for p in run.iterdir()) == ["config.yaml"]


def test_completed_nested_stage_and_other_run_folders_are_kept(tmp_path):
    outer, inner, other = tmp_path / "outer", tmp_path / "inner", tmp_path / "other"
    for d in (outer, inner, other):
        d.mkdir()
    with pytest.raises(_Boom):
        with stage_outputs(outer, "simulate", config_text="name: outer\n"):
            with stage_outputs(inner, "design", config_text="name: inner\n"):
                write_text(inner / "design.h5", "inner results")
            write_text(outer / "design.h5", "design run by the outer stage")
            with stage_outputs(outer, "design", config_text="name: outer\n"):
                write_text(outer / "design_poles.png", "nested, completed")
            write_text(other / "sim.h5", "written meanwhile by a stage of another thread")   # recorded too
            write_text(outer / "sim.h5", "outer results")
            raise _Boom
    assert sorted(p.name for p in inner.iterdir()) == ["config.yaml", "design.h5"]
    assert sorted(p.name for p in other.iterdir()) == ["sim.h5"]
    # the outer stage's own files go; the nested stage that completed keeps its files and config
    assert sorted(p.name for p in outer.iterdir()) == ["config.yaml", "design_poles.png"]
    assert (outer / "config.yaml").read_text().endswith("name: outer\n")


def test_a_failed_sweep_keeps_its_partial_tables(tmp_path):
    run = tmp_path / "run"
    run.mkdir()
    with pytest.raises(_Boom):
        with stage_outputs(run, "sweep", config_text="name: s\n"):
            write_text(run / "sweep.h5", "snapshot, complete = False")
            raise _Boom
    assert sorted(p.name for p in run.iterdir()) == ["sweep.h5"]


def test_only_a_figure_failing_keeps_the_results_with_their_config(tmp_path):
    from acmm_qpp.errors import FigureError

    run = tmp_path / "run"
    _earlier_run(run)
    with pytest.raises(FigureError):
        with stage_outputs(run, "design", config_text="name: new\n"):
            write_text(run / "design.h5", "new results")
            raise FigureError("cannot write design_poles.png")   # raised when the figures are joined
    # the results and this run's config.yaml; the earlier run's figure is pruned as on success
    assert sorted(p.name for p in run.iterdir()) == ["config.yaml", "design.h5"]
    assert (run / "config.yaml").read_text().endswith("name: new\n")


def test_a_nested_stage_figure_failing_does_not_finish_the_outer_stage(tmp_path):
    from acmm_qpp.errors import FigureError

    run = tmp_path / "run"
    run.mkdir()
    write_text(run / "sim.h5", "an earlier run's simulation")
    with pytest.raises(FigureError):
        with stage_outputs(run, "simulate", config_text="name: sim\n"):
            write_text(run / "sim_axes.png", "drawn before the design")
            with stage_outputs(run, "design", config_text="name: sim\n"):
                write_text(run / "design.h5", "design results")
                raise FigureError("cannot write design_poles.png")
    # the design finished (results, config.yaml); the simulation did not: its own file is removed,
    # and so is the earlier sim.h5, which the new config.yaml no longer describes
    assert sorted(p.name for p in run.iterdir()) == ["config.yaml", "design.h5"]
    assert (run / "config.yaml").read_text().endswith("name: sim\n")


def test_a_figure_completed_but_not_yet_recorded_is_removed_too(tmp_path):
    """A figure writer of the worker may complete a file the stage records only when it joins
    the worker; a stage that fails before then still removes it (it is new or replaced), and
    leaves the earlier run's files it did not touch."""
    run = tmp_path / "run"
    _earlier_run(run)
    with pytest.raises(_Boom):
        with stage_outputs(run, "design", config_text="name: new\n"):
            tmp = run / ".design_poles.png.tmp"
            tmp.write_text("a writer's figure")               # not through acmm_qpp.results: unrecorded
            tmp.replace(run / "design_poles.png")
            raise _Boom
    assert sorted(p.name for p in run.iterdir()) == ["config.yaml", "design.h5", "design_gains.png"]


def test_a_writer_killed_mid_write_leaves_no_temporary_file(tmp_path):
    """Ctrl-C while a figure writer was inside its atomic write: the writer, killed with its
    worker, left ``.sim_inertia.png.<random>.tmp`` beside the rolled-back folder (a review);
    only the next run removed it.  The rollback removes it (the stage holds the run lock)."""
    run = tmp_path / "run"
    _earlier_run(run)
    before = sorted(p.name for p in run.iterdir())
    with pytest.raises(_Boom):
        with stage_outputs(run, "simulate", config_text="name: new\n"):
            (run / ".sim_inertia.png.x7k2q9.tmp").write_bytes(b"half a PNG")   # a killed writer's
            raise _Boom
    assert sorted(p.name for p in run.iterdir()) == before


def test_ctrl_c_while_the_figures_are_drawn_rolls_the_stage_back(tmp_path):
    """Ctrl-C while the stage draws its figures (its results written): Python's interrupt path
    rolls the whole folder back, the results and the figures drawn so far included."""
    from acmm_qpp.results import draw_figures

    run = tmp_path / "run"
    _earlier_run(run)
    before = {p.name: p.read_bytes() for p in run.iterdir()}

    def interrupted_figure():
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        with stage_outputs(run, "design", config_text="name: new\n"):
            write_text(run / "design.h5", "new results")
            draw_figures([lambda: write_text(run / "design_poles.png", "a new figure"), interrupted_figure])
    assert {p.name: p.read_bytes() for p in run.iterdir()} == before


def test_a_sweep_whose_figure_fails_finishes_with_its_config(tmp_runs):
    """The sweep's tables are written before its figures: a figure in the way is exit 4 with
    this run's config.yaml, and the earlier run's other figure pruned."""
    import yaml
    from typer.testing import CliRunner

    from acmm.cli.app import app
    from tests.conftest import CONFIGS

    cfg = yaml.safe_load((CONFIGS / "sweep_smoke.yaml").read_text())
    cfg["sweep"].pop("margin", None)
    cfg["sweep"].update(n_runs=2, orbits=0.5)
    cfg["output"] = {"root": str(tmp_runs / "runs"), "figures": True}
    path = tmp_runs / "sw.yaml"
    path.write_text(yaml.safe_dump(cfg))
    r = CliRunner().invoke(app, ["sweep", str(path), "-j", "1"])
    assert r.exit_code == 0, r.output
    run = tmp_runs / "runs" / cfg["name"]
    (run / "sweep_map.png").unlink()
    (run / "sweep_map.png").mkdir()
    r = CliRunner().invoke(app, ["sweep", str(path), "-j", "1", "sweep.n_runs=3"])
    assert r.exit_code == 4, r.output
    assert "n_runs: 3" in (run / "config.yaml").read_text()
    # the map is drawn first and failed; the earlier run's peak-error figure is not this run's
    assert not (run / "sweep_peak_error.png").exists()


def test_an_interrupted_stage_puts_back_every_file_it_replaced(tmp_path):
    """Ctrl-C after the new results replaced the old ones (while the figures or config.yaml are
    written): the folder is as before the command, byte for byte, and no hidden folder is left."""
    run = tmp_path / "run"
    _earlier_run(run)
    write_text(run / "design_poles.png", "old poles")
    before = {p.name: p.read_bytes() for p in run.iterdir()}
    with pytest.raises(KeyboardInterrupt):
        with stage_outputs(run, "design", config_text="name: new\n"):
            write_text(run / "design.h5", "new results")
            write_text(run / "design_gains.png", "new figure")
            (run / "design_poles.png").unlink()         # whatever the stage did to its own files
            raise KeyboardInterrupt
    assert {p.name: p.read_bytes() for p in run.iterdir()} == before


def test_a_stage_that_fails_in_its_config_yaml_puts_the_old_one_back(tmp_path, monkeypatch):
    import acmm_qpp.outputs as outputs

    run = tmp_path / "run"
    _earlier_run(run)

    def prune_fails(*a, **k):                      # config.yaml written, then the end fails
        raise OSError("disk full")

    monkeypatch.setattr(outputs, "prune", prune_fails)
    with pytest.raises(OSError):
        with stage_outputs(run, "design", config_text="name: new\n"):
            write_text(run / "design.h5", "new results")
    assert (run / "config.yaml").read_text() == "name: old\n"
    assert (run / "design.h5").read_text() == "old results"


def test_a_finished_stage_leaves_no_rollback_folder_and_a_killed_ones_is_removed(tmp_path):
    import subprocess
    import sys

    run = tmp_path / "run"
    _earlier_run(run)
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True,
                          text=True).stdout.strip()
    (run / f".rollback-{dead}-1").mkdir()              # left by a process killed with kill -9
    write_text(run / f".rollback-{dead}-1" / "design.h5", "older")
    with stage_outputs(run, "design", config_text="name: new\n"):
        write_text(run / "design.h5", "new results")
    assert not [p for p in run.iterdir() if p.name.startswith(".rollback")]
    assert (run / "design.h5").read_text() == "new results"


def _slow_figure(path):
    """A figure writer that takes 1 s (module level: the worker calls it by reference)."""
    import time

    time.sleep(1.0)
    write_text(path, "a figure landing late")
    return path


def test_a_nested_stage_interrupted_keeps_the_earlier_run_whole(tmp_path):
    """acmm simulate → design, both of an earlier complete run on disk; the new design is
    interrupted: the design puts back its earlier design.h5, and the simulation that ran it does
    not then remove that restored file as one it wrote (it did: the earlier design.h5 was lost)."""
    d = tmp_path / "run"
    d.mkdir()
    with stage_outputs(d, "simulate", config_text="cfg: A\n"):
        with stage_outputs(d, "design", config_text="cfg: A\n"):
            write_text(d / "design.h5", "design A")
        write_text(d / "sim.h5", "sim A")
    before = {p.name: p.read_text() for p in d.iterdir()}
    with pytest.raises(KeyboardInterrupt):
        with stage_outputs(d, "simulate", config_text="cfg: B\n"):
            with stage_outputs(d, "design", config_text="cfg: B\n"):
                write_text(d / "design.h5", "design B")
                raise KeyboardInterrupt
    assert {p.name: p.read_text() for p in d.iterdir()} == before
