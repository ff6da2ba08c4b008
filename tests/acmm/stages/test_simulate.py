"""The simulation stage (acmm.stages.simulate): the report's claim 2 (130 orbits of the
stair-case), a divergence as a result, an inconsistent simulation refused before writing."""
import shutil

import h5py
import numpy as np
import pytest
from PIL import Image

from acmm.io.config import load_config
from acmm.stages.simulate import run_simulate
from tests.conftest import REPO

ORBIT = 2 * np.pi / 0.0011


@pytest.mark.slow
def test_claim2_staircase_130_orbits(tmp_path, monkeypatch, staircase_shipped):
    monkeypatch.chdir(tmp_path)
    # the session's shipped design (12 LMI points), reused as `acmm simulate` reuses a
    # matching design.h5
    (tmp_path / "runs" / "staircase").mkdir(parents=True)
    shutil.copy(staircase_shipped[1], tmp_path / "runs" / "staircase" / "design.h5")
    res, path = run_simulate(load_config("staircase"))
    assert res.design_note.startswith("reused"), res.design_note
    assert res.sim.verdict == "bounded"
    assert res.sim.t[-1] == pytest.approx(130 * ORBIT)
    assert len(res.stats) == 12
    with h5py.File(path) as f:
        assert f.attrs["verdict"] == "bounded"
        steady = np.degrees(f["levels/steady_error"][()])   # angles are stored in rad (issue 14)
        peak = f["levels/peak_momentum"][()]
        assert f["levels/steady_error"].attrs["units"] == "rad"
        bad = []
        f.visititems(lambda n, o: bad.append(n) if isinstance(o, h5py.Dataset) and "units" not in o.attrs else None)
        assert not bad
    assert steady.shape == (12, 3) and np.all(steady < 2.0)
    # peaks over every integrator step (the 300 s samples missed the AC level's 6 645 ft·lbf·s,
    # showing 3 986): never below the sampled ones, and far inside the CMG limit
    sampled = np.array([np.abs(res.sim.state[res.sim.level == k, 6:9]).max() for k in range(12)])
    assert np.all(peak >= sampled - 1e-9) and np.all(peak < 0.5 * res.config.actuators.momentum_limit)
    # the shipped route (regional LMI points) keeps the peak under the 6 000 ft·lbf·s design
    # target at every level (issue 32)
    assert res.config.design.pole_method == "lmi" and peak.max() <= 6000.0
    # with the table look-up the report names for claim 2 (ch. 6): the gain in force at each level
    # is the design points' gains interpolated linearly at the level's TEA estimate
    assert res.config.schedule.form == "table"
    with h5py.File(path) as f:
        gain, tea = f["levels/gain"][()], f["levels/tea_estimate"][()]
    with h5py.File(tmp_path / "runs" / "staircase" / "design.h5") as f:
        Ks, th, level = f["K"][()], f["tea"][()][:, 1], f["level"][()]
    # 12 levels and the nodes the table's refinement added between them, in the order of θ2*
    assert int(level.sum()) == 12 and Ks.shape == (level.size, 3, 24) and np.all(np.diff(th) > 0)
    for k in (0, 5, 11):
        want = np.array([[np.interp(tea[k, 1], th, Ks[:, i, j]) for j in range(24)] for i in range(3)])
        np.testing.assert_allclose(gain[k], want, rtol=1e-12, atol=1e-12 * np.abs(want).max())
    for fig in ("sim_summary.png", "sim_axes.png", "sim_inertia.png"):
        assert (tmp_path / "runs" / "staircase" / fig).stat().st_size > 10_000
    # the guide's stair-case figures (docs/img, `make docs-figures`) were drawn from this design:
    # their recorded per-level peaks (3 significant digits) are this fresh run's, to that rounding
    for fig in ("sim_summary.png", "design_poles.png", "design_path_margins.png"):
        text = Image.open(REPO / "docs" / "img" / fig).text
        assert text.get("acmm-qpp:command") == "acmm simulate staircase", fig
        drawn = np.array([float(v) for v in text["acmm-qpp:peak_momentum_ft_lbf_s"].split(",")])
        assert drawn.shape == peak.shape and np.allclose(drawn, peak, rtol=5e-3, atol=0), (fig, drawn, peak)


def test_divergence_is_a_result_not_a_crash(tmp_path, monkeypatch):
    from typer.testing import CliRunner

    from acmm.cli.app import app

    monkeypatch.chdir(tmp_path)
    out = CliRunner().invoke(app, ["simulate", "mb3_decoupled"])
    assert out.exit_code == 0, out.output
    assert "DIVERGED" in out.output
    with h5py.File(tmp_path / "runs" / "mb3_decoupled" / "sim.h5") as f:
        assert f.attrs["verdict"] == "diverged"
        assert f.attrs["stop_time_orbits"] < 0.1


@pytest.mark.parametrize("extra, field", [
    ("simulation: {orbits: 5, levels: [0, 1]}\n", "simulation.levels"),
    ("simulation: {orbits: 5, sample_interval: 1.0e-300}\n", "simulation.sample_interval"),
])
def test_simulate_rejects_inconsistent_simulation_before_writing(tmp_path, monkeypatch, extra, field):
    from typer.testing import CliRunner

    from acmm.cli.app import app

    from acmm import PACKAGED_CONFIGS
    from acmm_qpp.configio import packaged_config_path

    monkeypatch.chdir(tmp_path)
    text = packaged_config_path("mb3.yaml", PACKAGED_CONFIGS).read_text()
    text = text.replace("name: mb3", "name: badsim").split("simulation:")[0] + extra
    (tmp_path / "bad.yaml").write_text(text)
    out = CliRunner().invoke(app, ["simulate", "bad.yaml"])
    assert out.exit_code == 2
    assert field in out.stderr and "Traceback" not in out.output
    assert not (tmp_path / "runs").exists()


def test_simulate_no_figures_writes_no_figures(tmp_path, monkeypatch):
    from typer.testing import CliRunner

    from acmm.cli.app import app

    monkeypatch.chdir(tmp_path)
    out = CliRunner().invoke(app, ["simulate", "ac", "--no-figures"])
    assert out.exit_code == 0, out.output
    files = sorted(p.name for p in (tmp_path / "runs" / "ac").iterdir())
    assert files == ["config.yaml", "design.h5", "sim.h5"]
