"""The user guide (docs/, MkDocs + mkdocstrings) builds with warnings as errors.

``make docs`` runs ``mkdocs build --strict``; here the same build goes into a temporary folder, so
a broken link, a page left out of the navigation, a docstring mkdocstrings cannot render or a
missing page fails the suite.  The build reads the packages' sources (griffe, no import) and
takes a few seconds.
"""
from __future__ import annotations

import re
import subprocess
import sys

import yaml

from tests.conftest import REPO

MKDOCS = REPO / "mkdocs.yml"


def _nav_pages(nav) -> list[str]:
    pages = []
    for item in nav:
        value = next(iter(item.values())) if isinstance(item, dict) else item
        pages += _nav_pages(value) if isinstance(value, list) else [value]
    return pages


def test_the_guide_builds_strict(tmp_path):
    """``mkdocs build --strict`` succeeds and writes every page of the navigation."""
    site = tmp_path / "site"
    out = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--config-file", str(MKDOCS),
                          "--site-dir", str(site)], cwd=REPO, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-4000:]
    assert "WARNING" not in out.stderr, out.stderr[-4000:]
    config = yaml.safe_load(MKDOCS.read_text(encoding="utf-8"))
    for page in _nav_pages(config["nav"]):
        html = site / (page.removesuffix(".md").removesuffix("index") + "/index.html").lstrip("/")
        if page == "index.md":
            html = site / "index.html"
        assert html.is_file(), page
    # the reference pages are rendered from the docstrings, not left as `::: module` text
    ref = (site / "reference" / "acmm" / "index.html").read_text(encoding="utf-8")
    assert "sector_design" in ref and ":::" not in ref


def test_every_page_is_in_the_navigation_and_uses_numpy_docstrings():
    """No page of docs/ is left out of the navigation, and mkdocstrings reads numpydoc."""
    config = yaml.safe_load(MKDOCS.read_text(encoding="utf-8"))
    nav = set(_nav_pages(config["nav"]))
    pages = {p.relative_to(REPO / "docs").as_posix() for p in (REPO / "docs").rglob("*.md")}
    assert pages - nav == set() and nav - pages == set()
    handler = next(p for p in config["plugins"] if isinstance(p, dict) and "mkdocstrings" in p)
    assert handler["mkdocstrings"]["handlers"]["python"]["options"]["docstring_style"] == "numpy"


def test_the_reference_pages_name_existing_public_modules():
    """Every ``::: module`` of the reference is a module of the packages, none private."""
    named = [m for p in (REPO / "docs").rglob("*.md")
             for m in re.findall(r"^::: ([\w.]+)$", p.read_text(encoding="utf-8"), re.M)]
    assert len(named) > 20
    missing = [m for m in named
               if not (REPO / (m.replace(".", "/") + ".py")).is_file() and not (REPO / m.replace(".", "/")).is_dir()]
    assert missing == [] and [m for m in named if any(part.startswith("_") for part in m.split("."))] == []


def test_the_guide_figures_are_small_and_referenced():
    """Every PNG under docs/img is under 200 kB and embedded by some page (or the README)."""
    images = sorted((REPO / "docs" / "img").glob("*.png"))
    assert images
    texts = "\n".join(p.read_text(encoding="utf-8") for p in [REPO / "README.md", *(REPO / "docs").rglob("*.md")])
    assert [p.name for p in images if p.stat().st_size >= 200 * 1024] == []
    assert [p.name for p in images if f"img/{p.name}" not in texts] == []
