"""The functions of Trio BASIC expressions: arithmetic, trigonometry, strings, I/O reads, bits.

Every function takes the running program and its evaluated arguments and returns a value in the
variable format (numbers through :func:`~cosim.controllers.trio.values.fit`) or a string.
Trigonometry, ``EXP``, ``LN`` and ``SQR`` are computed in integer fixed point
(:mod:`.trig`, :func:`~cosim.controllers.trio.profile.sqrt_down`) and rounded to the variable format:
the same bits on every machine.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Callable
from fractions import Fraction
from typing import TYPE_CHECKING

from cosim.controllers.trio.profile import sqrt_down
from cosim.controllers.trio.runtime import BasicError
from cosim.controllers.trio.trig import atan2, cos_sin, exp_down, ln_down, pi_down
from cosim.controllers.trio.values import (
    Datum,
    Value,
    fit,
    hex_text,
    integer_part,
    number,
    parse_number,
    text,
    to_text,
)
from cosim.validate import shown

if TYPE_CHECKING:
    from cosim.controllers.trio.runtime import BasicRun

Function = Callable[..., Datum]
TRUE_VALUE, FALSE_VALUE = -1, 0


def _num(args: tuple[Datum, ...], k: int, name: str) -> Value:
    try:
        return number(args[k], f"{name} argument {k + 1}")
    except BasicError:
        raise
    except Exception as exc:
        raise BasicError(str(exc), 5) from None


def _str(args: tuple[Datum, ...], k: int, name: str) -> str:
    try:
        return text(args[k], f"{name} argument {k + 1}")
    except Exception as exc:
        raise BasicError(str(exc), 5) from None


def _count(value: Value, name: str) -> int:
    n = integer_part(value)
    if n < 0:
        raise BasicError(f"{name} = {n} is not allowed (allowed: >= 0)", 1)
    return n


def pi() -> Value:
    """PI in the variable format."""
    return fit(pi_down())


def _sqr(x: Value) -> Value:
    if x < 0:
        raise BasicError(f"SQR argument = {shown(x)} is not allowed (allowed: >= 0)", 1)
    return fit(sqrt_down(Fraction(x), bits=32))


def _sin(x: Value) -> Value:
    return fit(cos_sin(Fraction(x))[1])


def _cos(x: Value) -> Value:
    return fit(cos_sin(Fraction(x))[0])


def _tan(x: Value) -> Value:
    c, s = cos_sin(Fraction(x))
    if c == 0:
        raise BasicError("TAN of an odd multiple of PI/2 has no value", 1)
    return fit(s / c, "TAN")


def _asin_acos(x: Value, sine: bool) -> Value:
    if not -1 <= x <= 1:
        raise BasicError(f"{'ASIN' if sine else 'ACOS'} argument = {to_text(x)} is not allowed (allowed: -1..1)", 1)
    other = sqrt_down(1 - Fraction(x) ** 2)
    if sine:
        return fit(atan2(Fraction(x), other)) if other or x else 0
    return fit(atan2(other, Fraction(x))) if other or x else 0


def _ln(x: Value) -> Value:
    if x <= 0:
        raise BasicError(f"LN argument = {to_text(x)} is not allowed (allowed: > 0)", 1)
    return fit(ln_down(Fraction(x)))


def _exp(x: Value) -> Value:
    if x > 21:  # e**21.5 > 2**31
        raise BasicError(f"EXP argument = {to_text(x)} is not allowed (allowed: <= 21, a result below 2**31)", 9)
    return fit(exp_down(Fraction(x)))


def _atan2(y: Value, x: Value) -> Value:
    if x == 0 and y == 0:
        return 0
    return fit(atan2(Fraction(y), Fraction(x)))


def _frac(x: Value) -> Value:
    return fit(x - integer_part(x))


def _in(run: BasicRun, *args: Value) -> Value:
    io = run.controller.io
    if not args:  # IN: inputs 0..23 as a number
        return sum(io.read_input(n) << n for n in range(min(24, io.channels)))
    if len(args) == 1:
        return io.read_input(args[0])
    first, last = integer_part(args[0]), integer_part(args[1])
    if last < first or last - first > 23:
        raise BasicError(f"IN({first}, {last}) is not allowed (allowed: a range of at most 24 inputs, first <= last)",
                         1)
    return sum(io.read_input(n) << (n - first) for n in range(first, last + 1))


def _inputs(run: BasicRun, first: int) -> Value:
    """``INPUTS0`` / ``INPUTS1``: inputs ``first..first+15`` as a 16-bit number (bit 0 = input ``first``)."""
    io = run.controller.io
    return sum(io.read_input(n) << (n - first) for n in range(first, min(first + 16, io.channels)))


def _ieee_in(*values: Value) -> Value:
    """``IEEE_IN(b0, b1, b2, b3)``: the IEEE 754 single-precision number of four bytes, b0 the most significant
    (sign and exponent) [?: byte order as in network order]; exact (a float is a binary fraction)."""
    data = bytes(_byte(v, "IEEE_IN byte") for v in values)
    number_ = struct.unpack(">f", data)[0]
    if not math.isfinite(number_):
        raise BasicError(f"IEEE_IN({', '.join(str(b) for b in data)}) is not a finite number", 1)
    return fit(Fraction(number_))


def _ieee_out(value: Value, n: Value) -> Value:
    """``IEEE_OUT(value, n)``: byte ``n`` (0 the most significant) of ``value`` as an IEEE 754 single."""
    k = integer_part(n)
    if not 0 <= k <= 3:
        raise BasicError(f"IEEE_OUT byte = {k} is not allowed (allowed: 0..3)", 1)
    try:
        data = struct.pack(">f", float(value))
    except OverflowError:
        raise BasicError(f"IEEE_OUT value = {float(value)} does not fit an IEEE 754 single", 1) from None
    return data[k]


def _byte(value: Value, name: str) -> int:
    b = integer_part(value)
    if not 0 <= b <= 255:
        raise BasicError(f"{name} = {b} is not allowed (allowed: 0..255)", 1)
    return b


def _read_op(run: BasicRun, *args: Value) -> Value:
    io = run.controller.io
    if len(args) == 1:
        return io.read_output(args[0])
    first, last = integer_part(args[0]), integer_part(args[1])
    if last < first or last - first > 23:
        raise BasicError(f"READ_OP({first}, {last}) is not allowed (allowed: a range of at most 24 outputs)", 1)
    return sum(io.read_output(n) << (n - first) for n in range(first, last + 1))


def _bit(run: BasicRun, bit: Value, vr: Value) -> Value:
    b = integer_part(bit)
    if not 0 <= b <= 23:
        raise BasicError(f"READ_BIT bit = {b} is not allowed (allowed: 0..23)", 1)
    return (integer_part(number(run.controller.vr(vr), "VR")) >> b) & 1


def _mid(s: str, start: Value, count: Value | None = None) -> str:
    begin = _count(start, "MID start") - 1
    if begin < 0:
        raise BasicError("MID start = 0 is not allowed (allowed: >= 1, the first character)", 1)
    return s[begin:] if count is None else s[begin:begin + _count(count, "MID count")]


def _instr(args: tuple[Datum, ...]) -> Value:
    if len(args) == 3:
        start = _count(_num(args, 0, "INSTR"), "INSTR start")
        return text_find(_str(args, 1, "INSTR"), _str(args, 2, "INSTR"), max(start, 1))
    return text_find(_str(args, 0, "INSTR"), _str(args, 1, "INSTR"), 1)


def text_find(haystack: str, needle: str, start: int) -> int:
    """1-based position of ``needle`` in ``haystack`` from ``start`` (0: not found)."""
    return haystack.find(needle, start - 1) + 1


def _str_of(value: Value, width: Value | None = None) -> str:
    shown = to_text(value)
    return shown if width is None else shown.rjust(_count(width, "STR width"))


def _chr(code: Value) -> str:
    n = integer_part(code)
    if not 0 <= n <= 255:
        raise BasicError(f"CHR code = {n} is not allowed (allowed: 0..255)", 1)
    return chr(n)


def _value(s: str) -> Value:
    return parse_number(s)


def _flag(run: BasicRun, n: Value) -> Value:
    return run.controller.flag(n)


def _key(run: BasicRun, channel: Value | None = None) -> Value:
    ch = run.indevice if channel is None else integer_part(channel)
    return TRUE_VALUE if run.controller.channel(ch).waiting else FALSE_VALUE


def _ain(run: BasicRun, channel: Value) -> Value:
    return run.controller.analog_input(channel, where=run.where)


def _motion_error(run: BasicRun) -> Value:
    return run.controller.motion_error()


def _numeric(fn: Callable[..., Value], name: str) -> Function:
    def call(run: BasicRun, *args: Datum) -> Datum:
        return fn(*(_num(args, k, name) for k in range(len(args))))
    return call


def _stringy(fn: Callable[..., Datum], name: str, kinds: str) -> Function:
    """``kinds``: one letter per argument, ``s`` a string, ``n`` a number."""
    def call(run: BasicRun, *args: Datum) -> Datum:
        values = [_str(args, k, name) if kinds[k] == "s" else _num(args, k, name) for k in range(len(args))]
        return fn(*values)
    return call


FUNCTIONS: dict[str, Function] = {
    "TABLE": lambda run, n: fit(run.process.table_value(_num((n,), 0, "TABLE")), "TABLE value"),
    "VR": lambda run, n: run.controller.vr(_num((n,), 0, "VR")),
    "ABS": _numeric(lambda x: -x if x < 0 else x, "ABS"),
    "INT": _numeric(integer_part, "INT"),
    "FRAC": _numeric(_frac, "FRAC"),
    "SGN": _numeric(lambda x: (x > 0) - (x < 0), "SGN"),
    "SQR": _numeric(_sqr, "SQR"),
    "SIN": _numeric(_sin, "SIN"),
    "COS": _numeric(_cos, "COS"),
    "TAN": _numeric(_tan, "TAN"),
    "ATAN": _numeric(lambda x: _atan2(x, 1), "ATAN"),
    "ATAN2": _numeric(_atan2, "ATAN2"),
    "ASIN": _numeric(lambda x: _asin_acos(x, True), "ASIN"),
    "ACOS": _numeric(lambda x: _asin_acos(x, False), "ACOS"),
    "EXP": _numeric(_exp, "EXP"),
    "LN": _numeric(_ln, "LN"),
    "IN": lambda run, *args: _in(run, *(_num(args, k, "IN") for k in range(len(args)))),
    "READ_OP": lambda run, *args: _read_op(run, *(_num(args, k, "READ_OP") for k in range(len(args)))),
    "OP": lambda run, n: run.controller.io.read_output(_num((n,), 0, "OP")),
    "KEY": _key,
    "READ_BIT": lambda run, b, v: _bit(run, _num((b,), 0, "READ_BIT"), _num((v,), 0, "READ_BIT")),
    "FLAG": lambda run, n: _flag(run, _num((n,), 0, "FLAG")),
    "CHR": _stringy(_chr, "CHR", "n"),
    "HEX": _stringy(hex_text, "HEX", "n"),
    "STR": _stringy(_str_of, "STR", "nn"),
    "VAL": _stringy(_value, "VAL", "s"),
    "LEN": _stringy(len, "LEN", "s"),
    "LEFT": _stringy(lambda s, n: s[:_count(n, "LEFT count")], "LEFT", "sn"),
    "RIGHT": _stringy(lambda s, n: s[len(s) - min(len(s), _count(n, "RIGHT count")):], "RIGHT", "sn"),
    "MID": _stringy(_mid, "MID", "snn"),
    "UCASE": _stringy(str.upper, "UCASE", "s"),
    "LCASE": _stringy(str.lower, "LCASE", "s"),
    "INSTR": lambda run, *args: _instr(args),
    "AIN": lambda run, n: _ain(run, _num((n,), 0, "AIN")),
    "MOTION_ERROR": _motion_error,
    "FLAGS": lambda run: run.controller.flags,
    "IEEE_IN": lambda run, *args: _ieee_in(*(_num(args, k, "IEEE_IN") for k in range(4))),
    "IEEE_OUT": lambda run, value, n: _ieee_out(_num((value,), 0, "IEEE_OUT"), _num((n,), 0, "IEEE_OUT")),
    "INPUTS0": lambda run: _inputs(run, 0),
    "INPUTS1": lambda run: _inputs(run, 16),
    **{f"AIN{n}": (lambda run, n=n: _ain(run, n)) for n in range(4)},
    **{f"AINBI{n}": (lambda run, n=n: _ain(run, n)) for n in range(4)},
}
