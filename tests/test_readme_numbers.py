"""The README's numbers about the packaged configs equal a fresh run (issue 30, item 4).

``scripts/readme_numbers.py`` writes the ``<!-- generated:NAME -->`` blocks of README.md from the
stages' results; here the same blocks are computed from a fresh run into a temporary results root
(designs of mb3, mb3_decoupled, ac and the stair-case, their simulations, the qpp designs and
simulations of the two report chapters and the three shipped examples, the 400-case
``sweep_inertia30`` Monte Carlo and margin search, once per module) and compared
with the README, so a code change that moves a number fails here until ``make readme`` is run.
"""
from __future__ import annotations

import importlib.util

import pytest

from tests.conftest import REPO

pytestmark = pytest.mark.slow      # runs every packaged config (~40 s): `make test-slow`, run by CI


def _script():
    spec = importlib.util.spec_from_file_location("readme_numbers", REPO / "scripts" / "readme_numbers.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


rn = _script()


@pytest.fixture(scope="module")
def fresh(tmp_path_factory) -> dict:
    """Every generated block, computed from stages run into an empty results root."""
    return rn.compute_blocks(rn.run_stages(tmp_path_factory.mktemp("readme-root")))


def readme() -> str:
    """README.md and docs/*.md (a block lives in exactly one of them)."""
    return rn.docs_text()


def test_readme_blocks_equal_a_fresh_run(fresh):
    """Every block the script writes is in README.md or a docs/*.md page once and holds the fresh
    run's text."""
    assert sorted(fresh) == sorted(rn.BLOCKS)
    assert sorted(rn.read_blocks(readme())) == sorted(rn.BLOCKS)
    assert rn.check(readme(), fresh) == []


def test_a_wrong_digit_in_the_claims_table_fails(fresh):
    """One digit changed in a claims-table cell (the MB3 Monte Carlo count) is rejected and named."""
    text = readme()
    body = rn.read_blocks(text)["claims"]
    cell = next(line for line in body.splitlines() if "±30 %" in line)
    count = cell.split("MB3 **")[1].split("/")[0]
    wrong = str(int(count) + 1)
    bad_body = body.replace(cell, cell.replace(f"MB3 **{count}/", f"MB3 **{wrong}/"))
    assert bad_body != body
    bad = text.replace(body, bad_body)
    problems = rn.check(bad, fresh)
    assert len(problems) == 1 and problems[0].startswith("claims:") and f"**{wrong}/" in problems[0]
    # and the rewrite puts the computed number back
    assert rn.replace_blocks(bad, fresh) == rn.replace_blocks(text, fresh)


def test_a_missing_block_fails(fresh):
    """A README that lost a block's markers is rejected, and cannot be rewritten silently."""
    text = readme().replace("<!-- generated:sweep_margin -->", "")
    assert rn.check(text, fresh) == ["sweep_margin: no <!-- generated:sweep_margin --> block in README.md or docs/*.md"]
    with pytest.raises(ValueError, match="sweep_margin"):
        rn.replace_blocks(text, fresh)


@pytest.mark.parametrize("x, digits, text", [(3986.2, 3, "3 990"), (6644.9, 3, "6 640"), (0.03812, 3, "0.0381"),
                                             (-1.964, 3, "\u22121.96"), (9.996, 3, "10.0"), (0.0495, 2, "0.050"),
                                             (130.0, 3, "130")])
def test_significant_digits(x, digits, text):
    assert rn.sig(x, digits) == text


def test_scientific_and_fixed():
    assert rn.sci(48396.1) == "4.8e4"
    assert rn.sci(2.43e-6) == "2.4e\u22126"
    assert rn.fixed(-0.46802) == "\u22120.468"
    assert rn.fixed(5.0916, 2, sign=True) == "+5.09"
    assert rn.fixed(-0.0001) == "0.000"
