"""What each online command and each non-motion program statement does (:class:`~.runtime.Programs`' acting part).

Online commands run with a :class:`~.interpreter.Session` (the ``&n`` and ``#n`` they address): the
host's for files and ``[[command]]`` lines, a PLC's own for its ``CMD"..."`` strings (``ADDRESS``
sets it). What the model does not act on is accepted, kept and listed in the run's notes as "set,
not modelled" (``sim.notes.not_modelled``), never refused:

==========================================  ===============================================================
modelled                                     ``&n #n``, ``#n->...`` (linear axis definitions, ``->I``,
                                             ``->0``), ``Bn R H A K Q / \\``, ``%n``, assignments of every
                                             variable kind (ranges, ``=*``), M-variable definitions, ENABLE/
                                             DISABLE/PAUSE/RESUME PLC(C), ``^A ^K ^D ^R ^Q ^O``, PMATCH
                                             (forward kinematics), SEND and DISPLAY (to the console),
                                             ADDRESS, CMD
listed, not modelled                         jogs ``J+ J- J= J: J^``, ``HM``/``HOME``, ``O``, ``S``, ``FRAX``,
                                             ``LIST``, ``SAVE``, ``$$$``, ``DEFINE``/``DELETE GATHER``,
                                             ``GATHER``, ``ENDGATHER``, MACRO ``MS`` commands, ``CC1``...,
                                             queries (``I130``, ``P1``, ``#1->``), other control characters
==========================================  ===============================================================
"""

from __future__ import annotations

from collections.abc import Iterable
from fractions import Fraction
from typing import TYPE_CHECKING

from cosim.controllers.pmac import ivartable
from cosim.controllers.pmac.bus import Controller
from cosim.controllers.pmac.evaluate import expression, variable_number
from cosim.controllers.pmac.interpreter import Context, Session
from cosim.controllers.pmac.nodes import (
    Address,
    Assign,
    AxisSet,
    Begin,
    Cmd,
    Control,
    CsCommand,
    CsSelect,
    Display,
    Expr,
    Frax,
    Home,
    Jog,
    MDefine,
    MDefQuery,
    MotorDef,
    MotorKinematic,
    MotorQuery,
    MotorReport,
    MotorSelect,
    OpenLoop,
    Other,
    Percent,
    PercentQuery,
    PlcControl,
    Pmatch,
    Pos,
    Query,
    RangeAssign,
    RangeQuery,
    Send,
    Stmt,
    Undefine,
    located,
)

if TYPE_CHECKING:
    from cosim.controllers.pmac.mvars import Memory


class _Frame:
    """The frame of an online command's expressions: the memory and the addressed coordinate system."""

    def __init__(self, memory: Memory, cs: int) -> None:
        self.memory = memory
        self.cs = cs


