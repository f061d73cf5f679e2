"""Trio BASIC programs: parsed, checked and compiled before they run; run as SimPy processes.

A program is parsed with the LALR grammar of :mod:`.grammar`, checked and compiled by
:mod:`.compiler` (every error a program can show without running is found here, with the file,
line and column), and run by :class:`BasicRun` on a process of the controller with its own BASE,
local variables and ``TICKS``; ``VR``, ``TABLE``, the axes and the I/O are shared. Several programs
run at once (``RUN "NAME", process`` or :meth:`BasicProgram.start` with ``process=``).

Timing: statements take no simulated time; a program only waits at ``WAIT IDLE``, ``WAIT LOADED``,
``WAIT UNTIL`` (checked at once, then at every servo tick), ``WA``, a move while the move buffer is
full, and a ``PWM_CONTROL(3)`` while the FIFO is full. A process that runs
:data:`MAX_STATEMENTS_PER_SERVO_PERIOD` statements within one servo period is stopped with an
error naming its line: statements take no time in this model, so a loop that polls without
waiting (or waits a few ns at a time) would freeze the simulated clock or crawl along it (wait with
``WAIT UNTIL``, which checks once per servo cycle, or ``WA``).

Programs that run at the same instant run one after the other, each until it waits, in the order
they became ready (deterministic).
"""

from __future__ import annotations

from collections.abc import Generator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import simpy
from lark import Tree
from lark.exceptions import UnexpectedCharacters, UnexpectedInput, UnexpectedToken
from simpy.events import Event

from cosim import validate
from cosim.controllers.grammars import lark_parser
from cosim.controllers.trio.compiler import Compiled, Compiler
from cosim.controllers.trio.controller import TrioController
from cosim.controllers.trio.grammar import GRAMMAR, normalise_lines
from cosim.controllers.trio.params import PROCESSES
from cosim.controllers.trio.process import TrioProcess
from cosim.controllers.trio.values import Value
from cosim.errors import ConfigurationError, TimingViolation
from cosim.kernel import At
from cosim.timebase import Priority

EXAMPLES = Path(__file__).resolve().parent / "examples"
#: Statements a process may run within one servo period.
MAX_STATEMENTS_PER_SERVO_PERIOD = 100_000
#: Deepest GOSUB nesting.
MAX_GOSUB_DEPTH = 64
#: Longest console line [characters]; a longer one is written in parts.
MAX_PRINT_LINE = 10_000

_PARSER = lark_parser(GRAMMAR, parser="lalr", propagate_positions=True, maybe_placeholders=True)
_TERMINALS = {"_NL": "end of line", "NAME": "a name", "NUMBER": "a number", "HEXNUM": "a $hex number",
              "STRING": "a \"string\"", "LABEL": "a label", "LPAR": "(", "RPAR": ")", "COMMA": ",", "_COMMA": ",",
              "COLON": ":", "SEMICOLON": ";", "MINUS": "-", "PLUS": "+", "_EQ": "=", "CMP": "a comparison",
              "ADD": "+ or -", "MUL": "* / MOD", "LOGIC_AND": "AND", "LOGIC_OR": "OR XOR"}


@dataclass(frozen=True)
class BasicProgram:
    """A parsed, checked and compiled Trio BASIC program.

    Parameters
    ----------
    name : str
        Shown in error messages (``tn20_81.bas line 12: ...``); its stem is the name ``RUN`` uses.
    text : str
        The program text.
    """

    name: str
    text: str
    compiled: Compiled = field(repr=False, compare=False)

    @classmethod
    def parse(cls, text: str, *, name: str = "program.bas") -> BasicProgram:
        """Parse, check and compile ``text``; any line end (LF, CRLF, CR, FF, VT, NEL, ...) is accepted.

        Raises
        ------
        ConfigurationError
            A syntax error, an unknown keyword, a wrong argument count, ... with the line and column.
        """
        normalised = normalise_lines(text)
        try:
            tree = _PARSER.parse(normalised)
        except UnexpectedInput as exc:
            raise ConfigurationError(_syntax_message(exc, normalised, name)) from None
        assert isinstance(tree, Tree)
        return cls(name, text, Compiler(name).compile(tree))

    @classmethod
    def load(cls, path: str | Path) -> BasicProgram:
        """Parse a program file (UTF-8, or Latin-1 where it is not UTF-8)."""
        path = Path(path)
        data = path.read_bytes()
        try:
            text = data.decode("utf-8")
        except UnicodeDecodeError:
            text = data.decode("latin-1")
        return cls.parse(text, name=path.name)

    @property
    def key(self) -> str:
        """The name ``RUN "NAME"`` finds the program by: the file name without extension, upper case."""
        return Path(self.name).stem.upper()

    def install(self, controller: TrioController) -> None:
        """Make the program known to ``controller``, so a program can start it with ``RUN "NAME"``."""
        controller.programs[self.key] = self

    def start(self, controller: TrioController, *, process: int | None = None, base: tuple[int, ...] = (0,),
              at: int | None = None) -> BasicRun:
        """Run the program on ``controller`` from tick ``at`` (default: now), as a SimPy process.

        Parameters
        ----------
        controller : TrioController
        process : int, optional
            Process number, 1..5 (TRM 7-12: a Euro 205 runs 5 programs); default the lowest free.
        base : tuple of int
            BASE group the program starts with.
        at : int, optional
            Start instant [ticks].

        Raises
        ------
        ConfigurationError
            A process number outside 1..5 or already running a program, a bad BASE.
        """
        number = _process_number(controller, process)
        self.install(controller)
        run = BasicRun(self, controller, base=base, number=number)
        for channel in self.compiled.inputs:  # so a machine can drive them from the start; a bad channel is an
            if 0 <= channel < controller.io.channels:  # error at its line when the program gets there
                controller.io.input(channel)
        for channel in self.compiled.outputs:
            if controller.io.first_output <= channel < controller.io.channels:
                controller.io.output(channel)
        controller.processes[number] = run
        run.process_handle = controller.sim.process(run.main(controller.sim.now if at is None else at))
        return run


