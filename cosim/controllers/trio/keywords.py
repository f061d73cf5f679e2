"""The vocabulary of Trio BASIC: commands, functions, parameters, constants, and what each takes.

Every keyword of the Motion Coordinator Technical Reference Manual (TRM chapter 8) that a program
may write is listed here, with the number of arguments it takes and what the model does with it:

* **modelled** commands and functions act (a move, an output, a string function...);
* **settings** commands (``SETCOM``, ``SCOPE``, ``AUTORUN``...) are accepted, do nothing that
  changes timing, and are listed in the run's notes as "set, not modelled" with their arguments;
* **motion not modelled** (``MHELICAL``, ``ADDAX``...) are accepted by the compiler (they are the
  language) and stop the program with a message naming the command when it is reached, rather
  than moving nothing silently.

A name that is none of these is refused before the program runs, with the close matches.
"""

from __future__ import annotations

import difflib
from dataclasses import dataclass

from cosim.controllers.trio.params import AXIS_PARAMS, FALSE, OFF, ON, READ_ONLY_AXIS_PARAMS, SYSTEM_PARAMS, TRUE


@dataclass(frozen=True)
class Signature:
    """A command or function: how many arguments it takes.

    Parameters
    ----------
    name : str
        Keyword, upper case.
    low, high : int
        Fewest and most arguments (``high`` None: any number from ``low``).
    usage : str
        How it is written, for messages.
    axis_modifier : bool
        Takes an ``AXIS(n)`` modifier.
    """

    name: str
    low: int
    high: int | None
    usage: str
    axis_modifier: bool = False

    def allowed(self) -> str:
        """The allowed argument count as text."""
        if self.high == self.low:
            return str(self.low)
        return f"{self.low} or more" if self.high is None else f"{self.low}..{self.high}"

    def accepts(self, count: int) -> bool:
        """Does the command take ``count`` arguments?"""
        return count >= self.low and (self.high is None or count <= self.high)


def _sigs(*rows: tuple[str, int, int | None, str] | tuple[str, int, int | None, str, bool]) -> dict[str, Signature]:
    return {row[0]: Signature(*row) for row in rows}


#: Commands used as statements (``NAME(args)``, a bare ``NAME`` or ``NAME "text", args``), modelled.
COMMANDS: dict[str, Signature] = _sigs(
    ("BASE", 1, None, "BASE(axis, axis, ...)"),
    ("TABLE", 2, None, "TABLE(start, value, value, ...)"),
    ("PWM_CONTROL", 1, 5, "PWM_CONTROL(mode, ...)", True),
    ("DEFPOS", 1, None, "DEFPOS(position, ...)", True),
    ("MOVE", 1, None, "MOVE(distance, ...)", True),
    ("MOVEABS", 1, None, "MOVEABS(position, ...)", True),
    ("MOVECIRC", 5, 5, "MOVECIRC(end1, end2, centre1, centre2, direction)"),
    ("MOVEMODIFY", 1, 1, "MOVEMODIFY(position)", True),
    ("FORWARD", 0, 0, "FORWARD", True),
    ("REVERSE", 0, 0, "REVERSE", True),
    ("CANCEL", 0, 1, "CANCEL or CANCEL(1)", True),
    ("RAPIDSTOP", 0, 1, "RAPIDSTOP"),
    ("DATUM", 1, 1, "DATUM(sequence 0..6)", True),
    ("CONNECT", 2, 2, "CONNECT(ratio, driving axis)", True),
    ("CAMBOX", 5, 7, "CAMBOX(start, end, table multiplier, link distance, link axis[, link option[, link pos]])",
     True),
    ("CAM", 4, 4, "CAM(start, end, table multiplier, distance)", True),
    ("MOVELINK", 5, 7, "MOVELINK(distance, link dist, link acc, link dec, link axis[, link option[, link pos]])",
     True),
    ("REGIST", 1, 5, "REGIST(mode)", True),
    ("TRIGGER", 0, 0, "TRIGGER"),
    ("WA", 1, 1, "WA(ms)"),
    ("OP", 1, 2, "OP(output, ON/OFF) or OP(bit pattern)"),
    ("RUN", 1, 2, "RUN \"program\"[, process]"),
    ("STOP", 0, 2, "STOP or STOP \"program\"[, process]"),
    ("HALT", 0, 0, "HALT"),
    ("PROCESS", 0, 0, "PROCESS"),
    ("CLEAR", 0, 0, "CLEAR"),
    ("CLEAR_BIT", 2, 2, "CLEAR_BIT(bit, vr)"),
    ("SET_BIT", 2, 2, "SET_BIT(bit, vr)"),
    ("FLAG", 1, 2, "FLAG(flag, ON/OFF)"),
    ("FLAGS", 1, 1, "FLAGS(value) (FLAGS alone reads them)"),
    ("INVERT_IN", 2, 2, "INVERT_IN(input, ON/OFF)"),
    ("ENCODER_RATIO", 2, 2, "ENCODER_RATIO(denominator, numerator)", True),
    ("STEP_RATIO", 2, 2, "STEP_RATIO(denominator, numerator)", True),
)

