"""What a stage leaves in its run folder (acmm_qpp.outputs): its files are written in a staging
folder and moved into place when it succeeds; a stage that fails or is interrupted leaves the
folder as it was; no result beside a config.yaml of another run; files of earlier runs, of other
run folders and of nested stages that completed are left alone (the sweep, which keeps its
self-describing partial tables, writes into its run folder itself: tests/acmm/sweep/test_run.py).
The run lock's cleanup: what a killed run left is removed by the next run of that folder, the
staging folders of the kinds its caller names included."""
import os
import subprocess
import sys

import pytest

from acmm_qpp.errors import FigureError, OutputError
from acmm_qpp.outputs import remove_leftovers, run_lock, stage, _staged_outputs, write_text

DESIGN = ("design.h5", "design_*.png")
SIMULATE = ("sim.h5", "sim_*.png")


class _Boom(Exception):
    pass


def _earlier_run(run):
    run.mkdir(parents=True)
    write_text(run / "config.yaml", "name: old\n")
    write_text(run / "design.h5", "old results")
    write_text(run / "design_gains.png", "old figure")


def _contents(run):
    """Name → bytes of each entry (a folder: "folder"; config.yaml without its comment header)."""
    def body(p):
        data = p.read_bytes()
        return b"".join(ln for ln in data.splitlines(True) if not ln.startswith(b"#")) if p.name == "config.yaml" else data
    return {p.name: body(p) if p.is_file() else "folder" for p in sorted(run.iterdir())}


def test_a_stage_writes_in_its_staging_folder_and_moves_its_files_into_place(tmp_path):
    run = tmp_path / "run"
    _earlier_run(run)
    with _staged_outputs(run, DESIGN, config_text="name: new\n") as out:
        assert out.parent == run and out.name.startswith(f".staging-{os.getpid()}-")
        write_text(out / "design.h5", "new results")
        write_text(out / "design_poles.png", "new figure")
        assert (run / "design.h5").read_text() == "old results"       # nothing moved yet
    # this run's files and config.yaml; the earlier run's figure that this run did not draw is gone
    assert _contents(run) == {"config.yaml": b"name: new\n", "design.h5": b"new results",
                              "design_poles.png": b"new figure"}


def test_a_stage_failing_after_writing_leaves_the_folder_as_it_was(tmp_path):
    run = tmp_path / "run"
    _earlier_run(run)
    before = _contents(run)
    with pytest.raises(_Boom):
        with _staged_outputs(run, DESIGN, config_text="name: new\n") as out:
            write_text(out / "design.h5", "new results")
            write_text(out / "design_poles.png", "new figure")
            raise _Boom                                         # e.g. the next figure cannot be written
    assert _contents(run) == before                             # its staging folder gone too


def test_ctrl_c_while_the_figures_are_drawn_leaves_the_folder_as_it_was(tmp_path):
    from acmm_qpp.results import draw_figures

    run = tmp_path / "run"
    _earlier_run(run)
    before = _contents(run)

    def interrupted_figure():
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        with _staged_outputs(run, DESIGN, config_text="name: new\n") as out:
            write_text(out / "design.h5", "new results")
            draw_figures([lambda: write_text(out / "design_poles.png", "a new figure"), interrupted_figure])
    assert _contents(run) == before


@pytest.mark.parametrize("blocked", ["design.h5", "config.yaml"])
def test_a_directory_in_the_place_of_a_result_or_the_config_moves_nothing(tmp_path, blocked):
    run = tmp_path / "run"
    _earlier_run(run)
    (run / blocked).unlink()
    (run / blocked).mkdir()
    before = _contents(run)
    with pytest.raises(OutputError, match="a directory of that name is in the way"):
        with _staged_outputs(run, DESIGN, config_text="name: new\n") as out:
            write_text(out / "design.h5", "new results")
    assert _contents(run) == before


def test_only_a_figure_failing_keeps_the_results_with_their_config(tmp_path):
    run = tmp_path / "run"
    _earlier_run(run)
    with pytest.raises(FigureError):
        with _staged_outputs(run, DESIGN, config_text="name: new\n") as out:
            write_text(out / "design.h5", "new results")
            raise FigureError("cannot write design_poles.png")   # raised when the figures are joined
    # the results and this run's config.yaml; the earlier run's figure is removed as on success
    assert _contents(run) == {"config.yaml": b"name: new\n", "design.h5": b"new results"}


def test_a_directory_in_the_place_of_a_figure_keeps_the_results_with_their_config(tmp_path):
    run = tmp_path / "run"
    _earlier_run(run)
    (run / "design_poles.png").mkdir()
    with pytest.raises(FigureError, match="design_poles.png: a directory of that name is in the way"):
        with _staged_outputs(run, DESIGN, config_text="name: new\n") as out:
            write_text(out / "design.h5", "new results")
            write_text(out / "design_poles.png", "new figure")
    assert _contents(run) == {"config.yaml": b"name: new\n", "design.h5": b"new results",
                              "design_poles.png": "folder"}


