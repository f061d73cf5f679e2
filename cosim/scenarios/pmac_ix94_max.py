"""PMAC Ix94 at its maximum (8,388,607) during a fast master acceleration: no slip, the slave stays on the master.

Same conveyor as ``pmac_ix94_slip`` (rest to rtif counts/ms in accel_ms), but the time base may
change by up to 8,388,607 per servo cycle, more than any 24-bit time-base value can jump::

    source       _/‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾
    actual       _/‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾     = source every cycle
    Ix94 active  ___________________     never
    slip         0

The slave is ideal, so its commanded position must equal the master-derived one exactly.
"""

from __future__ import annotations

from fractions import Fraction

from cosim import rigs
from cosim.checks import Bound, IntervalsAbove
from cosim.controllers.pmac import IX94_MAX, LinearMove, scale_factor_for
from cosim.plants.analytic import IdealConveyor
from cosim.scenario import Param, Run
from cosim.scenarios.pmac_ix94_slip import no_slip

PARAMETERS = (
    Param("accel_ms", 5, "ms", (1, 50), "master acceleration time from rest to rtif"),
    Param("rtif", 64, "counts/ms", (1, 4096), "real-time input frequency (power of two)"),
)
UNTIL = "100 ms"


def scenario(run: Run) -> None:
    sim, p = run.sim, run.p
    rtif = Fraction(p.rtif)
    belt = IdealConveyor(sim, phases=[(sim.ticks(p.accel_ms, "ms"), rtif / p.accel_ms)])
    rig = rigs.external_time_base(sim, belt, scale_factor=scale_factor_for(rtif), ix94=IX94_MAX)
    rig.cs.run_program([LinearMove(10**7, rtif * 1000, 10)])
    rig.pmac.start()

    run.check(no_slip())
    run.check(IntervalsAbove("pmac.cs1.ix94_active", 0.5, name="Ix94 limit never acts"))
    run.check(Bound("pmac.motor1.sync_error", lower=0, upper=0, name="slave command = master-derived position"))
    run.figure("slip_counts", lambda: float(rig.cs.slip_counts or 0), "counts")
    run.figure("master_counts", lambda: float(belt.position(sim.now)), "counts")
