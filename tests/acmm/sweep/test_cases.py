"""A sweep's cases (acmm.sweep.cases): the physical-inertia check agrees with the config
validator, the draws follow numpy's SeedSequence contract."""
from __future__ import annotations

import numpy as np
import pytest

from acmm.model.inertia import perturb_inertia, physical_mask, unphysical_reason
from acmm.sweep.cases import case_values
from acmm.sweep.config import load_sweep

from tests.acmm.conftest import _sweep_yaml


def test_unphysical_reason_agrees_with_config_validator():
    from pydantic import ValidationError

    from acmm.io.config import Inertia

    rng = np.random.default_rng(0)
    base = np.array([[23.22e6, -0.023e6, 0.477e6], [-0.023e6, 1.30e6, -0.011e6], [0.477e6, -0.011e6, 23.23e6]])
    seen = set()
    for _ in range(300):
        m = perturb_inertia(base, dict(zip(["dI11", "dI22", "dI33", "dI12", "dI13", "dI23"],
                                           rng.uniform(-0.6, 0.6, 6))))
        try:
            Inertia.model_validate(m.tolist())
            ok = True
        except ValidationError:
            ok = False
        assert (unphysical_reason(m) is None) == ok == physical_mask(m[None])[0]     # the pilot's twin
        seen.add(ok)
    assert seen == {True, False}      # both outcomes were exercised
    # a scale beyond the physical range (a review: inertia_scale 1e160 overflowed the redesign)
    for scale in (1e6, 1e160, 1e200):
        m = perturb_inertia(base, {"inertia_scale": scale})
        with pytest.raises(ValidationError):
            Inertia.model_validate(m.tolist())
        assert "physical range" in unphysical_reason(m) and not physical_mask(m[None])[0]


def test_case_draws_follow_seedsequence_contract(tmp_path):
    sw = load_sweep(_sweep_yaml(tmp_path, "draws", monte_carlo={"inertia_scale": {"uniform": [0.9, 1.1]},
                                                                "offset_pitch": {"normal": [0.0, 2.0]}}))
    inertias = sw.bases[0].config.inertia.matrix()[None]
    for i in (5, 0, 3):                                 # any order
        rng = np.random.default_rng(np.random.SeedSequence([11, i]))
        want = {"inertia_scale": rng.uniform(0.9, 1.1), "offset_pitch": rng.normal(0.0, 2.0)}
        got, draws, why = case_values(sw.spec, i, inertias)
        assert got == want and draws == 1 and why is None