#: Commands the model accepts and lists as "set, not modelled" (communications, set-up, tools).
SETTINGS: dict[str, Signature] = _sigs(
    ("SETCOM", 5, 7, "SETCOM(baud rate, data bits, stop bits, parity, port[, mode[, variable]])"),
    ("OPEN", 1, None, "OPEN #channel ..."),
    ("CLOSE", 0, None, "CLOSE #channel"),
    ("SCOPE", 0, None, "SCOPE(ON/OFF, period, table start, table end, parameters...)"),
    ("AUTORUN", 0, 0, "AUTORUN"),
    ("DEFKEY", 1, None, "DEFKEY(...)"),
    ("CURSOR", 1, 1, "CURSOR(position)"),
    ("EPROM", 0, 0, "EPROM"),
    ("COMPILE", 0, 0, "COMPILE"),
    ("SELECT", 0, 1, "SELECT \"program\""),
    ("LIST", 0, 1, "LIST"),
    ("NEW", 0, 1, "NEW \"program\""),
    ("DEL", 0, 1, "DEL \"program\""),
    ("COPY", 0, 2, "COPY \"program\" \"new name\""),
    ("RENAME", 0, 2, "RENAME \"program\" \"new name\""),
    ("LOCK", 0, 1, "LOCK(code)"),
    ("UNLOCK", 0, 1, "UNLOCK(code)"),
    ("STORE", 0, 0, "STORE"),
    ("EXECUTE", 1, None, "EXECUTE \"command\""),
    ("INITIALISE", 0, 0, "INITIALISE"),
    ("DIR", 0, 0, "DIR"),
    ("ENABLE_OP", 1, 1, "ENABLE_OP(mask)"),
    ("PSWITCH", 1, 7, "PSWITCH(switch, enable[, axis, output, state, set position, reset position])"),
    ("READPACKET", 1, None, "READPACKET(...)"),
    ("CHANNEL_WRITE", 1, None, "CHANNEL_WRITE(...)"),
    ("CHANNEL_READ", 1, None, "CHANNEL_READ(channel, ...)"),
    ("FILE", 0, None, "FILE ..."),
    ("AOUT", 1, 2, "AOUT(channel, value)"),
    ("DISABLE_GROUP", 1, None, "DISABLE_GROUP(axis, ...)"),
    ("LOOKUP", 2, 2, "LOOKUP(format, entry)"),
    ("STEPLINE", 0, 2, "STEPLINE"),
    ("TROFF", 0, 1, "TROFF"),
    ("TRON", 0, 0, "TRON"),
    ("SEND", 1, None, "SEND(...)"),
)

