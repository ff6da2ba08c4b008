"""The numbers README.md and the guide quote about the packaged configs equal a fresh run.

``scripts/readme_numbers.py`` writes the ``<!-- generated:NAME -->`` blocks of README.md and of the
guide's pages (``docs/**/*.md``, each block once across them) as the report computes them
(:mod:`acmm.report.pages`); here the same blocks are computed from a fresh run into a temporary results root
(designs of mb3, mb3_decoupled, ac and the stair-case, their simulations, the qpp designs and
simulations of the two report chapters and the three shipped examples, the search over procedure
12.1's family of the two chapters, the 400-case ``sweep_inertia30`` Monte Carlo and margin search,
once a session: :func:`tests.conftest.readme_stages`) and compared
with the documents, so a code change that moves a number fails here until ``make readme`` is run.
"""
from __future__ import annotations

import numpy as np
import pytest

from acmm.model import linearize as lin
from acmm.model.tea import solve_tea_near
from acmm.report.build import build_report
from acmm.report.pages import BLOCKS
from tests.acmm.report.conftest import PageParser
from tests.conftest import REPO, readme_script

#: the tests that compare with a fresh run of every packaged config (several minutes): `make test-slow`, run by CI;
#: the others read only text
slow = pytest.mark.slow


rn = readme_script()


@pytest.fixture(scope="module")
def fresh(readme_stages) -> dict:
    """Every generated block, computed from the fresh stages (:func:`tests.conftest.readme_stages`)."""
    return {name: block(readme_stages) for name, block in BLOCKS.items()}


def texts() -> dict:
    """README.md and every page of docs/, path → text."""
    return rn.read_texts()


def _holding(all_texts: dict, name: str):
    """The document that holds block ``name``."""
    return next(p for p, t in all_texts.items() if f"<!-- generated:{name} -->" in t)


@slow
def test_readme_blocks_equal_a_fresh_run(fresh):
    """Every block the script writes is in README.md or docs/ exactly once and holds the fresh run's text."""
    assert sorted(fresh) == sorted(BLOCKS)
    assert sorted(rn.locate_blocks(texts())) == sorted(BLOCKS)
    assert rn.check(texts(), fresh) == []


@slow
def test_a_wrong_digit_in_the_claims_table_fails(fresh):
    """One digit changed in a claims-table cell (the MB3 Monte Carlo count) is rejected and named."""
    all_texts = texts()
    path = _holding(all_texts, "claims")
    body = rn.locate_blocks(all_texts)["claims"][1]
    cell = next(line for line in body.splitlines() if "±30 %" in line)
    count = cell.split("MB3 **")[1].split("/")[0]
    wrong = str(int(count) + 1)
    bad_body = body.replace(cell, cell.replace(f"MB3 **{count}/", f"MB3 **{wrong}/"))
    assert bad_body != body
    bad = {**all_texts, path: all_texts[path].replace(body, bad_body)}
    problems = rn.check(bad, fresh)
    assert len(problems) == 1 and problems[0].startswith("claims:") and f"**{wrong}/" in problems[0]
    # and the rewrite puts the computed number back, in the document that holds the block
    assert rn.replace_blocks(bad, fresh) == rn.replace_blocks(all_texts, fresh)


@slow
def test_a_missing_block_fails(fresh):
    """A document that lost a block's markers is rejected, and cannot be rewritten silently."""
    all_texts = texts()
    path = _holding(all_texts, "sweep_margin")
    lost = {**all_texts, path: all_texts[path].replace("<!-- generated:sweep_margin -->", "")}
    assert rn.check(lost, fresh) == ["sweep_margin: no <!-- generated:sweep_margin --> block in README.md or docs/"]
    with pytest.raises(ValueError, match="sweep_margin"):
        rn.replace_blocks(lost, fresh)


# ------------------------------------------------------------------ where blocks may live (no runs)
def _page(tmp_path, name, text):
    path = tmp_path / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return path


def test_blocks_are_found_in_any_document_and_rewritten_there(tmp_path):
    """A block in README.md and another in a page of the guide are both found, checked and
    rewritten in the file that holds each."""
    readme = _page(tmp_path, "README.md", "a\n<!-- generated:one -->\nold 1\n<!-- /generated:one -->\n")
    page = _page(tmp_path, "docs/how/page.md", "b\n<!-- generated:two -->\nold 2\n<!-- /generated:two -->\nc\n")
    all_texts = rn.read_texts([readme, page])
    assert {k: v[0] for k, v in rn.locate_blocks(all_texts).items()} == {"one": readme, "two": page}
    blocks = {"one": "new 1\n", "two": "new 2\n"}
    assert [line.split(":")[0] for line in rn.check(all_texts, blocks)] == ["one", "two"]
    new = rn.replace_blocks(all_texts, blocks)
    assert new[page] == "b\n<!-- generated:two -->\nnew 2\n<!-- /generated:two -->\nc\n"
    assert rn.check(new, blocks) == []


def test_a_block_in_two_documents_is_refused(tmp_path):
    one = _page(tmp_path, "README.md", "<!-- generated:one -->\nx\n<!-- /generated:one -->\n")
    two = _page(tmp_path, "docs/a.md", "<!-- generated:one -->\nx\n<!-- /generated:one -->\n")
    all_texts = rn.read_texts([one, two])
    with pytest.raises(ValueError, match="appears twice"):
        rn.locate_blocks(all_texts)
    assert "appears twice" in rn.check(all_texts, {"one": "x\n"})[0]


