"""The host's motion planner: multi-axis moves into per-slot pulse counts.

Each :class:`Move` is a straight line from the current position to ``target`` [pulses]. It is
parametrised by the distance ``s`` along its dominant axis (the one with the most pulses, ``S``);
axis i is at ``start_i + floor(d_i * s / S)``. ``s`` follows the slot trapezoid of
:mod:`~cosim.controllers.pokeys.profile` with the path limits that keep every axis within its own
maximum speed, acceleration and deceleration, so no axis count of a slot exceeds the axis' maximum
speed (25 pulses at 25 kHz) and the counts of a move add up to its distances exactly (the
remainder is carried, never rounded away). Moves start and end at rest. A job has as many axes as
the configurations given (3 for the 56 series, up to 8).

It is one planner: a move is a one-segment chain of :mod:`~cosim.controllers.pokeys.trajectory`,
the same speed rule that plans G-code tool paths (:func:`plan_toolpath`, from
:mod:`~cosim.controllers.pokeys.pathplan`, re-exported here).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from fractions import Fraction

from cosim.controllers.pokeys.buffer import Entry, encode_entry
from cosim.controllers.pokeys.config import FASTEST_RATE_HZ, AxisConfig, rate_hz
from cosim.controllers.pokeys.limits import AXIS_NAMES, SLOTS_PER_S
from cosim.controllers.pokeys.pathplan import HostAxis, PathSettings, PlannedJob, plan_toolpath
from cosim.controllers.pokeys.profile import SlotLimits
from cosim.controllers.pokeys.trajectory import Counts, Segment, profile_chain
from cosim.errors import ConfigurationError
from cosim.validate import integer, positive


@dataclass(frozen=True)
class Move:
    """A straight move to ``target`` (x, y, z, ...) [pulses].

    Parameters
    ----------
    target : tuple of int
        Absolute end position, one per planned axis [pulses].
    speed_hz : number, optional
        Speed limit of the dominant axis [pulses/s] (default: the axis limits only; the axes'
        maximum speeds bound it in any case).
    accel : number, optional
        Acceleration and deceleration limit of the dominant axis [pulses/s^2] (default: axis limits).
    """

    target: tuple[int, ...]
    speed_hz: int | Fraction | float | None = None
    accel: int | Fraction | float | None = None

    def __post_init__(self) -> None:
        if not 1 <= len(self.target) <= len(AXIS_NAMES):
            raise ConfigurationError.out_of_range("Move target axes", len(self.target), f"1..{len(AXIS_NAMES)}")
        for a, value in zip(AXIS_NAMES, self.target, strict=False):
            integer(value, "Move target", low=-(2**31), high=2**31 - 1, unit="pulses", where=f"axis {a}")
        if self.speed_hz is not None:
            rate_hz(self.speed_hz, "Move speed_hz", high=FASTEST_RATE_HZ)
        if self.accel is not None:
            positive(self.accel, "Move accel", unit="pulses/s^2")


@dataclass(frozen=True)
class Dwell:
    """Stand still for ``slots`` slots."""

    slots: int

    def __post_init__(self) -> None:
        integer(self.slots, "Dwell slots", low=0, high=10**9, unit="slots")


def plan_move(start: Sequence[int], move: Move, axes: Sequence[AxisConfig]) -> list[Counts]:
    """Per-slot signed counts of one move from ``start`` [pulses]."""
    if len(move.target) != len(axes):
        raise ConfigurationError.out_of_range("Move target axes", len(move.target),
                                              f"{len(axes)} ({', '.join(AXIS_NAMES[:len(axes)])}: the axes planned)")
    deltas = [t - s for t, s in zip(move.target, start, strict=True)]
    dominant = max(abs(d) for d in deltas)
    if dominant == 0:
        return []
    vmax = min(Fraction(axes[i].max_speed_per_slot * dominant, abs(d)) for i, d in enumerate(deltas) if d)
    accel = min(Fraction(axes[i].accel_per_slot2 * dominant, abs(d)) for i, d in enumerate(deltas) if d)
    decel = min(Fraction(axes[i].decel_per_slot2 * dominant, abs(d)) for i, d in enumerate(deltas) if d)
    if move.speed_hz is not None:
        vmax = min(vmax, rate_hz(move.speed_hz, "Move speed_hz", high=FASTEST_RATE_HZ) / SLOTS_PER_S)
    if move.accel is not None:
        limit = positive(move.accel, "Move accel", unit="pulses/s^2") / SLOTS_PER_S**2
        accel, decel = min(accel, limit), min(decel, limit)
    limits = SlotLimits.exact(vmax, accel, decel)
    segment = Segment(tuple(start), tuple(move.target), dominant * limits.scale, limits.vmax, limits.accel,
                      limits.decel)
    return profile_chain([segment])

def plan(steps: Iterable[Move | Dwell], axes: Sequence[AxisConfig], *,
         start: Sequence[int] | None = None) -> list[Counts]:
    """Per-slot signed counts (x, y, z, ...) of a job: moves and dwells in order, from ``start`` (default 0s).

    Examples
    --------
    >>> from cosim.controllers.pokeys.config import uniform_axes
    >>> counts = plan([Move((100, -50, 0)), Dwell(2)], uniform_axes(accel=1_000_000))
    >>> sum(c[0] for c in counts), sum(c[1] for c in counts), counts[-1]
    (100, -50, (0, 0, 0))
    """
    position = list(start) if start is not None else [0] * len(axes)
    out: list[Counts] = []
    shared: dict[Counts, Counts] = {}  # equal slots share one tuple: an hour's job is millions of slots
    planned: dict[tuple[tuple[int, ...], Move], list[Counts]] = {}  # a move repeated from the same start: planned once
    for step in steps:
        if isinstance(step, Dwell):
            out.extend([(0,) * len(axes)] * step.slots)
        else:
            key = (tuple(position), step)
            slots = planned.get(key)
            if slots is None:
                slots = planned[key] = [shared.setdefault(slot, slot) for slot in plan_move(position, step, axes)]
            out.extend(slots)
            position = list(step.target)
    return out


def to_entries(counts: Iterable[Sequence[int]], *, direction_bits: Sequence[bool] | None = None) -> list[Entry]:
    """Slot entries for per-slot counts; a zero count keeps the axis' previous direction bit (``direction_bits``:
    the bits before the first slot, default all clear)."""
    entries = []
    encoded: dict[tuple[tuple[int, ...], tuple[bool, ...]], Entry] = {}  # equal entries: one object, encoded once
    # (counts, direction bits before) -> (entry, direction bits after): a job repeats few slots many times
    after: dict[tuple[tuple[int, ...], tuple[bool, ...]], tuple[Entry, tuple[bool, ...]]] = {}
    negative: tuple[bool, ...] | None = tuple(direction_bits) if direction_bits is not None else None
    for slot in counts:
        counts_ = slot if isinstance(slot, tuple) else tuple(slot)
        if negative is None:
            negative = (False,) * len(counts_)
        known = after.get((counts_, negative))
        if known is None:
            bits = tuple(c < 0 if c else n for c, n in zip(counts_, negative, strict=True))
            entry = encoded.get((counts_, bits))
            if entry is None:
                entry = encoded[counts_, bits] = encode_entry(counts_, negative=bits)
            known = after[counts_, negative] = (entry, bits)
        entry, negative = known
        entries.append(entry)
    return entries

__all__ = ["Counts", "Dwell", "HostAxis", "Move", "PathSettings", "PlannedJob", "plan", "plan_move", "plan_toolpath",
           "to_entries"]
