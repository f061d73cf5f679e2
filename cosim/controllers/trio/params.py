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
    acts : bool
        The model uses the value; otherwise it is checked, stored, readable back and listed as
        "set, not modelled".
    """

    name: str
    default: Number
    allowed: str
    convert: Callable[[object, str, str], Number]
    unit: str = ""
    doc: str = ""
    pwm_only: bool = False
    acts: bool = True


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


def _number(value: object, name: str, where: str) -> Number:
    return validate.exact(value, name, where=where)


def _input_channel(value: object, name: str, where: str) -> Number:
    allowed = f"-1 (none) or an input 0..{DEFAULT_IO_CHANNELS - 1}"
    return validate.integer(value, name, low=-1, high=DEFAULT_IO_CHANNELS - 1, where=where, allowed=allowed,
                            whole=True)


def _whole(low: int | None, high: int | None) -> Callable[[object, str, str], Number]:
    def convert(value: object, name: str, where: str) -> Number:
        return validate.integer(value, name, low=low, high=high, where=where, whole=True)
    return convert


def _sramp(value: object, name: str, where: str) -> Number:
    return validate.in_range(validate.exact(value, name, where=where), name, low=0, high=SRAMP_MAX_MS, where=where,
                             allowed=f"0..{SRAMP_MAX_MS} ms")


def _rep_option(value: object, name: str, where: str) -> Number:
    return validate.integer(value, name, low=0, high=3, where=where, whole=True,
                            allowed="0..3 (bit 0: range 0..REP_DIST instead of -REP_DIST..REP_DIST)")


#: Largest SRAMP [ms] (S-ramp time) [?: not re-read in a manual].
SRAMP_MAX_MS = 250
#: Position range of the repeat distance by default [units] [?].
DEFAULT_REP_DIST = 200_000
#: Software limits by default: beyond REP_DIST, so off [?].
DEFAULT_FS_LIMIT = 200_000_000

_P = ParamSpec
#: Writable axis parameters. ``acts``: the model uses the value (it changes what the axis does or
#: when); the others are checked, stored, readable back and listed as "set, not modelled".
AXIS_PARAMS: dict[str, ParamSpec] = {p.name: p for p in (
    _P("UNITS", 1, "> 0", _positive, "counts/unit", "step pulses per user unit"),
    _P("SPEED", 1000, ">= 0", _not_negative, "units/s", "programmed path speed"),
    _P("ACCEL", 1000, "> 0", _positive, "units/s^2", "acceleration"),
    _P("DECEL", 1000, "> 0", _positive, "units/s^2", "deceleration"),
    _P("ATYPE", ATYPE_VIRTUAL, f"{ATYPE_VIRTUAL}, {ATYPE_STEPPER}, {ATYPE_STEPPER_PWM}", _atype, "",
       "axis type: 0 virtual, 1 stepper, 35 stepper output with PWM"),
    _P("INVERT_STEP", 0, "ON/OFF", _flag, "", "invert the step output: its active edge becomes rising (TRM 8-165)"),
    _P("SERVO", 0, "ON/OFF", _flag, "", "servo on: step pulses feed MPOS and PWM_ENCODER; FE is checked"),
    _P("FE_LIMIT", 2000, ">= 0", _not_negative, "units", "largest |DPOS - MPOS| before a motion error"),
    _P("PWM_CYCLE", 0, _REGISTER, _register, "clocks", "PWM mark+space period [20 MHz clocks]", pwm_only=True),
    _P("PWM_MARK", 0, _REGISTER, _register, "clocks", "PWM on-time [20 MHz clocks]", pwm_only=True),
    # acting parameters beyond TN20-81
    _P("CREEP", 200, ">= 0", _not_negative, "units/s", "speed of the slow phase of a DATUM sequence"),
    _P("JOGSPEED", 200, ">= 0", _not_negative, "units/s", "jog speed (FWD_JOG / REV_JOG inputs)"),
    _P("DATUM_IN", -1, "-1 or an input", _input_channel, "", "datum switch input (active low: at the switch "
       "while OFF)"),
    _P("FWD_IN", -1, "-1 or an input", _input_channel, "", "forward hardware limit input (active low)"),
    _P("REV_IN", -1, "-1 or an input", _input_channel, "", "reverse hardware limit input (active low)"),
    _P("FWD_JOG", -1, "-1 or an input", _input_channel, "", "forward jog input (active low)"),
    _P("REV_JOG", -1, "-1 or an input", _input_channel, "", "reverse jog input (active low)"),
    _P("FAST_JOG", -1, "-1 or an input", _input_channel, "", "jog at SPEED instead of JOGSPEED while active (low)"),
    _P("FS_LIMIT", DEFAULT_FS_LIMIT, "a number", _number, "units", "forward software limit (on while below "
       "REP_DIST)"),
    _P("RS_LIMIT", -DEFAULT_FS_LIMIT, "a number", _number, "units", "reverse software limit (on while above "
       "-REP_DIST)"),
    _P("REP_DIST", DEFAULT_REP_DIST, "> 0", _positive, "units", "repeat distance: DPOS and MPOS wrap at it"),
    _P("REP_OPTION", 0, "0..3", _rep_option, "", "bit 0: positions wrap in 0..REP_DIST"),
    _P("MERGE", 0, "ON/OFF", _flag, "", "merge a buffered linear move into the running one (no stop between)"),
    _P("SRAMP", 0, f"0..{SRAMP_MAX_MS}", _sramp, "ms", "S-ramp time: the acceleration ramps over it"),
    # accepted, stored, not modelled (servo tuning, encoder set-up, windows...)
    *(_P(name, default, "a number", _number, unit, doc, acts=False) for name, default, unit, doc in (
        ("P_GAIN", 1, "", "proportional gain"), ("I_GAIN", 0, "", "integral gain"),
        ("D_GAIN", 0, "", "derivative gain"),
        ("OV_GAIN", 0, "", "output velocity gain"), ("VFF_GAIN", 0, "", "velocity feed forward gain"),
        ("AFF_GAIN", 0, "", "acceleration feed forward gain"), ("DAC", 0, "", "DAC output when SERVO=OFF"),
        ("DAC_SCALE", 16, "", "DAC scaling"), ("D_ZONE_MIN", 0, "", "dead zone low"),
        ("D_ZONE_MAX", 0, "", "dead zone high"), ("OUTLIMIT", 1, "", "limit of the servo output"),
        ("FASTDEC", 0, "units/s^2", "fast deceleration"), ("FHSPEED", 0, "units/s", "feedhold speed"),
        ("CLOSE_WIN", 0, "units", "registration window end"), ("OPEN_WIN", 0, "units", "registration window start"),
        ("FE_RANGE", 0, "units", "following error warning range"), ("CLUTCH_RATE", 0, "", "CONNECT ratio rate"),
        ("BACKLASH_DIST", 0, "units", "backlash"), ("S_REF", 0, "", "speed reference (open loop)"),
        ("T_REF", 0, "", "torque reference"), ("ENDMOVE", 0, "units", "end of the current move"),
        ("ENCODER_RATIO", 1, "", "MPOS per encoder edge (ENCODER_RATIO(denominator, numerator))"),
        ("STEP_RATIO", 1, "", "step pulses per demand count (STEP_RATIO(denominator, numerator))"),
        ("REGIST_SPEED", 0, "units/s", "registration speed"))),
    *(_P(name, default, allowed, conv, "", doc, acts=False) for name, default, allowed, conv, doc in (
        ("FHOLD_IN", -1, "-1 or an input", _input_channel, "feedhold input"),
        ("AXIS_ENABLE", 1, "ON/OFF", _flag, "axis enable"), ("VERIFY", 0, "ON/OFF", _flag, "step verification"),
        ("FE_LIMIT_MODE", 0, "0..1", _whole(0, 1), "following error action"),
        ("AXIS_DISPLAY", 0, "0..7", _whole(0, 7), "what the axis LEDs show"),
        ("ENCODER_BITS", 0, "0..255", _whole(0, 255), "absolute encoder bits"),
        ("ENCODER_CONTROL", 0, "0..255", _whole(0, 255), "absolute encoder mode"),
        ("PP_STEP", 0, "-1024..1023", _whole(-1024, 1023), "pulses per step of a verifying stepper"),
        ("ERRORMASK", 268, "0..65535", _whole(0, 65535), "AXISSTATUS bits that are motion errors"),
        ("SSI_BITS", 0, "0..31", _whole(0, 31), "bits of an SSI absolute encoder"),
        ("MICROSTEP", 0, "ON/OFF", _flag, "microstepping (internal counts doubled)"),
        ("DRIVE_CONTROL", 0, "a whole number", _whole(None, None), "what a digital drive reports"),
        ("AXIS_MODE", 0, "a whole number >= 0", _whole(0, None), "axis mode bits (later firmware)"))),
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
    "AXISSTATUS": "status bits: 16 forward limit, 32 reverse limit, 64 datuming, 256 following error exceeded, "
                  "512 forward software limit, 1024 reverse software limit, 2048 cancelling",
    "AXIS_STATUS": "the same as AXISSTATUS (the later firmware's name)",
    "MARK": "TRUE (-1) once a registration armed by REGIST has captured REG_POS",
    "REG_POS": "position latched at the registration edge [units]",
    "MTYPE": "type of the running move (0 idle, 1 MOVE, 2 MOVEABS, 4 MOVECIRC, 10 FORWARD, 11 REVERSE, "
             "12 DATUM, 13 CAM, 14 FWD_JOG, 15 REV_JOG, 20 CAMBOX, 21 CONNECT, 22 MOVELINK)",
    "NTYPE": "type of the buffered move (as MTYPE)",
    "REMAIN": "distance to the end of the running move [units]",
    "MSPEED": "measured speed over the last servo cycle [units/s]",
    "DEMAND_EDGES": "demand position [counts]",
    "LINKAX": "the link axis of the running linked move (-1: none)",
    "MOVES_BUFFERED": "moves running or buffered on the axis",
    "DRIVE_STATUS": "drive status register (0: no drive with digital communications)",
    "ENCODER": "raw encoder count (the step count of a stepper)",
    "TRANS_DPOS": "demand position after the frame transformation (1:1 here: DPOS) [units]",
    # read back as a fixed value and listed as "read, not modelled" (see READ_NOT_MODELLED)
    "MARKB": "TRUE (-1) once the second registration channel captured (not modelled: FALSE)",
    "REG_POSB": "position latched by the second registration channel (not modelled: 0) [units]",
    "TRANSITIONS": "registration input transitions of a REGIST sequence (not modelled: 0)",
    "ENCODER_STATUS": "status of an absolute encoder (not modelled: 0)",
    "ENCODER_TYPE": "type of an absolute encoder (not modelled: 0)",
    "ENCODER_ID": "identity of an absolute encoder (not modelled: 0)",
    "FE_LATCH": "the following error that stopped the axis (not modelled: 0) [units]",
    "S_REF_OUT": "the speed reference sent to the drive (not modelled: 0)",
    "ADDAX_AXIS": "the axis an ADDAX superimposes (-1: none; ADDAX is not modelled)",
}
#: Read-only axis parameters read as a fixed value: each read is listed as "not modelled".
READ_NOT_MODELLED: dict[str, int] = {"MARKB": 0, "REG_POSB": 0, "TRANSITIONS": 0, "ENCODER_STATUS": 0,
                                     "ENCODER_TYPE": 0, "ENCODER_ID": 0, "FE_LATCH": 0, "S_REF_OUT": 0,
                                     "ADDAX_AXIS": -1}

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
