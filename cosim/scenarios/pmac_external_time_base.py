"""PMAC external time base: a servo slave tracks a conveyor whose speed drops from the real-time input frequency to 3/4.

The conveyor's encoder feeds a 1/T conversion-table entry and an untriggered time-base entry with
SCALE_FACTOR = 131072 / rtif; CS1 follows it (I5193=@I8002, Ix94 at its maximum). The slave runs
one long LINEAR move at F = rtif counts/ms, so at 100 % it moves count for count with the master::

    conveyor speed  ‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾\\__________      rtif, then 3/4 rtif
    time base %     100 ‾‾‾‾‾‾‾‾‾‾‾‾‾\\_ 75 ______
    Ix94 active     ____________________________      never: no slip
                    0       30 ms   40 ms     70 ms

The slave is a DC motor stand-in under a PID designed with python-control for bandwidth_hz.
Checks: 100 % and 75 % within one 1/32-count quantum, no slip, the Ix94 limit never acts, and the
sync error (master-derived position minus actual) stays within the servo's following error.
"""

from __future__ import annotations

from fractions import Fraction

from cosim import rigs
from cosim.checks import Bound, IntervalsAbove, ValueAt
from cosim.controllers.pmac import LinearMove, scale_factor_for
from cosim.controllers.pmac.units import IX94_MAX
from cosim.plants.analytic import IdealConveyor
from cosim.rigs import SERVO_AXIS
from cosim.scenario import Param, Run

PARAMETERS = (
    Param("rtif", 64, "counts/ms", (1, 4096), "real-time input frequency (a power of two: SF = 131072 / rtif)"),
    Param("ix94", IX94_MAX, "2^-23 ms/cycle", (0, IX94_MAX), "Ix94 time-base slew limit"),
    Param("bandwidth_hz", 100.0, "Hz", (1.0, 225.0), "position-loop crossover of the PID design"),
    Param("sync_limit", 60.0, "counts", (0.0, 1e6), "largest allowed |sync error|"),
)
UNTIL = "70 ms"


def scenario(run: Run) -> None:
    sim, p = run.sim, run.p
    ms = sim.ticks("1 ms")
    rtif = Fraction(p.rtif)
    belt = IdealConveyor(sim, speed_counts_per_ms=rtif, phases=[(30 * ms, 0), (10 * ms, -rtif / 40)])
    rig = rigs.external_time_base(sim, belt, scale_factor=scale_factor_for(rtif), ix94=p.ix94,
                                  slave=SERVO_AXIS, bandwidth_hz=p.bandwidth_hz)
    rig.cs.run_program([LinearMove(10**7, rtif * 1000, 50)])
    rig.pmac.start()

    quantum = 100 * 2 * scale_factor_for(rtif) / rig.pmac.i10  # one 1/32 count per cycle, in %
    run.check(ValueAt("pmac.cs1.timebase_pct", 25 * ms, 100, tol=quantum,
                      name="100 % at the real-time input frequency"))
    run.check(ValueAt("pmac.cs1.timebase_pct", 65 * ms, 75, tol=quantum, name="75 % at 3/4 of it"))
    run.check(Bound("pmac.cs1.slip", lower=0, upper=0, name="no slip"))
    run.check(IntervalsAbove("pmac.cs1.ix94_active", 0.5, name="Ix94 limit never acts"))
    run.check(Bound("pmac.motor1.sync_error", lower=-p.sync_limit, upper=p.sync_limit,
                    name="sync error within the servo's following error"))

    design = rig.design
    assert design is not None
    run.figure("phase_margin", design.phase_margin_deg, "deg")
    run.figure("gain_margin", design.gain_margin_db, "dB")
    run.figure("closed_loop_bandwidth", design.bandwidth_hz, "Hz")
    run.figure("scale_factor", scale_factor_for(rtif))
    run.figure("final_percent", lambda: float(rig.cs.percent), "%")
