"""Running a compiled Trio BASIC program on a process of the controller.

The layers of the language, each importing only the ones below it::

    grammar (text -> syntax tree) -> compiler (tree -> operations) -> operations, commands, functions
                                     -> runtime (this module: a process running the operations)

A program is a list of operations ``op(run, pc) -> next pc`` (:class:`Compiled`); :class:`BasicRun`
runs them as a SimPy process with the process' own BASE, local variables, ``TICKS``, error handler
and GOSUB stack. ``VR``, ``TABLE``, the axes, the I/O and the channels are shared.

Timing: statements take no simulated time; a program only waits at ``WAIT IDLE``, ``WAIT LOADED``,
``WAIT UNTIL`` (checked at once, then at every servo tick), ``WA``, a move while the move buffer is
full, a ``PWM_CONTROL(3)`` while the FIFO is full, and ``INPUT``/``GET`` until their channel has a
line or a character. A process that runs :data:`MAX_STATEMENTS_PER_SERVO_PERIOD` statements within
one servo period is stopped with an error naming its line (a loop that never waits would freeze
the simulated clock).

Priorities (TRM 7-12: the servo period is shared by three time slots, and the two highest
processes of a Euro 205, 5 and 4, are its high-priority tasks): programs that are ready at the same
instant run one after the other, each until it waits; processes 5 then 4 first, the others in the
order they became ready.

Errors: a run-time error (a value out of range, a division by zero, a bad index...) stops the
process with the error's number (``RUN_ERROR``) and line (``ERROR_LINE``), written to the console
as the controller does. With ``ON BASICERROR GOTO label`` (or ``GOSUB``) the program goes on at the
label instead; taking the handler disarms it [?: a model choice], so an error in the handler itself
stops the program (write ON BASICERROR again to re-arm it). Without a handler the run stops there
(the trace is kept up to that instant) and
the controller's job is stopped with the reason (``trio.job``: ERROR).
"""

from __future__ import annotations

from collections.abc import Callable, Generator
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import simpy
from simpy.events import Event

from cosim.controllers.trio.process import TrioProcess
from cosim.controllers.trio.servo import MemoryPoll
from cosim.controllers.trio.values import Datum, Value, typed
from cosim.errors import ConfigurationError, TimingViolation
from cosim.job import JobState
from cosim.kernel import At
from cosim.timebase import Priority

if TYPE_CHECKING:
    from cosim.controllers.trio.controller import TrioController

#: Statements a process may run within one servo period.
MAX_STATEMENTS_PER_SERVO_PERIOD = 100_000
#: Deepest GOSUB nesting.
MAX_GOSUB_DEPTH = 64
#: Longest console line [characters]; a longer one is written in parts.
MAX_PRINT_LINE = 10_000
#: Process numbers of the Euro 205's high-priority tasks (TRM 7-12), highest first.
HIGH_PRIORITY = (5, 4)

Op = Callable[["BasicRun", int], int]


class BasicError(ConfigurationError):
    """A run-time error of a Trio BASIC program: its number (``RUN_ERROR``) and text.

    Numbers (the model's; the manual's own table was not at hand): 1 a value or argument out of
    range, 2 division by zero, 3 a variable read before it is assigned, 4 an index outside an array,
    5 a string where a number is needed or the other way round, 6 RETURN without GOSUB or GOSUB
    nesting too deep, 7 a program or process that does not exist or is busy, 8 a command the model
    does not simulate, 9 a value beyond the variable format.
    """

    def __init__(self, message: str, code: int = 1) -> None:
        super().__init__(message)
        self.code = code


@dataclass(frozen=True)
class Compiled:
    """A compiled program: operations, the source (file, line) of each, the channels it names, its declarations.

    Parameters
    ----------
    ops : tuple of Op
    sources : tuple of (str, int)
        The file and line each operation comes from (an INCLUDEd file names itself).
    inputs, outputs : frozenset of int
        Input and output channels its literals name (created when it starts, for stimuli).
    """

    ops: tuple[Op, ...]
    sources: tuple[tuple[str, int], ...]
    inputs: frozenset[int] = frozenset()
    outputs: frozenset[int] = frozenset()
    labels: dict[str, int] = field(default_factory=dict)


