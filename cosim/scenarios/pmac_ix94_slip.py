"""PMAC Ix94 too low during a fast master acceleration: the time base lags, slip is reported in master counts.

The conveyor accelerates from rest to rtif counts/ms in accel_ms; the time-base source follows
within a few servo cycles, but the actual time base may only rise by Ix94 per servo cycle::

    source       _/‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾
    actual       _____/‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾      slope Ix94 per cycle
    Ix94 active  _|‾‾‾|__________________      the cycles the limit acted
    slip         0 ↗ constant (master counts never made up)

The slave is ideal (act = cmd), so the sync error is the slip in slave counts. The hazard: the
healthy rule of ``pmac_ix94_max``, "no slip", fails (verdict HAZARD SHOWN). Checks of the model:
the slip at the end matches the area between the two ramps (within slip_tol), and the limit acts
in one stretch of about (I10 - first source value) / Ix94 cycles. With an Ix94 larger than the
source's change per cycle the expected slip is 0, the limit must never act, and the hazard is
missed. Compare ``pmac_ix94_max``.
"""

from __future__ import annotations

from fractions import Fraction

from cosim import rigs
from cosim.checks import Bound, Duration, EdgeRef, IntervalsAbove, ValueAt
from cosim.controllers.pmac import LinearMove, scale_factor_for
from cosim.plants.analytic import IdealConveyor
from cosim.scenario import Param, Run

PARAMETERS = (
    Param("ix94", 16384, "2^-23 ms/cycle", (1, 500_000), "Ix94 time-base slew limit (too low)"),
    Param("accel_ms", 5, "ms", (1, 50), "master acceleration time from rest to rtif"),
    Param("rtif", 64, "counts/ms", (1, 4096), "real-time input frequency (power of two)"),
    Param("slip_tol", 0.15, "", (0.0, 1.0), "relative tolerance of the slip estimate"),
)
UNTIL = "300 ms"


def scenario(run: Run) -> None:
    sim, p = run.sim, run.p
    rtif = Fraction(p.rtif)
    accel_ticks = sim.ticks(p.accel_ms, "ms")
    belt = IdealConveyor(sim, phases=[(accel_ticks, rtif / p.accel_ms)])
    sf = scale_factor_for(rtif)
    rig = rigs.external_time_base(sim, belt, scale_factor=sf, ix94=p.ix94)
    rig.cs.run_program([LinearMove(10**7, rtif * 1000, 10)])
    rig.pmac.start()

    i10 = rig.pmac.i10
    clock = rig.pmac.clock
    ramp_cycles = Fraction(accel_ticks) / clock.period_ticks
    # master counts: the area between the Ix94 ramp and the source's ramp (none if Ix94 keeps up)
    estimate = max(Fraction(0), Fraction(i10, 2) * (Fraction(i10, p.ix94) - ramp_cycles) / (64 * sf))
    run.hazard(no_slip(), shows=f"Ix94 = {p.ix94} is too low for a {p.accel_ms} ms master acceleration: the time "
                                "base lags and the slave slips master counts that are never made up")
    run.check(ValueAt("pmac.cs1.slip", None, float(estimate), tol=max(1.0, float(p.slip_tol * estimate)),
                      name="slip reported: the area between the source and Ix94 ramps"))
    if estimate > 0:
        limit_cycles = Fraction(i10, p.ix94) - ramp_cycles / 2
        run.check(Duration(EdgeRef("pmac.cs1.ix94_active", 1), EdgeRef("pmac.cs1.ix94_active", 0),
                           equals=int(limit_cycles * clock.period_ticks),
                           tol=int(limit_cycles * clock.period_ticks / 10),
                           name="Ix94 acts for about I10/Ix94 cycles"))
    else:
        run.check(IntervalsAbove("pmac.cs1.ix94_active", 0.5, name="Ix94 fast enough: the limit never acts"))

    def first_last() -> tuple[int, int]:
        cycles = rig.cs.limit_cycles
        return (cycles[0], cycles[-1]) if cycles else (-1, -1)

    run.figure("slip_counts", lambda: float(rig.cs.slip_counts or 0), "counts")
    run.figure("slip_estimate_counts", float(estimate), "counts")
    run.figure("limit_cycles", lambda: len(rig.cs.limit_cycles))
    run.figure("first_limit_cycle", lambda: first_last()[0])
    run.figure("last_limit_cycle", lambda: first_last()[1])
    run.figure("slave_lag_counts", lambda: float(rig.cs.ideal_position("X") - rig.cs.position("X")), "counts")


def no_slip() -> Bound:
    """The healthy rule (shared with ``pmac_ix94_max``): the time base never slips."""
    return Bound("pmac.cs1.slip", lower=0, upper=0, name="no slip")
