"""Exact integer time: conversions refuse what is not a whole number of ticks."""

from __future__ import annotations

from fractions import Fraction

import pytest

from cosim.errors import ConfigurationError
from cosim.timebase import Priority, TimeBase

NS = TimeBase()


@pytest.mark.parametrize(
    ("value", "unit", "ticks"),
    [
        (1, "ms", 1_000_000),
        (250, "us", 250_000),
        (0.1, "ms", 100_000),  # a float is read as the decimal the user wrote
        ("442.708 us", None, 442_708),
        ("1e-3 s", None, 1_000_000),
        (Fraction(1, 3), "us", ConfigurationError),
        (0.5, "ns", ConfigurationError),
        ("12 parsecs", None, ConfigurationError),
        ("fast", None, ConfigurationError),
        (3, "weeks", ConfigurationError),
    ],
)
def test_ticks_table(value: object, unit: str | None, ticks: object) -> None:
    if isinstance(ticks, type):
        with pytest.raises(ticks):
            NS.ticks(value, unit)  # type: ignore[arg-type]
    else:
        assert NS.ticks(value, unit) == ticks  # type: ignore[arg-type]


def test_inexact_message_names_value_and_resolution() -> None:
    with pytest.raises(ConfigurationError, match=r"slot = 0.5 ns is not a whole number of ticks .*1 ns"):
        NS.ticks(0.5, "ns", name="slot")


def test_coarser_resolution() -> None:
    us = TimeBase(Fraction(1, 10**6))
    assert us.unit == "1 us"
    assert us.ticks(3, "ms") == 3000
    with pytest.raises(ConfigurationError):
        us.ticks(1500, "ns")


def test_check_ticks_refuses_floats_and_negative() -> None:
    assert NS.check_ticks(5) == 5
    with pytest.raises(ConfigurationError, match="integer number of ticks"):
        NS.check_ticks(5.0)
    with pytest.raises(ConfigurationError, match=r"period = -1 is not allowed \(allowed: >= 0 ticks\)"):
        NS.check_ticks(-1, name="period")


def test_event_time_from_fmu_snaps_float_noise_and_rounds_up_otherwise() -> None:
    assert NS.ticks_from_seconds_ceil(1e-3) == 1_000_000  # 1e-3 is a hair above 1 ms in binary
    assert NS.ticks_from_seconds_ceil(1.0000000004) == 1_000_000_001
    assert NS.seconds(1_500) == 1.5e-6


def test_priorities_are_ordered_as_documented() -> None:
    order = [Priority.URGENT, Priority.NORMAL, Priority.PLANT_EVENT, Priority.SERVO, Priority.SLOT,
             Priority.HOST, Priority.SAMPLE]
    assert order == sorted(order)
