"""Random and mutated Trio BASIC programs, for the fuzz test and the long fuzz run (``bench/fuzz_trio_basic.py``).

:func:`generate` writes a program a user might write (statements of the modelled subset with odd numbers,
axes and nesting); :func:`mutate` damages a program's text (characters inserted, deleted or replaced, line ends
of every kind, lines swapped). :func:`exercise` parses a text and, if it parses, runs it for a few simulated
milliseconds; it returns quietly or raises only what is not one of the project's own errors.
"""

from __future__ import annotations

import random

from cosim.controllers.trio import TrioController
from cosim.controllers.trio.basic import BasicProgram
from cosim.errors import CosimError
from cosim.kernel import Simulation

NUMBERS = ["0", "1", "2", "3", "-1", "0.5", ".5", "2.5e1", "1e9", "1e-40", "$FF", "$7FFFFFFF", "65535", "65536",
           "2147483647", "536870911", "1000", "16", "35", "300", "0.001", "7", "255", "100000"]
#: Literals beyond a Trio variable, used rarely (each refuses the whole program).
HUGE = ["3e9", "1e99", "2147483648", "$80000000", "1e99999999"]
PARAMS = ["UNITS", "SPEED", "ACCEL", "DECEL", "ATYPE", "SERVO", "FE_LIMIT", "PWM_CYCLE", "PWM_MARK", "INVERT_STEP",
          "WDOG", "TICKS", "CREEP", "JOGSPEED", "DATUM_IN", "FWD_IN", "REV_IN", "FWD_JOG", "FS_LIMIT", "RS_LIMIT",
          "REP_DIST", "REP_OPTION", "MERGE", "SRAMP", "P_GAIN", "OFFPOS", "OUTDEVICE", "AOUT0", "REGIST_SPEED",
          "ENCODER_RATIO"]
READ_ONLY = ["DPOS", "MPOS", "VP_SPEED", "OFFPOS", "PWM_ENCODER", "FE", "IDLE", "LOADED", "SERVO_PERIOD", "ON",
             "OFF", "TRUE", "FALSE", "AXISSTATUS", "MARK", "REG_POS", "MTYPE", "PROC_STATUS PROC(1)", "PROCNUMBER",
             "RUN_ERROR", "ERROR_LINE", "PI", "KEY", "TOP", "G", "KEY #1", "INPUTS0", "INPUTS1", "AIN0", "FLAGS",
             "TRANS_DPOS", "MARKB"]
VARIABLES = ["a", "b", "x", "i", "n"]
OPERATORS = ["+", "-", "*", "/", "MOD", "AND", "OR", "XOR", "=", "<>", "<", ">", "<=", ">="]
FUNCTIONS = ["ABS", "INT", "SGN", "SQR", "VR", "TABLE", "IN", "READ_OP", "OP", "SIN", "COS", "ATAN", "EXP", "LN",
             "FRAC", "LEN", "VAL", "FLAG", "arr"]
STRINGS = ['"ab"', 'CHR(65)', 'HEX(255)', 'STR(1.5)', 'LEFT("abc", 2)', 'MID("conveyor", 2, 3)', "s", 'UCASE(s)']
ODD = ["\r", "\r\n", "\x0b", "\x0c", "\x85", "\u2028", "\x00", "'", '"', ":", "(", ")", ",", ";", "$", "=", " ",
       "\t", "IF", "THEN", "ENDIF", "NEXT", "WEND", "UNTIL", "GOTO", "GOSUB", "RETURN", "label:", "é", "\ufeff",
       "#", "OPEN #5 AS ", "CLOSE #", " FOR INPUT", "PROC", "MOD("]


def _number(rng: random.Random) -> str:
    roll = rng.random()
    if roll < 0.005:
        return rng.choice(HUGE)
    return rng.choice(NUMBERS) if roll < 0.7 else str(rng.randint(-5, 4000))


