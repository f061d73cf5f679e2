"""cosim: a discrete-event co-simulation workbench for motion-controller timing.

Controllers run as SimPy processes in exact integer time; plants are FMUs that the master
advances only at the instants that matter; everything is recorded in a trace that checks,
exports and reports read.
"""

from cosim.errors import ConfigurationError, CosimError, FmuError, TimingViolation
from cosim.timebase import Priority, TimeBase

__all__ = [
    "ConfigurationError",
    "CosimError",
    "FmuError",
    "Priority",
    "TimeBase",
    "TimingViolation",
]

__version__ = "0.1.0"
