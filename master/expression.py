"""A safe evaluator of formulas in one variable, such as the force law of ``pantocosim
pantograph --force "120 + 30*sin(4*pi*t)"``.

The text is parsed with :mod:`ast` and only a whitelist is accepted: numbers, the variable,
the constants ``pi`` and ``e``, ``+ - * / ** %``, comparisons (for ``where``), and calls of
the numpy functions of :data:`FUNCTIONS` with positional arguments. Names, attributes,
subscripts, strings, lambdas and everything else are refused with a message naming the
field and the text. Every number is a float (no integer arithmetic that grows without
bound: ``9**9**9`` overflows to infinity at once, which the caller refuses), and the text and
its syntax tree have size limits, so neither parsing nor evaluation can take long.
"""

from __future__ import annotations

import ast
import math
from typing import Callable

import numpy as np

from pantocosim.core.errors import ParameterError

#: functions a formula may call (numpy's, elementwise)
FUNCTIONS = {name: getattr(np, name) for name in (
    "sin", "cos", "tan", "exp", "log", "sqrt", "abs", "sign", "tanh", "arctan", "minimum",
    "maximum", "where", "heaviside")}
CONSTANTS = {"pi": math.pi, "e": math.e}
#: longest formula [characters] and largest syntax tree [nodes]
MAX_LENGTH = 1000
MAX_NODES = 300

_OPERATORS = (ast.Add, ast.Sub, ast.Mult, ast.Div, ast.Pow, ast.Mod, ast.UAdd, ast.USub,
              ast.Lt, ast.LtE, ast.Gt, ast.GtE, ast.Eq, ast.NotEq)
_NODES = (ast.Expression, ast.BinOp, ast.UnaryOp, ast.Compare, ast.Call, ast.Name, ast.Load,
          ast.Constant) + _OPERATORS


def _refuse(field: str, text: str, why: str):
    return ParameterError(field, text, why)


def _check(tree: ast.AST, field: str, text: str, variable: str) -> None:
    accepted = (f"use numbers, {variable}, pi, e, + - * / ** % and "
                f"{', '.join(sorted(FUNCTIONS))}")
    nodes = list(ast.walk(tree))
    if len(nodes) > MAX_NODES:
        raise _refuse(field, text, f"too long a formula ({len(nodes)} terms, at most "
                      f"{MAX_NODES})")
    for node in nodes:
        if not isinstance(node, _NODES):
            raise _refuse(field, text, f"{type(node).__name__.lower()} not allowed; {accepted}")
        if isinstance(node, ast.Constant) and (isinstance(node.value, bool)
                                               or not isinstance(node.value, (int, float))):
            raise _refuse(field, text, f"{node.value!r} is not a number; {accepted}")
        if isinstance(node, ast.Name) and node.id != variable and node.id not in CONSTANTS \
                and node.id not in FUNCTIONS:
            raise _refuse(field, text, f"unknown name {node.id!r}; {accepted}")
        if isinstance(node, ast.Call):
            if not (isinstance(node.func, ast.Name) and node.func.id in FUNCTIONS):
                raise _refuse(field, text, f"only the functions {', '.join(sorted(FUNCTIONS))}"
                              " may be called")
            if node.keywords:
                raise _refuse(field, text, "functions take positional arguments only")
        if isinstance(node, ast.Name) and node.id in FUNCTIONS and not any(
                isinstance(p, ast.Call) and p.func is node for p in nodes):
            raise _refuse(field, text, f"{node.id!r} is a function: call it, e.g. "
                          f"{node.id}({variable})")


class _Floats(ast.NodeTransformer):
    """Integer literals become floats (float powers overflow to inf instead of growing)."""

    def visit_Constant(self, node):
        return ast.copy_location(ast.Constant(float(node.value)), node)


def compile_formula(text: str, field: str = "--force", variable: str = "t",
                    max_abs: float = math.inf, unit: str = "") -> Callable[[float], float]:
    """``f(x)`` of the formula ``text`` in ``variable``; a bad formula, or a value that is not
    a finite number within +/- ``max_abs`` [``unit``], raises :class:`ParameterError`
    naming ``field`` and the text."""
    if not isinstance(text, str) or not text.strip():
        raise _refuse(field, text, "empty formula")
    if len(text) > MAX_LENGTH:
        raise _refuse(field, text[:40] + "...", f"too long a formula ({len(text)} characters,"
                      f" at most {MAX_LENGTH})")
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except (SyntaxError, ValueError, RecursionError, MemoryError) as exc:
        raise _refuse(field, text, f"not a valid formula: {getattr(exc, 'msg', exc)}") from None
    _check(tree, field, text, variable)
    code = compile(ast.fix_missing_locations(_Floats().visit(tree)), f"<{field}>", "eval")
    names = {"__builtins__": {}, **FUNCTIONS, **CONSTANTS}

    def f(x: float) -> float:
        try:
            with np.errstate(all="ignore"):
                value = eval(code, names, {variable: np.float64(x)})  # noqa: S307 - checked
            value = float(value)
        except OverflowError:
            raise _refuse(field, text, f"overflows (beyond 1e308) at {variable} = "
                          f"{x:.6g}") from None
        except (ArithmeticError, ValueError, TypeError) as exc:
            raise _refuse(field, text, f"cannot be evaluated at {variable} = {x:.6g}: "
                          f"{exc}") from None
        if not abs(value) <= max_abs:
            raise _refuse(field, text, f"is {value:.6g}{unit} at {variable} = {x:.6g}; it "
                          f"must stay finite and within +/- {max_abs:g}{unit}")
        return value

    return f
