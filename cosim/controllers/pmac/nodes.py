"""The syntax tree of PMAC text: expressions, conditions and statements (small frozen objects).

:mod:`.syntax` builds them from the lark parse of a line; :mod:`.program` compiles a buffer's
statements into flat code; the runtime (:mod:`.evaluate`, :mod:`.interpreter`, :mod:`.runtime`)
runs them. This module imports nothing of the runtime.

Values are exact: ``int`` where they are whole, :class:`~fractions.Fraction` otherwise
(:mod:`.arith`).
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

from cosim.controllers.pmac import arith
from cosim.controllers.pmac.source import Pos, located

Value = int | Fraction


# -- expressions -------------------------------------------------------------------------------
@dataclass(frozen=True)
class Num:
    """A constant."""

    value: Value


@dataclass(frozen=True)
class Var:
    """A variable: ``kind`` I, P, Q or M and its number."""

    kind: str
    number: int
    pos: Pos

    def __str__(self) -> str:
        return f"{self.kind}{self.number}"


@dataclass(frozen=True)
class IndVar:
    """An indirect variable: ``P(expr)``, ``Q(expr)``, ``M(expr)``, ``I(expr)`` (the number is computed)."""

    kind: str
    index: Expr
    pos: Pos

    def __str__(self) -> str:
        return f"{self.kind}(...)"


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
    """``ABS(e)``, ``INT(e)``, ``SIN(e)``, ... (see :mod:`.arith`)."""

    name: str
    arg: Expr
    pos: Pos


Expr = Num | Var | IndVar | Neg | Ops | Func
Target = Var | IndVar


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


def constant(expr: Expr) -> Value | None:
    """The value of an expression without variables (None if it reads one)."""
    if isinstance(expr, Num):
        return expr.value
    if isinstance(expr, Var | IndVar):
        return None
    if isinstance(expr, Neg):
        arg = constant(expr.arg)
        return None if arg is None else -arg
    if isinstance(expr, Func):
        arg = constant(expr.arg)
        if arg is None:
            return None
        with located(expr.pos):
            return arith.function(expr.name, arg)
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
    """``&n``: address coordinate system n."""

    number: Expr


@dataclass(frozen=True)
class MotorSelect(Stmt):
    """``#n``: address motor n."""

    number: Expr


@dataclass(frozen=True)
class MotorDef(Stmt):
    """``#n->[c1]A1 [+c2 A2 ...] [+offset]``: motor n follows a linear combination of axes [counts per unit]."""

    motor: int
    terms: tuple[tuple[Fraction, str], ...]
    offset: Fraction = Fraction(0)

    @property
    def scale(self) -> Fraction:
        """Counts per unit of the first axis."""
        return self.terms[0][0]

    @property
    def axis(self) -> str:
        """The first axis."""
        return self.terms[0][1]


@dataclass(frozen=True)
class MotorKinematic(Stmt):
    """``#n->I`` (``inverse``: the inverse-kinematic program sets it) or ``#n->0`` (assigned to no axis)."""

    motor: int
    inverse: bool


@dataclass(frozen=True)
class MotorQuery(Stmt):
    """``#n->``: report motor n's axis definition."""

    motor: int


@dataclass(frozen=True)
class Undefine(Stmt):
    """``UNDEFINE`` (the addressed coordinate system's axis definitions) or ``UNDEFINE ALL``."""

    all: bool


@dataclass(frozen=True)
class OpenBuffer(Stmt):
    """``OPEN PROG n``, ``OPEN PLC n``, ``OPEN FORWARD [n]``, ``OPEN INVERSE [n]``, ``OPEN ROTARY`` [``CLEAR``]."""

    kind: str  # PROG, PLC, FORWARD, INVERSE, ROTARY
    number: int
    clear: bool = False


@dataclass(frozen=True)
class Clear(Stmt):
    """``CLEAR`` (of the open buffer)."""


@dataclass(frozen=True)
class Close(Stmt):
    """``CLOSE`` [``ALL``]."""

    all: bool = False


@dataclass(frozen=True)
class Begin(Stmt):
    """``Bn``: point the addressed coordinate system at motion program n."""

    number: Expr


@dataclass(frozen=True)
class CsCommand(Stmt):
    """A one-letter coordinate-system command: ``R`` run, ``S`` step, ``H`` hold, ``A`` abort, ``Q`` quit, ``K`` kill,
    ``/``, ``\\``."""

    letter: str


@dataclass(frozen=True)
class Percent(Stmt):
    """``%n``: feedrate override of the addressed coordinate system."""

    value: Expr


