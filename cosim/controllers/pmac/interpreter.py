"""Running compiled PMAC programs: motion programs calculated ahead of their moves, PLC scans.

Both kinds run their :class:`~cosim.controllers.pmac.program.Code` with a program counter and a
return stack (GOSUB, CALL: at most :data:`MAX_CALL_DEPTH` deep). Statements take no simulated time.

Motion programs (:class:`MotionProgram`, a coordinate system's feeder)
----------------------------------------------------------------------
A motion program is *calculated* in the servo cycle of its coordinate system, before and after
the moves advance: its statements run until the coordinate system holds :data:`LOOKAHEAD` moves
that take time (the one executing and the next), so the statements between move N and move N+1
run when move N starts -- one move early, as on the controller. Further:

* ``DWELL`` stops the calculation until the dwell has ended (then, in that servo cycle, the
  program goes on): statements after a ``DWELL`` run when every move before it is done. This is
  why the manual's triggered-move recipe starts with ``DWELL 0``. ``DELAY`` does not stop it.
* A jump back (``ENDWHILE``, a ``GOTO`` to an earlier label) that has queued no move since the
  calculation began ends the calculation for this servo cycle: a loop without moves runs one
  pass per servo cycle (the real-time interrupt, modelled at every servo cycle, I8 = 0).
* Modal state (LINEAR/RAPID, ABS/INC, F or TM, TA, TS) belongs to the coordinate system and
  lasts between runs; it starts from Ix87 (TA), Ix88 (TS) and Ix89 (F).

PLC programs (:class:`PlcProgram`)
----------------------------------
One scan runs the program from where it stopped to its end (or to RETURN), or to a jump back
(``ENDWHILE``, ``GOTO`` backwards): the next scan starts there. When scans happen is the
controller's business (:mod:`cosim.controllers.pmac.runtime`).

A scan or a calculation that runs :data:`MAX_STEPS` statements without ending is an error naming
the program (it would freeze simulated time).
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING

from cosim.controllers.pmac import arith
from cosim.controllers.pmac.motion import Delay, Dwell, Item, Move, RapidAxis, RapidMove
from cosim.controllers.pmac.nodes import (
    Assign,
    Call,
    Cmd,
    Compare,
    Cond,
    Disable,
    Enable,
    Expr,
    Func,
    Mode,
    Neg,
    Num,
    Ops,
    Param,
    Pos,
    Return,
    Stmt,
    Var,
    located,
)
from cosim.controllers.pmac.nodes import Delay as DelayStmt
from cosim.controllers.pmac.nodes import Dwell as DwellStmt
from cosim.controllers.pmac.program import Code, Instr, Jump, JumpUnless, MoveStmt, Sub

if TYPE_CHECKING:
    from cosim.controllers.pmac.coord import CoordinateSystem
    from cosim.controllers.pmac.runtime import Programs, Session

#: Moves (taking time) a coordinate system holds before the program stops calculating.
LOOKAHEAD = 2
#: Deepest GOSUB/CALL nesting.
MAX_CALL_DEPTH = 32
#: Statements one PLC scan or one motion-program calculation may run.
MAX_STEPS = 100_000


@dataclass
class MotionModes:
    """Modal state of a coordinate system's programs."""

    ta_ms: Fraction
    ts_ms: Fraction
    feedrate: Fraction
    tm_ms: Fraction | None = None
    rapid: bool = False
    incremental: bool = False


def evaluate(expr: Expr, programs: Programs) -> Fraction:
    """The value of ``expr`` (reads variables through the controller's memory)."""
    if isinstance(expr, Num):
        return expr.value
    if isinstance(expr, Var):
        return programs.memory.read(expr)
    if isinstance(expr, Neg):
        return -evaluate(expr.arg, programs)
    if isinstance(expr, Func):
        return arith.function(expr.name, evaluate(expr.arg, programs))
    assert isinstance(expr, Ops)
    value = evaluate(expr.first, programs)
    for op, operand in expr.rest:
        value = arith.binary(op, value, evaluate(operand, programs), where=str(expr.pos))
    return value


