"""Safe parsing of the user's nonlinearity expressions (CR-185644 ch. 10.1, eq 10.1), without eval.

Python's :mod:`ast` tree of an expression is walked node by node and only numbers, the
whitelisted symbols and the whitelisted functions are turned into a :mod:`sympy` expression.
Functions: sin cos tan exp log sqrt tanh atan abs sign min max, and the library forms

* ``sat(x, L)``       saturation  max(−L, min(L, x))  (L = 1 by default),
* ``deadzone(x, w)``  dead zone   x − sat(x, w),
* ``cubic(x)``        x³.

A bad expression raises :class:`acmm_qpp.errors.ConfigError` naming where it was written.
"""
from __future__ import annotations

import ast
import math
import operator

from acmm_qpp.errors import ConfigError

MAX_LEN = 400           #: longest accepted expression, characters
MAX_EXPONENT = 64       #: largest |numeric exponent| accepted in ``**``
MAX_CONSTANT = 1e300    #: largest |constant| accepted, written or computed (1e308*1e308 is not)


def sympy_module():
    """:mod:`sympy`, imported on first use (it takes a second to import).

    Returns
    -------
    module
        The sympy module.
    """
    import sympy  # deferred: sympy start-up, only for an expression nonlinearity

    return sympy


def _functions():
    sp = sympy_module()

    def sat(x, L=1):
        if sp.sympify(L).is_negative:          # max(−L, min(L, x)) would be the constant L
            raise ValueError(f"sat(x, L): the level L must be ≥ 0, got {L}")
        return sp.Max(-L, sp.Min(L, x))

    def deadzone(x, w):
        if sp.sympify(w).is_negative:          # x − sat(x, w) would be x − w
            raise ValueError(f"deadzone(x, w): the half-width w must be ≥ 0, got {w}")
        return x - sp.Max(-w, sp.Min(w, x))

    return {"sin": sp.sin, "cos": sp.cos, "tan": sp.tan, "exp": sp.exp, "log": sp.log, "sqrt": sp.sqrt,
            "tanh": sp.tanh, "atan": sp.atan, "abs": sp.Abs, "sign": sp.sign, "min": sp.Min, "max": sp.Max,
            "sat": sat, "deadzone": deadzone, "cubic": lambda x: x ** 3}


FUNCTIONS = ("sin", "cos", "tan", "exp", "log", "sqrt", "tanh", "atan", "abs", "sign", "min", "max",
             "sat", "deadzone", "cubic")


def parse_expression(text: str, symbols: dict, where: str = "expression"):
    """Safe parse of ``text`` into a sympy expression over ``symbols`` (name → sympy Symbol).

    Only numbers, +, −, *, /, ** (numeric exponent |e| ≤ 64), parentheses, the given symbols,
    ``pi`` and the functions of :data:`FUNCTIONS` are accepted; everything else raises
    :class:`ConfigError` naming ``where``.

    Parameters
    ----------
    text : str
        The expression.
    symbols : dict
        Name → sympy Symbol of every symbol the expression may use.
    where : str
        Where the expression was written (the config field), for error messages.

    Returns
    -------
    sympy.Expr
        The parsed expression.

    Raises
    ------
    ConfigError
        The expression is empty, too long, malformed, uses something not allowed or is singular.
    """
    sp = sympy_module()
    if not isinstance(text, str) or not text.strip():
        raise ConfigError(f"{where}: empty expression")
    if len(text) > MAX_LEN:
        raise ConfigError(f"{where}: expression longer than {MAX_LEN} characters")
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as exc:
        raise ConfigError(f"{where}: cannot parse {text!r} ({exc.msg})") from None
    expr = _to_sympy(tree, symbols, _functions(), where, text.strip())
    if expr.has(sp.zoo, sp.nan):
        raise ConfigError(f"{where}: expression {text!r} is singular (division by zero)")
    if expr.has(sp.oo, -sp.oo) or any(_beyond_float(c) for c in expr.atoms(sp.Number)):
        raise ConfigError(f"{where}: overflow: expression {text!r} has a constant beyond floating point "
                          f"(|c| ≤ {MAX_CONSTANT:.0e})")
    return expr


def _beyond_float(c) -> bool:
    """Whether the sympy number ``c`` (exact integers and rationals included) is beyond
    :data:`MAX_CONSTANT` in magnitude."""
    try:
        return not abs(float(c)) <= MAX_CONSTANT
    except (OverflowError, TypeError, ValueError):
        return True


