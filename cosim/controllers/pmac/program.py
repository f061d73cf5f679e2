"""PMAC text files: online commands and program buffers, compiled into flat code before anything runs.

A PMAC file (what users download to the controller) mixes online commands (I-variable
assignments, M-variable definitions, ``&1``, ``#1->1000X``, ``ENABLE PLC 1``, ``&1 B1 R``) with
buffers: ``OPEN PROG n``, ``OPEN PLC n``, ``OPEN FORWARD``, ``OPEN INVERSE`` [``CLEAR``] ``... CLOSE``,
on many lines or on one. :func:`parse_text` reads a whole file -- after the download preprocessor
(:mod:`.preprocess`) -- into :class:`PmacText`: its online statements and buffers in file order,
each buffer compiled into :class:`Code`, a flat list of statements and jumps (``IF``/``ELSE``/
``ENDIF``, ``WHILE``/``ENDWHILE``, ``GOTO``, ``GOSUB``) that the interpreter runs with a program
counter, so neither parsing nor running recurses over the program's structure.

Rules (each broken one is an error naming ``file:line:column``, before anything runs):

* a buffer ends with ``CLOSE`` (the file may not end inside one); text after ``CLOSE`` on its line
  is online commands again;
* ``IF``/``WHILE`` blocks close with ``ENDIF``/``ENDWHILE`` inside their buffer, nested at most
  :data:`MAX_BLOCKS` deep; an ``IF (cond)`` or ``WHILE (cond)`` followed by statements on its
  line governs the rest of that line only (a one-line ``IF`` may be followed by a one-line
  ``ELSE`` at the start of the next line); a line starting with ``AND (cond)`` or ``OR (cond)``
  continues the condition of the ``IF``/``WHILE`` that ended the line above (``AND`` binding
  tighter than ``OR``, as within one line);
* ``GOTO n`` and ``GOSUB n`` with a constant jump to a label ``Nn`` (or ``On``) of the same buffer;
  ``GOTO (expression)`` is resolved when it runs;
* motion statements (moves, ``LINEAR`` ... ``PVT``, ``F``, ``TA``, ``TS``, ``TM``, ``DWELL``,
  ``DELAY``, ``NORMAL``, G/M/T/D codes) and ``CALL`` are refused in a PLC and in kinematic programs.

Line ends: each of Python's line boundaries ends a line (LF, CR LF, CR, and also VT, FF, FS, GS,
RS, NEL, LS, PS); a leading byte-order mark is ignored.
"""

from __future__ import annotations

import re
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from cosim.controllers.pmac.nodes import (
    MOTION_ONLY,
    Call,
    Clear,
    Close,
    Cmd,
    CodeCall,
    Compare,
    Cond,
    Cont,
    Else,
    EndIf,
    EndWhile,
    Expr,
    Func,
    Gosub,
    Goto,
    If,
    IndVar,
    Label,
    Logic,
    MoveStmt,
    Neg,
    OpenBuffer,
    Ops,
    Pos,
    Stmt,
    Var,
    While,
)
from cosim.controllers.pmac.preprocess import Line, preprocess
from cosim.controllers.pmac.syntax import parse_line

__all__ = ["MAX_BLOCKS", "Buffer", "Code", "Jump", "JumpUnless", "MoveStmt", "PmacText", "Sub", "compile_buffer",
           "parse_text"]

#: Deepest nesting of IF/WHILE blocks (block and one-line ones together) in a buffer.
MAX_BLOCKS = 32
#: Label of PROG 1000..1003 that a G, M, T or D code calls: N(value * 1000).
CODE_PROGRAMS = {"G": 1000, "M": 1001, "T": 1002, "D": 1003}

_OPEN_HEAD = re.compile(r"\s*OPEN\s*(?:(?:PROGRAM|PROG|PLCC|PLC|FORWARD|FWD|INVERSE|INV)(?![A-Z])\s*(?:\d+)?"
                        r"|(?:BINARY\s+)?(?:ROTARY|ROT)(?![A-Z]))\s*(?:CLEAR(?![A-Z]))?", re.IGNORECASE)
