"""The job a controller runs, and how it ended: one ``<device>.job`` signal per controller.

A verdict must not flatter: a machine whose program stopped at a limit switch, or never ran, has
not done its job, whatever its other checks say. So every controller family records the state of
its job in the trace, as an ``int`` signal whose values are :class:`JobState`, and says why it
stopped on the run's console. The check :class:`cosim.checks.JobCompleted` reads that signal (checks
read the trace only); the figure ``job_s`` is the instant the job ended.

What "the job" is, per family (each family drives its :class:`Job`):

======== ====================================================================================
Trio     the processes a machine file starts ([[program]]), until each has stopped
PMAC     the motion programs started, until each has run to its end (PLCs run on: they are
         not the job)
PoKeys   the moves or the G-code program, until M2/M30/``%`` is reached and the buffer drained
======== ====================================================================================

A job is made of *parts* (a process, a motion program, a G-code file): :meth:`Job.begin` one when
it starts and :meth:`Job.finish` it when it reaches its end. The job is ``DONE`` at the instant the
last part finishes. :meth:`Job.stop` ends it early with a reason (a limit switch, an emergency
stop, a program error): the state says which, the reason goes to the console.

Examples
--------
>>> from cosim.kernel import Simulation
>>> sim = Simulation()
>>> job = Job(sim, "trio")
>>> job.begin("process 1"); job.begin("process 2")
>>> job.finish("process 1")
>>> JobState(job.signal.value).name
'RUNNING'
>>> job.finish("process 2")
>>> JobState(job.signal.value).name, job.end_t
('DONE', 0)
"""

from __future__ import annotations

from enum import IntEnum
from typing import TYPE_CHECKING

from cosim.signals import Signal

if TYPE_CHECKING:
    from cosim.kernel import Simulation


class JobState(IntEnum):
    """Values of a ``<device>.job`` signal."""

    #: Nothing has started yet (a job that never starts is not done).
    IDLE = 0
    #: At least one part is running.
    RUNNING = 1
    #: Every part reached its end.
    DONE = 2
    #: A program error stopped it (Trio run-time error, PMAC program fault, a G-code error).
    ERROR = 3
    #: A hardware or soft limit stopped it (limit switch, travel, following error).
    LIMIT = 4
    #: An emergency stop stopped it.
    EMERGENCY = 5
    #: Stopped by a command or the machine, for another reason (given on the console).
    ABORTED = 6


#: States in which the job has ended (the last value of the signal tells how).
ENDED = frozenset({JobState.DONE, JobState.ERROR, JobState.LIMIT, JobState.EMERGENCY, JobState.ABORTED})


class Job:
    """The job of one controller: its ``<device>.job`` signal and the parts still running.

    Parameters
    ----------
    sim : Simulation
    device : str
        The controller's device name (``trio``, ``pmac``, ``pokeys``): the signal is ``<device>.job``.
    """

    def __init__(self, sim: Simulation, device: str) -> None:
        self.sim = sim
        self.device = device
        self.signal = Signal(sim, f"{device}.job", kind="int", initial=JobState.IDLE,
                             description="the controller's job: 0 idle, 1 running, 2 done, 3 error stop, "
                                         "4 limit stop, 5 emergency stop, 6 aborted (cosim.job.JobState)")
        self.running: list[str] = []
        #: The instant the job ended (done or stopped) [ticks], or None while it has not.
        self.end_t: int | None = None
        #: Why it stopped early (None if it did not).
        self.reason: str | None = None

    @property
    def state(self) -> JobState:
        return JobState(int(self.signal.value))

    def begin(self, part: str) -> None:
        """A part of the job starts now (a part that is running already is left alone)."""
        if self.state in ENDED and self.state != JobState.DONE:
            return  # stopped: nothing starts again by itself
        if part not in self.running:
            self.running.append(part)
        self.end_t = None
        self.signal.set(JobState.RUNNING)

    def finish(self, part: str) -> None:
        """``part`` reached its end now; the job is done when no part is left."""
        if part in self.running:
            self.running.remove(part)
            if not self.running and self.state == JobState.RUNNING:
                self.end_t = self.sim.now
                self.signal.set(JobState.DONE)

    def stop(self, state: JobState, reason: str) -> None:
        """The job is stopped now for ``reason`` (``state`` one of ERROR, LIMIT, EMERGENCY, ABORTED).

        The reason is written to the console (source ``<device>.job``). A job stopped already keeps
        its first reason.
        """
        if state not in ENDED or state == JobState.DONE:
            raise ValueError(f"Job.stop takes ERROR, LIMIT, EMERGENCY or ABORTED, not {state!r}")
        if self.state in ENDED and self.state != JobState.DONE:
            return
        self.running.clear()
        self.end_t, self.reason = self.sim.now, reason
        self.sim.trace.write_line(self.sim.now, f"{self.device}.job", f"{JobState(state).name}: {reason}")
        self.signal.set(state)
