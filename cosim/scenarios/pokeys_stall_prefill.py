"""PoKeys host stall with enough prefill: the same 60 ms stall as ``pokeys_stall``, 100 slots queued, no underrun.

    host          ====|  stalled 60 ms       |=====
    buffer_level  100 \\_____________________/‾‾‾‾     lowest about 40 slots, never empty
    underrun      ________________________________

Checks: no underrun, and every pulse of the move is emitted.
"""

from __future__ import annotations

from dataclasses import replace

from cosim.checks import ValueAt
from cosim.scenario import Run
from cosim.scenarios import pokeys_stall
from cosim.scenarios.pokeys_stall import no_underrun, stalled_job

PARAMETERS = tuple(replace(p, default=100) if p.name == "prefill" else p for p in pokeys_stall.PARAMETERS)
UNTIL = "1.5 s"


def scenario(run: Run) -> None:
    _, host = stalled_job(run)
    run.check(no_underrun())
    run.check(ValueAt("pokeys.x.step", None, run.p.distance, name="every pulse of the move emitted"))

    def lowest_level() -> float:
        t, level = run.sim.trace.edges("pokeys.buffer_level")
        during = (t > (host.t_buffer_mode or 0)) & (t < (host.t_last_accepted or 0))
        return float(level[during].min()) if during.any() else 0.0

    run.figure("lowest_buffer_level_during_job", lowest_level, "slots")
