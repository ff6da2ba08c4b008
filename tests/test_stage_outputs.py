"""What a stage leaves in its run folder when it fails (common.outputs): no result beside a
config.yaml of another run; files of earlier runs, of other run folders and of nested stages that
completed are left alone; the sweep keeps its self-describing partial tables."""
import pytest

from common.outputs import stage_outputs
from common.results import write_text


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
    # nothing of the failed run is left; the earlier run's untouched files and config.yaml stay
    assert sorted(p.name for p in run.iterdir()) == ["config.yaml", "design_gains.png"]
    assert (run / "config.yaml").read_text() == "name: old\n"


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
    from common.errors import FigureError

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
    from common.errors import FigureError

    run = tmp_path / "run"
    run.mkdir()
    write_text(run / "sim.h5", "an earlier run's simulation")
    with pytest.raises(FigureError):
        with stage_outputs(run, "simulate", config_text="name: sim\n"):
            write_text(run / "sim_axes.png", "drawn before the design")
            with stage_outputs(run, "design", config_text="name: sim\n"):
                write_text(run / "design.h5", "design results")
                raise FigureError("cannot write design_poles.png")
    # the design finished (results, config.yaml); the simulation did not: its own file is removed
    # and the earlier sim.h5 is not pruned as if it had finished
    assert sorted(p.name for p in run.iterdir()) == ["config.yaml", "design.h5", "sim.h5"]
    assert (run / "sim.h5").read_text() == "an earlier run's simulation"
