"""The README's dependency table, its version column taken from requirements.lock.

One row per direct dependency of pyproject.toml (the main ones, then the test extra's): the
package, the version the lock holds (several when the lock holds one per Python range), and why
it is a dependency, the third column, kept as written in README.md.  ``tests/test_lock.py`` fails
while README.md's table differs from the one printed here, so a lock refreshed by ``make lock``
goes in with its README.

Usage: python scripts/lock_table.py            # print the table
       python scripts/lock_table.py --write    # put it in README.md (new rows get a placeholder)
"""
from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

from acmm.report.numbers import markdown_table

try:
    import tomllib
except ModuleNotFoundError:         # Python 3.10 (tomli is in the lock there: pytest's)
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[1]
LOCK = ROOT / "requirements.lock"
PYPROJECT = ROOT / "pyproject.toml"
README = ROOT / "README.md"
SECTION = "## Dependencies"
NO_REASON = "(why? say it here)"

_ENTRY = re.compile(r"^([A-Za-z0-9][A-Za-z0-9._-]*)==([^\s;\\]+)\s*(?:;\s*(.+?))?\s*\\?$")
_PYTHON = re.compile(r"python_full_version (<|<=|>=|>|==) '([0-9.]+?)(\.\*)?'")


def locked(path: Path = LOCK) -> dict[str, list[dict]]:
    """The lock's pins: canonical name -> [{"version", "marker" (None for all), "hashes"}]."""
    pins: dict[str, list[dict]] = {}
    entry = None
    for line in path.read_text(encoding="utf-8").splitlines():
        if line.startswith(("#", " ")) or not line.strip():
            if entry is not None and line.strip().startswith("--hash="):
                entry["hashes"].append(line.strip().removeprefix("--hash=").rstrip(" \\"))
            continue
        m = _ENTRY.match(line)
        if m is None:
            raise ValueError(f"{path.name}: not an exact pin: {line!r}")
        entry = {"version": m.group(2), "marker": m.group(3), "hashes": []}
        pins.setdefault(canonicalize_name(m.group(1)), []).append(entry)
    return pins


def direct(path: Path = PYPROJECT) -> list[tuple[Requirement, list[str]]]:
    """pyproject's main dependencies and the test extra's, each with the extras that name it."""
    project = tomllib.loads(path.read_text(encoding="utf-8"))["project"]
    extras = project.get("optional-dependencies", {})
    reqs = [Requirement(r) for r in project["dependencies"] + extras.get("test", [])]
    return [(r, [e for e, names in extras.items() if any(Requirement(n).name == r.name for n in names)])
            for r in reqs]


def _python_range(marker: str) -> str:
    """``python_full_version < '3.11'`` -> ``Python < 3.11``; any other marker as it is."""
    m = _PYTHON.fullmatch(marker)
    if m is None:
        return f"`{marker}`"
    op, version = m.group(1), m.group(2)
    return "Python " + ("" if op == "==" else {"<=": "≤", ">=": "≥"}.get(op, op) + " ") + version


def version_cell(pins: list[dict]) -> str:
    """``2.4.6``, or one version per Python range."""
    if len(pins) == 1 and pins[0]["marker"] is None:
        return pins[0]["version"]
    return ", ".join(p["version"] + (f" on {_python_range(p['marker'])}" if p["marker"] else "") for p in pins)


def readme_table(text: str) -> tuple[int, int, dict[str, str]]:
    """Where README's dependency table lies (start, end offsets) and its reasons by package."""
    start = text.index(SECTION)
    start = text.index("\n|", start) + 1
    end = start
    while text.startswith("|", end):
        end = text.index("\n", end) + 1
    reasons = {}
    for line in text[start:end].splitlines()[2:]:
        cells = [c.strip() for c in line.strip().strip("|").split("|", 2)]
        reasons[canonicalize_name(cells[0].split()[0].strip("`"))] = cells[-1]
    return start, end, reasons


def table(reasons: dict[str, str]) -> str:
    """The table (header, then one row per direct dependency), ending with a newline."""
    pins = locked()
    rows = []
    for req, extras in direct():
        name = canonicalize_name(req.name)
        if name not in pins:
            raise SystemExit(f"lock_table: {req.name} is not in {LOCK.name}: run make lock")
        where = "; ".join(("test extra" if e == "test" else f"`{e}` extra") for e in extras)
        label = req.name + (f" ({where})" if where else "")
        rows.append([label, version_cell(pins[name]), reasons.get(name, NO_REASON)])
    return markdown_table(["package", "locked", "why it earns its place"], rows)


def main(argv: list[str] | None = None) -> int:
    """Print the table, or write it into README.md with ``--write``."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true", help="replace the table in README.md")
    args = parser.parse_args(argv)
    text = README.read_text(encoding="utf-8")
    start, end, reasons = readme_table(text)
    new = table(reasons)
    if not args.write:
        sys.stdout.write(new)
        return 0
    README.write_text(text[:start] + new + text[end:], encoding="utf-8")
    if NO_REASON in new:
        print(f"lock_table: a new dependency has no reason yet: fill in {NO_REASON!r} in README.md")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
