"""Configuration of the pulse engine: per-axis motion parameters and switch wiring.

Vendor parameters and their names here:

=============================  ==========================  ===============================
device parameter               field                       unit / default
=============================  ==========================  ===============================
maximum speed                  ``max_speed_hz``            pulses/s, 0 < v <= 25000
acceleration                   ``accel``                   pulses/s^2, > 0
deceleration                   ``decel``                   pulses/s^2, > 0
limit+ / limit- / home enable  ``limit_pos_enabled`` ...   off
direction change               ``invert_direction``        off
homing direction               ``invert_homing``           off (home towards negative)
homing speed, return speed     ``homing_speed_pct`` ...    10 %, 1 % of the maximum speed
emergency-switch polarity      ``emergency_polarity``      0: a high input is an emergency
=============================  ==========================  ===============================
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction

from cosim.controllers.pokeys.limits import (
    AXES,
    BUFFER_SLOTS,
    INTERNAL_LOOKAHEAD_SLOTS,
    MAX_PULSES_PER_SLOT,
    SLOT_NS,
    check_int_range,
    check_positive,
    check_rate_hz,
)
from cosim.errors import ConfigurationError

SLOTS_PER_S = 1_000_000_000 // SLOT_NS


@dataclass(frozen=True)
class AxisConfig:
    """Motion parameters and switch configuration of one axis.

    Parameters
    ----------
    max_speed_hz : int, Fraction or float
        Maximum pulse frequency [pulses/s], 0 < v <= 25000.
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
        check_rate_hz(self.max_speed_hz, "max_speed_hz", where=where)
        check_positive(self.accel, "accel", "pulses/s^2", where=where)
        check_positive(self.decel, "decel", "pulses/s^2", where=where)

    @property
    def max_speed_per_slot(self) -> Fraction:
        """Maximum speed [pulses/slot] (<= 25)."""
        return check_rate_hz(self.max_speed_hz, "max_speed_hz") / SLOTS_PER_S

    @property
    def accel_per_slot2(self) -> Fraction:
        """Acceleration [pulses/slot^2]."""
        return check_positive(self.accel, "accel", "pulses/s^2") / SLOTS_PER_S**2

    @property
    def decel_per_slot2(self) -> Fraction:
        """Deceleration [pulses/slot^2]."""
        return check_positive(self.decel, "decel", "pulses/s^2") / SLOTS_PER_S**2


@dataclass(frozen=True)
class EngineConfig:
    """Configuration of the whole engine.

    Parameters
    ----------
    axes : tuple of 3 AxisConfig
        x, y, z.
    pulse_width_ns : int
        Width of a step pulse [ns] (1..20000; drawn in VCD, checked against the spacing).
    dir_setup_ns : int
        Direction set-up [ns]: the direction output changes at the slot start and the first
        pulse of the slot comes this long after it. ``dir_setup_ns + pulse_width_ns`` must not
        exceed 40000 (the pulse spacing at 25 kHz), so no pulse crosses a slot boundary.
    homing_speed_pct, homing_return_pct : int
        Homing search and back-off speeds [% of max speed] (1..100; defaults 10 and 1).
    emergency_enabled : bool
        Evaluate the emergency input.
    emergency_polarity : {0, 1}
        0: a high input (1) means emergency (normally-closed switch to ground, the default);
        1: a low input (0) means emergency.
    internal_lookahead_slots : int
        Slots the internal controller keeps queued in the buffer (1..128; default 10).
    """

    axes: tuple[AxisConfig, ...] = (AxisConfig(name="x"), AxisConfig(name="y"), AxisConfig(name="z"))
    pulse_width_ns: int = 5_000
    dir_setup_ns: int = 5_000
    homing_speed_pct: int = 10
    homing_return_pct: int = 1
    emergency_enabled: bool = True
    emergency_polarity: int = 0
    internal_lookahead_slots: int = INTERNAL_LOOKAHEAD_SLOTS

    def __post_init__(self) -> None:
        if len(self.axes) != len(AXES):
            raise ConfigurationError.out_of_range("number of axes", len(self.axes), "3 (x, y, z)")
        spacing = SLOT_NS // MAX_PULSES_PER_SLOT
        check_int_range(self.pulse_width_ns, "pulse_width_ns", 1, spacing // 2, "ns")
        check_int_range(self.dir_setup_ns, "dir_setup_ns", 0, spacing - self.pulse_width_ns,
                        f"ns (with pulse_width_ns = {self.pulse_width_ns})")
        check_int_range(self.homing_speed_pct, "homing_speed_pct", 1, 100, "%")
        check_int_range(self.homing_return_pct, "homing_return_pct", 1, 100, "%")
        check_int_range(self.emergency_polarity, "emergency_polarity", 0, 1)
        check_int_range(self.internal_lookahead_slots, "internal_lookahead_slots", 1, BUFFER_SLOTS, "slots")

    def axis(self, index: int) -> AxisConfig:
        """Configuration of axis ``index`` (0..2)."""
        return self.axes[index]


def uniform_axes(**fields: object) -> tuple[AxisConfig, ...]:
    """Three axes with the same parameters, named x, y, z."""
    return tuple(AxisConfig(name=name, **fields) for name in AXES)  # type: ignore[arg-type]
