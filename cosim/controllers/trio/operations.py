"""The operations a compiled Trio BASIC program is made of, and the arithmetic of its expressions.

An operation is ``op(run, pc) -> next pc`` (it may set ``run.pending`` to an event the program
waits for); an expression is ``expr(run) -> value``. Arithmetic keeps every result in the variable
format (:func:`~cosim.controllers.trio.values.fit`); logical operators act on the integer parts;
``+`` joins strings and comparisons compare them. An error is a
:class:`~cosim.controllers.trio.runtime.BasicError` with its number (``RUN_ERROR``).
"""

from __future__ import annotations

from collections.abc import Callable
from fractions import Fraction
from typing import TYPE_CHECKING, Any

from cosim.controllers.trio.runtime import BasicError
from cosim.controllers.trio.values import Datum, Value, fit, integer_part, to_text
from cosim.errors import ConfigurationError

if TYPE_CHECKING:
    from cosim.controllers.trio.runtime import BasicRun

Op = Callable[["BasicRun", int], int]
Expr = Callable[["BasicRun"], Datum]
TRUE_VALUE, FALSE_VALUE = -1, 0


def _both_numbers(a: Datum, b: Datum, op: str) -> tuple[Value, Value]:
    if isinstance(a, str) or isinstance(b, str):
        other = "a string" if isinstance(a, str) and isinstance(b, str) else "a number"
        raise BasicError(f"{op} of a string and {other} is not allowed (allowed: numbers; + joins two strings)", 5)
    return a, b


def _fit(value: Value) -> Value:
    try:
        return fit(value)
    except ConfigurationError as exc:
        raise BasicError(str(exc), 9) from None


def _add(a: Datum, b: Datum) -> Datum:
    if isinstance(a, str) and isinstance(b, str):
        return a + b
    x, y = _both_numbers(a, b, "+")
    return _fit(x + y)


def _sub(a: Datum, b: Datum) -> Datum:
    x, y = _both_numbers(a, b, "-")
    return _fit(x - y)


def _mul(a: Datum, b: Datum) -> Datum:
    x, y = _both_numbers(a, b, "*")
    return _fit(x * y)


def _div(a: Datum, b: Datum) -> Datum:
    x, y = _both_numbers(a, b, "/")
    if y == 0:
        raise BasicError("division by zero", 2)
    return _fit(Fraction(x) / y)


def _mod(a: Datum, b: Datum) -> Datum:
    x, y = (integer_part(v) for v in _both_numbers(a, b, "MOD"))
    if y == 0:
        raise BasicError("MOD by zero", 2)
    if x < 0 or y < 0:
        raise BasicError(f"MOD operand = {min(x, y)} is not allowed (allowed: >= 0 (the sign rule of MOD for "
                         "negative numbers is not in the facts at hand))", 1)
    return x % y


def _power(a: Datum, b: Datum) -> Datum:
    x, y = _both_numbers(a, b, "^")
    n = integer_part(y)
    if n != y or not -64 <= n <= 64:
        raise BasicError(f"exponent = {to_text(y)} is not allowed (allowed: a whole number -64..64)", 1)
    if x == 0 and n < 0:
        raise BasicError("division by zero (0 to a negative power)", 2)
    return _fit(Fraction(x) ** n)


def _logic(fn: Callable[[int, int], int], name: str) -> Callable[[Datum, Datum], Datum]:
    def op(a: Datum, b: Datum) -> Datum:
        x, y = _both_numbers(a, b, name)
        return fn(integer_part(x), integer_part(y))
    return op


def _compare(fn: Callable[[Any, Any], bool]) -> Callable[[Datum, Datum], Datum]:
    def op(a: Datum, b: Datum) -> Datum:
        if isinstance(a, str) != isinstance(b, str):
            raise BasicError("a comparison of a string with a number is not allowed (allowed: two numbers or two "
                             "strings)", 5)
        return TRUE_VALUE if fn(a, b) else FALSE_VALUE
    return op


