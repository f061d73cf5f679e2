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


def slot_loop(sim: Simulation, log: list[object], skipped: list[int]) -> object:
    """A loop at 0, 100, 200, ... that runs passes by skip_to while it can (those also in ``skipped``)."""
    k = 0
    while True:
        yield sim.at(k * 100, Priority.SLOT)
        log.append(("loop", sim.now))
        k += 1
        while sim.skip_to(k * 100):
            log.append(("loop", sim.now))
            skipped.append(sim.now)
            k += 1


def test_skip_to_moves_the_clock_only_when_nothing_is_due_before(sim: Simulation, log: list[object]) -> None:
    """A loop at 0, 100, 200, ... skips its events until the one queued at 250 is next.

    t:      0    100   200  250  300   400
    loop    L    L*    L*        L     L*      (* = run by skip_to, no kernel event)
    other                   O
    """
    skipped: list[int] = []

    sim.call_at(250, Priority.HOST, lambda: log.append(("other", sim.now)))
    sim.process(slot_loop(sim, log, skipped))  # type: ignore[arg-type]
    sim.run(until=450)
    assert log == [("loop", 0), ("loop", 100), ("loop", 200), ("other", 250), ("loop", 300), ("loop", 400)]
    assert skipped == [100, 200, 400]  # 300 came from its event (250 was queued when 200 ran); until 450 stops 500
    assert not sim.skip_to(399)  # never back


def test_a_cancelled_callback_never_runs_and_no_longer_stops_skip_to(sim: Simulation, log: list[object]) -> None:
    """The loop of the skip_to test with the other event at 250 taken back at 150: the passes at
    300 and 400 are skipped (300 had to wait for 250 before), and cancelling again, or an event
    that has fired, changes nothing.

    t:      0   50   100   150     200  250  300   400
    loop    L        L             L         L*    L*      (* = run by skip_to)
    events      F          cancel       (O: cancelled)
    """
    skipped: list[int] = []
    other = sim.call_at(250, Priority.HOST, lambda: log.append(("other", sim.now)))
    fired = sim.call_at(50, Priority.HOST, lambda: log.append(("fired", sim.now)))
    assert sim.due_by(250)

    def cancel_at_150() -> None:
        sim.cancel(other)
        sim.cancel(other)  # twice: no effect
        sim.cancel(fired)  # fired at 50: no effect

    sim.call_at(150, Priority.HOST, cancel_at_150)
    sim.process(slot_loop(sim, log, skipped))  # type: ignore[arg-type]
    sim.run(until=450)
    assert log == [("loop", 0), ("fired", 50), ("loop", 100), ("loop", 200), ("loop", 300), ("loop", 400)]
    assert skipped == [300, 400]  # 100 and 200 waited for the events at 50 and 150
    assert not sim.due_by(449) and sim.env.cancelled == 0  # the cancelled event has left the queue


def test_only_call_at_events_can_be_cancelled(sim: Simulation) -> None:
    with pytest.raises(ConfigurationError, match=r"is not an event of Simulation\.call_at"):
        sim.cancel(sim.env.timeout(5))


def test_skip_to_refuses_while_a_look_ahead_is_registered(sim: Simulation) -> None:
    sim.add_look_ahead(lambda t_next: None)
    assert not sim.skip_to(10) and sim.now == 0


@pytest.mark.parametrize("seed", [-1, 2**63, 1.5, True])
def test_a_seed_outside_0_to_2_63_is_refused_with_its_range(seed: object) -> None:
    from cosim.errors import ConfigurationError

    with pytest.raises(ConfigurationError, match=r"seed = .* is not allowed \(allowed: 0\.\.9223372036854775807\)"):
        Simulation(seed=seed)  # type: ignore[arg-type]


def test_a_run_with_stop_when_ends_at_the_first_check_that_holds_before_that_instants_events() -> None:
    """Checks every 100 ticks from 0; the job is done from tick 250 on: the run stops at 300, and the
    event at 300 has not run (as with until=300). One stop, one on_stop call; a later run goes on."""
    sim = Simulation()
    seen: list[int] = []
    stops: list[int] = []
    sim.on_stop(stops.append)
    for t in (250, 300, 350, 900):
        sim.call_at(t, Priority.NORMAL, lambda: seen.append(sim.now))
    sim.run(10_000, stop_when=lambda: sim.now >= 250, every=100)
    assert (sim.now, seen, stops) == (300, [250], [300])
    sim.run(1000)
    assert (sim.now, seen, stops) == (1000, [250, 300, 350, 900], [300, 1000])


