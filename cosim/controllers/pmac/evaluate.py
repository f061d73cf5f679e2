"""Expressions and conditions compiled once into Python closures, then evaluated many times.

A PLC scanned every 200 us or a motion program calculated every servo cycle evaluates the same
expressions again and again: :func:`expression` and :func:`condition` turn a syntax tree into a
closure of a :class:`Frame` (the memory, and the coordinate system whose Q-variables apply), so an
evaluation is a few calls, not a walk over the tree. Values stay exact (:mod:`.arith`: integers
where whole, fractions otherwise); an error names the statement's place.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

from cosim.controllers.pmac import arith
from cosim.controllers.pmac.bus import Value
from cosim.controllers.pmac.mvars import Memory, check_number
from cosim.controllers.pmac.nodes import Compare, Cond, Expr, Func, IndVar, Neg, Num, Var, located


class Frame(Protocol):
    """Where an expression is evaluated: the controller's memory and the coordinate system of its Q-variables."""

    memory: Memory
    cs: int


Evaluator = Callable[[Frame], Value]
Test = Callable[[Frame], bool]


def variable_number(var: Var | IndVar, frame: Frame) -> int:
    """The number of a direct or indirect variable now."""
    if isinstance(var, Var):
        return var.number
    return check_number(var.kind, expression(var.index)(frame), var.pos)


def expression(expr: Expr) -> Evaluator:
    """A closure computing ``expr`` in a frame."""
    if isinstance(expr, Num):
        value = expr.value
        return lambda frame: value
    if isinstance(expr, Var):
        kind, number, pos = expr.kind, expr.number, expr.pos
        if kind == "P":
            return lambda frame: frame.memory.p[number]
        return lambda frame: frame.memory.read(kind, number, frame.cs, pos)
    if isinstance(expr, IndVar):
        index = expression(expr.index)
        kind, pos = expr.kind, expr.pos
        return lambda frame: frame.memory.read(kind, check_number(kind, index(frame), pos), frame.cs, pos)
    if isinstance(expr, Neg):
        arg = expression(expr.arg)
        return lambda frame: -arg(frame)
    if isinstance(expr, Func):
        return _function(expr)
    first = expression(expr.first)
    rest = tuple((op, expression(operand)) for op, operand in expr.rest)
    where = str(expr.pos)
    binary = arith.binary
    if len(rest) == 1:
        ((op, second),) = rest
        return lambda frame: binary(op, first(frame), second(frame), where=where)

    def ops(frame: Frame) -> Value:
        value = first(frame)
        for op, operand in rest:
            value = binary(op, value, operand(frame), where=where)
        return value

    return ops


def _function(expr: Func) -> Evaluator:
    arg = expression(expr.arg)
    name, pos = expr.name, expr.pos
    if name in ("ABS", "INT"):
        function = arith.function
        return lambda frame: function(name, arg(frame))

    def transcendental(frame: Frame) -> Value:
        memory = frame.memory
        radians = memory.registers.get_ivar(15) == 1
        q0 = memory.read("Q", 0, frame.cs, pos) if name == "ATAN2" else 0
        with located(pos):
            return arith.function(name, arg(frame), radians=radians, q0=q0)

    return transcendental


_COMPARE: dict[str, Callable[[Value, Value], bool]] = {
    "=": lambda a, b: a == b, "!=": lambda a, b: a != b, "<>": lambda a, b: a != b,
    ">": lambda a, b: a > b, "<": lambda a, b: a < b, "!>": lambda a, b: a <= b, "<=": lambda a, b: a <= b,
    "!<": lambda a, b: a >= b, ">=": lambda a, b: a >= b,
    "~": lambda a, b: -1 < a - b < 1, "!~": lambda a, b: not -1 < a - b < 1,  # (not) approximately equal: within one
}


def condition(cond: Cond) -> Test:
    """A closure testing ``cond`` in a frame (AND and OR stop at the first term that decides)."""
    if isinstance(cond, Compare):
        left, right, compare = expression(cond.left), expression(cond.right), _COMPARE[cond.op]
        if cond.op == "=":
            return lambda frame: left(frame) == right(frame)
        return lambda frame: compare(left(frame), right(frame))
    items = tuple(condition(c) for c in cond.items)
    if cond.op == "AND":
        return lambda frame: all(test(frame) for test in items)
    return lambda frame: any(test(frame) for test in items)


__all__ = ["Evaluator", "Frame", "Test", "condition", "expression", "variable_number"]
