"""Fixed figures of the PoKeys pulse engine (v1, PoKeys56U/56E) and the checks on user input.

Every bad value raises :class:`~cosim.errors.ConfigurationError` naming the field, the value and
the allowed range, e.g. ``fill_buffer slot 3 axis x: pulses per slot = 26 is not allowed
(allowed: -25..25 ...)``.
"""

from __future__ import annotations

from decimal import Decimal, InvalidOperation
from fractions import Fraction

from cosim.errors import ConfigurationError

SLOT_NS = 1_000_000
"""Length of a time slot [ns]: the pulse frequency is constant inside a slot."""
MAX_PULSES_PER_SLOT = 25
"""Most pulses the generator emits per axis in one slot."""
MAX_RATE_HZ = MAX_PULSES_PER_SLOT * 1_000_000_000 // SLOT_NS
"""25 kHz: the highest pulse frequency (25 pulses per 1 ms slot)."""
BUFFER_SLOTS = 128
"""Depth of the slot buffer (128 slots = 128 ms of buffered motion)."""
ENTRY_BYTES = 3
"""Bytes per slot entry: one per axis."""
COUNT_BITS = 7
"""Bits of the pulse count in an axis byte; the MSB is the direction bit."""
COUNT_MASK = (1 << COUNT_BITS) - 1
DIRECTION_BIT = 1 << COUNT_BITS
FILL_SLOTS_PER_PACKET = 18
"""Slots one 64-byte fill-buffer packet carries (54 data bytes); the host model's default."""
INTERNAL_LOOKAHEAD_SLOTS = 10
"""Slots the internal controller keeps queued ahead (hence the document's 10 ms wait)."""

AXES: tuple[str, ...] = ("x", "y", "z")
"""Axis names, index 0..2."""

PINS: dict[int, str] = {
    32: "x.limit_pos", 33: "y.limit_pos", 34: "z.limit_pos",
    35: "x.limit_neg", 36: "y.limit_neg", 37: "z.limit_neg",
    38: "x.dir", 39: "y.dir", 40: "z.dir",
    46: "x.step", 48: "y.step", 49: "z.step",
    47: "x.home", 50: "y.home", 51: "z.home",
    52: "emergency",
}
"""PoKeys56 pin number -> model signal (without the ``pokeys.`` prefix). Pin 47 is home x, not a step."""


def check_axis(axis: object, *, where: str = "") -> int:
    """Return ``axis`` if it is an axis index 0..2 (x, y, z), else raise."""
    if isinstance(axis, bool) or not isinstance(axis, int) or not 0 <= axis < len(AXES):
        raise ConfigurationError.out_of_range("axis", axis, "0..2 (x, y, z)", where=where)
    return axis


def check_entry_count(count: object, *, where: str = "") -> int:
    """A signed pulse count that fits an axis byte: 7 bits of count plus the direction bit."""
    if isinstance(count, bool) or not isinstance(count, int) or abs(count) > COUNT_MASK:
        raise ConfigurationError.out_of_range(
            "pulse count", count, f"-{COUNT_MASK}..{COUNT_MASK} (7-bit count and a direction bit)", where=where)
    return count


def check_slot_count(count: int, *, where: str = "") -> int:
    """A signed per-slot pulse count the generator can emit (at most 25 per 1 ms slot)."""
    if abs(count) > MAX_PULSES_PER_SLOT:
        raise ConfigurationError.out_of_range(
            "pulses per slot", count,
            f"-{MAX_PULSES_PER_SLOT}..{MAX_PULSES_PER_SLOT} ({MAX_RATE_HZ} Hz at {SLOT_NS} ns slots)", where=where)
    return count


def exact(value: object, name: str, *, where: str = "") -> Fraction:
    """A number as an exact fraction (a float is taken as the decimal it prints as)."""
    if isinstance(value, bool):
        raise ConfigurationError.out_of_range(name, value, "a number", where=where)
    if isinstance(value, int | Fraction):
        return Fraction(value)
    if isinstance(value, float | Decimal | str):
        try:
            return Fraction(Decimal(str(value)))
        except (InvalidOperation, ValueError):
            pass
    raise ConfigurationError.out_of_range(name, value, "a number", where=where)


def check_rate_hz(value: object, name: str, *, where: str = "", allow_zero: bool = False,
                  signed: bool = False) -> Fraction:
    """A pulse rate [pulses/s]: positive (or zero / signed if allowed) and at most 25 kHz."""
    rate = exact(value, name, where=where)
    low = -MAX_RATE_HZ if signed else 0
    ok = low <= rate <= MAX_RATE_HZ and (allow_zero or signed or rate > 0)
    if not ok:
        lower = f"-{MAX_RATE_HZ}" if signed else ("0" if allow_zero else "> 0")
        raise ConfigurationError.out_of_range(name, value, f"{lower}..{MAX_RATE_HZ} pulses/s", where=where)
    return rate


def check_positive(value: object, name: str, unit: str, *, where: str = "") -> Fraction:
    """A strictly positive number (acceleration, deceleration)."""
    number = exact(value, name, where=where)
    if number <= 0:
        raise ConfigurationError.out_of_range(name, value, f"> 0 {unit}", where=where)
    return number


def check_int_range(value: object, name: str, low: int, high: int, unit: str = "", *, where: str = "") -> int:
    """An integer in ``low..high``."""
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        suffix = f" {unit}" if unit else ""
        raise ConfigurationError.out_of_range(name, value, f"{low}..{high}{suffix}", where=where)
    return value
