"""The programs of a PMAC: loading text, online commands, starting motion programs, scanning PLCs.

:class:`Programs` holds a controller's motion programs (``PROG n``), PLC programs (``PLC n``),
kinematic programs (``FORWARD``/``INVERSE`` per coordinate system), its variables
(:class:`~cosim.controllers.pmac.mvars.Memory`) and the host's command session, and runs online
commands (``&1 B1 R``, ``%50``, ``H``, ``I8008=$9F8018``, ``ENABLE PLC 1..3``, ``^A``, ...) whether they
come from a file, from the machine's command schedule or from a ``CMD"..."`` (see :mod:`.commands`).

Scan model
----------
* **Motion programs** are calculated in the servo interrupt of their coordinate system (see
  :mod:`cosim.controllers.pmac.interpreter`): after the conversion table, before and after the
  moves advance; statements there see the table as this cycle left it.
* **PLC 0** runs in the foreground: one scan every servo cycle, after the coordinate systems
  (the real-time interrupt, modelled at every servo cycle: I8 is not modelled).
* **PLC 1..31** run in the background, between servo interrupts: every enabled one is scanned
  once, in number order, at ``offset + k * period`` (``plc_scan_period``, default 200 us, and
  ``plc_scan_offset``, default 0), with priority :data:`BACKGROUND`: after every host action of the
  same instant (``[[command]]`` lines, scripts), before outputs settle and samples are taken. The
  period stands for the background cycle time, which on a real controller depends on its load.
* **Quiet scans are not repeated** (the design that keeps a PMAC run fast): when a background round
  changed nothing (no variable got a new value, no command, no output) and read nothing that changes
  by itself (an encoder or capture register, a table result, a countdown timer), and every PLC
  stopped where it started, the next rounds would do exactly the same until something a PLC can
  read changes (any write with a new value, an M-variable definition, ENABLE/DISABLE, the triggered
  entry's method digit turning to running). Those rounds are not run. Without plants that watch
  their outputs (no kernel look-ahead), not even their instants are scheduled: the background
  waits for the change and scans again at the first grid instant at or after it -- the instant and
  the result a scan of every grid instant would have given. With a watched plant (a Conveyor's
  registration mark) every grid instant keeps its event, because the kernel advances that plant to
  each event instant and its encoder edges are located from those steps: removing the instants
  would move edge instants by float rounding (a 1/256-count change of the master position in the
  flying shear), so the trace would no longer be the one of every instant scanned. Skipped scans are
  counted in :attr:`Programs.scans`.

So the time between a motion program's freeze of a triggered time-base entry and the PLC's arming
of it is at most one scan period (the stale-capture hazard of the Turbo manual depends on it; see
``docs/pmac.md``).

PLC programs are disabled after ``OPEN PLC`` and start with ``ENABLE PLC n`` (from the top);
``DISABLE PLC n`` stops one, ``PAUSE PLC n`` / ``RESUME PLC n`` stop and go on where it was.
``ENABLE``/``DISABLE``/``PAUSE``/``RESUME`` of a number that holds no PLC program (``DISABLE PLC
2..31`` over a project's few PLCs) does nothing to it, as on the controller; the run's notes say so.

**I5** (PLC program control; range 0..3, default 1 in the Turbo reference) permits what an enabled
PLC needs to run: bit 0 the foreground PLC 0 (and PLCC 0), bit 1 the background PLC 1..31 (and
PLCC 1..31). So at the default (1) PLC 0 runs and the background PLCs do not, however enabled; a
project that uses background PLCs sets I5 = 2 or 3. I5 is read at every scan (a program may
change it; the background wakes on the write). A PLC enabled when the servo clock starts (or
enabled later) that I5 keeps off is listed in the run's notes with the place of its ``ENABLE``.
"""

from __future__ import annotations

from collections.abc import Generator, Iterable
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path
from typing import Any

