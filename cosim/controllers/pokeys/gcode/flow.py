"""Program files and O-word control flow: where each O-word's partner lines are, and subroutine files.

A :class:`SourceFile` is a file read and parsed whole (every syntax error is found before anything
runs), with the lines of each O-word label indexed, so that ``if``/``else``/``endif``,
``while``/``endwhile``, ``do``/``while``, ``repeat``/``endrepeat``, ``break``/``continue`` and
``sub``/``endsub`` find their partners. A named subroutine that the program does not define is
looked up as ``<name>.ngc`` on the search path the machine file gives (then beside the program),
as LinuxCNC's ``SUBROUTINE_PATH``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path

from cosim.controllers.pokeys.gcode.syntax import GcodeSyntaxError, Neg, Num, SourceLine, parse_line

Label = int | str


class Stop(Exception):
    """The program ended (M2, M30, ``%``)."""


class ProgramError(Exception):
    """An error at ``where`` (``file:line:column``) with LinuxCNC's meaning."""

    def __init__(self, where: str, reason: str) -> None:
        super().__init__(f"{where}: {reason}")
        self.where = where
        self.reason = reason


@dataclass
class SourceFile:
    """A program file, parsed, with its O-word lines indexed by label."""

    path: str
    lines: list[SourceLine]
    labels: dict[Label, list[tuple[int, str]]] = field(default_factory=dict)
    start: int = 0
    """Index of the first line to run (after a leading ``%``)."""
    stop: int | None = None
    """Index of the closing ``%`` line, if the file opens with one."""

    def where(self, index: int, column: int = 0) -> str:
        line = index + 1
        return f"{self.path}:{line}:{column}" if column else f"{self.path}:{line}"

    def partner(self, label: Label, index: int, keywords: Sequence[str], *, backward: bool = False) -> int | None:
        """The next (or previous) line of ``label`` after ``index`` whose keyword is one of ``keywords``."""
        entries = self.labels.get(label, [])
        if backward:
            for i, kw in reversed(entries):
                if i < index and kw in keywords:
                    return i
            return None
        for i, kw in entries:
            if i > index and kw in keywords:
                return i
        return None

    def is_do_while(self, label: Label, index: int) -> bool:
        """Whether the ``while`` at ``index`` closes a ``do`` loop."""
        entries = [kw for i, kw in self.labels.get(label, []) if i < index]
        return bool(entries) and entries[-1] in ("do", "continue", "break") and "do" in entries

    def sub(self, label: Label) -> int | None:
        for i, kw in self.labels.get(label, []):
            if kw == "sub":
                return i
        return None


def literal_label(label: object) -> Label | None:
    """The label of an O-word if written as a number or a name (``o100``, ``o<name>``)."""
    if isinstance(label, str):
        return label
    value: Fraction | None = None
    if isinstance(label, Num):
        value = label.value
    elif isinstance(label, Neg) and isinstance(label.operand, Num):
        value = -label.operand.value
    if value is not None and value.denominator == 1:
        return int(value)
    return None


def parse_text(text: str, path: str) -> SourceFile:
    """Parse a whole program; the first syntax error is raised as ``ProgramError``."""
    text = text.removeprefix("\ufeff")  # a byte order mark, as Windows editors write it
    if "\x00" in text:
        line = text[:text.index("\x00")].count("\n") + 1
        raise ProgramError(f"{path}:{line}", "not G-code: the file holds NUL bytes (a binary file?)")
    lines: list[SourceLine] = []
    labels: dict[Label, list[tuple[int, str]]] = {}
    start, stop = 0, None
    first_content: int | None = None
    for index, raw in enumerate(text.splitlines()):
        stripped = raw.strip()
        if stripped == "%" or (stripped.startswith("%") and first_content is None):
            lines.append(SourceLine(index + 1, raw, False, None, (), (), (), None))
            if first_content is None:
                first_content, start = index, index + 1
            elif stop is None:
                stop = index
            continue
        if stripped and first_content is None:
            first_content = index
        if stop is not None:
            lines.append(SourceLine(index + 1, raw, False, None, (), (), (), None))
            continue
        try:
            parsed = parse_line(raw, index + 1)
        except GcodeSyntaxError as exc:
            raise ProgramError(f"{path}:{index + 1}:{exc.column}", f"not G-code: {exc.reason}") from None
        if parsed.oword is not None:
            label = literal_label(parsed.oword.label)
            if label is not None:
                labels.setdefault(label, []).append((index, parsed.oword.keyword))
        lines.append(parsed)
    return SourceFile(path, lines, labels, start, stop)


def read_source(path: str | Path) -> SourceFile:
    """Read and parse a program file (an unreadable or non-text file is refused)."""
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise ProgramError(str(path), f"cannot read the G-code file ({exc.strerror})") from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data[:exc.start].count(b"\n") + 1
        raise ProgramError(f"{path}:{line}", f"not G-code: not a UTF-8 text file (byte 0x{data[exc.start]:02x} at "
                                             f"offset {exc.start})") from None
    return parse_text(text, str(path))


class Library:
    """The subroutine files of a run: found on the search path, read once."""

    def __init__(self, search_path: Sequence[str | Path] = ()) -> None:
        self.search_path = [Path(p) for p in search_path]
        self.files: dict[str, SourceFile] = {}

    def find(self, name: str, beside: str) -> SourceFile | None:
        """The file defining subroutine ``name`` (``name.ngc`` on the path, then beside ``beside``), or None."""
        if name in self.files:
            return self.files[name]
        folders = [*self.search_path, Path(beside).parent]
        for folder in folders:
            for candidate in (folder / f"{name}.ngc", folder / f"{name}.NGC"):
                if candidate.is_file():
                    source = read_source(candidate)
                    self.files[name] = source
                    return source
        return None
