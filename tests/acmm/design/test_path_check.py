"""The scheduled gain judged along the whole path (acmm.design.path_check): its disk margins
against python-control's (SLICOT AB13MD) on the same local loops."""
import numpy as np
import pytest

from acmm.design.disk_margin import DISK_OMEGA_N
from acmm.design.settings import design_settings

N = 0.0011


def test_path_disk_margin_agrees_with_python_control(staircase_lqr):
    """Disk margin at the plant input (loop broken at u) against control.disk_margins (SLICOT
    AB13MD) on the same local loops, in the scaled realization."""
    import control

    from acmm.design import schedule as sch
    from acmm.design import path_check as path_check_mod

    if not hasattr(control, "disk_margins"):       # python-control < 0.10.2
        pytest.skip("this python-control has no disk_margins")
    pc = staircase_lqr.path_check
    path = path_check_mod.path_models(staircase_lqr.points, design_settings(staircase_lqr.config), pc.theta2.size)
    d = path.scales
    for j in (0, pc.theta2.size // 2, pc.theta2.size - 1):
        K = staircase_lqr.fit.gain(pc.theta2[j]) * d[None, :]
        L = control.ss(path.A[j] / d[:, None] * d[None, :], path.B[j] / d[:, None], K, np.zeros((3, 3)))
        dm, dgm, dpm = control.disk_margins(L, N * DISK_OMEGA_N)
        assert pc.disk_margin[j] == pytest.approx(dm, rel=1e-3)
        assert pc.disk_gain_margin_db[j] == pytest.approx(dgm, rel=1e-3)
        assert pc.disk_phase_margin_deg[j] == pytest.approx(dpm, rel=1e-3)
    assert pc.disk_margin.min() > 0
