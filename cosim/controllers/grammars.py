"""Lark parsers built once: per process, and across processes through the per-user cache.

Building an LALR parser from a grammar (the Trio BASIC, PMAC and G-code grammars) takes 5-170 ms;
loading the built parser takes a tenth of that. :func:`lark_parser` builds a grammar's parser once
per process and keeps it on disk in the per-user cache (``platformdirs``, for example
``~/.cache/cosim/<version>/grammars`` on Linux; ``COSIM_GRAMMARS`` overrides the folder), under a
name made of the SHA-256 of the grammar text, the options and the lark and Python versions: a
changed grammar is a new file, never a stale parser. A cache file that cannot be read (cut short,
from another lark) is built anew and replaced; a cache folder that cannot be written only costs the
build. Files are written whole (to a temporary name, then renamed), so processes that start at
the same time never read half a file.

Example::

    _PARSER = lark_parser(GRAMMAR, parser="lalr", propagate_positions=True)
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any, BinaryIO

from lark import Lark
from lark import __version__ as lark_version

#: Built parsers of this process, by cache key.
_BUILT: dict[str, Lark] = {}


def cache_folder() -> Path:
    """Where built parsers are kept: ``COSIM_GRAMMARS``, else ``grammars`` in cosim's per-user cache."""
    override = os.environ.get("COSIM_GRAMMARS")
    if override:
        return Path(override)
    from platformdirs import user_cache_path

    from cosim import __version__

    return user_cache_path("cosim", appauthor=False, version=__version__) / "grammars"


def cache_key(grammar: str, options: dict[str, Any]) -> str:
    """SHA-256 of the grammar, its options (sorted) and the lark and Python versions."""
    text = repr((grammar, sorted(options.items()), lark_version, sys.version_info[:2]))
    return hashlib.sha256(text.encode()).hexdigest()


def lark_parser(grammar: str, **options: Any) -> Lark:
    """The parser ``Lark(grammar, **options)``, built once per process and cached on disk.

    ``options`` are Lark's (``parser="lalr"``, ``start``, ``propagate_positions``...); they must be
    plain values (no transformer or callbacks: those are not saved with a parser).
    """
    options = {k: tuple(v) if isinstance(v, list) else v for k, v in options.items()}
    key = cache_key(grammar, options)
    if key in _BUILT:
        return _BUILT[key]
    path = cache_folder() / f"lark-{key[:32]}.bin"
    parser = _load(path)
    if parser is None:
        parser = Lark(grammar, **{k: list(v) if isinstance(v, tuple) else v for k, v in options.items()})
        _save(parser, path)
    _BUILT[key] = parser
    return parser


def _load(path: Path) -> Lark | None:
    """The parser saved at ``path``, or None when there is none or it cannot be read."""
    try:
        with path.open("rb") as stream:
            return Lark.load(stream)
    except Exception:  # missing, cut short, written by another lark: build it anew
        return None


def _save(parser: Lark, path: Path) -> None:
    """Write ``parser`` to ``path`` whole; an unwritable cache is left alone."""
    write_whole(path, parser.save)


def write_whole(path: Path, write: Callable[[BinaryIO], object]) -> bool:
    """Call ``write(stream)`` on a temporary file beside ``path``, then rename it to ``path``, so that a
    process reading the cache never sees half a file; False (and nothing left behind) when the cache
    folder cannot be written."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        handle, name = tempfile.mkstemp(dir=path.parent, prefix=path.name, suffix=".tmp")
    except OSError:
        return False
    try:
        with os.fdopen(handle, "wb") as stream:
            write(stream)
        os.replace(name, path)
    except OSError:
        with contextlib.suppress(OSError):
            os.unlink(name)
        return False
    return True
