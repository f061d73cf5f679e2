"""Fixed figures of the PoKeys pulse engine, with their units in their names.

The figures of one device model (axes, pulses per slot, entry formats) are in
:mod:`~cosim.controllers.pokeys.models`; the ones here are shared by every model. User input is
checked with :mod:`cosim.validate`: a bad value raises :class:`~cosim.errors.ConfigurationError`
naming the field, the value and the allowed range, e.g. ``fill_buffer slot 3 axis x: pulses per
slot = 26 is not allowed (allowed: -25..25 ...)``.

Times here are vendor figures in nanoseconds; the engine converts them once to ticks of the
simulation's resolution (``sim.ticks(SLOT_NS, "ns")``), which refuses a figure that is not a
whole number of ticks.
"""

from __future__ import annotations

from cosim.validate import integer

SLOT_NS = 1_000_000
"""Length of a time slot [ns]: the pulse frequency is constant inside a slot."""
SLOTS_PER_S = 1_000_000_000 // SLOT_NS
"""Slots per second (1000)."""
MAX_PULSES_PER_SLOT = 25
"""Most pulses the PoKeys56 generator (pulse engine v1) emits per axis in one slot."""
MAX_RATE_HZ = MAX_PULSES_PER_SLOT * SLOTS_PER_S
"""25 kHz: the highest pulse frequency of the PoKeys56 (25 pulses per 1 ms slot)."""
BUFFER_SLOTS = 128
"""Depth of the slot buffer (128 slots = 128 ms of buffered motion), every model."""
ENTRY_BYTES = 3
"""Bytes per slot entry of pulse engine v1: one per axis x, y, z."""
COUNT_BITS = 7
"""Bits of the pulse count in an axis byte; the MSB is the direction bit."""
COUNT_MASK = (1 << COUNT_BITS) - 1
DIRECTION_BIT = 1 << COUNT_BITS
FILL_SLOTS_PER_PACKET = 18
"""Slots one 64-byte fill-buffer packet carries (54 data bytes); the host model's default."""
INTERNAL_LOOKAHEAD_SLOTS = 10
"""Slots the internal controller keeps queued ahead (hence the document's 10 ms wait)."""

AXES: tuple[str, ...] = ("x", "y", "z")
"""The three axes of the 56 series (and of the 57E's internal generator), index 0..2."""
AXIS_NAMES: tuple[str, ...] = (*AXES, "a", "b", "c", "u", "v")
"""Axis names by index for any model: x, y, z, then a, b, c, u, v for the 8 axes of pulse engine v2."""

PINS: dict[int, str] = {
    32: "x.limit_pos", 33: "y.limit_pos", 34: "z.limit_pos",
    35: "x.limit_neg", 36: "y.limit_neg", 37: "z.limit_neg",
    38: "x.dir", 39: "y.dir", 40: "z.dir",
    46: "x.step", 48: "y.step", 49: "z.step",
    47: "x.home", 50: "y.home", 51: "z.home",
    52: "emergency",
}
"""PoKeys56 pin number -> model signal (without the ``pokeys.`` prefix). Pin 47 is home x, not a step."""


def axis_names(count: int) -> str:
    """The allowed-range text of an axis index for ``count`` axes, e.g. ``0..2 (x, y, z)``."""
    return f"0..{count - 1} ({', '.join(AXIS_NAMES[:count])})"


def check_axis(axis: object, *, where: str = "", count: int = 3) -> int:
    """An axis index ``0..count-1`` (:func:`cosim.validate.integer`); :meth:`PulseEngine.axis` checks its own count."""
    return integer(axis, "axis", low=0, high=count - 1, allowed=axis_names(count), where=where)
