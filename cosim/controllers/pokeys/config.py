"""Configuration of the pulse engine: per-axis motion parameters and switch wiring.

Vendor parameters and their names here:

=============================  ==========================  ===============================
device parameter               field                       unit / default
=============================  ==========================  ===============================
maximum speed                  ``max_speed_hz``            pulses/s, 0 < v <= model's (25000)
acceleration                   ``accel``                   pulses/s^2, > 0
deceleration                   ``decel``                   pulses/s^2, > 0
limit+ / limit- / home enable  ``limit_pos_enabled`` ...   off
direction change               ``invert_direction``        off
homing direction               ``invert_homing``           off (home towards negative)
homing speed, return speed     ``homing_speed_pct`` ...    10 %, 1 % of the maximum speed
emergency-switch polarity      ``emergency_polarity``      0: a high input is an emergency
device model                   ``model``                   ``56E`` (axes, pulses per slot)
=============================  ==========================  ===============================
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction

from cosim.controllers.pokeys.limits import (
    AXIS_NAMES,
    BUFFER_SLOTS,
    INTERNAL_LOOKAHEAD_SLOTS,
    SLOTS_PER_S,
)
from cosim.controllers.pokeys.models import MODELS, DeviceModel, device_model
from cosim.errors import ConfigurationError
from cosim.validate import choice, flag, in_range, integer, positive

FASTEST_RATE_HZ = max(m.max_rate_hz for m in MODELS.values())
"""Highest pulse frequency of any model [pulses/s]; :class:`EngineConfig` checks each axis against its model's."""
HOMING_RESETS = ("release", "trip")
"""Readings of the homing document's "when the switch is tripped" (see :mod:`.homing`)."""


def rate_hz(value: object, name: str, *, high: int, where: str = "", signed: bool = False) -> Fraction:
    """A pulse rate [pulses/s]: ``> 0..high`` (``signed``: ``-high..high``), exactly."""
    if signed:
        return in_range(value, name, low=-high, high=high, allowed=f"-{high}..{high} pulses/s", where=where)
    return in_range(value, name, low=0, low_open=True, high=high, allowed=f"> 0..{high} pulses/s", where=where)


@dataclass(frozen=True)
class AxisConfig:
    """Motion parameters and switch configuration of one axis.

    Parameters
    ----------
    max_speed_hz : int, Fraction or float
        Maximum pulse frequency [pulses/s], 0 < v <= the model's maximum (25000 on a 56E).
    accel, decel : int, Fraction or float
        Maximum acceleration and deceleration [pulses/s^2], > 0.
    limit_pos_enabled, limit_neg_enabled, home_enabled : bool
        Whether the engine evaluates that switch input.
    invert_direction : bool
        Invert the direction output of this axis (the position counter is not inverted).
    invert_homing : bool
        Home towards positive instead of negative.
    """

    max_speed_hz: int | Fraction | float = 25_000
    accel: int | Fraction | float = 100_000
    decel: int | Fraction | float = 100_000
    limit_pos_enabled: bool = False
    limit_neg_enabled: bool = False
    home_enabled: bool = False
    invert_direction: bool = False
    invert_homing: bool = False
    name: str = field(default="", compare=False)

    def __post_init__(self) -> None:
        where = f"axis {self.name}" if self.name else ""
        rate_hz(self.max_speed_hz, "max_speed_hz", high=FASTEST_RATE_HZ, where=where)
        positive(self.accel, "accel", unit="pulses/s^2", where=where)
        positive(self.decel, "decel", unit="pulses/s^2", where=where)
        for name in ("limit_pos_enabled", "limit_neg_enabled", "home_enabled", "invert_direction", "invert_homing"):
            flag(getattr(self, name), name, where=where)

    @property
    def max_speed_per_slot(self) -> Fraction:
        """Maximum speed [pulses/slot]."""
        return rate_hz(self.max_speed_hz, "max_speed_hz", high=FASTEST_RATE_HZ) / SLOTS_PER_S

    @property
    def accel_per_slot2(self) -> Fraction:
        """Acceleration [pulses/slot^2]."""
        return positive(self.accel, "accel", unit="pulses/s^2") / SLOTS_PER_S**2

    @property
    def decel_per_slot2(self) -> Fraction:
        """Deceleration [pulses/slot^2]."""
        return positive(self.decel, "decel", unit="pulses/s^2") / SLOTS_PER_S**2


