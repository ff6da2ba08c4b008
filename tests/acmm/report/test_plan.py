"""The report's plan (acmm.report.plan): the stages a part waits for, and those whose failure
keeps it from running."""
from __future__ import annotations

from acmm.report.gather import Failed, Gathered
from acmm.report.plan import section_tasks

STAGES = {f"{stage}:{name}" for stage in ("design", "simulate")
          for name in ("mb3", "mb3_decoupled", "staircase", "staircase_lqr", "staircase_quadratic")}


def test_the_quadratic_is_waited_for_but_its_failure_leaves_the_packaged_schedule(tmp_path):
    """The routes table and the gain-schedule figure show the report's quadratic beside the
    packaged schedule: they wait for its stages, but a failed quadratic leaves them to run
    (the section names the failure), while a failed packaged design still stops them."""
    tasks = {t.name: t for t in section_tasks(Gathered({}, {}), tmp_path, False, STAGES, None)}
    done = {name: object() for name in STAGES}
    done["design:staircase_quadratic"] = Failed("design:staircase_quadratic", "injected", 3)
    for part in ("schedule/routes", "schedule/gains"):
        assert "design:staircase_quadratic" in tasks[part].deps
        assert tasks[part].args(done)[-1] is None
    done["design:staircase"] = Failed("design:staircase", "injected", 3)
    for part in ("schedule/routes", "schedule/gains"):
        assert tasks[part].args(done)[-1].message == "injected"
