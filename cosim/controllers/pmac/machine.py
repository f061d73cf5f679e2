"""The PMAC controller model: servo clock, conversion table, coordinate systems, motors.

One SimPy process, :meth:`Pmac.servo_cycle`, runs every servo interrupt ``k`` at
``floor(k * I10 * 10^6 / 2^23)`` ns (floored to the resolution's ticks) with priority ``SERVO``,
in the firmware's order:

1. the encoder conversion table, top to bottom;
2. every coordinate system (time-base source via Ix93, Ix94 slew, program advance);
3. every motor (command, feedback, PID, DAC).

Coordinate systems start one cycle after the table (cycle 1): a time-base entry needs a
previous position before its first difference means anything.

The host (a scenario's script, a PLC stand-in) acts between interrupts through
:meth:`Pmac.set_ivar` (e.g. ``I8010=$B78008`` to arm), :meth:`Pmac.command_percent` (``%n``) and
:meth:`Pmac.read_x` (a dummy read of a capture register), normally with priority ``HOST``.

Programs as text: :meth:`Pmac.load` reads a PMAC file (I-variables, M-variable definitions,
``&1 #1->1000X``, ``OPEN PROG``/``OPEN PLC`` buffers, online commands) and :meth:`Pmac.command`
issues a line of online commands (``&1 B1 R``); see :mod:`.runtime` for when programs run.
"""

from __future__ import annotations

from collections.abc import Callable, Generator, Iterable
from fractions import Fraction
from pathlib import Path
from typing import TYPE_CHECKING, Any

from cosim.controllers.pmac import ivartable
from cosim.controllers.pmac.coord import CoordinateSystem, TimeBaseSource
from cosim.controllers.pmac.ect import (
    TURBO_ECT_BASE,
    ConversionTable,
    DifferentiatingEntry,
    OneOverTEntry,
    TriggeredTimeBaseEntry,
)
from cosim.controllers.pmac.encoder import CAPTURE_OFFSET, EncoderChannel, EncoderSource
from cosim.controllers.pmac.interpreter import KINEMATIC_AXES
from cosim.controllers.pmac.motor import Motor
from cosim.controllers.pmac.runtime import Programs
from cosim.controllers.pmac.servo import PidLoop
from cosim.controllers.pmac.setupfile import parse_setup
from cosim.controllers.pmac.units import I10_DEFAULT, REG_MASK, Reg, ServoClock, hexaddr
from cosim.errors import ConfigurationError
from cosim.job import Job
from cosim.kernel import At
from cosim.signals import PulseTrain, Signal
from cosim.timebase import Priority

if TYPE_CHECKING:
    from cosim.kernel import Simulation


class EntrySource:
    """A conversion-table time-base result as a coordinate system's time-base source."""

    def __init__(self, entry: DifferentiatingEntry) -> None:
        self.entry = entry
        self.address = entry.result_address

    def read(self) -> int:
        return self.entry.result

    @property
    def units_per_count(self) -> int:
        return self.entry.units_per_count


