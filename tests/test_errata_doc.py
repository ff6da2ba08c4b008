"""docs/ERRATA.md is the repository's own record of the report's misprints and conventions.

Every test it names as evidence must exist and every section it lists must be present (that no
source cites a document outside the repository is checked in ``tests/test_layers.py``).
"""
import ast
import re
from pathlib import Path

from tests.conftest import REPO as ROOT

ERRATA = ROOT / "docs" / "ERRATA.md"


def _tests_defined(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    return {n.name for n in tree.body if isinstance(n, ast.FunctionDef) and n.name.startswith("test_")}


def _evidence() -> list[tuple[str, str]]:
    """(file, test) pairs named in the document; a bare test name belongs to the last file named."""
    pairs, current = [], None
    for token in re.findall(r"`([^`]+)`", ERRATA.read_text(encoding="utf-8")):
        m = re.fullmatch(r"(tests/(?:\w+/)*test_\w+\.py)::(test_\w+)", token)
        if m:
            current = m.group(1)
            pairs.append((current, m.group(2)))
        elif re.fullmatch(r"test_\w+", token):
            assert current is not None, f"test {token} named before any test file"
            pairs.append((current, token))
    return pairs


def test_every_named_test_exists():
    pairs = _evidence()
    assert len(pairs) >= 40
    missing = [f"{f}::{t}" for f, t in pairs if t not in _tests_defined(ROOT / f)]
    assert not missing, missing


def test_every_listed_section_has_a_heading():
    text = ERRATA.read_text(encoding="utf-8")
    listed = re.search(r"Section names used in citations:(.*?)\n\n", text, re.S).group(1)
    names = re.findall(r"\*\*([^*]+)\*\*", listed)
    headings = set(re.findall(r"^### (.+)$", text, re.M))
    assert len(names) >= 15 and set(names) == headings, set(names) ^ headings
