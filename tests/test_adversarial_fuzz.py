"""Property-based fuzzing of the packaged configs (issue 13), with hypothesis.

Random edits (replace, delete, add keys; hostile numbers, strings, lists) of the packaged acmm,
qpp and sweep configs.  Properties: validation either accepts or raises a ConfigError (never
another exception, never a numpy/scipy warning); an accepted acmm config gives a finite TEA or
a reported AcmmError; the CLI refuses in one line with exit 2.  ~30 s in all.
"""
from __future__ import annotations

import copy
import math
import tempfile
import warnings
from pathlib import Path

import numpy as np
import pytest
import yaml

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from tests.conftest import CONFIGS  # noqa: E402

from acmm_qpp.errors import AcmmError, ConfigError  # noqa: E402

HOSTILE = st.one_of(
    st.none(), st.booleans(),
    st.integers(min_value=-10**40, max_value=10**40),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([1e308, -1e308, 1e-308, 5e-324, 0.0, -0.0, 1e300, 1e13, 1e12, 1e6, 2**63, -1]),
    st.text(max_size=12),
    st.sampled_from(["1e308", "nan", "inf", "1 kg", "3 slug*ft^2", "..", ".", "", "a\nb", "x" * 300,
                     "1e7 kg*m^2", "2 N*m", "-5 deg"]),
    st.lists(st.floats(allow_nan=True, allow_infinity=True), max_size=4),
    st.lists(st.lists(st.integers(-3, 3), max_size=3), max_size=3),
    st.dictionaries(st.text(max_size=4), st.integers(), max_size=2),
)


def _paths(node, prefix=()):
    out = [prefix] if prefix else []
    if isinstance(node, dict):
        for k, v in node.items():
            out += _paths(v, prefix + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            out += _paths(v, prefix + (i,))
    return out


@st.composite
def mutated(draw, name: str):
    base = yaml.safe_load((CONFIGS / f"{name}.yaml").read_text())
    d = copy.deepcopy(base)
    for _ in range(draw(st.integers(1, 3))):
        paths = _paths(d)
        if not paths:
            break
        path = draw(st.sampled_from(paths))
        parent = d
        for k in path[:-1]:
            parent = parent[k]
        op = draw(st.sampled_from(["scale", "scale", "set", "set", "delete", "add"]))
        leaf = parent[path[-1]]
        if op == "scale" and isinstance(leaf, (int, float)) and not isinstance(leaf, bool):
            # plausible-looking edits too, so that accepted configs are exercised further
            parent[path[-1]] = leaf * draw(st.sampled_from([-1, 1])) * 10.0 ** draw(st.integers(-14, 14))
        elif op in ("set", "scale"):
            parent[path[-1]] = draw(HOSTILE)
        elif op == "delete":
            del parent[path[-1]]
        elif isinstance(parent, dict):
            parent[draw(st.text(min_size=1, max_size=8))] = draw(HOSTILE)
        else:
            parent.append(draw(HOSTILE))
    return d


FUZZ = settings(max_examples=400, deadline=None, derandomize=True, database=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])


def _strict(fn, *args, **kwargs):
    """Call ``fn`` with every warning turned into an error (validation must never warn)."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        warnings.filterwarnings("ignore", category=DeprecationWarning)
        return fn(*args, **kwargs)


@pytest.mark.slow
@FUZZ
@given(mutated("mb3"))
def test_fuzz_acmm_config_accepts_or_refuses_cleanly(data):
    from acmm.io.config import parse_config
    from acmm.stages.runners import _compute_tea

    try:
        cfg = _strict(parse_config, data)
    except ConfigError as exc:
        assert str(exc)
        return
    try:
        with np.errstate(over="raise", invalid="raise", divide="raise"):
            t = _strict(_compute_tea, cfg).tea
    except AcmmError:
        return
    assert np.all(np.isfinite(t.theta)) and math.isfinite(t.residual)


@pytest.mark.slow
@settings(FUZZ, max_examples=300)
@given(mutated("qpp_siso"))
def test_fuzz_qpp_config_accepts_or_refuses_cleanly(data):
    from qpp.io.config import parse_config

    try:
        _strict(parse_config, data)
    except ConfigError as exc:
        assert str(exc)


@settings(FUZZ, max_examples=150)
@given(mutated("sweep_smoke"))
def test_fuzz_sweep_config_accepts_or_refuses_cleanly(data):
    from acmm.sweep.config import parse_sweep

    try:
        _strict(parse_sweep, data, directory=CONFIGS)
    except ConfigError as exc:
        assert str(exc)


@settings(FUZZ, max_examples=40)
@given(mutated("mb3"))
def test_fuzz_cli_sample_one_line(data):
    from typer.testing import CliRunner

    from acmm.cli.app import app

    with tempfile.TemporaryDirectory() as tmp:
        p = Path(tmp) / "c.yaml"
        p.write_text(yaml.safe_dump(data, allow_unicode=True))
        r = CliRunner().invoke(app, ["validate", str(p)])
        assert r.exit_code in (0, 2), (r.exit_code, r.stderr, r.exception)
        if r.exit_code == 2:
            assert len(r.stderr.splitlines()) == 1 and r.stderr.startswith("error: "), r.stderr
        else:
            assert r.stderr == ""
        assert sorted(x.name for x in Path(tmp).iterdir()) == ["c.yaml"]
