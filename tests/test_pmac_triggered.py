"""Turbo triggered time base: freeze, arm, start at the captured master position.

Conveyor at 64 counts/ms (one count every 15,625 ns); SCALE_FACTOR 256 (16384 / 64) so the
running time base is 100 %; registration marks 5 counts long.
"""

from __future__ import annotations

from collections.abc import Generator
from fractions import Fraction
from typing import Any

from cycle_probe import record_each_cycle

from cosim import rigs
from cosim.controllers.pmac.ect import ARMED, FROZEN, RUNNING, TriggeredTimeBaseEntry
from cosim.controllers.pmac.motion import LinearMove, compile_items
from cosim.kernel import Simulation
from cosim.plants.analytic import IdealConveyor
from cosim.signals import Signal
from cosim.timebase import Priority

MOVE = LinearMove(3000, 64_000, 10)


def _setup(sim: Simulation, *, initial: int, marks: list[Fraction | int],
           width_counts: int = 5) -> tuple[rigs.Rig[TriggeredTimeBaseEntry], IdealConveyor]:
    belt = IdealConveyor(sim, speed_counts_per_ms=64, marks=marks, mark_width_counts=width_counts)
    rig = rigs.triggered_time_base(sim, belt, belt.mark, scale_factor=256, method=initial)
    return rig, belt


def test_triggered_start_time_zero_is_master_position_at_trigger(sim: Simulation) -> None:
    """Frozen, armed at 2 ms, mark at 1000.3 counts: time zero = master position at the mark
    within 1/256 count, and afterwards the slave follows the master travel since the mark.

        mark         __________________|‾|_______
        method       9 |B‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾|A‾‾‾‾‾‾
        time base    0 0 0 0 0 0 0 0 0 0 |tb tb tb
        slave cmd    0 ..................0 / / /
    """
    rig, belt = _setup(sim, initial=FROZEN, marks=[Fraction(10003, 10)])
    clock = rig.pmac.clock
    rig.cs.run_program([MOVE])

    def plc() -> Generator[Any, Any, None]:
        yield sim.at(2_000_000, Priority.HOST)
        rig.pmac.set_ivar(8000, 0xB78008)

    sim.process(plc())
    rows = record_each_cycle(sim, clock, lambda k, t: (t, rig.motor.cmd, rig.entry.position), cycles=80)
    rig.pmac.start()
    sim.run(until=clock.t(80))
    (start,) = rig.entry.starts
    t_mark = belt.mark_times[0][0]
    assert start.capture_t == t_mark == 15_629_688  # ceil(1000.3 * 15625)
    assert abs(Fraction(start.time_zero_pos256, 256) - belt.position(t_mark)) <= Fraction(1, 256)
    assert start.t == clock.t(clock.first_cycle_at_or_after(t_mark))  # seen at the next servo cycle
    assert rig.entry.method == RUNNING
    (segment,) = compile_items([MOVE], {"X": Fraction(0)})
    assert len(rows) == 80
    before = [cmd for t, cmd, _pos in rows if t < start.t]
    after = [(cmd, pos256) for t, cmd, pos256 in rows if t >= start.t]
    assert len(before) == 36 and len(after) == 44  # the mark at 15.63 ms falls in cycle 36
    assert before == [0] * 36
    for cmd, pos256 in after:  # program time = master travel since the mark / 64 counts per ms, exactly
        assert cmd == segment.position(Fraction(2 * 256 * (pos256 - start.time_zero_pos256), 2**23))
    assert after[-1][0] > 0
    times, values = sim.trace.edges("pmac.ect.method")
    assert times.tolist() == [0, 2_000_000, start.t] and values.tolist() == [FROZEN, ARMED, RUNNING]


def test_stale_capture_starts_motion_at_the_wrong_master_position(sim: Simulation) -> None:
    """Entry left running; mark 1 (500 counts) sets the capture flag and nobody reads it. Freeze and
    arm fall between two servo interrupts (light load), so no cycle sees the entry frozen: the armed
    entry takes the stale capture at once and starts 1000 counts before mark 2.

        mark        __|‾|_________________________|‾|____
        flag        __|‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾|____________
        servo       |    |    |    |    |    |    |    |
        freeze/arm                     ^^ (same interval)
        start                              ^ wrong: master at ~820, mark 2 at 1500
    """
    belt, rig = rigs.stale_capture(sim, t_freeze=12_000_000, arm_after=100_000, dummy_read=False)
    clock = rig.pmac.clock
    k = clock.first_cycle_at_or_after(12_000_000)
    sim.run(until=30_000_000)
    (start,) = rig.entry.starts
    assert start.capture_t == belt.mark_times[0][0]  # the stale capture of mark 1
    assert Fraction(start.time_zero_pos256, 256) == 500
    assert start.t == clock.t(k + 1) < belt.mark_times[1][0]  # started long before mark 2
    start_error = belt.position(start.t) - 1500
    assert start_error < -650  # the motion begins about 680 counts early
    assert rig.entry.saturated_cycles == [k + 1]  # 300 counts of travel in one cycle: the result clips


