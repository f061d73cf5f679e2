"""Trio BASIC programs: parsed, checked and compiled before they run; run on processes of the controller.

The language in layers that import one way (text -> syntax tree -> compiled program -> runtime):
:mod:`.grammar` and :mod:`.syntax` parse, :mod:`.compiler` (with :mod:`.expressions`,
:mod:`.printing`) checks and compiles into operations (:mod:`.operations`, :mod:`.commands`,
:mod:`.functions`), :mod:`.runtime` runs them. This module ties them together:
:class:`BasicProgram` (parse, load, start) and :class:`ProgramControl` (``RUN``, ``STOP``, ``HALT``
and the process parameters ``PROC_STATUS``, ``TICKS PROC(n)``...).

Several programs of one machine share their ``CONSTANT`` and ``GLOBAL`` names
(:meth:`BasicProgram.parse_all`, :meth:`BasicProgram.load_all`), as on the controller.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from cosim import validate
from cosim.controllers.trio.compiler import Compiler, declarations_of
from cosim.controllers.trio.controller import TrioController
from cosim.controllers.trio.expressions import Declarations
from cosim.controllers.trio.params import PROCESSES
from cosim.controllers.trio.runtime import MAX_STATEMENTS_PER_SERVO_PERIOD, BasicError, BasicRun, Compiled
from cosim.controllers.trio.syntax import parse, parse_cached
from cosim.controllers.trio.values import Datum, Value, integer_part
from cosim.errors import ConfigurationError

EXAMPLES = Path(__file__).resolve().parent / "examples"
__all__ = ["MAX_STATEMENTS_PER_SERVO_PERIOD", "BasicProgram", "ProgramControl", "example"]


def _read(path: Path) -> str:
    data = path.read_bytes()
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return data.decode("latin-1")


def _includer(folder: Path | None, extra: dict[str, str]) -> Any:
    """``INCLUDE "name"``: a program of the machine, or ``name.bas`` / ``name`` beside the file."""
    def include(name: str) -> tuple[str, str]:
        key = Path(name).stem.upper()
        if key in extra:
            return f"{key.lower()}.bas", extra[key]
        if folder is not None:
            for candidate in (folder / name, folder / f"{name}.bas", folder / f"{name}.BAS"):
                if candidate.is_file():
                    return candidate.name, _read(candidate)
            matches = [p for p in folder.glob("*.bas") if p.stem.upper() == key]
            if matches:
                return matches[0].name, _read(matches[0])
        raise ConfigurationError(f"no program {name} (looked for {name}.bas beside the program)")
    return include


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
    def parse(cls, text: str, *, name: str = "program.bas", folder: str | Path | None = None,
              declarations: Declarations | None = None) -> BasicProgram:
        """Parse, check and compile ``text``; any line end (LF, CRLF, CR, FF, VT, NEL, ...) is accepted.

        Parameters
        ----------
        folder : path, optional
            Where ``INCLUDE "name"`` looks for ``name.bas``.
        declarations : Declarations, optional
            ``CONSTANT`` and ``GLOBAL`` names shared with other programs.

        Raises
        ------
        ConfigurationError
            A syntax error, an unknown keyword, a wrong argument count, ... with the line and column.
        """
        tree = parse(text, name)
        include = _includer(None if folder is None else Path(folder), {})
        shared = declarations if declarations is not None else Declarations()
        return cls(name, text, Compiler(name, declarations=shared, include=include).compile(tree))

    @classmethod
    def parse_all(cls, sources: Sequence[tuple[str, str]], *, folder: str | Path | None = None,
                  cached: bool = False) -> list[BasicProgram]:
        """Parse several ``(name, text)`` programs of one machine: each knows the others' CONSTANT and GLOBAL
        names, and may INCLUDE them by name. ``cached``: keep and reuse their syntax trees in the per-user
        cache (:func:`.syntax.parse_cached`; a machine's program files)."""
        trees = [(name, text, (parse_cached if cached else parse)(text, name)) for name, text in sources]
        shared = Declarations()
        for name, _text, tree in trees:
            declarations_of(tree, shared, name)
        by_key = {Path(name).stem.upper(): text for name, text in sources}
        include = _includer(None if folder is None else Path(folder), by_key)
        return [cls(name, text, Compiler(name, declarations=shared, include=include).compile(tree))
                for name, text, tree in trees]

    @classmethod
    def load(cls, path: str | Path) -> BasicProgram:
        """Parse a program file (UTF-8, or Latin-1 where it is not UTF-8)."""
        path = Path(path)
        return cls.parse(_read(path), name=path.name, folder=path.parent)

    @classmethod
    def load_all(cls, paths: Sequence[str | Path]) -> list[BasicProgram]:
        """Parse the program files of one machine together (see :meth:`parse_all`)."""
        files = [Path(p) for p in paths]
        folder = files[0].parent if files else None
        return cls.parse_all([(p.name, _read(p)) for p in files], folder=folder, cached=True)

    @property
    def key(self) -> str:
        """The name ``RUN "NAME"`` finds the program by: the file name without extension, upper case."""
        return Path(self.name).stem.upper()

    def install(self, controller: TrioController) -> None:
        """Make the program known to ``controller``, so a program can start it with ``RUN "NAME"``."""
        controller.programs[self.key] = self

    def start(self, controller: TrioController, *, process: int | None = None, base: tuple[int, ...] = (0,),
              at: int | None = None, job: bool = False) -> BasicRun:
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
        job : bool
            The process is a part of the controller's job (``trio.job``): it begins now and finishes
            when the process stops.

        Raises
        ------
        ConfigurationError
            A process number outside 1..5 or already running a program, a bad BASE.
        """
        number = _process_number(controller, process)
        self.install(controller)
        run = BasicRun(self.name, self.compiled, controller, base=base, number=number, program=self)
        run.program_control = ProgramControl(controller)
        run.max_statements = MAX_STATEMENTS_PER_SERVO_PERIOD  # read here, so a test may lower it
        for channel in self.compiled.inputs:  # so a machine can drive them from the start; a bad channel is an
            if 0 <= channel < controller.io.channels:  # error at its line when the program gets there
                controller.io.input(channel)
        for channel in self.compiled.outputs:
            if controller.io.first_output <= channel < controller.io.channels:
                controller.io.output(channel)
        controller.processes[number] = run
        if job:
            run.job_part = f"process {number} ({self.name})"
            controller.job.begin(run.job_part)
        run.process_handle = controller.sim.process(run.main(controller.sim.now if at is None else at))
        return run


def _process_number(controller: TrioController, process: object | None) -> int:
    allowed = f"1..{PROCESSES} (the user processes of a Euro 205)"
    if process is None:
        free = [n for n in range(1, PROCESSES + 1) if n not in controller.processes]
        if not free:
            raise ConfigurationError.out_of_range("number of running programs", PROCESSES + 1, f"1..{PROCESSES}")
        return free[0]
    number = validate.integer(process, "process", low=1, high=PROCESSES, allowed=allowed, whole=True)
    if number in controller.processes:
        raise ConfigurationError(f"process {number} already runs {controller.processes[number].name}")
    return number


def example(name: str = "tn20_81") -> BasicProgram:
    """A program bundled in ``cosim/controllers/trio/examples`` (``tn20_81``: the note's example)."""
    path = EXAMPLES / f"{name}.bas"
    if not path.exists():
        known = ", ".join(sorted(p.stem for p in EXAMPLES.glob("*.bas")))
        raise ConfigurationError.out_of_range("example", name, known)
    return BasicProgram.load(path)


class ProgramControl:
    """``RUN``, ``STOP``, ``HALT`` and the process parameters, for the programs of one controller."""

    def __init__(self, controller: TrioController) -> None:
        self.controller = controller

    def _other(self, run: BasicRun, process: Value | None) -> BasicRun | None:
        if process is None:
            return run
        number = integer_part(process)
        if not 0 <= number <= PROCESSES:
            raise BasicError(f"PROC = {number} is not allowed (allowed: 0..{PROCESSES})", 1)
        return self.controller.processes.get(number)

    def process_param(self, run: BasicRun, name: str, process: Value | None) -> Datum:
        """``NAME`` or ``NAME PROC(n)``: a process parameter of this or another process."""
        other = self._other(run, process)
        if name == "PROC_STATUS":
            return 0 if other is None or other.finished else 1
        if other is None:
            return 0
        if name == "TICKS":
            return other.process.ticks
        if name == "PROCNUMBER":
            return other.number
        if name == "ERROR_LINE":
            return other.error_line
        if name == "RUN_ERROR":
            return other.run_error
        if name == "INDEVICE":
            return other.indevice
        if name == "OUTDEVICE":
            return other.outdevice
        return -1 if other.waiting_move else 0  # PMOVE

    def set_process_param(self, run: BasicRun, name: str, value: Datum, process: Value | None) -> None:
        other = self._other(run, process)
        if other is None:
            raise BasicError(f"{name} PROC({integer_part(process or 0)}): no program runs on that process", 7)
        if isinstance(value, str):
            raise BasicError(f"{name} = {value!r}: a number is needed", 5)
        if name == "TICKS":
            other.process.ticks = value
        else:
            channel = validate.integer(value, name, low=0, high=255, whole=True)
            setattr(other, name.lower(), channel)

    def run_program(self, run: BasicRun, name: str, process: Value | None) -> None:
        """``RUN "NAME"[, process]``: start another program the controller knows (a job part if ``run`` is)."""
        controller = self.controller
        program = controller.programs.get(name.upper())
        if program is None:
            known = ", ".join(sorted(controller.programs)) or "none"
            raise BasicError(f"RUN program = {name!r} is not allowed (allowed: a program the machine loads: {known})",
                             7)
        if any(other.program is program for other in controller.processes.values()):
            raise BasicError(f"RUN \"{name}\": the program is already running", 7)
        try:
            program.start(controller, process=process, job=run.job_part is not None)
        except BasicError:
            raise
        except ConfigurationError as exc:
            raise BasicError(str(exc), 7) from None

    def stop_program(self, run: BasicRun, name: str, process: Value | None) -> None:
        """``STOP "NAME"[, process]``: stop a running program (a program not running: nothing happens)."""
        for other in list(self.controller.processes.values()):
            if other.program is not None and other.program.key == name.upper() and (
                    process is None or other.number == integer_part(process)):
                if other is run:
                    self.stop_self(run)
                else:
                    other.stop()

    def stop_self(self, run: BasicRun) -> None:
        """``STOP`` without a name: the program ends here."""
        run.stop_requested = True

    def halt(self, run: BasicRun) -> None:
        """``HALT``: stop every program (this one at the end of the statement)."""
        for other in list(self.controller.processes.values()):
            if other is run:
                self.stop_self(run)
            else:
                other.stop()
