"""The kernel: integer time, named same-instant order, look-aheads."""

from __future__ import annotations

import pytest

from cosim.errors import ConfigurationError
from cosim.kernel import Simulation
from cosim.timebase import Priority


def test_same_instant_order_follows_priorities_not_insertion(sim: Simulation, log: list[object]) -> None:
    """At t=1000 three stages fire; they run servo, slot, host whatever the insertion order.

    t:      0 ........ 1000
    host               H  (scheduled first)
    slot               S
    servo              V  (scheduled last)
    """
    for name, prio in (("host", Priority.HOST), ("slot", Priority.SLOT), ("servo", Priority.SERVO)):
        sim.call_at(1000, prio, lambda name=name: log.append((sim.now, name)))
    sim.run(until=2000)
    assert log == [(1000, "servo"), (1000, "slot"), (1000, "host")]


def test_periodic_process_times_are_k_times_period(sim: Simulation, log: list[object]) -> None:
    period = 442_708  # ticks: a PMAC-like servo period

    def servo_cycle() -> object:
        k = 0
        while True:
            yield sim.at(k * period, Priority.SERVO)
            log.append(sim.now)
            k += 1

    sim.process(servo_cycle())  # type: ignore[arg-type]
    sim.run(until=10 * period + 1)
    assert log == [k * period for k in range(11)]
    assert all(type(t) is int for t in log)


def test_float_and_past_times_are_refused(sim: Simulation) -> None:
    with pytest.raises(ConfigurationError, match="integer number of ticks"):
        sim.at(1.5)  # type: ignore[arg-type]
    sim.run(until=100)
    with pytest.raises(ConfigurationError, match="in the past"):
        sim.at(50)


def test_look_ahead_sees_next_instant_and_may_insert_earlier_event(sim: Simulation, log: list[object]) -> None:
    """A look-ahead told 'next is 1000' finds an event at 400; the kernel runs it first."""
    seen: list[tuple[int, int]] = []

    def look_ahead(t_next: int) -> None:
        seen.append((sim.now, t_next))
        if t_next == 1000 and sim.now == 0:
            sim.call_at(400, Priority.PLANT_EVENT, lambda: log.append(("event", sim.now)))

    sim.add_look_ahead(look_ahead)
    sim.call_at(1000, Priority.SLOT, lambda: log.append(("slot", sim.now)))
    sim.run(until=1500)
    assert log == [("event", 400), ("slot", 1000)]
    assert seen == [(0, 1000), (400, 1000), (1000, 1500)]


def test_a_failing_process_leaves_the_trace_ending_at_the_failure(sim: Simulation) -> None:
    from cosim.signals import Signal

    gate = Signal(sim, "test.gate")

    def fails() -> object:
        yield sim.at(100)
        gate.set(1)
        yield sim.at(200)
        raise RuntimeError("controller blew up")

    sim.process(fails())  # type: ignore[arg-type]
    with pytest.raises(RuntimeError, match="blew up"):
        sim.run(until=1000)
    assert sim.trace.edges("test.gate")[0].tolist() == [0, 100]
    assert sim.trace.end_t == 200


def test_skip_to_moves_the_clock_only_when_nothing_is_due_before(sim: Simulation, log: list[object]) -> None:
    """A loop at 0, 100, 200, ... skips its events until the one queued at 250 is next.

    t:      0    100   200  250  300   400
    loop    L    L*    L*        L     L*      (* = run by skip_to, no kernel event)
    other                   O
    """
    skipped: list[int] = []

    def loop() -> object:
        k = 0
        while True:
            yield sim.at(k * 100, Priority.SLOT)
            log.append(("loop", sim.now))
            k += 1
            while sim.skip_to(k * 100):
                log.append(("loop", sim.now))
                skipped.append(sim.now)
                k += 1

    sim.call_at(250, Priority.HOST, lambda: log.append(("other", sim.now)))
    sim.process(loop())  # type: ignore[arg-type]
    sim.run(until=450)
    assert log == [("loop", 0), ("loop", 100), ("loop", 200), ("other", 250), ("loop", 300), ("loop", 400)]
    assert skipped == [100, 200, 400]  # 300 came from its event (250 was queued when 200 ran); until 450 stops 500
    assert not sim.skip_to(399)  # never back


def test_skip_to_refuses_while_a_look_ahead_is_registered(sim: Simulation) -> None:
    sim.add_look_ahead(lambda t_next: None)
    assert not sim.skip_to(10) and sim.now == 0


@pytest.mark.parametrize("seed", [-1, 2**63, 1.5, True])
def test_a_seed_outside_0_to_2_63_is_refused_with_its_range(seed: object) -> None:
    from cosim.errors import ConfigurationError

    with pytest.raises(ConfigurationError, match=r"seed = .* is not allowed \(allowed: 0\.\.9223372036854775807\)"):
        Simulation(seed=seed)  # type: ignore[arg-type]
