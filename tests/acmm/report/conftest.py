"""The report tests' HTML reader (section ids, images, links and the text of every table) and one
fast report a session (:func:`fast_report`)."""
from __future__ import annotations

import contextlib
import json
import shutil
from html.parser import HTMLParser
from pathlib import Path

import pytest

from acmm.report import build as build_mod


@pytest.fixture(scope="session")
def fast_report(tmp_path_factory):
    """``(base, report)``: ``acmm report --fast`` built once a session into ``base / "out"``, its
    stages computed in ``base / "runs"`` (about half a minute on 2 cores).  The tests that build a
    report of their own with ``--root`` on that folder reuse its stages (same configs, same root,
    same hashes) and run only the sections; none may change a file's contents there."""
    base = tmp_path_factory.mktemp("report")
    return base, build_mod.build_report(base / "out", fast=True, root=base / "runs")


@contextlib.contextmanager
def moved_aside(root: Path, *names: str):
    """The run folders ``names`` of results root ``root`` (the shared :func:`fast_report`'s) moved
    out of it inside the block and back after it, so that a report on ``root`` finds them absent:
    what it writes there, or reads from disk, shows.  A folder the block left in their place is
    removed first."""
    hold = root.parent / "aside"
    hold.mkdir(exist_ok=True)
    for name in names:
        (root / name).rename(hold / name)
    try:
        yield
    finally:
        for name in names:
            if (root / name).exists():
                shutil.rmtree(root / name)
            (hold / name).rename(root / name)


def manifest_stages(out: Path) -> set:
    """The stages a report in ``out`` lists in its ``manifest.json`` (``"qpp simulate:qpp_siso"``, ...)."""
    return set(json.loads((out / "manifest.json").read_text(encoding="utf-8"))["files"])


VOID = {"meta", "img", "br", "hr", "link", "input", "source", "wbr"}


class PageParser(HTMLParser):
    """Collects section ids, image sources, links and the text of every table."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.ids, self.imgs, self.links, self.tables = [], [], [], []
        self._cell = None
        self._stack = []

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag not in VOID:
            self._stack.append(tag)
        if tag in ("h2", "h3") and "id" in a:
            self.ids.append(a["id"])
        if tag == "img":
            self.imgs.append(a.get("src", ""))
        if tag == "a":
            self.links.append(a.get("href", ""))
        if tag == "table":
            self.tables.append({"caption": "", "rows": []})
        if tag == "tr":
            self.tables[-1]["rows"].append([])
        if tag in ("td", "th", "caption"):
            self._cell = []

    def handle_endtag(self, tag):
        assert self._stack and self._stack[-1] == tag, f"unbalanced </{tag}> (open: {self._stack[-3:]})"
        self._stack.pop()
        if tag in ("td", "th"):
            self.tables[-1]["rows"][-1].append("".join(self._cell).strip())
            self._cell = None
        if tag == "caption":
            self.tables[-1]["caption"] = "".join(self._cell).strip()
            self._cell = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)