def library_expression(form: str, output: int, gain: str, level: float | None) -> str:
    """Expression text of a library form on output ``y<output>``: ``gain·form(y)``.

    Parameters
    ----------
    form : {"saturation", "dead_zone", "cubic", "sin"}
        The library form.
    output : int
        Number of the output (1-based).
    gain : str
        The gain, as expression text.
    level : float or None
        Saturation level or dead-zone half-width, in the units of y (saturation default 1).

    Returns
    -------
    str
        The expression text.

    Raises
    ------
    ConfigError
        A dead zone without a level, or an unknown form.
    """
    y = f"y{output}"
    if form == "saturation":
        return f"({gain})*sat({y}, {level if level is not None else 1.0})"
    if form == "dead_zone":
        if level is None:
            raise ConfigError("nonlinearity: dead_zone needs level (half-width of the dead zone)")
        return f"({gain})*deadzone({y}, {level})"
    if form == "cubic":
        return f"({gain})*{y}**3"
    if form == "sin":
        return f"({gain})*sin({y})"
    raise ConfigError(f"nonlinearity: unknown library form {form!r}")


_BINOPS = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul, ast.Div: operator.truediv}


def _float_sized(a, b) -> bool:
    """Whether the constant a**b stays within floating point (1e-300 ≤ |value| ≤ 1e300, or 0)."""
    try:
        x, e = abs(complex(a)), abs(complex(b))
    except (OverflowError, TypeError, ValueError):
        return False
    return x == 0 or math.isfinite(x) and e * abs(math.log10(x)) <= 300


def _to_sympy(node, symbols: dict, funcs: dict, where: str, text: str):
    """The sympy expression of one node of the expression's :mod:`ast` tree (recursive), or a
    :class:`ConfigError` for anything not whitelisted (:func:`parse_expression`)."""
    sp = sympy_module()

    def conv(node):
        return _to_sympy(node, symbols, funcs, where, text)

    if isinstance(node, ast.Expression):
        return conv(node.body)
    if isinstance(node, ast.Constant) and type(node.value) in (int, float):
        if not abs(node.value) <= MAX_CONSTANT:          # 1e400 is inf as a float
            raise ConfigError(f"{where}: overflow: the constant {ast.get_source_segment(text, node) or node.value} "
                              f"in {text!r} is beyond floating point (|c| ≤ {MAX_CONSTANT:.0e})")
        return sp.Integer(node.value) if isinstance(node.value, int) else sp.Float(node.value)
    if isinstance(node, ast.Name):
        if node.id in symbols:
            return symbols[node.id]
        if node.id == "pi":
            return sp.pi
        if node.id in funcs:
            raise ConfigError(f"{where}: function {node.id!r} used without arguments")
        raise ConfigError(f"{where}: unknown symbol {node.id!r} (allowed: "
                          f"{', '.join(sorted(symbols)) or 'none'}, pi)")
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
        v = conv(node.operand)
        return -v if isinstance(node.op, ast.USub) else v
    if isinstance(node, ast.BinOp):
        a, b = conv(node.left), conv(node.right)
        if type(node.op) in _BINOPS:
            return _BINOPS[type(node.op)](a, b)
        if isinstance(node.op, ast.Pow):
            if b.is_number and (not b.is_finite or abs(complex(b)) > MAX_EXPONENT):
                raise ConfigError(f"{where}: exponent {b} too large (|e| ≤ {MAX_EXPONENT})")
            if a.is_number and b.is_number and not _float_sized(a, b):
                # a constant power is computed exactly: (9**64)**64 nested would build numbers of
                # thousands of digits (and take minutes) before any check on the values
                raise ConfigError(f"{where}: the constant power in {text!r} is beyond floating point "
                                  f"(|value| outside 1e-300 … 1e300)")
            return a ** b
        hint = " (powers are written **)" if isinstance(node.op, ast.BitXor) else ""
        raise ConfigError(f"{where}: operator {type(node.op).__name__} not allowed{hint}")
    if isinstance(node, ast.Call):
        if not isinstance(node.func, ast.Name) or node.func.id not in funcs:
            name = node.func.id if isinstance(node.func, ast.Name) else ast.unparse(node.func)[:40]
            raise ConfigError(f"{where}: unknown function {name!r} (allowed: {', '.join(FUNCTIONS)})")
        if node.keywords:
            raise ConfigError(f"{where}: keyword arguments not allowed in {node.func.id}()")
        args = [conv(x) for x in node.args]
        if not args and node.func.id in ("min", "max"):      # sympy's Max() is −∞, Min() +∞
            raise ConfigError(f"{where}: {node.func.id}() needs at least one argument")
        try:
            return funcs[node.func.id](*args)
        except TypeError:
            raise ConfigError(f"{where}: wrong number of arguments to {node.func.id}()") from None
        except ValueError as exc:
            raise ConfigError(f"{where}: {exc}") from None
    raise ConfigError(f"{where}: syntax {type(node).__name__} not allowed in {text!r}")
