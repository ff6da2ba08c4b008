"""Checks of a qpp config that span fields or bound the work (issue 13): sectors, the sector
sampling budget of an expression nonlinearity, the periods to integrate.  Split from
:mod:`qpp.io.config`, whose validator calls them; each raises ``ValueError`` naming the field.
"""
from __future__ import annotations

import math

import numpy as np
from acmm_qpp.limits import how_to_raise, limit
from qpp import LIMITS


def check_periods(field: str, omega: float, t_final: float) -> None:
    """A periodic input of frequency ``omega`` over ``t_final`` stays within the
    ``QPP_PERIODS`` limit of periods to integrate.

    Parameters
    ----------
    field : str
        The config field, for the message.
    omega : float
        The frequency, rad/s.
    t_final : float
        The simulated time, s.

    Raises
    ------
    ValueError
        Too many periods (the message says what to lower, and the limit's variable).
    """
    periods = omega * t_final / (2 * math.pi)
    if periods > limit("QPP_PERIODS", LIMITS):
        raise ValueError(f"{field}: {omega:g} rad/s over simulation.t_final = {t_final:g} s is {periods:.3g} "
                         f"periods to integrate; lower the frequency or t_final ({how_to_raise('QPP_PERIODS', LIMITS)})")


def check_sector(field: str, sector) -> None:
    """Each pair [α_i, β_i] of a stated sector has α_i < β_i (lemma 1's critical disc).

    Parameters
    ----------
    field : str
        The config field, for the message.
    sector : list of pair or None
        The stated sector, one [α, β] pair per channel (dimensionless slopes).

    Raises
    ------
    ValueError
        A pair with α ≥ β.
    """
    for i, (a, b) in enumerate(sector or []):
        if not a < b:
            raise ValueError(f"{field}: pair {i + 1} is [{a:g}, {b:g}]; a sector needs alpha < beta")


#: how far (fraction of the computed half-width) a stated sector may lie inside the computed one:
#: the computed bounds can exceed φ's own by the 1 % widening of a random check that found a point
STATED_SECTOR_SLACK = 0.02


def check_stated_sector(field: str, stated, computed) -> None:
    """A sector stated for an ``expression`` nonlinearity holds φ's sector computed on the stated
    ranges (to :data:`STATED_SECTOR_SLACK`): the circle check and the thresholds of a narrower one
    would certify another nonlinearity.

    Parameters
    ----------
    field : str
        The config field, for the message.
    stated : array_like
        The stated sector, one [α, β] pair per channel (dimensionless slopes).
    computed : array_like
        The computed sector, same shape (dimensionless slopes).

    Raises
    ------
    ValueError
        A stated pair narrower than the computed one.
    """
    for i, ((a, b), (ca, cb)) in enumerate(zip(np.asarray(stated, float), np.asarray(computed, float))):
        slack = STATED_SECTOR_SLACK * max(0.5 * (cb - ca), 1e-12)
        if a > ca + slack or b < cb - slack:
            raise ValueError(f"{field}: pair {i + 1} [{a:g}, {b:g}] does not hold φ_{i + 1}, whose sector on the "
                             f"stated ranges is [{ca:.6g}, {cb:.6g}]; a certificate for a narrower sector is not one "
                             "for this nonlinearity (widen the pair, or leave the sector out to use the computed one)")


def check_sample_count(model) -> None:
    """The points at which :meth:`qpp.model.nonlin.ExpressionModel.sector_info` samples φ (its
    :meth:`~qpp.model.sector_grid.SampleGrid.sector_points`) stay within the ``QPP_SECTOR_POINTS``
    limit; the message gives the factors and what the config can lower.

    Parameters
    ----------
    model : qpp.model.nonlin.ExpressionModel
        The nonlinearity's model.

    Raises
    ------
    ValueError
        Too many points.
    """
    points = model.sector_points()
    if points <= limit("QPP_SECTOR_POINTS", LIMITS):
        return
    r, k = len(model.phi), len(model.names)
    n_theta, n_t = model.theta_sample_count(), model.time_sample_count()
    sizes = [model.sector_grid_size(i) for i in range(r)]
    widest = int(np.argmax(sizes))
    d = len(model.channel_outputs(widest))
    factors = (f"over {r} channel{'s' * (r != 1)}: {n_theta:.3g} samples of {k} uncertain parameter"
               f"{'s' * (k != 1)} × the channel's output grid, {sum(sizes):.3g} points in all, the largest "
               f"{max(sizes):.3g} (channel {widest + 1}, on {d} output{'s' * (d != 1)})"
               + (f", × {n_t} times on the channels that depend on t" if n_t > 1 else ""))
    # what the config can lower: the parameters (a factor of every point), and whichever grids hold
    # most of the points: those of channels on three or more outputs, or the n_grid-point ones
    wide = sum(n for i, n in enumerate(sizes) if len(model.channel_outputs(i)) >= 3)
    advice = ["fewer uncertain parameters (nonlinearity.parameters)"] if k > 1 else []
    if 2 * wide >= sum(sizes):
        advice.append("fewer outputs per channel (nonlinearity.f1)")
    elif model.n_grid > 5:
        advice.append(f"a coarser nonlinearity.n_grid (now {model.n_grid})")
    raise ValueError(f"nonlinearity: finding the sector samples φ at {points:.3g} points ({factors}); "
                     f"use {' or '.join(advice) or 'fewer nonlinear channels'} "
                     f"({how_to_raise('QPP_SECTOR_POINTS', LIMITS)})")
