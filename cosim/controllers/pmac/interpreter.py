"""Running compiled PMAC programs: motion programs calculated ahead of their moves, PLC scans, kinematics.

Every buffer's :class:`~cosim.controllers.pmac.program.Code` is prepared once (:class:`Compiled`:
expressions and conditions as closures, :mod:`.evaluate`) and run with a program counter and a
return stack (GOSUB, CALL, G/M/T/D codes: at most :data:`MAX_CALL_DEPTH` deep). Statements take no
simulated time.

Motion programs (:class:`MotionProgram`, a coordinate system's feeder)
----------------------------------------------------------------------
A motion program is *calculated* in the servo cycle of its coordinate system, before and after
the moves advance: its statements run until the coordinate system holds :data:`LOOKAHEAD` moves
that take time (the one executing and the next), so the statements between move N and move N+1
run when move N starts -- one move early, as on the controller. Further:

* ``DWELL`` stops the calculation until the dwell has ended: statements after a ``DWELL`` run
  when every move before it is done (why the manual's triggered-move recipe starts with
  ``DWELL 0``). ``DELAY`` does not stop it.
* A jump back (``ENDWHILE``, a ``GOTO`` to an earlier label) that has queued no move since the
  calculation began ends the calculation for this servo cycle: a loop without moves runs one
  pass per servo cycle.
* Modal state (LINEAR/RAPID/CIRCLE1/CIRCLE2/PVT/SPLINE1, ABS/INC per axis, F or TM, TA, TS, the
  NORMAL of the circle plane) belongs to the coordinate system and lasts between runs; it starts
  from Isx87 (TA), Isx88 (TS) and Isx89 (F); F is in axis units per Isx90 ms.
* With Isx50 = 1 and motors defined ``#n->I``, every move's end point goes through the
  coordinate system's ``OPEN INVERSE`` program (axis positions in Q1..Q9 -- A, B, C, U, V, W, X, Y,
  Z -- in, motor positions in P1..P32 out, as the Turbo User Manual gives them), and those motors
  follow the move from their start to their end counts (no segmentation: Isx13 is not modelled).
  ``R`` and ``PMATCH`` run ``OPEN FORWARD`` (motor positions in P1..P32, axis positions out in
  Q1..Q9) to find where the axes are.

PLC programs (:class:`PlcProgram`)
----------------------------------
One scan runs the program from where it stopped to its end (or to RETURN), or to a jump back
(``ENDWHILE``, ``GOTO`` backwards): the next scan starts there. A scan reports whether it was
*quiet* -- it changed nothing and read nothing that changes by itself -- which lets the background
skip the scans that would repeat it (:mod:`.runtime`).

A scan or a calculation that runs :data:`MAX_STEPS` statements without ending is an error naming
the program (it would freeze simulated time).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Protocol

from cosim.controllers.pmac.bus import Value
from cosim.controllers.pmac.evaluate import Evaluator, condition, expression
from cosim.controllers.pmac.motion import CircleMove, Delay, Dwell, Item, Move, PvtMove, RapidAxis, RapidMove, Segmented
from cosim.controllers.pmac.mvars import Memory, check_number
from cosim.controllers.pmac.nodes import (
    Assign,
    Call,
    CodeCall,
    Display,
    Frax,
    Gosub,
    Goto,
    Home,
    IndVar,
    Mode,
    MoveStmt,
    Normal,
    Param,
    Pos,
    Pvt,
    Return,
    Send,
    Stmt,
    Var,
    located,
)
from cosim.controllers.pmac.nodes import Delay as DelayStmt
from cosim.controllers.pmac.nodes import Dwell as DwellStmt
from cosim.controllers.pmac.program import CODE_PROGRAMS, Code, Jump, JumpUnless, Sub
from cosim.errors import ConfigurationError

if TYPE_CHECKING:
    from cosim.controllers.pmac.coord import CoordinateSystem

#: Moves (taking time) a coordinate system holds before the program stops calculating.
LOOKAHEAD = 2
#: Deepest GOSUB/CALL nesting.
MAX_CALL_DEPTH = 32
#: Statements one PLC scan or one motion-program calculation may run.
MAX_STEPS = 100_000
#: Kinematic axes in Q1..Q9, in the Turbo PMAC's order.
KINEMATIC_AXES = ("A", "B", "C", "U", "V", "W", "X", "Y", "Z")


class Host(Protocol):
    """What a running program asks of the controller's program system (:class:`~.runtime.Programs`)."""

    memory: Memory

    def compiled(self, code: Code) -> Compiled:
        """``code`` prepared for running (once)."""
        ...

    def program(self, number: int, pos: Pos) -> Code:
        """Motion program ``number`` (an error naming ``pos`` if there is none)."""
        ...

    def statement(self, stmt: Stmt, context: Context) -> None:
        """Run a statement that is not flow, assignment or motion (CMD, ENABLE PLC, SEND, ...)."""
        ...

    def check_axis(self, cs_number: int, axis: str, pos: Pos) -> None:
        """A move on ``axis`` needs a motor assigned to it in the coordinate system."""
        ...

    def rapid_parameters(self, cs_number: int, axis: str, pos: Pos) -> tuple[Fraction, Fraction, Fraction]:
        """RAPID speed [units/ms], TA and TS [ms] of ``axis``."""
        ...

    def kinematics(self, cs_number: int, targets: dict[str, Fraction], pos: Pos) -> dict[str, Fraction]:
        """Counts of the coordinate system's ``#n->I`` motors at the axis positions ``targets`` (``#n`` keys)."""
        ...

    def not_modelled(self, name: str, value: object, where: str) -> None:
        """List a setting or command that is accepted and kept but does not act."""
        ...

    def ivar(self, number: int) -> Value:
        """I``number`` now."""
        ...

    def fault(self, reason: str) -> None:
        """A motion program stopped on an error: the job stops (state ERROR, the reason on the console)."""
        ...