#: Commands of the manual without a model here that move axes or switch outputs over time: accepted, and an
#: error naming the command when reached (a motion or an output pulse the model would not make must not pass
#: quietly).
MOTION_NOT_MODELLED: dict[str, Signature] = _sigs(
    ("MHELICAL", 6, 8, "MHELICAL(end1, end2, centre1, centre2, direction, distance3[, ...])", True),
    ("MHELICALSP", 6, 8, "MHELICALSP(...)", True),
    ("MSPHERICAL", 5, 6, "MSPHERICAL(...)", True),
    ("MOVETANG", 1, 2, "MOVETANG(position)", True),
    ("MOVESP", 1, None, "MOVESP(distance, ...)", True),
    ("MOVEABSSP", 1, None, "MOVEABSSP(position, ...)", True),
    ("MOVECIRCSP", 5, 5, "MOVECIRCSP(...)", True),
    ("ADDAX", 1, 1, "ADDAX(axis)", True),
    ("ADD_DAC", 1, 1, "ADD_DAC(axis)", True),
    ("B_SPLINE", 4, 6, "B_SPLINE(...)", True),
    ("BACKLASH", 4, 4, "BACKLASH(on/off, distance, speed, accel)", True),
    ("ACC", 1, 1, "ACC(rate) (use ACCEL)", True),
    ("DEC", 1, 1, "DEC(rate) (use DECEL)", True),
    ("DLINK", 1, None, "DLINK(function, ...) (later firmware)", True),
    ("TIMER", 4, 5, "TIMER(timer, output, pattern, time[, option])"),
    ("RECORD", 1, None, "RECORD(...) (registration recording, later firmware)", True),
    ("MATCH", 1, None, "MATCH(...) (registration matching, later firmware)", True),
)

#: Functions used in expressions (``NAME(args)``).
FUNCTIONS: dict[str, Signature] = _sigs(
    ("TABLE", 1, 1, "TABLE(n)"),
    ("VR", 1, 1, "VR(n)"),
    ("ABS", 1, 1, "ABS(x)"),
    ("INT", 1, 1, "INT(x)"),
    ("FRAC", 1, 1, "FRAC(x)"),
    ("SGN", 1, 1, "SGN(x)"),
    ("SQR", 1, 1, "SQR(x)"),
    ("SIN", 1, 1, "SIN(radians)"),
    ("COS", 1, 1, "COS(radians)"),
    ("TAN", 1, 1, "TAN(radians)"),
    ("ATAN", 1, 1, "ATAN(x)"),
    ("ATAN2", 2, 2, "ATAN2(y, x)"),
    ("ASIN", 1, 1, "ASIN(x)"),
    ("ACOS", 1, 1, "ACOS(x)"),
    ("EXP", 1, 1, "EXP(x)"),
    ("LN", 1, 1, "LN(x)"),
    ("IN", 0, 2, "IN(input) or IN(first, last)"),
    ("READ_OP", 1, 2, "READ_OP(output) or READ_OP(first, last)"),
    ("OP", 1, 1, "OP(output)"),
    ("KEY", 0, 0, "KEY or KEY #channel"),
    ("READ_BIT", 2, 2, "READ_BIT(bit, vr)"),
    ("FLAG", 1, 1, "FLAG(flag)"),
    ("CHR", 1, 1, "CHR(code)"),
    ("HEX", 1, 1, "HEX(value)"),
    ("STR", 1, 2, "STR(value[, width])"),
    ("VAL", 1, 1, "VAL(string)"),
    ("LEN", 1, 1, "LEN(string)"),
    ("LEFT", 2, 2, "LEFT(string, count)"),
    ("RIGHT", 2, 2, "RIGHT(string, count)"),
    ("MID", 2, 3, "MID(string, start[, count])"),
    ("UCASE", 1, 1, "UCASE(string)"),
    ("LCASE", 1, 1, "LCASE(string)"),
    ("INSTR", 2, 3, "INSTR([start, ]string, search)"),
    ("AIN", 1, 1, "AIN(channel)"),
    ("MOTION_ERROR", 0, 0, "MOTION_ERROR"),
    ("FLAGS", 0, 0, "FLAGS (all 32 flags as a number)"),
    ("IEEE_IN", 4, 4, "IEEE_IN(byte0, byte1, byte2, byte3)"),
    ("IEEE_OUT", 2, 2, "IEEE_OUT(value, byte 0..3)"),
    # the inputs as numbers and the analogue channels by name (TRM 8-93, 8-103)
    ("INPUTS0", 0, 0, "INPUTS0 (inputs 0..15 as a number)"),
    ("INPUTS1", 0, 0, "INPUTS1 (inputs 16..31 as a number)"),
    *((f"AIN{n}", 0, 0, f"AIN{n} (the same as AIN({n}))") for n in range(4)),
    *((f"AINBI{n}", 0, 0, f"AINBI{n} (analogue input {n}, bipolar)") for n in range(4)),
)

