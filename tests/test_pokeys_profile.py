"""Slot profiles: integer trapezoids that land exactly, and the host planner's remainder carrying."""

from __future__ import annotations

from fractions import Fraction

import pytest
from hypothesis import given
from hypothesis import strategies as st

from cosim.controllers.pokeys.config import AxisConfig, uniform_axes
from cosim.controllers.pokeys.planner import Dwell, Move, plan, to_entries
from cosim.controllers.pokeys.profile import AxisMotion, SlotLimits, fastest_arriving, fastest_stoppable, stop_distance
from cosim.controllers.pokeys.trajectory import arriving_distance
from cosim.errors import ConfigurationError


@pytest.mark.parametrize("decel", [1, 3, 7, 100])
def test_fastest_stoppable_is_the_largest_speed_that_can_stop_in_time(decel: int) -> None:
    for remaining in range(0, 400):
        u = fastest_stoppable(remaining, decel)
        assert stop_distance(u, decel) <= remaining < stop_distance(u + 1, decel)


@pytest.mark.parametrize(("vmax", "accel", "decel", "target"), [
    (Fraction(25), Fraction(1, 10), Fraction(1, 10), 12_345),
    (Fraction(25), Fraction(1, 10), Fraction(1, 5), -777),
    (Fraction(7, 3), Fraction(1, 3), Fraction(2, 7), 50),
    (Fraction(25), Fraction(25), Fraction(25), 1),
])
def test_position_move_lands_exactly_within_the_limits(vmax: Fraction, accel: Fraction, decel: Fraction,
                                                       target: int) -> None:
    limits = SlotLimits.exact(vmax, accel, decel)
    motion = AxisMotion(limits, position=0)
    motion.move_to(target)
    counts, speeds = [], []
    while not motion.done:
        before = motion.p
        counts.append(motion.step())
        speeds.append(Fraction(abs(motion.p - before), limits.scale))  # the slot's speed
    assert sum(counts) == target
    assert max(abs(c) for c in counts) <= 25 and max(speeds) <= vmax
    steps = [b - a for a, b in zip([Fraction(0), *speeds], [*speeds, Fraction(0)], strict=True)]
    assert max(steps) <= accel and min(steps) >= -decel


def test_trapezoid_reaches_the_cruise_speed_and_is_symmetric() -> None:
    motion = AxisMotion(SlotLimits.exact(Fraction(5), Fraction(1), Fraction(1)))
    motion.move_to(40)
    counts = []
    while not motion.done:
        counts.append(motion.step())
    assert counts == [1, 2, 3, 4, 5, 5, 5, 5, 4, 3, 2, 1]


def test_planner_carries_remainders_exactly_on_every_axis() -> None:
    axes = uniform_axes(max_speed_hz=25_000, accel=300_000, decel=200_000)
    moves: list[Move | Dwell] = [Move((10_001, -3_333, 7)), Move((-5, 17, 25_000)), Dwell(3),
                                 Move((0, 0, 0), speed_hz=12_345)]
    counts = plan(moves, axes)
    totals = [0, 0, 0]
    for k, slot in enumerate(counts):
        assert max(abs(c) for c in slot) <= 25, k
        totals = [t + c for t, c in zip(totals, slot, strict=True)]
    assert totals == [0, 0, 0]
    first = plan(moves[:1], axes)
    assert [sum(c[a] for c in first) for a in range(3)] == [10_001, -3_333, 7]


def test_planner_respects_each_axis_limits_along_a_diagonal() -> None:
    axes = (AxisConfig(max_speed_hz=20_000), AxisConfig(max_speed_hz=5_000), AxisConfig())
    counts = plan([Move((4_000, 4_000, 0))], axes)
    assert max(c[1] for c in counts) == 5 and max(c[0] for c in counts) == 5  # y limits the path


def test_planner_is_symmetric_in_direction() -> None:
    axes = uniform_axes(accel=150_000)
    up = plan([Move((1_234, -1_234, 0))], axes)
    assert [c[0] for c in up] == [-c[1] for c in up]


def test_to_entries_keeps_the_direction_bit_on_zero_counts() -> None:
    entries = to_entries([(-3, 0, 0), (0, 0, 0), (2, 0, 0), (0, 0, 0)])
    assert [e[0] for e in entries] == [0x83, 0x80, 0x02, 0x00]


@pytest.mark.parametrize(("make", "message"), [
    (lambda: plan([Move((0, 0))], uniform_axes()), r"Move target axes = 2 is not allowed \(allowed: 3"),
    (lambda: Move((0,) * 9), r"Move target axes = 9 is not allowed \(allowed: 1..8"),
    (lambda: Move((0, 0, 0), speed_hz=0), r"Move speed_hz = 0 is not allowed \(allowed: > 0..125000"),
    (lambda: Move((0, 0, 0), accel=0), r"Move accel = 0 is not allowed \(allowed: > 0 pulses/s\^2"),
    (lambda: Dwell(-1), r"Dwell slots = -1 is not allowed"),
])
def test_bad_moves_are_refused(make: object, message: str) -> None:
    with pytest.raises(ConfigurationError, match=message):
        make()  # type: ignore[operator]


@given(u=st.integers(1, 5_000), decel=st.integers(1, 500), speed=st.integers(0, 5_000), extra=st.integers(0, 10**6))
def test_from_the_arriving_distance_on_a_corner_does_not_brake_the_speed(u: int, decel: int, speed: int,
                                                                          extra: int) -> None:
    # the planner skips fastest_arriving where remaining >= arriving_distance(vmax, ...): exact both ways
    threshold = arriving_distance(u, decel, speed)
    assert fastest_arriving(threshold + extra, decel, speed) >= u
    if threshold > 0:
        assert fastest_arriving(threshold - 1, decel, speed) < u


def test_arriving_distance_sums_the_slots_faster_than_the_corner() -> None:
    assert arriving_distance(6, 1, 3) == 6 + 5 + 4
    assert arriving_distance(10, 4, 0) == 10 + 6 + 2
    assert arriving_distance(3, 1, 3) == 0


def test_a_move_repeated_from_the_same_start_is_planned_as_the_first_time() -> None:
    axes = uniform_axes(accel=1_000_000)
    there, back = Move((700, -300, 50)), Move((0, 0, 0))
    once = plan([there], axes)
    again = plan([there, back, there], axes)
    assert again[:len(once)] == again[-len(once):] == once
    assert [sum(c[a] for c in again) for a in range(3)] == [700, -300, 50]
