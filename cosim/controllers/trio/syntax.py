"""Text to syntax tree, with the messages of a syntax error: the first layer of the language.

:func:`parse` normalises the line ends, parses with the grammar of :mod:`.grammar` and turns a lark
error into a :class:`~cosim.errors.ConfigurationError` naming the file, the line and the column,
what was found and what was expected, and the line itself.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import pickle
import sys
import tempfile
from pathlib import Path

from lark import Tree
from lark import __version__ as lark_version
from lark.exceptions import UnexpectedCharacters, UnexpectedInput, UnexpectedToken

from cosim.controllers.trio.grammar import GRAMMAR, PARSER_OPTIONS, TERMINALS, normalise_lines, parser
from cosim.errors import ConfigurationError

#: Syntax trees kept in the per-user cache at most (the oldest go first).
CACHED_TREES = 256


def parse(text: str, name: str) -> Tree:
    """The syntax tree of ``text`` (any line ends); a syntax error names ``name``, the line and the column."""
    normalised = normalise_lines(text)
    try:
        tree = parser().parse(normalised)
    except UnexpectedInput as exc:
        raise ConfigurationError(_syntax_message(exc, normalised, name)) from None
    assert isinstance(tree, Tree)
    return tree


def parse_cached(text: str, name: str) -> Tree:
    """:func:`parse`, through the per-user cache of built grammars (:mod:`cosim.controllers.grammars`).

    A machine's program files are mostly the same from one run to the next: their trees are kept
    under the SHA-256 of the grammar and its parser options, the text and the lark and Python
    versions (a changed program or grammar is a new file, never a stale tree), so a run loads them
    instead of building the parser and parsing (about a millisecond instead of tens). Only a text
    that parses is kept (a syntax error is reported by :func:`parse` every time); a file that cannot
    be read is parsed anew and replaced; a cache that cannot be written only costs the parse. At most
    :data:`CACHED_TREES` trees are kept.
    """
    from cosim.controllers.grammars import cache_folder

    key = hashlib.sha256(repr((GRAMMAR, sorted(PARSER_OPTIONS.items()), text, lark_version,
                               sys.version_info[:2])).encode()).hexdigest()
    folder = cache_folder()
    path = folder / f"trio-tree-{key[:32]}.pickle"
    try:
        with path.open("rb") as stream:
            tree = pickle.load(stream)
        if isinstance(tree, Tree):
            return tree
    except Exception:  # missing, cut short, from another lark: parse it anew
        pass
    tree = parse(text, name)
    _save_tree(tree, path)
    return tree


def _save_tree(tree: Tree, path: Path) -> None:
    """Write ``tree`` to ``path`` whole (a temporary file renamed), then drop the oldest trees beyond the limit."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        handle, name = tempfile.mkstemp(dir=path.parent, prefix=path.name, suffix=".tmp")
    except OSError:
        return
    try:
        with os.fdopen(handle, "wb") as stream:
            pickle.dump(tree, stream, protocol=pickle.HIGHEST_PROTOCOL)
        os.replace(name, path)
        kept = sorted(path.parent.glob("trio-tree-*.pickle"), key=lambda p: p.stat().st_mtime)
        for old in kept[:-CACHED_TREES]:
            old.unlink()
    except OSError:
        with contextlib.suppress(OSError):
            os.unlink(name)


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