def test_completed_nested_stage_and_other_run_folders_are_kept(tmp_path):
    run, other = tmp_path / "run", tmp_path / "other"
    run.mkdir()
    other.mkdir()
    write_text(run / "sim.h5", "an earlier run's simulation")
    write_text(run / "config.yaml", "name: old\n")
    write_text(other / "sim.h5", "another run's")
    with pytest.raises(_Boom):
        with _staged_outputs(run, SIMULATE, config_text="name: new\n") as sim_out:
            write_text(sim_out / "sim_axes.png", "drawn before the design")
            with _staged_outputs(run, DESIGN, config_text="name: new\n") as design_out:
                write_text(design_out / "design.h5", "design results")
            write_text(sim_out / "sim.h5", "new simulation")
            raise _Boom
    # the design finished (results, config.yaml); the simulation did not: its files are gone, and
    # so is the earlier sim.h5, which the new config.yaml no longer describes
    assert _contents(run) == {"config.yaml": b"name: new\n", "design.h5": b"design results"}
    assert _contents(other) == {"sim.h5": b"another run's"}


def test_a_nested_stage_figure_failing_does_not_finish_the_outer_stage(tmp_path):
    run = tmp_path / "run"
    run.mkdir()
    write_text(run / "sim.h5", "an earlier run's simulation")
    with pytest.raises(FigureError):
        with _staged_outputs(run, SIMULATE, config_text="name: sim\n") as sim_out:
            write_text(sim_out / "sim_axes.png", "drawn before the design")
            with _staged_outputs(run, DESIGN, config_text="name: sim\n") as design_out:
                write_text(design_out / "design.h5", "design results")
                raise FigureError("cannot write design_poles.png")
    assert _contents(run) == {"config.yaml": b"name: sim\n", "design.h5": b"design results"}


def test_a_nested_stage_interrupted_keeps_the_earlier_run_whole(tmp_path):
    run = tmp_path / "run"
    run.mkdir()
    with _staged_outputs(run, SIMULATE, config_text="cfg: A\n") as sim_out:
        with _staged_outputs(run, DESIGN, config_text="cfg: A\n") as design_out:
            write_text(design_out / "design.h5", "design A")
        write_text(sim_out / "sim.h5", "sim A")
    before = _contents(run)
    with pytest.raises(KeyboardInterrupt):
        with _staged_outputs(run, SIMULATE, config_text="cfg: B\n"):
            with _staged_outputs(run, DESIGN, config_text="cfg: B\n") as design_out:
                write_text(design_out / "design.h5", "design B")
                raise KeyboardInterrupt
    assert _contents(run) == before


def test_a_stage_declares_its_files_and_runs_under_the_lock_with_its_staging_folder(tmp_path):
    class Cfg:
        def run_dir(self):
            return tmp_path / "runs" / "x"

        def to_yaml(self):
            return "name: x\n"

    @stage(("x.h5",), lambda c: c)
    def run_x(cfg, value, *, out):
        assert (cfg.run_dir() / ".lock").is_file() and out.parent == cfg.run_dir()
        write_text(out / "x.h5", value)
        return out

    out = run_x(Cfg(), "v")
    assert not out.exists()
    assert _contents(tmp_path / "runs" / "x") == {"config.yaml": b"name: x\n", "x.h5": b"v"}


def test_what_a_killed_run_left_is_removed_by_the_next_run(tmp_path):
    """A run killed with kill -9 leaves its staging folder, a writer's temporary file and the
    lock file (the kernel released the lock); the next run of that folder removes them."""
    run = tmp_path / "run"
    _earlier_run(run)
    code = ("import os, sys\nfrom acmm_qpp.outputs import run_lock, _staged_outputs\n"
            "with run_lock(sys.argv[1]):\n"
            "    with _staged_outputs(sys.argv[1], ('design.h5',), config_text='name: killed') as out:\n"
            "        (out / 'design.h5').write_text('half')\n"
            "        (out.parent / '.design_gains.png.x7k2.tmp').write_text('half a PNG')\n"
            "        os.kill(os.getpid(), 9)\n")
    done = subprocess.run([sys.executable, "-c", code, str(run)], capture_output=True, text=True, timeout=60)
    assert done.returncode == -9, done.stderr
    left = sorted(p.name for p in run.iterdir() if p.name.startswith("."))
    assert left[0] == ".design_gains.png.x7k2.tmp" and left[1] == ".lock" and left[2].startswith(".staging-")
    with run_lock(run):
        pass
    assert _contents(run) == {"config.yaml": b"name: old\n", "design.h5": b"old results",
                              "design_gains.png": b"old figure"}


LEFT = (".staging-12-ab", ".figures-12-cd", ".design.h5.x7k2.tmp")
KEPT = (".figuresX", ".figures-cd", "figures-12-cd", "design.h5")


def _fill(run):
    run.mkdir()
    for name in LEFT + KEPT:                    # files end in .tmp or .h5, the rest are folders
        if name.endswith((".tmp", ".h5")):
            (run / name).write_text("")
        else:
            (run / name).mkdir()


def test_the_stages_leftovers_go_and_a_callers_kind_only_when_named(tmp_path):
    _fill(tmp_path / "a")
    assert sorted(remove_leftovers(tmp_path / "a")) == [".design.h5.x7k2.tmp", ".staging-12-ab"]
    assert sorted(remove_leftovers(tmp_path / "a", ("figures",))) == [".figures-12-cd"]
    assert sorted(p.name for p in (tmp_path / "a").iterdir()) == sorted(KEPT)


def test_the_run_lock_removes_the_leftovers_of_the_kinds_named(tmp_path):
    _fill(tmp_path / "b")
    with run_lock(tmp_path / "b", staging=("figures",)) as run:
        assert sorted(p.name for p in run.iterdir()) == sorted(KEPT + (".lock",))
    assert sorted(p.name for p in (tmp_path / "b").iterdir()) == sorted(KEPT)
