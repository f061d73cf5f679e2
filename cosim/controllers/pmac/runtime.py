"""The programs of a PMAC: loading text, online commands, starting motion programs, scanning PLCs.

:class:`Programs` holds a controller's motion programs (``PROG n``) and PLC programs (``PLC n``),
its variables (:class:`~cosim.controllers.pmac.mvars.Memory`) and the host's command session, and
runs online commands (``&1 B1 R``, ``%50``, ``H``, ``I8008=$9F8018``, ``ENABLE PLC 1``, ...)
whether they come from a file, from the machine's command schedule or from a ``CMD"..."``.

Scan model
----------
* **Motion programs** are calculated in the servo interrupt of their coordinate system (see
  :mod:`cosim.controllers.pmac.interpreter`): after the conversion table, before and after the
  moves advance; statements there see the table as this cycle left it.
* **PLC 0** runs in the foreground: one scan every servo cycle, after the coordinate systems
  (the real-time interrupt, modelled at every servo cycle: I8 = 0).
* **PLC 1..31** run in the background, between servo interrupts: every enabled one is scanned
  once, in number order, at ``offset + k * period`` (``plc_scan_period``, default 200 us, and
  ``plc_scan_offset``, default 0; priority HOST, after the servo tasks of the same instant). The
  period stands for the background cycle time, which on a real controller depends on its load:
  tens of microseconds when lightly loaded, milliseconds under a heavy load.

So the time between a motion program's freeze of a triggered time-base entry and the PLC's
arming of it is at most one scan period: with a period shorter than the servo period (a light
load) the PLC can arm before any servo cycle has seen the entry frozen, and without a dummy read
of the capture register a stale capture starts the motion (the Turbo manual's warning); with a
period of several servo cycles the frozen entry is most likely seen (its read of the capture
register re-arms the capture), but never certainly: the arm may come in the first interval.

PLC programs are disabled after ``OPEN PLC`` and start with ``ENABLE PLC n`` (from the top);
``DISABLE PLC n`` stops one (I5 is not modelled: every PLC may run).
"""

from __future__ import annotations

from collections.abc import Generator, Iterable, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from typing import TYPE_CHECKING, Any

from cosim import validate
from cosim.controllers.pmac.interpreter import MotionModes, MotionProgram, PlcProgram, evaluate
from cosim.controllers.pmac.mvars import Memory
from cosim.controllers.pmac.nodes import (
    Assign,
    Begin,
    Call,
    Clear,
    Close,
    Cmd,
    CsSelect,
    Disable,
    Enable,
    Hold,
    MDefine,
    MotorDef,
    MotorSelect,
    OpenBuffer,
    Percent,
    Pos,
    Query,
    Run,
    Stmt,
    Var,
    constant,
    located,
)
from cosim.controllers.pmac.program import (
    Buffer,
    Code,
    MoveStmt,
    compile_buffer,
    parse_text,
    stmt_variables,
)
from cosim.controllers.pmac.statements import (
    parse_line,
)
from cosim.timebase import Priority

if TYPE_CHECKING:
    from cosim.controllers.pmac.machine import Pmac

#: Default background (PLC) scan period [ns]: a lightly loaded controller.
PLC_SCAN_PERIOD_NS = 200_000


@dataclass
class Session:
    """Modal addressing of a command source: the coordinate system (``&n``) and motor (``#n``)."""

    cs: int = 1
    motor: int = 1


@dataclass(frozen=True)
class CommandLine:
    """A parsed line of online commands (``&1 B1 R``) and where it was written."""

    text: str
    statements: tuple[Stmt, ...]


