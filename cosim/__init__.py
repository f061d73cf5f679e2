"""cosim: a discrete-event co-simulation workbench for motion-controller timing.

Controllers run as SimPy processes in exact integer time; plants are FMUs that the master
advances only at the instants that matter; everything is recorded in a trace that checks,
exports and reports read.

``import cosim`` imports nothing else: the names below are looked up in their modules when first
used (so that ``cosim.timebase`` and the package do not import each other, and a command pays only
for what it runs).
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from cosim.errors import ConfigurationError, CosimError, FmuError, TimingViolation
    from cosim.timebase import Priority, TimeBase

#: The package's names, by the module that defines each.
_HOMES = {"ConfigurationError": "cosim.errors", "CosimError": "cosim.errors", "FmuError": "cosim.errors",
          "TimingViolation": "cosim.errors", "Priority": "cosim.timebase", "TimeBase": "cosim.timebase"}

__all__ = [
    "ConfigurationError",
    "CosimError",
    "FmuError",
    "Priority",
    "TimeBase",
    "TimingViolation",
]

__version__ = "0.1.0"


def __getattr__(name: str) -> Any:
    """``cosim.TimeBase`` and the other names of :data:`__all__`, imported when first used."""
    if name in _HOMES:
        value = getattr(import_module(_HOMES[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'cosim' has no attribute {name!r}")
