"""``acmm report`` (issue 8, acmm.report.build): the fast report end to end, its HTML, its numbers
and determinism; a report that cannot be written, or whose sections fail, and the user's run
folders it leaves alone.

One fast report is built into a temporary directory (:func:`tests.acmm.report.conftest.fast_report`,
once a session); the other tests read it, and the tests of a failing part build theirs on its
stages.  Numbers are checked against the report's printed values (Table 1, the
ch. 13/14 gains) or against independent closed forms (the MB3 gravity-gradient capacity, the
printed eq 3.6 residual of eq 4.2).
"""
from __future__ import annotations

import base64
import hashlib
import math
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest

from acmm.report import build as build_mod
from acmm.report import constants as constants_mod
from acmm.report import gather as gather_mod
from acmm.report.gather import ensure_qpp
from acmm.report import ledger as ledger_mod
from acmm.report import manifest as manifest_mod
from acmm_qpp.errors import ConvergenceError

from tests.conftest import invoke
from tests.acmm.report.conftest import PageParser, manifest_stages, moved_aside

pytestmark = pytest.mark.slow      # a whole `acmm report --fast` per session: `make test-slow`


N = 0.0011
MB3 = np.array([[23.22e6, -0.023e6, 0.477e6], [-0.023e6, 1.30e6, -0.011e6], [0.477e6, -0.011e6, 23.23e6]])


@pytest.fixture(scope="module")
def page(fast_report):
    _, r = fast_report
    p = PageParser()
    p.feed(r.html.read_text(encoding="utf-8"))
    p.close()
    return p


def _table(page, caption_start):
    t = [t for t in page.tables if t["caption"].startswith(caption_start)]
    assert t, [x["caption"] for x in page.tables]
    return t[0]["rows"]


# ----------------------------------------------------------------------------- structure
def test_every_section_present_in_html_and_markdown(fast_report, page):
    _, r = fast_report
    keys = [k for k, _ in constants_mod.SECTIONS]
    assert page.ids == keys
    md = r.markdown.read_text(encoding="utf-8")
    for _, title in constants_mod.SECTIONS:
        assert f"## {title}" in md
    assert page._stack == []                      # every tag closed


def test_every_image_is_embedded_or_exists(fast_report, page):
    _, r = fast_report
    assert len(page.imgs) >= 10
    for src in page.imgs:
        if src.startswith("data:image/png;base64,"):
            assert base64.b64decode(src.split(",", 1)[1])[:8] == b"\x89PNG\r\n\x1a\n"
        else:
            assert (r.html.parent / src).is_file(), src
    local = [h for h in page.links if not h.startswith(("#", "http", "data:"))]
    assert any(h.endswith(".pdf") for h in local)
    for h in local:
        assert (r.html.parent / h).is_file(), h
    for pdf in (r.out / "figures").glob("*.pdf"):
        assert pdf.read_bytes()[:5] == b"%PDF-"
    # the Markdown references only files that exist
    for ref in re.findall(r"\]\((figures/[^)]+)\)", r.markdown.read_text(encoding="utf-8")):
        assert (r.out / ref).is_file(), ref


# ----------------------------------------------------------------------------- numbers
def test_table1_computed_teas_round_to_printed(page):
    rows = _table(page, "Table 1: printed vs computed")
    header, body = rows[0], rows[1:]
    ip, ic, ist = header.index("printed"), header.index("computed"), header.index("status")
    printed_tea = {("MB3", 1): 1.3, ("MB3", 2): -44.7, ("MB3", 3): 2.1,
                   ("AC", 1): 0.19, ("AC", 2): -5.0, ("AC", 3): 0.56}
    seen = 0
    for row in body:
        m = re.match(r"θ(\d)\* \(deg\)", row[1])
        if m:
            want = printed_tea[(row[0], int(m.group(1)))]
            dec = len(row[ip].split(".")[1])
            assert float(row[ip]) == want
            assert round(float(row[ic]), dec) == pytest.approx(want, abs=1e-12)
            assert row[ist] == ledger_mod.STATUS_MATCHED
            seen += 1
        else:
            assert float(row[ic]) == pytest.approx(float(row[ip]), abs=1e-12)
    assert seen == 6