@dataclass
class Session:
    """Modal addressing of a command source: the coordinate system (``&n``) and motor (``#n``)."""

    cs: int = 1
    motor: int = 1


# -- prepared code -----------------------------------------------------------------------------
class Compiled:
    """A buffer's code with its expressions and conditions compiled (one tuple per instruction).

    Operations: ``("test", cond, target)``, ``("jump", target, back)``, ``("sub", target, pos)``,
    ``("goto" | "gosub", expression, pos)``, ``("call", program, label, pos)``, ``("code", letter,
    expression, pos)``, ``("return",)``, ``("assign", kind, number, index, value, op, pos)``,
    ``("stmt", statement)``.
    """

    def __init__(self, code: Code) -> None:
        self.code = code
        self.ops: list[tuple[Any, ...]] = [_prepare(instr) for instr in code.instrs]


def _prepare(instr: object) -> tuple[Any, ...]:
    if isinstance(instr, JumpUnless):
        return ("test", condition(instr.cond), instr.target)
    if isinstance(instr, Jump):
        return ("jump", instr.target, instr.back)
    if isinstance(instr, Sub):
        return ("sub", instr.target, instr.pos)
    if isinstance(instr, Goto | Gosub):
        assert instr.target is not None  # constant jumps were resolved by the compiler
        return ("goto" if isinstance(instr, Goto) else "gosub", expression(instr.target), instr.pos)
    if isinstance(instr, Call):
        return ("call", instr.program, instr.label, instr.pos)
    if isinstance(instr, CodeCall):
        return ("code", instr.letter, expression(instr.value), instr.pos)
    if isinstance(instr, Return):
        return ("return",)
    if isinstance(instr, Assign) and instr.expr is not None:
        var = instr.var
        if isinstance(var, Var):
            return ("assign", var.kind, var.number, None, expression(instr.expr), instr.op, instr.pos)
        assert isinstance(var, IndVar)
        return ("assign", var.kind, None, expression(var.index), expression(instr.expr), instr.op, instr.pos)
    assert isinstance(instr, Stmt)
    return ("stmt", instr)


