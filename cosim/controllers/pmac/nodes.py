"""The parsed form of PMAC text: places, expressions, conditions and statements (small frozen objects).

:mod:`.statements` builds them from the lark parse of a line; :mod:`.program` compiles a buffer's
statements into flat code; :mod:`.interpreter` and :mod:`.runtime` run them.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from fractions import Fraction

from cosim.controllers.pmac import arith
from cosim.errors import ConfigurationError


@dataclass(frozen=True)
class Pos:
    """A place in a file: ``source:line:column`` (1-based)."""

    source: str
    line: int
    column: int

    def __str__(self) -> str:
        return f"{self.source}:{self.line}:{self.column}"

    def error(self, message: str) -> ConfigurationError:
        """``ConfigurationError("file:line:col: message")``."""
        return ConfigurationError(f"{self}: {message}")

    def shifted(self, columns: int) -> Pos:
        """The same line, ``columns`` further right (a command inside a ``CMD"..."`` string)."""
        return Pos(self.source, self.line, self.column + columns)


@contextmanager
def located(pos: Pos) -> Iterator[None]:
    """Prefix a ConfigurationError raised inside with ``file:line:col`` (unless it names a place of that file)."""
    try:
        yield
    except ConfigurationError as exc:
        if str(exc).startswith(f"{pos.source}:"):
            raise
        raise ConfigurationError(f"{pos}: {exc}") from exc


# -- expressions -------------------------------------------------------------------------------
@dataclass(frozen=True)
class Num:
    """A constant."""

    value: Fraction


@dataclass(frozen=True)
class Var:
    """A variable reference: ``kind`` I, P or M and its number."""

    kind: str
    number: int
    pos: Pos

    def __str__(self) -> str:
        return f"{self.kind}{self.number}"


@dataclass(frozen=True)
class Neg:
    """Unary minus."""

    arg: Expr


@dataclass(frozen=True)
class Ops:
    """``first op1 e1 op2 e2 ...``, evaluated left to right (one precedence level)."""

    first: Expr
    rest: tuple[tuple[str, Expr], ...]
    pos: Pos


@dataclass(frozen=True)
class Func:
    """``ABS(e)`` or ``INT(e)``."""

    name: str
    arg: Expr


Expr = Num | Var | Neg | Ops | Func


@dataclass(frozen=True)
class Compare:
    """``left op right`` with op one of ``= != <> > < !> !< >= <=``."""

    op: str
    left: Expr
    right: Expr


@dataclass(frozen=True)
class Logic:
    """``AND`` / ``OR`` of conditions."""

    op: str
    items: tuple[Cond, ...]


Cond = Compare | Logic


def constant(expr: Expr) -> Fraction | None:
    """The value of an expression without variables (None if it reads one)."""
    if isinstance(expr, Num):
        return expr.value
    if isinstance(expr, Var):
        return None
    if isinstance(expr, Neg | Func):
        arg = constant(expr.arg)
        if arg is None:
            return None
        return -arg if isinstance(expr, Neg) else arith.function(expr.name, arg)
    value = constant(expr.first)
    for op, operand in expr.rest:
        right = constant(operand)
        if value is None or right is None:
            return None
        value = arith.binary(op, value, right, where=str(expr.pos))
    return value


# -- statements --------------------------------------------------------------------------------
@dataclass(frozen=True)
class Stmt:
    """Base of statements: where it is written."""

    pos: Pos

    @property
    def name(self) -> str:
        """The statement's keyword, for messages."""
        return type(self).__name__.upper()


@dataclass(frozen=True)
class CsSelect(Stmt):
    number: int


@dataclass(frozen=True)
class MotorSelect(Stmt):
    number: int


@dataclass(frozen=True)
class MotorDef(Stmt):
    """``#n->scale AXIS``: motor n follows ``scale`` counts per unit of the axis."""

    motor: int
    scale: Fraction
    axis: str


@dataclass(frozen=True)
class OpenBuffer(Stmt):
    kind: str  # "PROG" or "PLC"
    number: int


@dataclass(frozen=True)
class Clear(Stmt):
    pass


@dataclass(frozen=True)
class Close(Stmt):
    pass


@dataclass(frozen=True)
class Begin(Stmt):
    number: int


@dataclass(frozen=True)
class Run(Stmt):
    pass


@dataclass(frozen=True)
class Hold(Stmt):
    pass


@dataclass(frozen=True)
class Percent(Stmt):
    value: Fraction


@dataclass(frozen=True)
class Assign(Stmt):
    var: Var
    expr: Expr


@dataclass(frozen=True)
class MWord:
    """``X:address,offset,width,format`` (``Y:`` likewise)."""

    space: str
    address: int
    offset: int
    width: int
    signed: bool

    def __str__(self) -> str:
        return f"{self.space}:${self.address:06X},{self.offset},{self.width},{'S' if self.signed else 'U'}"


@dataclass(frozen=True)
class MDefine(Stmt):
    """``Mn->X:...`` or ``Mn->*`` (target None: a plain 48-bit memory word)."""

    number: int
    target: MWord | None


@dataclass(frozen=True)
class Query(Stmt):
    """A bare variable on a command line: read it (reading a capture register re-arms it)."""

    var: Var


@dataclass(frozen=True)
class Enable(Stmt):
    plcs: tuple[int, ...]


@dataclass(frozen=True)
class Disable(Stmt):
    plcs: tuple[int, ...]


@dataclass(frozen=True)
class Label(Stmt):
    number: int


@dataclass(frozen=True)
class Mode(Stmt):
    """``LINEAR``, ``RAPID``, ``ABS`` or ``INC``."""

    mode: str


@dataclass(frozen=True)
class Param(Stmt):
    """``F``, ``TA``, ``TS`` or ``TM`` with its value."""

    param: str
    expr: Expr


@dataclass(frozen=True)
class AxisWord(Stmt):
    """One axis of a move (``X1000``); consecutive axis words form one move."""

    axis: str
    expr: Expr


@dataclass(frozen=True)
class Dwell(Stmt):
    expr: Expr


@dataclass(frozen=True)
class Delay(Stmt):
    expr: Expr


@dataclass(frozen=True)
class If(Stmt):
    """``IF (cond)``: a block to ENDIF, or (``inline``: statements follow on its line) the rest of the line."""

    cond: Cond
    inline: bool


@dataclass(frozen=True)
class Else(Stmt):
    pass


@dataclass(frozen=True)
class EndIf(Stmt):
    pass


@dataclass(frozen=True)
class While(Stmt):
    """``WHILE (cond)``: a block to ENDWHILE, or (``inline``) the rest of its line, repeated."""

    cond: Cond
    inline: bool


@dataclass(frozen=True)
class EndWhile(Stmt):
    pass


@dataclass(frozen=True)
class Goto(Stmt):
    label: int


@dataclass(frozen=True)
class Gosub(Stmt):
    label: int


@dataclass(frozen=True)
class Call(Stmt):
    program: int


@dataclass(frozen=True)
class Return(Stmt):
    pass


@dataclass(frozen=True)
class Cmd(Stmt):
    """``CMD"..."``: online commands issued by a program (parsed when the file is read)."""

    text: str
    commands: tuple[Stmt, ...]


#: Statements that only a motion program may hold.
MOTION_ONLY = (Mode, Param, AxisWord, Dwell, Delay)