def _expr(rng: random.Random, depth: int = 0) -> str:
    roll = rng.random()
    if depth > 3 or roll < 0.3:
        return _number(rng)
    if roll < 0.45:
        return rng.choice(VARIABLES + PARAMS + READ_ONLY)
    if roll < 0.6:
        return f"{rng.choice(FUNCTIONS)}({_expr(rng, depth + 1)})"
    if roll < 0.85:
        return f"{_expr(rng, depth + 1)} {rng.choice(OPERATORS)} {_expr(rng, depth + 1)}"
    if roll < 0.92:
        return f"(NOT {_expr(rng, depth + 1)})"
    return f"({_expr(rng, depth + 1)})"


def _axis(rng: random.Random) -> str:
    return f" AXIS({rng.choice(['0', '1', '2', '3', '4', '-1', 'x'])})" if rng.random() < 0.2 else ""


def _simple(rng: random.Random) -> str:
    e = lambda: _expr(rng)  # noqa: E731 - short local helper
    choices = [
        lambda: f"{rng.choice(VARIABLES)} = {e()}",
        lambda: f"{rng.choice(PARAMS)}{_axis(rng)} = {e()}",
        lambda: f"VR({e()}) = {e()}",
        lambda: f"TABLE({e()}, {e()}, {e()})",
        lambda: f"BASE({rng.choice(['0', '1', '2', '3', '2, 3', '0, 1', '3, 2', '5'])})",
        lambda: f"MOVE({e()}){_axis(rng)}",
        lambda: f"MOVE({e()}, {e()})",
        lambda: f"MOVEABS({e()}){_axis(rng)}",
        lambda: f"MOVECIRC({e()}, {e()}, {e()}, {e()}, {rng.choice(['0', '1', '2'])})",
        lambda: rng.choice(["FORWARD", "REVERSE", "CANCEL", "WAIT IDLE", "WAIT LOADED"]) + _axis(rng),
        lambda: f"WA({e()})",
        lambda: f"OP({e()}, {e()})",
        lambda: f"PRINT {e()}{rng.choice([';', ','])} \"t\"{rng.choice(['', ';', ','])}",
        lambda: f"WAIT UNTIL {e()}",
        lambda: f"PWM_CONTROL({rng.choice(['0', '1', '4', '5', '6'])}){_axis(rng)}",
        lambda: f"PWM_CONTROL(2, {e()}, {e()}, {e()}, {rng.choice(['2', '3', '0'])})",
        lambda: f"PWM_CONTROL(3, {rng.choice(['0', '1'])}, ON, {e()}, {e()})",
        lambda: f"DEFPOS({e()})",
        lambda: "RUN \"F\"",
        lambda: f"GOSUB {rng.choice(['s1', 's2'])}",
        lambda: f"GOTO {rng.choice(['s1', 's2', 'top'])}",
        lambda: f"s = {rng.choice(STRINGS)} + {rng.choice(STRINGS)}",
        lambda: f"arr({e()}) = {e()}",
        lambda: f"PRINT #{rng.choice(['0', '5', '300'])}, {rng.choice(STRINGS)}; {e()}"
                f"[{rng.randint(0, 9)}, {rng.randint(0, 4)}]",
        lambda: f"DATUM({rng.choice(['0', '1', '3', '4', '7'])}){_axis(rng)}",
        lambda: f"CONNECT({e()}, {rng.choice(['0', '1', '3'])}){_axis(rng)}",
        lambda: f"MOVELINK({e()}, {e()}, {e()}, {e()}, {rng.choice(['0', '1', '2'])})",
        lambda: f"CAMBOX(0, 3, {e()}, {e()}, {rng.choice(['0', '1'])})",
        lambda: f"CAM(0, 3, {e()}, {e()})",
        lambda: f"MOVEMODIFY({e()})",
        lambda: f"REGIST({rng.choice(['1', '2', '3', '9'])})",
        lambda: rng.choice(["TRIGGER", "RAPIDSTOP", "CANCEL(1)", "PROCESS", "HALT", "STOP", 'STOP "F"']),
        lambda: f"ON {e()} GOSUB s1, s2",
        lambda: f"GET #{rng.choice(['0', '1'])}, k",
        lambda: f"SETCOM({e()}, 8, 1, 0, 1)",
        lambda: f"FLAG({e()}, ON)",
    ]
    return rng.choice(choices)()


