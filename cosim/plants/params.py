"""What the plants' parameter records share (the Python companions of the FMU parameters).

Their values are checked with :mod:`cosim.validate` in each record's ``__post_init__``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import fields
from typing import Any, TypeVar

from cosim.errors import ConfigurationError

T = TypeVar("T")


def from_mapping(cls: type[T], values: Mapping[str, Any], *, model: str, solver_only: frozenset[str]) -> T:
    """``cls`` (a parameter dataclass) from FMU parameter values, e.g. a preset.

    Names in ``solver_only`` steer only the FMU and are ignored; any other unknown name is refused.
    """
    known = {f.name for f in fields(cls)}  # type: ignore[arg-type]
    unknown = sorted(set(values) - known - solver_only)
    if unknown:
        raise ConfigurationError(f"not {model} parameters: {', '.join(unknown)} (known: {', '.join(sorted(known))})")
    return cls(**{name: value for name, value in values.items() if name in known})
