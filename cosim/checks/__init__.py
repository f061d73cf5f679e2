"""Timing checks: rules evaluated on a finished trace, with exact integer time.

A check is a small frozen dataclass; a scenario declares it with ``run.check(spec)`` and the
runner calls ``spec.evaluate(sim.trace)`` after the run, which returns a :class:`CheckResult`.
Checks read the trace and nothing else. Parameters are integer ticks of the trace's time base
(1 ns by default: use ``sim.ticks("25 us")``); results report instants and durations in ns.

A check that examined nothing neither passes nor fails: its outcome is ``UNCHECKED``
(``allow_empty=True`` where examining nothing is fine); a pass means something was checked.
See ``docs/checks.md`` for every check, its parameters and its report.

Examples
--------
>>> from cosim.trace import Trace
>>> trace = Trace()
>>> trace.declare("pokeys.x.step", "pulse")
>>> trace.record_segment("pokeys.x.step", 0, 1_000_000, 25, 1)  # 25 pulses in a 1 ms slot
>>> MaxPulseRate("pokeys.x.step", 25_000).evaluate(trace).summary()
'PASS MaxPulseRate(pokeys.x.step): 25 checked, 0 violations'
"""

from cosim.checks.base import Check, Clock, Findings
from cosim.checks.direction import DirectionSetup
from cosim.checks.duration import Duration, EdgeRef, PulseRef
from cosim.checks.edge_position import EdgeAtPosition
from cosim.checks.energy import EnergyPerLength
from cosim.checks.job import JobCompleted
from cosim.checks.levels import Bound, IntervalsAbove, IntervalsBelow, NoUnderrun, ValueAt
from cosim.checks.pulse_timing import MaxPulseRate, MinPulseSpacing, PulsesPerWindow
from cosim.checks.result import MAX_REPORTED, CheckResult, Violation
from cosim.checks.travel import Travel

__all__ = [
    "MAX_REPORTED",
    "Bound",
    "Check",
    "CheckResult",
    "Clock",
    "DirectionSetup",
    "Duration",
    "EdgeAtPosition",
    "EdgeRef",
    "EnergyPerLength",
    "Findings",
    "IntervalsAbove",
    "IntervalsBelow",
    "JobCompleted",
    "MaxPulseRate",
    "MinPulseSpacing",
    "NoUnderrun",
    "PulseRef",
    "PulsesPerWindow",
    "Travel",
    "ValueAt",
    "Violation",
]