def test_qpp_gains_match_printed_to_one_decimal(page):
    for cap, printed in (("Ch. 13 gains", {"K1(1, 1)": -299.9, "K1(1, 2)": -23.5, "Kc(1, 1)": 2506.2,
                                           "Kc(1, 2)": 1937.1}),
                         ("Ch. 14 gains", {"K1(1, 1)": -202.9, "K1(2, 2)": -108.4, "Kc(1, 1)": 1020.4,
                                           "Kc(2, 3)": 466.9})):
        rows = {r[0]: r for r in _table(page, cap)[1:]}
        for k, v in printed.items():
            assert float(rows[k][1]) == v
            assert abs(float(rows[k][2]) - v) <= 0.05 + 1e-9
            assert rows[k][3] == ledger_mod.STATUS_MATCHED


def test_every_printed_number_matched_or_explained(fast_report, page):
    _, r = fast_report
    assert [p for p in r.ledger if p.status == ledger_mod.STATUS_UNEXPLAINED] == []
    statuses = [p.status for p in r.ledger]
    assert statuses.count(ledger_mod.STATUS_MATCHED) >= 20
    # the inertias of Table 1 are inputs echoed back: shown, never counted as matched (issue 34)
    assert not [p for p in r.ledger if p.section == "Table 1" and p.quantity.split()[-1].startswith("I")]
    ledger_rows = [t for t in page.tables if t["rows"] and t["rows"][0][:3] == ["section", "quantity", "printed"]]
    assert len(ledger_rows) == 1 and len(ledger_rows[0]["rows"]) - 1 == len(r.ledger)
    for row in ledger_rows[0]["rows"][1:]:
        assert row[-1].startswith((ledger_mod.STATUS_MATCHED, ledger_mod.STATUS_BOUND, ledger_mod.STATUS_EXPLAINED + ": ")), row


def test_claim1_numbers_come_from_the_simulation(fast_report, page):
    import h5py

    base, r = fast_report
    with h5py.File(base / "runs" / "mb3_decoupled" / "sim.h5", "r") as f:
        div = float(f.attrs["stop_time_orbits"])
        assert f.attrs["verdict"] == "diverged"
    with h5py.File(base / "runs" / "mb3" / "sim.h5", "r") as f:
        assert f.attrs["verdict"] == "bounded"
    assert div < 0.1
    rows = _table(page, "Claim 1 on the nonlinear MB3 model")
    assert rows[0][3] == "Riccati backward error"
    assert rows[2][4] == "DIVERGED" and float(rows[2][5]) == pytest.approx(div, abs=5e-4)
    assert rows[1][4] == "BOUNDED"
    assert all(float(r[3]) <= 1e-12 for r in rows[1:])      # accepted on it (the residual is not)
    assert "claim 1 REPRODUCED" in r.markdown.read_text(encoding="utf-8")


def test_the_design_routes_side_by_side_come_from_their_runs(fast_report, page):
    """The report shows the packaged stair-case (regional LMI points, table) beside the report's
    route (issue 32 item 5): each row's κ, path count in the sector and peak CMG momentum read
    back from its own files; a --fast report says it leaves the quadratic out (the full report's
    three rows: tests/test_readme_numbers.py)."""
    import h5py

    base, _ = fast_report
    table = [t for t in page.tables if t["caption"].startswith("The design routes and schedule forms")]
    assert table and "the quadratic is not designed by a --fast report" in table[0]["caption"]
    rows = table[0]["rows"]
    assert len(rows) == 3 and "regional LMI points, table" in rows[1][0] and "sector LQR points, table" in rows[2][0]
    for row, name in zip(rows[1:], ("staircase_fast", "staircase_fast_lqr")):
        with h5py.File(base / "runs" / name / "design.h5", "r") as f:
            kappa = max(float(f["points"][k]["max_eig_condition"][()]) for k in f["points"])
            margin = f["schedule/path/sector_margin"][()]
        with h5py.File(base / "runs" / name / "sim.h5", "r") as f:
            peak = float(np.max(f["levels/peak_momentum"][()]))
        assert float(row[1]) == pytest.approx(kappa, rel=0.05) and float(row[7]) == pytest.approx(peak, abs=0.5)
        assert row[6] == f"{np.sum(margin >= 0)} of {margin.size}"
    assert float(rows[1][1]) <= 2e4 < float(rows[2][1])          # the LMI points are the better conditioned


