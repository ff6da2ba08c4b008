"""Checks of a qpp config that span fields or bound the work (issue 13): sectors, the sector
sampling budget of an expression nonlinearity, the periods to integrate.  Split from
:mod:`qpp.config`, whose validator calls them; each raises ``ValueError`` naming the field.
"""
from __future__ import annotations

import math


def _check_periods(field: str, omega: float, t_final: float) -> None:
    from common.limits import how_to_raise, limit

    periods = omega * t_final / (2 * math.pi)
    if periods > limit("QPP_PERIODS"):
        raise ValueError(f"{field}: {omega:g} rad/s over simulation.t_final = {t_final:g} s is {periods:.3g} "
                         f"periods to integrate; lower the frequency or t_final ({how_to_raise('QPP_PERIODS')})")


def _check_sector(field: str, sector) -> None:
    """Each pair [α_i, β_i] of a stated sector has α_i < β_i (lemma 1's critical disc)."""
    for i, (a, b) in enumerate(sector or []):
        if not a < b:
            raise ValueError(f"{field}: pair {i + 1} is [{a:g}, {b:g}]; a sector needs alpha < beta")


def _check_sample_count(model) -> None:
    """The points at which :meth:`qpp.nonlin.ExpressionModel.sector_info` samples φ (its
    :meth:`~qpp.sector_grid.SampleGrid.sector_points`) stay within the ``QPP_SECTOR_POINTS``
    limit; the message names what makes them many: the uncertain parameters (their samples) or
    the outputs a channel depends on (its grid)."""
    from common.limits import how_to_raise, limit

    points = model.sector_points()
    if points <= limit("QPP_SECTOR_POINTS"):
        return
    k, n_theta = len(model.names), model.theta_sample_count()
    widest = max(range(len(model.phi)), key=model.sector_grid_size)
    n_y = model.sector_grid_size(widest)
    d = len(model.channel_outputs(widest))
    coarser = " or a coarser nonlinearity.n_grid" if d <= 2 else ""   # n_grid sets 1- and 2-output grids
    if n_theta >= n_y:
        cause = (f"nonlinearity.parameters: {k} uncertain parameters sample φ at {points:.3g} points "
                 f"({n_theta:.3g} parameter samples × y grid × times); use fewer parameters{coarser}")
    else:
        cause = (f"nonlinearity.f1: channel {widest + 1} depends on {d} outputs, a grid of {n_y:.3g} points; "
                 f"φ is sampled at {points:.3g} points to find its sector; use fewer outputs per channel{coarser}")
    raise ValueError(f"{cause} ({how_to_raise('QPP_SECTOR_POINTS')})")
