"""Machine files as documents: TOML read once, ``--set`` applied by key, every key checked on use.

A :class:`Table` wraps one TOML table with its place in the file (``plant.stepper_x``), so every
message names the file, the key, the value and what is allowed::

    engraver.toml: plant.stepper_x.preset = 'nema17' is not allowed (allowed: nema17_17hs16_2004s1, ...)

Keys are taken with typed getters (:meth:`Table.text`, :meth:`Table.integer`, :meth:`Table.time`,
...); :meth:`Table.finish` then refuses any key that nothing took (a misspelt key is an error,
never silently ignored).

``--set KEY=VALUE`` (:func:`apply_overrides`) addresses a key by its dotted path
(``controller.axis.3.SPEED=2000``, ``check[0].max_count=20`` in an array of tables) or by any
unique trailing part of a path already in the file (``SPEED=2000`` when only one table has a
SPEED; the tables outside arrays are looked in first, so ``until`` stays ``machine.until``); the
value is read as a TOML value (``2000``, ``true``, ``"2 s"``, ``[1, 2]``), and text that is not a
TOML value is taken as a string (``--set until=2 s``).
"""

from __future__ import annotations

import difflib
import re
import tomllib
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path
from typing import Any, TypeVar

from cosim import validate
from cosim.errors import ConfigurationError
from cosim.timebase import TimeBase

T = TypeVar("T")
_MISSING: Any = object()