@dataclass(frozen=True)
class EngineConfig:
    """Configuration of the whole engine.

    Parameters
    ----------
    axes : tuple of AxisConfig
        One per axis of the model (3: x, y, z; 8 for a 57CNC: x, y, z, a, b, c, u, v).
    pulse_width_ns : int
        Width of a step pulse [ns] (1..half the pulse spacing at full rate: 20000 on a 56E; drawn
        in VCD, checked against the spacing).
    dir_setup_ns : int
        Direction set-up [ns]: the direction output changes at the slot start and the first
        pulse of the slot comes this long after it. ``dir_setup_ns + pulse_width_ns`` must not
        exceed the pulse spacing at full rate (40000 on a 56E), so no pulse crosses a slot boundary.
    homing_speed_pct, homing_return_pct : int
        Homing search and back-off speeds [% of max speed] (1..100; defaults 10 and 1).
    emergency_enabled : bool
        Evaluate the emergency input.
    emergency_polarity : {0, 1}
        0: a high input (1) means emergency (normally-closed switch to ground, the default);
        1: a low input (0) means emergency.
    internal_lookahead_slots : int
        Slots the internal controller keeps queued in the buffer (1..128; default 10).
    model : str
        Device model (:data:`~.models.MODELS`: ``56E`` default, ``56U``, ``57E``, ``57CNC``): its
        axes, pulses per slot and entry formats.
    homing_reset : {'release', 'trip'}
        When homing resets the counter: where the switch releases on the slow return (default),
        or where it trips at the end of the search (see :mod:`.homing`).
    """

    axes: tuple[AxisConfig, ...] = (AxisConfig(name="x"), AxisConfig(name="y"), AxisConfig(name="z"))
    pulse_width_ns: int = 5_000
    dir_setup_ns: int = 5_000
    homing_speed_pct: int = 10
    homing_return_pct: int = 1
    emergency_enabled: bool = True
    emergency_polarity: int = 0
    internal_lookahead_slots: int = INTERNAL_LOOKAHEAD_SLOTS
    model: str = "56E"
    homing_reset: str = "release"

    def __post_init__(self) -> None:
        device = device_model(self.model)
        if len(self.axes) != device.axes:
            names = ", ".join(device.axis_names)
            raise ConfigurationError.out_of_range("number of axes", len(self.axes),
                                                  f"{device.axes} ({names}) on a PoKeys{device.name}")
        for i, axis in enumerate(self.axes):
            rate_hz(axis.max_speed_hz, "max_speed_hz", high=device.max_rate_hz, where=f"axis {AXIS_NAMES[i]}")
        spacing = device.min_spacing_ns
        integer(self.pulse_width_ns, "pulse_width_ns", low=1, high=spacing // 2, unit="ns")
        integer(self.dir_setup_ns, "dir_setup_ns", low=0, high=spacing - self.pulse_width_ns,
                allowed=f"0..{spacing - self.pulse_width_ns} ns (with pulse_width_ns = {self.pulse_width_ns})")
        integer(self.homing_speed_pct, "homing_speed_pct", low=1, high=100, unit="%")
        integer(self.homing_return_pct, "homing_return_pct", low=1, high=100, unit="%")
        flag(self.emergency_enabled, "emergency_enabled")
        integer(self.emergency_polarity, "emergency_polarity", low=0, high=1)
        integer(self.internal_lookahead_slots, "internal_lookahead_slots", low=1, high=BUFFER_SLOTS, unit="slots")
        choice(self.homing_reset, "homing_reset", HOMING_RESETS)

    @classmethod
    def for_model(cls, model: str, **fields: object) -> EngineConfig:
        """A configuration of ``model`` with its axes (default parameters) and timing defaults, then ``fields``."""
        device = device_model(model)
        defaults: dict[str, object] = {"axes": uniform_axes(device.axes), "pulse_width_ns": device.pulse_width_ns,
                                       "dir_setup_ns": device.dir_setup_ns, "model": model}
        return cls(**{**defaults, **fields})  # type: ignore[arg-type]

    @property
    def device(self) -> DeviceModel:
        """The device model's figures."""
        return device_model(self.model)

    def axis(self, index: int) -> AxisConfig:
        """Configuration of axis ``index``."""
        return self.axes[index]


def uniform_axes(count: int = 3, **fields: object) -> tuple[AxisConfig, ...]:
    """``count`` axes (default 3: x, y, z) with the same parameters, named by :data:`~.limits.AXIS_NAMES`."""
    integer(count, "number of axes", low=1, high=len(AXIS_NAMES))
    return tuple(AxisConfig(name=name, **fields) for name in AXIS_NAMES[:count])  # type: ignore[arg-type]
