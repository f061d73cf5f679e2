"""Signals: the wires between controllers and plants.

A :class:`Signal` has a current value; setting a new value records an edge in the trace at the
current tick and tells every subscriber (the master uses this to advance an FMU to now and set
its input). A :class:`PulseTrain` carries step pulses as segments (see :mod:`cosim.pulses`).
Controllers only know signals, never FMUs: any plant or a test double can stand behind them.

*Ports* are the named bundles of signals at a controller's connectors that a coupling
(:mod:`cosim.couplings`) joins to a plant: :class:`StepDirPort` (step and direction outputs),
:class:`PwmPort` (a laser's modulation and enables), :class:`SwitchPort` (limit and home inputs).
A controller offers them (``engine.step_dir(0)``, ``trio.pwm_port(3)``); it never names the
plant variables they end up on.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING

from cosim import validate
from cosim.errors import ConfigurationError

if TYPE_CHECKING:
    from cosim.kernel import Simulation

Listener = Callable[["Signal"], None]
SegmentListener = Callable[["PulseTrain", int, int, int, int], None]
RunListener = Callable[["PulseTrain", int, int, Sequence[int], int, int], None]
EndListener = Callable[["PulseTrain"], None]


class Signal:
    """A recorded value that changes at exact ticks.

    Parameters
    ----------
    sim : Simulation
        The simulation whose clock and trace are used.
    name : str
        Trace name, ``<device>.<axis>.<signal>`` (see :mod:`cosim.trace`).
    kind : {'bit', 'int', 'real'}
        Logic level, integer register or real value.
    initial : float
        Value at t = 0 (recorded).
    unit, description : str
        For the trace and exports.
    """

    def __init__(self, sim: Simulation, name: str, *, kind: str = "bit", initial: float = 0,
                 unit: str = "", description: str = "") -> None:
        validate.choice(kind, f"kind of signal {name}", ("bit", "int", "real"))
        self.sim = sim
        self.name = name
        self.kind = kind
        self._listeners: list[Listener] = []
        sim.trace.declare(name, kind, unit=unit, description=description)
        self.value = self._coerce(initial)
        sim.trace.record(name, sim.now, self.value)
        self._record = sim.trace.recorder(name)  # bound once: a signal set every servo cycle costs 1/3 of before
        self._env = sim.env
        self._real = kind == "real"

    def _coerce(self, value: float) -> float:
        if self.kind == "bit":
            return 1 if value else 0
        if self.kind == "int":
            if isinstance(value, int) or (type(value) is float and value.is_integer()):  # the common cases
                return int(value)
            return validate.integer(value, f"signal {self.name}", whole=True)
        return float(value)

    def subscribe(self, listener: Listener) -> None:
        """Call ``listener(signal)`` after every change of value."""
        self._listeners.append(listener)

    def set(self, value: float) -> bool:
        """Set the value now; returns True if it changed (and was recorded)."""
        new = float(value) if self._real else self._coerce(value)
        if new == self.value:
            return False
        self.value = new
        self._record(self._env._now, new)  # type: ignore[arg-type]  # (the clock is an int)
        for listener in self._listeners:
            listener(self)
        return True

    def __repr__(self) -> str:
        return f"Signal({self.name}={self.value})"


class Sampled:
    """A real value recorded at requested sample times only (an analog plant output)."""

    def __init__(self, sim: Simulation, name: str, *, unit: str = "", description: str = "") -> None:
        self.sim = sim
        self.name = name
        sim.trace.declare(name, "real", unit=unit, description=description)

    def record(self, value: float) -> None:
        """Record ``value`` at the current tick."""
        self.sim.trace.record(self.name, self.sim.now, float(value))


class PulseTrain:
    """Step pulses, emitted as evenly spread segments.

    Parameters
    ----------
    sim : Simulation
    name : str
        Trace name of the step signal, e.g. ``pokeys.x.step``.
    pulse_width : int
        Width of a drawn pulse [ticks] (VCD display; checks use the pulse instants).
    description : str

    Notes
    -----
    ``position`` counts emitted pulses, signed by direction (dir 1 = positive).

    A controller that knows several slots ahead that nothing else can happen in between (a PoKeys
    engine between host events) may hand them over as one *run* of contiguous segments
    (:meth:`emit_run`), if every listener takes runs (:attr:`takes_runs`); the trace and the
    listeners end up as after one :meth:`emit` per segment at its own instant.
    """

    def __init__(self, sim: Simulation, name: str, *, pulse_width: int = 1, description: str = "",
                 announces_ends: bool = False) -> None:
        self.sim = sim
        self.name = name
        self.position = 0
        self._listeners: list[SegmentListener] = []
        self._run_listeners: list[RunListener] = []
        self._end_listeners: list[EndListener] = []
        self.takes_runs = sim.trace.takes_runs(name)
        """True while the trace and every listener take runs of segments (:meth:`emit_run` may be used)."""
        self.pull: Callable[[], None] | None = None
        """Set by a controller that computes some segments only when they are needed (a Trio's servo ticks
        in closed form): emits every segment due up to now. A listener that subscribed with ``pulls``
        calls it before it acts on the segments so far (a stepper coupling, before its plant steps)."""
        self.pulling = 0
        """How many listeners pull (see :attr:`pull`)."""
        self.announces_ends = announces_ends
        """The controller calls :meth:`end_run` at or before the end of every segment that no segment
        continues (the next one does not start where it ends), so a listener need not watch each
        segment's end for a stop: a PoKeys engine does at the next slot start."""
        sim.trace.declare(name, "pulse", description=description, pulse_width=pulse_width)
        self._record_segment = sim.trace.segment_recorder(name)
        self._record_run = sim.trace.segment_run_recorder(name)

    def subscribe(self, listener: SegmentListener, *, runs: RunListener | None = None,
                  ends: EndListener | None = None, pulls: bool = False) -> None:
        """Call ``listener(train, t0, duration, count, direction)`` for every segment.

        ``runs``, if given, takes a run of segments in one call instead (:meth:`emit_run`):
        ``runs(train, t0, duration, counts, direction, lead)``, segment ``j`` being
        ``[t0 + j duration, t0 + (j + 1) duration)`` with ``counts[j]`` pulses, which :meth:`emit`
        would have announced at ``t0 + j duration - lead``. Nothing else happens in the simulation
        before the last of those instants, so the listener may act for each segment as at its own
        instant (e.g. step a plant to it); the clock reads the first. A listener without ``runs``
        makes the train take single segments only (:attr:`takes_runs` false). ``ends``, if given, is
        called as ``ends(train)`` by :meth:`end_run` (see :attr:`announces_ends`). ``pulls``: the listener
        calls :attr:`pull` before it acts on the segments so far.
        """
        self._listeners.append(listener)
        self.pulling += pulls
        if ends is not None:
            self._end_listeners.append(ends)
        if runs is None:
            self.takes_runs = False
        else:
            self._run_listeners.append(runs)

    def emit(self, t0: int, duration: int, count: int, direction: int) -> None:
        """Emit ``count`` pulses spread over ``[t0, t0 + duration)`` in ``direction`` (1 or 0).

        Segments are emitted at or before ``t0`` (a controller announces the slot it starts).
        """
        if not (type(t0) is type(duration) is type(count) is int and duration > 0 and count >= 0
                and (direction == 0 or direction == 1)):  # the common case skips the checks: one per slot and axis
            self._check_segment(t0, duration, count, direction)
        self._record_segment(t0, duration, count, direction)
        self.position += count if direction else -count
        for listener in self._listeners:
            listener(self, t0, duration, count, direction)

    def emit_run(self, t0: int, duration: int, counts: Sequence[int], direction: int, lead: int) -> None:
        """Emit contiguous segments at once: segment ``j`` has ``counts[j]`` (> 0) pulses over
        ``[t0 + j duration, t0 + (j + 1) duration)`` in ``direction``, as if each had been emitted at
        ``t0 + j duration - lead`` (``t0 - lead`` is now).

        Only while :attr:`takes_runs` holds, and only when nothing else can happen in the simulation
        before the last of those instants (no event due, no look-ahead): the caller's promise.
        """
        if not self.takes_runs:
            raise ConfigurationError(f"{self.name}: a listener takes single segments only (emit_run needs "
                                     "every listener to take runs)")
        self._record_run(t0, duration, counts, direction)
        total = sum(counts)
        self.position += total if direction else -total
        for listener in self._run_listeners:
            listener(self, t0, duration, counts, direction, lead)

    def end_run(self) -> None:
        """No segment continues the last one emitted (a train that :attr:`announces_ends` calls this at
        or before its end): tell the listeners that asked."""
        for listener in self._end_listeners:
            listener(self)

    def _check_segment(self, t0: object, duration: object, count: object, direction: object) -> None:
        validate.integer(t0, "segment start", unit="ticks", where=self.name)
        validate.integer(duration, "segment duration", low=1, unit="ticks", where=self.name)
        validate.integer(count, "segment count", low=0, kind="an integer", where=self.name)
        validate.integer(direction, "segment direction", low=0, high=1, allowed="0 or 1", where=self.name)

    def pulse(self, t: int, direction: int) -> None:
        """Emit a single pulse at tick ``t`` (for trains that are not evenly spread)."""
        self.sim.trace.record_pulse(self.name, t, direction)
        self.position += 1 if direction else -1
        for listener in self._listeners:
            listener(self, t, 1, 1, direction)


