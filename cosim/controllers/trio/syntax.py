"""Text to syntax tree, with the messages of a syntax error: the first layer of the language.

:func:`parse` normalises the line ends, parses with the grammar of :mod:`.grammar` and turns a lark
error into a :class:`~cosim.errors.ConfigurationError` naming the file, the line and the column,
what was found and what was expected, and the line itself.
"""

from __future__ import annotations

from lark import Tree
from lark.exceptions import UnexpectedCharacters, UnexpectedInput, UnexpectedToken

from cosim.controllers.trio.grammar import TERMINALS, normalise_lines, parser
from cosim.errors import ConfigurationError


def parse(text: str, name: str) -> Tree:
    """The syntax tree of ``text`` (any line ends); a syntax error names ``name``, the line and the column."""
    normalised = normalise_lines(text)
    try:
        tree = parser().parse(normalised)
    except UnexpectedInput as exc:
        raise ConfigurationError(_syntax_message(exc, normalised, name)) from None
    assert isinstance(tree, Tree)
    return tree


def _expected(exc: UnexpectedInput) -> str:
    names = getattr(exc, "expected", None) or getattr(exc, "allowed", None) or set()
    shown = sorted({TERMINALS.get(n, n.lstrip("_")) for n in names})
    return f" (expected: {', '.join(shown)})" if shown else ""


def _syntax_message(exc: UnexpectedInput, text: str, name: str) -> str:
    lines = text.splitlines()
    line, column = exc.line, exc.column
    source = lines[line - 1] if 1 <= line <= len(lines) else ""
    if isinstance(exc, UnexpectedToken):
        found = "end of line" if exc.token.type == "_NL" else repr(str(exc.token))
    elif isinstance(exc, UnexpectedCharacters):
        found = repr(source[column - 1]) if 1 <= column <= len(source) else "?"
    else:
        found = "end of program"
    return (f"{name} line {line}, column {column}: syntax error, unexpected {found}{_expected(exc)}\n"
            f"    {source.rstrip()}")