@dataclass(frozen=True)
class PercentQuery(Stmt):
    """``%``: report the feedrate override."""


@dataclass(frozen=True)
class Assign(Stmt):
    """``var = expr`` (``expr`` None: ``var=*``, the I-variable's default)."""

    var: Target
    expr: Expr | None
    op: str = "="


@dataclass(frozen=True)
class RangeAssign(Stmt):
    """``I100..131=0`` or ``I5213,15,100=10``: ``count`` variables from ``first``, ``step`` apart."""

    kind: str
    first: int
    count: int
    step: int
    expr: Expr | None

    def numbers(self) -> range:
        """The variables' numbers."""
        return range(self.first, self.first + self.count * self.step, self.step)


@dataclass(frozen=True)
class RangeQuery(Stmt):
    """``I100..131`` or ``P1,10``: report a range of variables."""

    kind: str
    first: int
    count: int
    step: int

    def numbers(self) -> range:
        """The variables' numbers."""
        return range(self.first, self.first + self.count * self.step, self.step)


@dataclass(frozen=True)
class Query(Stmt):
    """A bare variable on a command line: read it (reading a capture register re-arms it)."""

    var: Target


@dataclass(frozen=True)
class MWord:
    """``X:address,offset,width,format`` (``Y:`` likewise): a bit field of a 24-bit word."""

    space: str
    address: int
    offset: int
    width: int
    signed: bool

    def __str__(self) -> str:
        return f"{self.space}:${self.address:06X},{self.offset},{self.width},{'S' if self.signed else 'U'}"


@dataclass(frozen=True)
class MWide:
    """``D:``, ``DP:``, ``L:`` or ``F:`` address: a 48-bit or 32-bit word (fixed or floating point)."""

    kind: str
    address: int

    def __str__(self) -> str:
        return f"{self.kind}:${self.address:06X}"


@dataclass(frozen=True)
class MThumb:
    """``TWS:``, ``TWB:``, ``TWD:``, ``TWR:``: thumbwheel-multiplexer inputs."""

    kind: str
    args: tuple[int, ...]

    def __str__(self) -> str:
        return f"{self.kind}:{','.join(str(a) for a in self.args)}"


MTarget = MWord | MWide | MThumb | None


@dataclass(frozen=True)
class MDefine(Stmt):
    """``Mn->...`` (or ``Mfirst..last->...``): M-variable definition; target None is ``->*``."""

    number: int
    target: MTarget
    last: int | None = None

    def numbers(self) -> range:
        """The M-variables defined."""
        return range(self.number, (self.last if self.last is not None else self.number) + 1)


@dataclass(frozen=True)
class MDefQuery(Stmt):
    """``Mn->``: report an M-variable's definition."""

    number: int


@dataclass(frozen=True)
class PlcControl(Stmt):
    """``ENABLE``/``DISABLE``/``PAUSE``/``RESUME`` ``PLC``/``PLCC`` with a list of numbers and ranges."""

    verb: str
    compiled: bool
    plcs: tuple[int, ...]


@dataclass(frozen=True)
class Jog(Stmt):
    """``J+ J- J/ J! J= J=n J:n J^n J=* J:* J^*`` of the addressed motor."""

    kind: str
    value: Expr | None


@dataclass(frozen=True)
class MotorReport(Stmt):
    """``P``, ``V`` or ``F``: report the addressed motor's position, velocity or following error."""

    letter: str


@dataclass(frozen=True)
class OpenLoop(Stmt):
    """``On``: open-loop output of the addressed motor [% of Ixx69]."""

    value: Expr


@dataclass(frozen=True)
class AxisSet(Stmt):
    """``X=n``: redefine the current position of an axis."""

    axis: str
    value: Expr


@dataclass(frozen=True)
class Control(Stmt):
    """A control character (``^A`` abort all, ``^K`` kill all, ``^D`` disable PLCs, ``^R`` run all, ...)."""

    letter: str


@dataclass(frozen=True)
class Frax(Stmt):
    """``FRAX``, ``FRAX(X,Y)``, ``NOFRAX``, ``FRAX2``: the feedrate axes (listed, not modelled)."""

    keyword: str
    axes: tuple[str, ...]


@dataclass(frozen=True)
class Pmatch(Stmt):
    """``PMATCH``: axis positions from motor positions (forward kinematics)."""


@dataclass(frozen=True)
class Home(Stmt):
    """``HOME``, ``HOMEZ``, ``HM``, ``HMZ`` of motors (a program lists them; online: the addressed one)."""

    keyword: str
    motors: tuple[int, ...]