from cosim import validate
from cosim.controllers.pmac import ivartable
from cosim.controllers.pmac.bus import Controller
from cosim.controllers.pmac.commands import Commands
from cosim.controllers.pmac.interpreter import (
    KINEMATIC_AXES,
    Compiled,
    Context,
    MotionModes,
    MotionProgram,
    PlcProgram,
    Session,
    run_to_end,
)
from cosim.controllers.pmac.mvars import Memory
from cosim.controllers.pmac.nodes import (
    Assign,
    Begin,
    Call,
    Cmd,
    CodeCall,
    CsSelect,
    MoveStmt,
    PlcControl,
    Pos,
    Stmt,
    Var,
    constant,
    located,
)
from cosim.controllers.pmac.program import CODE_PROGRAMS, Buffer, Code, compile_buffer, parse_text, stmt_variables
from cosim.controllers.pmac.syntax import parse_line
from cosim.job import JobState
from cosim.timebase import Priority

#: Default background (PLC) scan period [ns]: a lightly loaded controller.
PLC_SCAN_PERIOD_NS = 200_000
#: Priority of the background scans: after host actions (HOST), before SETTLE and SAMPLE.
BACKGROUND = Priority.HOST + 5


@dataclass(frozen=True)
class CommandLine:
    """A parsed line of online commands (``&1 B1 R``) and where it was written."""

    text: str
    statements: tuple[Stmt, ...]


