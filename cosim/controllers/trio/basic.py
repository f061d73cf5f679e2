"""An interpreter for the Trio BASIC subset that TN20-81 uses, built on lark.

Programs are parsed with the LALR grammar of :mod:`.grammar`, checked before they run, and run as
a SimPy process through :class:`~cosim.controllers.trio.process.TrioProcess`.

Supported: assignments to axis parameters (``UNITS=16``, ``UNITS AXIS(2)=16``), ``WDOG``, named
variables and ``VR(n)``; ``BASE``, ``TABLE``, ``PWM_CONTROL``, ``DEFPOS``, ``MOVE``, ``MOVEABS``,
``WA`` (with an optional ``AXIS(n)`` modifier); ``WAIT IDLE``, ``WAIT UNTIL``; ``REPEAT/UNTIL``,
``WHILE/WEND``, ``FOR/TO/STEP/NEXT``, ``IF/THEN/ELSE/ENDIF``; expressions with ``+ - * /``,
comparisons, ``AND OR NOT``, ``TABLE(n)``, ``VR(n)``, ``ABS``, ``INT``, parameters, ``IDLE``,
and the constants ``ON OFF TRUE FALSE``; ``'`` comments.

Timing: statements take no simulated time; a program only waits at ``WAIT``, ``WA``, a move while
the move buffer is full, and a ``PWM_CONTROL(3)`` while the FIFO is full. ``WAIT UNTIL`` checks its
condition at once and then at every servo tick. A loop that repeats :data:`MAX_LOOPS_PER_INSTANT`
times at one instant without waiting is an error (it would freeze simulated time).

Errors name the program and line: a syntax error, an unknown keyword (a command, function or
name that is not in the subset, or a variable that is assigned but never read, which is how a
misspelt parameter such as ``UNIT=16`` shows up) before the program starts; a bad value
(``PWM_MARK=70000``) when the line runs.
"""

from __future__ import annotations

from collections.abc import Callable, Generator, Iterator
from dataclasses import dataclass, field
from fractions import Fraction
from math import trunc
from pathlib import Path
from typing import Any

import simpy
from lark import Lark, Token, Tree
from lark.exceptions import UnexpectedCharacters, UnexpectedInput, UnexpectedToken
from simpy.events import Event

from cosim import validate
from cosim.controllers.trio.controller import TrioController
from cosim.controllers.trio.grammar import GRAMMAR
from cosim.controllers.trio.params import (
    AXIS_PARAMS,
    COMMANDS,
    CONSTANTS,
    FALSE,
    READ_ONLY_AXIS_PARAMS,
    SYSTEM_PARAMS,
    TRUE,
    unknown_name,
)
from cosim.controllers.trio.process import TrioProcess
from cosim.errors import ConfigurationError, TimingViolation
from cosim.timebase import Priority

EXAMPLES = Path(__file__).resolve().parent / "examples"
#: Commands usable as statements, and functions usable in expressions.
STATEMENTS = frozenset({"BASE", "TABLE", "PWM_CONTROL", "DEFPOS", "MOVE", "MOVEABS", "WA"})
FUNCTIONS = frozenset({"TABLE", "VR", "ABS", "INT"})
READABLE = frozenset(AXIS_PARAMS) | frozenset(READ_ONLY_AXIS_PARAMS) | frozenset(SYSTEM_PARAMS)
#: Loop repetitions allowed at one instant without waiting.
MAX_LOOPS_PER_INSTANT = 100_000

_PARSER = Lark(GRAMMAR, parser="lalr", propagate_positions=True, maybe_placeholders=True)


def _line(node: Tree | Token | None, default: int = 0) -> int:
    if isinstance(node, Token):
        return node.line or default
    if isinstance(node, Tree) and not node.meta.empty:
        return node.meta.line
    return default


def _statements(tree: Tree) -> list[Tree]:
    return [c for c in tree.children if isinstance(c, Tree)]