@dataclass(frozen=True)
class Other(Stmt):
    """A command the model accepts and keeps but does not act on: its keyword and its text as written."""

    keyword: str
    text: str


@dataclass(frozen=True)
class Label(Stmt):
    """``Nn`` or ``On``."""

    number: int


@dataclass(frozen=True)
class Mode(Stmt):
    """``LINEAR``, ``RAPID``, ``CIRCLE1``, ``CIRCLE2``, ``SPLINE1``, ``ABS`` or ``INC`` (``axes``: ``ABS(X,Y)``)."""

    mode: str
    axes: tuple[str, ...] = ()


@dataclass(frozen=True)
class Pvt(Stmt):
    """``PVTn``: PVT mode with segment time n [ms]."""

    expr: Expr


@dataclass(frozen=True)
class Param(Stmt):
    """``F``, ``TA``, ``TS`` or ``TM`` with its value."""

    param: str
    expr: Expr


@dataclass(frozen=True)
class AxisWord(Stmt):
    """One axis of a move (``X1000``, ``X100:50`` with a PVT velocity, ``X100^5`` until a trigger)."""

    axis: str
    expr: Expr
    velocity: Expr | None = None
    trigger: Expr | None = None


@dataclass(frozen=True)
class MoveStmt(Stmt):
    """A move: the axis words of a line (``X1000 Y500``), its circle centre (``I``, ``J``, ``K``) or radius ``R``."""

    axes: tuple[AxisWord, ...]
    centre: tuple[tuple[str, Expr], ...] = ()
    radius: Expr | None = None


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
class While(Stmt):
    """``WHILE (cond)``: a block to ENDWHILE, or (``inline``) the rest of its line, repeated."""

    cond: Cond
    inline: bool


@dataclass(frozen=True)
class Cont(Stmt):
    """``AND (cond)`` / ``OR (cond)`` starting a line: continues the condition of the IF or WHILE above."""

    op: str
    cond: Cond


@dataclass(frozen=True)
class Else(Stmt):
    pass


@dataclass(frozen=True)
class EndIf(Stmt):
    pass


@dataclass(frozen=True)
class EndWhile(Stmt):
    pass


@dataclass(frozen=True)
class Goto(Stmt):
    """``GOTO n`` (``target`` an expression: a computed jump, resolved when it runs)."""

    label: int | None
    target: Expr | None = None


@dataclass(frozen=True)
class Gosub(Stmt):
    label: int | None
    target: Expr | None = None


@dataclass(frozen=True)
class Call(Stmt):
    """``CALL n[.m]`` (label N(m*100000) of PROG n) with argument letters (``CALL 10 X5``: read by READ)."""

    program: int
    label: int | None = None
    args: tuple[tuple[str, Expr], ...] = ()


@dataclass(frozen=True)
class Return(Stmt):
    pass


@dataclass(frozen=True)
class Cmd(Stmt):
    """``CMD"..."`` / ``COMMAND"..."`` (online commands, parsed when the file is read) or ``CMD^A`` (``control``)."""

    text: str
    commands: tuple[Stmt, ...]
    control: str | None = None


@dataclass(frozen=True)
class Send(Stmt):
    """``SEND1"text"``, ``SENDS``, ``SENDP``, ... to the run's console (``control``: ``SEND^A``)."""

    port: str
    text: str
    control: str | None = None


@dataclass(frozen=True)
class Display(Stmt):
    """``DISPLAY [n] "text"`` or ``DISPLAY n,w.d,var`` (the display port): to the run's console."""

    text: str | None
    var: Target | None = None
    position: int = 0
    width: int = 0
    decimals: int = 0


@dataclass(frozen=True)
class Address(Stmt):
    """``ADDRESS &n #m``: the coordinate system and motor a PLC's ``CMD`` commands and Q-variables use."""

    cs: Expr | None
    motor: Expr | None


@dataclass(frozen=True)
class Normal(Stmt):
    """``NORMAL K-1``: the normal vector of the circle plane."""

    vector: tuple[tuple[str, Expr], ...]


@dataclass(frozen=True)
class CodeCall(Stmt):
    """``Gn``, ``Mn``, ``Tn``, ``Dn`` codes: a call of PROG 1000, 1001, 1002, 1003 at label N(n*1000)."""

    letter: str
    value: Expr


#: Statements that only a motion program may hold.
MOTION_ONLY = (Mode, Param, MoveStmt, AxisWord, Dwell, Delay, Pvt, Normal, CodeCall)
