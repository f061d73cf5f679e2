"""The one validation module: every user number is checked the same way, with the same message."""

from decimal import Decimal
from fractions import Fraction

import numpy as np
import pytest

from cosim import validate
from cosim.errors import ConfigurationError


@pytest.mark.parametrize(("value", "expected"), [
    (3, Fraction(3)), (0.1, Fraction(1, 10)), ("2.5", Fraction(5, 2)), (Decimal("1e3"), Fraction(1000)),
    (Fraction(1, 3), Fraction(1, 3)), (np.int64(7), Fraction(7)), (np.float64(0.25), Fraction(1, 4)),
])
def test_exact_takes_a_float_as_the_decimal_it_prints(value: object, expected: Fraction) -> None:
    assert validate.exact(value, "x") == expected


@pytest.mark.parametrize(("value", "allowed"), [
    (float("inf"), "a finite number"), (float("nan"), "a finite number"), (True, "a finite number"),
    ("abc", "a finite number"), (None, "a finite number"), ([1], "a finite number"),
    ("1e99999999", "magnitude <= 1e300"), (10**400, "magnitude <= 1e300"),
    ("1e-99999999", "at most 300 decimal places"),
])
def test_exact_refuses_what_is_not_a_bounded_finite_number(value: object, allowed: str) -> None:
    with pytest.raises(ConfigurationError, match=r"^f\.cfg: x = .* is not allowed \(allowed: .*" + allowed):
        validate.exact(value, "x", where="f.cfg")


def test_integer_names_the_range_and_refuses_floats_unless_whole_numbers_are_asked_for() -> None:
    assert validate.integer(25, "pulses", low=-25, high=25) == 25
    assert validate.integer(np.int32(3), "n") == 3
    with pytest.raises(ConfigurationError, match=r"^slot 3: pulses = 26 is not allowed \(allowed: -25\.\.25\)$"):
        validate.integer(26, "pulses", low=-25, high=25, where="slot 3")
    with pytest.raises(ConfigurationError, match=r"n = 4\.0 is not allowed \(allowed: 0\.\.9 ms\)"):
        validate.integer(4.0, "n", low=0, high=9, unit="ms")
    assert validate.integer(4.0, "n", low=0, high=9, whole=True) == 4
    assert validate.integer(Fraction(8, 2), "n", whole=True) == 4
    with pytest.raises(ConfigurationError, match=r"n = 4\.5 is not allowed"):
        validate.integer(4.5, "n", whole=True)
    with pytest.raises(ConfigurationError, match=r"n = True"):
        validate.integer(True, "n")
    with pytest.raises(ConfigurationError, match=r"\(allowed: >= 1 ticks\)"):
        validate.integer(0, "period", low=1, unit="ticks")


@pytest.mark.parametrize(("kwargs", "ok", "bad", "allowed"), [
    ({"low": 0, "low_open": True}, 1, 0, "> 0"),
    ({"low": 0}, 0, -1, ">= 0"),
    ({"low": 0, "high": 5, "high_open": True, "unit": "ms"}, 4.5, 5, ">= 0 and < 5 ms"),
    ({"low": -1, "high": 1}, 0.5, 1.5, "-1..1"),
])
def test_in_range_is_exact_at_open_and_closed_bounds(kwargs: dict, ok: float, bad: float, allowed: str) -> None:
    assert validate.in_range(ok, "x", **kwargs) == validate.exact(ok, "x")
    with pytest.raises(ConfigurationError, match=f"allowed: {allowed}"):
        validate.in_range(bad, "x", **kwargs)