def test_a_run_with_stop_when_that_never_holds_ends_at_until() -> None:
    sim = Simulation()
    asked: list[int] = []
    sim.run(1000, stop_when=lambda: bool(asked.append(sim.now)), every=300)
    assert sim.now == 1000 and asked == [300, 600, 900]


def test_stop_when_needs_a_positive_whole_period() -> None:
    with pytest.raises(ConfigurationError, match="every = 0 is not allowed"):
        Simulation().run(1000, stop_when=lambda: True, every=0)


def test_same_instant_same_priority_runs_in_the_order_scheduled_whichever_method(
        sim: Simulation, log: list[object]) -> None:
    """at 100, SLOT: a (call_at), b (a process's at), c (after), d (call_at) -- in that order, after SERVO."""

    def waiter(name: str, event: object) -> object:
        yield event
        log.append((sim.now, name))

    sim.call_at(100, Priority.SLOT, lambda: log.append((sim.now, "a")))
    sim.process(waiter("b", sim.at(100, Priority.SLOT)))  # type: ignore[arg-type]
    sim.process(waiter("c", sim.after(100, Priority.SLOT)))  # type: ignore[arg-type]
    sim.call_at(100, Priority.SLOT, lambda: log.append((sim.now, "d")))
    sim.call_at(100, Priority.SERVO, lambda: log.append((sim.now, "servo")))
    sim.run(until=200)
    assert log == [(100, "servo"), (100, "a"), (100, "b"), (100, "c"), (100, "d")]


def test_the_clock_stays_an_int_whatever_integer_type_is_given(sim: Simulation) -> None:
    import numpy as np

    seen: list[object] = []
    sim.call_at(np.int64(30), Priority.HOST, lambda: seen.append(sim.now))  # type: ignore[arg-type]
    sim.run(until=np.int64(50))  # type: ignore[arg-type]
    assert seen == [30] and type(seen[0]) is int and type(sim.now) is int and sim.now == 50
    sim.after(np.int64(5), Priority.HOST).callbacks.append(lambda _e: seen.append(sim.now))  # type: ignore[arg-type]
    sim.run(until=100)
    assert seen == [30, 55] and type(seen[1]) is int


def test_a_look_ahead_added_while_running_is_called_from_then_on(sim: Simulation, log: list[object]) -> None:
    """Slots at 0, 100, 200, 300; the look-ahead is added by the pass at 100: it sees 100 -> 200 and 200 -> 300."""

    def slots() -> object:
        for k in range(4):
            yield sim.at(100 * k, Priority.SLOT)
            if k == 1:
                sim.add_look_ahead(lambda t_next: log.append((sim.now, t_next)))

    sim.process(slots())  # type: ignore[arg-type]
    sim.run(until=350)
    assert log == [(100, 200), (200, 300), (300, 350)]


def test_progress_is_reported_every_4096_steps_of_work_and_can_be_switched_off(sim: Simulation) -> None:
    reported: list[int] = []

    def ticks() -> object:
        for k in range(3 * 4096):
            yield sim.at(k, Priority.SLOT)

    sim.env.on_progress = reported.append
    sim.process(ticks())  # type: ignore[arg-type]
    sim.run(until=2 * 4096)
    assert len(reported) == 2 and reported == sorted(reported)
    sim.env.on_progress = None
    sim.run(until=3 * 4096)
    assert len(reported) == 2


def test_a_run_of_slots_may_go_past_a_quiet_event_up_to_its_horizon(sim: Simulation) -> None:
    """A host cycle at 10 us that keeps to itself until 10 us + 1.2 ms (its command reaches the
    device one link delay later) does not bound a run; a plain event does.

    t [us]:   0      10 ............ 500 ...... 1210 ...... 2000
    quiet            Q ........................ | (Q + 1.2 ms)
    plain                                                   S
    run_bound: 1210 us; free_until: 10 us (the next queued event, quiet or not)
    """
    sim.quiet_at(10_000, Priority.HOST, quiet_for=1_200_000)
    sim.at(2_000_000, Priority.SLOT)
    assert sim.free_until() == 10_000
    assert sim.run_bound() == 1_210_000
    assert not sim.skip_to(20_000)  # the clock never passes a queued event, quiet or not
    sim.call_at(500_000, Priority.NORMAL, lambda: None)
    assert sim.run_bound() == 500_000  # a plain event before the horizon bounds the run
    event = sim.quiet_after(7_000, Priority.HOST, quiet_for=0)  # no horizon: an ordinary event
    assert sim.run_bound() == 7_000 and not getattr(event, "quiet_for", 0)
    with pytest.raises(ConfigurationError, match="quiet_for"):
        sim.quiet_at(30_000, Priority.HOST, quiet_for=-1)
