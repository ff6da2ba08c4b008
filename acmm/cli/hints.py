"""acmm's hints on a numerical failure: which setting of an acmm config to change when a solver
or a design fails (``; hint: ...`` after the command's one ``error:`` line), and the ``note:``
lines numba's cache leaves after a run.  The base's :func:`acmm_qpp.cli.plumbing.user_errors`
prints them: it knows neither product's settings."""
from __future__ import annotations

import re
import sys

from acmm_qpp.cli.plumbing import first_hint, user_errors

#: (words that must all occur in the message, hint) — the first match wins; case-insensitive.
#: Each hint names settings of the acmm configs only; ``{other}`` is the Riccati methods other
#: than the one the message says failed.
NUMERICAL_HINTS: list[tuple[tuple[str, ...], str]] = [
    (("cannot shift the poles",), "widen design.sector.half_angle_deg or lower design.sector.sigma "
                                  "(a narrow sector leaves the moved poles a sliver of the plane), or "
                                  "try design.pole_method: uniform; a nearly uncontrollable model (see "
                                  "`acmm linearize`) needs another design.model or design.drf_mode"),
    (("residual",), "raise design.residual_tol or try design.riccati_method: {other}; a nearly "
                    "uncontrollable model (see `acmm linearize`) needs another design.model or design.drf_mode"),
    (("matrix sign",), "use design.riccati_method: {other} (the sign iteration needs a well-conditioned model)"),
    (("sector lqr", "riccati", "failed"), "lower design.sector.sigma (the shift α asked of the LQR may "
                                          "be too large), or try another design.riccati_method ({other})"),
    (("riccati",), "try another design.riccati_method ({other})"),
    (("uncontrollable", "λ/n = 0+0j"), "no gain moves that pole and no sector (σ > 0) holds λ = 0: "
                                       "change design.model or design.drf_mode (an axisymmetric "
                                       "station's neutral mode, say)"),
    (("uncontrollable",), "no gain moves that pole: lower design.sector.sigma, or change design.model / "
                          "design.drf_mode"),
    (("not positive semidefinite",), "change design.Q0 or design.R"),
    (("sector",), "lower design.sector.sigma, widen design.sector.half_angle_deg, or try "
                  "design.pole_method: uniform / shift"),
    (("blend toward schedule.to", "no torque-equilibrium"),
     "reduce the bias of disturbance or of schedule.to (their blend must balance at every s), or "
     "give each as its bias_from_tea"),
    (("no torque-equilibrium",), "reduce disturbance.bias (or use disturbance.bias_from_tea with the "
                                 "attitude you want)"),
    (("tea continuation",), "check the products of inertia (inertia.I12, I13, I23) or give the bias as "
                            "disturbance.bias_from_tea"),
    (("converge",), "loosen the tolerance (design.residual_tol, simulation.rtol) or change "
                    "design.riccati_method ({other})"),
]

#: the values of design.riccati_method
RICCATI_METHODS = ("scipy", "sign", "slycot")


def numerical_hint(message: str) -> str:
    """A "which setting to change" hint for a numerical failure message of ``acmm``.

    Parameters
    ----------
    message : str
        The failure message.

    Returns
    -------
    str
        The first matching hint (:data:`NUMERICAL_HINTS`); empty when none applies.
    """
    return first_hint(message, NUMERICAL_HINTS).replace("{other}", other_riccati_methods(message.lower()))


def other_riccati_methods(low_message: str) -> str:
    """The Riccati methods to suggest: all but the one the message says failed (``method='…'``).

    Parameters
    ----------
    low_message : str
        The failure message, lower-case.

    Returns
    -------
    str
        ``"scipy or sign or slycot"`` without the failed one.
    """
    m = re.search(r"method='(\w+)'", low_message)
    used = m.group(1) if m else None
    return " or ".join(x for x in RICCATI_METHODS if x != used)


def compiled_cache_notes() -> list[str]:
    """A line for each reason numba could not save a kernel it compiled in this run.

    Returns
    -------
    list of str
        The notes (none when nothing was compiled: the cache module was not even imported).
    """
    cache = sys.modules.get("acmm.model.compiled_cache")       # (not imported: nothing was compiled)
    return cache.write_error_notes() if cache is not None else []


def acmm_command(fn):
    """:func:`acmm_qpp.cli.plumbing.user_errors` for an ``acmm`` command: with acmm's numerical
    hints and numba's cache notes.

    Parameters
    ----------
    fn : callable
        The command function.

    Returns
    -------
    callable
        The wrapped command.
    """
    return user_errors(fn, hint=numerical_hint, notes=compiled_cache_notes)