_COMPARE = {
    "=": lambda a, b: a == b, "!=": lambda a, b: a != b, "<>": lambda a, b: a != b,
    ">": lambda a, b: a > b, "<": lambda a, b: a < b, "!>": lambda a, b: a <= b, "<=": lambda a, b: a <= b,
    "!<": lambda a, b: a >= b, ">=": lambda a, b: a >= b,
}


def test(cond: Cond, programs: Programs) -> bool:
    """Whether ``cond`` holds."""
    if isinstance(cond, Compare):
        return bool(_COMPARE[cond.op](evaluate(cond.left, programs), evaluate(cond.right, programs)))
    if cond.op == "AND":
        return all(test(c, programs) for c in cond.items)
    return any(test(c, programs) for c in cond.items)


class Context:
    """A running buffer: the code, the program counter, the return stack."""

    def __init__(self, code: Code, session: Session) -> None:
        self.code = code
        self.pc = 0
        self.stack: list[tuple[Code, int]] = []
        self.session = session

    def next(self) -> Instr | None:
        """The instruction at the program counter (None at the end of the code)."""
        return self.code.instrs[self.pc] if self.pc < len(self.code.instrs) else None

    def push(self, code: Code, pc: int, pos: Pos) -> None:
        if len(self.stack) >= MAX_CALL_DEPTH:
            raise pos.error(f"GOSUB/CALL nested deeper than {MAX_CALL_DEPTH} levels")
        self.stack.append((self.code, self.pc + 1))
        self.code, self.pc = code, pc

    def pop(self) -> bool:
        """Return from a GOSUB/CALL; False at the top level (the program ends)."""
        if not self.stack:
            return False
        self.code, self.pc = self.stack.pop()
        return True

    def flow(self, instr: Instr, programs: Programs) -> bool | None:
        """Run a flow instruction; returns whether it jumped back, or None if ``instr`` is not one."""
        if isinstance(instr, JumpUnless):
            self.pc = self.pc + 1 if test(instr.cond, programs) else instr.target
            return False
        if isinstance(instr, Jump):
            self.pc = instr.target
            return instr.back
        if isinstance(instr, Sub):
            self.push(self.code, instr.target, instr.pos)
            return False
        if isinstance(instr, Call):
            self.push(programs.program(instr.program, instr.pos), 0, instr.pos)
            return False
        return None


def execute(stmt: Stmt, programs: Programs, session: Session) -> None:
    """A statement both kinds of program run: assignments, ENABLE/DISABLE PLC, CMD."""
    with located(stmt.pos):
        if isinstance(stmt, Assign):
            programs.memory.write(stmt.var, evaluate(stmt.expr, programs), stmt.pos)
        elif isinstance(stmt, Enable | Disable):
            programs.enable(stmt.plcs, isinstance(stmt, Enable), stmt.pos)
        elif isinstance(stmt, Cmd):
            programs.execute(stmt.commands, session)
        else:
            raise stmt.pos.error(f"{stmt.name} cannot run here")


class PlcProgram:
    """A PLC program and where its next scan starts."""

    def __init__(self, code: Code, programs: Programs, session: Session) -> None:
        self.programs = programs
        self.context = Context(code, session)
        self.scans = 0

    def restart(self, code: Code) -> None:
        """Run ``code`` from its top (a reloaded buffer)."""
        self.context = Context(code, self.context.session)

    def scan(self) -> None:
        """One scan: to the end of the program, to RETURN, or to a jump back."""
        self.scans += 1
        ctx = self.context
        for _step in range(MAX_STEPS):
            instr = ctx.next()
            if instr is None or isinstance(instr, Return):
                if not ctx.pop():
                    ctx.pc = 0
                    return
                continue
            back = ctx.flow(instr, self.programs)
            if back is None:
                assert isinstance(instr, Stmt)
                execute(instr, self.programs, ctx.session)
                ctx.pc += 1
            elif back:
                return
        raise ctx.code.pos.error(f"{ctx.code.title} ran {MAX_STEPS} statements in one scan without ending it")


