"""Per-state units in design.h5 and sim.h5: every per-state array carries its ``state_units``, its
unit string gives the unit of each element in terms of them, and pint (an independent units
library) converts the imperial file's elements into the SI file's, element by element.
The orbit-rate unit ``n`` and the unit ``orbit`` carry their definitions."""
from __future__ import annotations

import re

import numpy as np
import pytest

from acmm.io.config import load_config, parse_config


def _short(tmp_path, units):
    data = load_config("mb3").model_dump(mode="json")
    data["simulation"]["orbits"] = 1.0
    data["simulation"]["sample_interval"] = 600.0
    data["output"].update({"root": str(tmp_path / units), "figures": False, "units": units})
    return parse_config(data)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    from acmm.stages.simulate import run_simulate

    tmp = tmp_path_factory.mktemp("su")
    out = {}
    for units in ("imperial", "SI"):
        cfg = _short(tmp, units)
        _, sim = run_simulate(cfg)
        out[units] = (cfg, sim.parent / "design.h5", sim)
    return out


def _element_units(ureg, units, su, shape, vector=False):
    """The pint unit of every element of a dataset of ``shape`` whose unit string uses
    ``state_units[i]`` and ``state_units[j]``: row and column of a matrix (its last two axes),
    or the last axis of a ``vector`` of states."""
    text = units
    out = np.empty(shape, dtype=object)
    for idx in np.ndindex(*shape):
        i, j = (idx[-1], idx[-1]) if vector else (idx[-2], idx[-1])
        s = text.replace("state_units[i]", f"({su[i]})").replace("state_units[j]", f"({su[j]})")
        if "rad^k" in s:                           # schedule coefficients: power first
            s = s.replace("rad^k", f"rad^{idx[0]}")
        out[idx] = ureg.parse_units(s)
    return out


def _per_state(path):
    import h5py

    found = {}
    with h5py.File(path, "r") as f:
        def visit(name, o):
            if isinstance(o, h5py.Dataset) and "state_units" in o.attrs:
                found[name] = (o[()], o.attrs["units"], [u.decode() for u in o.attrs["state_units"]])
        f.visititems(visit)
    return found


def test_per_state_arrays_carry_state_units_and_convert_like_pint(files):
    import pint

    ureg = pint.UnitRegistry()
    checked = set()
    for which in (1, 2):                                      # design.h5, sim.h5
        imp, si = _per_state(files["imperial"][which]), _per_state(files["SI"][which])
        assert imp.keys() == si.keys() and imp
        for name, (a_imp, u_imp, su_imp) in imp.items():
            a_si, u_si, su_si = si[name]
            assert "per-state" not in u_imp and "state_units[" in u_imp, (name, u_imp)
            assert len(su_imp) in (24, 12) and len(su_imp) in a_imp.shape, name
            vector = name.endswith(("scales", "drf"))
            e_imp = _element_units(ureg, u_imp, su_imp, a_imp.shape, vector)
            e_si = _element_units(ureg, u_si, su_si, a_si.shape, vector)
            factor = np.vectorize(lambda a, b: ureg.Quantity(1.0, a).to(b).magnitude)(e_imp, e_si)
            # 1e-10: the program's and pint's factors round differently (a DRF state of sim.h5
            # differed by 1.2e-12 relative on this machine's kernel); a wrong factor is ≥ 1e-6 off
            np.testing.assert_allclose(a_si, a_imp * factor, rtol=1e-10, atol=0, err_msg=name)
            checked.add(name.rsplit("/", 1)[-1])
    assert {"A", "B", "G", "K", "P", "Q", "scales", "drf", "gain"} <= checked


def test_element_units_are_dimensionally_those_of_the_equations(files):
    """x' = A x + B u (eq 4.46), u = −K x and the LQR cost x0'P x0 in s (ch. 5.2)."""
    import pint

    ureg = pint.UnitRegistry()
    _, design, _ = files["imperial"]
    ds = _per_state(design)
    name = next(n for n in ds if n.endswith("/A"))
    group = name.rsplit("/", 1)[0]
    su = [ureg.parse_units(u) for u in ds[name][2]]
    torque = ureg.parse_units("ft*lbf")
    units = {k: _element_units(ureg, ds[f"{group}/{k}"][1], ds[f"{group}/{k}"][2], ds[f"{group}/{k}"][0].shape)
             for k in ("A", "B", "K", "P", "Q")}
    for i in range(24):
        for j in range(24):
            assert (units["A"][i, j] * su[j]).dimensionality == (su[i] / ureg.s).dimensionality
            assert (su[i] * units["P"][i, j] * su[j]).dimensionality == ureg.s.dimensionality
            assert (su[i] * units["Q"][i, j] * su[j]).dimensionality == ureg.dimensionless.dimensionality
        for k in range(3):
            assert (units["B"][i, k] * torque).dimensionality == (su[i] / ureg.s).dimensionality
            assert (units["K"][k, i] * su[i]).dimensionality == torque.dimensionality


def test_orbit_rate_and_orbit_units_are_defined(files):
    import h5py
    import pint

    cfg, design, sim = files["SI"]
    with h5py.File(design, "r") as f:
        margin = f["sector_margin"]
        assert margin.attrs["units"] == "n"
        definition = margin.attrs["units_definition"]
    with h5py.File(sim, "r") as f:
        orbits, t = f["orbits"][()], f["t"][()]
        orbit_def = f["orbits"].attrs["units_definition"]
    ureg = pint.UnitRegistry()
    ureg.define(definition)
    ureg.define(orbit_def)
    assert re.fullmatch(r"n = \S+ \* rad / s", definition)
    assert ureg.Quantity(1.0, "n").to("rad/s").magnitude == pytest.approx(cfg.orbit_rate, rel=1e-15)
    np.testing.assert_allclose(ureg.Quantity(orbits, "orbit").to("s").magnitude, t, rtol=1e-12)