class Programs(Commands):
    """Motion, PLC and kinematic programs, variables and command sessions of one controller.

    Parameters
    ----------
    pmac : Pmac
        The controller.
    """

    def __init__(self, pmac: Controller) -> None:
        self.pmac = pmac
        self.memory = Memory(pmac)
        self.memory.on_change = self.wake
        self.memory.on_unmodelled = self.not_modelled
        self.motion: dict[int, Code] = {}
        self.kinematic: dict[tuple[str, int], Code] = {}
        self.plcs: dict[int, PlcProgram] = {}
        self.enabled: set[int] = set()
        self.paused: set[int] = set()
        self.host = Session()
        self.selected: dict[int, int] = {}
        self.modes: dict[int, MotionModes] = {}
        self.running: dict[int, MotionProgram] = {}
        self.scan_period = pmac.sim.ticks(PLC_SCAN_PERIOD_NS, "ns")
        self.scan_offset = 0
        self._scans_run = 0
        self._dormant_from: int | None = None  # grid index of the first scan not run while waiting
        self._wake_event: Any = None
        self._dirty = True
        self._lines: dict[tuple[str, int], list[tuple[Stmt, ...]]] = {}
        self._uses: list[tuple[int, int, Pos]] = []
        self._compiled: dict[int, Compiled] = {}
        self._enabled_at: dict[int, Pos] = {}  # where each PLC was last enabled (for the I5 note)
        self._scanning = False

    # -- compiled code -------------------------------------------------------------------------
    def compiled(self, code: Code) -> Compiled:
        """``code`` prepared for running (kept: the code object stays alive as long as this entry)."""
        found = self._compiled.get(id(code))
        if found is None or found.code is not code:
            found = self._compiled[id(code)] = Compiled(code)
        return found

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
        elif buffer.kind in ("FORWARD", "INVERSE"):
            self.kinematic[(buffer.kind, buffer.number)] = code
        elif buffer.kind == "ROTARY":
            self.not_modelled("OPEN ROTARY", f"{sum(len(line) for line in lines)} statements", str(buffer.pos))
        elif buffer.number in self.plcs:
            self.plcs[buffer.number].restart(code)
            self.enabled.discard(buffer.number)
        else:
            self.plcs[buffer.number] = PlcProgram(code, self)

    def load(self, text: str, *, source: str, path: Path | None = None, defines: dict[str, str] | None = None,
             search: Iterable[Path] = ()) -> None:
        """Apply a PMAC file: its conversion-table lines first (as :meth:`Pmac.load_setup`), then in order."""
        parsed = parse_text(text, source=source, path=path, defines=defines, search=tuple(search))
        table_lines: dict[int, int] = {}
        where: dict[int, str] = {}
        used: set[int] = set()
        if not self.pmac.table.entries:
            for index, item in enumerate(parsed.items):
                if (isinstance(item, Assign) and isinstance(item.var, Var) and item.var.kind == "I"
                        and item.var.number >= ivartable.ECT_FIRST and item.expr is not None):
                    value = constant(item.expr)
                    if value is not None:  # an integer: checked when parsed
                        table_lines[item.var.number - ivartable.ECT_FIRST] = int(value)
                        where[item.var.number - ivartable.ECT_FIRST] = str(item.pos)
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
            if stmt.name in ("OPENBUFFER", "CLEAR", "CLOSE", "MOTORDEF", "MOTORKINEMATIC"):
                raise stmt.pos.error(f"{stmt.name} belongs in a file loaded before the run, not in a timed command")
        return CommandLine(text, tuple(statements))

    # -- what programs ask (interpreter.Host) --------------------------------------------------
    def program(self, number: int, pos: Pos) -> Code:
        """Motion program ``number`` (a jump into nothing is an error naming ``pos``)."""
        code = self.motion.get(number)
        if code is None:
            known = ", ".join(str(n) for n in sorted(self.motion)) or "none"
            raise pos.error(f"PROG {number} does not exist (motion programs: {known})")
        return code

    def ivar(self, number: int) -> Fraction | int:
        return self.pmac.get_ivar(number)

    def fault(self, reason: str) -> None:
        """A motion program stopped on an error: the job stops with the reason."""
        self.pmac.job.stop(JobState.ERROR, reason)

    def not_modelled(self, name: str, value: object, where: str) -> None:
        """List a setting or command that is accepted and kept but does not act."""
        self.pmac.sim.notes.not_modelled(self.pmac.device, name, value, where=where)

    def console(self, source: str, text: str) -> None:
        """A line on the run's console (SEND, DISPLAY) from ``pmac.<source>``."""
        sim = self.pmac.sim
        sim.trace.write_line(sim.now, f"{self.pmac.device}.{source}", text)

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

    def kinematics(self, cs_number: int, targets: dict[str, Fraction], pos: Pos) -> dict[str, Fraction]:
        """Counts of the coordinate system's ``#n->I`` motors at axis positions ``targets``: ``OPEN INVERSE``."""
        motors = self.pmac.inverse_motors(cs_number)
        if not motors or self.pmac.get_ivar(5000 + 100 * cs_number + 50) != 1:
            return {}
        code = self.kinematic.get(("INVERSE", cs_number)) or self.kinematic.get(("INVERSE", 0))
        if code is None:
            raise pos.error(f"coordinate system {cs_number} has motors #n->I ({', '.join(f'#{m}' for m in motors)}) "
                            f"and I{5000 + 100 * cs_number + 50}=1, but no OPEN INVERSE program")
        memory = self.memory
        for index, axis in enumerate(KINEMATIC_AXES, 1):
            if axis in targets:
                memory.write("Q", index, targets[axis], cs_number, pos)
        run_to_end(code, self, cs=cs_number)
        return {f"#{m}": Fraction(memory.p[m]) for m in motors}

    def forward(self, cs_number: int, pos: Pos) -> None:
        """``OPEN FORWARD``: motor positions in P1..P32, axis positions out of Q1..Q9 (R, PMATCH; Isx50 = 1)."""
        if self.pmac.get_ivar(5000 + 100 * cs_number + 50) != 1:
            return
        code = self.kinematic.get(("FORWARD", cs_number)) or self.kinematic.get(("FORWARD", 0))
        if code is None:
            return
        memory = self.memory
        cs = self.pmac.coordinate_system(cs_number)
        for number, motor in self.pmac.motors.items():
            if motor.cs is cs:
                memory.write("P", number, Fraction(*motor.cmd_ratio), cs_number, pos)
        run_to_end(code, self, cs=cs_number)
        positions = {axis: Fraction(memory.read("Q", index, cs_number, pos))
                     for index, axis in enumerate(KINEMATIC_AXES, 1) if axis in cs.axes}
        cs.set_positions(positions)

    # -- starting motion programs ------------------------------------------------------------------
    def begin(self, cs_number: int, number: int, pos: Pos) -> None:
        """``&x Bn``: point coordinate system x at the top of motion program n (B0: its rotary buffer)."""
        if number == 0:
            self.not_modelled(f"&{cs_number} B0", "the rotary buffer (not run)", str(pos))
            self.selected[cs_number] = 0
            return
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
        if number == 0:
            self.not_modelled(f"&{cs_number} R", "run of the rotary buffer (not modelled: nothing runs)", str(pos))
            return
        modes = self.modes.get(cs_number)
        if modes is None:
            base = 5000 + 100 * cs_number
            modes = self.modes[cs_number] = MotionModes(ta_ms=Fraction(self.pmac.get_ivar(base + 87)),
                                                        ts_ms=Fraction(self.pmac.get_ivar(base + 88)),
                                                        feedrate=Fraction(self.pmac.get_ivar(base + 89)))
        self.forward(cs_number, pos)
        program = MotionProgram(self.program(number, pos), self, cs_number, modes)
        self.running[cs_number] = program
        cs.run_feeder(program, name=f"CS{cs_number} PROG {number}")

    def abort(self, cs_number: int, how: str, pos: Pos) -> None:
        """``A`` (abort), ``K`` (kill), ``Q`` (quit), ``/`` or ``\\`` (stop): the program stops now."""
        cs = self.pmac.coordinate_system(cs_number)
        if cs.program_done:
            return
        self.running.pop(cs_number, None)
        reason = f"{how} of coordinate system {cs_number} at {pos}: its program stopped"
        cs.abort(reason)
        self.not_modelled(f"&{cs_number}{how}", "stops at once (the controller decelerates at Ixx15)", str(pos))
        self.pmac.job.stop(JobState.ABORTED, reason)

    # -- PLCs ---------------------------------------------------------------------------------
    def plc_control(self, stmt: PlcControl) -> None:
        """``ENABLE``/``DISABLE``/``PAUSE``/``RESUME`` ``PLC`` n,m..k (numbers with no PLC: no effect)."""
        self.note_missing(stmt)
        for number in stmt.plcs:
            plc = self.plcs.get(number)
            if plc is None:
                continue  # the controller accepts it: there is nothing to enable or disable
            if stmt.verb == "ENABLE":
                self._enabled_at[number] = stmt.pos
                if self._scanning and not self.i5_permits(number):
                    self._note_i5(number)
            if stmt.verb == "ENABLE" and number not in self.enabled:
                plc.restart(plc.context.code)
                self.enabled.add(number)
                self.paused.discard(number)
            elif stmt.verb == "DISABLE":
                self.enabled.discard(number)
            elif stmt.verb == "PAUSE":
                self.paused.add(number)
            elif stmt.verb == "RESUME":
                self.paused.discard(number)
        self.wake()

    def note_missing(self, stmt: PlcControl) -> None:
        """List the numbers of ``stmt`` that hold no PLC program in the run's notes (it does nothing to them)."""
        missing = tuple(number for number in stmt.plcs if number not in self.plcs)
        if missing:
            known = ", ".join(str(n) for n in sorted(self.plcs)) or "none"
            self.pmac.sim.notes.add(
                f"{self.pmac.device}: {stmt.verb} PLC{'C' if stmt.compiled else ''} at {stmt.pos}: no PLC program "
                f"{_numbers(missing)} (no effect on {'it' if len(missing) == 1 else 'them'}; PLC programs: {known})",
                key=f"PLC missing {self.pmac.device} {stmt.pos}")

    def _note_i5(self, number: int) -> None:
        """PLC ``number`` is enabled but I5 keeps it off: say so in the run's notes."""
        self.pmac.sim.notes.add(
            f"{self.pmac.device}: ENABLE PLC {number} at {self._enabled_at[number]}: I5 = {self.pmac.get_ivar(5)} "
            f"keeps {'PLC 0 (foreground)' if number == 0 else 'the background PLCs 1..31'} off (the PLC runs when "
            f"I5 is {'1 or 3' if number == 0 else '2 or 3'})", key=f"I5 {self.pmac.device} {number}")

    def i5_permits(self, number: int) -> bool:
        """I5 lets PLC ``number`` run: bit 0 for the foreground PLC 0, bit 1 for the background PLC 1..31."""
        return bool(int(self.pmac.get_ivar(5)) & (1 if number == 0 else 2))

    def configure_scan(self, *, period: int | None = None, offset: int | None = None) -> None:
        """Background scan period and offset [ticks] (see the module docstring)."""
        if period is not None:
            self.scan_period = validate.integer(period, "plc_scan_period [ticks]", low=1)
        if offset is not None:
            self.scan_offset = validate.integer(offset, "plc_scan_offset [ticks]", low=0)

    @property
    def scans(self) -> int:
        """Background scan rounds so far, those that were run and those skipped as repeats of a quiet one."""
        if self._dormant_from is None:
            return self._scans_run
        return self._scans_run + max(0, self._grid_index(self.pmac.sim.now) - self._dormant_from)

    def _grid_index(self, t: int) -> int:
        """Index of the first background instant at or after ``t``."""
        return max(0, -(-(t - self.scan_offset) // self.scan_period))

    def wake(self) -> None:
        """Something a PLC can read has changed: the background scans again."""
        self._dirty = True
        event = self._wake_event
        if event is not None:
            self._wake_event = None
            event.succeed()

    def foreground(self) -> None:
        """PLC 0, once per servo cycle."""
        if 0 in self.enabled and 0 not in self.paused and self.i5_permits(0):
            self.plcs[0].scan()

    def background(self) -> Generator[Any, Any, None]:
        """The background scans of PLC 1..31 (a SimPy process)."""
        sim = self.pmac.sim
        period, offset = self.scan_period, self.scan_offset
        k = self._grid_index(sim.now)
        quiet = False
        while True:
            yield sim.at(offset + k * period, BACKGROUND)
            self._scans_run += 1
            k += 1
            if quiet and not self._dirty:
                continue  # a repeat of the quiet round before: nothing to do
            self._dirty = False
            quiet = True
            for number in sorted(self.enabled) if self.i5_permits(1) else ():
                if number != 0 and number in self.enabled and number not in self.paused:
                    quiet = self.plcs[number].scan() and quiet
            if quiet and not sim.env.look_aheads:  # the next rounds would repeat this one: wait for a change
                self._dormant_from = k
                self._wake_event = sim.env.event()
                yield self._wake_event
                resume = max(k, self._grid_index(sim.now))
                self._scans_run += resume - k
                self._dormant_from = None
                k = resume
                quiet = False

    # -- checks before the run ----------------------------------------------------------------
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
                number = constant(stmt.number)
                if number is not None:
                    session.cs = int(number)
            elif isinstance(stmt, Begin):
                number = constant(stmt.number)
                if number is not None and number != 0:  # B0: the rotary buffer (not run)
                    self.check_program_axes(session.cs, self.program(int(number), stmt.pos))
            elif isinstance(stmt, PlcControl):
                self.note_missing(stmt)
            for var in stmt_variables(stmt):
                self._check_var(var)

    def _check_var(self, var: Var) -> None:
        if var.kind == "M" and var.number not in self.memory.definitions:
            raise var.pos.error(f"M{var.number} is not defined (define it first, e.g. M{var.number}->X:$07800B,0,24,S)")

    def check(self) -> None:
        """Before the servo clock starts: every jump, program, PLC, axis and M-variable is there."""
        listed: set[int] = set()
        for definition in self.memory.definitions.values():
            if id(definition) not in listed:
                listed.add(id(definition))
                self.memory.check_definition(definition)
        codes = [*self.motion.values(), *(plc.context.code for plc in self.plcs.values()), *self.kinematic.values()]
        for code in codes:
            for stmt in code.statements():
                if isinstance(stmt, Call):
                    self.program(stmt.program, stmt.pos)
                elif isinstance(stmt, CodeCall):
                    self.program(CODE_PROGRAMS[stmt.letter], stmt.pos)
                elif isinstance(stmt, Cmd):
                    self._check_statements(stmt.commands, Session())
                elif isinstance(stmt, PlcControl):
                    self._check_statements((stmt,), Session())
            for var in code.variables():
                self._check_var(var)
        for cs_number, number, _pos in self._uses:
            self.check_program_axes(cs_number, self.motion[number])

    def start(self) -> None:
        """Check everything and start the background scans (if there are PLC programs)."""
        self.check()
        self._scanning = True
        for number in sorted(self.enabled):
            if not self.i5_permits(number):
                self._note_i5(number)
        if any(number != 0 for number in self.plcs):
            self.pmac.sim.process(self.background())


def _numbers(numbers: tuple[int, ...]) -> str:
    """``2..4, 7`` for (2, 3, 4, 7)."""
    parts: list[str] = []
    start = previous = numbers[0]
    for number in (*numbers[1:], None):
        if number is not None and number == previous + 1:
            previous = number
            continue
        parts.append(str(start) if start == previous else f"{start}..{previous}")
        if number is not None:
            start = previous = number
    return ", ".join(parts)


__all__ = ["BACKGROUND", "PLC_SCAN_PERIOD_NS", "CommandLine", "Context", "Programs", "Session"]