_ROTARY_NUMBER = re.compile(r"\s*([0-9$][0-9A-F]*)", re.IGNORECASE)
_CS_PREFIX = re.compile(r"(?:\s*&\s*[0-9]+)*")
_CLOSE_WORD = re.compile(r"(?<![A-Z0-9_])CLOSE(?![A-Z0-9_])", re.IGNORECASE)


@dataclass(eq=False)
class JumpUnless:
    """Go to ``target`` unless ``cond`` holds (the test of an IF or WHILE)."""

    cond: Cond
    target: int
    pos: Pos


@dataclass(eq=False)
class Jump:
    """Go to ``target``; ``back`` for a jump to an earlier statement (a loop)."""

    target: int
    back: bool
    pos: Pos


@dataclass(frozen=True)
class Sub:
    """GOSUB: go to ``target``, come back at RETURN."""

    target: int
    pos: Pos


Instr = Stmt | JumpUnless | Jump | Sub


@dataclass(frozen=True, eq=False)
class Code:
    """A compiled buffer: ``PROG``, ``PLC``, ``FORWARD`` or ``INVERSE`` ``number``, its instructions and labels."""

    kind: str
    number: int
    instrs: tuple[Instr, ...]
    labels: dict[int, int]
    pos: Pos

    @property
    def title(self) -> str:
        """``PROG 1``, ``PLC 2``, ``FORWARD 1``."""
        return f"{self.kind} {self.number}"

    def statements(self) -> Iterator[Stmt]:
        """Every statement, including those inside ``CMD`` strings."""
        for instr in self.instrs:
            if isinstance(instr, Stmt):
                yield instr
                if isinstance(instr, Cmd):
                    yield from instr.commands

    def variables(self) -> Iterator[Var]:
        """Every variable the code names directly (not those an indirect ``P(expr)`` computes)."""
        for instr in self.instrs:
            if isinstance(instr, JumpUnless):
                yield from cond_variables(instr.cond)
            elif isinstance(instr, Stmt):
                yield from stmt_variables(instr)


def expr_variables(expr: Expr) -> Iterator[Var]:
    """Variables read by ``expr`` (and the indices of indirect ones)."""
    stack: list[Expr] = [expr]
    while stack:
        e = stack.pop()
        if isinstance(e, Var):
            yield e
        elif isinstance(e, IndVar):
            stack.append(e.index)
        elif isinstance(e, Neg | Func):
            stack.append(e.arg)
        elif isinstance(e, Ops):
            stack.append(e.first)
            stack.extend(x for _, x in e.rest)


def cond_variables(cond: Cond) -> Iterator[Var]:
    """Variables read by a condition."""
    stack: list[Cond] = [cond]
    while stack:
        c = stack.pop()
        if isinstance(c, Compare):
            yield from expr_variables(c.left)
            yield from expr_variables(c.right)
        elif isinstance(c, Logic):
            stack.extend(c.items)


def stmt_variables(stmt: Stmt) -> Iterator[Var]:
    """Variables a statement reads or writes (and those of the commands of a ``CMD``)."""
    if isinstance(stmt, Cmd):
        for command in stmt.commands:
            yield from stmt_variables(command)
        return
    if isinstance(stmt, MoveStmt):
        for word in stmt.axes:
            yield from expr_variables(word.expr)
        return
    value = getattr(stmt, "var", None)
    if isinstance(value, Var):
        yield value
    elif isinstance(value, IndVar):
        yield from expr_variables(value.index)
    expr = getattr(stmt, "expr", None)
    if expr is not None:
        yield from expr_variables(expr)


@dataclass(frozen=True)
class Buffer:
    """One ``OPEN ... CLOSE`` of a file: its lines and their compiled code."""

    kind: str
    number: int
    clear: bool
    lines: tuple[tuple[Stmt, ...], ...]
    pos: Pos
    code: Code


@dataclass(frozen=True)
class PmacText:
    """A parsed PMAC file: online statements and buffers, in file order."""

    source: str
    items: tuple[Stmt | Buffer, ...]

    def buffers(self) -> list[Buffer]:
        """The file's buffers."""
        return [item for item in self.items if isinstance(item, Buffer)]


@dataclass
class _Open:
    stmt: OpenBuffer
    clear: bool
    lines: list[tuple[Stmt, ...]] = field(default_factory=list)