def _process_number(controller: TrioController, process: int | None) -> int:
    allowed = f"1..{PROCESSES} (the user processes of a Euro 205)"
    if process is None:
        free = [n for n in range(1, PROCESSES + 1) if n not in controller.processes]
        if not free:
            raise ConfigurationError.out_of_range("number of running programs", PROCESSES + 1, f"1..{PROCESSES}")
        return free[0]
    number = validate.integer(process, "process", low=1, high=PROCESSES, allowed=allowed, whole=True)
    if number in controller.processes:
        raise ConfigurationError(f"process {number} already runs {controller.processes[number].program.name}")
    return number


def example(name: str = "tn20_81") -> BasicProgram:
    """A program bundled in ``cosim/controllers/trio/examples`` (``tn20_81``: the note's example)."""
    path = EXAMPLES / f"{name}.bas"
    if not path.exists():
        known = ", ".join(sorted(p.stem for p in EXAMPLES.glob("*.bas")))
        raise ConfigurationError.out_of_range("example", name, known)
    return BasicProgram.load(path)


def _expected(exc: UnexpectedInput) -> str:
    names = getattr(exc, "expected", None) or getattr(exc, "allowed", None) or set()
    shown = sorted({_TERMINALS.get(n, n.lstrip("_")) for n in names})
    return f" (expected: {', '.join(shown)})" if shown else ""


def _syntax_message(exc: UnexpectedInput, text: str, name: str) -> str:
    lines = text.splitlines()
    line, column = exc.line, exc.column
    source = lines[line - 1] if 1 <= line <= len(lines) else ""
    if isinstance(exc, UnexpectedToken):
        found = "end of line" if exc.token.type == "_NL" else repr(str(exc.token))
    elif isinstance(exc, UnexpectedCharacters):
        found = repr(source[column - 1]) if 1 <= column <= len(source) else "?"
    else:
        found = "end of program"
    return (f"{name} line {line}, column {column}: syntax error, unexpected {found}{_expected(exc)}\n"
            f"    {source.rstrip()}")