class Commands:
    """Mixin of :class:`~.runtime.Programs`: online commands and program statements that act."""

    pmac: Controller
    memory: Memory
    host: Session
    enabled: set[int]

    # provided by Programs
    def not_modelled(self, name: str, value: object, where: str) -> None: ...  # pragma: no cover
    def console(self, source: str, text: str) -> None: ...  # pragma: no cover
    def begin(self, cs_number: int, number: int, pos: Pos) -> None: ...  # pragma: no cover
    def run(self, cs_number: int, pos: Pos) -> None: ...  # pragma: no cover
    def abort(self, cs_number: int, how: str, pos: Pos) -> None: ...  # pragma: no cover
    def plc_control(self, stmt: PlcControl) -> None: ...  # pragma: no cover
    def forward(self, cs_number: int, pos: Pos) -> None: ...  # pragma: no cover
    def wake(self) -> None: ...  # pragma: no cover

    def value(self, expr: Expr, session: Session) -> Fraction | int:
        """An expression of an online command, with the session's Q-variables."""
        return expression(expr)(_Frame(self.memory, session.cs))

    def number(self, expr: Expr, session: Session, pos: Pos) -> int:
        value = self.value(expr, session)
        if value != int(value):
            raise pos.error(f"{value} is not a whole number")
        return int(value)

    def execute(self, statements: Iterable[Stmt], session: Session) -> None:
        """Run online commands with ``session``'s addressing."""
        pmac = self.pmac
        for stmt in statements:
            with located(stmt.pos):
                if isinstance(stmt, CsSelect):
                    session.cs = self.number(stmt.number, session, stmt.pos)
                elif isinstance(stmt, MotorSelect):
                    session.motor = self.number(stmt.number, session, stmt.pos)
                elif isinstance(stmt, MotorDef):
                    pmac.define_motor(stmt.motor, cs=session.cs, terms=stmt.terms, offset=stmt.offset,
                                      where=str(stmt.pos))
                elif isinstance(stmt, MotorKinematic):
                    pmac.define_kinematic_motor(stmt.motor, cs=session.cs, inverse=stmt.inverse, where=str(stmt.pos))
                elif isinstance(stmt, Undefine):
                    pmac.undefine(None if stmt.all else session.cs, where=str(stmt.pos))
                elif isinstance(stmt, Begin):
                    self.begin(session.cs, self.number(stmt.number, session, stmt.pos), stmt.pos)
                elif isinstance(stmt, CsCommand):
                    self.cs_command(stmt.letter, session.cs, stmt.pos)
                elif isinstance(stmt, Percent):
                    pmac.command_percent(session.cs, Fraction(self.value(stmt.value, session)))
                    self.wake()
                elif isinstance(stmt, Assign):
                    self.assign(stmt, _Frame(self.memory, session.cs))
                elif isinstance(stmt, RangeAssign):
                    self.range_assign(stmt, session)
                elif isinstance(stmt, MDefine):
                    self.memory.define(stmt)
                elif isinstance(stmt, Query):
                    var = stmt.var
                    frame = _Frame(self.memory, session.cs)
                    self.memory.read(var.kind, variable_number(var, frame), session.cs, stmt.pos)
                elif isinstance(stmt, PlcControl):
                    self.plc_control(stmt)
                elif isinstance(stmt, Control):
                    self.control(stmt.letter, stmt.pos)
                elif isinstance(stmt, Pmatch):
                    self.forward(session.cs, stmt.pos)
                elif isinstance(stmt, Jog | OpenLoop | Home | MotorReport):
                    self.not_modelled(f"#{session.motor} {_written(stmt)}", "motor command", str(stmt.pos))
                elif isinstance(stmt, AxisSet):
                    self.not_modelled(f"&{session.cs} {stmt.axis}=", self.value(stmt.value, session), str(stmt.pos))
                elif isinstance(stmt, Frax):
                    self.not_modelled(stmt.keyword, ",".join(stmt.axes) or "all axes", str(stmt.pos))
                elif isinstance(stmt, Other):
                    self.not_modelled(stmt.keyword, stmt.text, str(stmt.pos))
                elif isinstance(stmt, RangeQuery | PercentQuery | MotorQuery | MDefQuery):
                    pass  # a report to the host: nothing changes
                elif isinstance(stmt, Cmd | Send | Display | Address):
                    self._host_statement(stmt, session)
                else:
                    raise stmt.pos.error(f"{stmt.name} cannot be issued here")

    def _host_statement(self, stmt: Stmt, session: Session) -> None:
        if isinstance(stmt, Cmd):
            self.run_cmd(stmt, session)
        elif isinstance(stmt, Send | Display):
            self.console("host", self.message(stmt, _Frame(self.memory, session.cs)))
        elif isinstance(stmt, Address):
            self.address(stmt, session, _Frame(self.memory, session.cs))

    def assign(self, stmt: Assign, frame: _Frame | Context) -> None:
        var = stmt.var
        number = variable_number(var, frame)
        if stmt.expr is None:  # In=*: the reference's default
            self.pmac.set_ivar(number, ivartable.default(number), where=str(stmt.pos))
            self.memory.changed()
            return
        value = expression(stmt.expr)(frame)
        if var.kind == "M" and stmt.op != "=":
            self.memory.write_m(number, value, stmt.pos, stmt.op)
        else:
            self.memory.write(var.kind, number, value, frame.cs, stmt.pos)

    def range_assign(self, stmt: RangeAssign, session: Session) -> None:
        for number in stmt.numbers():
            if stmt.expr is None:
                self.pmac.set_ivar(number, ivartable.default(number), where=str(stmt.pos))
            else:
                self.memory.write(stmt.kind, number, self.value(stmt.expr, session), session.cs, stmt.pos)
        self.memory.changed()

    def cs_command(self, letter: str, cs_number: int, pos: Pos) -> None:
        pmac = self.pmac
        if letter == "R":
            self.run(cs_number, pos)
        elif letter == "S":
            self.not_modelled(f"&{cs_number}S", "step: runs the program as R does", str(pos))
            self.run(cs_number, pos)
        elif letter == "H":
            pmac.coordinate_system(cs_number).hold()
        else:
            self.abort(cs_number, letter, pos)

    def control(self, letter: str, pos: Pos) -> None:
        """A control character: ``^A`` abort all, ``^K`` kill all, ``^D`` disable all PLCs, ``^R`` run all, ..."""
        systems = sorted(self.pmac.cs)
        if letter in ("A", "K", "Q"):
            for number in systems:
                self.abort(number, f"^{letter}", pos)
        elif letter == "D":
            self.enabled.clear()
            self.wake()
        elif letter in ("R", "S"):
            for number in systems:
                if number in getattr(self, "selected", {}) and self.pmac.coordinate_system(number).program_done:
                    self.run(number, pos)
        elif letter == "O":
            for number in systems:
                self.pmac.coordinate_system(number).hold()
        else:
            self.not_modelled(f"^{letter}", "control character", str(pos))

    # -- program statements that act ------------------------------------------------------------
    def statement(self, stmt: Stmt, context: Context) -> None:
        """Run a statement that is not flow, assignment or motion (interpreter.Host)."""
        with located(stmt.pos):
            if isinstance(stmt, Assign):
                self.assign(stmt, context)
                return
            context.effects += 1
            if isinstance(stmt, PlcControl):
                self.plc_control(stmt)
            elif isinstance(stmt, Cmd):
                self.run_cmd(stmt, context.session)
            elif isinstance(stmt, Send | Display):
                self.console(context.source, self.message(stmt, context))
            elif isinstance(stmt, Address):
                self.address(stmt, context.session, context)
                context.cs = context.session.cs
            elif isinstance(stmt, Frax):
                self.not_modelled(stmt.keyword, ",".join(stmt.axes) or "all axes", str(stmt.pos))
            elif isinstance(stmt, Home):
                self.not_modelled(stmt.keyword, ",".join(str(m) for m in stmt.motors) or "-", str(stmt.pos))
            elif isinstance(stmt, Other):
                self.not_modelled(stmt.keyword, stmt.text, str(stmt.pos))
            elif isinstance(stmt, Pmatch):
                self.forward(context.cs, stmt.pos)
            else:
                raise stmt.pos.error(f"{stmt.name} cannot run here")

    def run_cmd(self, stmt: Cmd, session: Session) -> None:
        if stmt.control is not None:
            self.control(stmt.control, stmt.pos)
        else:
            self.execute(stmt.commands, session)

    def address(self, stmt: Address, session: Session, frame: _Frame | Context) -> None:
        if stmt.cs is not None:
            session.cs = _whole(expression(stmt.cs)(frame), stmt.pos, "ADDRESS &")
        if stmt.motor is not None:
            session.motor = _whole(expression(stmt.motor)(frame), stmt.pos, "ADDRESS #")

    def message(self, stmt: Send | Display, frame: _Frame | Context) -> str:
        """The text a SEND or DISPLAY puts on the console."""
        if isinstance(stmt, Send):
            return f"^{stmt.control}" if stmt.control is not None else stmt.text
        if stmt.var is None:
            return stmt.text or ""
        value = self.memory.read(stmt.var.kind, variable_number(stmt.var, frame), frame.cs, stmt.pos)
        return f"{float(value):{stmt.width}.{stmt.decimals}f}"


def _whole(value: object, pos: Pos, what: str) -> int:
    if not isinstance(value, int | Fraction) or value != int(value):
        raise pos.error(f"{what}{value}: a whole number is needed")
    return int(value)


def _written(stmt: Stmt) -> str:
    if isinstance(stmt, Jog):
        return stmt.kind
    if isinstance(stmt, Home):
        return stmt.keyword
    if isinstance(stmt, MotorReport):
        return stmt.letter
    return "O"


__all__ = ["Commands"]