#: Process parameters (``NAME`` or ``NAME PROC(n)``).
PROCESS_PARAMS: dict[str, str] = {
    "TICKS": "process counter, decremented every servo cycle (read/write)",
    "PROC_STATUS": "0 stopped, 1 running, 2 stepping, 3 paused (read only)",
    "PROCNUMBER": "the process the program runs on (read only)",
    "ERROR_LINE": "the line of the last run-time error (read only)",
    "RUN_ERROR": "the number of the last run-time error (read only)",
    "INDEVICE": "the channel INPUT and GET read by default",
    "OUTDEVICE": "the channel PRINT writes to by default",
    "PMOVE": "TRUE while a move of the process waits for the axes' buffers (read only)",
}
PROCESS_WRITABLE = frozenset({"TICKS", "INDEVICE", "OUTDEVICE"})

#: System parameters besides :data:`SYSTEM_PARAMS` that are stored and listed as not modelled.
SYSTEM_STORED: dict[str, int] = {"SCOPE_POS": 0, "LAST_AXIS": 3, "POS_OFFSET": 0, "NEG_OFFSET": 0,
                                 "ERROR_AXIS": -1, "SYSTEM_ERROR": 0, "VERSION": 0, "FREE": 47104,
                                 "NIO": 32, "TSIZE": 16000, "CONTROL": 205, "D_ZONE": 0, "BATTERY_LOW": 0,
                                 "AOUT0": 0, "AOUT1": 0, "AOUT2": 0, "AOUT3": 0, "DISPLAY": 0, "FRAME": 0,
                                 "POWER_UP": 0, "TIME": 0, "DATE": 0, "DAY": 0, "ADDRESS": 0, "LIMIT_BUFFERED": 1,
                                 "CHECKSUM": 0, "COMMSERROR": 0, "COMMSTYPE": 0}
#: Stored system parameters a program may write (``AOUT0 = 1000``: the analogue outputs, TRM 8-93; the
#: display, the frame, the power-up mode, the clock, the network address, the buffered limit).
SYSTEM_WRITABLE = frozenset({"AOUT0", "AOUT1", "AOUT2", "AOUT3", "DISPLAY", "FRAME", "POWER_UP", "TIME", "DATE",
                             "DAY", "ADDRESS", "LIMIT_BUFFERED"})
#: Functions of a channel (``KEY #1``).
CHANNEL_FUNCTIONS = frozenset({"KEY"})

#: Names a program can read as values.
CONSTANTS: dict[str, int] = {"ON": ON, "OFF": OFF, "TRUE": TRUE, "FALSE": FALSE}
READABLE = (frozenset(AXIS_PARAMS) | frozenset(READ_ONLY_AXIS_PARAMS) | frozenset(SYSTEM_PARAMS)
            | frozenset(PROCESS_PARAMS) | frozenset(SYSTEM_STORED) | {"PI"})
WRITABLE = frozenset(AXIS_PARAMS) | {"WDOG"} | PROCESS_WRITABLE | {"OFFPOS"} | SYSTEM_WRITABLE