def _block(rng: random.Random, depth: int) -> list[str]:
    lines: list[str] = []
    for _ in range(rng.randint(1, 5)):
        roll = rng.random()
        if depth < 3 and roll < 0.1:
            lines += [f"IF {_expr(rng)} THEN", *_block(rng, depth + 1), "ELSE", *_block(rng, depth + 1), "ENDIF"]
        elif depth < 3 and roll < 0.18:
            var = rng.choice(VARIABLES)
            lines += [f"FOR {var} = {_expr(rng)} TO {_expr(rng)}" + (f" STEP {_number(rng)}" if rng.random() < 0.3
                                                                     else ""), *_block(rng, depth + 1), f"NEXT {var}"]
        elif depth < 3 and roll < 0.24:
            lines += [f"WHILE {_expr(rng)}", *_block(rng, depth + 1), "WA(1)", "WEND"]
        elif depth < 3 and roll < 0.3:
            lines += ["REPEAT", *_block(rng, depth + 1), f"UNTIL {_expr(rng)}"]
        elif roll < 0.36:
            lines.append(f"IF {_expr(rng)} THEN {_simple(rng)}")
        else:
            lines.append(_simple(rng))
    return lines


def generate(rng: random.Random) -> str:
    """A program of the modelled subset, with labels and subroutines, that may or may not be valid."""
    lines = ["top:", 'CONSTANT "top", 3', 'GLOBAL "g", 7', "DIM arr(5), s AS STRING(8), k AS INTEGER",
             "ON BASICERROR GOTO s2" if rng.random() < 0.3 else "k = 0",
             *[f"{v} = {_number(rng)}" for v in VARIABLES], *_block(rng, 0), "GOTO top" if rng.random() < 0.2
             else "WA(1)", "s1:", *_block(rng, 2), "RETURN", "s2:", "RETURN"]
    lines.append(f"PRINT a; b; x; i; n; k; s {rng.choice(['', ';'])}")  # every variable is read
    return "\n".join(f"{line} ' c" if rng.random() < 0.1 else line for line in lines) + "\n"


def mutate(rng: random.Random, text: str) -> str:
    """``text`` with a few random edits."""
    chars = list(text)
    for _ in range(rng.randint(1, 4)):
        roll = rng.random()
        at = rng.randint(0, len(chars))
        if roll < 0.4:
            chars[at:at] = list(rng.choice(ODD) if rng.random() < 0.7 else chr(rng.randint(0, 0x2FFF)))
        elif roll < 0.7 and chars:
            del chars[at:at + rng.randint(1, 6)]
        elif chars:
            lines = "".join(chars).split("\n")
            i, j = rng.randrange(len(lines)), rng.randrange(len(lines))
            lines[i], lines[j] = lines[j], lines[i]
            chars = list("\n".join(lines))
    return "".join(chars)


def exercise(text: str, *, until_ms: int = 30, run: bool = True) -> bool:
    """Parse and compile ``text`` and, if it parses, run it for ``until_ms`` ms with a second program it
    may RUN (``run`` false: parse and compile only).

    Returns True when it parsed. Raises whatever is *not* a :class:`~cosim.errors.CosimError`.
    """
    try:
        program = BasicProgram.parse(text, name="fuzz.bas")
    except CosimError:
        return False
    if not run:
        return True
    sim = Simulation(seed=1)
    try:
        trio = TrioController(sim, encoder_at_atype=0)
        BasicProgram.parse("VR(1) = VR(1) + 1\nWA(2)\n", name="f.bas").install(trio)
        program.start(trio)
        sim.run(until=until_ms * 1_000_000)
    except CosimError:
        pass
    return True
