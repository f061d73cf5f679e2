"""Step/direction outputs to a stepper plant (the Stepper FMU, or any plant with the same roles).

A controller announces every stretch of evenly spread pulses as one pulse-train segment
``(t0, duration, count, direction)`` whose pulse k is at ``t0 + (k * duration) // count`` (the
rule of :mod:`cosim.pulses`): a PoKeys slot (announced at the slot start, ``t0`` = slot start +
direction set-up), a Trio servo cycle. :func:`couple_stepper` hands the segments to the plant in
one of two ways, and neither costs a kernel event per segment nor stops a controller's
:meth:`~cosim.kernel.Simulation.skip_to` shortcut:

**Segments** (the Stepper FMU on FMI 3.0; any plant with a ``step_segments`` Float64 array input of
rows ``(start [s], duration [s], signed pulses)``): each segment becomes a row, pulse k at
``start + k duration / |pulses|``, which is the controller's instant plus
``(k * duration mod count) / count`` ticks: **less than one tick later**, never in another segment.
The rows are written just before the plant's next step, whatever asks for it
(:meth:`~cosim.master.Plant.before_step`), so the plant is stepped only when an output is needed,
another input changes, it announces an event, or its rows are full (64 for the Stepper: every
62 slots or so of a PoKeys job), never for the segments alone::

    segment       |s                  |s+1                |s+2 ...    |s+62
    rows          [s] [s, s+1] ...                                   [s .. s+63] -> one FMU step, rows s+62, s+63 kept
    FMU steps     ______________________________________________________|

**Rate** (FMI 2.0, or a plant with only ``step_rate`` and ``step_phase``): the plant takes a signed
``step_rate`` held from an anchor with its ``step_phase`` and places pulse j at
``t_anchor + (j - phase) / |rate|``. The rate is set when the segment is announced (``now``, the
slot start), with the phase that puts its first pulse exactly at ``t0``:
``phase = 1 - (t0 - now) count / duration``. That holds while no pulse of the running segment
falls in ``[now, t0)`` and ``t0 - now`` is shorter than the new pulse period (for a PoKeys engine:
``dir_setup_ns`` under 40 us, which its configuration guarantees, since 25 pulses per 1 ms slot are
40 us apart); where it does not, the rate is set at ``t0`` by a kernel event instead, as before
(counted in :attr:`StepperCoupling.deferred`)::

    segment       |s                  |s+1                |s+2      (no segment)
    controller    |.  |  .  .  .  .   |.  |  .  .  .  .   |.  |
    step_rate     |‾‾‾‾ 5 kHz, phase 1 - d r ‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾|____   set at the slot start, 0 at the end of s+1
                      ^ t0 = slot start + d                        (s+1 has the same rate: not set again)

The inputs are set at most once per segment (one plant step each), and not at all while the count
and direction stay the same from one segment to the next (the plant continues its train from the
same anchor, so the pulses are the same). ``step_rate`` returns to 0 at the end of the last
segment of a run of segments.

Either way the end of a run of segments is caught by a kernel event at its end, armed for each
segment and cancelled (:meth:`~cosim.kernel.Simulation.cancel`) when the next segment continues
the run: there the rate returns to 0 and ``commanded_steps`` is recorded.

The pulses' sign follows the direction *pin*, as a driver sees it: with a port whose pin is
``reversed`` relative to the count, the motor turns the other way (and counts ``-position``).
Where a drive counts a pulse at its active edge, after the recorded instant (a Trio step output:
the port's ``active_delay`` is the pulse width), every segment reaches the plant that much later.

Roles (plant variables, with the Stepper FMU's names as defaults): ``step_rate`` [pulses/s] and
``step_phase`` [1] inputs; ``step_segments`` input (optional: without it the rate way is used);
``commanded_steps`` [steps] output (optional: recorded at the coupling and wherever the axis stops,
where it must equal the controller's count).
"""

from __future__ import annotations

from array import array
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from itertools import islice
from operator import ne
from typing import Any
from weakref import WeakKeyDictionary

import numpy as np
from simpy.events import Event

from cosim.couplings.roles import required, resolve
from cosim.errors import ConfigurationError
from cosim.kernel import At, Simulation
from cosim.master import Plant, PlantLike
from cosim.signals import PulseTrain, StepDirPort
from cosim.timebase import Priority, TimeBase

ROLES: dict[str, str | None] = {"step_rate": "step_rate", "step_phase": "step_phase",
                                "step_segments": "step_segments", "commanded_steps": "commanded_steps"}
"""Roles of the stepper coupling and the Stepper FMU's variables that play them."""

