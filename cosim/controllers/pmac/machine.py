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
"""

from __future__ import annotations

from collections.abc import Callable, Generator, Iterable
from fractions import Fraction
from typing import TYPE_CHECKING, Any

from cosim.controllers.pmac import ivars
from cosim.controllers.pmac.coord import CoordinateSystem, TimeBaseSource
from cosim.controllers.pmac.ect import (
    TURBO_ECT_BASE,
    ConversionTable,
    DifferentiatingEntry,
    OneOverTEntry,
    TriggeredTimeBaseEntry,
)
from cosim.controllers.pmac.encoder import EncoderChannel, EncoderSource
from cosim.controllers.pmac.motor import Motor
from cosim.controllers.pmac.servo import PidLoop
from cosim.controllers.pmac.units import I10_DEFAULT, Reg, ServoClock, hexaddr
from cosim.errors import ConfigurationError
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
    def units_per_count(self) -> Fraction:
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
        self.cycle = -1
        self._started = False
        self._master: tuple[OneOverTEntry | TriggeredTimeBaseEntry, int] | None = None
        self._master_pos: Signal | None = None
        self._method: Signal | None = None
        self._time_zero: Signal | None = None

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
        """Coordinate system ``&number`` (created on first use)."""
        if number not in self.cs:
            self.cs[number] = CoordinateSystem(self.sim, number, i10=self.i10, axes=axes, device=self.device)
        return self.cs[number]

    def add_motor(self, number: int, *, cs: int = 1, axis: str = "X", counts_per_unit: int | Fraction = 1,
                  loop: PidLoop | None = None, feedback: Callable[[], int | float] | None = None) -> Motor:
        """Motor ``#number`` on ``axis`` of coordinate system ``cs`` (``#n->counts_per_unit X``)."""
        if number in self.motors:
            raise ConfigurationError(f"motor {number} is added twice")
        motor = Motor(self.sim, number, self.coordinate_system(cs), axis=axis, counts_per_unit=counts_per_unit,
                      loop=loop, feedback=feedback, device=self.device)
        self.motors[number] = motor
        return motor

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
    def set_ivar(self, number: int, value: int, *, where: str = "") -> None:
        """Write I-variable ``number`` (like typing ``In=value``; at run time from the host)."""
        value = ivars.check_ivar(number, value, where=where)
        name = f"I{number}"
        cs_var = ivars.cs_ivar(number)
        if number == 10:
            if self._started:
                raise ConfigurationError(f"{where + ': ' if where else ''}I10 cannot change while the servo "
                                         "clock runs (the model fixes the servo period at start)")
            if self.cs:
                raise ConfigurationError(f"{where + ': ' if where else ''}set I10 before creating coordinate "
                                         "systems (their % registers are in units of I10)")
            self.clock = ServoClock(value, self.clock.t0, self.clock.ns_per_tick)
        elif cs_var is not None:
            x, suffix = cs_var
            if suffix == 93:
                self.set_ix93(x, value, where=where, ivar=f"{name} (Ix93 of CS{x})")
            else:
                self.coordinate_system(x).set_ix94(value, where=where)
        else:
            self._write_ect_line(number - ivars.ECT_FIRST, value, where=where)

    def get_ivar(self, number: int) -> int:
        """Read I-variable ``number``."""
        if not ivars.is_known(number):
            ivars.check_ivar(number, 0)  # raises: unknown variable
        cs_var = ivars.cs_ivar(number)
        if number == 10:
            return self.i10
        if cs_var is not None:
            cs = self.coordinate_system(cs_var[0])
            return cs.ix93 if cs_var[1] == 93 else cs.ix94
        address = self.table.base_address + number - ivars.ECT_FIRST
        entry = self.table.entry_at(address)
        return entry.y_word(address - entry.address) if entry is not None else 0

    def _write_ect_line(self, index: int, value: int, *, where: str) -> None:
        address = self.table.base_address + index
        entry = self.table.entry_at(address)
        name = f"I{ivars.ECT_FIRST + index}"
        if entry is None:
            raise ConfigurationError(
                f"{where + ': ' if where else ''}{name} = {hexaddr(value, 6)}: writing a conversion-table line "
                "that holds no entry is only modelled through load_setup() before start")
        offset = address - entry.address
        if isinstance(entry, TriggeredTimeBaseEntry) and offset == 0:
            entry.write_first_line(value, where=where, t=self.sim.now)
            if self._method is not None and entry is self._trigger_entry():
                self._method.set(entry.method)
        elif isinstance(entry, DifferentiatingEntry) and offset == 1:
            entry.set_scale_factor(value, where=where)
        else:
            raise ConfigurationError(
                f"{where + ': ' if where else ''}{name} = {hexaddr(value, 6)}: only the method digit of a "
                "triggered entry and the SCALE_FACTOR line of a time-base entry can change in this model")

    def load_setup(self, text: str, *, source: str = "setup") -> None:
        """Apply a setup file: its I8000..I8191 lines build the table, then the rest in file order."""
        if self._started:
            raise ConfigurationError("load the setup before start()")
        assignments = ivars.parse_setup(text, source=source)
        lines = {a.number - ivars.ECT_FIRST: a.value for a in assignments if a.number >= ivars.ECT_FIRST}
        if lines:
            if self.table.entries:
                raise ConfigurationError(f"{source}: sets conversion-table lines, but the table already has entries")
            where = {a.number - ivars.ECT_FIRST: a.where for a in assignments if a.number >= ivars.ECT_FIRST}
            self.table = ConversionTable.from_lines(lines, base_address=TURBO_ECT_BASE, where=where)
        for a in (a for a in assignments if a.number < ivars.ECT_FIRST):
            self.set_ivar(a.number, a.value, where=a.where)

    # -- host actions ----------------------------------------------------------------------
    def command_percent(self, number: int, pct: int | Fraction) -> int:
        """``&x %n``: returns the register value written."""
        return self.coordinate_system(number).command_percent(pct)

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
        self.table.bind(self.channels)
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
        self._started = True
        self.sim.process(self.servo_cycle())

    def servo_cycle(self) -> Generator[Any, Any, None]:
        """The servo interrupt: table, coordinate systems, motors, every ``t_k``."""
        k = k0 = self.clock.first_cycle_at_or_after(self.sim.now)
        trigger = self._trigger_entry()
        while True:
            t = self.clock.t(k)
            yield self.sim.at(t, Priority.SERVO)
            self.cycle = k
            self.table.run(t, k)
            if self._master is not None and self._master_pos is not None:
                entry, scale = self._master
                self._master_pos.set(entry.position / scale)
            if trigger is not None and self._method is not None and self._time_zero is not None:
                self._method.set(trigger.method)
                if trigger.starts and trigger.starts[-1].cycle == k:
                    self._time_zero.set(trigger.starts[-1].time_zero_pos256 / 256)
            if k > k0:
                for cs in self.cs.values():
                    cs.update(k, t)
            for motor in self.motors.values():
                motor.update(k, t)
            k += 1
