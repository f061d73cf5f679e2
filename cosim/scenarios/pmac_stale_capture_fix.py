"""Turbo PMAC stale-capture fix: a dummy read of the capture register after freezing; motion starts at the right mark.

Same timing as ``pmac_stale_capture`` (entry left running, mark 1 captured and never read, freeze
and arm between the same two servo interrupts), but the motion program reads the capture register
X:$07800B (entry address + 3) right after freezing. That resets the trigger logic, so the armed
entry waits for mark 2::

    mark       __|‾|_______________________________|‾|____
    flag       __|‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾|_______________|‾‾‾
    freeze/arm+read                 ^^
    method     $A ‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾|$B ‾‾‾‾‾‾‾‾‾‾‾‾‾‾|$A      starts at mark 2

Checks: time zero equals the master position at mark 2 within 1/256 count, the entry is still
armed just before mark 2 and runs within one servo period after it.
"""

from __future__ import annotations

from cosim.checks import Duration, EdgeRef
from cosim.controllers.pmac import RUNNING
from cosim.scenario import Run
from cosim.scenarios import pmac_stale_capture

PARAMETERS = tuple(p for p in pmac_stale_capture.PARAMETERS if p.name != "dummy_read")
UNTIL = "40 ms"


def scenario(run: Run) -> None:
    belt, rig, t_mark2 = pmac_stale_capture.stale_capture_run(run, dummy_read=True)
    period = int(-(-rig.pmac.clock.period_ticks // 1))
    for rule in pmac_stale_capture.correct_start(belt, t_mark2):
        run.check(rule)
    run.check(Duration(EdgeRef("conveyor.mark", 1, which="last"), EdgeRef("pmac.ect.method", RUNNING), max=period,
                       name="running within one servo period of mark 2"))

