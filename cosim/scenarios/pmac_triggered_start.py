"""Turbo PMAC triggered time base: a servo slave starts its move exactly at a registration mark on the conveyor.

The triggered time-base entry (I8000=$978008, SF = 16384 / rtif) starts frozen; the motion
program loads the move, the PLC arms the entry at t_arm; the mark sensor is the capture trigger::

    mark       _______________________|‾|______
    method     $9 |$B‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾|$A‾‾‾‾‾     armed -> running at the first servo cycle after the mark
    time base  0  0  0  0  0  0  0  0  0 |100 %
    slave      0 ........................./‾‾‾

The captured position (1/T extended to 1/256 count) is time zero, so the slave's program time is
the master travel since the mark. Checks: time zero equals the master position at the mark
within 1/256 count, the entry runs within one servo period of the mark, the slave does not move
before it, and the sync error stays within the servo's following error.
"""

from __future__ import annotations

from collections.abc import Generator
from fractions import Fraction
from typing import Any

from cosim import rigs
from cosim.checks import Bound, Duration, EdgeRef, ValueAt
from cosim.controllers.pmac import ARMED, FROZEN, RUNNING, LinearMove, scale_factor_for
from cosim.plants.analytic import IdealConveyor
from cosim.rigs import SERVO_AXIS
from cosim.scenario import Param, Run
from cosim.timebase import Priority

PARAMETERS = (
    Param("rtif", 64, "counts/ms", (1, 4096), "real-time input frequency = conveyor speed (power of two)"),
    Param("mark_counts", 1000.3, "counts", (10.0, 5000.0), "registration mark position on the conveyor"),
    Param("t_arm_ms", 2.0, "ms", (0.5, 10.0), "when the PLC arms the entry"),
    Param("bandwidth_hz", 100.0, "Hz", (1.0, 225.0), "position-loop crossover of the PID design"),
    Param("sync_limit", 60.0, "counts", (0.0, 1e6), "largest allowed |sync error|"),
)
UNTIL = "120 ms"


def scenario(run: Run) -> None:
    sim, p = run.sim, run.p
    rtif = Fraction(p.rtif)
    mark = Fraction(str(p.mark_counts))
    belt = IdealConveyor(sim, speed_counts_per_ms=rtif, marks=[mark], mark_width_counts=5)
    rig = rigs.triggered_time_base(sim, belt, belt.mark, scale_factor=scale_factor_for(rtif, triggered=True),
                                   method=FROZEN, slave=SERVO_AXIS, bandwidth_hz=p.bandwidth_hz)
    rig.cs.run_program([LinearMove(2000, rtif * 1000, 20)])

    def plc() -> Generator[Any, Any, None]:
        yield sim.at(sim.ticks(p.t_arm_ms, "ms"), Priority.HOST)
        rig.pmac.set_ivar(8000, (ARMED << 20) | rigs.MASTER_CHANNEL)

    sim.process(plc())
    rig.pmac.start()

    t_mark = belt.mark_times[0][0]
    true_pos = belt.position(t_mark)
    period = int(-(-rig.pmac.clock.period_ticks // 1))
    run.check(ValueAt("pmac.ect.time_zero_pos", None, float(true_pos), tol=1 / 256,
                      name="time zero = master position at the mark (1/256 count)"))
    run.check(Duration(EdgeRef("conveyor.mark", 1), EdgeRef("pmac.ect.method", RUNNING), max=period,
                       name="running within one servo period of the mark"))
    run.check(ValueAt("pmac.motor1.cmd_pos", t_mark, 0, name="slave still before the mark"))
    run.check(Bound("pmac.motor1.sync_error", lower=-p.sync_limit, upper=p.sync_limit,
                    name="sync error within the servo's following error"))

    def start_error() -> float:
        starts = rig.entry.starts
        return float(Fraction(starts[0].time_zero_pos256, 256) - true_pos) if starts else float("nan")

    run.figure("start_error_counts", start_error, "counts")
    run.figure("mark_time_ms", t_mark / 1e6, "ms")
    assert rig.design is not None
    run.figure("phase_margin", rig.design.phase_margin_deg, "deg")
    run.figure("gain_margin", rig.design.gain_margin_db, "dB")