Row = tuple[int, int, int]  # (t0 [ticks], duration [ticks], signed pulses)


def segment_rate_hz(timebase: TimeBase, duration: int, count: int, sign: int) -> float:
    """``step_rate`` [pulses/s] that puts ``count`` pulses evenly into a segment of ``duration`` ticks.

    Examples
    --------
    >>> segment_rate_hz(TimeBase(), 1_000_000, 5, -1)
    -5000.0
    """
    resolution = timebase.resolution_s  # count / (duration resolution), correctly rounded (int / int)
    return sign * count * resolution.denominator / (duration * resolution.numerator) if count else 0.0


def slot_start_phase(now: int, t0: int, duration: int, count: int) -> Fraction | None:
    """The ``step_phase`` that puts a rate set at ``now`` on the first pulse of a segment at ``t0``.

    ``1 - (t0 - now) count / duration`` (0 when ``t0 == now``); None when the gap is not shorter
    than the segment's pulse period (the phase would not be in [0, 1)).

    Examples
    --------
    >>> slot_start_phase(0, 5_000, 1_000_000, 25)   # 5 us before a 25 kHz segment: 1/8 of a period
    Fraction(7, 8)
    >>> slot_start_phase(0, 40_000, 1_000_000, 25) is None
    True
    """
    gap = t0 - now
    if gap == 0:
        return Fraction(0)
    if gap < 0 or gap * count >= duration:
        return None
    return 1 - Fraction(gap * count, duration)


class _Wakeups:
    """Kernel events at instants where some coupled axis may change its rate or stop.

    Shared by every stepper coupling of a simulation, so an instant costs one event for all axes:
    each coupling arms the instants it needs and withdraws those it no longer needs, and an instant
    nobody needs any more is cancelled (it then never fires). At an instant every coupling is asked
    (:meth:`StepperCoupling.update`); each knows what, if anything, it has to do there.
    """

    def __init__(self, sim: Simulation) -> None:
        self.sim = sim
        self.couplings: list[StepperCoupling] = []
        self._due: dict[int, list[Any]] = {}  # t -> [event, how many arms]

    def arm(self, t: int) -> None:
        """One more wake-up at ``t`` (not before now)."""
        entry = self._due.get(t)
        if entry is None:
            # HOST: after the controller's slot or servo cycle at the same tick has announced its segments.
            # The event of Simulation.call_at, made directly: this runs once per slot.
            event = At(self.sim.env, t, Priority.HOST)
            event.callbacks.append(self._fire)
            self._due[t] = [event, 1]
        else:
            entry[1] += 1

    def withdraw(self, t: int) -> None:
        """One wake-up at ``t`` less (one armed before)."""
        entry = self._due[t]
        entry[1] -= 1
        if not entry[1]:
            del self._due[t]
            self.sim.cancel(entry[0])

    def _fire(self, _event: Event) -> None:
        t = self.sim.now
        del self._due[t]
        for coupling in self.couplings:
            coupling.update(t)


_WAKEUPS: WeakKeyDictionary[Simulation, _Wakeups] = WeakKeyDictionary()