def test_dummy_read_of_capture_register_fixes_the_stale_start(sim: Simulation) -> None:
    """Same timing, plus a dummy read of X:$07800B after freezing: the flag is cleared, the armed
    entry waits for mark 2 and starts there within 1/256 count."""
    belt, rig = rigs.stale_capture(sim, t_freeze=12_000_000, arm_after=100_000, dummy_read=True)
    clock = rig.pmac.clock
    sim.run(until=30_000_000)
    (start,) = rig.entry.starts
    t_mark2 = belt.mark_times[1][0]
    assert start.capture_t == t_mark2
    assert abs(Fraction(start.time_zero_pos256, 256) - belt.position(t_mark2)) <= Fraction(1, 256)
    assert start.t == clock.t(clock.first_cycle_at_or_after(t_mark2))
    assert rig.entry.saturated_cycles == []


def test_a_servo_cycle_in_frozen_state_also_clears_the_stale_capture(sim: Simulation) -> None:
    """Without the dummy read but with the arm two servo cycles after the freeze, the table reads the
    capture register while frozen and the start is correct (the hazard needs a light load)."""
    belt, rig = rigs.stale_capture(sim, t_freeze=12_000_000, arm_after=1_000_000, dummy_read=False)
    sim.run(until=30_000_000)
    (start,) = rig.entry.starts
    assert start.capture_t == belt.mark_times[1][0]


def test_mark_under_the_sensor_at_the_trigger_cycle_recaptures(sim: Simulation) -> None:
    """Level-triggered capture: the entry's read at the trigger cycle re-arms while the 30-count mark
    is still under the sensor, so a new (stale-to-be) capture is latched at that instant."""
    rig, belt = _setup(sim, initial=ARMED, marks=[1000], width_counts=30)
    rig.pmac.start()
    sim.run(until=20_000_000)
    (start,) = rig.entry.starts
    assert [t for t, _ in rig.channel.captures] == [belt.mark_times[0][0], start.t]
    assert rig.channel.capture_flag


def test_master_position_signal_is_the_undifferentiated_1_256_position(sim: Simulation) -> None:
    rig, belt = _setup(sim, initial=FROZEN, marks=[])
    rig.pmac.start()
    sim.run(until=rig.pmac.clock.t(10) + 1)
    t, v = sim.trace.edges("pmac.ect.master_pos")
    assert t[1:].tolist() == [rig.pmac.clock.t(k) for k in range(1, 11)]  # one new value every servo cycle
    for ti, vi in zip(t[1:], v[1:], strict=True):
        assert 0 <= belt.position(int(ti)) - Fraction(vi) < Fraction(1, 256)


def test_the_frozen_entry_reads_the_capture_register_every_servo_cycle(sim: Simulation) -> None:
    """Turbo SRM: "When this entry is in the frozen state, the table reads the channel's capture position
    register each servo cycle". A trigger pulse in every servo interval: each is latched (the previous
    cycle's read re-armed the capture) and each servo cycle leaves the flag clear. Reading every other
    cycle would lose every second pulse and leave the flag set after half the cycles.

        servo     |    |    |    |    |        cycles 1..20
        trigger    _|‾|__|‾|__|‾|__|‾|_         one pulse 100..200 us after each interrupt
        flag       _|‾‾|_|‾‾|_|‾‾|_|‾‾|_        cleared by the frozen entry's read at every interrupt
    """
    belt = IdealConveyor(sim, speed_counts_per_ms=64)
    trigger = Signal(sim, "test.trigger", kind="bit")
    rig = rigs.triggered_time_base(sim, belt, trigger, scale_factor=256, method=FROZEN)
    clock = rig.pmac.clock
    for k in range(1, 21):
        sim.call_at(clock.t(k) + 100_000, Priority.HOST, lambda: trigger.set(1))
        sim.call_at(clock.t(k) + 200_000, Priority.HOST, lambda: trigger.set(0))
    flags = record_each_cycle(sim, clock, lambda k, t: rig.channel.capture_flag, cycles=22)
    rig.pmac.start()
    sim.run(until=clock.t(22))
    assert len(rig.channel.captures) == 20
    assert [t for t, _ in rig.channel.captures] == [clock.t(k) + 100_000 for k in range(1, 21)]
    assert flags == [False] * 22  # after every servo cycle, the frozen entry's read has cleared the flag
    assert rig.entry.result == 0 and rig.entry.starts == []
