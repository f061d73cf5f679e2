"""PMAC text files: online commands and program buffers, compiled into flat code before anything runs.

A PMAC file (what users download to the controller) mixes online commands (I-variable
assignments, M-variable definitions, ``&1``, ``#1->1000X``, ``ENABLE PLC 1``, ``&1 B1 R``) with
buffers: ``OPEN PROG n [CLEAR] ... CLOSE`` (a motion program) and ``OPEN PLC n [CLEAR] ... CLOSE``
(a PLC program). :func:`parse_text` reads a whole file into :class:`PmacText`: its online
statements and buffers in file order, each buffer compiled into :class:`Code`, a flat list of
statements and jumps (``IF``/``ELSE``/``ENDIF``, ``WHILE``/``ENDWHILE``, ``GOTO``, ``GOSUB``)
that the interpreter runs with a program counter, so neither parsing nor running recurses over
the program's structure.

Rules (each broken one is an error naming ``file:line:column``, before anything runs):

* a buffer ends with ``CLOSE`` (the file may not end inside one); ``OPEN ... [CLEAR]`` and
  ``CLOSE`` end their lines;
* ``IF``/``WHILE`` blocks close with ``ENDIF``/``ENDWHILE`` inside their buffer, nested at most
  :data:`MAX_BLOCKS` deep; an ``IF (cond)`` or ``WHILE (cond)`` followed by statements on its
  line governs the rest of that line only (a one-line ``IF`` may be followed by a one-line
  ``ELSE`` at the start of the next line);
* ``GOTO n`` and ``GOSUB n`` jump to a label ``Nn`` of the same buffer (a label that is not there
  is a jump into nothing);
* consecutive axis words on a line form one move, each axis at most once;
* motion statements (``LINEAR``, ``RAPID``, ``ABS``, ``INC``, ``F``, ``TA``, ``TS``, ``TM``, moves,
  ``DWELL``, ``DELAY``) and ``CALL`` are refused in a PLC.

Line ends: each of Python's line boundaries ends a line (LF, CR LF, CR, and also VT, FF, FS, GS,
RS, NEL, LS, PS); a leading byte-order mark is ignored.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field

from cosim.controllers.pmac.nodes import (
    MOTION_ONLY,
    AxisWord,
    Call,
    Clear,
    Close,
    Cmd,
    Compare,
    Cond,
    Else,
    EndIf,
    EndWhile,
    Expr,
    Func,
    Gosub,
    Goto,
    If,
    Label,
    Logic,
    Neg,
    OpenBuffer,
    Ops,
    Pos,
    Stmt,
    Var,
    While,
)
from cosim.controllers.pmac.statements import (
    parse_line,
)

#: Deepest nesting of IF/WHILE blocks (block and one-line ones together) in a buffer.
MAX_BLOCKS = 32


@dataclass(frozen=True)
class MoveStmt(Stmt):
    """A move: the consecutive axis words of a line (``X1000 Y500``)."""

    axes: tuple[AxisWord, ...]


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


@dataclass(frozen=True)
class Code:
    """A compiled buffer: ``PROG`` or ``PLC`` ``number``, its instructions and labels."""

    kind: str
    number: int
    instrs: tuple[Instr, ...]
    labels: dict[int, int]
    pos: Pos

    @property
    def title(self) -> str:
        """``PROG 1`` or ``PLC 2``."""
        return f"{self.kind} {self.number}"

    def statements(self) -> Iterator[Stmt]:
        """Every statement, including those inside ``CMD`` strings."""
        for instr in self.instrs:
            if isinstance(instr, Stmt):
                yield instr
                if isinstance(instr, Cmd):
                    yield from instr.commands

    def variables(self) -> Iterator[Var]:
        """Every variable the code reads or writes."""
        for instr in self.instrs:
            if isinstance(instr, JumpUnless):
                yield from cond_variables(instr.cond)
            elif isinstance(instr, Stmt):
                yield from stmt_variables(instr)


def expr_variables(expr: Expr) -> Iterator[Var]:
    """Variables read by ``expr``."""
    stack: list[Expr] = [expr]
    while stack:
        e = stack.pop()
        if isinstance(e, Var):
            yield e
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
    for name in ("var",):
        value = getattr(stmt, name, None)
        if isinstance(value, Var):
            yield value
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


def parse_text(text: str, *, source: str = "program.pmc") -> PmacText:
    """Parse and compile a PMAC file (see the module docstring for the rules).

    Raises
    ------
    ConfigurationError
        ``source:line:column: ...`` for the first thing wrong.
    """
    items: list[Stmt | Buffer] = []
    current: tuple[OpenBuffer, bool, list[tuple[Stmt, ...]]] | None = None
    for line_no, raw in enumerate(text.removeprefix("\ufeff").splitlines(), 1):
        if current is None:
            statements = parse_line(raw, context="online", source=source, line=line_no)
            for index, stmt in enumerate(statements):
                if isinstance(stmt, OpenBuffer):
                    rest = statements[index + 1:]
                    clear = bool(rest) and isinstance(rest[0], Clear)
                    if rest[clear:]:
                        raise rest[clear].pos.error(f"nothing may follow OPEN {stmt.kind} {stmt.number}"
                                                    f"{' CLEAR' if clear else ''} on its line: the buffer's "
                                                    "statements go on the lines after it")
                    current = (stmt, clear, [])
                    break
                if isinstance(stmt, Clear):
                    raise stmt.pos.error("CLEAR outside a buffer: write OPEN PROG n CLEAR (or OPEN PLC n CLEAR)")
                if not isinstance(stmt, Close):  # CLOSE with nothing open: a no-op, as files often start with it
                    items.append(stmt)
            continue
        statements = parse_line(raw, context="program", source=source, line=line_no)
        opened, clear, lines = current
        for index, stmt in enumerate(statements):
            if isinstance(stmt, Clear) and (index > 0 or lines):
                raise stmt.pos.error("CLEAR must come first in a buffer (right after OPEN)")
        clear = clear or any(isinstance(s, Clear) for s in statements)
        body = tuple(s for s in statements if not isinstance(s, Clear))
        close = next((i for i, s in enumerate(body) if isinstance(s, Close)), None)
        if close is None:
            if body:
                lines.append(body)
            current = (opened, clear, lines)
            continue
        if close != len(body) - 1:
            raise body[close + 1].pos.error("CLOSE must end its line")
        if body[:close]:
            lines.append(body[:close])
        code = compile_buffer(opened.kind, opened.number, lines, pos=opened.pos)
        items.append(Buffer(opened.kind, opened.number, clear, tuple(lines), opened.pos, code))
        current = None
    if current is not None:
        opened = current[0]
        raise opened.pos.error(f"OPEN {opened.kind} {opened.number} has no CLOSE (the file ends inside the buffer)")
    return PmacText(source, tuple(items))


def keyword(stmt: Stmt) -> str:
    """How a statement is written, for messages (``LINEAR``, ``TA``, ``DWELL``, ``a move``)."""
    if isinstance(stmt, MoveStmt | AxisWord):
        return "a move"
    for name in ("mode", "param"):
        value = getattr(stmt, name, None)
        if isinstance(value, str):
            return value
    return stmt.name


def _moves(line: tuple[Stmt, ...]) -> list[Stmt]:
    """The line with consecutive axis words joined into moves."""
    out: list[Stmt] = []
    words: list[AxisWord] = []

    def flush() -> None:
        if words:
            out.append(MoveStmt(words[0].pos, tuple(words)))
            words.clear()

    for stmt in line:
        if isinstance(stmt, AxisWord):
            if any(w.axis == stmt.axis for w in words):
                raise stmt.pos.error(f"axis {stmt.axis} appears twice in one move")
            words.append(stmt)
        else:
            flush()
            out.append(stmt)
    flush()
    return out


@dataclass
class _Frame:
    kind: str  # IF, WHILE, ELSE (a one-line ELSE)
    stmt: Stmt
    test: JumpUnless | None = None
    start: int = 0
    skip: Jump | None = None


@dataclass
class _Compiler:
    kind: str
    number: int
    code: list[Instr] = field(default_factory=list)
    labels: dict[int, int] = field(default_factory=dict)
    blocks: list[_Frame] = field(default_factory=list)
    jumps: list[tuple[int, Goto | Gosub]] = field(default_factory=list)

    @property
    def title(self) -> str:
        return f"{self.kind} {self.number}"

    def depth_check(self, stmt: Stmt, inline: list[_Frame]) -> None:
        if len(self.blocks) + len(inline) >= MAX_BLOCKS:
            raise stmt.pos.error(f"IF/WHILE nested deeper than {MAX_BLOCKS} levels")

    def line(self, statements: list[Stmt], after_inline_if: JumpUnless | None) -> JumpUnless | None:
        """Compile one line; returns the test of a one-line IF it ended with (for a following ELSE)."""
        inline: list[_Frame] = []
        for index, stmt in enumerate(statements):
            if self.kind == "PLC" and isinstance(stmt, (*MOTION_ONLY, MoveStmt, Call)):
                raise stmt.pos.error(f"{keyword(stmt)} is a motion-program statement, not allowed in {self.title}")
            if isinstance(stmt, Label):
                if stmt.number in self.labels:
                    raise stmt.pos.error(f"label N{stmt.number} appears twice in {self.title}")
                self.labels[stmt.number] = len(self.code)
            elif isinstance(stmt, If | While):
                self.depth_check(stmt, inline)
                test = JumpUnless(stmt.cond, -1, stmt.pos)
                frame = _Frame("IF" if isinstance(stmt, If) else "WHILE", stmt, test, len(self.code))
                self.code.append(test)
                (inline if stmt.inline else self.blocks).append(frame)
            elif isinstance(stmt, Else):
                self.else_(stmt, index, after_inline_if, inline)
            elif isinstance(stmt, EndIf | EndWhile):
                self.end_block(stmt)
            elif isinstance(stmt, Goto | Gosub):
                self.jumps.append((len(self.code), stmt))
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
            target = self.labels.get(jump.label)
            if target is None:
                known = ", ".join(f"N{n}" for n in sorted(self.labels)) or "none"
                raise jump.pos.error(f"{jump.name} {jump.label} jumps into nothing: {self.title} has no label "
                                     f"N{jump.label} (its labels: {known})")
            self.code[index] = (Jump(target, target <= index, jump.pos) if isinstance(jump, Goto)
                                else Sub(target, jump.pos))
        return Code(self.kind, self.number, tuple(self.code), dict(self.labels), pos)


def compile_buffer(kind: str, number: int, lines: list[tuple[Stmt, ...]] | tuple[tuple[Stmt, ...], ...], *,
                   pos: Pos) -> Code:
    """Compile a buffer's lines into :class:`Code` (raises naming the line and column)."""
    compiler = _Compiler(kind, number)
    after_inline_if = None
    for line in lines:
        after_inline_if = compiler.line(_moves(line), after_inline_if)
    return compiler.finish(pos)
