"""The download preprocessor: what a PMAC project's files become before the controller reads them.

Delta Tau's download tools run a C-like preprocessor over a file before sending it line by line;
project files rely on it. :func:`preprocess` does the same, keeping for every output line the file
and line it came from (so errors still name them):

* ``#define NAME text`` -- ``NAME`` (a word: letters, digits, ``_``) is replaced by ``text`` in the
  lines after it, as a whole word, repeatedly (a macro may use macros; at most
  :data:`MAX_EXPANSIONS` rounds); ``#define NAME`` alone defines it as empty. Names are
  case-sensitive, as in C.
* ``#undefine NAME`` (also ``#undef``) forgets a macro.
* ``#include "file"`` (or ``<file>``, or no quotes) reads a file in place: a path relative to the
  including file first, then each folder of the search path, in order. At most
  :data:`MAX_INCLUDE_DEPTH` deep; a file including itself is refused.
* ``#ifdef`` / ``#ifndef`` / ``#else`` / ``#endif`` keep or drop lines.
* ``$(NAME)`` -- a template macro, given its value by the machine file (``[controller.defines]``);
  one with no value is an error naming it (see :class:`TemplateMacroError`).
* Comments: ``;`` and ``//`` to the end of the line, ``/* ... */`` over lines (outside strings),
  are removed; a line of nothing but ``#`` characters (a banner) is empty.

Any other line starting with ``#`` followed by a letter is an unknown directive (an error naming
it); ``#`` followed by a digit, ``(`` or nothing is PMAC's motor addressing, left alone.

This is the text layer of the front end: it knows lines, not statements.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from cosim.controllers.pmac.source import Pos
from cosim.errors import ConfigurationError

#: Rounds of macro substitution on one line (a macro defined through itself stops here).
MAX_EXPANSIONS = 32
#: Deepest ``#include`` nesting.
MAX_INCLUDE_DEPTH = 16
#: Longest line after expansion [characters].
MAX_LINE = 10_000

_WORD = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_TEMPLATE = re.compile(r"\$\(([^)\s]*)\)")
_DIRECTIVE = re.compile(r"\s*#\s*([A-Za-z]+)\b(.*)$")
_BANNER = re.compile(r"\s*#{2,}\s*$")


class TemplateMacroError(ConfigurationError):
    """A ``$(NAME)`` template macro that the machine file gives no value."""


@dataclass(frozen=True)
class Line:
    """One line of preprocessed text and the place it came from."""

    text: str
    source: str
    line: int

    def pos(self, column: int = 1) -> Pos:
        """``source:line:column``."""
        return Pos(self.source, self.line, column)


Reader = Callable[[Path], str]


def _read_file(path: Path) -> str:
    try:
        return path.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigurationError(f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None


def strip_comments(text: str, *, in_block: bool = False) -> tuple[str, bool]:
    """``text`` without ``;`` / ``//`` comments and ``/* */`` parts, and whether a block comment stays open."""
    out: list[str] = []
    i, n = 0, len(text)
    in_string = False
    while i < n:
        if in_block:
            end = text.find("*/", i)
            if end < 0:
                return "".join(out), True
            i, in_block = end + 2, False
            out.append(" ")
            continue
        char = text[i]
        if char == '"':
            in_string = not in_string
        elif not in_string:
            if char == ";" or text.startswith("//", i):
                break
            if text.startswith("/*", i):
                in_block = True
                i += 2
                continue
        out.append(char)
        i += 1
    return "".join(out), in_block


class _State:
    def __init__(self, defines: Mapping[str, str], search: Sequence[Path], read: Reader) -> None:
        self.macros: dict[str, str] = {}
        self.templates = {str(k): str(v) for k, v in defines.items()}
        self.search = list(search)
        self.read = read
        self.out: list[Line] = []
        self.open: list[str] = []

    def expand(self, text: str, pos: Pos) -> str:
        if "$(" in text:
            text = self._templates(text, pos)
        if not self.macros:
            return text
        for _round in range(MAX_EXPANSIONS):
            changed = False

            def substitute(match: re.Match[str]) -> str:
                nonlocal changed
                value = self.macros.get(match.group(0))
                if value is None:
                    return match.group(0)
                changed = True
                return value

            text = _replace_outside_strings(_WORD, substitute, text)
            if len(text) > MAX_LINE:
                raise pos.error(f"the line is longer than {MAX_LINE} characters after macro substitution")
            if not changed:
                return text
        raise pos.error(f"macros are still substituted after {MAX_EXPANSIONS} rounds (a macro defined through "
                        "itself?)")

    def _templates(self, text: str, pos: Pos) -> str:
        def substitute(match: re.Match[str]) -> str:
            name = match.group(1)
            if name not in self.templates:
                given = ", ".join(sorted(self.templates)) or "none"
                raise TemplateMacroError(
                    f"{pos.shifted(match.start())}: `$({name})`: template macro with no value; give it in "
                    f"[controller.defines] (given: {given})")
            return self.templates[name]

        return _TEMPLATE.sub(substitute, text)