@dataclass(frozen=True)
class BasicProgram:
    """A parsed and checked Trio BASIC program.

    Parameters
    ----------
    name : str
        Shown in error messages (``tn20_81.bas line 12: ...``).
    text : str
        The program text.
    """

    name: str
    text: str
    tree: Tree = field(repr=False, compare=False)

    @classmethod
    def parse(cls, text: str, *, name: str = "program.bas") -> BasicProgram:
        """Parse and check ``text``.

        Raises
        ------
        ConfigurationError
            A syntax error or an unknown keyword, with the line number.
        """
        try:
            tree = _PARSER.parse(text if text.endswith("\n") else text + "\n")
        except UnexpectedInput as exc:
            raise ConfigurationError(_syntax_message(exc, text, name)) from None
        _Checker(name).check(tree)
        return cls(name, text, tree)

    @classmethod
    def load(cls, path: str | Path) -> BasicProgram:
        """Parse a program file."""
        path = Path(path)
        return cls.parse(path.read_text(), name=path.name)

    def start(self, controller: TrioController, *, base: tuple[int, ...] = (0,), at: int | None = None) -> BasicRun:
        """Run the program on ``controller`` from tick ``at`` (default: now), as a SimPy process."""
        run = BasicRun(self, controller, base=base)
        run.process_handle = controller.sim.process(run.main(controller.sim.now if at is None else at))
        return run


def example(name: str = "tn20_81") -> BasicProgram:
    """A program bundled in ``cosim/controllers/trio/examples`` (``tn20_81``: the note's example)."""
    path = EXAMPLES / f"{name}.bas"
    if not path.exists():
        known = ", ".join(sorted(p.stem for p in EXAMPLES.glob("*.bas")))
        raise ConfigurationError.out_of_range("example", name, known)
    return BasicProgram.load(path)


def _syntax_message(exc: UnexpectedInput, text: str, name: str) -> str:
    line, column = exc.line, exc.column
    if isinstance(exc, UnexpectedToken):
        found = "end of line" if exc.token.type == "_NL" else repr(str(exc.token))
    elif isinstance(exc, UnexpectedCharacters):
        found = repr(text.splitlines()[line - 1][column - 1]) if line >= 1 else "?"
    else:
        found = "end of program"
    source = text.splitlines()[line - 1] if 1 <= line <= len(text.splitlines()) else ""
    return f"{name} line {line}: syntax error at column {column}, unexpected {found}\n    {source.rstrip()}"


