"""The run lock's cleanup (acmm_qpp.runlock): what a killed run left is removed by the next run
of that folder, the staging folders of the kinds its caller names included."""
from __future__ import annotations

from acmm_qpp.runlock import remove_leftovers, run_lock

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