BINARY: dict[str, Callable[[Datum, Datum], Datum]] = {
    "+": _add, "-": _sub, "*": _mul, "/": _div, "MOD": _mod, "^": _power,
    "AND": _logic(lambda x, y: x & y, "AND"), "OR": _logic(lambda x, y: x | y, "OR"),
    "XOR": _logic(lambda x, y: x ^ y, "XOR"),
    "<": _compare(lambda a, b: a < b), ">": _compare(lambda a, b: a > b), "<=": _compare(lambda a, b: a <= b),
    ">=": _compare(lambda a, b: a >= b), "<>": _compare(lambda a, b: a != b), "=": _compare(lambda a, b: a == b),
}


def negate(operand: Expr) -> Expr:
    def evaluate(run: BasicRun) -> Datum:
        value = operand(run)
        if isinstance(value, str):
            raise BasicError("- of a string is not allowed", 5)
        return _fit(-value)
    return evaluate


def logical_not(operand: Expr) -> Expr:
    def evaluate(run: BasicRun) -> Datum:
        value = operand(run)
        if isinstance(value, str):
            raise BasicError("NOT of a string is not allowed", 5)
        return ~integer_part(value)
    return evaluate


def constant(value: Datum) -> Expr:
    return lambda run: value


def chain(first: Expr, rest: list[tuple[Callable[[Datum, Datum], Datum], Expr]]) -> Expr:
    def evaluate(run: BasicRun) -> Datum:
        value = first(run)
        for op, operand in rest:
            value = op(value, operand(run))
        return value

    return evaluate


def truth(value: Datum) -> bool:
    """A condition's value: any non-zero number is TRUE; a string is an error."""
    if isinstance(value, str):
        raise BasicError("a string is not a condition (allowed: a number; TRUE is any value but 0)", 5)
    return value != 0


# -- operations -----------------------------------------------------------------------------------
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
    return lambda run, pc: pc + 1 if truth(condition(run)) else target


def gosub(target: int) -> Op:
    def op(run: BasicRun, pc: int) -> int:
        run.call_gosub(pc + 1)
        return target

    return op


def on_jump(selector: Expr, targets: list[int], *, sub: bool) -> Op:
    """``ON n GOTO/GOSUB l1, l2, ...``: to the n-th label (1-based); out of range: the next statement."""
    def op(run: BasicRun, pc: int) -> int:
        value = selector(run)
        if isinstance(value, str):
            raise BasicError("ON ... GOTO needs a number", 5)
        k = integer_part(value)
        if not 1 <= k <= len(targets):
            return pc + 1
        if sub:
            run.call_gosub(pc + 1)
        return targets[k - 1]

    return op


def for_init(var: str, start: Expr, stop: Expr, step: Expr, exit_pc: int,
             store: Callable[[BasicRun, str, Datum], None]) -> Op:
    def op(run: BasicRun, pc: int) -> int:
        value, limit, increment = start(run), stop(run), step(run)
        if isinstance(value, str) or isinstance(limit, str) or isinstance(increment, str):
            raise BasicError("FOR needs numbers", 5)
        if increment == 0:
            raise BasicError("FOR STEP = 0 is not allowed (allowed: not 0)", 1)
        run.loops[pc] = (limit, increment)
        store(run, var, value)
        past = value > limit if increment > 0 else value < limit
        return exit_pc if past else pc + 1

    return op


def for_next(var: str, init: int, body: int, load: Callable[[BasicRun, str], Datum],
             store: Callable[[BasicRun, str, Datum], None]) -> Op:
    def op(run: BasicRun, pc: int) -> int:
        state = run.loops.get(init)
        if state is None:
            raise BasicError(f"NEXT {var} without its FOR (a GOTO into the loop?)", 6)
        limit, increment = state
        current = load(run, var)
        if isinstance(current, str):
            raise BasicError("FOR needs numbers", 5)
        try:
            value = fit(current + increment, var)
        except ConfigurationError as exc:
            raise BasicError(str(exc), 9) from None
        store(run, var, value)
        stored = load(run, var)
        if isinstance(stored, str):
            raise BasicError("FOR needs numbers", 5)
        past = stored > limit if increment > 0 else stored < limit
        return pc + 1 if past else body

    return op
