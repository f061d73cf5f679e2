"""One line of G-code text into its syntax tree: words, parameter settings, comments, an O-word.

:func:`parse_line` takes out spaces and lowers the case outside comments (as LinuxCNC does),
parses what is left with :data:`~.grammar.GRAMMAR` and returns a :class:`SourceLine`. Values stay
unevaluated (:data:`Expr` trees): parameters change between lines, so the interpreter evaluates
them when it runs the line. A number written in the text is an exact :class:`~fractions.Fraction`.

Every error is a :class:`GcodeSyntaxError` with the column (1-based) in the line as written.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from functools import lru_cache
from typing import Any, Union

from lark import Lark, Token, Transformer, v_args
from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken, VisitError

from cosim.controllers.grammars import lark_parser
from cosim.controllers.pokeys.gcode.grammar import GRAMMAR

Expr = Union["Num", "Param", "Neg", "Binary", "Func", "Exists"]


@dataclass(frozen=True, slots=True)
class Num:
    """A number as written (exact)."""

    value: Fraction


@dataclass(frozen=True, slots=True)
class Param:
    """A parameter's value: ``#12`` (index an expression) or ``#<name>`` (index a str, lower case)."""

    index: Expr | str


@dataclass(frozen=True, slots=True)
class Neg:
    """``-value``."""

    operand: Expr


@dataclass(frozen=True, slots=True)
class Binary:
    """``left op right`` (op lower case: ``+``, ``mod``, ``**``, ``eq``, ``and``, ...)."""

    op: str
    left: Expr
    right: Expr


@dataclass(frozen=True, slots=True)
class Func:
    """``name[arg]`` (``atan`` takes two: ``atan[y]/[x]``)."""

    name: str
    args: tuple[Expr, ...]


@dataclass(frozen=True, slots=True)
class Exists:
    """``exists[#<name>]``."""

    name: str


@dataclass(frozen=True, slots=True)
class Word:
    """A letter (upper case) and its value; ``column`` where the letter is written (1-based)."""

    letter: str
    expr: Expr
    column: int

    @property
    def literal(self) -> Fraction | None:
        """The value if it is a plain number (``X-2.5``), else None."""
        e = self.expr
        if isinstance(e, Num):
            return e.value
        if isinstance(e, Neg) and isinstance(e.operand, Num):
            return -e.operand.value
        return None


@dataclass(frozen=True, slots=True)
class Setting:
    """``#index = value`` (takes effect after the line)."""

    index: Expr | str
    expr: Expr
    column: int


@dataclass(frozen=True, slots=True)
class OWord:
    """An O-word: its label (``100``, ``<name>`` as a str, or an expression), keyword and bracketed arguments."""

    label: Expr | str
    keyword: str
    args: tuple[Expr, ...]
    column: int


@dataclass(frozen=True, slots=True)
class SourceLine:
    """One line as written, parsed (``number`` counts lines from 1)."""

    number: int
    text: str
    block_delete: bool
    line_number: Fraction | None
    words: tuple[Word, ...]
    settings: tuple[Setting, ...]
    comments: tuple[str, ...]
    oword: OWord | None

    @property
    def empty(self) -> bool:
        """Nothing to do but comments."""
        return not self.words and not self.settings and self.oword is None


class GcodeSyntaxError(Exception):
    """A line that is not G-code: ``reason`` at ``column`` (1-based) of the text as written."""

    def __init__(self, reason: str, column: int) -> None:
        super().__init__(reason)
        self.reason = reason
        self.column = column




@lru_cache(maxsize=1)
def _parser() -> Lark:
    """The line parser, built once per process (and kept in the per-user cache: :mod:`cosim.controllers.grammars`)."""
    return lark_parser(GRAMMAR, parser="lalr", lexer="contextual", propagate_positions=False,
                       maybe_placeholders=False)


