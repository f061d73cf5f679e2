"""PMAC units: servo interrupts from I10 (2^-23 ms), exact and never accumulated."""

from __future__ import annotations

from fractions import Fraction

import pytest

from cosim.controllers.pmac.units import (
    Reg,
    ServoClock,
    formula_percent,
    percent,
    saturate24,
    scale_factor_for,
    timebase_for_percent,
    wrap24,
)
from cosim.errors import ConfigurationError


def test_default_servo_interrupts_are_floor_of_exact_instants() -> None:
    """I10 = 3,713,707 -> 442,708.37 ns: interrupts at floor(k * I10 * 10^6 / 2^23).

        k     0        1        2        3
        t_ns  0     442708   885416  1328125
    """
    clock = ServoClock()
    assert clock.i10 == 3_713_707
    assert clock.period_ns == Fraction(3_713_707 * 10**6, 2**23)
    assert [clock.t(k) for k in range(4)] == [0, 442_708, 885_416, 1_328_125]
    assert {clock.t(k + 1) - clock.t(k) for k in range(1000)} == {442_708, 442_709}


def test_servo_clock_never_drifts_from_real_time() -> None:
    """After a million cycles the interrupt is still within 1 ns of k * period (no accumulation)."""
    clock = ServoClock()
    for k in (10**3, 10**6, 10**9):
        assert 0 <= k * Fraction(3_713_707 * 10**6, 2**23) - clock.t(k) < 1
    assert clock.t(10**9) == 442_708_373_069_763  # floor(10^9 * 3,713,707 * 10^6 / 2^23) ns


def test_servo_clock_at_10_ns_resolution_floors_the_same_instants_to_10_ns_ticks() -> None:
    """I10 = 3,713,707 is 442,708.37 ns: at 10 ns per tick the interrupts fall on 44,270, 88,541, ... ticks."""
    clock = ServoClock(ns_per_tick=Fraction(10))
    assert [clock.t(k) for k in range(4)] == [0, 44_270, 88_541, 132_812]
    assert clock.period_ticks == Fraction(3_713_707 * 10**6, 2**23 * 10)
    assert clock.first_cycle_at_or_after(44_271) == 2


def test_servo_clock_offset_and_cycle_lookup() -> None:
    clock = ServoClock(t0=1000)
    assert clock.t(0) == 1000 and clock.t(1) == 443_708
    assert clock.first_cycle_at_or_after(1000) == 0
    assert clock.first_cycle_at_or_after(1001) == 1
    assert clock.first_cycle_at_or_after(443_708) == 1
    assert clock.first_cycle_at_or_after(443_709) == 2


def test_exact_period_from_ns_and_refusal_of_inexact() -> None:
    assert ServoClock.from_period_ns(250_000).i10 == 2**21
    assert ServoClock.from_period_ns(250_000).t(3) == 750_000
    with pytest.raises(ConfigurationError,
                       match=r"servo period_ns = 442708 is not allowed \(allowed: multiples of 15625"):
        ServoClock.from_period_ns(442_708)


@pytest.mark.parametrize("i10", [0, -5, 8_388_608, 2.5])
def test_i10_out_of_range(i10: object) -> None:
    with pytest.raises(ConfigurationError, match=r"I10 \(servo interrupt time\) = .* \(allowed: integers 1..8388607"):
        ServoClock(i10)  # type: ignore[arg-type]


def test_percent_and_time_base_conversions() -> None:
    assert percent(3_713_707, 3_713_707) == 100
    assert percent(1_856_853, 3_713_707) == Fraction(185_685_300, 3_713_707)  # 49.99998654 %
    assert percent(2**20, 2**21) == 50
    assert timebase_for_percent(50, 2**21) == 2**20
    assert formula_percent(2048, 64) == 100
    assert formula_percent(2048, 48) == 75
    assert formula_percent(64, 256, triggered=True) == 100


def test_scale_factor_from_real_time_input_frequency() -> None:
    """SF = 131072 / RTIF (untriggered, 1/32 count) and 16384 / RTIF (triggered, 1/256 count)."""
    assert scale_factor_for(64) == 2048
    assert scale_factor_for(256, triggered=True) == 64
    with pytest.raises(ConfigurationError, match=r"SCALE_FACTOR = .* \(allowed: integers 1..8388607: 131072 / RTIF"):
        scale_factor_for(60)
    with pytest.raises(ConfigurationError, match=r"real-time input frequency = 0"):
        scale_factor_for(0)


def test_24_bit_register_arithmetic() -> None:
    assert wrap24(2**24 + 5) == 5
    assert wrap24(2**23) == -(2**23)
    assert saturate24(10**9) == 2**23 - 1 and saturate24(-(10**9)) == -(2**23)
    assert repr(Reg(1833)) == "$0729 (1833)"
    assert repr(Reg(0xC, digits=1)) == "$C"
