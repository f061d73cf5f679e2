"""One line of PMAC text as statements: the lark parse tree turned into the objects of :mod:`.nodes`.

:func:`parse_line` parses a line with the grammar of :mod:`.grammar` (``online`` outside a buffer,
``program`` inside ``OPEN ... CLOSE``) and returns its statements, each with its place (file, line,
column). Everything that can be checked on one line is checked here, before anything runs: the
syntax (an unknown command names the word), variable numbers (I, P, Q, M 0..8191), constant values
of I-variables against their ranges in the Turbo reference (:mod:`.ivartable`), M-variable
definitions, coordinate-system, motor, PLC and program numbers, nesting of parentheses (at most
:data:`MAX_PARENS`).
"""

from __future__ import annotations

import re
from fractions import Fraction

from lark import Token, Tree
from lark.exceptions import UnexpectedInput, UnexpectedToken

from cosim.controllers.pmac import arith, ivartable
from cosim.controllers.pmac.grammar import parser
from cosim.controllers.pmac.nodes import (
    Address,
    Assign,
    AxisSet,
    AxisWord,
    Begin,
    Call,
    Clear,
    Close,
    Cmd,
    CodeCall,
    Compare,
    Cond,
    Cont,
    Control,
    CsCommand,
    CsSelect,
    Delay,
    Display,
    Dwell,
    Else,
    EndIf,
    EndWhile,
    Expr,
    Frax,
    Func,
    Gosub,
    Goto,
    Home,
    If,
    IndVar,
    Jog,
    Label,
    Logic,
    MDefine,
    MDefQuery,
    Mode,
    MotorDef,
    MotorKinematic,
    MotorQuery,
    MotorReport,
    MotorSelect,
    MoveStmt,
    MTarget,
    MThumb,
    MWide,
    MWord,
    Neg,
    Normal,
    Num,
    OpenBuffer,
    OpenLoop,
    Ops,
    Other,
    Param,
    Percent,
    PercentQuery,
    PlcControl,
    Pmatch,
    Pos,
    Pvt,
    Query,
    RangeAssign,
    RangeQuery,
    Return,
    Send,
    Stmt,
    Target,
    Undefine,
    Var,
    While,
    constant,
)
from cosim.errors import ConfigurationError

#: Deepest nesting of parentheses in one expression or condition.
MAX_PARENS = 32
#: Variable numbers: I, P, Q and M 0..8191 on Turbo PMAC.
VAR_LAST = 8191
#: Coordinate systems, motors, motion programs, PLC programs, labels (Turbo PMAC).
CS_RANGE = (1, 16)
MOTOR_RANGE = (1, 32)
PROG_RANGE = (1, 32767)
BEGIN_RANGE = (0, 32767)  # B0 points a coordinate system at its rotary buffer
PLC_RANGE = (0, 31)
LABEL_RANGE = (0, 99999)
#: Highest register address of the 24-bit address space.
ADDRESS_LAST = 0xFFFFFF

_WORD = re.compile(r"[A-Za-z0-9_.$@]+|\S+")
_CONTROL_NAMES = {chr(c): chr(c + 64) for c in range(1, 27)}


# -- parsing -----------------------------------------------------------------------------------
def _check_parens(text: str, source: str, line: int, column: int) -> None:
    depth = 0
    in_string = False
    for index, char in enumerate(text):
        if char == '"':
            in_string = not in_string
        elif in_string:
            continue
        elif char == ";":
            return
        elif char == "(":
            depth += 1
            if depth > MAX_PARENS:
                raise Pos(source, line, column + index).error(f"parentheses nested deeper than {MAX_PARENS} levels")
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
    _check_parens(text, source, line, column)
    try:
        tree = parser(context).parse(text)
    except UnexpectedInput as exc:
        raise _syntax_error(exc, text, context=context, pos=Pos(source, line, column)) from None
    return _Converter(source, line, column - 1).line(tree)