def test_the_documents_are_the_readme_and_every_page_of_the_guide():
    docs = rn.documents()
    assert docs[0] == REPO / "README.md"
    assert set(docs[1:]) == set((REPO / "docs").rglob("*.md")) and len(docs) > 5


def _blend_poles(cfg, d, coef, count: int = 101) -> np.ndarray:
    """Poles / n of the scheduled local loop at ``count`` points of the stair-case's blend, with
    our own blend (TEA of the blended inertia and bias, local model, np.polyval of ``coef``)."""
    n = cfg.orbit_rate
    inertia, bias, theta = d["inertia"], d["bias"], d["tea"][0]
    out = []
    for s in np.linspace(0.0, 1.0, count):
        theta = solve_tea_near((1 - s) * inertia[0] + s * inertia[-1], n, (1 - s) * bias[0] + s * bias[-1],
                               theta).theta
        m = lin.design_point((1 - s) * inertia[0] + s * inertia[-1], theta, n, model=cfg.design.model,
                             drf_mode=cfg.design.drf_mode)
        K = np.array([[np.polyval(coef[::-1, i, j], theta[1]) for j in range(24)] for i in range(3)])
        out.append(np.linalg.eigvals(m.A - m.B @ K) / n)
    return np.array(out)


@slow
def test_converged_quadratic_holds_the_decay_and_the_momentum_target(readme_stages):
    """Issue 41 item 4, on the routes table's ``staircase_quadratic`` run: the report's form
    (one quadratic in θ2* per gain element) started from the regional LMI points' least-squares
    fit, whose loop is unstable, and converged by Newton's method on the path's shifted LQR cost
    (``schedule.fit: shifted_lqr``).  Every local loop on the 1 001 path TEAs has Re λ ≤ −0.25n —
    the design's own check, and here with our own blend at 101 points, where every pole is also
    inside the 70° cone about −0.3n — and no level of the 130-orbit stair-case peaks above
    6 000 ft·lbf·s."""
    cfg, d, sim = (readme_stages[f"{k}:staircase_quadratic"] for k in ("config", "design", "simulate"))
    sc = d["schedule"]
    method = sc["fit_method"]
    assert (method.decode() if isinstance(method, bytes) else str(method)) == "shifted_lqr"
    assert float(sc["refit_converged"]) == 1.0 and float(sc["refit_accepted"]) == 1.0
    assert float(sc["refit_max_real_before"]) > 0
    path = sc["path"]
    assert path["theta2"].size == 1001 and path["max_real"].max() <= -0.25
    lam = _blend_poles(cfg, d, sc["coef"])
    assert lam.real.max() <= -0.25
    shifted = lam + float(sc["refit_decay"])
    assert np.all(np.abs(shifted.imag) < np.tan(np.radians(float(sc["refit_cone_deg"]))) * -shifted.real)
    peak = sim["levels"]["peak_momentum"]
    assert peak.size == 12 and peak.max() <= 6000.0
    assert sim["attrs"]["verdict"] in ("bounded", b"bounded")


@slow
def test_the_report_shows_the_schedule_forms_side_by_side_from_the_same_runs(readme_root, readme_stages, tmp_path):
    """Issue 41 item 4: the full ``acmm report`` on the README's results root takes its runs (the
    converged quadratic is not designed again: its ``design.h5`` is the same file) and shows the
    packaged table, the report's route and the report's quadratic form converged on the path side
    by side, each row's largest Re λ, path count in the sector and peak momentum those files'; the
    gain-schedule figure draws the quadratic beside the table."""
    quadratic = readme_root / "staircase_quadratic" / "design.h5"
    before = quadratic.stat().st_mtime_ns
    r = build_report(tmp_path / "out", root=readme_root)
    assert quadratic.stat().st_mtime_ns == before
    page = PageParser()
    page.feed(r.html.read_text(encoding="utf-8"))
    page.close()
    table = [t for t in page.tables if t["caption"].startswith("The design routes and schedule forms")]
    rows = table[0]["rows"]
    assert len(rows) == 4 and "--fast" not in table[0]["caption"]
    for row, name, form in zip(rows[1:], ("staircase", "staircase_lqr", "staircase_quadratic"),
                               ("regional LMI points, table", "sector LQR points, table",
                                "regional LMI points, quadratic converged on the path")):
        path = readme_stages[f"design:{name}"]["schedule"]["path"]
        margin = np.asarray(path["sector_margin"])
        assert row[0].startswith(form) and f"`{name}`" in row[0]
        assert float(row[5]) == pytest.approx(np.max(path["max_real"]), abs=5e-4)
        assert row[6] == f"{np.sum(margin >= 0)} of {margin.size}"
        assert float(row[7]) == pytest.approx(np.max(readme_stages[f"simulate:{name}"]["levels"]["peak_momentum"]), abs=0.5)
    assert rows[3][6].startswith("0 of ") and rows[1][6] == "1001 of 1001"
    assert "the report's quadratic form converged on the path (dashed)" in r.markdown.read_text(encoding="utf-8")

