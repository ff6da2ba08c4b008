"""How the report writes a number: one set of formatting functions for the HTML report's tables
and for the numbers README.md and the guide quote (:mod:`acmm.report.pages`).

Numbers the pages quote are rounded to the digits that mean something (:func:`sig`,
:func:`fixed`, :func:`sci`, with a Unicode minus), so their text does not change between
machines; :func:`fmt_value` writes a table cell by a format string; :func:`markdown_table` is
the one Markdown table writer (the report's ``report.md`` and the pages' blocks).
"""
from __future__ import annotations

import math

import numpy as np

#: the minus sign of a number in a page (U+2212)
MINUS = "\u2212"


def fmt_value(x, f="{:.4g}"):
    """A number (or each of a sequence) as text in the report's tables, ``—`` for none.

    Parameters
    ----------
    x : float, array_like or None
        The value(s), in the units of the table's column.
    f : str, optional
        The format of one number.

    Returns
    -------
    str
        The text (``[a, b, …]`` for a sequence).
    """
    if x is None:
        return "—"
    if isinstance(x, (list, tuple, np.ndarray)):
        return "[" + ", ".join(fmt_value(v, f) for v in np.ravel(x)) + "]"
    return f.format(float(x))


def sig(x: float, digits: int = 3) -> str:
    """``x`` rounded to ``digits`` significant digits, plain notation, thousands spaced.

    Parameters
    ----------
    x : float
        The number, in the units of the text around it.
    digits : int, optional
        Significant digits.

    Returns
    -------
    str
        E.g. ``sig(3986.2) == "3 990"``, ``sig(0.03812) == "0.0381"``, ``sig(-1.964) == "−1.96"``
        (a Unicode minus).
    """
    x = float(x)
    if x == 0 or not math.isfinite(x):
        return f"{x:g}"
    decimals = digits - 1 - math.floor(math.log10(abs(x)))
    r = round(x, decimals)
    if r != 0 and math.floor(math.log10(abs(r))) != math.floor(math.log10(abs(x))):   # 9.99 → 10.0
        decimals -= 1
        r = round(x, decimals)
    text = f"{abs(r):,.{max(decimals, 0)}f}".replace(",", " ")
    return (MINUS if r < 0 else "") + text


def fixed(x: float, decimals: int = 3, sign: bool = False) -> str:
    """``x`` with ``decimals`` decimals and a Unicode minus (``sign``: also a ``+``).

    Parameters
    ----------
    x : float
        The number, in the units of the text around it.
    decimals : int, optional
        Decimals.
    sign : bool, optional
        Write ``+`` before a positive number.

    Returns
    -------
    str
        E.g. ``fixed(-0.4680) == "−0.468"``.
    """
    text = f"{float(x):{'+' if sign else ''}.{decimals}f}"
    if float(text) == 0:
        text = text.lstrip("+-")
    return text.replace("-", MINUS)


def sci(x: float, digits: int = 2) -> str:
    """``x`` in ``1.7e4`` notation with ``digits`` significant digits.

    Parameters
    ----------
    x : float
        The number, in the units of the text around it.
    digits : int, optional
        Significant digits.

    Returns
    -------
    str
        E.g. ``sci(48396.1) == "4.8e4"``, ``sci(2.43e-6) == "2.4e−6"``.
    """
    mant, exp = f"{float(x):.{digits - 1}e}".split("e")
    return f"{mant.replace('-', MINUS)}e{int(exp)}".replace("e-", "e" + MINUS)


def markdown_table(header: list[str], rows: list[list[str]], align: str | None = None) -> str:
    """A Markdown table, its cells as given (a ``|`` inside a cell escaped by the caller).

    Parameters
    ----------
    header : list of str
        Column titles.
    rows : list of list of str
        Cells.
    align : str, optional
        One character per column, ``l`` or ``r`` (default: all left).

    Returns
    -------
    str
        The table, one line per row, ending with a newline.
    """
    align = align or "l" * len(header)
    rule = ["---" if a == "l" else "--:" for a in align]
    return "\n".join("| " + " | ".join(r) + " |" for r in [header, rule] + rows) + "\n"
