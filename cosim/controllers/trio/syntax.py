"""Text to syntax tree, with the messages of a syntax error: the first layer of the language.

:func:`parse` normalises the line ends, parses with the grammar of :mod:`.grammar` and turns a lark
error into a :class:`~cosim.errors.ConfigurationError` naming the file, the line and the column,
what was found and what was expected, and the line itself.
"""

from __future__ import annotations

import contextlib
import hashlib
import pickle
import re
import sys
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
    """Write ``tree`` to ``path`` whole, then drop the oldest trees beyond :data:`CACHED_TREES`."""
    from cosim.controllers.grammars import write_whole

    if write_whole(path, lambda stream: pickle.dump(tree, stream, protocol=pickle.HIGHEST_PROTOCOL)):
        with contextlib.suppress(OSError):
            kept = sorted(path.parent.glob("trio-tree-*.pickle"), key=lambda p: p.stat().st_mtime)
            for old in kept[:-CACHED_TREES]:
                old.unlink()


def _expected(exc: UnexpectedInput) -> str:
    names = getattr(exc, "expected", None) or getattr(exc, "allowed", None) or set()
    shown = sorted({TERMINALS.get(n, n.lstrip("_")) for n in names})
    return f" (expected: {', '.join(shown)})" if shown else ""


#: The blocks of Trio BASIC: the word that opens one, the word that closes it, and how it is written.
BLOCKS = {"IF": ("ENDIF", "IF condition THEN ... ENDIF"), "FOR": ("NEXT", "FOR v = a TO b ... NEXT"),
          "WHILE": ("WEND", "WHILE condition ... WEND"), "REPEAT": ("UNTIL", "REPEAT ... UNTIL condition")}
_CLOSERS = {closer: opener for opener, (closer, _usage) in BLOCKS.items()}
_STRING_OR_COMMENT = re.compile(r'"[^"\n]*"|\'.*$|(?<![A-Za-z0-9_])REM(?![A-Za-z0-9_]).*$', re.IGNORECASE)


def open_blocks(text: str, *, until_line: int | None = None) -> list[tuple[str, int]]:
    """The blocks still open (innermost last) after line ``until_line`` - 1 of ``text`` (all lines by default).

    A line-by-line scan of the block words (a one-line ``IF ... THEN statement`` opens nothing), used to
    say which block a syntax error at a closing word or at the end of the program leaves open.

    Examples
    --------
    >>> open_blocks("FOR i = 1 TO 3\nIF i = 2 THEN\nx = 1\nNEXT i\n")
    [('FOR', 1), ('IF', 2)]
    """
    stack: list[tuple[str, int]] = []
    for number, raw in enumerate(text.splitlines(), start=1):
        if until_line is not None and number >= until_line:
            break
        for statement in _STRING_OR_COMMENT.sub(" ", raw).split(":"):
            words = statement.split()
            if not words:
                continue
            first = words[0].upper()
            if (first == "IF" and words[-1].upper() == "THEN") or first in ("FOR", "WHILE", "REPEAT"):
                stack.append((first, number))
            elif first in _CLOSERS:
                for k in range(len(stack) - 1, -1, -1):
                    if stack[k][0] == _CLOSERS[first]:
                        del stack[k:]
                        break
    return stack


def _a(word: str) -> str:
    return f"an {word}" if word == "IF" else f"a {word}"


def _unclosed(exc: UnexpectedInput, text: str, name: str) -> str | None:
    """The message for an error at the end of the program or at a closing word that leaves a block open."""
    if not isinstance(exc, UnexpectedToken):
        return None
    word = str(exc.token).upper()
    at_end = exc.token.type == "$END"
    if not at_end and word not in _CLOSERS:
        return None
    stack = open_blocks(text, until_line=None if at_end else exc.line)
    if not at_end and all(opened != _CLOSERS[word] for opened, _line in stack):
        wanted = _CLOSERS[word]
        return (f"{name} line {exc.line}, column {exc.column}: {word} closes {_a(wanted)} block, but no {wanted} "
                f"block is open here ({BLOCKS[wanted][1]})")
    if not stack:
        return None
    opener, line = stack[-1]
    closer, usage = BLOCKS[opener]
    if at_end:
        return (f"{name} line {line}: the {opener} block that starts here is not closed: {closer} is missing before "
                f"the end of the program ({usage})")
    if _CLOSERS[word] == opener:
        return None
    return (f"{name} line {exc.line}, column {exc.column}: {word} closes {_a(_CLOSERS[word])} block, but the {opener} "
            f"block of line {line} is not closed yet: {closer} is missing ({usage})")


def _syntax_message(exc: UnexpectedInput, text: str, name: str) -> str:
    unclosed = _unclosed(exc, text, name)
    if unclosed is not None:
        return unclosed
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
