"""The JSON schemas of the three config kinds (issue 14 item 3) accept what the loader of each kind
(acmm.cli.configkinds.load_any) accepts, and every packaged config validates against its schema."""
from __future__ import annotations

import json

import pytest
import yaml

from acmm_qpp.errors import ConfigError

from tests.conftest import CONFIGS, invoke


def acmm(*args):
    from acmm.cli.app import app

    return invoke(app, *args)


def qpp(*args):
    from qpp.cli import app

    return invoke(app, *args)


# ---------------------------------------------------------------------------------------------
# item 3: JSON schemas
# ---------------------------------------------------------------------------------------------
def _schema(kind):
    r = acmm("schema", "--kind", kind)
    assert r.exit_code == 0, r.output
    return json.loads(r.stdout)


@pytest.fixture(scope="module")
def schemas():
    import jsonschema

    out = {}
    for kind in ("acmm", "sweep", "qpp"):
        s = _schema(kind)
        jsonschema.Draft202012Validator.check_schema(s)
        out[kind] = jsonschema.Draft202012Validator(s)
    r = qpp("schema")
    assert json.loads(r.stdout) == out["qpp"].schema
    return out


def test_every_packaged_config_validates_against_its_schema(schemas):
    from acmm.cli.command import CONFIGS as KINDS
    from acmm.cli.configkinds import load_any

    paths = sorted(CONFIGS.glob("*.yaml"))
    assert len(paths) >= 9
    for p in paths:
        data = yaml.safe_load(p.read_text())
        kind = KINDS.kind_of(data)
        errors = [e.message for e in schemas[kind].iter_errors(data)]
        assert errors == [], (p.name, errors)
        assert load_any(p)[0] == kind


def _mb3():
    return yaml.safe_load((CONFIGS / "mb3.yaml").read_text())


def _variants_ok():
    a = _mb3()
    a["inertia"] = {"I11": "31.48e6 kg*m^2", "I22": "1.76e6 kg*m^2", "I33": "31.5e6 kg*m^2"}
    a["actuators"] = {"torque_limit": "200 N*m", "momentum_limit": 20000}
    a["disturbance"]["A"] = ["1 N*m", 2.0, "1.5 ft*lbf"]
    a["orbit_rate"] = "0.063 deg/s"
    b = _mb3()
    m = [[23.22e6, -0.023e6, 0.477e6], [-0.023e6, 1.30e6, -0.011e6], [0.477e6, -0.011e6, 23.23e6]]
    b["inertia"] = m
    c = _mb3()
    c["sweep"] = {"grid": {"inertia_scale": [0.9, 1.1]}, "tea_estimate": True}
    return [("acmm", a), ("acmm", b), ("sweep", c)]


def _variants_bad():
    out = []
    for edit in (lambda d: d["simulation"].__setitem__("orbit", 3),            # unknown key
                 lambda d: d.__setitem__("inertia", {"Ixx": 1.0, "I22": 2.0, "I33": 2.0}),
                 lambda d: d["design"].__setitem__("riccati_method", "newton"),   # not an enum value
                 lambda d: d["actuators"].__setitem__("torque_limit", "lots"),    # not a quantity
                 lambda d: d["simulation"].__setitem__("initial_offset", [0, 1]),  # two values
                 lambda d: d["design"]["sector"].__setitem__("sigma", -1),        # bound
                 lambda d: d.pop("name")):                                       # required
        d = _mb3()
        edit(d)
        out.append(("acmm", d))
    s = yaml.safe_load((CONFIGS / "sweep_smoke.yaml").read_text())
    s["sweep"]["n_runz"] = 3
    out.append(("sweep", s))
    s = _mb3()
    s["sweep"] = {"base": "ac", "grid": {"inertia_scale": [1.0]}}       # inline section with a base
    out.append(("sweep", s))
    q = yaml.safe_load((CONFIGS / "qpp_siso.yaml").read_text())
    q["hinf"]["rhoo"] = 1
    out.append(("qpp", q))
    q = yaml.safe_load((CONFIGS / "qpp_siso.yaml").read_text())
    q["nonlinearity"]["kind"] = "cubic"
    out.append(("qpp", q))
    return out


def test_schema_accepts_what_the_loader_accepts(schemas, tmp_path):
    from acmm.cli.configkinds import load_any

    for k, (kind, data) in enumerate(_variants_ok()):
        assert [e.message for e in schemas[kind].iter_errors(data)] == [], (k, kind)
        p = tmp_path / f"ok{k}.yaml"
        p.write_text(yaml.safe_dump(data))
        assert load_any(p)[0] == kind
    for k, (kind, data) in enumerate(_variants_bad()):
        assert list(schemas[kind].iter_errors(data)), (k, kind, data)
        p = tmp_path / f"bad{k}.yaml"
        p.write_text(yaml.safe_dump(data))
        with pytest.raises(ConfigError):
            load_any(p)
