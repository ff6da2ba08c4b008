"""Provenance of a results file (acmm_qpp.provenance): the git commit asked once per process, an
edited checkout flagged as such."""
from __future__ import annotations

import pytest

from tests.conftest import REPO


def test_git_commit_asked_once_per_process(monkeypatch, tmp_path):
    import subprocess

    from acmm_qpp import provenance
    from acmm_qpp.results import read_h5, write_h5

    calls = []
    real = subprocess.run

    def counting(*args, **kwargs):
        calls.append(args)
        return real(*args, **kwargs)

    provenance._git_state.cache_clear()
    monkeypatch.setattr(subprocess, "run", counting)
    try:
        first = provenance.git_commit()
        assert provenance.git_commit() == first and len(calls) == 1
        prov = read_h5(write_h5(tmp_path / "a.h5", {}, "a: 1\n"))["attrs"]
        assert prov["git_commit"] == first and prov["git_dirty"] in ("yes", "no") and len(calls) == 1
    finally:
        provenance._git_state.cache_clear()


def test_provenance_flags_uncommitted_changes(tmp_path):
    """A results file written by an edited checkout says so (git_dirty = yes): the commit alone
    does not say what code ran.  A git repository of its own holds a copy of this package."""
    import os
    import shutil
    import subprocess
    import sys

    if shutil.which("git") is None:
        pytest.skip("no git")
    repo = tmp_path / "repo"
    shutil.copytree(REPO / "acmm_qpp", repo / "acmm_qpp",
                    ignore=shutil.ignore_patterns("__pycache__"))
    git = ["git", "-c", "user.name=t", "-c", "user.email=t@t", "-c", "init.defaultBranch=main"]
    subprocess.run(git + ["init", "-q"], cwd=repo, check=True)
    subprocess.run(git + ["add", "-A"], cwd=repo, check=True)
    subprocess.run(git + ["commit", "-q", "-m", "x"], cwd=repo, check=True)
    head = subprocess.run(["git", "rev-parse", "HEAD"], cwd=repo, capture_output=True, text=True).stdout.strip()
    probe = "from acmm_qpp import provenance as p; print(p.git_commit(), p.git_dirty())"
    env = {**os.environ, "PYTHONPATH": str(repo)}

    def state():
        r = subprocess.run([sys.executable, "-c", probe], cwd=tmp_path, env=env, capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        return r.stdout.split()

    assert state() == [head, "no"]
    with open(repo / "acmm_qpp" / "units.py", "a") as f:
        f.write("# edited\n")
    assert state() == [head, "yes"]
