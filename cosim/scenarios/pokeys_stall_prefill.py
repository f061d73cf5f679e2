"""PoKeys host stall with enough prefill: the same 60 ms stall as ``pokeys_stall``, 100 slots queued, no underrun.

    host          ====|  stalled 60 ms       |=====
    buffer_level  100 \\_____________________/‾‾‾‾     lowest about 40 slots, never empty
    underrun      ________________________________

Checks: no underrun, and every pulse of the move is emitted.
"""

from __future__ import annotations

from cosim.checks import IntervalsAbove, ValueAt
from cosim.scenario import Param, Run
from cosim.scenarios.pokeys_stall import stalled_job

PARAMETERS = (
    Param("prefill", 100, "slots", (1, 128), "slots queued before the start, and the level the host keeps"),
    Param("stall_at_ms", 300, "ms", (0, 10_000), "when the host stalls"),
    Param("stall_ms", 60, "ms", (1, 10_000), "how long the host stalls"),
    Param("link", "usb", "", ("usb", "ethernet"), "host link profile"),
    Param("distance", 15_000, "pulses", (1, 1_000_000), "x travel of the move"),
)
UNTIL = "1.5 s"


def scenario(run: Run) -> None:
    _, host = stalled_job(run)
    run.check(IntervalsAbove("pokeys.underrun", 0, name="no buffer underrun"))
    run.check(ValueAt("pokeys.x.step", None, run.p.distance, name="every pulse of the move emitted"))

    def lowest_level() -> float:
        t, level = run.sim.trace.edges("pokeys.buffer_level")
        during = (t > (host.t_buffer_mode_ns or 0)) & (t < (host.t_last_accepted_ns or 0))
        return float(level[during].min()) if during.any() else 0.0

    run.figure("lowest_buffer_level_during_job", lowest_level, "slots")