def normalize(text: str) -> tuple[str, list[int]]:
    """The line as LinuxCNC reads it (no spaces, lower case outside comments) and each character's column.

    Raises
    ------
    GcodeSyntaxError
        A comment opened inside a comment, or one not closed on its line.
    """
    out: list[str] = []
    columns: list[int] = []
    depth_start = 0
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if c == "(":
            end = i + 1
            while end < n and text[end] not in "()":
                end += 1
            if end >= n:
                raise GcodeSyntaxError("a comment is not closed on its line (unclosed '(')", i + 1)
            if text[end] == "(":
                raise GcodeSyntaxError("a comment opens inside a comment (nested '(')", end + 1)
            out.append(text[i:end + 1])
            columns.extend(range(i + 1, end + 2))
            i = end + 1
            continue
        if c == ";":
            out.append(text[i:])
            columns.extend(range(i + 1, n + 1))
            break
        if c in " \t\r\f\v":
            i += 1
            continue
        out.append(c.lower())
        columns.append(i + 1)
        i += 1
        depth_start = i
    del depth_start
    return "".join(out), columns


MAX_DEPTH = 50
"""Brackets, ``#`` and signs nested at most this deep in one value."""


def _too_deep(normalized: str) -> int | None:
    """The index where a value nests more than :data:`MAX_DEPTH` levels, or None."""
    depth = run = 0
    for i, c in enumerate(normalized):
        if c == "(" or c == ";":
            break
        if c == "[":
            depth += 1
        elif c == "]":
            depth -= 1
        if c in "#-+":
            run += 1
        elif c != "[":
            run = 0
        if depth + run > MAX_DEPTH:
            return i
    return None


@lru_cache(maxsize=4096)
def _parse(normalized: str) -> Any:
    return _parser().parse(normalized)


def parse_line(text: str, number: int = 1) -> SourceLine:
    """The syntax tree of one line of text (``number``: its line number in the file, from 1).

    Raises
    ------
    GcodeSyntaxError
        The text is not a line of G-code: the reason and the column as written.
    """
    normalized, columns = normalize(text)
    if not normalized:
        return SourceLine(number, text, False, None, (), (), (), None)
    deep = _too_deep(normalized)
    if deep is not None:
        raise GcodeSyntaxError(f"expression nested more than {MAX_DEPTH} levels deep", _column(columns, deep, text))
    try:
        tree = _parse(normalized)
    except UnexpectedInput as exc:
        raise _syntax_error(exc, normalized, columns, text) from None
    try:
        return _Build(columns, text, number).transform(tree)
    except VisitError as exc:  # pragma: no cover - the transformer does not raise for a parsed tree
        raise GcodeSyntaxError(str(exc.orig_exc), 1) from None


def _column(columns: list[int], index: int, text: str) -> int:
    if 0 <= index < len(columns):
        return columns[index]
    return len(text.rstrip()) + 1


def _syntax_error(exc: UnexpectedInput, normalized: str, columns: list[int], text: str) -> GcodeSyntaxError:
    pos: int = getattr(exc, "pos_in_stream", None) or 0
    if isinstance(exc, UnexpectedCharacters):
        index: int = exc.pos_in_stream or 0
        char = normalized[index]
        column = _column(columns, index, text)
        written = text[column - 1] if 0 < column <= len(text) else char
        if char == ")":
            return GcodeSyntaxError("')' closes a comment that was never opened", column)
        if char == "n":
            return GcodeSyntaxError("a line number N is only allowed at the start of the line", column)
        if char.isalpha() and index > 0 and normalized[index - 1].isalpha():
            return GcodeSyntaxError(f"the letter {normalized[index - 1].upper()!r} at column "
                                    f"{_column(columns, index - 1, text)} is followed by {written!r}, not a "
                                    "value (a word is a letter and a number, e.g. G1 or X-2.5)", column)
        return GcodeSyntaxError(f"unexpected {written!r} (a word is a letter and a value, e.g. G1, X-2.5, "
                                "X#1, X[1+2])", column)
    if isinstance(exc, UnexpectedToken | UnexpectedEOF):
        token = getattr(exc, "token", None)
        at_end = token is None or token.type == "$END"
        index = len(normalized) if at_end or token is None else (token.start_pos if token.start_pos is not None
                                                                  else pos)
        column = _column(columns, index, text)
        before = normalized[:index]
        found = "the end of the line" if at_end else repr(str(token))
        if before and before[-1].isalpha() and before[-1] not in "o":
            return GcodeSyntaxError(f"the letter {before[-1].upper()!r} at column {_column(columns, index - 1, text)}"
                                    f" is followed by {found}, not a value (a word is a letter and a number, "
                                    "e.g. G1 or X-2.5)", column)
        if before.rstrip("0123456789.").endswith("o") or (before.endswith(">") and "o<" in before):
            return GcodeSyntaxError(f"an O-word needs a keyword after its label (sub, endsub, call, if, ...), "
                                    f"found {found}", column)
        if "[" in before and before.count("[") > before.count("]"):
            return GcodeSyntaxError(f"{found} in an expression: '[' opened at column "
                                    f"{_column(columns, before.rindex('['), text)} is not closed properly", column)
        return GcodeSyntaxError(f"unexpected {found}", column)
    return GcodeSyntaxError("cannot be read", 1)  # pragma: no cover - lark raises only the kinds above


