"""What a sweep writes (acmm.sweep.output): the unit 'orbit' defined per case, its figures with a
quantity and a unit on every axis."""
from __future__ import annotations

import numpy as np
import yaml

from acmm_qpp.results import read_h5
from acmm.sweep.run import run_sweep
from acmm.sweep.config import load_sweep

from tests.conftest import CONFIGS
from tests.acmm.conftest import _check_labels, _sweep_yaml


def test_orbits_are_defined_per_case_when_bases_differ_in_orbit_rate(tmp_path):
    """With bases of different orbit rates the unit 'orbit' had no definition in sweep.h5 (a
    review): each case's orbit is now its base's period (orbit_period, s), and the datasets in
    orbits say so; with one rate the pint definition is there as before."""
    data = yaml.safe_load((CONFIGS / "ac.yaml").read_text())
    data.update(name="ac_slow", orbit_rate=0.001)
    (tmp_path / "ac_slow.yaml").write_text(yaml.safe_dump(data))
    p = _sweep_yaml(tmp_path, "rates", monte_carlo=None, n_runs=None, grid={"dI11": [0.0]}, orbits=0.1)
    d = yaml.safe_load(p.read_text())
    d["sweep"].pop("base")
    d["sweep"]["bases"] = [str(CONFIGS / "ac.yaml"), str(tmp_path / "ac_slow.yaml")]
    p.write_text(yaml.safe_dump(d))
    h = read_h5(run_sweep(load_sweep(p), workers=1).path)
    rates = [load_sweep(p).bases[int(b)].config.orbit_rate for b in h["base"]]
    np.testing.assert_allclose(h["orbit_period"], 2 * np.pi / np.array(rates), rtol=1e-15)
    import h5py

    with h5py.File(tmp_path / "runs" / "rates" / "sweep.h5") as f:
        attrs = f["time_to_divergence"].attrs
        assert "units_definition" not in attrs and attrs["units_per_case"] == "orbit = orbit_period[case] * s"


def test_sweep_figures_have_quantities_and_units(captured, tmp_path):
    import yaml

    from acmm.sweep.run import run_sweep

    from tests.conftest import CONFIGS

    p = tmp_path / "s.yaml"
    p.write_text(yaml.safe_dump({"name": "figs", "sweep": {
        "base": str(CONFIGS / "ac.yaml"), "grid": {"dI22": [-0.1, 0.1], "bias_pitch": [0.0, 0.2]},
        "orbits": 0.5}, "output": {"root": str(tmp_path / "runs"), "figures": True}}))
    run_sweep(p, workers=1)
    assert len(captured) == 2
    for fig in captured:
        _check_labels(fig)
    assert "relative change of I22" in captured[0].axes[0].get_xlabel()
