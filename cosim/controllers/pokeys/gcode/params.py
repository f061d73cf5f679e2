"""Parameters and expressions as LinuxCNC 2.9 evaluates them.

* **Numbered** ``#1``..``#5602``: 1-30 are a subroutine's arguments (local to each call), 31-5000 the
  user's, 5061-5602 the system's (coordinate systems, G28/G30 positions, tool data); ``#0`` and a
  never-set number read 0.
* **Named** ``#<name>`` local to the subroutine (or the main program) that sets it, ``#<_name>``
  global; reading one that does not exist is an error. Names are lower case without spaces.
* **Predefined** read-only globals (``#<_x>``, ``#<_metric>``, ``#<_value>``, ...) come from the
  interpreter through ``predefined(name)``.

Expressions: ``**``, ``* / mod``, ``+ -``, ``eq ne gt ge lt le``, ``and or xor`` (left-associative,
in that order); ``eq``/``ne`` compare within 0.0001 (LinuxCNC's ``TOLERANCE_EQUAL``); ``mod`` is
never negative (``-7 mod 3`` is 2); ``round`` rounds halves away from zero; ``fix`` is the floor,
``fup`` the ceiling; angles are in degrees. Numbers written in the program are exact fractions and
``+ - * /`` of exact numbers stay exact; anything else (functions, ``**``, parameters) is a double,
as in LinuxCNC.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from fractions import Fraction
from typing import Any

from cosim.controllers.pokeys.gcode.syntax import Binary, Exists, Expr, Func, Neg, Num, Param

Number = Fraction | float | int
MAX_PARAMETER = 5602
#: The largest number a program may write or compute (a double holds 1.8e308; a machine needs far less).
LARGEST = 10**15
LARGEST_RESULT = 1e300
TOLERANCE_EQUAL = 0.0001
#: Numbered parameters kept per call (the subroutine's arguments).
LOCAL_NUMBERED = range(1, 31)


class EvalError(Exception):
    """An expression or a parameter that cannot be evaluated (LinuxCNC's message)."""


class Parameters:
    """The numbered, named and predefined parameters of a running program.

    Parameters
    ----------
    predefined : callable
        ``predefined(name)``: the value of a predefined parameter (a name starting with ``_``),
        or None if there is none of that name.
    """

    def __init__(self, predefined: Callable[[str], Number | None]) -> None:
        self.numbered: list[Number] = [0.0] * (MAX_PARAMETER + 1)
        self.globals: dict[str, Number] = {}
        self.frames: list[dict[str, Number]] = [{}]
        self.predefined = predefined

    # -- access ------------------------------------------------------------------------------------
    def read(self, index: Number | str) -> Number:
        if isinstance(index, str):
            if index.startswith("_"):
                value = self.predefined(index)
                if value is not None:
                    return value
                if index in self.globals:
                    return self.globals[index]
            elif index in self.frames[-1]:
                return self.frames[-1][index]
            raise EvalError(f"Named parameter #<{index}> not defined")
        return self.numbered[self.number(index)]

    def exists(self, name: str) -> bool:
        if name.startswith("_"):
            return self.predefined(name) is not None or name in self.globals
        return name in self.frames[-1]

    def number(self, index: Number) -> int:
        n = _integer(index)
        if n is None or not 0 <= n <= MAX_PARAMETER:
            raise EvalError(f"Parameter number out of range: #{_show(index)} (allowed: 0..{MAX_PARAMETER})")
        return n

    def write(self, index: Number | str, value: Number) -> None:
        if isinstance(index, str):
            if index.startswith("_"):
                if self.predefined(index) is not None:
                    raise EvalError(f"Cannot assign to read-only parameter #<{index}>")
                self.globals[index] = value
            else:
                self.frames[-1][index] = value
            return
        self.numbered[self.number(index)] = value

    # -- calls -----------------------------------------------------------------------------------
    def enter(self, args: list[Number]) -> list[Number]:
        """A subroutine call: a new local scope, ``#1``.. the arguments (the rest 0); the caller's 1-30 back."""
        saved = self.numbered[1:31]
        for i in LOCAL_NUMBERED:
            self.numbered[i] = args[i - 1] if i <= len(args) else 0.0
        self.frames.append({})
        return saved

    def leave(self, saved: list[Number]) -> None:
        self.numbered[1:31] = saved
        if len(self.frames) > 1:
            self.frames.pop()

    # -- evaluation -----------------------------------------------------------------------------
    def evaluate(self, expr: Expr) -> Number:
        """The value of ``expr`` with the parameters as they are now."""
        kind = type(expr)
        if kind is Num:
            value = expr.value  # type: ignore[union-attr]
            if value > LARGEST:
                digits = len(str(int(value)))
                raise EvalError(f"a number of {digits} digits is too large (at most {LARGEST:.0e})")
            return value
        if kind is Param:
            index = expr.index  # type: ignore[union-attr]
            return self.read(index if isinstance(index, str) else self.evaluate(index))
        if kind is Neg:
            return -self.evaluate(expr.operand)  # type: ignore[union-attr]
        if kind is Binary:
            return binary(expr.op, self.evaluate(expr.left), self.evaluate(expr.right))  # type: ignore[union-attr]
        if kind is Func:
            return function(expr.name, [self.evaluate(a) for a in expr.args])  # type: ignore[union-attr]
        if kind is Exists:
            return 1 if self.exists(expr.name) else 0  # type: ignore[union-attr]
        raise EvalError(f"cannot evaluate {expr!r}")  # pragma: no cover


def binary(op: str, a: Any, b: Any) -> Number:
    """``a op b`` as LinuxCNC computes it."""
    if op == "+":
        return _finite(a + b)
    if op == "-":
        return _finite(a - b)
    if op == "*":
        return _finite(a * b)
    if op == "/":
        if b == 0:
            raise EvalError("Attempt to divide by zero")
        return _finite(a / b)
    if op == "mod":
        if b == 0:
            raise EvalError("Attempt to divide by zero (mod 0)")
        result = math.fmod(a, b) if isinstance(a, float) or isinstance(b, float) else a - b * int(a / b)
        return result + abs(b) if result < 0 else result
    if op == "**":
        if a < 0 and math.floor(b) != b:
            raise EvalError("Attempt to raise negative to non integer power")
        if a == 0 and b < 0:
            raise EvalError("Attempt to divide by zero (0 to a negative power)")
        try:
            return _finite(math.pow(float(a), float(b)))
        except OverflowError:
            raise EvalError(f"{_show(a)} ** {_show(b)} is too large") from None
    if op == "eq":
        return 1 if abs(a - b) < TOLERANCE_EQUAL else 0
    if op == "ne":
        return 0 if abs(a - b) < TOLERANCE_EQUAL else 1
    if op == "gt":
        return 1 if a > b else 0
    if op == "ge":
        return 1 if a >= b else 0
    if op == "lt":
        return 1 if a < b else 0
    if op == "le":
        return 1 if a <= b else 0
    if op == "and":
        return 0 if a == 0 or b == 0 else 1
    if op == "or":
        return 1 if a != 0 or b != 0 else 0
    if op == "xor":
        return 1 if (a == 0) != (b == 0) else 0
    raise EvalError(f"unknown operator {op!r}")  # pragma: no cover


def function(name: str, args: list[Any]) -> Number:
    """``name[args]`` (angles in degrees)."""
    x = args[0]
    if name == "atan":
        return math.degrees(math.atan2(float(x), float(args[1])))
    if name == "abs":
        return abs(x)
    if name in ("acos", "asin"):
        if not -1 <= x <= 1:
            raise EvalError(f"Argument to {name} out of range")
        return math.degrees(math.acos(x) if name == "acos" else math.asin(x))
    if name == "cos":
        return math.cos(math.radians(x))
    if name == "sin":
        return math.sin(math.radians(x))
    if name == "tan":
        return math.tan(math.radians(x))
    if name == "exp":
        try:
            return math.exp(x)
        except OverflowError:
            raise EvalError(f"exp[{_show(x)}] is too large") from None
    if name == "fix":
        return math.floor(x)
    if name == "fup":
        return math.ceil(x)
    if name == "round":
        return math.floor(x + Fraction(1, 2)) if x >= 0 else -math.floor(-x + Fraction(1, 2))
    if name == "ln":
        if x <= 0:
            raise EvalError("Zero or negative argument to ln")
        return math.log(x)
    if name == "sqrt":
        if x < 0:
            raise EvalError("Negative argument to sqrt")
        return math.sqrt(x)
    raise EvalError(f"unknown function {name!r}")  # pragma: no cover


def _finite(value: Any) -> Number:
    if isinstance(value, float) and not math.isfinite(value):
        raise EvalError("the result is not a finite number")
    if not isinstance(value, float) and abs(value) > LARGEST_RESULT:
        raise EvalError("the result is too large")
    return value


def _integer(value: Any) -> int | None:
    """``value`` as an integer if within 0.0001 of one (LinuxCNC's rule for indices and codes); None if not."""
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return None
    n = round(value)
    return int(n) if abs(value - n) < TOLERANCE_EQUAL else None


def integer(value: Number | None) -> int | None:
    """Public form of :func:`_integer`."""
    return _integer(value)


def _show(value: Number) -> str:
    if isinstance(value, Fraction):
        return str(value.numerator) if value.denominator == 1 else f"{float(value):g}"
    return f"{float(value):g}"


def show(value: Number) -> str:
    """A number as a message shows it (``10``, ``2.5``)."""
    return _show(value)