def _replace_outside_strings(pattern: re.Pattern[str], substitute: Callable[[re.Match[str]], str], text: str) -> str:
    if '"' not in text:
        return pattern.sub(substitute, text)
    parts = text.split('"')
    return '"'.join(pattern.sub(substitute, part) if i % 2 == 0 else part for i, part in enumerate(parts))


def preprocess(text: str, *, source: str, path: Path | None = None, defines: Mapping[str, str] | None = None,
               search: Sequence[Path] = (), read: Reader = _read_file) -> list[Line]:
    """The lines of ``text`` after the download preprocessor (see the module doc).

    Parameters
    ----------
    text : str
        The file's content.
    source : str
        Its name in messages.
    path : Path, optional
        Where it is (``#include`` is relative to its folder; without it, only the search path).
    defines : mapping, optional
        Values of ``$(NAME)`` template macros (a machine file's ``[controller.defines]``).
    search : sequence of Path
        Folders ``#include`` looks in after the including file's own.
    read : callable
        Reads an included file (tests pass their own).

    Raises
    ------
    ConfigurationError
        ``file:line:column: ...`` naming the directive, macro or file.
    """
    state = _State(defines or {}, search, read)
    _process(state, text, source=source, path=path, depth=0)
    return state.out


def _process(state: _State, text: str, *, source: str, path: Path | None, depth: int) -> None:
    key = str(path.resolve()) if path is not None else source
    if key in state.open:
        raise ConfigurationError(f"{source}: includes itself (through {' -> '.join(state.open)})")
    state.open.append(key)
    conditions: list[tuple[bool, Pos]] = []  # (keeping, where the #if was)
    in_block = False
    for number, raw in enumerate(text.removeprefix("\ufeff").splitlines(), 1):
        line, in_block_after = strip_comments(raw, in_block=in_block)
        in_block = in_block_after
        keeping = all(keep for keep, _pos in conditions)
        directive = _DIRECTIVE.match(line)
        pos = Pos(source, number, 1)
        if directive is not None:
            name = directive.group(1).lower()
            argument = directive.group(2).strip()
            column = line.index("#") + 1
            where = Pos(source, number, column)
            if name in ("ifdef", "ifndef"):
                defined = argument.split()[0] in state.macros if argument else False
                conditions.append(((defined if name == "ifdef" else not defined), where))
            elif name == "else":
                if not conditions:
                    raise where.error("#else without #ifdef or #ifndef")
                keep, opened = conditions[-1]
                conditions[-1] = (not keep, opened)
            elif name == "endif":
                if not conditions:
                    raise where.error("#endif without #ifdef or #ifndef")
                conditions.pop()
            elif not keeping:
                pass
            elif name == "define":
                _define(state, argument, where)
            elif name in ("undefine", "undef"):
                if not _WORD.fullmatch(argument.split()[0] if argument else ""):
                    raise where.error(f"#{directive.group(1)} needs a macro name")
                state.macros.pop(argument.split()[0], None)
            elif name == "include":
                _include(state, argument, where, path=path, depth=depth)
            else:
                raise where.error(f"#{directive.group(1)}: unknown preprocessor directive (known: #define, "
                                  "#undefine, #include, #ifdef, #ifndef, #else, #endif)")
            state.out.append(Line("", source, number))
            continue
        if not keeping or _BANNER.match(line):
            state.out.append(Line("", source, number))
            continue
        state.out.append(Line(state.expand(line, pos), source, number))
    if conditions:
        raise conditions[-1][1].error("#ifdef/#ifndef without #endif")
    state.open.pop()


def _define(state: _State, argument: str, where: Pos) -> None:
    match = _WORD.match(argument)
    if match is None:
        raise where.error("#define needs a macro name (letters, digits, _)")
    name = match.group(0)
    rest = argument[match.end():]
    if rest.startswith("("):
        raise where.error(f"#define {name}(...): macros with arguments are not supported (define {name} as text)")
    state.macros[name] = state.expand(rest.strip(), where)


def _include(state: _State, argument: str, where: Pos, *, path: Path | None, depth: int) -> None:
    name = argument.strip()
    if len(name) >= 2 and ((name[0] == name[-1] == '"') or (name[0] == "<" and name[-1] == ">")):
        name = name[1:-1]
    if not name:
        raise where.error("#include needs a file name")
    if depth >= MAX_INCLUDE_DEPTH:
        raise where.error(f"#include nested deeper than {MAX_INCLUDE_DEPTH} files")
    folders = list(dict.fromkeys(([path.parent] if path is not None else []) + state.search))
    found = next((folder / name for folder in folders if (folder / name).is_file()), None)
    if found is None:
        looked = ", ".join(str(f) for f in folders) or "no folder (give the including file's path or a search path)"
        raise where.error(f"#include {name!r}: file not found (looked in {looked})")
    _process(state, state.read(found), source=found.name, path=found, depth=depth + 1)