class _Checker:
    """Static checks before a program runs: every keyword known, every variable read and written."""

    def __init__(self, name: str) -> None:
        self.name = name
        self.assigned: dict[str, int] = {}
        self.read: dict[str, int] = {}

    def fail(self, line: int, message: str) -> ConfigurationError:
        return ConfigurationError(f"{self.name} line {line}: {message}")

    def check(self, tree: Tree) -> None:
        self.statements(_statements(tree))
        for var, line in self.read.items():
            if var not in self.assigned:
                raise self.fail(line, unknown_name(var) + " (not a keyword, nor a variable the program assigns)")
        for var, line in self.assigned.items():
            if var not in self.read:
                raise self.fail(line, unknown_name(var) + " (assigned but never read: a misspelt keyword?)")

    def statements(self, nodes: list[Tree]) -> None:
        for node in nodes:
            self.statement(node)

    def statement(self, node: Tree) -> None:
        line = _line(node)
        kind = node.data
        kids = node.children
        if kind == "assign":
            self.assignment(str(kids[0]).upper(), kids[1], line)
            self.expr(kids[2])
        elif kind == "index_assign":
            name = str(kids[0]).upper()
            if name != "VR" or len(kids) != 3:
                raise self.fail(line, f"cannot assign to {kids[0]}(...); write VR(n) = value or TABLE(n, value)")
            self.expr(kids[1])
            self.expr(kids[2])
        elif kind == "call":
            self.command(str(kids[0]).upper(), kids[1:-1], kids[-1], line)
        elif kind == "bare":
            self.bare(str(kids[0]).upper(), line)
        elif kind in ("wait_idle", "wait_until", "repeat", "while_loop", "for_loop", "if_block", "if_line"):
            self.compound(node)

    def compound(self, node: Tree) -> None:
        kids = node.children
        if node.data == "for_loop":
            var = str(kids[0]).upper()
            self.assignment(var, None, _line(node))
            self.read.setdefault(var, _line(node))
        for kid in kids:
            if isinstance(kid, Tree) and kid.data == "body":
                self.statements(_statements(kid))
            elif isinstance(kid, Tree) and kid.data in ("assign", "index_assign", "call", "bare", "wait_idle",
                                                        "wait_until"):
                self.statement(kid)
            elif isinstance(kid, Tree | Token) and not (isinstance(kid, Token) and kid.type == "NAME"):
                self.expr(kid)

    def assignment(self, name: str, axis_mod: Tree | None, line: int) -> None:
        if name in AXIS_PARAMS or name == "WDOG":
            if axis_mod is not None and name == "WDOG":
                raise self.fail(line, "WDOG is not an axis parameter; write WDOG = ON without AXIS()")
        elif name in READ_ONLY_AXIS_PARAMS or name in SYSTEM_PARAMS:
            raise self.fail(line, f"{name} is read-only" + (" (use DEFPOS)" if name in ("DPOS", "MPOS") else ""))
        elif name in COMMANDS or name in CONSTANTS:
            raise self.fail(line, f"cannot assign to {name}")
        elif axis_mod is not None:
            raise self.fail(line, unknown_name(name) + " (AXIS() only modifies axis parameters)")
        else:
            self.assigned.setdefault(name, line)
        if axis_mod is not None:
            self.expr(axis_mod)

    def command(self, name: str, args: list[Any], axis_mod: Tree | None, line: int) -> None:
        if name not in STATEMENTS:
            if name in FUNCTIONS:
                raise self.fail(line, f"{name}(...) is a function, not a command; use it in an expression")
            raise self.fail(line, unknown_name(name))
        if name == "TABLE" and len(args) < 2:
            raise self.fail(line, "TABLE(n) reads a location; write TABLE(start, value, ...) to store values")
        if name == "BASE" and axis_mod is not None:
            raise self.fail(line, "BASE takes no AXIS() modifier")
        for arg in args:
            self.expr(arg)
        if axis_mod is not None:
            self.expr(axis_mod)

    def bare(self, name: str, line: int) -> None:
        if name in READABLE:
            raise self.fail(line, f"{name} is a parameter; write {name} = value")
        if name in COMMANDS:
            raise self.fail(line, f"{name} needs its arguments: {COMMANDS[name]}")
        raise self.fail(line, unknown_name(name))

    def expr(self, node: Tree | Token | None) -> None:
        if not isinstance(node, Tree):
            return
        line = _line(node)
        if node.data == "ref":
            name = str(node.children[0]).upper()
            if name not in READABLE and name not in CONSTANTS:
                if node.children[1] is not None:
                    raise self.fail(line, unknown_name(name) + " (AXIS() only modifies axis parameters)")
                self.read.setdefault(name, line)
        elif node.data == "func":
            name = str(node.children[0]).upper()
            if name not in FUNCTIONS:
                if name in STATEMENTS:
                    raise self.fail(line, f"{name}(...) is a command, not a function")
                raise self.fail(line, unknown_name(name))
        for kid in node.children:
            if isinstance(kid, Tree):
                self.expr(kid)