def read_document(path: Path) -> dict[str, Any]:
    """The TOML document of a machine file (ConfigurationError with the file, line and column)."""
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigurationError(f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None
    except OSError as exc:
        raise ConfigurationError(f"{path}: cannot read the machine file ({exc.strerror})") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigurationError(_toml_error(path, text, str(exc))) from None


_AT_LINE = re.compile(r"\(at line (\d+), column (\d+)\)")
_HEADER = re.compile(r"^\s*\[\[?\s*([^\]]+?)\s*\]\]?")


def _toml_error(path: Path, text: str, message: str) -> str:
    """A TOML error with the file and line, and for a key given twice the key by its dotted name."""
    at = _AT_LINE.search(message)
    if at is None:
        return f"{path}: not a valid TOML machine file: {message}"
    number = int(at.group(1))
    lines = text.splitlines()
    line = lines[number - 1] if 0 < number <= len(lines) else ""
    twice = "Cannot overwrite" in message or "twice" in message or "Duplicate" in message
    if not twice:
        return f"{path}:{number}: not a valid TOML machine file: {message}\n    {line.strip()}"
    header = _HEADER.match(line)
    if header is not None and "=" not in line.split("]")[0]:
        key = header.group(1).replace(" ", "")
    else:
        table = next((m.group(1).replace(" ", "") for m in (_HEADER.match(x) for x in reversed(lines[:number - 1]))
                      if m is not None), "")
        name = line.split("=", 1)[0].strip().strip("{").strip()
        duplicate = re.search(r"key '([^']+)'", message)
        if duplicate is not None:
            name = f"{name}.{duplicate.group(1)}"
        key = f"{table}.{name}" if table else name
    return (f"{path}:{number}: {key} is given twice (a key may appear once in a TOML file; the second is on "
            f"line {number}: {line.strip()})")


def machine_description(path: Path) -> str:
    """The one-line description of a machine file (``machine.description``), for ``cosim list``."""
    try:
        machine = read_document(path).get("machine", {})
    except ConfigurationError:
        return ""
    text = machine.get("description", "") if isinstance(machine, dict) else ""
    return str(text).strip().splitlines()[0] if str(text).strip() else ""


def leaves(data: Mapping[str, Any], prefix: str = "") -> Iterator[tuple[str, Any]]:
    """Every key of a document with its value, by its dotted path as messages name it: tables by name,
    arrays of tables by index (``controller.axis.x.accel``, ``check[0].max_count``)."""
    for key, value in data.items():
        path = f"{prefix}{key}"
        if isinstance(value, dict):
            yield from leaves(value, path + ".")
        elif isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            for index, item in enumerate(value):
                yield from leaves(item, f"{path}[{index}].")
        else:
            yield path, value


def _value(text: str) -> Any:
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text


def apply_overrides(data: dict[str, Any], overrides: dict[str, Any], *, file: Path) -> dict[str, Any]:
    """A copy of ``data`` with ``--set`` values applied (see the module docstring for the key rules)."""
    import copy

    out = copy.deepcopy(data)
    paths = [path for path, _ in leaves(data)]
    tables = [path for path in paths if "[" not in path]  # a trailing part is looked up here first
    for key, raw in overrides.items():
        value = _value(raw) if isinstance(raw, str) else raw
        path = key if key in paths or ("." in key and _creatable(out, key)) else None
        if path is None:
            matches = [leaf for leaf in tables if leaf == key or leaf.endswith("." + key)] or [
                leaf for leaf in paths if leaf.endswith("." + key)]
            if len(matches) > 1:
                raise ConfigurationError(f"{file}: --set {key} is ambiguous: it could be {', '.join(matches)}; "
                                         "write the whole dotted key")
            if not matches:
                close = difflib.get_close_matches(key, paths, n=3, cutoff=0.5)
                hint = f"; did you mean {', '.join(close)}?" if close else ""
                raise ConfigurationError(f"{file}: --set {key}: the machine file has no key {key!r}{hint} "
                                         "(a new key is written as its whole dotted path, e.g. "
                                         "controller.axis.3.SPEED)")
            path = matches[0]
        *parents, leaf = path.split(".")
        node = out
        for part in parents:
            name, index = _indexed(part)
            try:
                node = node.setdefault(name, {}) if index is None else node[name][index]
            except (KeyError, IndexError, TypeError):
                raise ConfigurationError(f"{file}: --set {key}: the machine file has no table {part}") from None
            if not isinstance(node, dict):
                raise ConfigurationError(f"{file}: --set {key}: {part} is a value, not a table")
        node[leaf] = value
    return out


_INDEXED = re.compile(r"(.+)\[(\d+)\]")


def _indexed(part: str) -> tuple[str, int | None]:
    """``check[0]`` -> ``("check", 0)``; ``axis`` -> ``("axis", None)``."""
    match = _INDEXED.fullmatch(part)
    return (part, None) if match is None else (match[1], int(match[2]))


def _creatable(data: dict[str, Any], key: str) -> bool:
    """A new dotted key can be made when its first part names a table of the document, or a table of an
    array of tables that is there (``check[0].name``)."""
    name, index = _indexed(key.split(".")[0])
    if index is None:
        return isinstance(data.get(name), dict)
    tables = data.get(name)
    return isinstance(tables, list) and index < len(tables) and isinstance(tables[index], dict)


@dataclass(frozen=True)
class KeySpec:
    """What a key of a machine file takes, as the machine's builder asked for it (for ``cosim params``).

    Parameters
    ----------
    key : str
        Dotted key (``controller.axis.x.max_speed_hz``).
    value : object
        The value in the file, or the default the builder used (None: no default).
    given : bool
        The file (or ``--set``) gives the key.
    unit : str
        Unit of the value (``time`` for a time written with its unit).
    allowed : str
        The allowed values or range.
    """

    key: str
    value: Any
    given: bool
    unit: str = ""
    allowed: str = ""


class Table:
    """One TOML table of a machine file, with its dotted place for messages.

    Parameters
    ----------
    data : dict
        The table.
    file : Path
        The machine file.
    path : str
        The table's dotted key (``""`` for the document).
    timebase : TimeBase
        Converts times written with a unit (``"40 us"``) into ticks.
    """

    def __init__(self, data: dict[str, Any], *, file: Path, path: str = "", timebase: TimeBase | None = None) -> None:
        self.data = data
        self.file = file
        self.path = path
        self.timebase = timebase or TimeBase()
        self.used: set[str] = set()
        self.children: list[Table] = []
        #: What each key takes, by name, as the getters asked for it (:meth:`specs`).
        self.key_specs: dict[str, KeySpec] = {}

    # -- places and errors ----------------------------------------------------------------------
    def key(self, name: str) -> str:
        """The dotted key of ``name`` in this table."""
        return f"{self.path}.{name}" if self.path else str(name)

    @property
    def where(self) -> str:
        """``FILE: TABLE`` for messages about the table itself."""
        return f"{self.file}: {self.path or 'the document'}"

    def error(self, name: str, value: object, allowed: str) -> ConfigurationError:
        """The standard message for key ``name`` of this table."""
        return ConfigurationError.out_of_range(self.key(name), value, allowed, where=str(self.file))

    @contextmanager
    def at(self, name: str | None = None) -> Iterator[None]:
        """Prefix errors raised inside with the file and the key (when they do not name the file yet)."""
        try:
            yield
        except ConfigurationError as exc:
            text = str(exc)
            if text.startswith(str(self.file)):
                raise
            place = self.key(name) if name is not None else (self.path or "the document")
            raise ConfigurationError(f"{self.file}: {place}: {text}") from exc

    # -- what keys take (for `cosim params`) ----------------------------------------------------
    def _spec(self, name: str, default: Any, unit: str, allowed: str) -> None:
        given = name in self.data
        value = self.data[name] if given else (None if default is _MISSING else default)
        self.key_specs.setdefault(name, KeySpec(self.key(name), value, given, unit, allowed))

    def describe(self, name: str, *, unit: str = "", allowed: str = "") -> None:
        """Say what key ``name`` takes (if given here): a key read with :meth:`raw` and checked elsewhere."""
        if name in self.data:
            self.key_specs[name] = KeySpec(self.key(name), self.data[name], True, unit, allowed)

    def specs(self) -> list[KeySpec]:
        """What every key read here and in the sub-tables takes, in the order they were read."""
        out = list(self.key_specs.values())
        for child in self.children:
            out += child.specs()
        return out

    # -- getting keys ---------------------------------------------------------------------------
    def has(self, name: str) -> bool:
        """Is key ``name`` in the table."""
        return name in self.data

    def raw(self, name: str, default: Any = _MISSING) -> Any:
        """The value of ``name`` as written (marks it used); a missing key without default is an error."""
        self.used.add(name)
        if name not in self.data:
            if default is _MISSING:
                raise ConfigurationError(f"{self.file}: {self.key(name)} is missing (required)")
            return default
        return self.data[name]

    def _typed(self, name: str, default: Any, convert: Callable[[Any], T]) -> T:
        value = self.raw(name, default)
        if value is default and default is not _MISSING:
            return value
        with self.at(name):
            return convert(value)

    def text(self, name: str, default: Any = _MISSING, *, choices: Sequence[str] | None = None) -> str:
        """A string key (one of ``choices`` if given)."""
        self._spec(name, default, "", ", ".join(choices) if choices is not None else "text")

        def convert(value: Any) -> str:
            if not isinstance(value, str):
                raise ConfigurationError.out_of_range("value", value, "a string")
            if choices is not None:
                validate.choice(value, "value", choices)
            return value
        return self._typed(name, default, convert)

    def integer(self, name: str, default: Any = _MISSING, *, low: int | None = None,
                high: int | None = None, unit: str = "") -> int:
        """An integer key in ``low..high``."""
        self._spec(name, default, unit, validate.integer_range(low, high))
        return self._typed(name, default, lambda v: validate.integer(v, "value", low=low, high=high, unit=unit))

    def number(self, name: str, default: Any = _MISSING) -> Fraction:
        """A number key, exactly (a TOML float is taken as the decimal it prints as)."""
        self._spec(name, default, "", "a number")
        return self._typed(name, default, lambda v: validate.exact(v, "value"))

    def flag(self, name: str, default: Any = _MISSING) -> bool:
        """A true/false key."""
        self._spec(name, default, "", "true, false")
        return self._typed(name, default, lambda v: validate.flag(v, "value"))

    def time(self, name: str, default: Any = _MISSING, *, hint: str = "ms") -> int:
        """A time written with a unit (``"40 us"``) as ticks of the resolution (``hint``: the unit a bare
        number is suggested with)."""
        self._spec(name, default, "time", "a time with a unit, e.g. \"40 us\"")
        return self._typed(name, default, lambda v: self.ticks(v, hint=hint))

    def ticks(self, value: Any, *, hint: str = "ms") -> int:
        """Convert a time written with a unit (``"40 us"``) to ticks; a bare number other than 0 is refused."""
        if isinstance(value, str):
            return self.timebase.ticks(value, name="time")
        if isinstance(value, int | float) and not isinstance(value, bool) and value == 0:
            return 0
        shown = validate.shown(value) if isinstance(value, int | float) and not isinstance(value, bool) else None
        hint_text = f"; did you mean \"{shown} {hint}\"?" if shown is not None else ""
        raise ConfigurationError.out_of_range("time", value, f"a time with a unit, e.g. \"40 us\"{hint_text}")

    def file_path(self, name: str, base: Path, *, suffixes: Sequence[str] = ()) -> Path:
        """A file named by key ``name``, relative to ``base`` (the machine file's folder); it must exist."""
        text = self.text(name)
        self.key_specs[name] = KeySpec(self.key(name), text, True, "", "a file, relative to the machine file"
                                       + (" (" + ", ".join(suffixes) + ")" if suffixes else ""))
        path = (base / text).resolve()
        if not path.is_file():
            raise ConfigurationError(f"{self.file}: {self.key(name)}: file {path} does not exist"
                                     + (" (it is a folder)" if path.is_dir() else ""))
        if suffixes and path.suffix.lower() not in suffixes:
            raise self.error(name, text, "a file ending " + ", ".join(suffixes))
        return path

    def table(self, name: str, *, required: bool = False) -> Table:
        """A sub-table (an empty one when absent and not ``required``)."""
        value = self.raw(name, _MISSING if required else {})
        if not isinstance(value, dict):
            raise self.error(name, value, "a table")
        child = Table(value, file=self.file, path=self.key(name), timebase=self.timebase)
        self.children.append(child)
        return child

    def tables(self, name: str) -> list[Table]:
        """An array of tables (``[[check]]``): empty when absent."""
        value = self.raw(name, [])
        if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
            raise self.error(name, value, "an array of tables ([[...]] sections)")
        out = [Table(v, file=self.file, path=f"{self.key(name)}[{i}]", timebase=self.timebase)
               for i, v in enumerate(value)]
        self.children.extend(out)
        return out

    def items(self) -> list[tuple[str, Table]]:
        """Every sub-table of this table by name (``[plant.x]``, ``[plant.y]``), in file order."""
        out = []
        for name in self.data:
            out.append((name, self.table(name)))
        return out

    def only(self, known: Sequence[str], *, what: str) -> None:
        """Refuse a key that is not one of ``known`` before any key is read (a misspelt key is named, not
        reported as a missing one): ``what`` says what the keys are of (``the parameters of Bound``)."""
        for name in self.data:
            if name not in known:
                close = difflib.get_close_matches(str(name), list(known), n=3)
                hint = f"; did you mean {', '.join(close)}?" if close else ""
                raise ConfigurationError(f"{self.file}: {self.key(name)} is not a key here{hint} ({what}: "
                                         f"{', '.join(known)})")

    def finish(self) -> None:
        """Refuse keys that nothing took, here and in every sub-table taken."""
        for name in self.data:
            if name not in self.used:
                known = sorted(self.used)
                close = difflib.get_close_matches(str(name), known, n=3)
                hint = f"; did you mean {', '.join(close)}?" if close else ""
                raise ConfigurationError(f"{self.file}: {self.key(name)} is not a key of {self.path or 'the document'}"
                                         f"{hint} (keys used here: {', '.join(known) or 'none'})")
        for child in self.children:
            child.finish()
