"""A report's files go into --out all together or not at all (acmm.report.publish): a review's disk
filled up while the report moved its figures and wrote its pages, which left the new figures and
manifest beside the previous page."""
from __future__ import annotations

import os

import pytest

from acmm_qpp.errors import OutputError
from acmm.report import publish as publish_mod


def _tree(root):
    return {p.relative_to(root).as_posix(): (p.read_text() if p.is_file() else "/")
            for p in sorted(root.rglob("*"))}


def _setup(tmp_path):
    out = tmp_path / "out"
    (out / "figures").mkdir(parents=True)
    for name in ("index.html", "report.md", "manifest.json", "figures/a.png"):
        (out / name).write_text(f"old {name}")
    staged = out / ".figures-1-x"
    (staged / ".pages").mkdir(parents=True)
    pairs = []
    for name in ("a.png", "b.png"):                          # b.png: a figure the old report lacked
        (staged / name).write_text(f"new {name}")
        pairs.append((staged / name, out / "figures" / name))
    for name in ("manifest.json", "report.md", "index.html"):
        (staged / ".pages" / name).write_text(f"new {name}")
        pairs.append((staged / ".pages" / name, out / name))
    return out, staged, pairs


def test_every_file_is_replaced_when_nothing_fails(tmp_path):
    out, staged, pairs = _setup(tmp_path)
    publish_mod.publish(pairs, staged / ".replaced")
    for _, target in pairs:
        assert target.read_text() == f"new {target.name}"


@pytest.mark.parametrize("fail_at", range(9))
def test_a_move_that_fails_leaves_the_folder_as_it_was(tmp_path, monkeypatch, fail_at):
    """Whichever rename fails (the 9 of them: 4 previous files aside, 5 new ones in), the
    previous report's files are back and no new file is left in --out."""
    out, staged, pairs = _setup(tmp_path)
    before = {k: v for k, v in _tree(out).items() if not k.startswith(".figures")}
    calls = []
    replace = os.replace

    def failing(src, dst):
        calls.append(dst)
        if len(calls) == fail_at + 1:
            raise OSError(28, "No space left on device")
        return replace(src, dst)

    monkeypatch.setattr(publish_mod.os, "replace", failing)
    with pytest.raises(OutputError, match="No space left on device.*left as it was"):
        publish_mod.publish(pairs, staged / ".replaced")
    monkeypatch.setattr(publish_mod.os, "replace", replace)
    after = {k: v for k, v in _tree(out).items() if not k.startswith(".figures")}
    assert after == before


def test_a_directory_in_the_way_changes_nothing(tmp_path):
    out, staged, pairs = _setup(tmp_path)
    (out / "report.md").unlink()
    (out / "report.md").mkdir()
    before = _tree(out)
    with pytest.raises(OutputError, match="report.md: a directory of that name is in the way"):
        publish_mod.publish(pairs, staged / ".replaced")
    assert _tree(out) == before


def test_a_previous_file_that_cannot_be_put_back_is_kept_and_named(tmp_path, monkeypatch):
    """The undo itself fails: the old file must not go with the staging folder (a review)."""
    out, staged, pairs = _setup(tmp_path)
    replace, calls = os.replace, []

    def failing(src, dst):
        calls.append((src, dst))
        if len(calls) == 4 or (len(calls) > 4 and str(src).endswith(os.sep + "0")):
            raise OSError(28, "No space left on device")     # the 4th move, then a.png's way back
        return replace(src, dst)

    monkeypatch.setattr(publish_mod.os, "replace", failing)
    with pytest.raises(OutputError, match=r"not every file of the previous report could be put back: they are in "
                                          r".*\.previous-report-\d+"):
        publish_mod.publish(pairs, staged / ".replaced")
    monkeypatch.setattr(publish_mod.os, "replace", replace)
    kept = next(out.glob(".previous-report-*"))
    assert (kept / "0").read_text() == "old figures/a.png"
