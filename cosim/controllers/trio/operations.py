"""The operations a compiled Trio BASIC program is made of, and the arithmetic of its expressions.

An operation is ``op(run, pc) -> next pc`` (it may set ``run.pending`` to an event the program
waits for); an expression is ``expr(run) -> value``. Arithmetic keeps every result in the variable
format (:func:`~cosim.controllers.trio.values.fit`); logical operators act on the integer parts.
"""

from __future__ import annotations

from collections.abc import Callable
from fractions import Fraction
from typing import TYPE_CHECKING, Any

from cosim.controllers.trio.profile import sqrt_down
from cosim.controllers.trio.values import Value, fit, integer_part, to_text
from cosim.errors import ConfigurationError

if TYPE_CHECKING:
    from cosim.controllers.trio.basic import BasicRun

Op = Callable[["BasicRun", int], int]
Expr = Callable[["BasicRun"], Value]
TRUE_VALUE, FALSE_VALUE = -1, 0


def _div(a: Value, b: Value) -> Value:
    if b == 0:
        raise ConfigurationError("division by zero")
    return fit(Fraction(a) / b)


def _mod(a: Value, b: Value) -> Value:
    x, y = integer_part(a), integer_part(b)
    if y == 0:
        raise ConfigurationError("MOD by zero")
    if x < 0 or y < 0:
        raise ConfigurationError.out_of_range("MOD operand", min(x, y), ">= 0 (the sign rule of MOD for negative "
                                              "numbers is not in the facts at hand)")
    return x % y


BINARY: dict[str, Callable[[Value, Value], Value]] = {
    "+": lambda a, b: fit(a + b), "-": lambda a, b: fit(a - b), "*": lambda a, b: fit(a * b), "/": _div,
    "MOD": _mod,
    "AND": lambda a, b: integer_part(a) & integer_part(b), "OR": lambda a, b: integer_part(a) | integer_part(b),
    "XOR": lambda a, b: integer_part(a) ^ integer_part(b),
    "<": lambda a, b: TRUE_VALUE if a < b else FALSE_VALUE, ">": lambda a, b: TRUE_VALUE if a > b else FALSE_VALUE,
    "<=": lambda a, b: TRUE_VALUE if a <= b else FALSE_VALUE,
    ">=": lambda a, b: TRUE_VALUE if a >= b else FALSE_VALUE,
    "<>": lambda a, b: TRUE_VALUE if a != b else FALSE_VALUE, "=": lambda a, b: TRUE_VALUE if a == b else FALSE_VALUE,
}


def _sqr(x: Value) -> Value:
    if x < 0:
        raise ConfigurationError.out_of_range("SQR argument", x, ">= 0")
    return fit(sqrt_down(Fraction(x), bits=32))


def _abs(x: Value) -> Value:
    return -x if x < 0 else x


def _sgn(x: Value) -> Value:
    return (x > 0) - (x < 0)


FUNCTIONS: dict[str, Callable[[BasicRun, Value], Value]] = {
    "TABLE": lambda run, n: fit(run.process.table_value(n), "TABLE value"),
    "VR": lambda run, n: run.controller.vr(n),
    "ABS": lambda run, x: _abs(x),
    "INT": lambda run, x: integer_part(x),
    "SGN": lambda run, x: _sgn(x),
    "SQR": lambda run, x: _sqr(x),
    "IN": lambda run, n: run.process.input(n),
    "READ_OP": lambda run, n: run.process.read_op(n),
    "OP": lambda run, n: run.process.read_op(n),
}


def text(value: str) -> Callable[[BasicRun], str]:
    """A PRINT item that is a string."""
    return lambda run: value


def formatted(value: Expr) -> Callable[[BasicRun], str]:
    """A PRINT item that is an expression, as PRINT formats numbers."""
    return lambda run: to_text(value(run))


def chain(first: Expr, rest: list[tuple[Callable[[Value, Value], Value], Expr]]) -> Expr:
    def evaluate(run: BasicRun) -> Value:
        value = first(run)
        for op, operand in rest:
            value = op(value, operand(run))
        return value

    return evaluate


def action(do: Callable[[BasicRun], object]) -> Op:
    """An operation that does ``do(run)`` and goes on."""
    def op(run: BasicRun, pc: int) -> int:
        do(run)
        return pc + 1

    return op


def wait(event: Callable[[BasicRun], Any]) -> Op:
    def op(run: BasicRun, pc: int) -> int:
        run.pending = event(run)
        return pc + 1

    return op


def jump(target: int) -> Op:
    return lambda run, pc: target


def jump_unless(condition: Expr, target: int) -> Op:
    return lambda run, pc: pc + 1 if condition(run) != 0 else target


def gosub(target: int) -> Op:
    def op(run: BasicRun, pc: int) -> int:
        run.call_gosub(pc + 1)
        return target

    return op


def for_init(var: str, start: Expr, stop: Expr, step: Expr, exit_pc: int) -> Op:
    def op(run: BasicRun, pc: int) -> int:
        value, limit, increment = start(run), stop(run), step(run)
        if increment == 0:
            raise ConfigurationError.out_of_range("FOR STEP", 0, "not 0")
        run.loops[pc] = (limit, increment)
        run.variables[var] = value
        past = value > limit if increment > 0 else value < limit
        return exit_pc if past else pc + 1

    return op


def for_next(var: str, init: int, body: int) -> Op:
    def op(run: BasicRun, pc: int) -> int:
        state = run.loops.get(init)
        if state is None:
            raise ConfigurationError(f"NEXT {var} without its FOR (a GOTO into the loop?)")
        limit, increment = state
        value = run.variables[var] = fit(run.variable(var) + increment, var)
        past = value > limit if increment > 0 else value < limit
        return pc + 1 if past else body

    return op


def command(name: str, values: list[Expr], axis: Callable[[BasicRun], Value | None]) -> Op:
    def op(run: BasicRun, pc: int) -> int:
        args = [v(run) for v in values]
        run.pending = run.command(name, args, axis(run))
        return pc + 1

    return op
