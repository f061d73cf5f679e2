"""One line of PMAC text as statements: the lark parse tree turned into the objects of :mod:`.nodes`.

:func:`parse_line` parses a line with the grammar of :mod:`.grammar` (``online`` outside a buffer,
``program`` inside ``OPEN ... CLOSE``) and returns its statements, each with its place
(:class:`Pos`: file, line, column). Everything that can be checked on one line is checked here,
before anything runs: the syntax (an unknown command names the word), variable numbers (I0..I8191
and known to the model, P0..P8191, M0..M8191), constant values of I-variables against their
ranges, M-variable definitions, nesting of parentheses (at most :data:`MAX_PARENS`).
"""

from __future__ import annotations

import re
from fractions import Fraction

from lark import Token, Tree
from lark.exceptions import UnexpectedInput, UnexpectedToken

from cosim.controllers.grammars import lark_parser
from cosim.controllers.pmac import arith, ivars
from cosim.controllers.pmac.ect import TURBO_ECT_BASE
from cosim.controllers.pmac.grammar import GRAMMAR
from cosim.controllers.pmac.nodes import (
    Assign,
    AxisWord,
    Begin,
    Call,
    Clear,
    Close,
    Cmd,
    Compare,
    Cond,
    CsSelect,
    Delay,
    Disable,
    Dwell,
    Else,
    Enable,
    EndIf,
    EndWhile,
    Expr,
    Func,
    Gosub,
    Goto,
    Hold,
    If,
    Label,
    Logic,
    MDefine,
    Mode,
    MotorDef,
    MotorSelect,
    MWord,
    Neg,
    Num,
    OpenBuffer,
    Ops,
    Param,
    Percent,
    Pos,
    Query,
    Return,
    Run,
    Stmt,
    Var,
    While,
    constant,
)
from cosim.controllers.pmac.units import REG_MASK
from cosim.errors import ConfigurationError

#: Deepest nesting of parentheses in one expression or condition.
MAX_PARENS = 32
#: Variable numbers: I, P, M (and Q) 0..8191 on Turbo PMAC.
VAR_LAST = 8191
#: Coordinate systems, motors, motion programs, PLC programs, labels.
CS_RANGE = (1, 8)
MOTOR_RANGE = (1, 32)
PROG_RANGE = (1, 32767)
PLC_RANGE = (0, 31)
LABEL_RANGE = (0, 99999)

_PARSER = lark_parser(GRAMMAR, parser="lalr", start=["online_line", "program_line"], propagate_positions=True,
                      maybe_placeholders=True)
_WORD = re.compile(r"[A-Za-z0-9_.$@]+|\S+")


# -- parsing -----------------------------------------------------------------------------------
def _check_parens(text: str, source: str, line: int) -> None:
    depth = 0
    in_string = False
    for column, char in enumerate(text, 1):
        if char == '"':
            in_string = not in_string
        elif in_string:
            continue
        elif char == ";":
            return
        elif char == "(":
            depth += 1
            if depth > MAX_PARENS:
                raise Pos(source, line, column).error(f"parentheses nested deeper than {MAX_PARENS} levels")
        elif char == ")":
            depth = max(0, depth - 1)


def parse_line(text: str, *, context: str, source: str, line: int, column: int = 1) -> list[Stmt]:
    """The statements of one line.

    Parameters
    ----------
    text : str
        The line (no line break).
    context : str
        ``"online"`` (outside a buffer) or ``"program"`` (inside ``OPEN ... CLOSE``).
    source, line : str, int
        File name and line number for messages.
    column : int
        Column of ``text``'s first character in the file (for a ``CMD`` string).

    Raises
    ------
    ConfigurationError
        ``file:line:column: ...`` for anything wrong on the line.
    """
    _check_parens(text, source, line)
    try:
        tree = _PARSER.parse(text, start=f"{context}_line")
    except UnexpectedInput as exc:
        raise _syntax_error(exc, text, context=context, pos=Pos(source, line, column)) from None
    return _Converter(source, line, column - 1).line(tree)


def _syntax_error(exc: UnexpectedInput, text: str, *, context: str, pos: Pos) -> ConfigurationError:
    if isinstance(exc, UnexpectedToken) and exc.token.type == "$END":
        return pos.shifted(len(text.rstrip())).error("the statement is incomplete at the end of the line")
    col = exc.column if isinstance(exc.column, int) and exc.column > 0 else len(text) + 1
    start = col - 1
    if start < len(text) and text[start].isalpha():
        while start > 0 and text[start - 1].isalpha():  # the whole word (F of FEED lexes as the F command)
            start -= 1
    where = pos.shifted(start)
    match = _WORD.match(text, start)
    word = match.group(0) if match else text[start:start + 1]
    shown = word if len(word) <= 30 else word[:27] + "..."
    if context == "online" and re.match(r"\s*OPEN\b", text, re.IGNORECASE):
        return where.error("nothing may follow OPEN PROG n [CLEAR] (or OPEN PLC n [CLEAR]) on its line: the buffer's "
                           "statements go on the lines after it")
    other = "program" if context == "online" else "online"
    try:
        _PARSER.parse(text[start:], start=f"{other}_line")
    except UnexpectedInput:
        pass
    else:
        if context == "online":
            return where.error(f"{shown!r} is a program statement: write it between OPEN PROG n (or OPEN PLC n) "
                               "and CLOSE")
        return where.error(f"{shown!r} is an online command, not allowed inside a program buffer (CLOSE it first)")
    before = text[:start].rstrip()
    if before.endswith("="):
        return where.error(f"{shown!r} is not a value (write a number: decimal, $hex or @In; a variable; or an "
                           "expression of them)")
    if word[:1] in "eE" and start > 0 and text[start - 1].isdigit():
        return where.error(f"syntax error: unexpected {shown!r} (PMAC numbers are written without an exponent)")
    if word[:1].isalpha():
        return where.error(f"unknown command {shown!r}")
    return where.error(f"syntax error: unexpected {shown!r}")


