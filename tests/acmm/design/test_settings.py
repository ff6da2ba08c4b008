"""The numerical core takes arrays and small settings objects, never the whole Config (issue 12)."""
import inspect

import numpy as np
import pytest

from acmm.design import design_core
from acmm.design import sector_lqr
from acmm.design import schedule
from acmm.design import path_check as pc
from acmm.design import schedule_shifted_lqr, disk_margin
from acmm.design import schedule_points as sp
from acmm.io.config import load_config
from acmm.design.settings import DesignSettings, ScheduleSettings, Sector, design_settings, schedule_settings

CORE = [schedule.design_one, schedule.sector_design, schedule.check_schedule, pc.path_models,
        sp.schedule_specs, schedule.fit_schedule, pc.check_path, schedule_shifted_lqr.refit_shifted_lqr,
        disk_margin.disk_margin_input, design_core.design_schedule, sector_lqr.sector_lqr, sector_lqr.sector_margin]


@pytest.mark.parametrize("fn", CORE, ids=lambda f: f.__name__)
def test_core_signatures_take_no_config(fn):
    for name, p in inspect.signature(fn).parameters.items():
        ann = str(p.annotation)
        assert "Config" not in ann and name not in ("cfg", "config"), (fn.__name__, name, ann)


def test_settings_are_built_once_from_the_config():
    cfg = load_config("staircase")
    s = design_settings(cfg)
    assert s.sector == Sector(cfg.design.sector.sigma, cfg.design.sector.half_angle_deg)
    assert s.orbit_rate == cfg.orbit_rate and s.model == cfg.design.model
    sc = schedule_settings(cfg)
    assert isinstance(sc, ScheduleSettings) and sc.n_check == cfg.schedule.n_check
    with pytest.raises(Exception):
        s.sector.sigma = 1.0                     # frozen


class _Bare:
    """An object with no attributes: a core function reaching for a config field fails on it."""

    __slots__ = ()


def test_sector_design_reads_only_the_settings():
    cfg = load_config("mb3")
    s = design_settings(cfg)
    spec = sp.point_specs(cfg)[0]
    p = schedule.design_one(spec, s)
    r = schedule.sector_design(p.model.A, p.model.B, p.model.scales, s)
    np.testing.assert_array_equal(r.K, p.gain.K)
    with pytest.raises(AttributeError):
        schedule.sector_design(p.model.A, p.model.B, p.model.scales, _Bare())
    assert isinstance(s, DesignSettings)