class Context:
    """A running buffer: the code, the program counter, the return stack (and the frame its expressions see)."""

    def __init__(self, compiled: Compiled, host: Host, *, cs: int = 1, session: Session | None = None,
                 source: str = "") -> None:
        self.compiled = compiled
        self.ops = compiled.ops
        self.pc = 0
        self.stack: list[tuple[Compiled, int]] = []
        self.host = host
        self.memory = host.memory
        self.cs = cs  # the coordinate system whose Q-variables the program uses
        self.session = session or Session(cs)
        self.source = source or f"{compiled.code.kind.lower()}{compiled.code.number}"
        self.effects = 0  # statements run that act outside the variables (CMD, SEND, ENABLE, ...)

    @property
    def code(self) -> Code:
        return self.compiled.code

    def state(self) -> tuple[object, int, int]:
        """Where the next scan starts (for the quiet-scan test)."""
        return self.compiled, self.pc, len(self.stack)

    def push(self, compiled: Compiled, pc: int, pos: Pos) -> None:
        if len(self.stack) >= MAX_CALL_DEPTH:
            raise pos.error(f"GOSUB/CALL nested deeper than {MAX_CALL_DEPTH} levels")
        self.stack.append((self.compiled, self.pc + 1))
        self.compiled, self.ops, self.pc = compiled, compiled.ops, pc

    def pop(self) -> bool:
        """Return from a GOSUB/CALL; False at the top level (the program ends)."""
        if not self.stack:
            return False
        self.compiled, self.pc = self.stack.pop()
        self.ops = self.compiled.ops
        return True

    def label(self, code: Code, number: int, pos: Pos, what: str) -> int:
        target = code.labels.get(number)
        if target is None:
            known = ", ".join(f"N{n}" for n in sorted(code.labels)) or "none"
            raise pos.error(f"{what} jumps into nothing: {code.title} has no label N{number} (its labels: {known})")
        return target

    def assign(self, op: tuple[Any, ...]) -> None:
        _tag, kind, number, index, value, how, pos = op
        if number is None:
            number = check_number(kind, index(self), pos)
        result = value(self)
        with located(pos):
            if kind == "M" and how != "=":
                self.memory.write_m(number, result, pos, how)
            else:
                self.memory.write(kind, number, result, self.cs, pos)

    def flow(self, op: tuple[Any, ...]) -> bool | None:
        """Run a flow operation; returns whether it jumped back, or None if ``op`` is not one."""
        tag = op[0]
        if tag == "test":
            self.pc = self.pc + 1 if op[1](self) else op[2]
            return False
        if tag == "jump":
            self.pc = op[1]
            return op[2]
        if tag == "sub":
            self.push(self.compiled, op[1], op[2])
            return False
        if tag in ("goto", "gosub"):
            value = op[1](self)
            pos = op[2]
            if value != int(value):
                raise pos.error(f"{tag.upper()} {value}: a label is a whole number")
            target = self.label(self.code, int(value), pos, f"{tag.upper()} {int(value)}")
            if tag == "gosub":
                self.push(self.compiled, target, pos)
                return False
            back = target <= self.pc
            self.pc = target
            return back
        if tag == "call":
            code = self.host.program(op[1], op[3])
            start = 0 if op[2] is None else self.label(code, op[2], op[3], f"CALL {op[1]}.{op[2]}")
            self.push(self.host.compiled(code), start, op[3])
            return False
        if tag == "code":
            value = op[2](self)
            pos = op[3]
            code = self.host.program(CODE_PROGRAMS[op[1]], pos)
            number = int(Fraction(value) * 1000)
            self.push(self.host.compiled(code), self.label(code, number, pos, f"{op[1]}{value}"), pos)
            return False
        return None


# -- PLC programs ------------------------------------------------------------------------------
class PlcProgram:
    """A PLC program and where its next scan starts."""

    def __init__(self, code: Code, host: Host) -> None:
        self.host = host
        self.context = Context(host.compiled(code), host, source=f"plc{code.number}")
        self.scans = 0

    def restart(self, code: Code) -> None:
        """Run ``code`` from its top (a reloaded buffer, or ``ENABLE PLC``)."""
        self.context = Context(self.host.compiled(code), self.host, source=f"plc{code.number}")

    def scan(self) -> bool:
        """One scan: to the end of the program, to RETURN, or to a jump back; returns whether it was quiet."""
        self.scans += 1
        ctx = self.context
        memory = ctx.memory
        before = ctx.state()
        changes, effects = memory.changes, ctx.effects
        memory.volatile = False
        for _step in range(MAX_STEPS):
            if ctx.pc >= len(ctx.ops):
                if not ctx.pop():
                    ctx.pc = 0
                    break
                continue
            op = ctx.ops[ctx.pc]
            tag = op[0]
            if tag == "assign":
                ctx.assign(op)
                ctx.pc += 1
                continue
            if tag == "return":
                if not ctx.pop():
                    ctx.pc = 0
                    break
                continue
            if tag == "stmt":
                self.host.statement(op[1], ctx)
                ctx.pc += 1
                continue
            if ctx.flow(op):
                break
        else:
            raise ctx.code.pos.error(f"{ctx.code.title} ran {MAX_STEPS} statements in one scan without ending it")
        return (memory.changes == changes and ctx.effects == effects and not memory.volatile
                and ctx.state() == before)