def test_errata_table_carries_independent_evidence(page):
    rows = {r[0]: r for r in [t for t in page.tables if t["rows"] and t["rows"][0][0] == "item"][0]["rows"][1:]}
    for key in ("eq 3.6 (1,1) entry", "4 ft·lbf pitch bias (Wie et al. 1989)", "eq 4.34 A2(3,1)",
                "eq 4.44 DRF input rows", "eq 5.6 sign iteration", "state scaling", "claim 1",
                "eqs 4.12–4.14 ∂τgg/∂θ", "B_z of 13.6 / Table 14.1", "β3 (10.54) and m"):
        assert key in rows, sorted(rows)
        assert rows[key][3] and rows[key][4].startswith("tests/")
    # MB3's pitch capacity in closed form: 3n² sqrt(((I33 − I11)/2)² + I13²)
    cap = 3 * N**2 * math.hypot((MB3[2, 2] - MB3[0, 0]) / 2, MB3[0, 2])
    assert f"{cap:.3f} ft·lbf < 4" in rows["4 ft·lbf pitch bias (Wie et al. 1989)"][3]
    assert "no equilibrium" in rows["4 ft·lbf pitch bias (Wie et al. 1989)"][3]
    # printed eq 3.6 residual of eq 4.2 in row 1: n sin θ3 (1 − 1/cos θ3) at (10°, −30°, 25°)
    t3 = math.radians(25.0)
    assert f"{abs(N * math.sin(t3) * (1 - 1 / math.cos(t3))):.2e} rad/s" in rows["eq 3.6 (1,1) entry"][3]
    # A2(3,1) at the MB3 TEA (1.3°, −44.7°, 2.1°): −n cos θ1 cos θ3, printed sign breaks skewness by 2|·|
    a231 = N * math.cos(math.radians(1.3)) * math.cos(math.radians(2.1))
    assert f"{2 * a231:.3e} rad/s" in rows["eq 4.34 A2(3,1)"][3]
    assert "UNSTABLE on the true model" in rows["eq 4.34 A2(3,1)"][3]
    assert "UNSTABLE on the true model" in rows["eq 4.44 DRF input rows"][3]
    assert "printed form — matrix sign" in rows["eq 5.6 sign iteration"][3]
    # 0.05 ‖(sin 5t)_T‖₂ at T = 0.5 s, closed form
    b3 = 0.05 * math.sqrt(0.25 - math.sin(5.0) / 20)
    assert f"{b3:.5f}" in rows["β3 (10.54) and m"][3]


def test_robustness_section(fast_report, page, monkeypatch):
    _, r = fast_report
    md = r.markdown.read_text(encoding="utf-8")
    try:
        import acmm.sweep  # noqa: F401
        have = True
    except ImportError:
        have = False
    if have:
        rows = _table(page, "±30 % inertia Monte Carlo")
        assert [x[0] for x in rows[1:]] == ["MB3", "AC"]
        for x in rows[1:]:
            nb, tot = map(int, re.match(r"(\d+)/(\d+)", x[1]).groups())
            assert tot == gather_mod.FAST_SWEEP_RUNS and 0 <= nb <= tot
    else:
        assert "Not available in this run" in md