class BasicRun:
    """One running program: its process, local variables, loops, GOSUB stack, error handler, SimPy process.

    Parameters
    ----------
    name : str
        The program's name (``tn20_81.bas``), as messages show it.
    compiled : Compiled
    controller : TrioController
    base : tuple of int
        BASE group the program starts with.
    number : int
        Process number.
    """

    def __init__(self, name: str, compiled: Compiled, controller: TrioController, *, base: tuple[int, ...] = (0,),
                 number: int = 1, program: Any = None) -> None:
        self.name = name
        self.compiled = compiled
        self.program = program
        self.controller = controller
        self.sim = controller.sim
        self.number = number
        self.process = TrioProcess(controller, base)
        self.variables: dict[str, Datum] = {}
        self.arrays: dict[str, list[Datum]] = {}
        self.types: dict[str, tuple[str, int]] = {}  # DIM'd names: (kind, string length)
        self.array_sizes: dict[str, tuple[int, ...]] = {}
        #: RUN, STOP, process parameters: set by the program that starts the run (see :mod:`.basic`).
        self.program_control: Any = None
        self.input_step = 0
        self.input_prompted = False
        self.stop_requested = False
        self.max_statements = MAX_STATEMENTS_PER_SERVO_PERIOD
        self.loops: dict[int, tuple[Value, Value]] = {}
        self.gosubs: list[int] = []
        self.pending: Event | None = None
        self.pc = 0
        self.finished = False
        self.stopped = False
        self.process_handle: simpy.Process | None = None
        self.error_handler: tuple[int, bool] | None = None  # ON BASICERROR: (pc, gosub)
        self.error_line = 0
        self.run_error = 0
        self.indevice = 0
        self.outdevice = 0
        self.waiting_move = False
        #: The part of the controller's job this process is (None: not part of the job).
        self.job_part: str | None = None
        self.priority = Priority.HOST - (len(HIGH_PRIORITY) - HIGH_PRIORITY.index(number)
                                         if number in HIGH_PRIORITY else 0)
        self._printing: list[str] = []
        self._printed = 0
        self._print_channel = 0

    @property
    def line(self) -> int:
        """The program line being run."""
        sources = self.compiled.sources
        return sources[self.pc][1] if 0 <= self.pc < len(sources) else 0

    @property
    def where(self) -> str:
        sources = self.compiled.sources
        file = sources[self.pc][0] if 0 <= self.pc < len(sources) else self.name
        return f"{file} line {self.line}"

    def main(self, at: int) -> Generator[Event, Any, None]:
        """The program as a SimPy process, from tick ``at``."""
        ops = self.compiled.ops
        try:
            yield At(self.sim.env, at, self.priority)
            period = self.controller.period_ticks
            pc, cycle, used = 0, -1, 0
            while 0 <= pc < len(ops):
                now = self.sim.now
                if now // period != cycle:
                    cycle, used = now // period, 0
                used += 1
                self.pc = pc
                if used > self.max_statements:
                    raise TimingViolation(
                        f"process {self.number} ran {self.max_statements} statements in the servo period "
                        f"from t = {cycle * period} ns to {now} ns; statements take no simulated time, so a loop "
                        "that does not wait for the servo cycle would freeze the clock (wait with WAIT UNTIL, "
                        "WAIT IDLE or WA)")
                try:
                    pc = ops[pc](self, pc)
                except ConfigurationError as exc:
                    pc = self._handle(exc, pc)
                if self.stop_requested:
                    break
                event, self.pending = self.pending, None
                if event is not None and (isinstance(event, At) or not event.triggered):
                    yield event  # a command that had room at once (a succeeded plain event) does not wait
        except simpy.Interrupt:
            self.stopped = True
        except (ConfigurationError, TimingViolation) as exc:
            self._stop_job(exc)
            raise type(exc)(f"{self.where}: {exc}") from exc
        finally:
            self._end()
        self.finished = True

    def _handle(self, exc: ConfigurationError, pc: int) -> int:
        """A run-time error at ``pc``: go on at the ON BASICERROR label, or raise it."""
        self.error_line, self.run_error = self.line, getattr(exc, "code", 1)
        self.controller.console.error(process=self.number, text=f"%[Process {self.number}:Line {self.line}] - {exc}")
        if self.error_handler is None:
            raise exc
        target, gosub = self.error_handler
        self.error_handler = None  # taken: an error in the handler stops the program (ON BASICERROR re-arms it)
        if gosub:
            self.call_gosub(pc + 1)
        return target

    def _stop_job(self, exc: Exception) -> None:
        job = self.controller.job
        if self.job_part is not None:
            job.stop(JobState.ERROR, f"process {self.number} ({self.name}) {self.where}: {exc}")

    def _end(self) -> None:
        controller = self.controller
        if controller.processes.get(self.number) is self:
            del controller.processes[self.number]
        if self._printing:
            self._flush_print()
        if self.job_part is not None:
            controller.job.finish(self.job_part)

    def stop(self) -> None:
        """Stop the program where it waits (Trio ``STOP``); moves it has issued still run to their end."""
        if self.process_handle is not None and self.process_handle.is_alive and not self.finished:
            self.process_handle.interrupt("STOP")

    # -- what the compiled operations call ------------------------------------------------------
    def variable(self, name: str) -> Datum:
        """A local variable's value (an error if the program has not assigned it yet)."""
        try:
            return self.variables[name]
        except KeyError:
            raise BasicError(f"variable {name} is read before the program assigns it", 3) from None

    def next_servo_tick(self, *, memory_only: bool = False) -> Event:
        """An event at the next servo tick (after the servo cycle there); ``memory_only``: for a check that reads
        only memory (a :class:`~.servo.MemoryPoll`, which the servo cycle's closed form does not stop at)."""
        period = self.controller.period_ticks
        return (MemoryPoll if memory_only else At)(self.sim.env, (self.sim.now // period + 1) * period, self.priority)

    def call_gosub(self, return_pc: int) -> None:
        if len(self.gosubs) >= MAX_GOSUB_DEPTH:
            raise BasicError(f"GOSUB nesting = {len(self.gosubs) + 1} is not allowed (allowed: 1..{MAX_GOSUB_DEPTH})",
                             6)
        self.gosubs.append(return_pc)

    def return_from_gosub(self) -> int:
        if not self.gosubs:
            raise BasicError("RETURN without GOSUB", 6)
        return self.gosubs.pop()

    def print_text(self, text: str, *, end: bool, channel: int = 0) -> None:
        """``PRINT``: add ``text`` to the line; a line is written to the console when it ends (or reaches
        :data:`MAX_PRINT_LINE` characters). A channel other than 0 is named at the start of the line."""
        if channel != self._print_channel and self._printing:
            self._flush_print()
        self._print_channel = channel
        self._printing.append(text)
        self._printed += len(text)
        if end or self._printed >= MAX_PRINT_LINE:
            self._flush_print()

    def _flush_print(self) -> None:
        text = "".join(self._printing)
        if self._print_channel:
            text = f"[#{self._print_channel}] {text}"
        self.controller.console.write(process=self.number, program=self.name, line=self.line, text=text)
        self._printing, self._printed = [], 0


def store_variable(run: BasicRun, name: str, value: Datum) -> None:
    """Assign a local variable (created on first assignment; a DIM'd one keeps its type)."""
    kind = run.types.get(name)
    run.variables[name] = value if kind is None else typed(value, kind[0], name, kind[1])