def _syntax_error(exc: UnexpectedInput, text: str, *, context: str, pos: Pos) -> ConfigurationError:
    if isinstance(exc, UnexpectedToken) and exc.token.type == "$END":
        return pos.shifted(len(text.rstrip())).error("the statement is incomplete at the end of the line")
    col = exc.column if isinstance(exc.column, int) and exc.column > 0 else len(text) + 1
    start = col - 1
    if start < len(text) and text[start].isdigit() and start > 0 and text[start - 1].isalpha():
        start -= 1  # a letter and its number (X10): the word starts at the letter
    if start < len(text) and text[start].isalpha():
        while start > 0 and text[start - 1].isalpha():  # the whole word (F of FEED lexes as the F command)
            start -= 1
    where = pos.shifted(start)
    match = _WORD.match(text, start)
    word = match.group(0) if match else text[start:start + 1]
    shown = word if len(word) <= 30 else word[:27] + "..."
    other = "program" if context == "online" else "online"
    try:
        parser(other).parse(text[start:])
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


def _int(token: object) -> int:
    return int(str(token))


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
        out: list[Stmt] = []
        for i, child in enumerate(children):
            stmt = self.statement(child, last=i == len(children) - 1)
            if isinstance(stmt, list):
                out.extend(stmt)
            else:
                out.append(stmt)
        return out

    # -- statements ------------------------------------------------------------------------
    def statement(self, node: Tree, *, last: bool = True) -> Stmt | list[Stmt]:
        kind = str(node.data)
        kids = node.children
        pos = self.pos(node)
        simple = {"else_head": Else, "endif": EndIf, "endwhile": EndWhile, "return": Return, "pmatch": Pmatch,
                  "percent_query": PercentQuery}
        if kind in simple:
            return simple[kind](pos)
        if kind == "cs_select":
            return CsSelect(pos, self.numbered(kids[0], "coordinate system &n", CS_RANGE, pos))
        if kind == "motor_select":
            return MotorSelect(pos, self.numbered(kids[0], "motor #n", MOTOR_RANGE, pos))
        if kind == "motor_def":
            return self.motor_def(pos, kids)
        if kind == "motor_query":
            return MotorQuery(pos, _range(_int(kids[0]), "motor #n", MOTOR_RANGE, pos))
        if kind == "undefine":
            return Undefine(pos, kids[1] is not None)
        if kind == "open_buffer":
            return self.open_buffer(pos, kids)
        if kind == "open_rotary":
            return OpenBuffer(pos, "ROTARY", 0, kids[1] is not None)
        if kind == "close_buffer":
            return Close(pos, kids[1] is not None)
        if kind == "clear_buffer":
            return Other(pos, "CLEAR", f"CLEAR {kids[1]}") if kids[1] is not None else Clear(pos)
        if kind == "p0_assign":
            literal: Expr = Num(arith.literal(str(kids[1]), where=str(pos)))
            if kids[0] is not None and str(kids[0]) == "-":
                literal = Neg(literal)
            return Assign(pos, Var("P", 0, pos), literal)
        if kind == "begin":
            return Begin(pos, self.numbered(kids[0], "program number (Bn; B0: the rotary buffer)", BEGIN_RANGE, pos))
        if kind == "cs_command":
            return CsCommand(pos, str(kids[0]).upper())
        if kind == "percent":
            override = self.data(kids[1])
            number = constant(override)
            if number is not None and number < 0:
                raise pos.error(f"%{number}: the feedrate override is not allowed below 0")
            return Percent(pos, override)
        if kind in ("assign", "range_assign"):
            return self.assign(pos, kind, kids)
        if kind == "query":
            return Query(pos, self.var(kids[0]))
        if kind == "range_query":
            first, count, step, var_kind = self.var_range(kids[0])
            return RangeQuery(pos, var_kind, first, count, step)
        if kind == "mdef":
            return self.mdef(pos, kids)
        if kind == "mdef_query":
            return MDefQuery(pos, self.number(kids[0]))
        if kind == "plc_control":
            return self.plc_control(pos, kids)
        if kind == "jog":
            jog = re.sub(r"\s", "", str(kids[0])).upper()
            return Jog(pos, jog, self.data(kids[1]) if kids[1] is not None else None)
        if kind == "motor_report":
            return MotorReport(pos, str(kids[0]).upper())
        if kind == "open_loop":
            return OpenLoop(pos, self.data(kids[1]))
        if kind == "axis_set":
            return AxisSet(pos, str(kids[0]).upper(), self.data(kids[1]))
        if kind == "control_char":
            return Control(pos, self.control(kids[0]))
        if kind == "frax":
            return Frax(pos, str(kids[0]).upper(), tuple(str(k).upper() for k in kids[1:] if k is not None))
        if kind == "home_cmd":
            motors = self.plc_numbers(kids[1], "motor of HOME", MOTOR_RANGE, pos) if kids[1] is not None else ()
            return Home(pos, str(kids[0]).upper(), motors)
        if kind in ("other_online", "other_program"):
            text = " ".join(str(k).strip() for k in kids if k is not None)
            if isinstance(kids[0], Token) and kids[0].type == "PORT_SELECT":  # ##n: motor group; @n: card
                return Other(pos, "##" if text.startswith("##") else "@", re.sub(r"\s", "", text).upper())
            return Other(pos, str(kids[0]).upper(), text)
        if kind == "label":
            return Label(pos, _range(_int(kids[0]), "label N", LABEL_RANGE, pos))
        if kind == "mod_assign":
            var = self.var(kids[0])
            return Assign(pos, var, self.expr(kids[2]), str(kids[1]))
        if kind == "move":
            return self.move(pos, kids)
        if kind == "mode":
            return Mode(pos, _MODES[str(kids[0]).upper()])
        if kind == "modal_axes":
            return Mode(pos, str(kids[0]).upper(), tuple(str(k).upper() for k in kids[1:]))
        if kind == "pvt":
            return Pvt(pos, self.data(kids[1]))
        if kind == "param":
            return Param(pos, str(kids[0]).upper(), self.data(kids[1]))
        if kind == "dwell":
            return Dwell(pos, self.data(kids[0]))
        if kind == "delay":
            return Delay(pos, self.data(kids[0]))
        if kind in ("if_head", "while_head"):
            cls = If if kind == "if_head" else While
            return cls(pos, self.cond(kids[0]), not last)
        if kind == "cont":
            return Cont(pos, str(kids[0]).upper(), self.cond(kids[1]))
        if kind in ("goto", "gosub"):
            return self.jump(pos, kind, kids[0])
        if kind == "call":
            return self.call(pos, kids)
        if kind == "cmd":
            return self.cmd(pos, kids[0])
        if kind == "send":
            port = str(kids[0]).upper()[4:] or "S"
            token = kids[1]
            assert isinstance(token, Token)
            if token.type == "STRING":
                return Send(pos, port, str(token)[1:-1])
            return Send(pos, port, "", self.control(token))
        if kind == "display_text":
            return Display(pos, str(kids[1])[1:-1], position=_int(kids[0]) if kids[0] is not None else 0)
        if kind == "display_var":
            return Display(pos, None, self.var(kids[3]), _int(kids[0]), _int(kids[1]), _int(kids[2]))
        if kind == "address_cmd":
            cs = motor = None
            for item in kids:
                if item.data == "address_cs":
                    cs = self.numbered(item.children[0], "coordinate system of ADDRESS", CS_RANGE, pos)
                else:
                    motor = self.numbered(item.children[0], "motor of ADDRESS", MOTOR_RANGE, pos)
            return Address(pos, cs, motor)
        if kind == "normal":
            return Normal(pos, tuple(self.centre(k) for k in kids))
        if kind == "code_call":
            return CodeCall(pos, str(kids[0]).upper(), self.data(kids[1]))
        if kind == "mcode":
            return CodeCall(pos, "M", Num(self.number(kids[0])))
        raise pos.error(f"statement {kind!r} is not supported")  # the grammar has no other

    def numbered(self, node: Tree, name: str, bounds: tuple[int, int], pos: Pos) -> Expr:
        """A number that may be computed (``&(P1)``): a constant is checked against ``bounds`` now."""
        expr = self.data(node)
        value = constant(expr)
        if value is not None:
            if value != int(value):
                raise pos.error(f"{name} = {value} is not allowed (allowed: integers {bounds[0]}..{bounds[1]})")
            _range(int(value), name, bounds, pos)
        return expr

    def open_buffer(self, pos: Pos, kids: list) -> OpenBuffer:
        word = str(kids[0]).upper()
        kind = {"PROGRAM": "PROG", "PROG": "PROG", "PLC": "PLC", "PLCC": "PLC", "FORWARD": "FORWARD",
                "FWD": "FORWARD", "INVERSE": "INVERSE", "INV": "INVERSE"}[word]
        number = kids[1]
        clear = kids[2] is not None
        if kind in ("FORWARD", "INVERSE"):
            cs = _range(_int(number), f"coordinate system of OPEN {kind}", CS_RANGE, pos) if number is not None else 0
            return OpenBuffer(pos, kind, cs, clear)
        if number is None:
            raise pos.error(f"OPEN {kind} needs a number")
        bounds = PLC_RANGE if kind == "PLC" else PROG_RANGE
        return OpenBuffer(pos, kind, _range(_int(number), f"{kind} number", bounds, pos), clear)

    def motor_def(self, pos: Pos, kids: list) -> MotorDef | MotorKinematic:
        motor = _range(_int(kids[0]), "motor #n", MOTOR_RANGE, pos)
        definition = kids[1]
        if definition.data == "axis_inverse":
            return MotorKinematic(pos, motor, True)
        if definition.data == "axis_null":
            if arith.literal(str(definition.children[0])) != 0:
                raise pos.error(f"#{motor}->{definition.children[0]}: a constant alone must be 0 (#n->0: the motor "
                                "is assigned to no axis)")
            return MotorKinematic(pos, motor, False)
        parts = definition.children
        sign = -1 if parts[0] is not None and str(parts[0]) == "-" else 1
        terms: list[tuple[Fraction, str]] = []
        offset = Fraction(0)
        index = 1
        while index < len(parts):
            part = parts[index]
            if isinstance(part, Tree):
                scale_token, axis = part.children
                scale = Fraction(arith.literal(str(scale_token), where=str(pos))) if scale_token is not None \
                    else Fraction(1)
                axis_name = str(axis).upper()
                if any(a == axis_name for _c, a in terms):
                    raise pos.error(f"#{motor}->...: axis {axis_name} appears twice in one definition")
                terms.append((sign * scale, axis_name))
                index += 1
            elif part is None:
                index += 1
            elif part.type == "SIGN":
                sign = -1 if str(part) == "-" else 1
                index += 1
            else:  # the constant offset
                offset = sign * Fraction(arith.literal(str(part), where=str(pos)))
                index += 1
        if all(c == 0 for c, _a in terms):
            raise pos.error(f"#{motor}->0{terms[0][1]}: the scale of a motor definition must not be 0")
        return MotorDef(pos, motor, tuple(terms), offset)

    def var_range(self, node: Tree) -> tuple[int, int, int, str]:
        token = node.children[0]
        kind, first = str(token)[0].upper(), int(str(token)[1:])
        pos = self.pos(token)
        _range(first, f"{kind}-variable number", (0, VAR_LAST), pos)
        if node.data == "var_span":
            last = _int(node.children[1])
            _range(last, f"last {kind}-variable of the range", (first, VAR_LAST), pos)
            return first, last - first + 1, 1, kind
        count = _int(node.children[1])
        step = _int(node.children[2]) if node.children[2] is not None else 1
        if count < 1 or step < 1:
            raise pos.error(f"{kind}{first},{count},{step}: count and increment must be at least 1")
        last = first + (count - 1) * step
        _range(last, f"last {kind}-variable of {kind}{first},{count},{step}", (0, VAR_LAST), pos)
        return first, count, step, kind

    def assign(self, pos: Pos, kind: str, kids: list) -> Assign | RangeAssign:
        value = kids[1]
        expr = None if isinstance(value, Token) and value.type == "DEFAULT" else self.expr(value)
        if kind == "range_assign":
            first, count, step, var_kind = self.var_range(kids[0])
            if expr is None and var_kind != "I":
                raise pos.error(f"{var_kind}{first}..=*: only I-variables have a default value")
            number = constant(expr) if expr is not None else None
            if var_kind == "I" and number is not None:
                for n in range(first, first + count * step, step):
                    ivartable.check(n, number, where=str(pos))
            return RangeAssign(pos, var_kind, first, count, step, expr)
        var = self.var(kids[0])
        if expr is None and var.kind != "I":
            raise pos.error(f"{var}=*: only I-variables have a default value")
        if isinstance(var, Var) and var.kind == "I" and expr is not None:
            number = constant(expr)
            if number is not None:
                ivartable.check(var.number, number, where=str(pos))
        return Assign(pos, var, expr)

    def mdef(self, pos: Pos, kids: list) -> MDefine:
        head = kids[0]
        if isinstance(head, Tree):  # Mfirst..last
            first = self.number(head.children[0])
            last = _range(_int(head.children[1]), "last M-variable of the range", (first, VAR_LAST), pos)
        else:
            first = self.number(head)
            last = None
        return MDefine(pos, first, self.mtarget(pos, first, kids[1]), last)

    def mtarget(self, pos: Pos, number: int, target: Tree) -> MTarget:
        if target.data == "mself":
            return None
        if target.data == "mwide":
            return MWide(re.sub(r"\s|:", "", str(target.children[0])).upper(), self.address(pos, number,
                                                                                             target.children[1]))
        if target.data == "mthumb":
            return MThumb(re.sub(r"\s|:", "", str(target.children[0])).upper(),
                          tuple(_int(k) for k in target.children[1:]))
        space, address, offset, width, fmt = target.children
        address_value = self.address(pos, number, address)
        offset_value = _int(offset) if offset is not None else 0
        width_value = _int(width) if width is not None else (24 if offset is None else 1)
        if not 0 <= offset_value <= 23:
            raise pos.error(f"M{number} bit offset = {offset_value} is not allowed (allowed: 0..23)")
        if not 1 <= width_value <= 24 - offset_value:
            raise pos.error(f"M{number} width = {width_value} is not allowed (allowed: 1..{24 - offset_value}: "
                            "offset + width <= 24 bits)")
        signed = fmt is not None and str(fmt).upper() == "S"
        return MWord(str(space)[0].upper(), address_value, offset_value, width_value, signed)

    def address(self, pos: Pos, number: int, token: object) -> int:
        text = str(token)
        value = int(text[1:], 16) if text.startswith("$") else int(text)
        if not 0 <= value <= ADDRESS_LAST:
            raise pos.error(f"M{number} address = {text} is not allowed (allowed: $000000..$FFFFFF)")
        return value

    def plc_numbers(self, node: Tree, name: str, bounds: tuple[int, int], pos: Pos) -> tuple[int, ...]:
        numbers: list[int] = []
        for item in node.children:
            first = _range(_int(item.children[0]), name, bounds, pos)
            last = _range(_int(item.children[1]), name, (first, bounds[1]), pos) if item.children[1] is not None \
                else first
            numbers.extend(range(first, last + 1))
        return tuple(numbers)

    def plc_control(self, pos: Pos, kids: list) -> PlcControl:
        verb = {"ENA": "ENABLE", "DIS": "DISABLE"}.get(str(kids[0]).upper(), str(kids[0]).upper())
        compiled = str(kids[1]).upper() == "PLCC"
        return PlcControl(pos, verb, compiled, self.plc_numbers(kids[2], "PLC number", PLC_RANGE, pos))

    def control(self, token: object) -> str:
        text = str(token)
        return text[1].upper() if text.startswith("^") else _CONTROL_NAMES.get(text, "?")

    def move(self, pos: Pos, kids: list) -> MoveStmt:
        words: list[AxisWord] = []
        centre: list[tuple[str, Expr]] = []
        radius: Expr | None = None
        for item in kids:
            item_pos = self.pos(item)
            if item.data in ("move_word", "trigger_word"):
                axis = str(item.children[0]).upper()
                if any(w.axis == axis for w in words):
                    raise item_pos.error(f"axis {axis} appears twice in one move")
                value = self.data(item.children[1])
                extra = self.data(item.children[2]) if len(item.children) > 2 and item.children[2] is not None \
                    else None
                if item.data == "trigger_word":
                    words.append(AxisWord(item_pos, axis, value, trigger=extra))
                else:
                    words.append(AxisWord(item_pos, axis, value, velocity=extra))
            elif item.data == "radius":
                radius = self.data(item.children[1])
            else:
                centre.append(self.centre(item))
        return MoveStmt(words[0].pos, tuple(words), tuple(centre), radius)

    def centre(self, item: Tree) -> tuple[str, Expr]:
        if item.data == "center_ivar":
            text = str(item.children[0])
            return "I", Num(arith.literal(text[1:], where=str(self.pos(item))))
        if item.data == "radius":
            return "R", self.data(item.children[1])
        return str(item.children[0]).upper(), self.data(item.children[1])

    def jump(self, pos: Pos, kind: str, node: Tree) -> Goto | Gosub:
        expr = self.data(node)
        value = constant(expr)
        cls = Goto if kind == "goto" else Gosub
        if value is None:
            return cls(pos, None, expr)
        if value != int(value):
            raise pos.error(f"{cls.__name__.upper()} {value}: a label is a whole number")
        return cls(pos, _range(int(value), f"label of {cls.__name__.upper()}", LABEL_RANGE, pos))

    def call(self, pos: Pos, kids: list) -> Call:
        value = constant(self.data(kids[0]))
        if value is None:
            raise pos.error("CALL takes a constant program number (CALL n or CALL n.m)")
        program = _range(int(value), "program of CALL", PROG_RANGE, pos)
        fraction = Fraction(value) - program
        label = int(fraction * 100000) if fraction else None
        args: list[tuple[str, Expr]] = []
        if kids[1] is not None:
            items = kids[1].children
            index = 0
            while index < len(items):
                item = items[index]
                if item.type == "IVAR":
                    args.append(("I", Num(int(str(item)[1:]))))
                    index += 1
                else:
                    args.append((str(item).upper(), self.data(items[index + 1])))
                    index += 2
        return Call(pos, program, label, tuple(args))

    def cmd(self, pos: Pos, token: object) -> Cmd:
        assert isinstance(token, Token)
        if token.type == "CTRL":
            return Cmd(pos, str(token), (), self.control(token))
        text = str(token)[1:-1]
        start = self.pos(token).column + 1
        commands = parse_line(text, context="online", source=self.source, line=self.line_no, column=start)
        for command in commands:
            if isinstance(command, OpenBuffer | Close):
                raise command.pos.error("OPEN and CLOSE cannot be issued from a program")
        return Cmd(pos, text, tuple(commands))

    # -- expressions -----------------------------------------------------------------------
    def number(self, node: Tree | Token) -> int:
        """The number of a directly named variable (``M103``), checked."""
        var = self.var(node)
        assert isinstance(var, Var)
        return var.number

    def var(self, node: Tree | Token) -> Target:
        if isinstance(node, Tree) and len(node.children) == 2:  # P(expr)
            token = node.children[0]
            assert isinstance(token, Token)
            return IndVar(str(token).upper(), self.expr(node.children[1]), self.pos(token))
        token = node.children[0] if isinstance(node, Tree) else node
        assert isinstance(token, Token)
        text = str(token)
        kind, number = text[0].upper(), int(text[1:])
        pos = self.pos(token)
        _range(number, f"{kind}-variable number", (0, VAR_LAST), pos)
        return Var(kind, number, pos)

    def data(self, node: Tree | Token) -> Expr:
        """``{data}``: a signed constant or variable, or a parenthesised expression."""
        if isinstance(node, Tree) and node.data == "data":
            sign, value = node.children
            expr = self.expr(value)
            return Neg(expr) if sign is not None and str(sign) == "-" else expr
        return self.expr(node)

    def expr(self, node: Tree | Token) -> Expr:
        if isinstance(node, Token):  # a bare token: a number
            return Num(arith.literal(str(node), where=str(self.pos(node))))
        kind = str(node.data)
        kids = node.children
        if kind in ("number", "hexnumber"):
            token = kids[0]
            return Num(arith.literal(str(token), where=str(self.pos(token))))
        if kind == "address_of":
            text = str(kids[0])
            target = int(text[2:])
            pos = self.pos(kids[0])
            address = ivartable.address_of(target)
            if address is None:
                raise pos.error(f"{text} = address of I{target} is not allowed "
                                f"(allowed: @I{ivartable.ECT_FIRST}..@I{ivartable.ECT_LAST}, conversion-table lines)")
            return Num(address)
        if kind == "var":
            return self.var(node)
        if kind == "data":
            return self.data(node)
        if kind == "neg":
            return Neg(self.expr(kids[0]))
        if kind in ("sum", "product"):
            rest = tuple((str(kids[i]), self.expr(kids[i + 1])) for i in range(1, len(kids), 2))
            return Ops(self.expr(kids[0]), rest, self.pos(node))
        if kind == "func":
            return Func(str(kids[0]).upper(), self.expr(kids[1]), self.pos(node))
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


_MODES = {"LINEAR": "LINEAR", "LIN": "LINEAR", "RAPID": "RAPID", "RPD": "RAPID", "CIRCLE1": "CIRCLE1",
          "CIR1": "CIRCLE1", "CIRCLE2": "CIRCLE2", "CIR2": "CIRCLE2", "SPLINE1": "SPLINE1", "SPL1": "SPLINE1",
          "ABS": "ABS", "INC": "INC"}
