"""The report's figure style (acmm.report.figure_style): the warm-up figure leaves the caller's
backend and rcParams alone; fixed margins are inches of the figure."""
from __future__ import annotations

import os

import numpy as np
import pytest

pytestmark = pytest.mark.skipif(not hasattr(os, "fork"), reason="worker processes are forked")


def test_figure_warm_up_and_fixed_layout():
    """The pre-fork warm-up figure leaves the caller's backend and rcParams alone; fixed margins
    are inches of the figure, spacings fractions."""
    import matplotlib

    from acmm.report.figure_style import COLORS, RC, SPEED_RC, fixed_layout, pyplot, warm

    backend, rc = matplotlib.get_backend(), dict(matplotlib.rcParams)
    warm()
    assert matplotlib.get_backend() == backend and dict(matplotlib.rcParams) == rc
    plt = pyplot()
    assert all(plt.rcParams[k] == v for k, v in {**RC, **SPEED_RC}.items())
    assert plt.rcParams["axes.prop_cycle"].by_key()["color"] == list(COLORS)
    fig, _ = plt.subplots(2, 2, figsize=(10.0, 5.0))
    fixed_layout(fig, left=1.0, bottom=0.5, top=0.25, right=0.2, wspace=0.3, hspace=0.1)
    p = fig.subplotpars
    assert np.allclose([p.left, p.right, p.bottom, p.top, p.wspace, p.hspace],
                       [0.1, 0.98, 0.1, 0.95, 0.3, 0.1])
    plt.close(fig)
