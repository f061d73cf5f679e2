"""A coordinate system: its time-base source (Ix93), slew limit (Ix94), program and slip.

Every servo cycle, after the conversion table:

1. the source register at address Ix93 is read (the ``%`` command register by default, or a
   time-base result of the conversion table, e.g. $0729 = 1833);
2. the actual time-base value moves toward it by at most Ix94 (2^-23 ms per cycle);
3. the running program (or jog) advances by the actual time-base value.

Ix94 under external time base
-----------------------------
When the limit acts while the source is an external (table) time base, the elapsed program time
falls behind the master: the shortfall ``source - actual`` of that cycle, divided by the
entry's time-base units per master count, is *slip* in master counts. The coordinate system
records every cycle in which the limit acted and the accumulated slip; a second, "ideal"
program clock advanced by the source value itself gives the master-derived positions that the
slave should have (slip-free), for the sync error.

The first servo cycle of a coordinate system takes the source value as its actual value (no
slew from an arbitrary power-on value).

Feed hold (``H``) slews the actual value to 0 at Ix95 per cycle, whatever the source; ``R`` slews it
back to the source at Ix95. Under external time base the master travel missed meanwhile is slip,
as with Ix94.

Programs
--------
:meth:`CoordinateSystem.run_program` runs a list of moves (all compiled at once);
:meth:`CoordinateSystem.run_feeder` runs a motion program that is calculated as it goes (a
:class:`Feeder`, e.g. a program read from text): every servo cycle, before and after the moves
advance, the feeder may queue more (:meth:`CoordinateSystem.queue`).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING, Protocol

from cosim import validate
from cosim.controllers.pmac.motion import Item, LinearMove, Segment, compile_item
from cosim.controllers.pmac.runner import ProgramRunner
from cosim.controllers.pmac.units import IX94_ALLOWED, IX94_DEFAULT, IX94_MAX, REG_MAX, hexaddr, percent
from cosim.errors import ConfigurationError
from cosim.signals import Signal

if TYPE_CHECKING:
    from cosim.kernel import Simulation

#: Address of coordinate system 1's ``%`` command register; CS x is at +(x-1)*$100 (Turbo defaults).
PERCENT_REGISTER_BASE = 0x2000


class TimeBaseSource(Protocol):
    """A register a coordinate system can take its time base from."""

    address: int

    def read(self) -> int:
        """Current value [2^-23 ms per servo cycle]."""
        ...

    @property
    def units_per_count(self) -> int | None:
        """Time-base units per master count (None for a software register: not external)."""
        ...


class PercentRegister:
    """The ``%`` command register of a coordinate system (set by the host's ``%n``).

    Parameters
    ----------
    address : int
    i10 : int
        Servo interrupt time; ``%100`` writes I10.
    """

    units_per_count: int | None = None

    def __init__(self, address: int, i10: int) -> None:
        self.address = address
        self.i10 = i10
        self.value = i10

    def read(self) -> int:
        return self.value

    def command(self, pct: int | Fraction) -> int:
        """``%n``: write ``round(n * I10 / 100)``, saturated at 8,388,607 (the largest implementable)."""
        exact = validate.positive(pct, "%n (feedrate override)", zero=True,
                                  allowed=f">= 0 (up to {self.max_percent():.2f})")
        self.value = min(REG_MAX, round(exact * self.i10 / 100))
        return self.value

    def max_percent(self) -> float:
        """Largest implementable ``%`` value, ``(2^23 / I10) * 100``."""
        return float(Fraction(1 << 23, self.i10) * 100)


class Feeder(Protocol):
    """A motion program calculated while it runs (see :mod:`cosim.controllers.pmac.interpreter`)."""

    @property
    def finished(self) -> bool:
        """True when the program has nothing more to queue."""
        ...

    def calculate(self, cs: CoordinateSystem, t: int) -> None:
        """Run the program's statements at servo instant ``t``, queueing moves with ``cs.queue``."""
        ...


@dataclass(frozen=True)
class LimitEvent:
    """A servo cycle in which Ix94 limited the time base.

    Attributes
    ----------
    cycle, t : int
        Servo cycle and its instant [ticks].
    source, actual : int
        Source value and the limited actual value [2^-23 ms].
    slip_counts : Fraction or None
        Accumulated slip after this cycle [master counts] (None if the source is not external).
    """

    cycle: int
    t: int
    source: int
    actual: int
    slip_counts: Fraction | None


class CoordinateSystem:
    """Coordinate system ``&x`` with time-base control.

    Parameters
    ----------
    sim : Simulation
    number : int
        Coordinate system number x (1..8).
    i10 : int
        Servo interrupt time [2^-23 ms].
    axes : iterable of str
        Axis letters (positions start at 0).
    ix94 : int
        Ix94, time-base slew limit [2^-23 ms per servo cycle], 0..8,388,607.
    device : str
        Trace name prefix.
    """

    def __init__(self, sim: Simulation, number: int, *, i10: int, axes: Iterable[str] = ("X",),
                 ix94: int = IX94_DEFAULT, device: str = "pmac") -> None:
        self.number = validate.integer(number, "coordinate system number", low=1, high=8, allowed="integers 1..8")
        self.sim = sim
        self.i10 = i10
        self.ix94 = validate.integer(ix94, f"I{number}94 (Ix94)", low=0, high=IX94_MAX, allowed=IX94_ALLOWED)
        self.percent_register = PercentRegister(PERCENT_REGISTER_BASE + (number - 1) * 0x100, i10)
        self.ix93 = self.percent_register.address
        self.source: TimeBaseSource = self.percent_register
        self.axes = {axis: Fraction(0) for axis in axes}
        self.ix95 = IX94_DEFAULT
        self.ix87: int = 0  # default TA [ms]
        self.ix88: int = 50  # default TS [ms]
        self.ix89: Fraction = Fraction(1000)  # default F [axis units/s]
        self.holding = False
        self.releasing = False
        self.actual = 0
        self.source_value = 0
        self.slip_units = 0
        self.limit_events: list[LimitEvent] = []
        self.notes: list[tuple[int, str]] = []
        self._runner: ProgramRunner | None = None
        self._ideal: ProgramRunner | None = None
        self._pending: list[Item] | Feeder | None = None
        self._feeder: Feeder | None = None
        self._end: dict[str, Fraction] = {}
        self._ideal_end: dict[str, Fraction] = {}
        self._started = False
        self._last: list[int | bool | None] = [None, None, None, None]  # actual, source, limited, slip as recorded
        self._dwell_noted = False
        self._program_name: str | None = None
        #: Called with (program name, True) when a program starts and (name, False) when it reaches its end.
        self.on_program: Callable[[str, bool], None] | None = None
        p = f"{device}.cs{number}"
        self._tb = Signal(sim, f"{p}.timebase", kind="int", unit="2^-23 ms", description="actual time-base value")
        self._pct = Signal(sim, f"{p}.timebase_pct", kind="real", unit="%", description="actual time base in %")
        self._src = Signal(sim, f"{p}.timebase_source", kind="int", unit="2^-23 ms",
                           description="value of the register Ix93 points at")
        self._slip = Signal(sim, f"{p}.slip", kind="int", unit="counts",
                            description="master counts lost to the Ix94 limit (truncated)")
        self._active = Signal(sim, f"{p}.ix94_active", kind="bit", description="Ix94 limited the time base")

    # -- configuration ---------------------------------------------------------------------
    @property
    def external(self) -> bool:
        """True if the time-base source is a conversion-table result (external time base)."""
        return self.source.units_per_count is not None

    def define_axis(self, axis: str) -> None:
        """Add ``axis`` (a motor definition ``#n->...axis`` names it), at position 0."""
        if axis not in self.axes:
            self.axes[axis] = Fraction(0)

    def set_source(self, address: int, source: TimeBaseSource) -> None:
        """Point Ix93 at ``source`` (the machine resolves and validates the address)."""
        self.ix93 = address
        self.source = source

    def set_ix94(self, value: object, *, where: str = "") -> None:
        """Set Ix94 (0..8,388,607)."""
        self.ix94 = validate.integer(value, f"I{self.number}94 (Ix94)", low=0, high=IX94_MAX, where=where,
                                     allowed=IX94_ALLOWED)

    def set_ix95(self, value: object, *, where: str = "") -> None:
        """Set Ix95, the feed-hold slew rate (0..8,388,607)."""
        self.ix95 = validate.integer(value, f"I{self.number}95 (Ix95)", low=0, high=IX94_MAX, where=where,
                                     allowed=IX94_ALLOWED)

    def command_percent(self, pct: int | Fraction) -> int:
        """Host ``%n``; acts only while Ix93 points at this system's ``%`` register."""
        return self.percent_register.command(pct)

    def hold(self) -> None:
        """``H``: feed hold, the time base slews to 0 at Ix95 per cycle."""
        self.holding, self.releasing = True, False

    def release(self) -> None:
        """``R`` after ``H``: the time base slews back to its source at Ix95 per cycle."""
        if self.holding:
            self.holding, self.releasing = False, True

    @property
    def percent(self) -> Fraction:
        """Actual time base in % (what a ``%`` query reports, whatever the source)."""
        return percent(self.actual, self.i10)

    # -- programs ---------------------------------------------------------------------------
    def run_program(self, items: Iterable[Item], *, name: str = "") -> None:
        """Start a motion program (a list of moves); it begins at the next servo cycle."""
        if not self.program_done:
            raise ConfigurationError(f"coordinate system {self.number} is still running a program or jog")
        self._pending = list(items)
        self._program_name = name or f"CS{self.number} program"

    def run_feeder(self, feeder: Feeder, *, name: str = "") -> None:
        """Start a motion program that is calculated as it runs; it begins at the next servo cycle."""
        if not self.program_done:
            raise ConfigurationError(f"coordinate system {self.number} is still running a program or jog")
        self._pending = feeder
        self._program_name = name or f"CS{self.number} program"

    def abort(self, reason: str) -> None:
        """``A``/``K``/``^A``: the program stops now; every axis holds its commanded position (no deceleration)."""
        positions = {axis: self.position(axis) for axis in self.axes}
        ideal = {axis: self.ideal_position(axis) for axis in self.axes}
        self._pending = self._feeder = None
        self._runner = ProgramRunner([], positions)
        self._ideal = ProgramRunner([], ideal)
        self.axes = positions
        self.notes.append((self.sim.now, reason))
        self._program_name = None

    def set_positions(self, positions: dict[str, Fraction]) -> None:
        """Where the axes are (forward kinematics at ``R`` or ``PMATCH``), while no program runs."""
        if not self.program_done:
            raise ConfigurationError(f"coordinate system {self.number}: axis positions change only while no "
                                     "program runs")
        current = {axis: self.position(axis) for axis in self.axes}
        current.update(positions)
        self.axes = current
        self._runner = ProgramRunner([], current)
        self._ideal = ProgramRunner([], dict(current))

    def queue(self, item: Item) -> int:
        """Append a move to the running program (from a feeder); returns its segment index."""
        if self._runner is None or self._ideal is None:
            raise ConfigurationError(f"coordinate system {self.number} runs no program to queue moves to")
        self._runner.segments.append(compile_item(item, self._end))
        self._ideal.segments.append(compile_item(item, self._ideal_end))
        return len(self._runner.segments) - 1

    def segment_done(self, index: int) -> bool:
        """True once queued segment ``index`` has finished."""
        return self._runner is None or self._runner.index > index

    def queued_ahead(self) -> int:
        """Queued segments not finished yet that take time (the current one included)."""
        return self._runner.queued_ahead() if self._runner is not None else 0

    def program_end(self, axis: str) -> Fraction:
        """Where ``axis`` is at the end of the moves queued so far [axis units]."""
        return self._end.get(axis, self.position(axis)) if self._runner is not None else self.position(axis)

    def jog(self, target: int | Fraction, *, speed_per_ms: int | Fraction, ta_ms: int | Fraction = 10,
            axis: str = "X") -> None:
        """Non-programmed move (jog) to ``target`` [axis units] at ``speed_per_ms`` (Ixx22) with TA Ixx20.

        It runs under the coordinate system's time base, like a programmed move.
        """
        speed = validate.exact(speed_per_ms, "jog speed_per_ms (Ixx22)")
        self.run_program([LinearMove(target, speed * 1000, ta_ms, axis)])

    @property
    def program_done(self) -> bool:
        """True when no program or jog is running or pending."""
        return (self._pending is None and self._feeder is None
                and (self._runner is None or self._runner.done))

    def position(self, axis: str) -> Fraction:
        """Commanded position of ``axis`` [axis units]."""
        return self._runner.position(axis) if self._runner is not None else self.axes[axis]

    def ideal_position(self, axis: str) -> Fraction:
        """Master-derived (slip-free) position of ``axis`` [axis units]."""
        return self._ideal.position(axis) if self._ideal is not None else self.axes[axis]

    def position_ratio(self, axis: str, *, ideal: bool = False) -> tuple[int, int]:
        """:meth:`position` (or :meth:`ideal_position`) as ``(numerator, denominator)`` integers."""
        runner = self._ideal if ideal else self._runner
        if runner is not None:
            return runner.position_ratio(axis)
        value = self.axes[axis]
        return value.numerator, value.denominator

    @property
    def slip_counts(self) -> Fraction | None:
        """Accumulated slip [master counts] (None if the source is not external)."""
        upc = self.source.units_per_count
        return None if upc is None else Fraction(self.slip_units) / upc

    @property
    def limit_cycles(self) -> list[int]:
        """Servo cycles in which Ix94 acted."""
        return [e.cycle for e in self.limit_events]

    # -- servo cycle ------------------------------------------------------------------------
    def update(self, cycle: int, t: int) -> None:
        """One servo cycle: read the source, apply Ix94, advance the program (integers only)."""
        source = self.source.read()
        self.source_value = source
        if not self._started:
            self.actual = source
            self._started = True
        actual = self.actual
        hold = self.holding or self.releasing
        target = 0 if self.holding else source
        rate = self.ix95 if hold else self.ix94
        diff = target - actual
        step = -rate if diff < -rate else (rate if diff > rate else diff)
        actual += step
        self.actual = actual
        limited = step != diff
        upc = self.source.units_per_count
        external = upc is not None
        if hold:
            if external:
                self.slip_units += source - actual
            if self.releasing and not limited:
                self.releasing = False
            limited = False
        elif limited:
            if external:
                self.slip_units += source - actual
                if not any("Ix94" in n for _, n in self.notes):
                    self.notes.append((t, f"Ix94 limit acted under external time base at cycle {cycle}: "
                                             "position synchronization to the master is lost"))
            self.limit_events.append(LimitEvent(cycle, t, source, actual, self.slip_counts))
        if self._runner is not None or self._pending is not None:
            self._advance_program(source if external else actual, t)
        last = self._last
        if actual != last[0]:
            last[0] = actual
            self._tb.set(actual)
            self._pct.set(100 * actual / self.i10)  # = float(percent(actual, I10)), correctly rounded
        if source != last[1]:
            last[1] = source
            self._src.set(source)
        slip = 0
        if upc is not None and self.slip_units:
            slip = abs(self.slip_units) // upc  # truncated toward zero, as int(slip_counts)
            if self.slip_units < 0:
                slip = -slip
        if slip != last[3]:
            last[3] = slip
            self._slip.set(slip)
        if limited != last[2]:
            last[2] = limited
            self._active.set(limited)

    def _start_pending(self) -> None:
        pending, self._pending = self._pending, None
        start = {axis: self.position(axis) for axis in self.axes}
        ideal = {axis: self.ideal_position(axis) for axis in self.axes}
        segments: list[Segment] = []
        self._runner = ProgramRunner(segments, start)
        self._ideal = ProgramRunner([], ideal)
        self._end, self._ideal_end = dict(start), dict(ideal)
        self.axes = start
        if self.on_program is not None and self._program_name is not None:
            self.on_program(self._program_name, True)
        if isinstance(pending, list):
            self._feeder = None
            for item in pending:
                self.queue(item)
        else:
            self._feeder = pending

    def _advance_program(self, ideal_units: int, t: int) -> None:
        if self._pending is not None:
            self._start_pending()
        if self._runner is None or self._ideal is None:
            return
        feeder = self._feeder
        if feeder is not None:
            feeder.calculate(self, t)
        if not self._dwell_noted and self._runner.in_dwell and self.external:
            self._dwell_noted = True
            self.notes.append((t, "DWELL under external time base: it runs in real time, so "
                                     "synchronism with the master is lost"))
        self._runner.advance(self.actual, self.i10)
        self._ideal.advance(ideal_units, self.i10)
        if feeder is not None:
            feeder.calculate(self, t)
            if feeder.finished and self._runner.done:
                self._feeder = None
                self._ended()
        elif self._program_name is not None and self._runner.done:  # (_ended() does nothing without a name)
            self._ended()

    def _ended(self) -> None:
        name, self._program_name = self._program_name, None
        if name is not None and self.on_program is not None:
            self.on_program(name, False)

    def describe_source(self) -> str:
        """Ix93 as text, e.g. ``$2000 (CS1 % register)``."""
        kind = "external time base" if self.external else "% command register"
        return f"{hexaddr(self.ix93)} ({kind})"