class Pmac:
    """A (Turbo) PMAC running external / triggered time base.

    Parameters
    ----------
    sim : Simulation
    i10 : int
        I10, servo interrupt time [2^-23 ms] (default 3,713,707, about 442.7 us).
    table : ConversionTable, optional
        The encoder conversion table (default: an empty Turbo table at $3501; a setup file's
        I8000..I8191 lines build one).
    device : str
        Trace name prefix (``pmac``).

    Examples
    --------
    >>> from cosim.kernel import Simulation
    >>> sim = Simulation()
    >>> pmac = Pmac(sim)
    >>> pmac.command_percent(1, 50)
    1856854
    """

    def __init__(self, sim: Simulation, *, i10: int = I10_DEFAULT, table: ConversionTable | None = None,
                 device: str = "pmac") -> None:
        self.sim = sim
        self.device = device
        self.clock = ServoClock(i10, sim.now, sim.timebase.resolution_s * 10**9)
        self.table = table if table is not None else ConversionTable(TURBO_ECT_BASE)
        self.channels: dict[int, EncoderChannel] = {}
        self.cs: dict[int, CoordinateSystem] = {}
        self.motors: dict[int, Motor] = {}
        self._cycle = -1
        self._started = False
        self._master: tuple[OneOverTEntry | TriggeredTimeBaseEntry, int] | None = None
        self._master_pos: Signal | None = None
        self._method: Signal | None = None
        self._time_zero: Signal | None = None
        self._stale: Signal | None = None
        self._ivars: dict[int, int | Fraction] = {}
        self._timers: dict[tuple[int, int], tuple[int, int]] = {}
        self._cycle0 = 0  # the first servo cycle (timers count from it)
        self.programs = Programs(self)
        self.job = Job(sim, device)
        #: Values of ``$(NAME)`` template macros and the folders ``#include`` looks in (a machine file's).
        self.defines: dict[str, str] = {}
        self.include_path: list[Path] = []

    @property
    def started(self) -> bool:
        """True once the servo clock runs."""
        return self._started

    @property
    def cycle(self) -> int:
        """The servo cycle that ran last (-1 before the first)."""
        return self._cycle

    @property
    def i10(self) -> int:
        """I10 [2^-23 ms]."""
        return self.clock.i10

    # -- building --------------------------------------------------------------------------
    def add_channel(self, address: int, encoder: EncoderSource, *, trigger: Signal | None = None,
                    trigger_level: int = 1, name: str | None = None) -> EncoderChannel:
        """Connect an encoder (and optionally a capture trigger) to the channel at ``address``."""
        if address in self.channels:
            raise ConfigurationError(f"encoder channel {hexaddr(address, 6)} is added twice")
        channel = EncoderChannel(self.sim, address, encoder, trigger=trigger, trigger_level=trigger_level,
                                 name=name, device=self.device)
        self.channels[address] = channel
        return channel

    def coordinate_system(self, number: int, *, axes: Iterable[str] = ("X",)) -> CoordinateSystem:
        """Coordinate system ``&number`` (created on first use; its job parts go to :attr:`job`)."""
        if number not in self.cs:
            cs = self.cs[number] = CoordinateSystem(self.sim, number, i10=self.i10, axes=axes, device=self.device)
            cs.on_program = self._program_event
        return self.cs[number]

    def _program_event(self, name: str, started: bool) -> None:
        """A motion program started or reached its end: a part of the job (see :mod:`cosim.job`)."""
        if started:
            self.job.begin(name)
        else:
            self.job.finish(name)

    def add_motor(self, number: int, *, cs: int = 1, axis: str = "X", counts_per_unit: int | Fraction = 1,
                  loop: PidLoop | None = None, feedback: Callable[[], int | float] | None = None,
                  terms: tuple[tuple[Fraction, str], ...] | None = None, offset: Fraction = Fraction(0)) -> Motor:
        """Motor ``#number`` on ``axis`` of coordinate system ``cs`` (``#n->counts_per_unit X``).

        ``terms`` (``((c1, "X"), (c2, "Y"))``) and ``offset`` give a linear combination of axes instead
        (``#n->c1X+c2Y+offset``); an axis ``#n`` (the motor's own name) is an inverse-kinematic motor.
        """
        if number in self.motors:
            raise ConfigurationError(f"motor {number} is added twice")
        motor = Motor(self.sim, number, self.coordinate_system(cs), axis=axis, counts_per_unit=counts_per_unit,
                      loop=loop, feedback=feedback, device=self.device, terms=terms, offset=offset)
        self.motors[number] = motor
        return motor

    def _check_definable(self, number: int, written: str, where: str) -> None:
        prefix = f"{where}: " if where else ""
        if self._started:
            raise ConfigurationError(f"{prefix}#{number}->{written}: motors are defined before the servo clock starts")
        if number in self.motors:
            old = self.motors[number]
            raise ConfigurationError(f"{prefix}#{number}->{written}: motor {number} is already defined "
                                     f"(on axis {old.axis} of coordinate system {old.cs.number})")

    def define_motor(self, number: int, *, cs: int, axis: str | None = None,
                     counts_per_unit: int | Fraction = 1, terms: tuple[tuple[Fraction, str], ...] | None = None,
                     offset: Fraction = Fraction(0), where: str = "") -> Motor:
        """``&cs #number->counts_per_unit axis`` (or a linear combination of axes): a motor, before start."""
        if terms is None:
            assert axis is not None
            terms = ((Fraction(counts_per_unit), axis),)
        written = "+".join(f"{c}{a}" for c, a in terms) + (f"+{offset}" if offset else "")
        self._check_definable(number, written, where)
        system = self.coordinate_system(cs)
        for _coefficient, name in terms:
            system.define_axis(name)
        first_scale, first_axis = terms[0]
        return self.add_motor(number, cs=cs, axis=first_axis, counts_per_unit=first_scale,
                              terms=terms if len(terms) > 1 or offset else None, offset=offset)

    def define_kinematic_motor(self, number: int, *, cs: int, inverse: bool, where: str = "") -> Motor | None:
        """``#n->I`` (its position comes from the coordinate system's inverse kinematics) or ``#n->0`` (no axis)."""
        self._check_definable(number, "I" if inverse else "0", where)
        if not inverse:
            self.sim.notes.not_modelled(self.device, f"#{number}->0", "assigned to no axis", where=where)
            return None
        name = f"#{number}"
        self.coordinate_system(cs).define_axis(name)
        return self.add_motor(number, cs=cs, axis=name, counts_per_unit=1)

    def undefine(self, cs: int | None, *, where: str = "") -> None:
        """``UNDEFINE`` (the axis definitions of ``cs``) or ``UNDEFINE ALL`` (cs None), before start."""
        if self._started:
            raise ConfigurationError(f"{where + ': ' if where else ''}UNDEFINE: axis definitions change before "
                                     "the servo clock starts in this model")
        for number in [n for n, m in self.motors.items() if cs is None or m.cs.number == cs]:
            del self.motors[number]

    def motor_axes(self, cs: int) -> set[str]:
        """Axes a program of coordinate system ``cs`` may move: those a motor is assigned to, and with motors
        ``#n->I`` (inverse kinematics) every axis letter A, B, C, U, V, W, X, Y, Z."""
        axes = {name for m in self.motors.values() if m.cs.number == cs for name in m.axes if not name.startswith("#")}
        if self.inverse_motors(cs):
            system = self.coordinate_system(cs)
            for name in KINEMATIC_AXES:
                system.define_axis(name)
            axes.update(KINEMATIC_AXES)
        return axes

    def inverse_motors(self, cs: int) -> list[int]:
        """Motors ``#n->I`` of coordinate system ``cs``."""
        return sorted(n for n, m in self.motors.items() if m.cs.number == cs and m.axis.startswith("#"))

    def motor_on(self, cs: int, axis: str) -> Motor:
        """The (first) motor on ``axis`` of coordinate system ``cs``."""
        for motor in self.motors.values():
            if motor.cs.number == cs and motor.axis == axis:
                return motor
        raise ConfigurationError(f"axis {axis} of coordinate system {cs} has no motor (define one with #n->{axis})")

    def rapid_parameters(self, cs: int, axis: str) -> tuple[Fraction, Fraction, Fraction]:
        """RAPID speed [axis units/ms], TA and TS [ms] of ``axis``: its motor's Ixx22, Ixx20, Ixx21."""
        motor = self.motor_on(cs, axis)
        jog = Fraction(self.get_ivar(motor.number * 100 + 22))
        if jog == 0:
            raise ConfigurationError(f"I{motor.number * 100 + 22} (Ixx22, jog speed) = 0: a RAPID move of axis {axis} "
                                     "needs a speed > 0")
        speed = jog / abs(motor.counts_per_unit)
        return (speed, Fraction(self.get_ivar(motor.number * 100 + 20)),
                Fraction(self.get_ivar(motor.number * 100 + 21)))

    def time_base_registers(self) -> dict[int, TimeBaseSource]:
        """Every register Ix93 may point at: ``%`` command registers and table time-base results."""
        registers: dict[int, TimeBaseSource] = {cs.percent_register.address: cs.percent_register
                                                for cs in self.cs.values()}
        for entry in self.table.time_base_entries():
            registers[entry.result_address] = EntrySource(entry)
        return registers

    def _describe_registers(self) -> str:
        parts = [f"{hexaddr(cs.percent_register.address)} (CS{cs.number} % register)" for cs in self.cs.values()]
        parts += [f"{hexaddr(e.result_address)} ({type(e).__name__} result)" for e in self.table.time_base_entries()]
        return ", ".join(parts)

    def set_ix93(self, number: int, address: int, *, where: str = "", ivar: str = "") -> None:
        """Point coordinate system ``number``'s time base at ``address`` (raises if nothing is there)."""
        cs = self.coordinate_system(number)
        source = self.time_base_registers().get(address)
        if source is None:
            raise ConfigurationError.out_of_range(
                ivar or f"I{number}93 (Ix93 of CS{number})", Reg(address),
                f"addresses of time-base registers: {self._describe_registers()}", where=where)
        cs.set_source(address, source)

    # -- I-variables -----------------------------------------------------------------------
    #: Coordinate-system variables the model acts on (Isx87..Isx89, Isx93..Isx95): setting one makes the system.
    CS_MODELLED = (87, 88, 89, 93, 94, 95)
    #: Motor variables the model acts on (RAPID speed, TA, TS: Ixx22, Ixx20, Ixx21).
    MOTOR_MODELLED = (20, 21, 22)
    #: Global variables the model acts on: I5 (which PLCs run), I10 (servo clock), I15 (degrees or radians),
    #: I68 (timers of active systems).
    GLOBAL_MODELLED = (5, 10, 15, 68)

    def set_ivar(self, number: int, value: int | Fraction, *, where: str = "") -> None:
        """Write I-variable ``number`` (like typing ``In=value``; at run time from the host).

        Every I0..I8191 is accepted within its range (:mod:`.ivartable`) and stored; a variable the
        model acts on acts, any other is listed in the run's notes as "set, not modelled".
        """
        checked = ivartable.check(number, value, where=where)
        family, unit, suffix = ivartable.split(number)
        if family == "ECT":
            self._write_ect_line(suffix, int(checked), where=where)
            return
        if family == "CS" and suffix in (11, 12):  # countdown timers: the value and the cycle it was written in
            self._timers[(unit, suffix)] = (int(checked), self.cycle)
            return
        self._ivars[number] = checked
        if family == "GLOBAL" and suffix == 10:
            if self._started:
                raise ConfigurationError(f"{where + ': ' if where else ''}I10 cannot change while the servo "
                                         "clock runs (the model fixes the servo period at start)")
            if self.cs:
                raise ConfigurationError(f"{where + ': ' if where else ''}set I10 before creating coordinate "
                                         "systems (their % registers are in units of I10)")
            self.clock = ServoClock(int(checked), self.clock.t0, self.clock.ns_per_tick)
        elif family == "CS" and suffix in self.CS_MODELLED:
            cs = self.coordinate_system(unit)
            if suffix == 93:
                self.set_ix93(unit, int(checked), where=where, ivar=f"I{number} (Ix93 of CS{unit})")
            elif suffix == 94:
                cs.set_ix94(checked, where=where)
            elif suffix == 95:
                cs.set_ix95(checked, where=where)
            elif suffix == 87:
                cs.ix87 = int(checked)
            elif suffix == 88:
                cs.ix88 = int(checked)
            else:
                cs.ix89 = Fraction(checked)
        elif not ((family == "MOTOR" and suffix in self.MOTOR_MODELLED)
                  or (family == "GLOBAL" and suffix in self.GLOBAL_MODELLED)
                  or (family == "CS" and suffix in (13, 50, 90))):
            self.sim.notes.not_modelled(self.device, f"I{number}", _shown(checked), where=where)

    def get_ivar(self, number: int) -> int | Fraction:
        """Read I-variable ``number``: what was set, or the reference's default."""
        family, unit, suffix = ivartable.split(number)
        if family == "ECT":
            address = self.table.base_address + suffix
            entry = self.table.entry_at(address)
            return entry.y_word(address - entry.address) if entry is not None else 0
        if family == "GLOBAL" and suffix == 10:
            return self.i10
        if family == "CS":
            if suffix in (11, 12):  # count down one per servo cycle while the system is active (I68)
                value, cycle = self._timers.get((unit, suffix), (0, self._cycle0 - 1))
                if unit > int(self.get_ivar(68)) + 1:
                    return value
                return max(ivartable.REG_MIN, value - (self.cycle - cycle))
            cs = self.cs.get(unit)
            if cs is not None and suffix in self.CS_MODELLED:
                values: dict[int, int | Fraction] = {87: cs.ix87, 88: cs.ix88, 89: cs.ix89, 93: cs.ix93,
                                                     94: cs.ix94, 95: cs.ix95}
                return values[suffix]
        stored = self._ivars.get(number)
        return stored if stored is not None else ivartable.default(number)

    def ivar_is_volatile(self, number: int) -> bool:
        """True for the countdown timers Isx11 and Isx12 (they change every servo cycle)."""
        family, _unit, suffix = ivartable.split(number)
        return family == "CS" and suffix in (11, 12)

    def _write_ect_line(self, index: int, value: int, *, where: str) -> None:
        address = self.table.base_address + index
        entry = self.table.entry_at(address)
        name = f"I{ivartable.ECT_FIRST + index}"
        if entry is None:
            raise ConfigurationError(
                f"{where + ': ' if where else ''}{name} = {hexaddr(value, 6)}: writing a conversion-table line "
                "that holds no entry is only modelled through load_setup() before start")
        offset = address - entry.address
        if isinstance(entry, TriggeredTimeBaseEntry) and offset == 0:
            entry.write_first_line(value, where=where, t=self.sim.now)
            if self._method is not None and entry is self._trigger_entry():
                self._method.set(entry.method)
            self.programs.wake()
        elif isinstance(entry, DifferentiatingEntry) and offset == 1:
            entry.set_scale_factor(value, where=where)
        else:
            raise ConfigurationError(
                f"{where + ': ' if where else ''}{name} = {hexaddr(value, 6)}: only the method digit of a "
                "triggered entry and the SCALE_FACTOR line of a time-base entry can change in this model")

    def build_table(self, lines: dict[int, int], *, where: dict[int, str]) -> None:
        """Build the (empty) conversion table from setup lines ``{index: value}`` (I8000 + index)."""
        if self.table.entries:
            raise ConfigurationError(f"{next(iter(where.values()), 'setup')}: sets conversion-table lines, but the "
                                     "table already has entries")
        self.table = ConversionTable.from_lines(lines, base_address=TURBO_ECT_BASE, where=where)

    def load_setup(self, text: str, *, source: str = "setup") -> None:
        """Apply a setup file: its I8000..I8191 lines build the table, then the rest in file order."""
        if self._started:
            raise ConfigurationError("load the setup before start()")
        assignments = parse_setup(text, source=source)
        lines = {a.number - ivartable.ECT_FIRST: int(a.value) for a in assignments if a.number >= ivartable.ECT_FIRST}
        if lines:
            if self.table.entries:
                raise ConfigurationError(f"{source}: sets conversion-table lines, but the table already has entries")
            where = {a.number - ivartable.ECT_FIRST: a.where for a in assignments if a.number >= ivartable.ECT_FIRST}
            self.build_table(lines, where=where)
        for a in (a for a in assignments if a.number < ivartable.ECT_FIRST):
            self.set_ivar(a.number, a.value, where=a.where)

    def load(self, text: str, *, source: str = "program.pmc", path: Path | None = None,
             defines: dict[str, str] | None = None, search: Iterable[Path] = ()) -> None:
        """Read a PMAC file (setup, definitions, programs, commands; see :mod:`.program`), before start.

        Raises
        ------
        ConfigurationError
            ``source:line:column: ...``. The whole file is parsed and checked first, so a syntax or
            range error applies nothing; an error that only applying shows (an Ix93 naming no
            time-base register) stops the load there.
        """
        if self._started:
            raise ConfigurationError(f"{source}: load PMAC files before start()")
        self.programs.load(text, source=source, path=path,
                           defines=self.defines if defines is None else defines,
                           search=[*search, *self.include_path])

    def command(self, text: str, *, source: str = "command") -> None:
        """Issue a line of online commands now (``&1 B1 R``, ``%50``, ``ENABLE PLC 1``)."""
        line = self.programs.parse_command(text, source=source)
        self.programs.execute(line.statements, self.programs.host)

    # -- host actions ----------------------------------------------------------------------
    def command_percent(self, number: int, pct: int | Fraction) -> int:
        """``&x %n``: returns the register value written."""
        return self.coordinate_system(number).command_percent(pct)

    # -- registers (M-variables) -------------------------------------------------------------
    def register_is_volatile(self, space: str, address: int) -> bool:
        """True for X registers (encoder counts, captures, table results change by themselves); Y words are setup."""
        return space == "X"

    def has_register(self, space: str, address: int) -> bool:
        """True if the model has register ``space:address`` (X or Y)."""
        if space == "Y":
            return self.table.entry_at(address) is not None
        return (any(address - base in (0, CAPTURE_OFFSET) for base in self.channels)
                or self.table.entry_at(address) is not None
                or any(address == cs.percent_register.address for cs in self.cs.values()))

    def describe_registers(self) -> str:
        """The registers M-variables may name, for messages."""
        channels = ", ".join(f"X:${a:06X} and X:${a + CAPTURE_OFFSET:06X}" for a in sorted(self.channels))
        lines = (f"X: and Y:{hexaddr(self.table.entries[0].address)}.." if self.table.entries else "no table lines")
        return f"encoder channels {channels or '(none)'}; table lines {lines}"

    def read_word(self, space: str, address: int) -> int:
        """The 24-bit word at ``space:address`` (an X read of a capture register re-arms it)."""
        if space == "Y":
            entry = self.table.entry_at(address)
            if entry is None:
                raise ConfigurationError.out_of_range("Y-memory address", Reg(address, digits=6),
                                                      "conversion-table lines (Y words = I8000..I8191)")
            return entry.y_word(address - entry.address)
        return self.read_x(address) & REG_MASK

    def write_word(self, space: str, address: int, value: int, *, where: str = "") -> None:
        """Write a Y word of the conversion table (= the I-variable of that line)."""
        if space != "Y" or self.table.entry_at(address) is None:
            raise ConfigurationError.out_of_range(f"{space}-memory address written", Reg(address, digits=6),
                                                  "Y words of conversion-table lines", where=where)
        self.set_ivar(ivartable.ECT_FIRST + address - self.table.base_address, value, where=where)

    def read_x(self, address: int) -> int:
        """Read X-memory ``address`` (e.g. ``M103`` on the capture register X:$07800B: re-arms it)."""
        for base, channel in self.channels.items():
            if address - base in (0, 3):
                return channel.read_register(address - base)
        entry = self.table.entry_at(address)
        if entry is not None:
            return entry.x_word(address - entry.address)
        for cs in self.cs.values():
            if address == cs.percent_register.address:
                return cs.percent_register.value
        raise ConfigurationError.out_of_range("X-memory address", Reg(address, digits=6),
                                              "encoder channel registers (+0 position, +3 capture), table lines, "
                                              "% registers")

    # -- the controller protocol ------------------------------------------------------------
    def outputs(self) -> list[Signal | PulseTrain]:
        """Every signal the PMAC drives: each motor's DAC (:class:`cosim.controllers.Controller`)."""
        return [motor.dac for motor in self.motors.values()]

    def inputs(self) -> list[Signal]:
        """Every signal the PMAC reads: the channels' capture triggers."""
        return [c.trigger for c in self.channels.values() if c.trigger is not None]

    # -- running ---------------------------------------------------------------------------
    def _trigger_entry(self) -> TriggeredTimeBaseEntry | None:
        return next((e for e in self.table.entries if isinstance(e, TriggeredTimeBaseEntry)), None)

    def start(self) -> None:
        """Check the configuration and start the servo interrupt process."""
        if self._started:
            raise ConfigurationError("Pmac.start() called twice")
        self.table.lenient = True  # motors' 1/T entries without a coupled encoder read 0 (listed below)
        self.table.bind(self.channels)
        for entry in self.table.entries:
            if isinstance(entry, OneOverTEntry) and entry.unconnected:
                self.sim.notes.not_modelled(self.device, entry.origin or entry.label(),
                                            f"1/T of channel {hexaddr(entry.channel_address, 6)}: no encoder is "
                                            "connected, the entry reads 0")
        registers = self.time_base_registers()
        for cs in self.cs.values():
            if cs.ix93 not in registers:
                raise ConfigurationError.out_of_range(
                    f"I{cs.number}93 (Ix93 of CS{cs.number})", Reg(cs.ix93),
                    f"addresses of time-base registers: {self._describe_registers()}")
            cs.set_source(cs.ix93, registers[cs.ix93])
        trigger = self._trigger_entry()
        first_1t = next((e for e in self.table.entries if isinstance(e, OneOverTEntry)), None)
        master = trigger or first_1t
        if master is not None:
            self._master = (master, 256 if master is trigger else 32)
            self._master_pos = Signal(self.sim, f"{self.device}.ect.master_pos", kind="real", unit="counts",
                                      description=f"master position from the {master.label()} (1/T extended)")
        if trigger is not None:
            self._method = Signal(self.sim, f"{self.device}.ect.method", kind="int", initial=trigger.method,
                                  description=f"method digit of the {trigger.label()}: 9 frozen, 11 armed, 10 running")
            self._time_zero = Signal(self.sim, f"{self.device}.ect.time_zero_pos", kind="real", initial=float("nan"),
                                     unit="counts", description="captured master position used as time zero")
            self._stale = Signal(self.sim, f"{self.device}.ect.stale_start", kind="bit",
                                 description="1 from a triggered start whose capture latched before the entry was "
                                             "last frozen (the stale-capture hazard)")
        k0 = self.clock.first_cycle_at_or_after(self.sim.now)
        self._timers = {key: (value, k0 - 1 if cycle < k0 else cycle) for key, (value, cycle) in self._timers.items()}
        self._cycle, self._cycle0 = k0 - 1, k0
        self.programs.start()
        self._started = True
        self.sim.process(self.servo_cycle())

    def servo_cycle(self) -> Generator[Any, Any, None]:
        """The servo interrupt: table, coordinate systems, motors, every ``t_k``."""
        k = k0 = self.clock.first_cycle_at_or_after(self.sim.now)
        trigger = self._trigger_entry()
        env, table, clock = self.sim.env, self.table, self.clock
        master = self._master if self._master_pos is not None else None
        method = trigger.method if trigger is not None else None
        servo, programs = Priority.SERVO, self.programs
        coordinate_systems, motors = self.cs.values(), self.motors.values()  # live views
        while True:
            t = clock.t(k)
            yield At(env, t, servo)  # t >= now: the clock's instants only grow
            self._cycle = k
            table.run(t, k)
            if master is not None:
                entry, scale = master
                self._master_pos.set(entry.position / scale)  # type: ignore[union-attr]
            if trigger is not None and self._method is not None and self._time_zero is not None:
                if trigger.method != self._method.value:  # also written by the host between cycles
                    self._method.set(trigger.method)
                if trigger.method != method:
                    method = trigger.method
                    self.programs.wake()  # the method digit changed: PLCs may read it
                if trigger.starts and trigger.starts[-1].cycle == k:
                    self._time_zero.set(trigger.starts[-1].time_zero_pos256 / 256)
                    if self._stale is not None:
                        self._stale.set(trigger.starts[-1].stale)
            if k > k0:
                for cs in coordinate_systems:
                    cs.update(k, t)
                programs.foreground()
            for motor in motors:
                motor.update(k, t)
            k += 1


def _shown(value: int | Fraction) -> int | float | str:
    """A stored I-variable value as the notes show it (exact integers, fractions as their decimal)."""
    if isinstance(value, int):
        return value
    return float(value)
