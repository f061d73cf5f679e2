"""Speed profiles quantised to slots, in exact integer arithmetic.

The pulse frequency is constant inside a slot, so a motion profile is a sequence of per-slot
speeds. Speeds are held as integers in units of ``1/scale`` pulse per slot, positions in
``1/scale`` pulse; ``scale`` is chosen so that the maximum speed, the acceleration and the
deceleration (and every whole pulses/s rate) are exact. The pulses of a slot are then

    count = floor(p_after / scale) - floor(p_before / scale)

which carries every fractional remainder to later slots exactly: the counts of a move add up to
its distance, and no slot exceeds the maximum speed.

Trapezoid rule (position control): each slot takes the highest speed ``u`` that is reachable
from the previous slot's speed (``v - decel <= u <= v + accel``, ``u <= vmax``) and from which
the axis can still stop at the target by decelerating ``decel`` per slot. The distance covered
from speed ``u`` (this slot included) while decelerating is ``T(u) = sum_k max(0, u - k*decel)``
for k = 0, 1, ...; the largest ``u`` with ``T(u) <= remaining`` has a closed form, so the ramp
down lands exactly on the target.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from fractions import Fraction
from math import isqrt, lcm

from cosim.errors import ConfigurationError

SPEED_QUANTUM_DEN = 1000
"""``scale`` is a multiple of this, so whole pulses/s speeds are exact at 1 ms slots."""


@dataclass(frozen=True)
class SlotLimits:
    """Speed limits in integer units (``1/scale`` pulse per slot, per slot^2).

    Parameters
    ----------
    scale : int
        Sub-pulse resolution.
    vmax : int
        Maximum speed [1/scale pulse per slot].
    accel, decel : int
        Acceleration and deceleration [1/scale pulse per slot^2], > 0.
    """

    scale: int
    vmax: int
    accel: int
    decel: int

    @classmethod
    def exact(cls, vmax: Fraction, accel: Fraction, decel: Fraction, *, scale: int = 1) -> SlotLimits:
        """Limits from pulses/slot and pulses/slot^2 fractions, with a scale that makes all exact."""
        if vmax <= 0 or accel <= 0 or decel <= 0:
            raise ConfigurationError(f"speed limits must be > 0; got vmax={vmax}, accel={accel}, decel={decel}")
        q = lcm(scale, SPEED_QUANTUM_DEN, vmax.denominator, accel.denominator, decel.denominator)
        return cls(q, int(vmax * q), int(accel * q), int(decel * q))

    def speed(self, per_slot: Fraction) -> int:
        """A speed [pulses/slot] in units of this scale (floored towards zero if not exact)."""
        value = per_slot * self.scale
        return int(value)  # int() truncates towards zero


def stop_distance(u: int, decel: int) -> int:
    """``T(u)``: distance covered from speed ``u`` (this slot included) decelerating ``decel`` per slot."""
    if u <= 0:
        return 0
    m = -(-u // decel) - 1  # slots after this one with a positive speed
    return (m + 1) * u - decel * m * (m + 1) // 2


def fastest_stoppable(remaining: int, decel: int) -> int:
    """The largest speed ``u >= 0`` with ``stop_distance(u, decel) <= remaining``."""
    if remaining <= 0:
        return 0
    m = (isqrt(8 * (remaining // decel) + 1) - 1) // 2
    while decel * (m + 1) * (m + 2) // 2 <= remaining:
        m += 1
    while m > 0 and decel * m * (m + 1) // 2 > remaining:
        m -= 1
    return (remaining + decel * m * (m + 1) // 2) // (m + 1)


def fastest_arriving(remaining: int, decel: int, speed: int) -> int:
    """The largest speed ``u >= 0`` from which the slots faster than ``speed`` cover at most ``remaining``.

    Decelerating ``decel`` per slot from ``u``, the slots with a speed above ``speed`` cover
    ``T(u) = m*u - decel*m*(m-1)/2`` (``m`` of them); ``speed = 0`` is :func:`fastest_stoppable`.
    The host planner brakes with it towards a corner that may be passed at ``speed``.

    Examples
    --------
    >>> fastest_arriving(10, 1, 0), fastest_stoppable(10, 1)
    (4, 4)
    >>> fastest_arriving(10, 1, 3)  # 5, 4 cover 9 above 3; 6, 5, 4 would cover 15
    5
    """
    if remaining <= 0:
        return max(0, speed) if remaining == 0 else 0
    if speed <= 0:
        return fastest_stoppable(remaining, decel)
    # m: the most slots above ``speed`` that end exactly at speed + m*decel within ``remaining``
    b = 2 * speed + decel
    m = (isqrt(b * b + 8 * decel * remaining) - b) // (2 * decel)
    while m * speed + decel * m * (m + 1) // 2 > remaining:
        m -= 1
    while (m + 1) * speed + decel * (m + 1) * (m + 2) // 2 <= remaining:
        m += 1
    return max(speed + decel * m, (remaining + decel * m * (m + 1) // 2) // (m + 1))


def speed_to_cover(v: int, remaining: int, limits: SlotLimits) -> int:
    """Next slot speed (>= 0) towards a target ``remaining`` ahead, from speed ``v`` (>= 0).

    If the axis cannot stop in time any more (it started too fast), it decelerates at the limit
    and overshoots.
    """
    low = max(0, v - limits.decel)
    high = min(limits.vmax, v + limits.accel)
    return max(low, min(fastest_stoppable(remaining, limits.decel), high))


def speed_towards(v: int, target: int, limits: SlotLimits) -> int:
    """Next slot speed (signed) from ``v`` towards the signed speed ``target`` (clamped to vmax)."""
    w = max(-limits.vmax, min(limits.vmax, target))
    if v == w:
        return v
    if v * w >= 0 and abs(w) > abs(v):  # same side (or from rest): accelerate
        step = min(abs(w), abs(v) + limits.accel)
        return step if w > 0 else -step
    if v * w > 0:  # same side, slower: decelerate to the target speed
        step = max(abs(w), abs(v) - limits.decel)
        return step if v > 0 else -step
    step = max(0, abs(v) - limits.decel)  # stop first, then reverse
    return step if v > 0 else -step


class Mode(Enum):
    """What the internal controller of an axis is doing."""

    IDLE = 0
    POSITION = 1  # internal position control: towards a target
    SPEED = 2  # internal speed control (and jogging): towards a speed


class AxisMotion:
    """Per-slot motion of one coordinate: a position or a speed reference.

    Parameters
    ----------
    limits : SlotLimits
    position : int
        Starting position [pulses].

    Examples
    --------
    >>> motion = AxisMotion(SlotLimits.exact(Fraction(5), Fraction(1), Fraction(1)), position=0)
    >>> motion.move_to(20)
    >>> [motion.step() for _ in range(8)]
    [1, 2, 3, 4, 4, 3, 2, 1]
    """

    def __init__(self, limits: SlotLimits, *, position: int = 0) -> None:
        self.limits = limits
        self.p = position * limits.scale  # exact position [1/scale pulse]
        self.v = 0  # speed of the last slot [1/scale pulse per slot]
        self.mode = Mode.IDLE
        self._target = 0

    @property
    def position(self) -> int:
        """Position [pulses] (floor of the exact position)."""
        return self.p // self.limits.scale

    @property
    def done(self) -> bool:
        """True when a position move has arrived at rest (always False in speed mode)."""
        return self.mode is Mode.IDLE or (self.mode is Mode.POSITION and self.v == 0 and self.p == self._target)

    def move_to(self, target: int) -> None:
        """Position control: go to ``target`` [pulses] within the limits."""
        self.mode = Mode.POSITION
        self._target = target * self.limits.scale

    def run_at(self, speed_per_slot: Fraction) -> None:
        """Speed control: run at ``speed_per_slot`` [pulses/slot, signed] within the limits."""
        self.mode = Mode.SPEED
        self._target = self.limits.speed(speed_per_slot)

    def halt(self) -> None:
        """Hard stop: speed 0 at once, no reference."""
        self.mode = Mode.IDLE
        self.v = 0

    def reset_position(self, position: int) -> None:
        """Set the position [pulses] (drops the sub-pulse remainder)."""
        self.p = position * self.limits.scale

    def step(self) -> int:
        """Advance one slot; return the signed pulses of that slot."""
        if self.mode is Mode.IDLE:
            return 0
        if self.mode is Mode.SPEED:
            self.v = speed_towards(self.v, self._target, self.limits)
        else:
            self.v = self._position_speed()
        before = self.p
        self.p += self.v
        if self.mode is Mode.POSITION and self.p == self._target and abs(self.v) <= self.limits.decel:
            self.v = 0  # arrived: the next slot's speed is 0 anyway
        return self.p // self.limits.scale - before // self.limits.scale

    def _position_speed(self) -> int:
        remaining = self._target - self.p
        if remaining == 0 and self.v == 0:
            return 0
        sign = 1 if remaining > 0 or (remaining == 0 and self.v < 0) else -1
        if self.v * sign < 0 or remaining == 0:  # moving away (or arrived too fast): brake first
            u = max(0, abs(self.v) - self.limits.decel)
            return u if self.v > 0 else -u
        return sign * speed_to_cover(abs(self.v), abs(remaining), self.limits)