@dataclass(eq=False)
class StepperCoupling:
    """State of one step/direction output driving one stepper plant (made by :func:`couple_stepper`).

    Attributes
    ----------
    plant : PlantLike
    sign : int
        +1, or -1 when the port's direction pin is reversed relative to its count.
    commanded_signal : str or None
        Trace name of the plant's ``commanded_steps``, recorded at the coupling and whenever the
        axis stops, where it must equal the controller's count; None when the plant has no such output.
    way : str
        ``"segments"`` (rows of ``step_segments``, written before the plant's steps) or ``"rate"``
        (``step_rate`` and ``step_phase``).
    rate_hz : float
        The pulse rate the plant follows now [pulses/s] (signed; 0 between runs of segments).
    settings : int
        Rate changes so far (on the rate way each is one input change, one plant step at most).
    deferred : int
        Rate way: segments whose rate was set at their ``t0`` by a kernel event, because the
        slot-start rule did not hold (see the module's description).
    writes : int
        Segments way: writes of the rows (one before each plant step that follows new segments).
    """

    sim: Simulation
    plant: PlantLike
    sign: int
    commanded_signal: str | None
    commanded_variable: str | None = field(repr=False)
    wakeups: _Wakeups = field(repr=False)
    set_rate: Callable[[Sequence[float]], None] = field(repr=False)
    set_rate_phase: Callable[[Sequence[float]], None] | None = field(repr=False)
    way: str = "rate"
    settings: int = 0
    deferred: int = 0
    writes: int = 0
    _rate: float = field(default=0.0, repr=False)  # the step_rate written last
    _phase: float = field(default=0.0, repr=False)  # the step_phase written last
    _announced: dict[int, tuple[float, int, int]] = field(default_factory=dict, repr=False)  # t0 -> rate, length, n
    _running: Row | None = field(default=None, repr=False)  # the latest segment (t0, duration, signed pulses)
    _t_end: int | None = field(default=None, repr=False)  # end of the run of segments [ticks]
    _armed_end: int | None = field(default=None, repr=False)  # the stop check armed (at _t_end), if any
    _ends: bool = field(default=False, repr=False)  # the train announces the ends of its runs
    _rows: array = field(default_factory=lambda: array("q"), repr=False)  # segments not placed yet, flat
    _array: np.ndarray | None = field(default=None, repr=False)  # the plant's step_segments value
    _capacity: int = field(default=0, repr=False)  # its elements, 3 per row (0: the rate way)
    _write: Callable[[], None] | None = field(default=None, repr=False)
    _written: int = field(default=0, repr=False)  # rows holding a segment in the plant's value
    _dirty: bool = field(default=False, repr=False)
    _train: PulseTrain | None = field(default=None, repr=False)  # the segments way: the train it pulls

    def on_segment(self, _train: PulseTrain, t0: int, duration: int, count: int, direction: int) -> None:
        """Segment listener: the pulses of ``[t0, t0 + duration)``, announced now (at or before ``t0``)."""
        if not count:
            return  # no pulses: a run of segments going on ends at t0
        signed = count if direction else -count
        if self.sign < 0:
            signed = -signed
        wakeups = self.wakeups
        continues = self._t_end == t0
        if continues and self._armed_end == t0:
            wakeups.withdraw(t0)  # the run goes on: no stop at t0
            self._armed_end = None
        if self._capacity:  # the segments way (first: it runs for every segment)
            rows = self._rows
            rows.extend((t0, duration, signed))
            self._dirty = True
            if len(rows) == self._capacity:
                self._make_room()
            running = self._running
            if running is None or running[1] != duration or running[2] != signed:
                self.settings += 1  # another rate (rate_hz works it out when asked)
            self._running = (t0, duration, signed)
            self._t_end = t_end = t0 + duration
            if not self._ends:
                wakeups.arm(t_end)
                self._armed_end = t_end
            return
        rate_hz = segment_rate_hz(self.sim.timebase, duration, count, 1 if signed > 0 else -1)
        if continues and rate_hz == self._rate and not self._announced:
            self._start(t0, duration, signed)  # same rate from the same anchor: the plant continues the train
        elif (continues or self._t_end is None) and (phase := self._phase_now(t0, duration, count)) is not None:
            self._apply(rate_hz, float(phase))
            self._start(t0, duration, signed)
        else:  # set the rate at t0 by a kernel event, phase 0 (after the running segment's stop, if any)
            self._announced[t0] = (rate_hz, duration, signed)
            self.deferred += 1
            wakeups.arm(t0)

    def on_run(self, _train: PulseTrain, t0: int, duration: int, counts: Sequence[int], direction: int,
               lead: int) -> None:
        """Run listener (segments way): :meth:`on_segment` for each segment of a run, as at its own instant.

        Segment ``j`` covers ``[t0 + j duration, t0 + (j + 1) duration)`` with ``counts[j]`` (> 0) pulses,
        announced at ``t0 + j duration - lead``; nothing else happens before the last announcement, so
        where the rows fill up the plant is stepped to that segment's announcement, as it would have
        been then. The run goes on from segment to segment: one stop check at its end.
        """
        sign = self.sign if direction else -self.sign
        if self._t_end == t0 and self._armed_end == t0:
            self.wakeups.withdraw(t0)  # the run goes on: no stop at t0
            self._armed_end = None
        signed = counts if sign > 0 else [-c for c in counts]
        running = self._running
        previous = running[2] if running is not None and running[1] == duration else None
        self.settings += (signed[0] != previous) + sum(map(ne, signed, islice(signed, 1, None)))  # rate changes
        n = len(signed)
        rows, capacity = self._rows, self._capacity
        self._dirty = True
        if len(rows) + 3 * n < capacity:  # the rows do not fill up within the run
            flat = [duration] * (3 * n)
            flat[::3] = range(t0, t0 + n * duration, duration)
            flat[2::3] = signed
            rows.fromlist(flat)
        else:
            t = t0
            for count in signed:
                rows.extend((t, duration, count))
                self._dirty = True
                if len(rows) == capacity:
                    self._make_room(t - lead)
                t += duration
        t_last = t0 + (n - 1) * duration
        self._running = (t_last, duration, signed[-1])
        self._t_end = t_end = t_last + duration
        if not self._ends:
            self.wakeups.arm(t_end)
            self._armed_end = t_end

    def on_end(self, _train: PulseTrain) -> None:
        """End listener (a train that announces ends): no segment continues the last one, so stop at its end."""
        t_end = self._t_end
        if t_end is not None and self._armed_end != t_end:
            if t_end < self.sim.now:
                raise ConfigurationError(f"{_train.name}: the end of a run of segments at t={t_end} ticks was "
                                         f"announced late (now {self.sim.now})")
            self.wakeups.arm(t_end)
            self._armed_end = t_end

    def update(self, t: int) -> None:
        """At ``t`` (a kernel event): start a deferred segment, or stop where the run of segments ends."""
        if self._armed_end == t:
            self._armed_end = None
        segment = self._announced.pop(t, None)
        if segment is not None:
            rate_hz, duration, signed = segment
            self._apply(rate_hz, 0.0)
            self._start(t, duration, signed)
        elif self._t_end == t:
            self._t_end = self._running = None
            if self._capacity:
                self.settings += 1
            else:
                self._apply(0.0, self._phase)
            if self.commanded_signal is not None and self.commanded_variable is not None:
                self.sim.trace.record(self.commanded_signal, self.sim.now,
                                      _as_int(self.plant.read(self.commanded_variable)))

    # -- the rate way ---------------------------------------------------------------------------
    def _phase_now(self, t0: int, duration: int, count: int) -> Fraction | None:
        """The phase that starts the segment's train now, or None if the slot-start rule does not hold."""
        if self._announced or self.set_rate_phase is None:
            return None
        now = self.sim.now
        running = self._running
        if running is not None:
            r0, r_duration, r_count = running[0], running[1], abs(running[2])
            if (r0 - now) * r_count + (r_count - 1) * r_duration >= 0:  # its last pulse is not before now
                return None
        return slot_start_phase(now, t0, duration, count)

    def _apply(self, rate_hz: float, phase: float) -> None:
        if phase != self._phase:
            assert self.set_rate_phase is not None
            self.set_rate_phase((rate_hz, phase))
            self._phase = phase
        elif rate_hz != self._rate:
            self.set_rate((rate_hz,))
        else:
            return  # same rate and phase: the plant continues the train by itself
        if rate_hz != self._rate:
            self._rate = rate_hz
            self.settings += 1

    # -- both ways ------------------------------------------------------------------------------
    @property
    def rate_hz(self) -> float:
        """The pulse rate the plant follows now [pulses/s] (signed; 0 between runs of segments)."""
        if not self._capacity:
            return self._rate
        running = self._running
        if running is None:
            return 0.0
        return segment_rate_hz(self.sim.timebase, running[1], abs(running[2]), 1 if running[2] > 0 else -1)

    def _start(self, t0: int, duration: int, signed: int) -> None:
        self._running = (t0, duration, signed)
        self._t_end = t_end = t0 + duration
        if not self._ends:
            self.wakeups.arm(t_end)
            self._armed_end = t_end

    # -- the segments way -------------------------------------------------------------------------
    def before_step(self, t: int) -> None:
        """Plant hook: write the rows before the plant steps to ``t``; forget those it places in that step."""
        train = self._train
        if train is not None and train.pull is not None:
            train.pull()  # segments a controller computes when needed (PulseTrain.pull): up to now first
        rows = self._rows  # flat: t0, duration, signed pulses, t0, ...
        if self._dirty:
            array = self._array
            assert array is not None and self._write is not None
            n = len(rows) // 3
            if n:
                table = np.frombuffer(rows, dtype=np.int64).reshape(n, 3)
                resolution = self.sim.timebase.resolution_s
                if resolution.numerator == 1:  # seconds as the FMU's times are made (TimeBase.seconds)
                    np.divide(table[:, :2], resolution.denominator, out=array[:n, :2])
                else:
                    array[:n, :2] = [[self.sim.timebase.seconds(int(t)) for t in row] for row in table[:, :2]]
                array[:n, 2] = table[:, 2]
                del table  # releases rows' buffer (rows is shortened below)
            if self._written > n:
                array[n:self._written] = 0.0
            self._written = n
            self._write()
            self.writes += 1
            self._dirty = False
        # the rows that end by t, from the first: placed in this step (the rows are in time order, so
        # those that end later are the last few)
        done = len(rows)
        while done and rows[done - 3] + rows[done - 2] > t:
            done -= 3
        if done:
            del rows[:done]  # the plant's value keeps them until the next write

    def _make_room(self, t: int | None = None) -> None:
        """The rows are full: step the plant to now (or to ``t``, the announcement of a segment of a run),
        which places (and forgets) every row that has ended."""
        assert isinstance(self.plant, Plant)
        if t is None:
            self.plant.advance()
        else:
            self.plant.advance_ahead(t)
        if len(self._rows) == self._capacity:
            raise ConfigurationError(f"{self.plant.name}: more than {self._capacity // 3 - 1} pulse-train segments "
                                     "announced ahead of the simulation's time (the plant's step_segments rows)")


