"""Move profiles with TA and TS: the S-curve this model chose (docs/pmac.md, "programs"), in exact numbers.

A = max(TA, 2 TS) is the acceleration time; each ramp has jerk-limited ends of TS; the move time
(distance / F, at least A) counts from mid-acceleration to mid-deceleration. Peak acceleration
a = v / (A - TS). The numbers below are worked by hand from those rules.
"""

from __future__ import annotations

import itertools
from fractions import Fraction

import pytest

from cosim.controllers.pmac.motion import LinearMove, Move, compile_items, path_length
from cosim.controllers.pmac.profile import Profile

F = Fraction


def test_pure_s_curve_when_ta_is_below_twice_ts() -> None:
    """2000 units at F100000 (100 units/ms), TA0 TS10: A = 20 ms, a = 10 units/ms^2, no plateau.

        tau [ms]   0   5       10      15        20     30       40
        x [units]  0   125/6   500/3   3125/6    1000   5500/3   2000
        v [u/ms]   0   12.5    50      87.5      100    50       0
    """
    (seg,) = compile_items([LinearMove(2000, 100_000, 0, ts_ms=10)], {"X": F(0)})
    assert seg.duration_units == 40 * 2**23
    profile = seg.paths[0].profile
    assert (profile.accel_ms, profile.move_ms, profile.speed) == (20, 20, 100)
    assert [seg.position(F(t)) for t in (0, 5, 10, 15, 20, 30, 40)] == [0, F(125, 6), F(500, 3), F(3125, 6), 1000,
                                                                       F(5500, 3), 2000]
    assert [profile.speed_at(F(t)) for t in (5, 10, 15, 20, 30)] == [F(25, 2), 50, F(175, 2), 100, 50]


def test_s_curve_ends_around_a_constant_acceleration() -> None:
    """3000 units at 100 units/ms, TA30 TS10: jerk 10 ms, constant a = 5 units/ms^2 for 10 ms, jerk 10 ms.

        tau [ms]   10      20       30     60
        x [units]  250/3   1750/3   1500   3000 - 1500
    """
    (seg,) = compile_items([LinearMove(3000, 100_000, 30, ts_ms=10)], {"X": F(0)})
    assert [seg.position(F(t)) for t in (10, 20, 30, 60)] == [F(250, 3), F(1750, 3), 1500, 3000]
    profile = seg.paths[0].profile
    assert profile.speed_at(F(10)) == 25 and profile.speed_at(F(20)) == 75  # a s / 2, then + a * 10


def test_a_ramp_covers_v_a_over_2_whatever_ts() -> None:
    """The plateau position v (tau - A/2) is the same for TS = 0 and TS > 0 (point-symmetric ramps)."""
    for ts in (0, 1, 5, 10):
        (seg,) = compile_items([LinearMove(10_000, 100_000, 20, ts_ms=ts)], {"X": F(0)})
        assert seg.position(F(20)) == 1000 and seg.position(F(50)) == 4000, ts


@pytest.mark.parametrize(("ta", "ts"), [(0, 7), (20, 3), (10, 5), (12, 0)])
def test_speed_and_position_are_continuous_and_the_acceleration_bounded(ta: int, ts: int) -> None:
    profile = Profile.plan(F(500), ta_ms=F(ta), ts_ms=F(ts), speed=F(64))
    a = profile.speed / (profile.accel_ms - profile.ts_ms)
    eps = F(1, 10**6)
    taus = [F(k, 8) for k in range(int(profile.total_ms * 8) + 1)]
    xs = [profile.travelled(t) for t in taus]
    assert all(b >= x for x, b in itertools.pairwise(xs)) and xs[-1] == 500
    for tau in taus[1:-1]:
        jump = abs(profile.speed_at(tau + eps) - profile.speed_at(tau - eps))
        assert jump <= 2 * a * eps  # no step in speed anywhere, the ramps' ends included
        slope = (profile.travelled(tau + eps) - profile.travelled(tau - eps)) / (2 * eps)
        assert abs(slope - profile.speed_at(tau)) <= a * eps


def test_multi_axis_move_shares_one_profile_along_the_path() -> None:
    """X30 Y40 at 5 units/ms, TA0: 50 units in 10 ms; each axis in proportion."""
    (seg,) = compile_items([Move({"X": 30, "Y": 40}, feedrate=5000, ta_ms=0)], {"X": F(0), "Y": F(0)})
    assert seg.duration_units == 10 * 2**23
    assert (seg.position(F(5), "X"), seg.position(F(5), "Y")) == (15, 20)


def test_path_length_is_exact_when_rational_else_truncated_to_2_to_the_minus_32() -> None:
    assert path_length([F(3), F(4)]) == 5 and path_length([F(3, 10), F(-2, 5)]) == F(1, 2)
    root2 = path_length([F(1), F(1)])
    assert root2.denominator == 2**32 and 0 <= 2 - root2 * root2 < F(3, 2**32)