# ----------------------------------------------------------------------------- determinism
def test_two_runs_give_identical_datasets(fast_report, tmp_path):
    """Recompute the cheap stages into a fresh root; every dataset hash equals the report's."""
    import json

    _, r = fast_report
    manifest = json.loads(r.manifest.read_text())
    cfgs = {n: gather_mod.acmm_config(n, tmp_path) for n in ("mb3", "mb3_decoupled")}
    fresh = [gather_mod.ensure_acmm_design(cfgs["mb3"], rerun=True), gather_mod.ensure_acmm_simulation(cfgs["mb3"], rerun=True),
             gather_mod.ensure_acmm_simulation(cfgs["mb3_decoupled"], rerun=True)]
    q = gather_mod.qpp_config("qpp_siso", tmp_path)
    fresh += [gather_mod.ensure_qpp(q, "design", rerun=True), gather_mod.ensure_qpp(q, "simulate", rerun=True)]
    compared = 0
    for run in fresh:
        assert not run.reused
        old = manifest["files"][f"{run.stage}:{run.config}"]
        # (config hashes differ: the resolved config records its results root)
        new = manifest_mod.dataset_hashes(run.path)
        assert new == old["datasets"]
        compared += len(new)
    assert compared > 100
    # the comparison the report prints: identical, then a changed dataset is reported
    same = manifest_mod.compare_manifests(manifest, manifest)
    assert same["status"] == "identical" and same["compared"] > compared
    changed = json.loads(json.dumps(manifest))
    key = "acmm simulate:mb3"
    ds = sorted(changed["files"][key]["datasets"])[0]
    changed["files"][key]["datasets"][ds] = "0" * 16
    diff = manifest_mod.compare_manifests(manifest, changed)
    assert diff["status"] == "different" and diff["differences"] == [f"{key}: {ds}"]
    assert manifest_mod.compare_manifests(None, manifest)["status"] == "no previous report"
    # a previous report of other results (another root: other config hashes) is no evidence:
    # it said "identical (0 datasets compared)"
    other = json.loads(json.dumps(manifest))
    for f in other["files"].values():
        f["config_hash"] = "x" + f["config_hash"]
    none = manifest_mod.compare_manifests(other, manifest)
    assert none["status"] == "nothing comparable" and none["compared"] == 0


# ----------------------------------------------------------------------------- real browser
CHROMIUM = Path("/usr/bin/chromium")


@pytest.mark.skipif(not CHROMIUM.exists(), reason="no /usr/bin/chromium on this machine")
def test_headless_chromium_screenshot(fast_report, tmp_path):
    _, r = fast_report
    shot = tmp_path / "page.png"
    subprocess.run([str(CHROMIUM), "--headless", "--disable-gpu", "--no-sandbox", "--hide-scrollbars",
                    "--disable-quic", "--no-first-run", "--disable-background-networking",
                    "--disable-component-update", "--disable-sync", f"--user-data-dir={tmp_path / 'profile'}",
                    f"--screenshot={shot}", "--window-size=1200,2400", r.html.resolve().as_uri()],
                   check=True, timeout=120, capture_output=True)
    data = shot.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 20_000
    from matplotlib.image import imread

    img = imread(shot)
    assert img.shape[0] >= 1000 and np.std(img[..., :3]) > 0.05        # not a blank page


@pytest.mark.slow
def test_a_report_that_cannot_be_written_leaves_out_as_it_was(fast_report, tmp_path):
    """A directory in the way of one page: the figures, the manifest and the other pages stay
    the previous report's (they were replaced before the failing write: a review)."""
    import hashlib
    import shutil

    from acmm_qpp.errors import OutputError

    base, r = fast_report
    out = tmp_path / "out"
    shutil.copytree(r.out, out)
    (out / "report.md").unlink()
    (out / "report.md").mkdir()

    def tree():
        return {p.relative_to(out).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest() if p.is_file() else "/"
                for p in sorted(out.rglob("*"))}

    before = tree()
    with pytest.raises(OutputError, match="report.md: a directory of that name is in the way"):
        build_mod.build_report(out, fast=True, root=base / "runs")
    assert tree() == before


def _tree(folder: Path) -> dict:
    """Relative path → SHA-256 of every file under ``folder`` (folders as ``"/"``)."""
    return {p.relative_to(folder).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest() if p.is_file() else "/"
            for p in sorted(folder.rglob("*"))}


def test_report_leaves_the_users_run_folders_byte_identical(tmp_runs):
    """A user's ``runs/qpp_siso/`` with figures (``qpp design`` and ``qpp simulate`` as the user
    runs them): after ``acmm report --fast`` every file there is the same, none added or removed,
    and no other ``runs/<name>/`` appeared; the report's stages ran in ``runs/report/results``."""
    from acmm.cli.app import app as acmm_app
    from qpp.cli import app as qpp_app

    for stage in ("design", "simulate"):
        res = invoke(qpp_app, stage, "qpp_siso")
        # ch. 13 carries no consistent certificate: `qpp design` writes it labelled uncertified, exit 3
        assert res.exit_code == (3 if stage == "design" else 0), res.output
    user = tmp_runs / "runs" / "qpp_siso"
    before = _tree(user)
    assert any(k.endswith(".png") or k.endswith(".pdf") for k in before), sorted(before)   # figures made
    res = invoke(acmm_app, "report", "--fast", "--jobs", "1")
    assert res.exit_code == 0, res.output
    assert _tree(user) == before
    assert sorted(p.name for p in (tmp_runs / "runs").iterdir()) == ["qpp_siso", "report"]
    own = tmp_runs / "runs" / "report" / "results"
    assert (own / "qpp_siso" / "qpp_design.h5").is_file() and (own / "qpp_siso" / "qpp_sim.h5").is_file()
    assert "runs/report/results/" in (tmp_runs / "runs" / "report" / "report.md").read_text(encoding="utf-8")