class BasicRun:
    """One running program: its variables and the SimPy process that executes it.

    Parameters
    ----------
    program : BasicProgram
    controller : TrioController
    base : tuple of int
        BASE group the program starts with.
    """

    def __init__(self, program: BasicProgram, controller: TrioController, *, base: tuple[int, ...] = (0,)) -> None:
        self.program = program
        self.controller = controller
        self.sim = controller.sim
        self.process = TrioProcess(controller, base)
        self.variables: dict[str, Fraction] = {}
        self.line = 0
        self.finished = False
        self.stopped = False
        self.process_handle: simpy.Process | None = None
        self._spin_t = -1
        self._spins = 0

    @property
    def where(self) -> str:
        return f"{self.program.name} line {self.line}"

    def main(self, at: int) -> Generator[Event, Any, None]:
        """The program as a SimPy process, from tick ``at`` (priority HOST)."""
        try:
            yield self.sim.at(at, Priority.HOST)
            yield from self._block(_statements(self.program.tree))
        except simpy.Interrupt:
            self.stopped = True
        except (ConfigurationError, TimingViolation) as exc:
            raise type(exc)(f"{self.where}: {exc}") from exc
        self.finished = True

    def stop(self) -> None:
        """Stop the program where it waits (Trio ``STOP``); moves it has issued still run to their end."""
        if self.process_handle is not None and self.process_handle.is_alive and not self.finished:
            self.process_handle.interrupt("STOP")

    # -- statements ---------------------------------------------------------------------------
    def _block(self, nodes: list[Tree]) -> Generator[Event, Any, None]:
        for node in nodes:
            yield from self._statement(node)

    def _statement(self, node: Tree) -> Generator[Event, Any, None]:
        self.line = _line(node, self.line)
        kids = node.children
        kind = node.data
        if kind == "assign":
            name = str(kids[0]).upper()
            value = self._eval(kids[2])
            if name in AXIS_PARAMS or name == "WDOG":
                self.process.set(name, value, axis=self._axis(kids[1]))
            else:
                self.variables[name] = value
        elif kind == "index_assign":
            index = validate.integer(self._eval(kids[1]), "VR index", whole=True)
            self.controller.vr_memory[index] = self._eval(kids[2])
        elif kind == "call":
            yield from self._command(str(kids[0]).upper(), [self._eval(a) for a in kids[1:-1]], kids[-1])
        elif kind == "wait_idle":
            yield from self._wait(self.process.wait_idle(axis=self._axis(kids[0])))
        elif kind == "wait_until":
            yield from self.process.wait_until(lambda: self._truth(kids[0]))
        elif kind == "repeat":
            yield from self._repeat(node)
        elif kind == "while_loop":
            while self._truth(kids[0]):
                yield from self._block(_statements(kids[1]))
                self._spin(node)
        elif kind == "for_loop":
            yield from self._for(node)
        elif kind == "if_block":
            cond, then_body, else_body = kids
            chosen = then_body if self._truth(cond) else else_body
            if chosen is not None:
                yield from self._block(_statements(chosen))
        elif kind == "if_line" and self._truth(kids[0]):
            yield from self._statement(kids[1])

    def _repeat(self, node: Tree) -> Generator[Event, Any, None]:
        body, cond = node.children
        while True:
            yield from self._block(_statements(body))
            self.line = _line(cond, self.line)
            if self._truth(cond):
                return
            self._spin(node)

    def _for(self, node: Tree) -> Generator[Event, Any, None]:
        var_token, start, stop, step, body = node.children[:5]
        var = str(var_token).upper()
        value, last = self._eval(start), self._eval(stop)
        increment = Fraction(1) if step is None else self._eval(step)
        if increment == 0:
            raise ConfigurationError.out_of_range("FOR STEP", 0, "not 0")
        while (increment > 0 and value <= last) or (increment < 0 and value >= last):
            self.variables[var] = value
            yield from self._block(_statements(body))
            value = self.variables[var] + increment
            self._spin(node)
        self.variables[var] = value

    def _command(self, name: str, args: list[Fraction], axis_mod: Tree | None) -> Generator[Event, Any, None]:
        p, axis = self.process, self._axis(axis_mod)
        if name == "BASE":
            p.base(*args)
        elif name == "TABLE":
            p.table(*args)
        elif name == "DEFPOS":
            p.defpos(*args, axis=axis)
        elif name == "PWM_CONTROL":
            if not args:
                raise ConfigurationError("PWM_CONTROL needs a mode: PWM_CONTROL(mode, ...)")
            yield from self._wait(p.pwm_control(args[0], *args[1:], axis=axis))
        elif name == "MOVE":
            yield from self._wait(p.move(*args, axis=axis))
        elif name == "MOVEABS":
            yield from self._wait(p.moveabs(*args, axis=axis))
        elif name == "WA":
            if len(args) != 1:
                raise ConfigurationError.out_of_range("number of WA arguments", len(args), "1 (time [ms])")
            yield from self._wait(p.wa(args[0]))

    def _wait(self, event: Event) -> Iterator[Event]:
        yield event  # resumes at once (same instant) if the event has already succeeded

    def _spin(self, node: Tree) -> None:
        now = self.sim.now
        if now != self._spin_t:
            self._spin_t, self._spins = now, 0
        self._spins += 1
        if self._spins >= MAX_LOOPS_PER_INSTANT:
            raise TimingViolation(
                f"the loop starting at line {_line(node)} ran {MAX_LOOPS_PER_INSTANT} times at t = {now} ns without "
                "waiting; a loop that never waits freezes simulated time (add WA(...) or WAIT)")

    # -- expressions --------------------------------------------------------------------------
    def _axis(self, axis_mod: Tree | None) -> int | None:
        if axis_mod is None:
            return None
        return self.controller.axis(self._eval(axis_mod.children[0])).number

    def _truth(self, node: Tree | Token) -> bool:
        return self._eval(node) != 0

    def _eval(self, node: Tree | Token) -> Fraction:
        if isinstance(node, Token):  # pragma: no cover - every token is wrapped in a rule
            raise ConfigurationError(f"cannot evaluate {node!r}")
        kids = node.children
        handler = _EVALUATORS.get(node.data)
        if handler is None:  # pragma: no cover - the grammar has no other expression rules
            raise ConfigurationError(f"cannot evaluate {node.data}")
        return handler(self, kids)

    def _ref(self, kids: list[Any]) -> Fraction:
        name = str(kids[0]).upper()
        if name in CONSTANTS:
            return Fraction(CONSTANTS[name])
        if name in READABLE:
            return self.process.get(name, axis=self._axis(kids[1]))
        if name not in self.variables:
            raise ConfigurationError(f"variable {name} is read before the program assigns it")
        return self.variables[name]

    def _func(self, kids: list[Any]) -> Fraction:
        name = str(kids[0]).upper()
        args = [self._eval(a) for a in kids[1:-1]]
        if len(args) != 1:
            raise ConfigurationError.out_of_range(f"number of {name} arguments", len(args), "1")
        if name == "TABLE":
            return self.process.table_value(args[0])
        if name == "VR":
            return self.controller.vr_memory.get(validate.integer(args[0], "VR index", whole=True), Fraction(0))
        if name == "ABS":
            return abs(args[0])
        return Fraction(trunc(args[0]))

    def _arith(self, kids: list[Any]) -> Fraction:
        a, op, b = self._eval(kids[0]), str(kids[1]), self._eval(kids[2])
        if op == "+":
            return a + b
        if op == "-":
            return a - b
        if op == "*":
            return a * b
        if b == 0:
            raise ConfigurationError("division by zero")
        return a / b

    def _compare(self, kids: list[Any]) -> Fraction:
        a, op, b = self._eval(kids[0]), str(kids[1]), self._eval(kids[2])
        result = {"<": a < b, ">": a > b, "<=": a <= b, ">=": a >= b, "<>": a != b}[op]
        return Fraction(TRUE if result else FALSE)


def _bool(value: bool) -> Fraction:
    return Fraction(TRUE if value else FALSE)


_EVALUATORS: dict[str, Callable[[BasicRun, list[Any]], Fraction]] = {
    "number": lambda run, kids: validate.exact(str(kids[0]), "number"),
    "hexnumber": lambda run, kids: Fraction(int(str(kids[0])[1:], 16)),
    "ref": BasicRun._ref,
    "idle_ref": lambda run, kids: run.process.get("IDLE", axis=run._axis(kids[0])),
    "func": BasicRun._func,
    "arith": BasicRun._arith,
    "compare": BasicRun._compare,
    "equal": lambda run, kids: _bool(run._eval(kids[0]) == run._eval(kids[1])),
    "neg": lambda run, kids: -run._eval(kids[0]),
    "not_op": lambda run, kids: _bool(run._eval(kids[0]) == 0),
    "and_op": lambda run, kids: _bool(run._eval(kids[0]) != 0 and run._eval(kids[1]) != 0),
    "or_op": lambda run, kids: _bool(run._eval(kids[0]) != 0 or run._eval(kids[1]) != 0),
}