def couple_stepper(port: StepDirPort, plant: PlantLike, *,
                   variables: Mapping[str, str | None] | None = None) -> StepperCoupling:
    """Drive a stepper ``plant`` from a controller's step/direction ``port``.

    Parameters
    ----------
    port : StepDirPort
        E.g. ``engine.step_dir(0)`` (PoKeys axis x) or ``trio.step_dir(3)``.
    plant : PlantLike
        The Stepper FMU (or a plant with the roles of :data:`ROLES`).
    variables : mapping role -> variable, optional
        The plant's names for the roles, where they differ from the Stepper FMU's;
        ``{"step_segments": None}`` drives the plant by its rate even where it has segment rows.

    Returns
    -------
    StepperCoupling
        Also records ``<plant>.commanded_steps`` [steps] now and whenever the axis stops (rate
        back to 0), so a check can compare it with the controller's count at the end of a job.

    Examples
    --------
    ::

        x = run.plant("Stepper", name="stepper_x", preset="nema17_17hs16_2004s1")
        couple_stepper(engine.step_dir(0), x)
    """
    names = resolve(plant, "stepper", ROLES, variables, optional=("commanded_steps", "step_segments"))
    sim = plant.sim
    rate, phase = required(names, "step_rate"), required(names, "step_phase")
    plant.set({rate: 0.0, phase: 0.0})
    commanded = names["commanded_steps"]
    signal = None
    if commanded is not None:
        signal = f"{plant.name}.commanded_steps"
        sim.trace.declare(signal, "int", unit="steps",
                          description=f"{plant.name} {commanded}, read at the coupling and where "
                                      f"{port.step.name} stops")
        sim.trace.record(signal, sim.now, _as_int(plant.read(commanded)))
    wakeups = _WAKEUPS.get(sim)
    if wakeups is None:
        wakeups = _WAKEUPS[sim] = _Wakeups(sim)
    coupling = StepperCoupling(sim, plant, -1 if port.reversed else 1, signal, commanded, wakeups,
                               plant.setter((rate,)), plant.setter((rate, phase)))
    wakeups.couplings.append(coupling)
    segments = names["step_segments"]
    if segments is not None and isinstance(plant, Plant):
        shape = plant.fmu.variable(segments).shape
        if len(shape) != 2 or shape[1] != 3 or shape[0] < 3:
            raise ConfigurationError(f"stepper coupling of {plant.name}: {segments} has dimensions {list(shape)} "
                                     "(allowed: [rows, 3] with at least 3 rows of start, duration, pulses)")
        coupling.way = "segments"
        coupling._array = np.zeros(shape, dtype=np.float64)
        coupling._capacity = 3 * shape[0]
        coupling._write = plant.ahead_writer(segments, coupling._array)
        plant.before_step(coupling.before_step)
    delay = port.active_delay
    coupling._ends = port.step.announces_ends
    segments_way = coupling.way == "segments"
    if segments_way:
        coupling._train = port.step
    if delay:  # the drive counts at the active edge
        port.step.subscribe(lambda train, t0, duration, count, direction:
                            coupling.on_segment(train, t0 + delay, duration, count, direction),
                            runs=(lambda train, t0, duration, counts, direction, lead:
                                  coupling.on_run(train, t0 + delay, duration, counts, direction, lead + delay))
                            if segments_way else None,
                            ends=coupling.on_end if coupling._ends else None, pulls=segments_way)
    else:  # runs of segments on the segments way (the rate way sets inputs at each segment's instant)
        port.step.subscribe(coupling.on_segment, runs=coupling.on_run if segments_way else None,
                            ends=coupling.on_end if coupling._ends else None, pulls=segments_way)
    return coupling


def _as_int(value: object) -> int:
    return int(value)  # type: ignore[call-overload]
