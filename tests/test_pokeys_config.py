"""PoKeys configuration: axis parameters in pulses/s and pulses/s^2, and every bad value named with its range."""

from __future__ import annotations

from fractions import Fraction

import pytest

from cosim.controllers.pokeys import MAX_RATE_HZ, AxisConfig, EngineConfig, PulseEngine, uniform_axes
from cosim.controllers.pokeys.limits import check_axis
from cosim.errors import ConfigurationError
from cosim.kernel import Simulation


def test_axis_parameters_convert_exactly_to_slot_units() -> None:
    axis = AxisConfig(max_speed_hz=12_345, accel=100_000, decel=250_000)
    assert axis.max_speed_per_slot == Fraction(12_345, 1000)
    assert (axis.accel_per_slot2, axis.decel_per_slot2) == (Fraction(1, 10), Fraction(1, 4))
    assert MAX_RATE_HZ == 25_000 and AxisConfig(max_speed_hz=25_000).max_speed_per_slot == 25


@pytest.mark.parametrize(("fields", "message"), [
    ({"max_speed_hz": 0}, r"axis x: max_speed_hz = 0 is not allowed \(allowed: > 0\.\."),
    ({"max_speed_hz": -5.5}, r"max_speed_hz = -5.5 is not allowed"),
    ({"accel": 0}, r"axis x: accel = 0 is not allowed \(allowed: > 0 pulses/s\^2\)"),
    ({"accel": -1}, r"axis x: accel = -1 is not allowed \(allowed: > 0 pulses/s\^2\)"),
    ({"decel": 0.0}, r"axis x: decel = 0.0 is not allowed \(allowed: > 0 pulses/s\^2\)"),
    ({"decel": "fast"}, r"decel = 'fast' is not allowed \(allowed: a finite number\)"),
])
def test_bad_axis_parameters_are_refused(fields: dict[str, object], message: str) -> None:
    with pytest.raises(ConfigurationError, match=message):
        AxisConfig(name="x", **fields)  # type: ignore[arg-type]


@pytest.mark.parametrize(("model", "fastest_hz"), [("56E", 25_000), ("57E", 25_000), ("57CNC", 125_000)])
def test_maximum_speed_is_the_models_pulse_rate(model: str, fastest_hz: int) -> None:
    """56 series and the 57's internal generator: 25 kHz; the 8-channel generator of the 57CNC: 125 kHz."""
    assert EngineConfig.for_model(model, axes=uniform_axes(3 if model != "57CNC" else 8, max_speed_hz=fastest_hz))
    message = rf"axis x: max_speed_hz = {fastest_hz + 1} is not allowed \(allowed: > 0..{fastest_hz} pulses/s\)"
    with pytest.raises(ConfigurationError, match=message):
        EngineConfig.for_model(model, axes=uniform_axes(3 if model != "57CNC" else 8, max_speed_hz=fastest_hz + 1))


@pytest.mark.parametrize(("fields", "message"), [
    ({"axes": (AxisConfig(), AxisConfig())}, r"number of axes = 2 is not allowed \(allowed: 3"),
    ({"model": "57CNC"}, r"number of axes = 3 is not allowed \(allowed: 8 \(x, y, z, a, b, c, u, v\) on a PoKeys57CNC"),
    ({"model": "55"}, r"model = '55' is not allowed \(allowed: 56E, 56U, 57E, 57CNC\)"),
    ({"homing_reset": "midway"}, r"homing_reset = 'midway' is not allowed \(allowed: release, trip\)"),
    ({"pulse_width_ns": 0}, r"pulse_width_ns = 0 is not allowed \(allowed: 1..20000 ns\)"),
    ({"pulse_width_ns": 30_000}, r"pulse_width_ns = 30000 is not allowed"),
    ({"dir_setup_ns": 36_000}, r"dir_setup_ns = 36000 is not allowed \(allowed: 0..35000 ns \(with pulse_width_ns"),
    ({"homing_speed_pct": 0}, r"homing_speed_pct = 0 is not allowed \(allowed: 1..100 %\)"),
    ({"homing_return_pct": 101}, r"homing_return_pct = 101 is not allowed"),
    ({"emergency_polarity": 2}, r"emergency_polarity = 2 is not allowed \(allowed: 0..1\)"),
    ({"internal_lookahead_slots": 0}, r"internal_lookahead_slots = 0 is not allowed \(allowed: 1..128 slots\)"),
])
def test_bad_engine_settings_are_refused(fields: dict[str, object], message: str) -> None:
    with pytest.raises(ConfigurationError, match=message):
        EngineConfig(**fields)  # type: ignore[arg-type]


@pytest.mark.parametrize("axis", [-1, 3, 1.0, True, "x"])
def test_axis_index_outside_0_to_2_is_refused(axis: object) -> None:
    with pytest.raises(ConfigurationError, match=r"axis = .* is not allowed \(allowed: 0..2 \(x, y, z\)\)"):
        check_axis(axis)


def test_engine_commands_name_the_bad_axis(sim: Simulation) -> None:
    engine = PulseEngine(sim)
    with pytest.raises(ConfigurationError, match=r"set_position: axis = 3 is not allowed \(allowed: 0..2"):
        engine.set_position(3, 0)
    with pytest.raises(ConfigurationError, match=r"jog axis x: speed_hz = -30000 is not allowed"):
        engine.jog(0, -30_000)
