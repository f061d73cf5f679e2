"""The position-gating FIFO of a EURO205X PWM axis (TN20-81, ``PWM_CONTROL`` modes 3 to 6).

``PWM_CONTROL(3, GT/LT, ON/OFF, start, end)`` loads TABLE positions ``start..end`` into a FIFO
up to :data:`~cosim.controllers.trio.params.FIFO_DEPTH` (256) deep; the ON/OFF state is toggled
entry by entry, starting with the given one. The head entry is compared with ``PWM_ENCODER``, a
29-bit count of the axis' step pulses, at every count: GT fires at the first count *above*
``position * UNITS``, LT at the first count *below* it. When the head fires the gate latch takes
its ON/OFF state and the entry leaves the FIFO; the next head is compared from the same count
on, so two positions within one count fire at the same pulse. The gate therefore changes at the
exact instant of the pulse that satisfies the comparison, never on a servo-cycle boundary.

Choices where the note is silent (see ``docs/trio.md``):

* positions are converted with the axis' UNITS at load time; the comparison is exact
  (``count > p`` for a fractional ``p`` is ``count > floor(p)``);
* the 29-bit comparison is wrap-safe: ``count - threshold`` is taken modulo ``2**29`` as a
  signed 29-bit number, so positions and counts may cross the register's wrap;
* entries are compared only while gating is on (``PWM_CONTROL(5)``); ``PWM_CONTROL(4)`` empties
  the FIFO and closes the latch;
* a load that does not fit waits (the calling program with it) and is retried at every servo
  cycle; ``trio.axisN.fifo_waiting`` shows the positions waiting;
* an entry that fires because it was loaded (or gating switched on, or PWM_ENCODER cleared)
  rather than because the axis counted onto it was passed before it could be compared: it is
  *late*. It still toggles the gate at that instant, and its position [units] is recorded in
  ``trio.axisN.gate_late`` so a scenario can report the positions a starved FIFO missed;
  ``trio.axisN.late_positions`` counts them (0 all run long: the FIFO never starved).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from fractions import Fraction
from math import ceil, floor
from typing import TYPE_CHECKING

from simpy.events import Event

from cosim.controllers.trio.counter import StepCounter
from cosim.controllers.trio.outputs import SettledSignal
from cosim.controllers.trio.params import FIFO_DEPTH, PWM_ENCODER_MODULUS
from cosim.signals import Signal
from cosim.timebase import Priority

if TYPE_CHECKING:
    from cosim.kernel import Simulation

_HALF = PWM_ENCODER_MODULUS >> 1


def wrapped_difference(count: int, threshold: int) -> int:
    """``count - threshold`` as a signed 29-bit number (the register's wrap-safe comparison).

    Examples
    --------
    >>> wrapped_difference(5, 3), wrapped_difference(2**29 - 2, 1), wrapped_difference(1, 2**29 - 2)
    (2, -3, 3)
    """
    return ((count - threshold + _HALF) % PWM_ENCODER_MODULUS) - _HALF


@dataclass(frozen=True)
class GateEntry:
    """One FIFO entry.

    Parameters
    ----------
    position : Fraction
        Position as programmed [units].
    threshold : int
        Count the comparison is against [counts]: ``floor(position*UNITS)`` for GT,
        ``ceil(position*UNITS)`` for LT.
    greater : bool
        True for GT (fire at the first count above), False for LT (first count below).
    state : int
        Gate state (1 ON, 0 OFF) the entry sets when it fires.
    """

    position: Fraction
    threshold: int
    greater: bool
    state: int

    @classmethod
    def make(cls, position: Fraction, units: Fraction, *, greater: bool, state: int) -> GateEntry:
        counts = position * units
        return cls(position, floor(counts) if greater else ceil(counts), greater, state)

    def satisfied(self, count: int) -> bool:
        """Does ``count`` satisfy the comparison?"""
        diff = wrapped_difference(count, self.threshold)
        return diff > 0 if self.greater else diff < 0


def first_hit(entry: GateEntry, before: int, sign: int, first: int, count: int) -> int | None:
    """The first pulse ``k`` in ``first..count-1`` of a segment after which the count satisfies ``entry``.

    The count after pulse ``k`` is ``before + sign * (k + 1 - first)`` (``before``: the count after
    pulse ``first - 1``). Whether it satisfies the entry changes only where the wrap-safe difference
    crosses 0 or the wrap (``+-2**28``), so the pulses just at those crossings are the only
    candidates besides ``first``: the answer in O(1), whatever the segment's size.

    Examples
    --------
    >>> e = GateEntry(Fraction(110), 1760, True, 1)
    >>> first_hit(e, 1700, 1, 0, 100), first_hit(e, 1761, 1, 0, 5), first_hit(e, 1800, -1, 0, 100)
    (60, 0, 0)
    >>> first_hit(e, 1700, 1, 0, 50) is None, first_hit(e, 1760, -1, 0, 100) is None
    (True, True)
    """
    d0 = wrapped_difference(before, entry.threshold)  # the difference before pulse `first`
    candidates = {first}
    for edge in (0, _HALF, -_HALF):
        # difference after pulse k: d0 + sign * (k + 1 - first); it reaches edge + e at k = ...
        for e in (-1, 0, 1):
            k = first - 1 + sign * (edge + e - d0)
            if first <= k < count:
                candidates.add(k)
    for k in sorted(candidates):
        if entry.satisfied(before + sign * (k + 1 - first)):
            return k
    return None


def toggled_entries(positions: Sequence[Fraction], units: Fraction, *, greater: bool,
                    first_state: int) -> list[GateEntry]:
    """The entries of one load: the ON/OFF state toggles entry by entry from ``first_state``."""
    return [GateEntry.make(p, units, greater=greater, state=first_state ^ (k & 1))
            for k, p in enumerate(positions)]


class GateFifo:
    """Gating FIFO, gate latch and ``PWM_ENCODER`` of one PWM axis.

    Parameters
    ----------
    sim : Simulation
    prefix : str
        Trace prefix of the axis, e.g. ``trio.axis3``.
    encoder_start : int
        Raw PWM_ENCODER value at power-up.
    """

    def __init__(self, sim: Simulation, prefix: str, *, encoder_start: int = 0) -> None:
        self.sim = sim
        self.prefix = prefix
        self.encoder = StepCounter(encoder_start)
        self.entries: deque[GateEntry] = deque()
        self.latch = 0
        self.gating = False
        self.pwm_on = False
        self.late: list[tuple[int, Fraction]] = []
        self._waiting: deque[tuple[list[GateEntry], Event]] = deque()
        self._plan_id = 0
        self.on_fire: Callable[[GateEntry, int], None] | None = None
        self.output = SettledSignal(sim, f"{prefix}.gate", kind="bit",
                                    description="gate to the laser: FIFO latch while gating is on, "
                                                "else open while PWM is on")
        self.level = Signal(sim, f"{prefix}.fifo_level", kind="int", unit="positions",
                            description="gate positions in the FIFO")
        self.waiting_level = Signal(sim, f"{prefix}.fifo_waiting", kind="int", unit="positions",
                                    description="positions of PWM_CONTROL(3) loads waiting for FIFO space")
        sim.trace.declare(f"{prefix}.gate_late", "real", unit="units",
                          description="position of a gate entry passed before it was loaded (recorded when it fires)")
        self.late_count = Signal(sim, f"{prefix}.late_positions", kind="int", unit="positions",
                                 description="gate entries passed before they were loaded so far (FIFO starvation)")

    # -- PWM_ENCODER --------------------------------------------------------------------------
    #: Brings the servo ticks before now up to date (set by the controller; see :mod:`.servo`).
    sync: Callable[[], None] = staticmethod(lambda: None)

    def encoder_value(self, t: int | None = None) -> int:
        """Raw PWM_ENCODER (0 .. 2**29-1) at ``t`` (default: now)."""
        self.sync()
        return self.encoder.value(self.sim.now if t is None else t) % PWM_ENCODER_MODULUS

    def preset_encoder(self, raw: int) -> None:
        """Load PWM_ENCODER with ``raw`` now (power-up value after ATYPE=35; 0 for PWM_CONTROL(6))."""
        self.encoder.set_value(self.sim.now, raw % PWM_ENCODER_MODULUS)
        self._plan(count_event=False)

    def feed(self, t0: int, duration: int, count: int, sign: int) -> None:
        """The step pulses of a servo cycle (called at ``t0`` when the encoder counts)."""
        self.encoder.feed(t0, duration, count, sign)
        self._plan(count_event=True)

    # -- commands -----------------------------------------------------------------------------
    def load(self, entries: list[GateEntry]) -> Event:
        """``PWM_CONTROL(3, ...)``: an event that succeeds once every entry is in the FIFO."""
        done = self.sim.env.event()
        if not self._waiting and len(self.entries) + len(entries) <= FIFO_DEPTH:
            self._push(entries)
            done.succeed()
        else:
            self._waiting.append((entries, done))
            self.waiting_level.set(self.waiting_level.value + len(entries))
        return done

    @property
    def has_waiting(self) -> bool:
        """Loads wait for FIFO space."""
        return bool(self._waiting)

    def retry_waiting(self) -> None:
        """Servo cycle: move waiting loads in, oldest first, while they fit."""
        while self._waiting and len(self.entries) + len(self._waiting[0][0]) <= FIFO_DEPTH:
            entries, done = self._waiting.popleft()
            self.waiting_level.set(self.waiting_level.value - len(entries))
            self._push(entries)
            done.succeed()

    def empty(self) -> None:
        """``PWM_CONTROL(4)``: empty the FIFO and close the gate latch (waiting loads stay waiting)."""
        self.entries.clear()
        self.level.set(0)
        self.latch = 0
        self._plan_id += 1
        self._refresh()

    def gating_on(self) -> None:
        """``PWM_CONTROL(5)``: the FIFO latch gates the output from now on."""
        self.gating = True
        self._refresh()
        self._plan(count_event=False)

    def gating_off(self) -> None:
        """Gating off (with ``PWM_CONTROL(0)``): the gate no longer depends on the FIFO."""
        self.gating = False
        self._plan_id += 1
        self._refresh()

    def set_pwm_on(self, on: bool) -> None:
        """Tell the gate whether the PWM output is on (an ungated output is open while it is)."""
        self.pwm_on = on
        self._refresh()

    # -- comparison ---------------------------------------------------------------------------
    def _push(self, entries: list[GateEntry]) -> None:
        was_empty = not self.entries
        self.entries.extend(entries)
        self.level.set(len(self.entries))
        if was_empty:
            self._plan(count_event=False)

    def _plan(self, *, count_event: bool) -> None:
        """Fire every head satisfied now, then schedule the head's pulse in the current segment."""
        self._plan_id += 1
        if not self.gating or not self.entries:
            return
        now = self.sim.now
        count = self.encoder.value(now)
        while self.entries and self.entries[0].satisfied(count):
            self._fire(late=not count_event)
        if self.entries:
            self._schedule(self.encoder.happened(now))

    def _schedule(self, first: int) -> None:
        """Schedule the firing of the head at the first pulse ``>= first`` that satisfies it."""
        enc = self.encoder
        count = enc.count
        if first >= count:
            return
        k = first_hit(self.entries[0], enc.after_pulse(first - 1), enc.sign, first, count)
        if k is None:
            return
        plan_id = self._plan_id
        self.sim.call_at(enc.t0 + (k * enc.duration) // count, Priority.SERVO, lambda: self._on_pulse(plan_id, k))

    def _on_pulse(self, plan_id: int, k: int) -> None:
        if plan_id != self._plan_id:
            return  # the FIFO, the gating or the encoder changed since this was planned
        count = self.encoder.after_pulse(k)
        self._fire(late=False)
        while self.entries and self.entries[0].satisfied(count):
            self._fire(late=False)
        self._plan_id += 1
        if self.entries:
            self._schedule(k + 1)

    def _fire(self, *, late: bool) -> None:
        entry = self.entries.popleft()
        self.level.set(len(self.entries))
        self.latch = entry.state
        if late:
            self.late.append((self.sim.now, entry.position))
            self.sim.trace.record(f"{self.prefix}.gate_late", self.sim.now, float(entry.position))
            self.late_count.set(len(self.late))
        if self.on_fire is not None:
            self.on_fire(entry, self.sim.now)
        self._refresh()

    def _refresh(self) -> None:
        self.output.request(self.latch if self.gating else int(self.pwm_on))