def run_to_end(code: Code, host: Host, *, cs: int) -> None:
    """Run a kinematic program (``OPEN FORWARD``/``OPEN INVERSE``) from its top to its end, at once."""
    ctx = Context(host.compiled(code), host, cs=cs)
    for _step in range(MAX_STEPS):
        if ctx.pc >= len(ctx.ops):
            if not ctx.pop():
                return
            continue
        op = ctx.ops[ctx.pc]
        tag = op[0]
        if tag == "assign":
            ctx.assign(op)
            ctx.pc += 1
        elif tag == "return":
            if not ctx.pop():
                return
        elif tag == "stmt":
            host.statement(op[1], ctx)
            ctx.pc += 1
        else:
            ctx.flow(op)
    raise code.pos.error(f"{code.title} ran {MAX_STEPS} statements without ending")


# -- motion programs ---------------------------------------------------------------------------
@dataclass
class MotionModes:
    """Modal state of a coordinate system's programs."""

    ta_ms: Fraction
    ts_ms: Fraction
    feedrate: Fraction
    tm_ms: Fraction | None = None
    move: str = "LINEAR"
    incremental: set[str] = field(default_factory=set)
    all_incremental: bool = False
    pvt_ms: Fraction = Fraction(0)
    normal: tuple[str, int] = ("K", -1)
    velocities: dict[str, Fraction] = field(default_factory=dict)

    @property
    def rapid(self) -> bool:
        return self.move == "RAPID"


_PLANES = {"K": ("X", "Y"), "I": ("Y", "Z"), "J": ("Z", "X")}


