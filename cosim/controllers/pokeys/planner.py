"""The host's motion planner: multi-axis moves into per-slot pulse counts.

Each :class:`Move` is a straight line from the current position to ``target`` [pulses]. It is
parametrised by the distance ``s`` along its dominant axis (the one with the most pulses, ``S``);
axis i is at ``start_i + floor(d_i * s / S)``. ``s`` follows the slot trapezoid of
:mod:`~cosim.controllers.pokeys.profile` with the path limits that keep every axis within its own
maximum speed, acceleration and deceleration, so every axis count of a slot is at most 25 and the
counts of a move add up to its distances exactly (the remainder is carried, never rounded away).
Moves start and end at rest.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from fractions import Fraction

from cosim.controllers.pokeys.buffer import Entry, encode_entry
from cosim.controllers.pokeys.config import SLOTS_PER_S, AxisConfig
from cosim.controllers.pokeys.limits import AXES, check_int_range, check_positive, check_rate_hz
from cosim.controllers.pokeys.profile import AxisMotion, SlotLimits
from cosim.errors import ConfigurationError

Counts = tuple[int, int, int]


@dataclass(frozen=True)
class Move:
    """A straight move to ``target`` (x, y, z) [pulses].

    Parameters
    ----------
    target : tuple of 3 int
        Absolute end position [pulses].
    speed_hz : number, optional
        Speed limit of the dominant axis [pulses/s] (default: the axis limits only).
    accel : number, optional
        Acceleration and deceleration limit of the dominant axis [pulses/s^2] (default: axis limits).
    """

    target: tuple[int, ...]
    speed_hz: int | Fraction | float | None = None
    accel: int | Fraction | float | None = None

    def __post_init__(self) -> None:
        if len(self.target) != len(AXES):
            raise ConfigurationError.out_of_range("Move target axes", len(self.target), "3 (x, y, z)")
        for a, value in zip(AXES, self.target, strict=True):
            check_int_range(value, "Move target", -(2**31), 2**31 - 1, "pulses", where=f"axis {a}")
        if self.speed_hz is not None:
            check_rate_hz(self.speed_hz, "Move speed_hz")
        if self.accel is not None:
            check_positive(self.accel, "Move accel", "pulses/s^2")


@dataclass(frozen=True)
class Dwell:
    """Stand still for ``slots`` slots."""

    slots: int

    def __post_init__(self) -> None:
        check_int_range(self.slots, "Dwell slots", 0, 10**9, "slots")


def plan_move(start: Sequence[int], move: Move, axes: Sequence[AxisConfig]) -> list[Counts]:
    """Per-slot signed counts of one move from ``start`` [pulses]."""
    deltas = [t - s for t, s in zip(move.target, start, strict=True)]
    dominant = max(abs(d) for d in deltas)
    if dominant == 0:
        return []
    vmax = min(Fraction(axes[i].max_speed_per_slot * dominant, abs(d)) for i, d in enumerate(deltas) if d)
    accel = min(Fraction(axes[i].accel_per_slot2 * dominant, abs(d)) for i, d in enumerate(deltas) if d)
    decel = min(Fraction(axes[i].decel_per_slot2 * dominant, abs(d)) for i, d in enumerate(deltas) if d)
    if move.speed_hz is not None:
        vmax = min(vmax, check_rate_hz(move.speed_hz, "Move speed_hz") / SLOTS_PER_S)
    if move.accel is not None:
        limit = check_positive(move.accel, "Move accel", "pulses/s^2") / SLOTS_PER_S**2
        accel, decel = min(accel, limit), min(decel, limit)
    limits = SlotLimits.exact(vmax, accel, decel)
    path = AxisMotion(limits, position=0)
    path.move_to(dominant)
    den = dominant * limits.scale
    axes_sd = [(-1 if d < 0 else 1, abs(d)) for d in deltas]  # truncate towards the start: symmetric
    slots: list[Counts] = []
    before: tuple[int, ...] = (0, 0, 0)
    while not path.done:
        path.step()
        now = tuple(sign * (dist * path.p // den) for sign, dist in axes_sd)
        slots.append((now[0] - before[0], now[1] - before[1], now[2] - before[2]))
        before = now
    return slots


def plan(steps: Iterable[Move | Dwell], axes: Sequence[AxisConfig], *,
         start: Sequence[int] = (0, 0, 0)) -> list[Counts]:
    """Per-slot signed counts (x, y, z) of a job: moves and dwells in order.

    Examples
    --------
    >>> from cosim.controllers.pokeys.config import uniform_axes
    >>> counts = plan([Move((100, -50, 0)), Dwell(2)], uniform_axes(accel=1_000_000))
    >>> sum(c[0] for c in counts), sum(c[1] for c in counts), counts[-1]
    (100, -50, (0, 0, 0))
    """
    position = list(start)
    out: list[Counts] = []
    for step in steps:
        if isinstance(step, Dwell):
            out.extend([(0, 0, 0)] * step.slots)
        else:
            out.extend(plan_move(position, step, axes))
            position = list(step.target)
    return out


def to_entries(counts: Iterable[Sequence[int]]) -> list[Entry]:
    """Slot entries for per-slot counts; a zero count keeps the axis' previous direction bit."""
    negative = [False, False, False]
    entries = []
    for slot in counts:
        for a, c in enumerate(slot):
            if c:
                negative[a] = c < 0
        entries.append(encode_entry(slot, negative=negative))
    return entries
