"""Checks shared by the plants' parameter records (the Python companions of the FMU parameters)."""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import fields
from typing import Any, TypeVar

from cosim.errors import ConfigurationError

T = TypeVar("T")


def require_finite(record: object, names: Iterable[str], *, positive: bool, where: str) -> None:
    """Refuse a field of ``record`` that is not finite and ``> 0`` (``positive``) or ``>= 0``."""
    for name in names:
        value = getattr(record, name)
        if not (math.isfinite(value) and (value > 0 if positive else value >= 0)):
            raise ConfigurationError.out_of_range(name, value, "> 0" if positive else ">= 0", where=where)


def from_mapping(cls: type[T], values: Mapping[str, Any], *, model: str, solver_only: frozenset[str]) -> T:
    """``cls`` (a parameter dataclass) from FMU parameter values, e.g. a preset.

    Names in ``solver_only`` steer only the FMU and are ignored; any other unknown name is refused.
    """
    known = {f.name for f in fields(cls)}  # type: ignore[arg-type]
    unknown = sorted(set(values) - known - solver_only)
    if unknown:
        raise ConfigurationError(f"not {model} parameters: {', '.join(unknown)} (known: {', '.join(sorted(known))})")
    return cls(**{name: value for name, value in values.items() if name in known})