class MotionProgram:
    """A motion program running in a coordinate system (a :class:`~cosim.controllers.pmac.coord.Feeder`)."""

    def __init__(self, code: Code, host: Host, cs: int, modes: MotionModes, *, session: Session | None = None) -> None:
        self.host = host
        self.context = Context(host.compiled(code), host, cs=cs, session=session or Session(cs),
                               source=f"prog{code.number}")
        self.modes = modes
        self.finished = False
        self._dwell: int | None = None
        self._yielded_at: int | None = None
        self._spline: tuple[dict[str, Fraction], Stmt] | None = None  # a SPLINE1 point waiting for the next

    def calculate(self, cs: CoordinateSystem, t: int) -> None:
        """Run statements until LOOKAHEAD moves are queued, a DWELL waits, a loop yields, or the end.

        An error stops the program and the job (its reason on the console), then the run.
        """
        if self._yielded_at == t:  # a loop without moves made its pass of this servo cycle
            return
        try:
            self._calculate(cs, t)
        except ConfigurationError as exc:
            self.host.fault(str(exc))
            raise

    def _calculate(self, cs: CoordinateSystem, t: int) -> None:
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
            if ctx.pc >= len(ctx.ops):
                if not ctx.pop():
                    self._flush_spline(cs)
                    self.finished = True
                continue
            op = ctx.ops[ctx.pc]
            tag = op[0]
            if tag == "assign":
                ctx.assign(op)
                ctx.pc += 1
                continue
            if tag == "return":
                if not ctx.pop():
                    self._flush_spline(cs)
                    self.finished = True
                continue
            if tag == "stmt":
                queued = self.statement(op[1], cs) or queued
                ctx.pc += 1
                continue
            if ctx.flow(op) and not queued:
                self._yielded_at = t
                return
        raise ctx.code.pos.error(f"{ctx.code.title} ran {MAX_STEPS} statements in one servo cycle without a move")

    def statement(self, stmt: Stmt, cs: CoordinateSystem) -> bool:
        """Run one statement; True if it queued a move, DWELL or DELAY."""
        modes = self.modes
        with located(stmt.pos):
            if isinstance(stmt, Mode):
                self.mode(stmt)
                return False
            if isinstance(stmt, Param):
                value = Fraction(expression(stmt.expr)(self.context))
                if stmt.param == "F":
                    modes.feedrate, modes.tm_ms = value, None
                elif stmt.param == "TM":
                    modes.tm_ms = value
                elif stmt.param == "TA":
                    modes.ta_ms = value
                else:
                    modes.ts_ms = value
                return False
            if isinstance(stmt, Pvt):
                modes.move, modes.pvt_ms = "PVT", Fraction(expression(stmt.expr)(self.context))
                return False
            if isinstance(stmt, Normal):
                letter, component = max(stmt.vector,
                                        key=lambda item: abs(Fraction(expression(item[1])(self.context))))
                number = Fraction(expression(component)(self.context))
                modes.normal = (letter, 1 if number > 0 else -1)
                return False
            if isinstance(stmt, MoveStmt):
                return self.move(stmt, cs)
            if isinstance(stmt, DwellStmt):
                self._flush_spline(cs)
                self._dwell = cs.queue(Dwell(Fraction(expression(stmt.expr)(self.context))))
                return True
            if isinstance(stmt, DelayStmt):
                self._flush_spline(cs)
                cs.queue(Delay(Fraction(expression(stmt.expr)(self.context))))
                return True
            if isinstance(stmt, Frax | Home):
                self.host.not_modelled(stmt.name if isinstance(stmt, Frax) else stmt.keyword,
                                       ",".join(getattr(stmt, "axes", ())) or "-", str(stmt.pos))
                return False
            if isinstance(stmt, Send | Display):
                self.host.statement(stmt, self.context)
                return False
            self.host.statement(stmt, self.context)
            return False

    def mode(self, stmt: Mode) -> None:
        modes = self.modes
        if stmt.mode in ("ABS", "INC"):
            if stmt.axes:
                for axis in stmt.axes:
                    (modes.incremental.add if stmt.mode == "INC" else modes.incremental.discard)(axis)
            else:
                modes.all_incremental = stmt.mode == "INC"
                modes.incremental.clear()
            return
        modes.move = stmt.mode

    def targets(self, stmt: MoveStmt, cs: CoordinateSystem) -> dict[str, Fraction]:
        """Where each axis of the move goes [axis units] (incremental axes add to where they are going)."""
        modes = self.modes
        targets: dict[str, Fraction] = {}
        for word in stmt.axes:
            self.host.check_axis(cs.number, word.axis, word.pos)
            value = Fraction(expression(word.expr)(self.context))
            incremental = modes.all_incremental or word.axis in modes.incremental
            targets[word.axis] = cs.program_end(word.axis) + value if incremental else value
        return targets

    def move(self, stmt: MoveStmt, cs: CoordinateSystem) -> bool:
        modes = self.modes
        targets = self.targets(stmt, cs)
        axes = {a: cs.program_end(a) for a in cs.axes if not a.startswith("#")}
        followers = self.host.kinematics(cs.number, {**axes, **targets}, stmt.pos)
        segment_ms = Fraction(self.host.ivar(5000 + 100 * cs.number + 13)) if followers else Fraction(0)
        if segment_ms > 0:  # segmented (Isx13 > 0): the inverse kinematics at every segment point
            followers = {}
        time_units = Fraction(self.host.ivar(5000 + 100 * cs.number + 90))
        if time_units == 0:
            raise stmt.pos.error(f"I{5000 + 100 * cs.number + 90} (Isx90, feedrate time units) = 0: F needs a time "
                                 "unit > 0 ms")
        scale_f = 1000 / time_units  # F per Isx90 ms -> per s
        item: Item
        if modes.move == "RAPID":
            rapid: dict[str, RapidAxis] = {}
            for axis, target in targets.items():
                speed, ta, ts = self.host.rapid_parameters(cs.number, axis, stmt.pos)
                rapid[axis] = RapidAxis(target, speed, ta, ts)
            item = RapidMove(rapid, followers)
        elif modes.move in ("CIRCLE1", "CIRCLE2"):
            item = self.circle(stmt, targets, followers, scale_f)
        elif modes.move == "PVT":
            if modes.pvt_ms <= 0:
                raise stmt.pos.error(f"PVT{modes.pvt_ms}: the segment time must be > 0 ms")
            v1 = {w.axis: Fraction(expression(w.velocity)(self.context)) * scale_f / 1000 if w.velocity is not None
                  else Fraction(0) for w in stmt.axes}
            item = PvtMove(targets, {a: modes.velocities.get(a, Fraction(0)) for a in targets}, v1, modes.pvt_ms,
                           followers)
            modes.velocities.update(v1)
        elif modes.move == "SPLINE1":
            return self.spline(stmt, targets, followers, cs)
        elif modes.tm_ms is not None:
            item = Move(targets, tm_ms=modes.tm_ms, ta_ms=modes.ta_ms, ts_ms=modes.ts_ms, followers=followers)
        else:
            item = Move(targets, feedrate=modes.feedrate * scale_f, ta_ms=modes.ta_ms, ts_ms=modes.ts_ms,
                        followers=followers)
        self._flush_spline(cs)
        if segment_ms > 0:
            number, pos = cs.number, stmt.pos
            item = Segmented(item, segment_ms, lambda positions: self.host.kinematics(number, positions, pos))
        cs.queue(item)
        return True

    def circle(self, stmt: MoveStmt, targets: dict[str, Fraction], followers: dict[str, Fraction],
               scale_f: Fraction) -> CircleMove:
        modes = self.modes
        letter, sign = modes.normal
        plane = _PLANES[letter]
        centre = None
        radius = None
        if stmt.radius is not None:
            radius = Fraction(expression(stmt.radius)(self.context))
        else:
            vector = {axis: Fraction(0) for axis in "XYZ"}
            axis_of = {"I": "X", "J": "Y", "K": "Z"}
            for name, expr in stmt.centre:
                vector[axis_of.get(name, name)] = Fraction(expression(expr)(self.context))
            centre = (vector[plane[0]], vector[plane[1]])
        clockwise = (modes.move == "CIRCLE1") == (sign < 0)
        feed = (None, modes.tm_ms) if modes.tm_ms is not None else (modes.feedrate * scale_f, None)
        return CircleMove(targets, plane, clockwise, centre, radius, feed[0], feed[1], modes.ta_ms, modes.ts_ms,
                          followers)

    def spline(self, stmt: MoveStmt, targets: dict[str, Fraction], followers: dict[str, Fraction],
               cs: CoordinateSystem) -> bool:
        """SPLINE1: a point waits until the next is known (its velocity is the central difference)."""
        waiting = self._spline
        t = self.modes.tm_ms if self.modes.tm_ms is not None else Fraction(0)
        if t <= 0:
            raise stmt.pos.error("SPLINE1 needs a segment time: set it with TM (> 0)")
        if waiting is not None:
            self._queue_spline(cs, waiting[0], targets)
        self._spline = ({**targets, **followers}, stmt)
        return waiting is not None

    def _queue_spline(self, cs: CoordinateSystem, point: dict[str, Fraction], following: dict[str, Fraction] | None
                      ) -> None:
        modes = self.modes
        t = modes.tm_ms if modes.tm_ms is not None else Fraction(1)
        axes = {a: p for a, p in point.items() if not a.startswith("#")}
        follow = {a: p for a, p in point.items() if a.startswith("#")}
        v0 = {a: modes.velocities.get(a, Fraction(0)) for a in axes}
        if following is None:
            v1 = {a: Fraction(0) for a in axes}
        else:
            v1 = {a: (following.get(a, p) - cs.program_end(a)) / (2 * t) for a, p in axes.items()}
        cs.queue(PvtMove(axes, v0, v1, t, follow))
        modes.velocities.update(v1)

    def _flush_spline(self, cs: CoordinateSystem) -> None:
        """The last SPLINE1 point: to rest at its position."""
        if self._spline is not None:
            point, _stmt = self._spline
            self._spline = None
            self._queue_spline(cs, point, None)
            self.modes.velocities.clear()


__all__ = ["KINEMATIC_AXES", "LOOKAHEAD", "MAX_CALL_DEPTH", "MAX_STEPS", "Compiled", "Context", "Evaluator", "Host",
           "MotionModes", "MotionProgram", "PlcProgram", "Session", "run_to_end"]