def test_positive_finite_flag_and_choice() -> None:
    assert validate.positive(Fraction(1, 10**9), "accel") == Fraction(1, 10**9)
    assert validate.positive(0, "speed", zero=True) == 0
    with pytest.raises(ConfigurationError, match=r"accel = 0 is not allowed \(allowed: > 0 pulses/s\^2\)"):
        validate.positive(0, "accel", unit="pulses/s^2")
    assert validate.finite(2, "bound") == 2.0
    for bad in (float("inf"), float("-inf"), float("nan"), "1", True):
        with pytest.raises(ConfigurationError, match="bound = "):
            validate.finite(bad, "bound")
    assert validate.flag(1, "enabled") is True and validate.flag(False, "enabled") is False
    with pytest.raises(ConfigurationError, match=r"enabled = 2 is not allowed \(allowed: True/False \(or 1/0\)\)"):
        validate.flag(2, "enabled")
    assert validate.choice("usb", "link", ("usb", "ethernet")) == "usb"
    with pytest.raises(ConfigurationError, match=r"link = 'wifi' is not allowed \(allowed: usb, ethernet\)"):
        validate.choice("wifi", "link", ("usb", "ethernet"))
    with pytest.raises(ConfigurationError, match=r"polarity = True"):
        validate.choice(True, "polarity", (0, 1))


def test_integer_can_say_what_kind_of_value_it_wants_apart_from_the_range() -> None:
    kind = "an integer number of ticks"
    with pytest.raises(ConfigurationError, match=r"^w = 1\.5 is not allowed \(allowed: an integer number of ticks\)$"):
        validate.integer(1.5, "w", low=1, unit="ticks", kind=kind)
    with pytest.raises(ConfigurationError, match=r"^w = 0 is not allowed \(allowed: >= 1 ticks\)$"):
        validate.integer(0, "w", low=1, unit="ticks", kind=kind)


def test_whole_numbers_beyond_the_magnitude_bound_are_refused_by_their_range() -> None:
    with pytest.raises(ConfigurationError, match=r"^PWM_MARK = 1e\+600 is not allowed \(allowed: 0\.\.65535\)$"):
        validate.integer(Fraction(10**600), "PWM_MARK", low=0, high=65535, whole=True)


@pytest.mark.parametrize(("value", "text"), [
    (10**5000, "1e+5000"), (-(10**5000), "-1e+5000"), (Fraction(10**400, 3), "3.33333e+399"), (10**30, str(10**30)),
    (Fraction(10**2000 + 1, 10**2000), "about 1.0"), (np.int64(7), "7"), (np.float64(0.5), "0.5"),
], ids=["1e5000", "-1e5000", "1e400/3", "1e30", "1+1e-2000", "np.int64", "np.float64"])
def test_shown_keeps_huge_and_numpy_values_readable(value: object, text: str) -> None:
    assert repr(validate.shown(value)) == text


def test_in_range_shows_the_value_as_it_was_given() -> None:
    with pytest.raises(ConfigurationError, match=r"^inertia = 0\.0 is not allowed \(allowed: > 0\)$"):
        validate.positive(0.0, "inertia")
    with pytest.raises(ConfigurationError, match=r"^x = 1e\+5000 is not allowed \(allowed: a finite number of magni"):
        validate.exact(10**5000, "x")


def test_flag_takes_the_values_a_controller_language_has_for_yes() -> None:
    on_off = {"true": (1, -1), "allowed": "ON/OFF (1, 0 or TRUE = -1)"}
    assert [validate.flag(v, "SERVO", **on_off) for v in (Fraction(1), -1, 0.0, True)] == [True, True, False, True]
    for bad in (2, float("nan"), "1"):
        with pytest.raises(ConfigurationError, match=r"SERVO = .* is not allowed \(allowed: ON/OFF \(1, 0 or TRUE"):
            validate.flag(bad, "SERVO", **on_off)
    with pytest.raises(ConfigurationError, match=r"enabled = -1 is not allowed"):
        validate.flag(-1, "enabled")


def test_choice_returns_the_option_itself() -> None:
    number = validate.choice(Fraction(35), "ATYPE", (0, 35))
    assert number == 35 and type(number) is int
    assert validate.choice("ms", "unit", ("s", "ms")) == "ms"
