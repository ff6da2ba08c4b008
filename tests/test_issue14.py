"""Issue 14: schedule.to by reference, netCDF layout (xarray), units (pint, SI output), the API."""
from __future__ import annotations

import numpy as np
import pytest
import yaml

from acmm.config import load_config, parse_config
from acmm.errors import ConfigError
from conftest import CONFIGS


# ---------------------------------------------------------------- schedule.to by reference
def _staircase_data():
    return yaml.safe_load((CONFIGS / "staircase.yaml").read_text())


def test_schedule_to_file_relative_to_referring_file_or_packaged_name(tmp_path, monkeypatch):
    inline = load_config(CONFIGS / "staircase.yaml")
    sub = tmp_path / "cfgs" / "ends"
    sub.mkdir(parents=True)
    (sub / "end.yaml").write_text((CONFIGS / "ac.yaml").read_text())
    data = _staircase_data()
    data["schedule"]["to"] = "ends/end.yaml"          # relative to the referring file, not the cwd
    (tmp_path / "cfgs" / "main.yaml").write_text(yaml.safe_dump(data))
    monkeypatch.chdir(tmp_path)
    by_file = load_config(tmp_path / "cfgs" / "main.yaml")
    data["schedule"]["to"] = "ac"                     # a packaged name
    by_name = parse_config(data)
    for cfg in (by_file, by_name):
        assert cfg.schedule.to == inline.schedule.to
        assert cfg.n_design_points() == inline.n_design_points()
    data["schedule"]["to"] = "nowhere.yaml"
    with pytest.raises(ConfigError, match="schedule.to: config file not found"):
        parse_config(data)