class _Reader:
    """The line-by-line reader of :func:`parse_text`."""

    def __init__(self) -> None:
        self.items: list[Stmt | Buffer] = []
        self.current: _Open | None = None

    def online(self, text: str, line: Line, column: int = 1) -> None:
        head = _OPEN_HEAD.match(text)
        if head is not None:  # OPEN ... [CLEAR] then, maybe, the buffer's statements on the same line
            statements = parse_line(text[:head.end()], context="online", source=line.source, line=line.line,
                                    column=column)
            opened = statements[0] if statements else None
            if len(statements) != 1 or not isinstance(opened, OpenBuffer):  # the grammar read it otherwise
                raise (statements[-1].pos if statements else line.pos(column)).error(
                    f"{text[:head.end()].strip()!r} is not an OPEN of a buffer")
            rest = text[head.end():]
            number = _ROTARY_NUMBER.match(rest) if opened.kind == "ROTARY" else None
            if number is not None:
                raise line.pos(column + head.end() + number.start(1)).error(
                    f"OPEN ROTARY {number.group(1)}: a rotary buffer takes no number (OPEN ROTARY opens every "
                    "coordinate system's rotary buffer; &n chooses the one that takes the lines, &n DEFINE ROT n "
                    "gives its size)")
            self.current = _Open(opened, opened.clear)
            if rest.strip():
                self.program(rest, line, column + head.end())
            return
        for stmt in parse_line(text, context="online", source=line.source, line=line.line, column=column):
            if isinstance(stmt, Clear):
                raise stmt.pos.error("CLEAR outside a buffer: write OPEN PROG n CLEAR (or OPEN PLC n CLEAR)")
            if not isinstance(stmt, Close):  # CLOSE with nothing open: a no-op, as files often start with it
                self.items.append(stmt)

    def program(self, text: str, line: Line, column: int = 1) -> None:
        opened = self.current
        assert opened is not None
        select = _CS_PREFIX.match(text) if opened.stmt.kind == "ROTARY" else None
        if select is not None and select.end() > 0:  # &n X10 Y10: the line goes to &n's rotary buffer
            parse_line(text[:select.end()], context="online", source=line.source, line=line.line, column=column)
            text, column = text[select.end():], column + select.end()
        close = _close_in(text)
        before = text if close is None else text[:close]
        statements = parse_line(before, context="program", source=line.source, line=line.line, column=column) \
            if before.strip() else []
        for index, stmt in enumerate(statements):
            if isinstance(stmt, Clear):
                if index > 0 or opened.lines:
                    raise stmt.pos.error("CLEAR must come first in a buffer (right after OPEN)")
                opened.clear = True
        body = [s for s in statements if not isinstance(s, Close | Clear)]
        if body:
            opened.lines.append(tuple(body))
        if close is None and not any(isinstance(s, Close) for s in statements):
            return
        self.finish(opened)
        if close is not None:
            after = text[close + len("CLOSE"):]
            if after.strip():
                self.online(after, line, column + close + len("CLOSE"))

    def finish(self, opened: _Open) -> None:
        stmt = opened.stmt
        code = compile_buffer(stmt.kind, stmt.number, opened.lines, pos=stmt.pos)
        self.items.append(Buffer(stmt.kind, stmt.number, opened.clear, tuple(opened.lines), stmt.pos, code))
        self.current = None


def _close_in(text: str) -> int | None:
    """Where a ``CLOSE`` keyword starts in ``text`` (outside strings), or None."""
    for match in _CLOSE_WORD.finditer(text):
        if text[:match.start()].count('"') % 2 == 0:
            return match.start()
    return None


def parse_text(text: str, *, source: str = "program.pmc", path: Path | None = None,
               defines: Mapping[str, str] | None = None, search: Sequence[Path] = ()) -> PmacText:
    """Preprocess, parse and compile a PMAC file (see the module docstring for the rules).

    Parameters
    ----------
    text : str
        The file's content.
    source : str
        Its name in messages.
    path : Path, optional
        Where it is (for ``#include``).
    defines : mapping, optional
        Values of ``$(NAME)`` template macros.
    search : sequence of Path
        More folders for ``#include``.

    Raises
    ------
    ConfigurationError
        ``source:line:column: ...`` for the first thing wrong.
    """
    reader = _Reader()
    for line in preprocess(text, source=source, path=path, defines=defines, search=search):
        if not line.text.strip():
            continue
        if reader.current is None:
            reader.online(line.text, line)
        else:
            reader.program(line.text, line)
    if reader.current is not None:
        opened = reader.current.stmt
        raise opened.pos.error(f"OPEN {opened.kind} {opened.number} has no CLOSE (the file ends inside the buffer)")
    return PmacText(source, tuple(reader.items))