#: Words of the grammar itself.
STATEMENT_WORDS = frozenset({"AXIS", "PROC", "WAIT", "IDLE", "LOADED", "UNTIL", "REPEAT", "WHILE", "WEND", "FOR",
                             "TO", "STEP", "NEXT", "IF", "THEN", "ELSE", "ELSEIF", "ENDIF", "GOTO", "GOSUB",
                             "RETURN", "PRINT", "INPUT", "GET", "LINPUT", "DIM", "AS", "CONSTANT", "GLOBAL",
                             "INCLUDE", "BASICERROR", "AND", "OR", "XOR", "NOT", "MOD", "REM"})
#: Types of ``DIM ... AS``.
TYPES = ("INTEGER", "FLOAT", "BOOLEAN", "STRING")

ALL_COMMANDS: dict[str, Signature] = {**SETTINGS, **MOTION_NOT_MODELLED, **COMMANDS}
KEYWORDS = (frozenset(ALL_COMMANDS) | frozenset(FUNCTIONS) | READABLE | frozenset(CONSTANTS) | STATEMENT_WORDS
            | {"WDOG"})


#: What a word of the grammar is, for a message when it stands where it cannot (``x = PROC``, ``MOD(7, 2)``).
GRAMMAR_WORDS: dict[str, str] = {
    "AXIS": "a modifier: write AXIS(n) after an axis command or parameter (MOVE(10) AXIS(2), UNITS AXIS(2) = 50)",
    "PROC": "a modifier: write PROC(n) after a process parameter or command (TICKS PROC(2), PROC_STATUS PROC(3))",
    "MOD": "an operator: write a MOD b (17 MOD 5 is 2)",
    "AND": "an operator: write a AND b", "OR": "an operator: write a OR b", "XOR": "an operator: write a XOR b",
    "NOT": "an operator: write NOT a",
    **dict.fromkeys(("IF", "THEN", "ELSE", "ELSEIF", "ENDIF"), "a word of IF condition THEN ... [ELSE ...] ENDIF"),
    **dict.fromkeys(("FOR", "TO", "STEP", "NEXT"), "a word of FOR v = a TO b [STEP c] ... NEXT v"),
    **dict.fromkeys(("WHILE", "WEND"), "a word of WHILE condition ... WEND"),
    "REPEAT": "a word of REPEAT ... UNTIL condition",
    "UNTIL": "a word of REPEAT ... UNTIL condition and WAIT UNTIL condition",
    "WAIT": "a statement: WAIT IDLE, WAIT LOADED or WAIT UNTIL condition",
    "IDLE": "a word of WAIT IDLE (or a parameter read in an expression: IDLE AXIS(n))",
    "LOADED": "a word of WAIT LOADED (or a parameter read in an expression: LOADED AXIS(n))",
    **dict.fromkeys(("GOTO", "GOSUB"), "a statement: GOTO label / GOSUB label"),
    "RETURN": "a statement: RETURN ends a GOSUB",
    **dict.fromkeys(("PRINT", "INPUT", "GET", "LINPUT"), "a statement (PRINT [#channel,] items; INPUT [#channel,] "
                                                         "variable; GET [#channel,] variable), not a value"),
    **dict.fromkeys(("DIM", "AS"), "a word of DIM name[(size)] [AS type]"),
    "CONSTANT": "a statement: CONSTANT \"name\", value",
    "GLOBAL": "a statement: GLOBAL \"name\", vr index",
    "INCLUDE": "a statement: INCLUDE \"program\"",
    "BASICERROR": "a word of ON BASICERROR GOTO label",
    "REM": "a comment: REM text",
}


_CLOSES = {"ENDIF": "IF", "NEXT": "FOR", "WEND": "WHILE", "UNTIL": "REPEAT"}
_AS_WHAT = {"command": "a command", "channel": "a command", "function": "a function", "value": "a value",
            "assignment": "the target of an assignment"}