def _number(text: str) -> Fraction:
    return Fraction(text)


@v_args(inline=True)
class _Build(Transformer):
    def __init__(self, columns: list[int], text: str, number: int) -> None:
        super().__init__()
        self.columns = columns
        self.text = text
        self.line = number

    def _col(self, token: Token) -> int:
        return _column(self.columns, token.start_pos or 0, self.text)

    def start(self, *items: Any) -> SourceLine:
        block_delete = False
        line_number = None
        words: list[Word] = []
        settings: list[Setting] = []
        comments: list[str] = []
        oword = None
        for item in items:
            if isinstance(item, Token):
                if item.type == "BLOCK_DELETE":
                    block_delete = True
                else:
                    comments.append(str(item)[1:-1] if item.startswith("(") else str(item)[1:])
            elif isinstance(item, Word):
                words.append(item)
            elif isinstance(item, Setting):
                settings.append(item)
            elif isinstance(item, OWord):
                oword = item
            else:
                line_number = item
        return SourceLine(self.line, self.text, block_delete, line_number, tuple(words), tuple(settings),
                          tuple(comments), oword)

    def line_number(self, token: Token) -> Fraction:
        return _number(token)

    def word(self, letter: Token, value: Expr) -> Word:
        return Word(str(letter).upper(), value, self._col(letter))

    def setting(self, index: Expr | str, value: Expr) -> Setting:
        return Setting(index, value, 0)

    def oword(self, label: Expr | str, keyword: Token, *args: Expr) -> OWord:
        return OWord(label, str(keyword), tuple(args), self._col(keyword))

    def named_label(self, token: Token) -> str:
        return str(token)[1:-1]

    def numbered_label(self, value: Expr) -> Expr:
        return value

    def oarg(self, expr: Expr) -> Expr:
        return expr

    def number(self, token: Token) -> Num:
        return Num(_number(token))

    def neg(self, value: Expr) -> Expr:
        return Neg(value)

    def value(self, value: Expr) -> Expr:  # "+" value
        return value

    def parameter(self, index: Expr | str) -> Param:
        return Param(index)

    def named(self, token: Token) -> str:
        return str(token)[1:-1]

    def numbered(self, value: Expr) -> Expr:
        return value

    def func(self, name: Token, arg: Expr) -> Func:
        return Func(str(name), (arg,))

    def atan(self, y: Expr, x: Expr) -> Func:
        return Func("atan", (y, x))

    def exists(self, token: Token) -> Exists:
        return Exists(str(token)[1:-1])

    def binary(self, left: Expr, op: Any, right: Expr) -> Binary:
        return Binary(_op(op), left, right)

    def power(self, left: Expr, right: Expr) -> Binary:
        return Binary("**", left, right)

    def addop(self, token: Token) -> str:
        return str(token)

    def mulop(self, token: Token) -> str:
        return str(token)


def _op(op: Any) -> str:
    return str(op)
