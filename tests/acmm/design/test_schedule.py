"""Gain schedules (acmm.design.schedule): the fit recovers a known quadratic, the table is exact at
its nodes, and the design weights Q0 / Q0_groups act on the scaled states."""
import numpy as np

from acmm.io.config import load_config
from acmm.design.schedule import fit_schedule, schedule_gain
from acmm.design.settings import design_settings


def test_fit_recovers_a_known_quadratic_and_table_is_exact_at_nodes():
    rng = np.random.default_rng(1)
    th = np.radians(np.linspace(-45, -5, 9))
    coef = rng.normal(size=(3, 3, 24))
    gains = np.array([coef[0] + coef[1] * t + coef[2] * t * t for t in th])
    fit = fit_schedule(th, gains, 2)
    assert np.allclose(fit.coef, coef, rtol=1e-9, atol=1e-9)
    assert fit.rel_residual.max() < 1e-10
    for k, t in enumerate(th):
        assert np.allclose(schedule_gain("table", fit.coef, th, gains, t), gains[k])
    mid = 0.5 * (th[2] + th[3])
    assert np.allclose(schedule_gain("table", fit.coef, th, gains, mid), 0.5 * (gains[2] + gains[3]))


def test_config_q0_is_a_weight_on_the_scaled_states():
    """design.Q0 = q means Q̃ = q·I on x̃ = D⁻¹x: the returned physical Q satisfies D Q D ⪰ q I
    (pole shifting only adds positive semidefinite terms)."""
    from acmm.design.schedule import design_one
    from acmm.design.schedule_points import point_specs

    cfg = load_config("ac")
    cfg = cfg.model_copy(update={"design": cfg.design.model_copy(
        update={"Q0": 1e-3, "Q0_groups": None, "min_margin": 0.01})})
    p = design_one(point_specs(cfg)[0], design_settings(cfg))
    d = p.model.scales
    q_scaled = p.gain.riccati.Q * d[:, None] * d[None, :]
    assert np.linalg.eigvalsh(0.5 * (q_scaled + q_scaled.T) - 1e-3 * np.eye(24)).min() > -1e-9
    assert np.linalg.eigvalsh(q_scaled).max() < 10.0      # not the 1/d² blow-up of a physical q·I


def test_config_q0_groups_are_diagonal_weights_on_the_scaled_states():
    """Q0_groups = per-group diagonal on x̃ = D⁻¹x: D Q D − diag(groups) ⪰ 0 (pole shifting only
    adds positive semidefinite terms), and the groups sit on the right states."""
    from acmm.io.config import Q0Groups
    from acmm.design.schedule import design_one
    from acmm.design.schedule_points import point_specs

    g = Q0Groups(rates=1e-5, attitudes=2e-6, momentum=3e-6, momentum_integral=4e-5, drf=5e-7)
    np.testing.assert_array_equal(g.diagonal()[[0, 3, 6, 9, 12, 23]], [1e-5, 2e-6, 3e-6, 4e-5, 5e-7, 5e-7])
    cfg = load_config("ac")
    cfg = cfg.model_copy(update={"design": cfg.design.model_copy(update={"Q0_groups": g})})
    p = design_one(point_specs(cfg)[0], design_settings(cfg))
    d = p.model.scales
    q_scaled = p.gain.riccati.Q * d[:, None] * d[None, :]
    q_scaled = 0.5 * (q_scaled + q_scaled.T)
    assert np.linalg.eigvalsh(q_scaled - np.diag(g.diagonal())).min() > -1e-9 * np.abs(q_scaled).max()