def misplaced(name: str, where: str) -> str | None:
    """Message for a keyword standing where it cannot (``where``: command, function, value, assignment), if it is one.

    Examples
    --------
    >>> misplaced("MOD", "value")
    'MOD is an operator: write a MOD b (17 MOD 5 is 2); it cannot stand as a value'
    """
    upper = name.upper()
    opener = _CLOSES.get(upper)
    if opener is not None and where in ("command", "channel"):
        article = "an" if opener == "IF" else "a"
        return f"{upper} closes {article} {opener} block, but no {opener} block is open here"
    if upper in GRAMMAR_WORDS:
        return f"{upper} is {GRAMMAR_WORDS[upper]}; it cannot stand as {_AS_WHAT.get(where, where)}"
    if where in ("command", "channel") and upper in READABLE:
        if upper in WRITABLE:
            return f"{upper} is a parameter; write {upper} = value (a parameter is not a command)"
        return f"{upper} is a read-only parameter; read it in an expression (x = {upper})"
    if where in ("command", "channel") and upper in FUNCTIONS:
        return f"{upper}(...) is a function, not a command; use it in an expression"
    if where == "assignment" and (upper in ALL_COMMANDS or upper in FUNCTIONS):
        kind = "a command" if upper in ALL_COMMANDS else "a function"
        usage = (ALL_COMMANDS.get(upper) or FUNCTIONS[upper]).usage
        return f"{upper} is {kind}, not a parameter: write {usage}"
    return None


def _close(name: str, known: frozenset[str] | list[str]) -> str:
    close = [c for c in difflib.get_close_matches(name.upper(), sorted(known), n=4) if c != name.upper()][:3]
    return f"; did you mean {', '.join(close)}?" if close else ""


def unknown_command(name: str) -> str:
    """Message for a statement keyword the model does not know (with close matches)."""
    return f"unknown keyword {name}{_close(name, KEYWORDS)} (not a Trio BASIC command; see docs/trio.md)"


def unknown_function(name: str) -> str:
    """Message for a function the model does not know."""
    return f"unknown keyword {name}{_close(name, KEYWORDS)} (not a Trio BASIC function; see docs/trio.md)"


def unknown_name(name: str) -> str:
    """Message for a name that is neither a keyword nor a variable the program assigns."""
    return f"unknown keyword {name}{_close(name, KEYWORDS)}"


def misspelt_parameter(name: str) -> str | None:
    """The writable parameter ``name`` differs from by one letter (inserted, missing or replaced), if any.

    A variable that is assigned and never read under such a name is almost always a misspelt
    parameter (``UNIT = 16``); the controller would create it silently.

    Examples
    --------
    >>> misspelt_parameter("UNIT"), misspelt_parameter("SPEED1"), misspelt_parameter("I")
    ('UNITS', None, None)
    """
    upper = name.upper()
    if not upper.isalpha() and not upper.replace("_", "").isalpha():
        return None
    for known in sorted(AXIS_PARAMS):
        if abs(len(known) - len(upper)) > 1 or known == upper:
            continue
        if _one_letter_apart(upper, known):
            return known
    return None


def _one_letter_apart(a: str, b: str) -> bool:
    if len(a) == len(b):
        diff = [(x, y) for x, y in zip(a, b, strict=True) if x != y]
        return len(diff) == 1 and diff[0][0].isalpha() and diff[0][1].isalpha()
    short, long = (a, b) if len(a) < len(b) else (b, a)
    for k in range(len(long)):
        if long[:k] + long[k + 1:] == short:
            return long[k].isalpha()
    return False


def wrong_count(signature: Signature, count: int) -> str:
    """Message for a call with the wrong number of arguments (the allowed count and the usage)."""
    return (f"number of {signature.name} arguments = {count} is not allowed (allowed: {signature.allowed()}: "
            f"{signature.usage})")
