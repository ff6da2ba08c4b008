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


def _check_sample_count(points: int, k: int) -> None:
    """The ``points`` at which :meth:`qpp.nonlin.ExpressionModel.sector_info` samples φ (its
    :meth:`~qpp.nonlin.ExpressionModel.sector_points`, with ``k`` uncertain parameters) stay
    within the ``QPP_SECTOR_POINTS`` limit."""
    from common.limits import how_to_raise, limit

    if points > limit("QPP_SECTOR_POINTS"):
        raise ValueError(f"nonlinearity.parameters: {k} uncertain parameters sample φ at {points:.3g} points "
                         f"(parameter samples × y grid × times) to find its sector; use fewer parameters "
                         f"or a coarser nonlinearity.n_grid ({how_to_raise('QPP_SECTOR_POINTS')})")
