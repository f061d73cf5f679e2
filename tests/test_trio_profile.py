"""Trio trapezoidal profiles: exact rational phases, rounded-down square roots, exact end positions."""

from __future__ import annotations

from fractions import Fraction

import pytest

from cosim.controllers.trio.profile import SQRT_BITS, Trapezoid, sqrt_down


@pytest.mark.parametrize(("value", "root"), [(Fraction(0), Fraction(0)), (Fraction(9, 4), Fraction(3, 2)),
                                             (Fraction(2500), Fraction(50)), (Fraction(1, 16), Fraction(1, 4))])
def test_sqrt_down_is_exact_for_rational_squares(value: Fraction, root: Fraction) -> None:
    assert sqrt_down(value) == root


@pytest.mark.parametrize("value", [Fraction(2), Fraction(300_000), Fraction(1, 3), Fraction(10**12 + 1)])
def test_sqrt_down_rounds_an_irrational_root_down_to_the_grid(value: Fraction) -> None:
    root = sqrt_down(value)
    step = Fraction(1, 2**SQRT_BITS)
    assert root * root < value < (root + step) ** 2
    assert (root / step).denominator == 1


def test_trapezoid_phases_are_exact() -> None:
    """300 units at 100 units/s, ACCEL 1000, DECEL 500.

    speed 100 |    ______________________
              |   /                      \\
              0  0.1 s               2.95 s  3.15 s
    """
    p = Trapezoid.plan(Fraction(300), speed=Fraction(100), accel=Fraction(1000), decel=Fraction(500))
    assert (p.peak, p.t_accel, p.t_const, p.t_decel, p.t_end) == (
        Fraction(100), Fraction(1, 10), Fraction(57, 20), Fraction(1, 5), Fraction(63, 20))
    assert p.position(Fraction(1, 10)) == 5  # A t^2 / 2
    assert p.position(Fraction(1, 10) + Fraction(57, 20)) == 290  # 5 + 100 * 2.85
    assert p.position(p.t_end) == 300 and p.position(p.t_end + 1) == 300
    assert p.speed(Fraction(1, 20)) == 50 and p.speed(Fraction(1)) == 100 and p.speed(p.t_end - Fraction(1, 10)) == 50


@pytest.mark.parametrize(("length", "speed", "accel", "decel"), [
    (Fraction(300), Fraction(1000), Fraction(1000), Fraction(1000)),   # triangle, irrational peak
    (Fraction(100), Fraction(1000), Fraction(800), Fraction(1200)),    # triangle, asymmetric
    (Fraction(20), Fraction(50), Fraction(200), Fraction(200)),        # trapezoid: the ramps take 12.5 units
    (Fraction(7, 3), Fraction(5), Fraction(11), Fraction(13)),         # trapezoid with thirds
])
def test_profile_is_continuous_monotone_and_ends_exactly(length: Fraction, speed: Fraction, accel: Fraction,
                                                        decel: Fraction) -> None:
    p = Trapezoid.plan(length, speed=speed, accel=accel, decel=decel)
    assert p.peak <= speed and p.t_const >= 0
    assert p.position(p.t_end) == length
    for boundary in (p.t_accel, p.t_accel + p.t_const):
        eps = Fraction(1, 10**30)
        assert abs(p.position(boundary + eps) - p.position(boundary - eps)) < Fraction(1, 10**25)
    samples = [p.position(p.t_end * k / 200) for k in range(201)]
    assert samples == sorted(samples) and samples[0] == 0 and samples[-1] == length


def test_triangle_peak_is_rounded_down_so_the_move_still_ends_on_target() -> None:
    p = Trapezoid.plan(Fraction(300), speed=Fraction(1000), accel=Fraction(1000), decel=Fraction(1000))
    exact_peak_squared = 2 * Fraction(300) * 1000 * 1000 / 2000  # 300000: irrational peak
    assert p.peak * p.peak < exact_peak_squared
    assert 0 <= p.t_const < Fraction(1, 10**15)
    assert p.position(p.t_end) == 300


def test_zero_length_move_takes_no_time() -> None:
    p = Trapezoid.plan(Fraction(0), speed=Fraction(1), accel=Fraction(1), decel=Fraction(1))
    assert p.t_end == 0 and p.position(Fraction(1)) == 0 and p.speed(Fraction(0)) == 0