@dataclass
class Programs:
    """Motion and PLC programs, variables and command sessions of one controller.

    Parameters
    ----------
    pmac : Pmac
        The controller.
    """

    pmac: Pmac
    memory: Memory = field(init=False)
    motion: dict[int, Code] = field(default_factory=dict)
    plcs: dict[int, PlcProgram] = field(default_factory=dict)
    enabled: set[int] = field(default_factory=set)
    host: Session = field(default_factory=Session)
    selected: dict[int, int] = field(default_factory=dict)
    modes: dict[int, MotionModes] = field(default_factory=dict)
    scan_period: int = 0
    scan_offset: int = 0
    scans: int = 0
    _lines: dict[tuple[str, int], list[tuple[Stmt, ...]]] = field(default_factory=dict)
    _uses: list[tuple[int, int, Pos]] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.memory = Memory(self.pmac)
        self.scan_period = self.pmac.sim.ticks(PLC_SCAN_PERIOD_NS, "ns")

    # -- loading ---------------------------------------------------------------------------
    def install(self, buffer: Buffer) -> None:
        """Store a buffer of a file (``OPEN`` without ``CLEAR`` appends to what is there)."""
        key = (buffer.kind, buffer.number)
        if buffer.clear or key not in self._lines:
            lines, code = list(buffer.lines), buffer.code
        else:
            lines = self._lines[key] + list(buffer.lines)
            code = compile_buffer(buffer.kind, buffer.number, lines, pos=buffer.pos)
        self._lines[key] = lines
        if buffer.kind == "PROG":
            self.motion[buffer.number] = code
        elif buffer.number in self.plcs:
            self.plcs[buffer.number].restart(code)
            self.enabled.discard(buffer.number)
        else:
            self.plcs[buffer.number] = PlcProgram(code, self, Session())

    def load(self, text: str, *, source: str) -> None:
        """Apply a PMAC file: its conversion-table lines first (as :meth:`Pmac.load_setup`), then in order."""
        parsed = parse_text(text, source=source)
        table_lines: dict[int, int] = {}
        where: dict[int, str] = {}
        used: set[int] = set()
        if not self.pmac.table.entries:
            for index, item in enumerate(parsed.items):
                is_line = isinstance(item, Assign) and item.var.kind == "I" and item.var.number >= 8000
                value = constant(item.expr) if isinstance(item, Assign) and is_line else None
                if isinstance(item, Assign) and value is not None:  # an integer: checked when parsed
                    table_lines[item.var.number - 8000] = int(value)
                    where[item.var.number - 8000] = str(item.pos)
                    used.add(index)
        if table_lines:
            self.pmac.build_table(table_lines, where=where)
        for index, item in enumerate(parsed.items):
            if index in used:
                continue
            if isinstance(item, Buffer):
                self.install(item)
            else:
                self.execute((item,), self.host)

    def parse_command(self, text: str, *, source: str, line: int = 1) -> CommandLine:
        """Parse a line of online commands (checked as far as one line allows)."""
        statements = parse_line(text, context="online", source=source, line=line)
        for stmt in statements:
            if isinstance(stmt, OpenBuffer | Clear | Close | MotorDef):
                raise stmt.pos.error(f"{stmt.name} belongs in a file loaded before the run, not in a timed command")
        return CommandLine(text, tuple(statements))

    # -- online commands ---------------------------------------------------------------------
    def execute(self, statements: Iterable[Stmt], session: Session) -> None:
        """Run online commands with ``session``'s addressing."""
        pmac = self.pmac
        for stmt in statements:
            with located(stmt.pos):
                if isinstance(stmt, CsSelect):
                    session.cs = stmt.number
                elif isinstance(stmt, MotorSelect):
                    session.motor = stmt.number
                elif isinstance(stmt, MotorDef):
                    pmac.define_motor(stmt.motor, cs=session.cs, axis=stmt.axis, counts_per_unit=stmt.scale,
                                      where=str(stmt.pos))
                elif isinstance(stmt, Begin):
                    self.begin(session.cs, stmt.number, stmt.pos)
                elif isinstance(stmt, Run):
                    self.run(session.cs, stmt.pos)
                elif isinstance(stmt, Hold):
                    pmac.coordinate_system(session.cs).hold()
                elif isinstance(stmt, Percent):
                    pmac.command_percent(session.cs, stmt.value)
                elif isinstance(stmt, Assign):
                    self.memory.write(stmt.var, evaluate(stmt.expr, self), stmt.pos)
                elif isinstance(stmt, MDefine):
                    self.memory.define(stmt)
                elif isinstance(stmt, Query):
                    self.memory.read(stmt.var)
                elif isinstance(stmt, Enable | Disable):
                    self.enable(stmt.plcs, isinstance(stmt, Enable), stmt.pos)
                else:
                    raise stmt.pos.error(f"{stmt.name} cannot be issued here")

    def program(self, number: int, pos: Pos) -> Code:
        """Motion program ``number`` (a jump into nothing is an error naming ``pos``)."""
        code = self.motion.get(number)
        if code is None:
            known = ", ".join(str(n) for n in sorted(self.motion)) or "none"
            raise pos.error(f"PROG {number} does not exist (motion programs: {known})")
        return code

    def begin(self, cs_number: int, number: int, pos: Pos) -> None:
        """``&x Bn``: point coordinate system x at the top of motion program n."""
        code = self.program(number, pos)
        self.check_program_axes(cs_number, code)
        cs = self.pmac.coordinate_system(cs_number)
        if not cs.program_done:
            cs.notes.append((self.pmac.sim.now, f"B{number} ignored at {pos}: CS{cs_number} is running a program"))
            return
        self.selected[cs_number] = number
        self._uses.append((cs_number, number, pos))

    def run(self, cs_number: int, pos: Pos) -> None:
        """``&x R``: run the program (or end a feed hold)."""
        cs = self.pmac.coordinate_system(cs_number)
        if cs.holding:
            cs.release()
            return
        if not cs.program_done:
            cs.notes.append((self.pmac.sim.now, f"R ignored at {pos}: CS{cs_number} is running a program"))
            return
        number = self.selected.get(cs_number)
        if number is None:
            raise pos.error(f"R: coordinate system {cs_number} has no program to run (point it at one with B n)")
        modes = self.modes.get(cs_number)
        if modes is None:
            modes = self.modes[cs_number] = MotionModes(ta_ms=Fraction(cs.ix87), ts_ms=Fraction(cs.ix88),
                                                        feedrate=Fraction(cs.ix89))
        cs.run_feeder(MotionProgram(self.program(number, pos), self, Session(cs=cs_number), modes))

    def enable(self, numbers: Sequence[int], on: bool, pos: Pos) -> None:
        """``ENABLE PLC n`` (from the top) or ``DISABLE PLC n``."""
        for number in numbers:
            plc = self.plcs.get(number)
            if plc is None:
                known = ", ".join(str(n) for n in sorted(self.plcs)) or "none"
                raise pos.error(f"PLC {number} does not exist (PLC programs: {known})")
            if on and number not in self.enabled:
                plc.restart(plc.context.code)
                self.enabled.add(number)
            elif not on:
                self.enabled.discard(number)

    # -- program checks ----------------------------------------------------------------------
    def check_axis(self, cs_number: int, axis: str, pos: Pos) -> None:
        """A move on ``axis`` needs a motor assigned to it in the coordinate system."""
        axes = self.pmac.motor_axes(cs_number)
        if axis not in axes:
            raise pos.error(f"axis {axis} is not defined in coordinate system {cs_number} (its axes: "
                            f"{', '.join(sorted(axes)) or 'none'}; define one with &{cs_number} #n->{axis})")

    def rapid_parameters(self, cs_number: int, axis: str, pos: Pos) -> tuple[Fraction, Fraction, Fraction]:
        """RAPID speed [units/ms], TA and TS [ms] of ``axis`` (its motor's Ixx22, Ixx20, Ixx21)."""
        with located(pos):
            return self.pmac.rapid_parameters(cs_number, axis)

    def check_program_axes(self, cs_number: int, code: Code) -> None:
        """Every axis that ``code`` (and the programs it calls) moves is defined in the coordinate system."""
        seen: set[int] = set()
        todo = [code]
        while todo:
            current = todo.pop()
            for stmt in current.statements():
                if isinstance(stmt, MoveStmt):
                    for word in stmt.axes:
                        self.check_axis(cs_number, word.axis, word.pos)
                elif isinstance(stmt, Call) and stmt.program not in seen and stmt.program in self.motion:
                    seen.add(stmt.program)
                    todo.append(self.motion[stmt.program])

    def check_commands(self, lines: Iterable[CommandLine], session: Session | None = None) -> None:
        """Check timed command lines before the run: programs and PLCs exist, axes, M-variables."""
        session = session or Session(self.host.cs, self.host.motor)
        for line in lines:
            self._check_statements(line.statements, session)

    def _check_statements(self, statements: Iterable[Stmt], session: Session) -> None:
        for stmt in statements:
            if isinstance(stmt, CsSelect):
                session.cs = stmt.number
            elif isinstance(stmt, Begin):
                self.check_program_axes(session.cs, self.program(stmt.number, stmt.pos))
            elif isinstance(stmt, Enable | Disable):
                for number in stmt.plcs:
                    if number not in self.plcs:
                        self.enable((number,), True, stmt.pos)  # raises: no such PLC
            for var in stmt_variables(stmt):
                self._check_var(var)

    def _check_var(self, var: Var) -> None:
        if var.kind == "M" and var.number not in self.memory.definitions:
            raise var.pos.error(f"M{var.number} is not defined (define it first, e.g. M{var.number}->X:$07800B,0,24,S)")

    def check(self) -> None:
        """Before the servo clock starts: every jump, program, PLC, axis and M-variable is there."""
        for definition in self.memory.definitions.values():
            self.memory.check_definition(definition)
        for code in [*self.motion.values(), *(plc.context.code for plc in self.plcs.values())]:
            for stmt in code.statements():
                if isinstance(stmt, Call):
                    self.program(stmt.program, stmt.pos)
                elif isinstance(stmt, Cmd):
                    self._check_statements(stmt.commands, Session())
                elif isinstance(stmt, Enable | Disable):
                    self._check_statements((stmt,), Session())
            for var in code.variables():
                self._check_var(var)
        for cs_number, number, _pos in self._uses:
            self.check_program_axes(cs_number, self.motion[number])

    # -- running -----------------------------------------------------------------------------
    def configure_scan(self, *, period: int | None = None, offset: int | None = None) -> None:
        """Background scan period and offset [ticks] (see the module docstring)."""
        if period is not None:
            self.scan_period = validate.integer(period, "plc_scan_period [ticks]", low=1)
        if offset is not None:
            self.scan_offset = validate.integer(offset, "plc_scan_offset [ticks]", low=0)

    def foreground(self) -> None:
        """PLC 0, once per servo cycle."""
        if 0 in self.enabled:
            self.plcs[0].scan()

    def background(self) -> Generator[Any, Any, None]:
        """The background scans of PLC 1..31 (a SimPy process)."""
        sim = self.pmac.sim
        period, offset = self.scan_period, self.scan_offset
        k = max(0, -(-(sim.now - offset) // period))
        while True:
            yield sim.at(offset + k * period, Priority.HOST)
            self.scans += 1
            for number in sorted(self.enabled):
                if number != 0 and number in self.enabled:
                    self.plcs[number].scan()
            k += 1

    def start(self) -> None:
        """Check everything and start the background scans (if there are PLC programs)."""
        self.check()
        if any(number != 0 for number in self.plcs):
            self.pmac.sim.process(self.background())
