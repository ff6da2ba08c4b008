"""requirements.lock pins every direct dependency of pyproject.toml, with hashes, within its bounds,
and the README's dependency table says the versions the lock holds (``scripts/lock_table.py``)."""
import importlib.util

from packaging.markers import Marker, default_environment
from packaging.utils import canonicalize_name

from tests.conftest import REPO as ROOT

_spec = importlib.util.spec_from_file_location("lock_table", ROOT / "scripts" / "lock_table.py")
lock_table = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(lock_table)


def _applies(pin: dict, env: dict) -> bool:
    return pin["marker"] is None or Marker(pin["marker"]).evaluate(env)


def test_every_locked_package_is_an_exact_pin_with_hashes():
    pins = lock_table.locked()
    assert pins, "requirements.lock is empty"
    assert [name for name, entries in pins.items() if any(not p["hashes"] for p in entries)] == []


def test_every_direct_dependency_is_pinned_within_pyproject_bounds():
    """For this Python and for each Python the project supports (3.10 on, to 3.14), exactly one
    pin of each main and test dependency applies, and its version satisfies pyproject.toml."""
    pins = lock_table.locked()
    envs = [default_environment()]
    for minor in range(10, 15):
        envs.append({**default_environment(), "python_version": f"3.{minor}", "python_full_version": f"3.{minor}.0"})
    bad = []
    for req, _extras in lock_table.direct():
        entries = pins.get(canonicalize_name(req.name), [])
        for env in envs:
            applying = [p for p in entries if _applies(p, env)]
            if len(applying) != 1 or applying[0]["version"] not in req.specifier:
                bad.append(f"{req} on Python {env['python_full_version']}: {[p['version'] for p in applying]}")
    assert bad == [], "requirements.lock is stale: run make lock"


def test_readme_dependency_table_says_the_locked_versions():
    text = lock_table.README.read_text(encoding="utf-8")
    start, end, reasons = lock_table.readme_table(text)
    assert lock_table.NO_REASON not in text[start:end], "a dependency in README.md has no reason"
    assert text[start:end] == lock_table.table(reasons), \
        "README.md's dependency table differs from requirements.lock: python scripts/lock_table.py --write"
