"""Trio EURO205X parameters: names, defaults, allowed ranges and the hardware constants of TN20-81.

Parameters keep their vendor names (``UNITS``, ``PWM_MARK``...) because that is what users write in
their programs; values are exact (``int`` or :class:`~fractions.Fraction`), never floats. Every
write goes through its :class:`ParamSpec` converter (built on :mod:`cosim.validate`), which raises
:class:`~cosim.errors.ConfigurationError` naming the parameter, the value and the allowed range.

Constants from the note (TN20-81) and the controller facts:

==========================  ==========  =============================================
``PWM_CLOCK_HZ``            20 MHz      base clock of the PWM generator
``PWM_REGISTER_MAX``        65535       largest ``PWM_CYCLE`` / ``PWM_MARK`` [clocks]
``PWM_ENCODER_BITS``        29          width of the ``PWM_ENCODER`` step counter
``FIFO_DEPTH``              256         gate positions the FIFO holds
``PWM_AXES``                (2, 3)      the only axes with the PWM / gating feature
``SERVO_PERIODS_US``        250..2000   servo periods modelled (1 ms default)
==========================  ==========  =============================================
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from fractions import Fraction

from cosim import validate

PWM_CLOCK_HZ = 20_000_000
#: One PWM clock [ns] (exact: 10**9 / 20 MHz).
PWM_CLOCK_NS = 50
PWM_REGISTER_MAX = 65535
PWM_ENCODER_BITS = 29
PWM_ENCODER_MODULUS = 1 << PWM_ENCODER_BITS
FIFO_DEPTH = 256
PWM_AXES = (2, 3)
SERVO_PERIODS_US = (250, 500, 1000, 2000)
DEFAULT_SERVO_PERIOD_US = 1000
#: ATYPE values modelled: 0 virtual axis (no output), 1 stepper (step/direction output, any axis),
#: 35 stepper output with PWM (axes 2 and 3, TN20-81).
ATYPE_VIRTUAL = 0
ATYPE_STEPPER = 1
ATYPE_STEPPER_PWM = 35
#: The ATYPEs that emit step pulses.
STEPPER_ATYPES = (ATYPE_STEPPER, ATYPE_STEPPER_PWM)
#: Divisor of the speed-link formula of PWM_CONTROL(2) (``VP_SPEED * multiplier / 100000 + offset``).
SPEED_LINK_DIVISOR = 100_000
#: Default size of TABLE memory [entries] (not stated in the note: a model parameter).
DEFAULT_TABLE_SIZE = 16_000
#: Default number of VR globals, VR(0)..VR(1023) (not re-read in a manual: a model parameter).
DEFAULT_VR_SIZE = 1024
#: User processes of a Euro 205, numbered 1..5 (TRM 7-12; process 0 is the command line).
PROCESSES = 5
#: Digital I/O channels: IN(0)..IN(31); outputs OP(8)..OP(31) (0..7 are inputs only) [model choice].
DEFAULT_IO_CHANNELS = 32
FIRST_OUTPUT = 8
#: Step pulse width [ns] from the leading to the active edge (not in the facts: a model parameter).
DEFAULT_STEP_PULSE_WIDTH_NS = 100
#: Direction set-up before the leading edge of a step pulse [ns] (TRM 8-165 note: a wrong INVERT_STEP
#: "may lose position by one step when changing direction", so the direction changes with the leading edge).
DEFAULT_DIR_SETUP_NS = 0

#: BASIC constants.
ON, OFF, TRUE, FALSE = 1, 0, -1, 0

Number = int | Fraction


#: The allowed values of an ON/OFF parameter, as messages say them.
ON_OFF = "ON/OFF (1, 0 or TRUE = -1)"


def on_off(value: object, name: str, *, where: str = "") -> int:
    """An ON/OFF value: 1 (ON), 0 (OFF) or -1 (TRUE) -> 1 or 0."""
    return int(validate.flag(value, name, where=where, true=(ON, TRUE), allowed=ON_OFF))


@dataclass(frozen=True)
class ParamSpec:
    """One parameter: its vendor name, default, allowed range and meaning.

    Parameters
    ----------
    name : str
        Vendor name, upper case (``PWM_MARK``).
    default : int or Fraction
        Power-up value.
    allowed : str
        The allowed range as text for error messages (``"0..65535"``).
    convert : callable
        ``convert(value, name, where) -> int | Fraction``: checks and converts a written value.
    unit : str
        Unit of the value.
    doc : str
        One line for humans.
    pwm_only : bool
        Only on axes with the PWM feature (:data:`PWM_AXES`).
    """

    name: str
    default: Number
    allowed: str
    convert: Callable[[object, str, str], Number]
    unit: str = ""
    doc: str = ""
    pwm_only: bool = False


_REGISTER = f"integer 0..{PWM_REGISTER_MAX}"


def _positive(value: object, name: str, where: str) -> Number:
    return validate.positive(value, name, where=where)


def _not_negative(value: object, name: str, where: str) -> Number:
    return validate.positive(value, name, where=where, zero=True)


def _register(value: object, name: str, where: str) -> Number:
    return validate.integer(value, name, low=0, high=PWM_REGISTER_MAX, where=where, allowed=_REGISTER, whole=True)


def _flag(value: object, name: str, where: str) -> Number:
    return on_off(value, name, where=where)


ATYPES = f"{ATYPE_VIRTUAL} (virtual), {ATYPE_STEPPER} (stepper), {ATYPE_STEPPER_PWM} (stepper output with PWM)"


def _atype(value: object, name: str, where: str) -> Number:
    number = validate.integer(value, name, where=where, allowed=ATYPES, whole=True)
    return validate.choice(number, name, (ATYPE_VIRTUAL, ATYPE_STEPPER, ATYPE_STEPPER_PWM), where=where,
                           allowed=ATYPES)


#: Writable axis parameters.
AXIS_PARAMS: dict[str, ParamSpec] = {p.name: p for p in (
    ParamSpec("UNITS", 1, "> 0", _positive, "counts/unit", "step pulses per user unit"),
    ParamSpec("SPEED", 1000, ">= 0", _not_negative, "units/s", "programmed path speed"),
    ParamSpec("ACCEL", 1000, "> 0", _positive, "units/s^2", "acceleration"),
    ParamSpec("DECEL", 1000, "> 0", _positive, "units/s^2", "deceleration"),
    ParamSpec("ATYPE", ATYPE_VIRTUAL, f"{ATYPE_VIRTUAL}, {ATYPE_STEPPER}, {ATYPE_STEPPER_PWM}", _atype, "",
              "axis type: 0 virtual, 1 stepper, 35 stepper output with PWM"),
    ParamSpec("INVERT_STEP", 0, "ON/OFF", _flag, "", "invert the step output: its active edge becomes rising "
              "(TRM 8-165)"),
    ParamSpec("SERVO", 0, "ON/OFF", _flag, "", "servo on: step pulses feed MPOS and PWM_ENCODER"),
    ParamSpec("FE_LIMIT", 2000, ">= 0", _not_negative, "units", "largest |DPOS - MPOS| before a motion error"),
    ParamSpec("PWM_CYCLE", 0, _REGISTER, _register, "clocks", "PWM mark+space period [20 MHz clocks]",
              pwm_only=True),
    ParamSpec("PWM_MARK", 0, _REGISTER, _register, "clocks", "PWM on-time [20 MHz clocks]", pwm_only=True),
)}

#: Axis parameters that can only be read (computed by the model).
READ_ONLY_AXIS_PARAMS: dict[str, str] = {
    "DPOS": "demand position [units]",
    "MPOS": "measured position [units] (counted step pulses while SERVO=ON)",
    "VP_SPEED": "velocity-profile speed [units/s]; the path speed of an interpolated move",
    "OFFPOS": "position offset of a DEFPOS not yet applied by the servo cycle [units]",
    "PWM_ENCODER": "29-bit count of the step pulses (PWM axes)",
    "IDLE": "TRUE (-1) when the axis has no move running or buffered",
    "LOADED": "TRUE (-1) when no move waits in the axis' next-move buffer",
    "FE": "following error DPOS - MPOS [units]",
}

#: Controller-wide parameters.
SYSTEM_PARAMS: dict[str, str] = {
    "WDOG": "drive enable relay; OFF switches every PWM output off at once",
    "SERVO_PERIOD": "servo period [us] (read-only: set when the controller is created)",
}


def axis_spec(name: str) -> ParamSpec:
    """The spec of writable axis parameter ``name`` (KeyError if there is none)."""
    return AXIS_PARAMS[name.upper()]


def check_servo_period_us(value: object) -> int:
    """A servo period [us] the EURO205X model supports."""
    allowed = ", ".join(map(str, SERVO_PERIODS_US)) + " us"
    number = validate.integer(value, "SERVO_PERIOD", allowed=allowed, whole=True)
    return validate.choice(number, "SERVO_PERIOD", SERVO_PERIODS_US, allowed=allowed)

def unknown_name(name: str) -> str:
    """The message for a parameter name the model does not know, with close matches."""
    import difflib

    known = sorted(AXIS_PARAMS) + sorted(READ_ONLY_AXIS_PARAMS) + sorted(SYSTEM_PARAMS)
    close = difflib.get_close_matches(name.upper(), known, n=3)
    hint = f"; did you mean {', '.join(close)}?" if close else ""
    return f"unknown parameter {name}{hint}"
