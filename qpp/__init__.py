"""qpp — quantitative pole placement: L∞ tracking in the sense of spheres for Lure systems.

Implements Part III of NASA CR-185644 (Parlos & Jayasuriya, 1990), chapters 9–14 (ch. 9–14).
"""
__version__ = "0.1.0"

#: The data package of the configs shipped with the distribution (the source tree's ``configs/``
#: folder, mapped by ``pyproject.toml``), looked up by name with importlib.resources.
PACKAGED_CONFIGS = "acmm.configs"
#: The top-level sections of a qpp config: a config with one of them is a qpp config.
CONFIG_SECTIONS = ("plant", "nonlinearity", "hinf", "spheres")

#: qpp's work limits (issue 13: nothing hangs), each raised through ``ACMM_LIMIT_<NAME>``
#: (:func:`acmm_qpp.limits.limit`; QPP_RHS_EVALS, which only the integration can see, is
#: checked when it is reached, the others at validation):
#:
#: =====================  ============  =======================================================
#: name                   default       what it bounds
#: =====================  ============  =======================================================
#: QPP_PERIODS            10 000        periods of a qpp signal or nonlinearity (ω·t_final/2π)
#: QPP_WORK               50 000        qpp simulation work: t_final × fastest closed-loop rate
#:                                      (1/s) × (scenarios + 1); ~2.4 ms per unit, so ~2 min at
#:                                      the limit
#: QPP_RHS_EVALS          3 000 000     evaluations of a qpp loop's right-hand side in one run
#:                                      (~40 µs each, so ~2 min): the runtime bound where
#:                                      QPP_WORK cannot see the rate (a t inside an expression
#:                                      nonlinearity); the shipped examples take ~15 000
#: QPP_SAMPLES            2 000 000     qpp output samples × (scenarios + 1)
#: QPP_SECTOR_POINTS      5 000 000     points at which a qpp expression's sector is sampled
#:                                      (per channel: parameter samples × the grid of the
#:                                      outputs it depends on × times; ~3 µs each)
#: =====================  ============  =======================================================
LIMITS = {
    "QPP_PERIODS": 10_000,
    "QPP_WORK": 50_000,
    "QPP_RHS_EVALS": 3_000_000,
    "QPP_SAMPLES": 2_000_000,
    "QPP_SECTOR_POINTS": 5_000_000,
}
