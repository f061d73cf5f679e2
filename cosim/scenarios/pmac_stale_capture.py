"""Turbo PMAC stale-capture hazard: freeze and arm in one servo interval, so a stale capture starts motion early.

The entry is left running ($A), so nothing reads the capture register when mark 1 passes: the
capture flag stays set. The motion program freezes the entry and the PLC arms it 100 us later,
between the same two servo interrupts (a lightly loaded Turbo PMAC), so no servo cycle sees it
frozen and nothing resets the trigger logic. The armed entry sees the old flag at once::

    mark       __|‾|_______________________________|‾|____      mark 1 (500), mark 2 (1500)
    flag       __|‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾|___________
    servo      |    |    |    |    |    |    |    |    |
    freeze/arm                        ^^
    method     $A ‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾|$A (stale start, ~680 counts before mark 2)

The hazard: two rules of a correct start (those of ``pmac_stale_capture_fix``) fail: time zero is
the master position at mark 2, and the entry is still armed just before mark 2 (verdict HAZARD
SHOWN: time zero is mark 1, the entry runs before mark 2). With ``--set dummy_read=true`` the
program reads X:$07800B after freezing (the manual's fix), the start is correct and the hazard is
missed; ``pmac_stale_capture_fix`` is that run, where the same rules pass.
"""

from __future__ import annotations

from cosim import rigs
from cosim.checks import ValueAt
from cosim.controllers.pmac import ARMED, TriggeredTimeBaseEntry
from cosim.plants.analytic import IdealConveyor
from cosim.rigs import Rig
from cosim.scenario import Param, Run

PARAMETERS = (
    Param("dummy_read", False, "", None, "read the capture register after freezing (the fix)"),
    Param("t_freeze_ms", 12.0, "ms", (9.0, 20.0), "when the motion program freezes the entry"),
    Param("arm_after_us", 100, "us", (1, 5000), "PLC arms this long after the freeze"),
)
UNTIL = "40 ms"


def stale_capture_run(run: Run, *, dummy_read: bool) -> tuple[IdealConveyor, Rig[TriggeredTimeBaseEntry], int]:
    """The set-up and the time-zero error figure (shared with ``pmac_stale_capture_fix``); returns
    the belt, the rig and the instant of mark 2."""
    sim, p = run.sim, run.p
    belt, rig = rigs.stale_capture(sim, t_freeze=sim.ticks(p.t_freeze_ms, "ms"),
                                   arm_after=sim.ticks(p.arm_after_us, "us"), dummy_read=dummy_read)
    t_mark2 = belt.mark_times[1][0]

    def time_zero_error() -> float:
        starts = rig.entry.starts
        return float(starts[0].time_zero_pos256 / 256 - belt.position(t_mark2)) if starts else float("nan")

    run.figure("time_zero_error_counts", time_zero_error, "counts")
    return belt, rig, t_mark2


def scenario(run: Run) -> None:
    belt, rig, t_mark2 = stale_capture_run(run, dummy_read=run.p.dummy_read)
    at_mark2, armed = correct_start(belt, t_mark2)
    run.hazard(at_mark2, shows="freeze and arm in one servo interval: the stale capture of mark 1 becomes time zero")
    run.hazard(armed, shows="the stale capture starts motion at once, before mark 2")

    def early() -> float:
        starts = rig.entry.starts
        return float(belt.position(starts[0].t) - belt.position(t_mark2)) if starts else float("nan")

    run.figure("master_at_start_minus_mark2_counts", early, "counts")
    run.figure("saturated_cycles", lambda: len(rig.entry.saturated_cycles))


def correct_start(belt: IdealConveyor, t_mark2: int) -> tuple[ValueAt, ValueAt]:
    """Two rules of a correct triggered start (shared with ``pmac_stale_capture_fix``): time zero is the
    master position at mark 2 (1/256 count), and the entry is still armed just before mark 2."""
    return (ValueAt("pmac.ect.time_zero_pos", None, float(belt.position(t_mark2)), tol=1 / 256,
                    name="time zero = master position at mark 2 (1/256 count)"),
            ValueAt("pmac.ect.method", t_mark2 - 1, ARMED, name="still armed just before mark 2"))