def _failing_text14(ctx):
    raise ConvergenceError("injected: the chapter 14 solver did not converge")


def test_a_failed_section_is_shown_and_the_others_complete(fast_report, tmp_path, monkeypatch):
    """One section part raising a user-facing error (the first part of QPP chapter 14): the
    report is written, that section shows its heading and the one-line error, every other
    section is there with its content, and the command exits with the error's code (3) on one
    ``error:`` line.  (The stages are the session's fast report's, reused.)"""
    import acmm.report.plan as plan
    from acmm.cli.app import app
    from acmm.report.constants import SECTIONS

    parts = [(p[0], p[1], _failing_text14, *p[3:]) if p[0] == "qpp14" else p for p in plan.PARTS]
    monkeypatch.setattr(plan, "PARTS", parts)
    out = tmp_path / "out"
    res = invoke(app, "report", "--fast", "--jobs", "2", "--out", out, "--root", fast_report[0] / "runs")
    assert res.exit_code == 3, res.output
    last = res.output.strip().splitlines()[-1]
    assert last.startswith("error: report incomplete:") and "injected: the chapter 14 solver" in last
    assert "Traceback" not in res.output
    md = (out / "report.md").read_text(encoding="utf-8")
    for _, title in SECTIONS:
        assert f"## {title}" in md, title
    q14 = md.split("## QPP chapter 14")[1].split("\n## ")[0]
    assert "FAILED — qpp14 failed: injected: the chapter 14 solver did not converge." in q14
    q13 = md.split("## QPP chapter 13")[1].split("\n## ")[0]
    assert "FAILED" not in q13 and "|" in q13                   # its tables are there
    assert md.count("FAILED — ") == 1                           # nothing else failed
    assert "injected: the chapter 14 solver" in (out / "index.html").read_text(encoding="utf-8")


def _broken_qpp_design(cfg, stage, rerun):
    if stage == "design" and cfg.name == "qpp_manipulator":
        raise ConvergenceError("injected: qpp design of qpp_manipulator did not converge")
    return ensure_qpp(cfg, stage, rerun)


def test_a_failed_stage_fails_only_the_sections_that_read_it(fast_report, tmp_path, monkeypatch):
    """A stage raising (the chapter-14 qpp design, in a worker): its simulation is not run, the
    chapter-14 parts show the error, chapter 13 and the rest are complete, exit 3.  (The other
    stages are the session's fast report's, reused.)"""
    import sys

    from acmm.cli.app import app

    gather_mod = sys.modules["acmm.report.gather"]     # (acmm.report.gather the attribute is the function)
    monkeypatch.setattr(gather_mod, "ensure_qpp", _broken_qpp_design)
    out, root = tmp_path / "out", fast_report[0] / "runs"
    with moved_aside(root, "qpp_manipulator"):
        res = invoke(app, "report", "--fast", "--jobs", "2", "--out", out, "--root", root)
        assert not (root / "qpp_manipulator").exists()                # its simulation was not run
    assert res.exit_code == 3, res.output
    assert res.output.strip().splitlines()[-1].startswith("error: report incomplete:")
    md = (out / "report.md").read_text(encoding="utf-8")
    q14 = md.split("## QPP chapter 14")[1].split("\n## ")[0]
    assert ("FAILED — qpp14 not computed: qpp design:qpp_manipulator failed: injected: qpp design of "
            "qpp_manipulator did not converge.") in q14
    assert "FAILED" not in md.split("## QPP chapter 14")[0]     # the sections before it are complete
    stages = manifest_stages(out)
    assert {"qpp design:qpp_siso", "qpp simulate:qpp_siso"} <= stages          # ch. 13 ran (reused)
    assert not {"qpp design:qpp_manipulator", "qpp simulate:qpp_manipulator"} & stages
