"""The printed-number ledger: every number printed in CR-185644 that the report compares, and its status."""
from __future__ import annotations

from dataclasses import dataclass

STATUS_MATCHED = "matched to printed precision"
STATUS_BOUND = "consistent with the printed bound"
STATUS_EXPLAINED = "explained"
STATUS_UNEXPLAINED = "NOT EXPLAINED"


@dataclass
class PrintedNumber:
    """One number printed in CR-185644 and what this run computed for it.

    Attributes
    ----------
    section : str
        Report section it belongs to.
    quantity : str
        What it is.
    printed : str
        The number exactly as printed.
    computed : float or None
        This run's value, in ``unit`` (None: not computed).
    unit : str
        Unit of both numbers.
    status : str
        One of the ``STATUS_*`` constants.
    note : str
        The explanation of an explained number.
    """

    section: str
    quantity: str
    printed: str
    computed: float | None
    unit: str = ""
    status: str = STATUS_UNEXPLAINED
    note: str = ""


def matches_printed(printed: str, computed: float) -> bool:
    """|computed − printed| ≤ half a unit of the printed number's last digit.

    Parameters
    ----------
    printed : str
        The number as printed.
    computed : float
        This run's value, in the printed number's unit.

    Returns
    -------
    bool
        It matches to printed precision.
    """
    mantissa = printed.strip().lower().split("e")[0]          # "-44.7" → 1 decimal, "1020" → 0
    half = 0.5 * 10.0 ** (-(len(mantissa.split(".")[1]) if "." in mantissa else 0))
    return bool(abs(float(computed) - float(printed)) <= half * (1 + 1e-9) + 1e-15)


def check_printed(section: str, quantity: str, printed: str, computed, unit: str = "", *,
                  explanation: str = "", bound: str | None = None) -> PrintedNumber:
    """Classify one printed number.

    Parameters
    ----------
    section : str
        Report section.
    quantity : str
        What the number is.
    printed : str
        The number exactly as printed (its decimals set the precision).
    computed : float or None
        This run's value, in ``unit`` (None: not computed, ``explanation`` required).
    unit : str, optional
        Unit of the printed and computed numbers.
    explanation : str
        Why a number that does not match differs (required for it to count as explained).
    bound : {"upper", None}
        ``"upper"``: the report prints a bound ("less than 0.094"); the value is consistent when
        it is below the bound.

    Returns
    -------
    PrintedNumber
        The entry with its status.
    """
    if computed is not None and bound == "upper" and float(computed) < float(printed):
        status = STATUS_BOUND
    elif computed is not None and bound is None and matches_printed(printed, computed):
        status = STATUS_MATCHED
    elif explanation:
        status = STATUS_EXPLAINED
    else:
        status = STATUS_UNEXPLAINED
    return PrintedNumber(section, quantity, printed, None if computed is None else float(computed), unit,
                         status, explanation if status == STATUS_EXPLAINED else "")


def status_text(pn: PrintedNumber) -> str:
    """The status of a ledger entry as shown in the tables (explained ones carry their note).

    Parameters
    ----------
    pn : PrintedNumber
        The entry.

    Returns
    -------
    str
        The status text.
    """
    return pn.status if pn.status != STATUS_EXPLAINED else f"{STATUS_EXPLAINED}: {pn.note}"
