"""Places in PMAC text: ``file:line:column`` for every statement and every message about it.

The lowest layer of the language front end (text -> syntax tree -> program -> runtime): the
preprocessor, the parser, the compiler and the runtime all name places with :class:`Pos`.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

from cosim.errors import ConfigurationError


@dataclass(frozen=True)
class Pos:
    """A place in a file: ``source:line:column`` (1-based)."""

    source: str
    line: int
    column: int

    def __str__(self) -> str:
        return f"{self.source}:{self.line}:{self.column}"

    def error(self, message: str) -> ConfigurationError:
        """``ConfigurationError("file:line:col: message")``."""
        return ConfigurationError(f"{self}: {message}")

    def shifted(self, columns: int) -> Pos:
        """The same line, ``columns`` further right (a command inside a ``CMD"..."`` string)."""
        return Pos(self.source, self.line, self.column + columns)


@contextmanager
def located(pos: Pos) -> Iterator[None]:
    """Prefix a ConfigurationError raised inside with ``file:line:col`` (unless it names a place of that file)."""
    try:
        yield
    except ConfigurationError as exc:
        if str(exc).startswith(f"{pos.source}:"):
            raise
        raise ConfigurationError(f"{pos}: {exc}") from exc
