"""``acmm report`` stands alone (issue 30, item 5): it computes in its own results root and a
failed section is shown in the report while the others complete.

The report ran its stages in each config's ``output.root`` (``runs/<name>/``) with figures off:
``acmm report --fast`` after a user's ``qpp design qpp_siso`` re-ran that stage in the user's
``runs/qpp_siso/`` and deleted and rewrote the figures there.  And the first stage or section that
failed stopped the whole report (nothing written).
"""
from __future__ import annotations

import hashlib
from pathlib import Path

import pytest

from acmm_qpp.errors import ConvergenceError
from tests.conftest import invoke

pytestmark = pytest.mark.slow      # three `acmm report --fast` runs: `make test-slow`


def _tree(folder: Path) -> dict:
    """Relative path → SHA-256 of every file under ``folder`` (folders as ``"/"``)."""
    return {p.relative_to(folder).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest() if p.is_file() else "/"
            for p in sorted(folder.rglob("*"))}


def test_report_leaves_the_users_run_folders_byte_identical(tmp_runs):
    """A user's ``runs/qpp_siso/`` with figures (``qpp design`` and ``qpp simulate`` as the user
    runs them): after ``acmm report --fast`` every file there is the same, none added or removed,
    and no other ``runs/<name>/`` appeared; the report's stages ran in ``runs/report/results``."""
    from acmm.cli.app import app as acmm_app
    from qpp.cli import app as qpp_app

    for stage in ("design", "simulate"):
        res = invoke(qpp_app, stage, "qpp_siso")
        assert res.exit_code == 0, res.output
    user = tmp_runs / "runs" / "qpp_siso"
    before = _tree(user)
    assert any(k.endswith(".png") or k.endswith(".pdf") for k in before), sorted(before)   # figures made
    res = invoke(acmm_app, "report", "--fast", "--jobs", "1")
    assert res.exit_code == 0, res.output
    assert _tree(user) == before
    assert sorted(p.name for p in (tmp_runs / "runs").iterdir()) == ["qpp_siso", "report"]
    own = tmp_runs / "runs" / "report" / "results"
    assert (own / "qpp_siso" / "qpp_design.h5").is_file() and (own / "qpp_siso" / "qpp_sim.h5").is_file()
    assert "runs/report/results/" in (tmp_runs / "runs" / "report" / "report.md").read_text(encoding="utf-8")


def _failing_text14(ctx):
    raise ConvergenceError("injected: the chapter 14 solver did not converge")


def test_a_failed_section_is_shown_and_the_others_complete(tmp_path, monkeypatch):
    """One section part raising a user-facing error (the first part of QPP chapter 14): the
    report is written, that section shows its heading and the one-line error, every other
    section is there with its content, and the command exits with the error's code (3) on one
    ``error:`` line."""
    import acmm.report.plan as plan
    from acmm.cli.app import app
    from acmm.report.constants import SECTIONS

    parts = [(p[0], p[1], _failing_text14, *p[3:]) if p[0] == "qpp14" else p for p in plan.PARTS]
    monkeypatch.setattr(plan, "PARTS", parts)
    out = tmp_path / "out"
    res = invoke(app, "report", "--fast", "--jobs", "2", "--out", out)
    assert res.exit_code == 3, res.output
    last = res.output.strip().splitlines()[-1]
    assert last.startswith("error: report incomplete:") and "injected: the chapter 14 solver" in last
    assert "Traceback" not in res.output
    md = (out / "report.md").read_text(encoding="utf-8")
    for _, title in SECTIONS:
        assert f"## {title}" in md, title
    q14 = md.split("## QPP chapter 14")[1].split("\n## ")[0]
    assert "FAILED — qpp14 failed: injected: the chapter 14 solver did not converge." in q14
    q13 = md.split("## QPP chapter 13")[1].split("\n## ")[0]
    assert "FAILED" not in q13 and "|" in q13                   # its tables are there
    assert md.count("FAILED — ") == 1                           # nothing else failed
    assert "injected: the chapter 14 solver" in (out / "index.html").read_text(encoding="utf-8")


def _broken_qpp_design(cfg, stage, rerun):
    if stage == "design" and cfg.name == "qpp_manipulator":
        raise ConvergenceError("injected: qpp design of qpp_manipulator did not converge")
    from acmm.report.stage_results import ensure_qpp

    return ensure_qpp(cfg, stage, rerun=rerun)


def test_a_failed_stage_fails_only_the_sections_that_read_it(tmp_path, monkeypatch):
    """A stage raising (the chapter-14 qpp design, in a worker): its simulation is not run, the
    chapter-14 parts show the error, chapter 13 and the rest are complete, exit 3."""
    import sys

    from acmm.cli.app import app

    gather_mod = sys.modules["acmm.report.gather"]     # (acmm.report.gather the attribute is the function)
    monkeypatch.setattr(gather_mod, "_qpp_task", _broken_qpp_design)
    out = tmp_path / "out"
    res = invoke(app, "report", "--fast", "--jobs", "2", "--out", out)
    assert res.exit_code == 3, res.output
    assert res.output.strip().splitlines()[-1].startswith("error: report incomplete:")
    md = (out / "report.md").read_text(encoding="utf-8")
    q14 = md.split("## QPP chapter 14")[1].split("\n## ")[0]
    assert ("FAILED — qpp14 not computed: qpp design:qpp_manipulator failed: injected: qpp design of "
            "qpp_manipulator did not converge.") in q14
    assert "FAILED" not in md.split("## QPP chapter 14")[0]     # the sections before it are complete
    assert not (out / "results" / "qpp_manipulator" / "qpp_sim.h5").exists()    # not run
    assert (out / "results" / "qpp_siso" / "qpp_sim.h5").is_file()