def _range(value: int, name: str, bounds: tuple[int, int], pos: Pos) -> int:
    low, high = bounds
    if not low <= value <= high:
        raise pos.error(f"{name} = {value} is not allowed (allowed: {low}..{high})")
    return value


class _Converter:
    """Lark tree -> statements, checking what one line can show."""

    def __init__(self, source: str, line: int, offset: int) -> None:
        self.source = source
        self.line_no = line
        self.offset = offset

    def pos(self, node: Tree | Token) -> Pos:
        if isinstance(node, Token):
            return Pos(self.source, self.line_no, (node.column or 1) + self.offset)
        return Pos(self.source, self.line_no, (1 if node.meta.empty else node.meta.column) + self.offset)

    def line(self, tree: Tree) -> list[Stmt]:
        children = [child for child in tree.children if child is not None]
        return [self.statement(child, last=i == len(children) - 1) for i, child in enumerate(children)]

    # -- statements ------------------------------------------------------------------------
    def statement(self, node: Tree, *, last: bool = True) -> Stmt:
        kind = str(node.data)
        kids = node.children
        pos = self.pos(node)
        if kind == "cs_select":
            return CsSelect(pos, _range(int(str(kids[0])), "coordinate system &n", CS_RANGE, pos))
        if kind == "motor_select":
            return MotorSelect(pos, _range(int(str(kids[0])), "motor #n", MOTOR_RANGE, pos))
        if kind == "motor_def":
            return self.motor_def(pos, kids)
        if kind == "open_buffer":
            buffer = "PLC" if str(kids[0]).upper() == "PLC" else "PROG"
            bounds = PLC_RANGE if buffer == "PLC" else PROG_RANGE
            return OpenBuffer(pos, buffer, _range(int(str(kids[1])), f"{buffer} number", bounds, pos))
        simple = {"clear": Clear, "close": Close, "run": Run, "hold": Hold, "else_head": Else, "endif": EndIf,
                  "endwhile": EndWhile, "return": Return}
        if kind in simple:
            return simple[kind](pos)
        if kind == "begin":
            return Begin(pos, _range(int(str(kids[0])), "program number (Bn)", PROG_RANGE, pos))
        if kind == "percent":
            return Percent(pos, arith.literal(str(kids[0]), where=str(pos)))
        if kind == "assign":
            return self.assign(pos, kids)
        if kind == "mdef":
            return self.mdef(pos, kids)
        if kind == "query":
            return Query(pos, self.var(kids[0]))
        if kind in ("plc_enable", "plc_disable"):
            numbers = tuple(_range(int(str(k)), "PLC number", PLC_RANGE, pos) for k in kids)
            return Enable(pos, numbers) if kind == "plc_enable" else Disable(pos, numbers)
        if kind == "label":
            return Label(pos, _range(int(str(kids[0])), "label N", LABEL_RANGE, pos))
        if kind == "mode":
            return Mode(pos, str(kids[0]).upper())
        if kind == "param":
            return Param(pos, str(kids[0]).upper(), self.expr(kids[1]))
        if kind == "axis":
            return AxisWord(pos, str(kids[0]).upper(), self.expr(kids[1]))
        if kind == "dwell":
            return Dwell(pos, self.expr(kids[0]))
        if kind == "delay":
            return Delay(pos, self.expr(kids[0]))
        if kind in ("if_head", "while_head"):
            cls = If if kind == "if_head" else While
            return cls(pos, self.cond(kids[0]), not last)
        if kind == "goto":
            return Goto(pos, _range(int(str(kids[0])), "label of GOTO", LABEL_RANGE, pos))
        if kind == "gosub":
            return Gosub(pos, _range(int(str(kids[0])), "label of GOSUB", LABEL_RANGE, pos))
        if kind == "call":
            return Call(pos, _range(int(str(kids[0])), "program of CALL", PROG_RANGE, pos))
        if kind == "cmd":
            assert isinstance(kids[0], Token)
            return self.cmd(pos, kids[0])
        raise pos.error(f"statement {kind!r} is not supported")  # the grammar has no other

    def motor_def(self, pos: Pos, kids: list) -> MotorDef:
        motor = _range(int(str(kids[0])), "motor #n", MOTOR_RANGE, pos)
        sign = -1 if kids[1] is not None and str(kids[1]) == "-" else 1
        scale = arith.literal(str(kids[2]), where=str(pos)) * sign if kids[2] is not None else Fraction(sign)
        if scale == 0:
            raise pos.error(f"#{motor}->0{kids[3]}: the scale of a motor definition must not be 0")
        return MotorDef(pos, motor, scale, str(kids[3]).upper())

    def assign(self, pos: Pos, kids: list) -> Assign:
        var = self.var(kids[0])
        expr = self.expr(kids[1])
        value = constant(expr) if var.kind == "I" else None
        if value is not None:
            ivars.check_ivar(var.number, value.numerator if value.denominator == 1 else value, where=str(pos))
        return Assign(pos, var, expr)

    def mdef(self, pos: Pos, kids: list) -> MDefine:
        number = self.var(kids[0]).number
        target = kids[1]
        if target.data == "mself":
            return MDefine(pos, number, None)
        space, address, offset, width, fmt = target.children
        address_value = int(arith.literal(str(address))) if str(address).startswith("$") else int(address)
        if not 0 <= address_value <= REG_MASK:
            raise pos.error(f"M{number} address = {address} is not allowed (allowed: $000000..$FFFFFF)")
        offset_value = int(offset) if offset is not None else 0
        width_value = int(width) if width is not None else (24 if offset is None else 1)
        if not 0 <= offset_value <= 23:
            raise pos.error(f"M{number} bit offset = {offset_value} is not allowed (allowed: 0..23)")
        if not 1 <= width_value <= 24 - offset_value:
            raise pos.error(f"M{number} width = {width_value} is not allowed (allowed: 1..{24 - offset_value}: "
                            "offset + width <= 24 bits)")
        signed = fmt is not None and str(fmt).upper() == "S"
        return MDefine(pos, number, MWord(str(space)[0].upper(), address_value, offset_value, width_value, signed))

    def cmd(self, pos: Pos, token: Token) -> Cmd:
        text = str(token)[1:-1]
        start = self.pos(token).column + 1
        commands = parse_line(text, context="online", source=self.source, line=self.line_no, column=start)
        for command in commands:
            if isinstance(command, OpenBuffer | Clear | Close):
                raise command.pos.error("OPEN, CLEAR and CLOSE cannot be issued from a program")
        return Cmd(pos, text, tuple(commands))

    # -- expressions -----------------------------------------------------------------------
    def var(self, node: Tree | Token) -> Var:
        token = node.children[0] if isinstance(node, Tree) else node
        assert isinstance(token, Token)
        text = str(token)
        kind, number = text[0].upper(), int(text[1:])
        pos = self.pos(token)
        _range(number, f"{kind}-variable number", (0, VAR_LAST), pos)
        if kind == "I" and not ivars.is_known(number):
            ivars.check_ivar(number, 0, where=str(pos))  # raises: unknown I-variable, naming the known ones
        return Var(kind, number, pos)

    def expr(self, node: Tree | Token) -> Expr:
        if isinstance(node, Token):  # a bare token cannot reach here (the grammar wraps numbers)
            return Num(arith.literal(str(node), where=str(self.pos(node))))
        kind = str(node.data)
        kids = node.children
        if kind == "number" or kind == "hexnumber":
            token = kids[0]
            return Num(arith.literal(str(token), where=str(self.pos(token))))
        if kind == "address_of":
            text = str(kids[0])
            target = int(text[2:])
            pos = self.pos(kids[0])
            if not ivars.ECT_FIRST <= target <= ivars.ECT_LAST:
                raise pos.error(f"{text} = address of I{target} is not allowed "
                                f"(allowed: @I{ivars.ECT_FIRST}..@I{ivars.ECT_LAST}, conversion-table lines)")
            return Num(Fraction(TURBO_ECT_BASE + target - ivars.ECT_FIRST))
        if kind == "var":
            return self.var(node)
        if kind == "neg":
            return Neg(self.expr(kids[0]))
        if kind in ("sum", "product"):
            rest = tuple((str(kids[i]), self.expr(kids[i + 1])) for i in range(1, len(kids), 2))
            return Ops(self.expr(kids[0]), rest, self.pos(node))
        if kind == "func":
            return Func(str(kids[0]).upper(), self.expr(kids[1]))
        if len(kids) == 1:  # "+" atom, or a parenthesised expression
            return self.expr(kids[0])
        raise self.pos(node).error(f"expression {kind!r} is not supported")

    def cond(self, node: Tree) -> Cond:
        kind = str(node.data)
        kids = node.children
        if kind == "compare":
            return Compare(str(kids[1]), self.expr(kids[0]), self.expr(kids[2]))
        if kind == "equal":
            return Compare("=", self.expr(kids[0]), self.expr(kids[1]))
        if kind in ("cond_or", "cond_and"):
            return Logic("OR" if kind == "cond_or" else "AND", tuple(self.cond(k) for k in kids))
        if len(kids) == 1:
            return self.cond(kids[0])
        raise self.pos(node).error(f"condition {kind!r} is not supported")