def keyword(stmt: Stmt) -> str:
    """How a statement is written, for messages (``LINEAR``, ``TA``, ``DWELL``, ``a move``)."""
    if isinstance(stmt, MoveStmt):
        return "a move"
    for name in ("mode", "param"):
        value = getattr(stmt, name, None)
        if isinstance(value, str):
            return value
    if isinstance(stmt, CodeCall):
        return f"a {stmt.letter}-code"
    return stmt.name


@dataclass
class _Frame:
    kind: str  # IF, WHILE, ELSE (a one-line ELSE)
    stmt: Stmt
    test: JumpUnless | None = None
    start: int = 0
    skip: Jump | None = None
    terms: list[tuple[str, Cond]] = field(default_factory=list)


@dataclass
class _Compiler:
    kind: str
    number: int
    code: list[Instr] = field(default_factory=list)
    labels: dict[int, int] = field(default_factory=dict)
    blocks: list[_Frame] = field(default_factory=list)
    jumps: list[tuple[int, Goto | Gosub]] = field(default_factory=list)
    last_test: _Frame | None = None

    @property
    def title(self) -> str:
        return "the rotary buffer" if self.kind == "ROTARY" else f"{self.kind} {self.number}"

    def depth_check(self, stmt: Stmt, inline: list[_Frame]) -> None:
        if len(self.blocks) + len(inline) >= MAX_BLOCKS:
            raise stmt.pos.error(f"IF/WHILE nested deeper than {MAX_BLOCKS} levels")

    def line(self, statements: Sequence[Stmt], after_inline_if: JumpUnless | None) -> JumpUnless | None:
        """Compile one line; returns the test of a one-line IF it ended with (for a following ELSE)."""
        inline: list[_Frame] = []
        continued = self.last_test
        self.last_test = None
        for index, stmt in enumerate(statements):
            if self.kind not in ("PROG", "ROTARY") and isinstance(stmt, (*MOTION_ONLY, Call)):
                raise stmt.pos.error(f"{keyword(stmt)} is a motion-program statement, not allowed in {self.title}")
            if isinstance(stmt, Cont):
                if index != 0 or continued is None:
                    raise stmt.pos.error(f"{stmt.op} (condition) continues the condition of an IF or WHILE that ends "
                                         "the line above; there is none")
                self.continue_condition(continued, stmt)
                self.last_test = continued
                continue
            if isinstance(stmt, Label):
                if stmt.number in self.labels:
                    raise stmt.pos.error(f"label N{stmt.number} appears twice in {self.title}")
                self.labels[stmt.number] = len(self.code)
            elif isinstance(stmt, If | While):
                self.depth_check(stmt, inline)
                test = JumpUnless(stmt.cond, -1, stmt.pos)
                frame = _Frame("IF" if isinstance(stmt, If) else "WHILE", stmt, test, len(self.code),
                               terms=[("", stmt.cond)])
                self.code.append(test)
                (inline if stmt.inline else self.blocks).append(frame)
                if not stmt.inline and index == len(statements) - 1:
                    self.last_test = frame
            elif isinstance(stmt, Else):
                self.else_(stmt, index, after_inline_if, inline)
            elif isinstance(stmt, EndIf | EndWhile):
                self.end_block(stmt)
            elif isinstance(stmt, Goto | Gosub):
                if stmt.label is not None:
                    self.jumps.append((len(self.code), stmt))
                self.code.append(stmt)
            elif isinstance(stmt, CodeCall):
                self.code.append(stmt)
            else:
                self.code.append(stmt)
        ended_with_if = None
        for frame in reversed(inline):
            if frame.kind == "WHILE":
                self.code.append(Jump(frame.start, True, frame.stmt.pos))
            self.close(frame)
            ended_with_if = frame.test if frame.kind == "IF" and frame.skip is None else None
        return ended_with_if

    @staticmethod
    def continue_condition(frame: _Frame, stmt: Cont) -> None:
        """``AND``/``OR`` lines: the head's condition and each continued one, AND binding tighter than OR."""
        frame.terms.append((stmt.op, stmt.cond))
        groups: list[list[Cond]] = [[]]
        for op, cond in frame.terms:
            if op == "OR":
                groups.append([])
            groups[-1].append(cond)
        anded = [group[0] if len(group) == 1 else Logic("AND", tuple(group)) for group in groups]
        assert frame.test is not None
        frame.test.cond = anded[0] if len(anded) == 1 else Logic("OR", tuple(anded))

    def else_(self, stmt: Else, index: int, after_inline_if: JumpUnless | None, inline: list[_Frame]) -> None:
        skip = Jump(-1, False, stmt.pos)
        if inline and inline[-1].kind == "IF" and inline[-1].skip is None:  # IF (c) ... ELSE ... on one line
            frame = inline[-1]
            assert frame.test is not None
            self.code.append(skip)
            frame.test.target = len(self.code)
            frame.skip = skip
            return
        if index == 0 and after_inline_if is not None:
            self.code.append(skip)
            after_inline_if.target = len(self.code)
            inline.append(_Frame("ELSE", stmt, skip=skip))
            return
        block = self.blocks[-1] if self.blocks else None
        if block is None or block.kind != "IF" or block.skip is not None:
            raise stmt.pos.error("ELSE without IF")
        assert block.test is not None
        self.code.append(skip)
        block.test.target = len(self.code)
        block.skip = skip

    def end_block(self, stmt: EndIf | EndWhile) -> None:
        want = "IF" if isinstance(stmt, EndIf) else "WHILE"
        frame = self.blocks[-1] if self.blocks else None
        if frame is None or frame.kind != want:
            opened = f" (the open block is the {frame.kind} at {frame.stmt.pos})" if frame else ""
            raise stmt.pos.error(f"END{want} without {want}{opened}")
        self.blocks.pop()
        if want == "WHILE":
            self.code.append(Jump(frame.start, True, stmt.pos))
        self.close(frame)

    def close(self, frame: _Frame) -> None:
        if frame.skip is not None:
            frame.skip.target = len(self.code)
        elif frame.test is not None:
            frame.test.target = len(self.code)

    def finish(self, pos: Pos) -> Code:
        if self.blocks:
            frame = self.blocks[-1]
            raise frame.stmt.pos.error(f"{frame.kind} without END{frame.kind} in {self.title}")
        for index, jump in self.jumps:
            assert jump.label is not None
            target = self.labels.get(jump.label)
            if target is None:
                known = ", ".join(f"N{n}" for n in sorted(self.labels)) or "none"
                raise jump.pos.error(f"{jump.name} {jump.label} jumps into nothing: {self.title} has no label "
                                     f"N{jump.label} (its labels: {known})")
            self.code[index] = (Jump(target, target <= index, jump.pos) if isinstance(jump, Goto)
                                else Sub(target, jump.pos))
        return Code(self.kind, self.number, tuple(self.code), dict(self.labels), pos)


def _moves(line: tuple[Stmt, ...]) -> list[Stmt]:
    """The line with consecutive moves joined into one (``X10`` then ``Y5``: one move of X and Y)."""
    out: list[Stmt] = []
    for stmt in line:
        previous = out[-1] if out else None
        if (isinstance(stmt, MoveStmt) and isinstance(previous, MoveStmt) and not previous.centre
                and previous.radius is None):
            for word in stmt.axes:
                if any(w.axis == word.axis for w in previous.axes):
                    raise word.pos.error(f"axis {word.axis} appears twice in one move")
            out[-1] = MoveStmt(previous.pos, previous.axes + stmt.axes, stmt.centre, stmt.radius)
        else:
            out.append(stmt)
    return out


def compile_buffer(kind: str, number: int, lines: Sequence[tuple[Stmt, ...]], *, pos: Pos) -> Code:
    """Compile a buffer's lines into flat :class:`Code` (checks blocks, labels and jumps)."""
    compiler = _Compiler(kind, number)
    after_if: JumpUnless | None = None
    for line in lines:
        after_if = compiler.line(_moves(line), after_if)
    return compiler.finish(pos)
