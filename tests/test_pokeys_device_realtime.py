"""Real-time pacing with a fake wall clock: which slot starts run when, and the lag report.

::

    wall clock  0 ........ 2.5 ms                     3.2 ms
    catch-up             ^ slot starts 0, 1, 2 ms run   ^ slot start 3 ms runs
    sim.now     0        3 ms (end of the running slot) 4 ms
"""

from __future__ import annotations

from collections.abc import Generator
from typing import Any

from cosim.kernel import Simulation
from cosim.pokeys_device.realtime import RealtimePacer
from cosim.timebase import Priority

#: The pulse engine's time slot: "1 millisecond time slots" (PoKeys pulse engine documentation).
SLOT_NS = 1_000_000


class FakeClock:
    """A wall clock [ns] that moves only when the test says so."""

    def __init__(self) -> None:
        self.t_ns = 1_000_000_000

    def __call__(self) -> int:
        return self.t_ns


def slot_starts(sim: Simulation, log: list[object]) -> Generator[Any, Any, None]:
    k = 0
    while True:
        yield sim.at(k * SLOT_NS, Priority.SLOT)
        log.append(sim.now)
        k += 1


def test_catch_up_runs_every_slot_start_the_wall_clock_has_reached(sim: Simulation, log: list[object]) -> None:
    clock = FakeClock()
    pacer = RealtimePacer(sim, clock=clock)
    sim.process(slot_starts(sim, log))
    pacer.catch_up()
    assert sim.now == 0 and log == []  # not started: time does not move
    pacer.start()
    clock.t_ns += 2_500_000
    pacer.catch_up()
    assert log == [0, 1_000_000, 2_000_000] and sim.now == 3_000_000
    pacer.catch_up()
    assert sim.now == 3_000_000  # up to date: nothing to run
    clock.t_ns += 700_000
    pacer.catch_up()
    assert log[-1] == 3_000_000 and sim.now == 4_000_000


def test_lag_report_counts_how_late_each_slot_start_ran(sim: Simulation) -> None:
    clock = FakeClock()
    pacer = RealtimePacer(sim, clock=clock)
    pacer.start()
    clock.t_ns += 2_500_000  # slots 0, 1, 2 run at 2.5 ms: 2.5, 1.5 and 0.5 slots late
    pacer.catch_up()
    clock.t_ns += 700_000  # slot 3 runs at 3.2 ms: 0.2 slots late
    pacer.catch_up()
    report = pacer.report()
    assert (report.slots, report.late_slots, report.catch_ups) == (4, 2, 2)
    assert report.max_lag_slots == 2.5 and report.mean_lag_slots == (2.5 + 1.5 + 0.5 + 0.2) / 4
    assert not report.kept_up
    times, lags_us = sim.trace.samples("pokeys_device.lag")
    assert times.tolist() == [3_000_000, 4_000_000] and lags_us.tolist() == [500.0, 200.0]


def test_a_pacer_woken_at_every_slot_boundary_keeps_up(sim: Simulation) -> None:
    clock = FakeClock()
    pacer = RealtimePacer(sim, clock=clock, record_lag=False)
    pacer.start()
    pacer.catch_up()
    for _ in range(100):
        clock.t_ns += SLOT_NS - 100_000  # 0.9 ms later ...
        pacer.catch_up()
        clock.t_ns += 100_000  # ... and at the boundary
        pacer.catch_up()
    report = pacer.report()
    assert (report.slots, report.catch_ups, report.max_lag_slots, report.mean_lag_slots) == (101, 101, 0.0, 0.0)
    assert report.kept_up