class BasicRun:
    """One running program: its process, local variables, loops, GOSUB stack, and the SimPy process.

    Parameters
    ----------
    program : BasicProgram
    controller : TrioController
    base : tuple of int
        BASE group the program starts with.
    number : int
        Process number.
    """

    program: BasicProgram
    controller: TrioController
    process: TrioProcess
    variables: dict[str, Value]

    def __init__(self, program: BasicProgram, controller: TrioController, *, base: tuple[int, ...] = (0,),
                 number: int = 1) -> None:
        self.program = program
        self.controller = controller
        self.sim = controller.sim
        self.number = number
        self.process = TrioProcess(controller, base)
        self.variables: dict[str, Value] = {}
        self.loops: dict[int, tuple[Value, Value]] = {}
        self.gosubs: list[int] = []
        self.pending: Event | None = None
        self.pc = 0
        self.finished = False
        self.stopped = False
        self.process_handle: simpy.Process | None = None
        self._printing: list[str] = []
        self._printed = 0

    @property
    def line(self) -> int:
        """The program line being run."""
        lines = self.program.compiled.lines
        return lines[self.pc] if 0 <= self.pc < len(lines) else 0

    @property
    def where(self) -> str:
        return f"{self.program.name} line {self.line}"

    def main(self, at: int) -> Generator[Event, Any, None]:
        """The program as a SimPy process, from tick ``at`` (priority HOST)."""
        ops = self.program.compiled.ops
        try:
            yield self.sim.at(at, Priority.HOST)
            period = self.controller.period_ticks
            pc, cycle, used = 0, -1, 0
            while 0 <= pc < len(ops):
                now = self.sim.now
                if now // period != cycle:
                    cycle, used = now // period, 0
                used += 1
                self.pc = pc
                if used > MAX_STATEMENTS_PER_SERVO_PERIOD:
                    raise TimingViolation(
                        f"process {self.number} ran {MAX_STATEMENTS_PER_SERVO_PERIOD} statements in the servo period "
                        f"from t = {cycle * period} ns to {now} ns; statements take no simulated time, so a loop "
                        "that does not wait for the servo cycle would freeze the clock (wait with WAIT UNTIL, "
                        "WAIT IDLE or WA)")
                pc = ops[pc](self, pc)
                event, self.pending = self.pending, None
                if event is not None and (isinstance(event, At) or not event.triggered):
                    yield event  # a command that had room at once (a succeeded plain event) does not wait
        except simpy.Interrupt:
            self.stopped = True
        except (ConfigurationError, TimingViolation) as exc:
            raise type(exc)(f"{self.where}: {exc}") from exc
        finally:
            if self.controller.processes.get(self.number) is self:
                del self.controller.processes[self.number]
            if self._printing:
                self._flush_print()
        self.finished = True

    def stop(self) -> None:
        """Stop the program where it waits (Trio ``STOP``); moves it has issued still run to their end."""
        if self.process_handle is not None and self.process_handle.is_alive and not self.finished:
            self.process_handle.interrupt("STOP")

    # -- what the compiled operations call ------------------------------------------------------
    def variable(self, name: str) -> Value:
        """A local variable's value (an error if the program has not assigned it yet)."""
        try:
            return self.variables[name]
        except KeyError:
            raise ConfigurationError(f"variable {name} is read before the program assigns it") from None

    def next_servo_tick(self) -> Event:
        """An event at the next servo tick (after the servo cycle there)."""
        period = self.controller.period_ticks
        return self.sim.at((self.sim.now // period + 1) * period, Priority.HOST)

    def call_gosub(self, return_pc: int) -> None:
        if len(self.gosubs) >= MAX_GOSUB_DEPTH:
            raise ConfigurationError.out_of_range("GOSUB nesting", len(self.gosubs) + 1, f"1..{MAX_GOSUB_DEPTH}")
        self.gosubs.append(return_pc)

    def return_from_gosub(self) -> int:
        if not self.gosubs:
            raise ConfigurationError("RETURN without GOSUB")
        return self.gosubs.pop()

    def print_text(self, text: str, *, end: bool) -> None:
        """``PRINT``: add ``text`` to the line; a line is written to the console when it ends (or reaches
        :data:`MAX_PRINT_LINE` characters)."""
        self._printing.append(text)
        self._printed += len(text)
        if end or self._printed >= MAX_PRINT_LINE:
            self._flush_print()

    def _flush_print(self) -> None:
        self.controller.console.write(process=self.number, program=self.program.name, line=self.line,
                                      text="".join(self._printing))
        self._printing, self._printed = [], 0

    def run_program(self, name: str, process: Value | None) -> None:
        """``RUN "NAME"[, process]``: start another program the controller knows."""
        program = self.controller.programs.get(name.upper())
        if program is None:
            known = ", ".join(sorted(self.controller.programs)) or "none"
            raise ConfigurationError.out_of_range("RUN program", name, f"a program the machine loads: {known}")
        if any(run.program is program for run in self.controller.processes.values()):
            raise ConfigurationError(f"RUN \"{name}\": the program is already running")
        program.start(self.controller, process=None if process is None else process)

    def command(self, name: str, args: list[Value], axis: Value | None) -> Event | None:
        """Run command ``name``; an event the program waits for, or None."""
        p = self.process
        p.origin = self.where
        if name == "BASE":
            p.base(*args)
        elif name == "TABLE":
            p.table(*args)
        elif name == "DEFPOS":
            p.defpos(*args, axis=axis)
        elif name == "PWM_CONTROL":
            return p.pwm_control(args[0], *args[1:], axis=axis)
        elif name in ("MOVE", "MOVEABS"):
            return (p.move if name == "MOVE" else p.moveabs)(*args, axis=axis)
        elif name == "MOVECIRC":
            return p.movecirc(*args)
        elif name in ("FORWARD", "REVERSE"):
            return (p.forward if name == "FORWARD" else p.reverse)(axis=axis)
        elif name == "CANCEL":
            p.cancel(axis=axis)
        elif name == "WA":
            return p.wa(args[0])
        elif name == "OP":
            p.op(args[0], args[1])
        return None
