"""Work bounds of a sweep, checked when the sweep config is validated (issue 13: nothing hangs).

* ``SWEEP_CASES``: cases of all bases together (a grid's Cartesian product can be enormous).
* ``SWEEP_ORBITS``: simulated orbits of all cases together (cases × orbits per run), the margin
  searches' simulations included.
* ``SIM_SAMPLES``: output samples of one run at the sweep's ``orbits`` (as for ``acmm simulate``).
* ``SWEEP_DRAWS``: expected Monte Carlo draws, resampling of unphysical inertias included.  When
  the worst case (cases × ``max_draws``) exceeds the limit, a pilot of :data:`PILOT` draws (its
  own random stream, so the cases' draws are untouched) estimates the fraction p of physical
  draws; the expected total is cases × min(max_draws, 1/p).  A distribution that almost never
  gives a physical inertia with a huge ``max_draws`` is thus refused in well under a second
  instead of grinding through billions of eigenvalue tests.

Limits: ``acmm.LIMITS`` (:func:`acmm_qpp.limits.limit`, ``ACMM_LIMIT_<NAME>`` environment variables).
"""
from __future__ import annotations

import numpy as np

from acmm_qpp.errors import ConfigError
from acmm_qpp.limits import how_to_raise, limit
from acmm import LIMITS
import math
from acmm.design.schedule_points import point_specs
from acmm.model.inertia import perturb_inertia, physical_mask
from acmm.sweep.cases import draw_parameters

PILOT = 1000


def _physical_fraction(sweep, n: int) -> tuple[int, int]:
    """(physical draws, draws) of a pilot of ``n`` draws at every level of every base."""
    spec = sweep.spec
    rng = np.random.default_rng(np.random.SeedSequence([spec.seed, 0x9E3779B9]))
    draws = [draw_parameters(rng, spec) for _ in range(n)]
    ok = np.ones(n, bool)
    for b in sweep.bases:
        for s in point_specs(b.config):
            ok &= physical_mask(np.array([perturb_inertia(s.inertia, d) for d in draws]))
    return int(ok.sum()), n


def _margin_evaluations(margin) -> int:
    """Most simulations of the two margin searches of one base (:func:`acmm.sweep.case.margin_search`
    settings ``margin``): the nominal, the scan and the bisection to ``rel_tol``, each way; 0 without a search."""
    if margin is None:
        return 0
    total = 0
    for end in (margin.high, margin.low):
        step = abs(math.log(end)) / margin.scan_points          # log-width of the bracket bisected
        total += 1 + margin.scan_points + max(0, math.ceil(math.log2(step / math.log1p(margin.rel_tol)))) + 1
    return total


def check_sweep_work(sweep, source: str = "sweep config") -> None:
    """Raise a one-line :class:`ConfigError` when a sweep exceeds a work limit.

    Parameters
    ----------
    sweep : acmm.sweep.config.Sweep
        The validated sweep (its ``spec`` and ``bases``).
    source : str, optional
        Where the sweep came from, prefixed to the message.

    Raises
    ------
    ConfigError
        No base, or too many cases, orbits, redesigns or expected Monte Carlo draws.
    """
    spec = sweep.spec
    nb = len(sweep.bases)
    if nb == 0:
        raise ConfigError(f"{source}: sweep.base: give a base config ('base: NAME' or 'bases: [...]')")
    cases = spec.n_cases() * nb
    if cases > limit("SWEEP_CASES", LIMITS):
        raise ConfigError(f"{source}: sweep: {cases:.3g} cases over {nb} base(s); use fewer grid values or "
                          f"n_runs ({how_to_raise('SWEEP_CASES', LIMITS)})")
    all_orbits = 0
    for b in sweep.bases:          # the per-run output-sample limit at the sweep's own orbits
        sim = b.config.simulation
        orbits = spec.orbits if spec.orbits is not None else sim.orbits
        samples = b.config.output_samples(orbits)
        if samples > limit("SIM_SAMPLES", LIMITS):
            raise ConfigError(f"{source}: sweep.orbits: {orbits:g} orbits of {b.label} at its sample_interval "
                              f"{sim.sample_interval:g} s give {samples:.3g} output samples per run; lower "
                              f"sweep.orbits or raise simulation.sample_interval ({how_to_raise('SIM_SAMPLES', LIMITS)})")
        all_orbits += orbits
    runs = cases // nb + _margin_evaluations(spec.margin)        # per base
    total_orbits = all_orbits * runs
    if total_orbits > limit("SWEEP_ORBITS", LIMITS):
        raise ConfigError(f"{source}: sweep.orbits: {cases} cases"
                          f"{' and the margin searches' if spec.margin is not None else ''} simulate "
                          f"{total_orbits:.3g} orbits in all; lower sweep.orbits, the number of cases or "
                          f"margin.scan_points ({how_to_raise('SWEEP_ORBITS', LIMITS)})")
    if spec.design == "redesign":
        designs = runs * sum(b.config.n_design_points() for b in sweep.bases)
        if designs > limit("SWEEP_DESIGNS", LIMITS):
            raise ConfigError(f"{source}: sweep.design: redesign runs {designs} sector-LQR designs ({cases} cases "
                              f"× design points); use design: fixed or fewer cases ({how_to_raise('SWEEP_DESIGNS', LIMITS)})")
    if spec.grid is not None or spec.unphysical != "resample":
        return
    cap = limit("SWEEP_DRAWS", LIMITS)
    if cases * spec.max_draws <= cap:
        return
    good, n = _physical_fraction(sweep, PILOT)
    expected = cases * (spec.max_draws if good == 0 else min(spec.max_draws, n / good))
    if expected > cap:
        raise ConfigError(f"{source}: sweep.max_draws: {good} of {n} pilot draws give a physical inertia, so "
                          f"{cases} cases would need ~{expected:.3g} draws; narrow sweep.monte_carlo, lower "
                          f"max_draws or set unphysical: reject ({how_to_raise('SWEEP_DRAWS', LIMITS)})")
