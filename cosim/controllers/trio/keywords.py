"""The vocabulary of the modelled Trio BASIC: commands, functions, names, and what each takes.

Every keyword a program may use is listed here with the number of arguments it takes, so a
program with an unknown keyword or a wrong argument count is refused before it runs, with the
allowed keywords or counts in the message.
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


#: Commands used as statements (``NAME(args)`` or a bare ``NAME``).
COMMANDS: dict[str, Signature] = {s.name: s for s in (
    Signature("BASE", 1, None, "BASE(axis, axis, ...)"),
    Signature("TABLE", 2, None, "TABLE(start, value, value, ...)"),
    Signature("PWM_CONTROL", 1, 5, "PWM_CONTROL(mode, ...)", True),
    Signature("DEFPOS", 1, None, "DEFPOS(position, ...)", True),
    Signature("MOVE", 1, None, "MOVE(distance, ...)", True),
    Signature("MOVEABS", 1, None, "MOVEABS(position, ...)", True),
    Signature("MOVECIRC", 5, 5, "MOVECIRC(end1, end2, centre1, centre2, direction)"),
    Signature("FORWARD", 0, 0, "FORWARD", True),
    Signature("REVERSE", 0, 0, "REVERSE", True),
    Signature("CANCEL", 0, 0, "CANCEL", True),
    Signature("WA", 1, 1, "WA(ms)"),
    Signature("OP", 2, 2, "OP(output, ON/OFF)"),
)}

#: Functions used in expressions (``NAME(args)``).
FUNCTIONS: dict[str, Signature] = {s.name: s for s in (
    Signature("TABLE", 1, 1, "TABLE(n)"),
    Signature("VR", 1, 1, "VR(n)"),
    Signature("ABS", 1, 1, "ABS(x)"),
    Signature("INT", 1, 1, "INT(x)"),
    Signature("SGN", 1, 1, "SGN(x)"),
    Signature("SQR", 1, 1, "SQR(x)"),
    Signature("IN", 1, 1, "IN(input)"),
    Signature("READ_OP", 1, 1, "READ_OP(output)"),
    Signature("OP", 1, 1, "OP(output)"),
)}

#: Names a program can read in expressions (parameters, constants, process parameters).
CONSTANTS: dict[str, int] = {"ON": ON, "OFF": OFF, "TRUE": TRUE, "FALSE": FALSE}
PROCESS_PARAMS: dict[str, str] = {"TICKS": "process counter, decremented every servo cycle (read/write)"}
READABLE = frozenset(AXIS_PARAMS) | frozenset(READ_ONLY_AXIS_PARAMS) | frozenset(SYSTEM_PARAMS) | frozenset(
    PROCESS_PARAMS)
WRITABLE = frozenset(AXIS_PARAMS) | {"WDOG"} | frozenset(PROCESS_PARAMS)

#: Words of the grammar itself.
STATEMENT_WORDS = frozenset({"AXIS", "WAIT", "IDLE", "LOADED", "UNTIL", "REPEAT", "WHILE", "WEND", "FOR", "TO",
                             "STEP", "NEXT", "IF", "THEN", "ELSE", "ELSEIF", "ENDIF", "GOTO", "GOSUB", "RETURN",
                             "PRINT", "RUN", "AND", "OR", "XOR", "NOT", "MOD", "REM"})

#: Trio keywords the model refuses on purpose, with the reason.
NOT_MODELLED: dict[str, str] = {
    "DATUM": "its datum sequences (the DATUM_IN input, CREEP speed, which switch edge zeroes the position) are "
             "not in the facts at hand; home with REVERSE, WAIT UNTIL IN(n) = ON, CANCEL, WAIT IDLE, DEFPOS(0)",
    "MERGE": "moves run rest to rest in this model",
    "STOP": "a program ends at its last line; STOP of another program is not modelled",
}

KEYWORDS = frozenset(COMMANDS) | frozenset(FUNCTIONS) | READABLE | frozenset(CONSTANTS) | STATEMENT_WORDS | {
    "WDOG"}


def _close(name: str, known: frozenset[str] | list[str]) -> str:
    close = difflib.get_close_matches(name.upper(), sorted(known), n=3)
    return f"; did you mean {', '.join(close)}?" if close else ""


def unknown_command(name: str) -> str:
    """Message for a statement keyword the model does not know (close matches and the supported commands)."""
    upper = name.upper()
    if upper in NOT_MODELLED:
        return f"{upper} is not modelled: {NOT_MODELLED[upper]}"
    return (f"unknown keyword {name}{_close(name, KEYWORDS)} (supported commands: "
            f"{', '.join(sorted(COMMANDS))}; see docs/trio.md)")


def unknown_function(name: str) -> str:
    """Message for a function the model does not know."""
    return f"unknown keyword {name}{_close(name, KEYWORDS)} (supported functions: {', '.join(sorted(FUNCTIONS))})"


def unknown_name(name: str) -> str:
    """Message for a name that is neither a keyword nor a variable the program assigns."""
    return f"unknown keyword {name}{_close(name, KEYWORDS)}"


def wrong_count(signature: Signature, count: int) -> str:
    """Message for a call with the wrong number of arguments (the allowed count and the usage)."""
    return (f"number of {signature.name} arguments = {count} is not allowed (allowed: {signature.allowed()}: "
            f"{signature.usage})")
