"""PMAC host %n slewing: %0, then %100 and %50 from the host; the time base slews at Ix94 per servo cycle.

CS1's time base comes from its own % command register (Ix93 at its default $2000). The host
writes %100 at t_up and %50 at t_down; the actual value moves by at most Ix94 per cycle::

    %cmd      0 |‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾|50‾‾‾‾‾‾‾
    actual    0 |   /‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾|‾‾‾\\_____     1644 per cycle with the default Ix94
                t_up  +1000 ms       t_down +500 ms

With the defaults 0 -> 100 % takes ceil(I10 / Ix94) = 2259 cycles (the manual's "about one
second"). A programmed move runs meanwhile, scaled by the time base. Checks: the exact number of
servo cycles of each slew and the final percentages.
"""

from __future__ import annotations

from collections.abc import Generator
from typing import Any

from cosim.checks import Duration, EdgeRef, ValueAt
from cosim.controllers.pmac import IX94_DEFAULT, LinearMove, Pmac
from cosim.scenario import Param, Run
from cosim.timebase import Priority

PARAMETERS = (
    Param("ix94", IX94_DEFAULT, "2^-23 ms/cycle", (1, 8_388_607), "Ix94 time-base slew limit"),
    Param("t_up_ms", 10, "ms", (1, 100), "when the host sends %100"),
    Param("t_down_ms", 1200, "ms", (200, 2000), "when the host sends %50"),
)
UNTIL = "1800 ms"


def scenario(run: Run) -> None:
    sim, p = run.sim, run.p
    pmac = Pmac(sim)
    cs = pmac.coordinate_system(1)
    pmac.set_ivar(194, p.ix94)
    pmac.add_motor(1)
    pmac.command_percent(1, 0)
    cs.run_program([LinearMove(10**6, 10_000, 100)])

    def host() -> Generator[Any, Any, None]:
        yield sim.at(sim.ticks(p.t_up_ms, "ms"), Priority.HOST)
        pmac.command_percent(1, 100)
        yield sim.at(sim.ticks(p.t_down_ms, "ms"), Priority.HOST)
        pmac.command_percent(1, 50)

    sim.process(host())
    pmac.start()

    clock, i10 = pmac.clock, pmac.i10
    half = round(i10 / 2)
    up_cycles = -(-i10 // p.ix94)
    down_cycles = -(-(i10 - half) // p.ix94)
    k_up = clock.first_cycle_at_or_after(sim.ticks(p.t_up_ms, "ms"))
    k_down = clock.first_cycle_at_or_after(sim.ticks(p.t_down_ms, "ms"))
    run.check(Duration(EdgeRef("pmac.cs1.timebase_source", i10, which="first"), EdgeRef("pmac.cs1.timebase", i10),
                       equals=clock.t(k_up + up_cycles - 1) - clock.t(k_up),
                       name="0 -> 100 % in ceil(I10 / Ix94) servo cycles"))
    run.check(Duration(EdgeRef("pmac.cs1.timebase_source", half), EdgeRef("pmac.cs1.timebase", half),
                       equals=clock.t(k_down + down_cycles - 1) - clock.t(k_down),
                       name="100 -> 50 % in ceil(I10 / 2 / Ix94) servo cycles"))
    run.check(ValueAt("pmac.cs1.timebase_pct", sim.ticks(p.t_down_ms, "ms") - 1, 100, name="100 % before %50"))
    run.check(ValueAt("pmac.cs1.timebase_pct", None, float(100 * half / i10), name="50 % at the end"))
    run.figure("slew_up_ms", float((up_cycles - 1) * clock.period_ns / 10**6), "ms")
    run.figure("slew_up_cycles", up_cycles)
    run.figure("axis_position", lambda: float(cs.position("X")), "units")
