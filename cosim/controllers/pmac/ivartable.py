"""The Turbo PMAC I-variable space, I0..I8191: each variable's family, name, range, default and unit.

Every number from 0 to 8191 is an I-variable of the Turbo PMAC (the Turbo PMAC/PMAC2 Software
Reference, "Turbo PMAC Global I-Variables"): an assignment is checked against the variable's range
(:func:`check`) and stored; :func:`spec` gives what the reference says of it. Whether the model acts
on a variable is the controller's business (:mod:`.machine`); everything else is stored, readable
back and listed in the run's notes as "set, not modelled".

Families (x: motor 1..32, s: coordinate system 1..16, m: Servo IC 0..9, n: its channel 1..4):

====================  ===================================================  =================
numbers               family                                               as the reference
====================  ===================================================  =================
I0..I99               global                                               I5, I10, I15, ...
I100..I3299           motor xx: I(100 xx + nn)                             Ixx00..Ixx99
I3300..I4999          not used by the Turbo PMAC (kept as 48-bit values)
I5000..I5099          data gathering and A/D processing                    I5000..I5099
I5100..I6699          coordinate system s: I(5000 + 100 s + nn)            Isx00..Isx99
I6800..I6999          MACRO ICs                                            I6800..I6999
I7000..I7999          Servo IC m, channel n: I(7000 + 100 m + 10 n + k)    I7mnk
I8000..I8191          encoder conversion table setup lines                 I8000..I8191
====================  ===================================================  =================

The PMAC (non-Turbo) numbers of the coordinate-system time-base variables, Ix93 and Ix94 for
x = 1..8 (I193..I894), are kept as aliases of Isx93 and Isx94: the Turbo PMAC has no motor
variables Ixx93 and Ixx94, so nothing else is meant by those numbers.

Ranges and defaults: :data:`SOURCE` says where each number of this table comes from -- ``SRM``, read
in the Turbo Software Reference; ``QRG``, the PMAC Quick Reference Guide's I-variable summary for the
same motor variable (the Turbo reference's page was not at hand); ``word``, no page at hand: the
variable's register (a signed 24-bit word, or a 48-bit value) bounds it, and its default is 0.
A value outside the range is refused, naming the range (the controller itself would roll an
integer over, modulo its range -- a setup file that does that is almost always a mistake).
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

from cosim import validate
from cosim.errors import ConfigurationError

Value = int | Fraction

ECT_FIRST = 8000
ECT_LAST = 8191
#: Address of the first conversion-table line (I8000 is Y:$3501).
ECT_BASE = 0x3501
REG_MAX = (1 << 23) - 1
REG_MIN = -(1 << 23)
WORD_MAX = (1 << 24) - 1
BIG = (1 << 47) - 1
#: Motors, coordinate systems of the Turbo PMAC.
MOTORS = 32
SYSTEMS = 16


@dataclass(frozen=True)
class Spec:
    """What the reference says of one I-variable.

    Attributes
    ----------
    family : str
        The reference's name of the family (``Ixx30``, ``Isx93``, ``I7mn0``, ``I10``).
    name : str
        What it is.
    low, high : int or Fraction or None
        Allowed range (None: no bound on that side).
    default : int or Fraction
    unit : str
    kind : str
        ``int`` (whole numbers), ``float`` (any number), ``positive`` (the reference's "positive floating
        point": a number >= 0) or ``address``.
    source : str
        ``SRM``, ``QRG`` or ``word`` (see the module doc).
    """

    family: str
    name: str
    low: Value | None
    high: Value | None
    default: Value
    unit: str = ""
    kind: str = "int"
    source: str = "SRM"

    def allowed(self) -> str:
        """The range as messages say it."""
        if self.kind == "positive":
            return f">= 0{' and <= ' + str(self.high) if self.high is not None else ''}" + (
                f" ({self.unit})" if self.unit else "")
        kind = "integers " if self.kind in ("int", "address") else ""
        low = f"${self.low:X}" if self.kind == "address" and self.low is not None else self.low
        high = f"${self.high:X}" if self.kind == "address" and self.high is not None else self.high
        text = f"{kind}{low}..{high}" if low is not None and high is not None else (
            f">= {low}" if low is not None else f"<= {high}")
        return text + (f" ({self.unit})" if self.unit else "")


def _i(family: str, name: str, low: Value | None, high: Value | None, default: Value, unit: str = "",
       source: str = "SRM") -> Spec:
    return Spec(family, name, low, high, default, unit, "int", source)


def _f(family: str, name: str, low: Value | None, high: Value | None, default: Value, unit: str = "",
       source: str = "SRM") -> Spec:
    return Spec(family, name, low, high, default, unit, "float", source)


def _p(family: str, name: str, default: Value, unit: str = "", source: str = "SRM", high: Value | None = None
       ) -> Spec:
    return Spec(family, name, 0, high, default, unit, "positive", source)


def _a(family: str, name: str, default: int = 0, source: str = "SRM") -> Spec:
    return Spec(family, name, 0, WORD_MAX, default, "address", "address", source)


def _word(family: str, name: str) -> Spec:
    return Spec(family, name, REG_MIN, WORD_MAX, 0, "", "int", "word")


_MS = "ms"
_CT16 = "1/16 count"

#: Global I-variables I0..I99 that the model names (the others: :func:`_global_word`).
GLOBAL: dict[int, Spec] = {
    0: _i("I0", "serial card number", 0, 15, 0, source="word"),
    1: _i("I1", "serial port mode", 0, 3, 0, source="word"),
    2: _i("I2", "control panel port activation", 0, 3, 0, source="word"),
    3: _i("I3", "I/O handshake control", 0, 3, 1, source="SRM"),
    4: _i("I4", "communications integrity mode", 0, 3, 0, source="word"),
    5: _i("I5", "PLC program control", 0, 3, 1),
    6: _i("I6", "error reporting mode", 0, 3, 1, source="word"),
    7: _i("I7", "phase cycle extension", 0, 15, 0, source="word"),
    8: _i("I8", "real-time interrupt period", 0, 255, 2, "servo cycles - 1", source="word"),
    9: _i("I9", "full/abbreviated listing control", 0, 3, 2, source="word"),
    10: _i("I10", "servo interrupt time", 1, REG_MAX, 3713707, "2^-23 ms"),
    11: _i("I11", "programmed move calculation time", 0, REG_MAX, 0, _MS, source="word"),
    12: _i("I12", "lookahead spline time", 0, 1, 0, source="word"),
    13: _i("I13", "foreground in-position check enable", 0, 1, 0, source="word"),
    14: _i("I14", "temporary buffer save enable", 0, 1, 0, source="word"),
    15: _i("I15", "degree/radian control for user trig functions", 0, 1, 0, source="word"),
    16: _i("I16", "rotary buffer request on point", 0, REG_MAX, 5, source="word"),
    17: _i("I17", "rotary buffer request off point", 0, REG_MAX, 10, source="word"),
    18: _i("I18", "fixed buffer full warning point", 0, REG_MAX, 10, source="word"),
    19: _i("I19", "clock source I-variable number", 6807, 7907, 7007, source="word"),
    30: _i("I30", "compensation table wrap enable", 0, 1, 0, source="word"),
    37: _i("I37", "additional wait states", 0, 3, 0, source="word"),
    38: _i("I38", "in-line CALL enable", 0, 1, 0, source="word"),
    40: _i("I40", "watchdog timer reset value", 0, 65535, 0, "servo cycles", source="word"),
    41: _i("I41", "I-variable lockout control", 0, 15, 0, source="word"),
    42: _i("I42", "spline/PVT time control mode", 0, 1, 0, source="word"),
    51: _i("I51", "compensation table enable", 0, 1, 0, source="word"),
    52: _i("I52", "CPU frequency control", 0, 63, 7, source="word"),
    53: _i("I53", "auxiliary serial port baud rate control", 0, 15, 12, source="word"),
    54: _i("I54", "serial port baud rate control", 0, 15, 12, source="word"),
    59: _i("I59", "motor/C.S. group select", 0, 3, 0),
    60: _i("I60", "filtered velocity sample time", 0, 15, 15, "servo cycles - 1"),
    61: _i("I61", "filtered velocity shift", 0, 255, 8, source="word"),
    65: _f("I65", "user configuration variable (no automatic function)", -BIG, BIG, 0),
    67: _a("I67", "Modbus TCP buffer start address"),
    68: _i("I68", "coordinate system activation control", 0, 15, 15, source="word"),
}

#: Motor I-variables Ixx00..Ixx99 (xx = 1..32: I(100 xx + nn)) that the model names.
MOTOR: dict[int, Spec] = {
    0: _i("Ixx00", "activation control", 0, 1, 1, source="word"),
    1: _i("Ixx01", "commutation enable", 0, 3, 0, source="word"),
    2: _a("Ixx02", "command output address", source="word"),
    3: _a("Ixx03", "position-loop feedback address", source="word"),
    4: _a("Ixx04", "velocity-loop feedback address", source="word"),
    5: _a("Ixx05", "master position address", source="word"),
    6: _i("Ixx06", "position following enable and mode", 0, 3, 0, source="word"),
    7: _i("Ixx07", "master (handwheel) scale factor", REG_MIN, REG_MAX, 96),
    8: _i("Ixx08", "position scale factor", 0, REG_MAX, 96),
    9: _i("Ixx09", "velocity-loop scale factor", 0, REG_MAX, 96, source="word"),
    10: _a("Ixx10", "power-on servo position address", source="word"),
    11: _i("Ixx11", "fatal following error limit", 0, REG_MAX, 32000, _CT16, source="QRG"),
    12: _i("Ixx12", "warning following error limit", 0, REG_MAX, 16000, _CT16, source="QRG"),
    13: _f("Ixx13", "positive software position limit", -BIG, BIG, 0, "counts", source="QRG"),
    14: _f("Ixx14", "negative software position limit", -BIG, BIG, 0, "counts", source="QRG"),
    15: _p("Ixx15", "abort/limit deceleration rate", Fraction(1, 4), "counts/ms^2", source="QRG"),
    16: _p("Ixx16", "maximum program velocity", 32, "counts/ms"),
    17: _p("Ixx17", "maximum program acceleration", Fraction(1, 64), "counts/ms^2", source="QRG"),
    19: _p("Ixx19", "maximum jog/home acceleration", Fraction(1, 64), "counts/ms^2", source="QRG"),
    20: _i("Ixx20", "jog/home acceleration time", 0, REG_MAX, 0, _MS, source="QRG"),
    21: _i("Ixx21", "jog/home S-curve time", 0, REG_MAX, 50, _MS, source="QRG"),
    22: _p("Ixx22", "jog speed", 32, "counts/ms", source="QRG", high=REG_MAX),
    23: _f("Ixx23", "homing speed and direction", -BIG, BIG, 32, "counts/ms", source="QRG"),
    24: _a("Ixx24", "flag mode control", source="word"),
    25: _a("Ixx25", "flag address", source="word"),
    26: _i("Ixx26", "home offset", REG_MIN, REG_MAX, 0, _CT16, source="QRG"),
    27: _i("Ixx27", "position rollover range", -(1 << 35), 1 << 35, 0, "counts"),
    28: _i("Ixx28", "in-position band", 0, REG_MAX, 160, _CT16, source="QRG"),
    29: _i("Ixx29", "output/first phase offset", -32768, 32767, 0, "DAC bits", source="QRG"),
    30: _i("Ixx30", "PID proportional gain", REG_MIN, REG_MAX, 2000, source="QRG"),
    31: _i("Ixx31", "PID derivative gain", REG_MIN, REG_MAX, 1280, source="QRG"),
    32: _i("Ixx32", "PID velocity feed forward gain", 0, REG_MAX, 1280, source="QRG"),
    33: _i("Ixx33", "PID integral gain", 0, REG_MAX, 0, source="QRG"),
    34: _i("Ixx34", "PID integration mode", 0, 1, 1, source="QRG"),
    35: _i("Ixx35", "PID acceleration feed forward gain", 0, REG_MAX, 0, source="QRG"),
    57: _i("Ixx57", "continuous current limit", 0, 32767, 0, "DAC bits", source="QRG"),
    58: _i("Ixx58", "integrated current limit", 0, REG_MAX, 0, source="QRG"),
    59: _i("Ixx59", "user-written servo/phase enable", 0, 3, 0, source="QRG"),
    60: _i("Ixx60", "servo cycle period extension", 0, 255, 0, "servo interrupts", source="QRG"),
    63: _i("Ixx63", "integration limit", REG_MIN, REG_MAX, 4194304, _CT16, source="QRG"),
    64: _i("Ixx64", "deadband gain factor", -32768, 32767, 0, source="QRG"),
    65: _i("Ixx65", "deadband size", 0, 32767, 16, _CT16, source="QRG"),
    66: _i("Ixx66", "PWM scale factor", 0, 32767, 6527, "PWM_CLK cycles"),
    67: _i("Ixx67", "linear position error limit", 0, REG_MAX, 4194304, _CT16, source="QRG"),
    68: _i("Ixx68", "friction feed forward", -32768, 32767, 0, "DAC bits", source="QRG"),
    69: _i("Ixx69", "output command limit", 0, 32767, 20480, "DAC bits", source="QRG"),
    70: _i("Ixx70", "number of commutation cycles", 0, 255, 1, source="QRG"),
    71: _i("Ixx71", "counts per N commutation cycles", 0, REG_MAX, 1000, "counts", source="QRG"),
    72: _i("Ixx72", "commutation phase angle", 0, 255, 85, source="QRG"),
    73: _i("Ixx73", "phase finding output value", 0, 32767, 0, "DAC bits", source="QRG"),
    74: _i("Ixx74", "phase finding time", 0, 255, 0, "servo cycles", source="QRG"),
    75: _i("Ixx75", "absolute phase position offset", REG_MIN, REG_MAX, 0, source="QRG"),
    76: _i("Ixx76", "velocity phase advance gain", 0, REG_MAX, 0, source="QRG"),
    77: _i("Ixx77", "magnetization current", -32768, 32767, 0, "DAC bits", source="QRG"),
    78: _i("Ixx78", "slip gain", 0, REG_MAX, 0, source="QRG"),
    79: _i("Ixx79", "second phase offset", -32768, 32767, 0, "DAC bits", source="QRG"),
    80: _i("Ixx80", "power-up mode", 0, 7, 0, source="QRG"),
    81: _a("Ixx81", "power-on phase position address", source="QRG"),
    82: _a("Ixx82", "current-loop feedback address", source="word"),
    83: _a("Ixx83", "ongoing phase position address", source="QRG"),
    92: _i("Ixx92", "jog move calculation time", 1, REG_MAX, 10, _MS),
    95: _a("Ixx95", "power-on servo position format"),
}

#: Coordinate-system I-variables Isx00..Isx99 (s = 1..16: I(5000 + 100 s + nn)) that the model names.
CS: dict[int, Spec] = {
    11: _i("Isx11", "user countdown timer 1", REG_MIN, REG_MAX, 0, "servo cycles"),
    12: _i("Isx12", "user countdown timer 2", REG_MIN, REG_MAX, 0, "servo cycles"),
    13: _i("Isx13", "segmentation time", 0, REG_MAX, 0, _MS, source="word"),
    20: _i("Isx20", "lookahead length", 0, 65535, 0, "segments", source="word"),
    21: _i("Isx21", "lookahead state control", 0, 15, 0),
    50: _i("Isx50", "kinematic calculations enable", 0, 1, 0),
    87: _i("Isx87", "default program acceleration time", 0, REG_MAX, 0, _MS, source="QRG"),
    88: _i("Isx88", "default program S-curve time", 0, REG_MAX, 50, _MS, source="QRG"),
    89: _p("Isx89", "default program feedrate/move time", 1000, "axis units / Isx90", high=REG_MAX),
    90: _p("Isx90", "feedrate time units", 1000, _MS),
    93: _a("Isx93", "time base control address", 0x2000),
    94: _i("Isx94", "time base slew rate", 0, REG_MAX, 1644, "2^-23 ms per servo cycle"),
    95: _i("Isx95", "feed hold slew rate", 0, REG_MAX, 1644, "2^-23 ms per servo cycle"),
}

#: The names the model's messages have always used for the variables it acts on.
LABELS = {("CS", 87): "Ix87, default TA", ("CS", 88): "Ix88, default TS", ("CS", 89): "Ix89, default feedrate",
          ("CS", 93): "Ix93, time-base source address", ("CS", 94): "Ix94, time-base slew limit",
          ("CS", 95): "Ix95, feed-hold slew rate", ("MOTOR", 20): "Ixx20, jog acceleration time",
          ("MOTOR", 21): "Ixx21, jog S-curve time", ("MOTOR", 22): "Ixx22, jog speed",
          ("GLOBAL", 10): "servo interrupt time", ("ECT", 0): "conversion table line"}
#: Non-Turbo numbers kept as aliases: Ix93, Ix94 of coordinate systems 1..8 (I193..I894).
PMAC_ALIASES = (93, 94)


def split(number: int) -> tuple[str, int, int]:
    """``(family, unit, suffix)``: ``("MOTOR", 3, 30)`` for I330, ``("CS", 2, 94)`` for I5294 or I294.

    Families: GLOBAL, MOTOR, UNUSED, GATHER, CS, MACRO, SERVO_IC, ECT.

    Examples
    --------
    >>> split(130), split(5194), split(194), split(7012), split(8002)
    (('MOTOR', 1, 30), ('CS', 1, 94), ('CS', 1, 94), ('SERVO_IC', 0, 12), ('ECT', 0, 2))
    """
    if not 0 <= number <= ECT_LAST:
        raise ConfigurationError.out_of_range("I-variable number", number, f"0..{ECT_LAST}")
    if number < 100:
        return "GLOBAL", 0, number
    if number < 100 * (MOTORS + 1):
        unit, suffix = divmod(number, 100)
        if suffix in PMAC_ALIASES and unit <= 8:
            return "CS", unit, suffix
        return "MOTOR", unit, suffix
    if number < 5000:
        return "UNUSED", 0, number
    if number < 5100:
        return "GATHER", 0, number - 5000
    if number < 5000 + 100 * (SYSTEMS + 1):
        unit, suffix = divmod(number - 5000, 100)
        return "CS", unit, suffix
    if number < 7000:
        return "MACRO", 0, number - 6800
    if number < ECT_FIRST:
        ic, rest = divmod(number - 7000, 100)
        return "SERVO_IC", ic, rest
    return "ECT", 0, number - ECT_FIRST


def spec(number: int) -> Spec:
    """What the reference says of I``number`` (see the module doc for the sources)."""
    family, unit, suffix = split(number)
    if family == "GLOBAL":
        return GLOBAL.get(suffix) or _word(f"I{suffix}", "global I-variable")
    if family == "MOTOR":
        return MOTOR.get(suffix) or _word(f"Ixx{suffix:02d}", f"motor {unit} I-variable")
    if family == "CS":
        return CS.get(suffix) or _word(f"Isx{suffix:02d}", f"coordinate system {unit} I-variable")
    if family == "ECT":
        return _i(f"I{number}", "conversion table setup line", 0, WORD_MAX, 0)
    if family == "SERVO_IC":
        return _servo_ic(unit, suffix)
    if family == "GATHER":
        if 1 <= suffix <= 48:
            return _a("I5001..I5048", "data gathering source address", source="word")
        return _word(f"I{number}", "data gathering / A-D processing I-variable")
    if family == "MACRO":
        return _word(f"I{number}", "MACRO IC I-variable")
    return Spec(f"I{number}", "not used by the Turbo PMAC", -BIG, BIG, 0, "", "float", "word")


#: Servo IC channel variables I7mn0..I7mn9: name, range, default (read in the reference for 0, 1, 3, 5; 2 from
#: the project's controller facts, TSRM p. 222).
SERVO_CHANNEL: dict[int, tuple[str, int, int, int, str]] = {
    0: ("encoder/timer decode control", 0, 15, 7, "SRM"), 1: ("encoder filter disable", 0, 1, 0, "SRM"),
    2: ("capture control", 0, 15, 1, "SRM"), 3: ("capture flag select control", 0, 3, 0, "SRM"),
    4: ("encoder gated index select", 0, 1, 0, "word"), 5: ("encoder index gate state/demux control", 0, 3, 0, "SRM"),
    6: ("output mode control", 0, 3, 0, "word"), 7: ("output invert control", 0, 3, 0, "word"),
    8: ("PFM direction signal invert control", 0, 1, 0, "word"), 9: ("hardware 1/T control", 0, 1, 0, "word"),
}


def _servo_ic(ic: int, rest: int) -> Spec:
    channel, item = divmod(rest % 50, 10)
    family = f"I7m{'n' if channel else '0'}{item}"
    if channel == 0:
        return _word(family, f"Servo IC {ic} multi-channel I-variable")
    name, low, high, default, source = SERVO_CHANNEL[item]
    return _i(family, f"Servo IC {ic} channel {channel} {name}", low, high, default, source=source)


def name(number: int) -> str:
    """``I5194 (Ix94, time-base slew limit)``: the variable and what it is, for messages."""
    family, _unit, suffix = split(number)
    label = LABELS.get((family, suffix)) or LABELS.get((family, 0) if family == "ECT" else ("", 0))
    if label is None:
        item = spec(number)
        label = f"{item.family}, {item.name}"
    return f"I{number} ({label})"


def check(number: int, value: object, *, where: str = "") -> Value:
    """``value`` checked against I``number``'s range; returns it exactly (an int where it is whole)."""
    item = spec(number)
    what = name(number)
    if item.kind in ("int", "address"):
        low = None if item.low is None else int(item.low)
        high = None if item.high is None else int(item.high)
        checked: Value = validate.integer(value, what, low=low, high=high, where=where, allowed=item.allowed())
        return checked
    exact = validate.exact(value, what, where=where) if not isinstance(value, int | Fraction) else Fraction(value)
    if item.kind == "positive":  # "positive floating point": 0 and more (I100..131=0 is a setup file's first line)
        if exact < 0 or (item.high is not None and exact > item.high):
            raise ConfigurationError.out_of_range(what, value, item.allowed(), where=where)
    elif (item.low is not None and exact < item.low) or (item.high is not None and exact > item.high):
        raise ConfigurationError.out_of_range(what, value, item.allowed(), where=where)
    return exact.numerator if exact.denominator == 1 else exact


def default(number: int) -> Value:
    """The reference's default of I``number``."""
    return spec(number).default


def address_of(number: int) -> int | None:
    """``@In``: the address of conversion-table line I``number`` (None for other variables)."""
    return ECT_BASE + number - ECT_FIRST if ECT_FIRST <= number <= ECT_LAST else None