# -- ports: the signal bundles at a controller's connectors -----------------------------------------
@dataclass(frozen=True)
class StepDirPort:
    """A step/direction output as a driver sees it.

    Parameters
    ----------
    step : PulseTrain
        Step pulses; a segment's ``direction`` is the direction the controller counts (1 = up).
    direction : Signal
        The direction pin.
    reversed : bool
        True when the pin is inverted relative to the count (a PoKeys axis with
        ``invert_direction``): the motor then turns opposite to the counted direction.
    active_delay : int
        Ticks from a recorded pulse instant (its leading edge) to its active edge, where a drive
        counts it (0: at the instant; a Trio step output: the step pulse width).
    """

    step: PulseTrain
    direction: Signal
    reversed: bool = False
    active_delay: int = 0


@dataclass(frozen=True)
class PwmPort:
    """The outputs that modulate a laser.

    Parameters
    ----------
    enable : Signal
        Drive enable (bit; the Trio WDOG).
    gate : Signal
        Gate (bit): the output may be on.
    period_clocks, mark_clocks : Signal
        Carrier period and on-time [clocks of ``clock_hz``] (int).
    phase_clocks : Signal
        Clock count at which the carrier's periods start (int).
    clock_hz : Fraction
        The PWM base clock [Hz].
    """

    enable: Signal
    gate: Signal
    period_clocks: Signal
    mark_clocks: Signal
    phase_clocks: Signal
    clock_hz: Fraction


@dataclass(frozen=True)
class SwitchPort:
    """Switch inputs of one axis (bits, 1 = tripped); ``None`` where the axis has no such input."""

    limit_pos: Signal | None = None
    limit_neg: Signal | None = None
    home: Signal | None = None

