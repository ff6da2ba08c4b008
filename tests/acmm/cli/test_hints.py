"""acmm's hints on a numerical failure (acmm.cli.hints): which setting to change, never the one
that failed, and the ``; hint:`` the base's one-line error carries."""
from __future__ import annotations

from acmm.cli.hints import NUMERICAL_HINTS, acmm_command, numerical_hint
from acmm_qpp.cli.plumbing import with_hint
from acmm_qpp.errors import ConfigError, ConvergenceError, NoEquilibriumError


def test_a_riccati_hint_never_suggests_the_method_that_failed():
    for used in ("scipy", "sign", "slycot"):
        for msg in (f"Riccati solve (method='{used}') residual 3e-6 above design.residual_tol",
                    f"sector LQR: Riccati solve (method='{used}') failed",
                    f"Riccati solve (method='{used}') did not converge"):
            hint = numerical_hint(msg)
            assert "riccati_method" in hint and used not in hint.split("riccati_method", 1)[1].split(")")[0], hint
    assert "scipy or sign or slycot" in numerical_hint("Riccati solve failed")


def test_hints_for_an_uncontrollable_pole_at_zero_and_a_narrow_sector_can_help():
    """'lower design.sector.sigma' cannot help an uncontrollable pole at 0 (no sector σ > 0 holds
    it), nor 'uncontrollable?' a controllable plant in a 1° sector (review)."""
    at0 = numerical_hint("sector LQR: open-loop pole λ/n = 0+0j lies outside the sector and is uncontrollable "
                         "(PBH ratio 3.2e-18); no feedback can move it")
    assert "sigma" not in at0 and "design.drf_mode" in at0
    away = numerical_hint("sector LQR: open-loop pole λ/n = 0.2+0j lies outside the sector and is uncontrollable")
    assert "lower design.sector.sigma" in away
    narrow = numerical_hint("sector LQR (shift): cannot shift the poles λ/n = [(-2.3+0.8j)] (uncontrollable?): "
                            "Riccati solve (method='scipy'): relative residual 1.2e-07 exceeds tolerance 1.0e-09")
    assert narrow.startswith("widen design.sector.half_angle_deg")


def test_the_hint_follows_a_numerical_failure_only_and_once():
    exc = ConvergenceError("sector LQR: Riccati solve (method='sign') failed")
    assert with_hint(exc, numerical_hint) == (
        "sector LQR: Riccati solve (method='sign') failed; hint: lower design.sector.sigma (the shift α "
        "asked of the LQR may be too large), or try another design.riccati_method (scipy or slycot)")
    assert with_hint(exc) == str(exc)                                   # no product: no hint
    assert "hint:" in with_hint(NoEquilibriumError("no torque-equilibrium attitude"), numerical_hint)
    assert with_hint(ConfigError("design.sector: residual_tol must be > 0"), numerical_hint).count("hint") == 0
    assert with_hint(ConvergenceError("riccati failed; hint: x"), numerical_hint) == "riccati failed; hint: x"
    assert len(NUMERICAL_HINTS) > 10 and acmm_command(lambda: 1)() == 1