class MotionProgram:
    """A motion program running in a coordinate system (a :class:`~cosim.controllers.pmac.coord.Feeder`)."""

    def __init__(self, code: Code, programs: Programs, session: Session, modes: MotionModes) -> None:
        self.programs = programs
        self.context = Context(code, session)
        self.modes = modes
        self.finished = False
        self._dwell: int | None = None
        self._yielded_at: int | None = None

    def calculate(self, cs: CoordinateSystem, t: int) -> None:
        """Run statements until LOOKAHEAD moves are queued, a DWELL waits, a loop yields, or the end."""
        if self._yielded_at == t:  # a loop without moves made its pass of this servo cycle
            return
        ctx = self.context
        queued = False
        for _step in range(MAX_STEPS):
            if self.finished:
                return
            if self._dwell is not None:
                if not cs.segment_done(self._dwell):
                    return
                self._dwell = None
            if cs.queued_ahead() >= LOOKAHEAD:
                return
            instr = ctx.next()
            if instr is None or isinstance(instr, Return):
                if not ctx.pop():
                    self.finished = True
                continue
            back = ctx.flow(instr, self.programs)
            if back:
                if not queued:
                    self._yielded_at = t
                    return
            elif back is None:
                assert isinstance(instr, Stmt)
                queued = self.statement(instr, cs) or queued
                ctx.pc += 1
        raise ctx.code.pos.error(f"{ctx.code.title} ran {MAX_STEPS} statements in one servo cycle without a move")

    def statement(self, stmt: Stmt, cs: CoordinateSystem) -> bool:
        """Run one statement; True if it queued a move, DWELL or DELAY."""
        modes = self.modes
        with located(stmt.pos):
            if isinstance(stmt, Mode):
                if stmt.mode in ("LINEAR", "RAPID"):
                    modes.rapid = stmt.mode == "RAPID"
                else:
                    modes.incremental = stmt.mode == "INC"
                return False
            if isinstance(stmt, Param):
                value = evaluate(stmt.expr, self.programs)
                if stmt.param == "F":
                    modes.feedrate, modes.tm_ms = value, None
                elif stmt.param == "TM":
                    modes.tm_ms = value
                elif stmt.param == "TA":
                    modes.ta_ms = value
                else:
                    modes.ts_ms = value
                return False
            if isinstance(stmt, MoveStmt):
                cs.queue(self.move(stmt, cs))
                return True
            if isinstance(stmt, DwellStmt):
                self._dwell = cs.queue(Dwell(evaluate(stmt.expr, self.programs)))
                return True
            if isinstance(stmt, DelayStmt):
                cs.queue(Delay(evaluate(stmt.expr, self.programs)))
                return True
            execute(stmt, self.programs, self.context.session)
            return False

    def move(self, stmt: MoveStmt, cs: CoordinateSystem) -> Item:
        """The move an axis-word statement commands, from the modal state."""
        modes = self.modes
        targets: dict[str, Fraction] = {}
        for word in stmt.axes:
            self.programs.check_axis(cs.number, word.axis, word.pos)
            value = evaluate(word.expr, self.programs)
            targets[word.axis] = cs.program_end(word.axis) + value if modes.incremental else value
        if modes.rapid:
            axes = {}
            for axis, target in targets.items():
                speed, ta, ts = self.programs.rapid_parameters(cs.number, axis, stmt.pos)
                axes[axis] = RapidAxis(target, speed, ta, ts)
            return RapidMove(axes)
        if modes.tm_ms is not None:
            return Move(targets, tm_ms=modes.tm_ms, ta_ms=modes.ta_ms, ts_ms=modes.ts_ms)
        return Move(targets, feedrate=modes.feedrate, ta_ms=modes.ta_ms, ts_ms=modes.ts_ms)
