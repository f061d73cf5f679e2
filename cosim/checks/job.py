"""Did the job happen? The controller's ``<device>.job`` signal at the end of the run.

Every controller family records the state of its job as an ``int`` signal (:class:`cosim.job.JobState`:
0 idle, 1 running, 2 done, 3 error stop, 4 limit stop, 5 emergency stop, 6 aborted) and writes why it
stopped on the run's console (source ``<device>.job``). :class:`JobCompleted` reads both from the
trace and nothing else::

    pokeys.job   0 ___|‾ 1 (running) ‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾|_ 4 (limit stop) ____________    FAIL at 6.03 s:
    console                                       6.03 s  pokeys.job  LIMIT: x hit its positive limit switch

A run whose other checks all pass but whose job stopped at a limit switch, never started, or was
still running when the run ended is not a PASS.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from cosim import validate
from cosim.checks.base import Check, Clock, Findings, records, unit_of
from cosim.checks.result import Violation
from cosim.job import ENDED, JobState

if TYPE_CHECKING:
    from cosim.trace import Trace

#: The end states a job may be expected to reach, by their names in machine files.
ENDS = {"done": JobState.DONE, "error": JobState.ERROR, "limit": JobState.LIMIT,
        "emergency": JobState.EMERGENCY, "aborted": JobState.ABORTED}
_SAID = {JobState.IDLE: "never started", JobState.RUNNING: "was still running when the run ended",
         JobState.DONE: "completed", JobState.ERROR: "stopped on an error", JobState.LIMIT: "stopped at a limit",
         JobState.EMERGENCY: "stopped by an emergency stop", JobState.ABORTED: "was aborted"}


@dataclass(frozen=True)
class JobCompleted(Check):
    """The controller's job ran to its end: the last value of its ``<device>.job`` signal is DONE.

    Parameters
    ----------
    signal : str
        The job signal, ``<device>.job`` (``trio.job``, ``pmac.job``, ``pokeys.job``).
    ends : {'done', 'error', 'limit', 'emergency', 'aborted'}
        The state the job is expected to end in: ``'done'`` (every program reached its end) for a
        healthy machine; a stop (``'limit'``) where a machine file demonstrates that stop.

    Notes
    -----
    ``checked`` is 1: the job's end. A violation (``t_ns`` the instant the job stopped, or the
    run's end for a job that never started or was still running; ``value`` the state reached;
    ``limit`` the expected state) says how the job ended, with the stop's reason from the run's
    console. Measured: ``state`` (the last value) and ``end_ns`` (when the job ended; absent if
    it did not). A trace without the signal (a controller that does not report its job) is
    examined nothing (``UNCHECKED``), never a pass.

    Examples
    --------
    >>> from cosim.trace import Trace
    >>> trace = Trace()
    >>> trace.declare("pokeys.job", "int")
    >>> for t, v in [(0, 0), (1_000_000, 1), (6_030_000_000, 4)]:
    ...     trace.record("pokeys.job", t, v)
    >>> trace.write_line(6_030_000_000, "pokeys.job", "LIMIT: x hit its positive limit switch")
    >>> JobCompleted("pokeys.job").evaluate(trace).summary()  # doctest: +NORMALIZE_WHITESPACE
    'FAIL JobCompleted(pokeys.job): 1 checked, 1 violation; first at t=6030000000 ns: 4 vs limit 2
     (the job stopped at a limit (LIMIT) at 6.03 s: x hit its positive limit switch)'
    """

    signal: str
    ends: str = "done"

    def __post_init__(self) -> None:
        validate.choice(self.ends, "ends", tuple(ENDS), where=self.where)

    @property
    def label(self) -> str:
        if self.name:
            return self.name
        ends = "" if self.ends == "done" else f", ends={self.ends}"
        return f"JobCompleted({self.signal}{ends})"

    def examine(self, trace: Trace, clock: Clock) -> Findings:
        expected = ENDS[self.ends]
        found = Findings(self.signal, description=f"the job of {self.signal.rpartition('.')[0] or self.signal} "
                                                  f"ends {expected.name}",
                         empty_detail=f"no signal {self.signal} in the trace: this controller does not report its "
                                      "job, so whether it completed was not examined")
        if self.signal not in trace.info:
            return found
        t, v = records(trace, self.signal, self)
        state = JobState(int(v[-1])) if v.size else JobState.IDLE
        t_change = job_end_t(trace, self.signal)
        found.checked = 1
        found.measured["state"] = int(state)
        if t_change is not None:
            found.measured["end_ns"] = clock.t_ns(t_change)
        if state == expected:
            return found
        at = t_change if t_change is not None else max(trace.end_t, int(t[-1]) if t.size else 0)
        detail = f"the job {_SAID[state]} ({state.name})"
        if t_change is not None:
            detail += f" at {trace.timebase.seconds(t_change):g} s"
        reason = _reason(trace, self.signal, t_change)
        if reason:
            detail += f": {reason}"
        found.n_violations = 1
        found.violations.append(Violation(clock.t_ns(at), int(state), int(expected), detail,
                                          unit=unit_of(trace, self.signal)))  # states, named by the signal
        return found


def _reason(trace: Trace, signal: str, t: int | None) -> str:
    """The reason the job's stop wrote on the console (``STATE: reason``, source = the signal), last one at ``t``."""
    if t is None:
        return ""
    said = ""
    for line in trace.console():
        if line.source == signal and line.t <= t:
            said = line.text.partition(": ")[2] or line.text
    return said


def job_end_t(trace: Trace, signal: str) -> int | None:
    """When the job of ``signal`` ended [ticks]: the instant its signal last changed to an end state.

    None when the signal is not in the trace, or its last value is not an end state (the job never
    started, or was still running when the run ended). This is the figure ``job_s``.

    Examples
    --------
    >>> from cosim.trace import Trace
    >>> trace = Trace()
    >>> trace.declare("trio.job", "int")
    >>> for t, v in [(0, 0), (0, 1), (2_084_000_000, 2)]:
    ...     trace.record("trio.job", t, v)
    >>> job_end_t(trace, "trio.job")
    2084000000
    """
    if signal not in trace.info:
        return None
    t, v = trace.edges(signal)
    if not v.size or JobState(int(v[-1])) not in ENDED:
        return None
    changes = np.flatnonzero(np.diff(v, prepend=float(JobState.IDLE)) != 0)
    return int(t[changes[-1]])
