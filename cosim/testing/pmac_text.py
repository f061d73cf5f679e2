"""Fuzz inputs for the PMAC text parsers: generated token soups and mutations of real PMAC files.

Used by ``tests/test_pmac_fuzz.py`` (a few hundred inputs per run) and ``bench/bench_pmac_fuzz.py``
(millions). :func:`feed` gives one text to every reader of PMAC text -- the download preprocessor,
``parse_setup``, ``parse_text``, ``Pmac.load`` and a line of online commands -- and to a short run when it loads,
and returns the name of the first that raised something other than the project's own errors.
"""

from __future__ import annotations

import random
from collections.abc import Callable

from cosim.controllers.pmac import Pmac
from cosim.controllers.pmac.preprocess import preprocess
from cosim.controllers.pmac.program import parse_text
from cosim.controllers.pmac.setupfile import parse_setup
from cosim.errors import CosimError
from cosim.kernel import Simulation

#: Words and pieces of PMAC text, right and wrong.
TOKENS = (
    "I10", "I8000", "I8001", "I8008", "I8009", "I5193", "I5194", "I5195", "I5187", "I5188", "I5189", "I122", "I120",
    "I7000", "I130", "P1", "P8191", "P8192", "M103", "M1", "M8000", "Q1", "=", "==", "->", "X:", "Y:", "$07800B",
    "$078008", "$3501", "$AF8018", "$9F8018", "$BF8018", "$FFFFFFFFFFFFFF", "@I8002", "@I10", ",0,24,S", ",20,4",
    ",U", "*", "&1", "&9", "#1", "#1->1000X", "#2->-2.5Y", "OPEN", "PROG", "PLC", "1", "0", "31", "32", "CLEAR",
    "CLOSE", "LINEAR", "RAPID", "ABS", "INC", "F64000", "F", "TA20", "TS10", "TM", "X", "Y", "Z", "A", "B", "C",
    "U", "V", "W", "X1000", "Y(P1+2)", "DWELL", "DWELL0", "DELAY", "IF", "ELSE", "ENDIF", "ENDI", "WHILE", "ENDWHILE",
    "ENDW", "GOTO", "GOSUB", "CALL", "RETURN", "N10", "O5", "CMD", '"&1B1R"', '"', "ENABLE", "DISABLE", "B1", "R",
    "H", "%50", "%", "(", ")", "((", "))", "+", "-", "*", "/", "&", "|", "^", "!=", "<>", "!>", "!<", ">", "<",
    ">=", "<=", "AND", "OR", "ABS(", "INT(", "1e5", "1.5", ".5", "99999999999999999", "0.000000000000000000001",
    "3713707", "8388607", "8388608", "-1", "nan", "inf", "Infinity", "sNaN", ";", "; comment", "\ufeff", "é",
    "/0", "%0", "P1=P2/P3", "P1=P1*P1*P1", "ENABLE PLC 1", "&1B1R", "M1->*", "M1=1/3", "GOSUB10", "WHILE(1=1)",
    # the whole language (issue 27): preprocessor, variables, kinematics, program commands, online commands
    "#define", "#define N 5", "#define X P1+", "#undefine", "#undef N", "#include", '#include "x.pmc"', "#ifdef",
    "#ifndef N", "#else", "#endif", "#pragma", "####", "$(PLC)", "$(", "$()", "//", "/*", "*/", "N", "Q(", "P(",
    "M(", "I(", "Q7", "Q8191", "Q8192", "I5111", "I5212", "I5150=1", "I5250", "I5113=10", "I7000", "I7012,4,10=1",
    "I100..131=0", "I5213,15,100=10", "I130=*", "I100..131=*", "M0..8191->*", "M1->D:$8B", "M2->L:$6000",
    "M3->DP:$60000", "M4->F:$60001", "M5->TWS:1", "M6->", "#1->I", "#2->0", "#3->500X+300Y+100", "#1->", "&16",
    "&17", "UNDEFINE", "UNDEFINE ALL", "OPEN FORWARD", "OPEN INVERSE", "OPEN FORWARD 2 CLEAR", "OPEN ROTARY",
    "OPEN PLC 1 CLEAR P1=1 CLOSE", "CLOSE ALL", "CLEAR ALL", "CIRCLE1", "CIRCLE2", "NORMAL K-1", "I10 J0", "R5",
    "R-5", "PVT50", "X10:50", "SPLINE1", "TM50", "X10^5", "ABS(X,Y)", "INC(Z)", "HOME1", "HOMEZ", "#1HMZ", "#1J+",
    "#1J=100", "#1J/", "#1O10", "PMATCH", "FRAX(X,Y)", "NOFRAX", "AND (P1=1)", "OR (P2=2)", "CMD^A", "COMMAND\"R\"",
    "CMD\"&2B2R\"", "^A", "^D", "^K", "SEND1\"HI\"", "DISPLAY 0 \"X\"", "DISPLAY 40,8.3,P1", "ADDRESS &2 #3",
    "ENABLE PLC 2..31", "DISABLE PLCC 0..31", "PAUSE PLC 1", "RESUME PLC 1", "DEFINE GATHER", "GATHER", "ENDGATHER",
    "END GATHER", "DELETE GATHER", "MS0,MI910=$F", "MSR0,MI920,P1", "LIST PROG 1", "$$$", "???", "G01", "M03", "T1",
    "D01", "CALL 10.5", "CALL 5 X10", "GOTO(P1)", "GOSUB(P2+1)", "SIN(30)", "ATAN2(1)", "SQRT(-1)", "LN(0)",
    "EXP(100)", "ACOS(2)", "342", "STOP", "WAIT", "CC1", "BLOCKSTART", "LOCK4,P10", "READ(X,Y)",
    # after the review of the language front end: bit operators, approximate comparators, ports, the rotary buffer
    "P1=P2&3", "IF(M1&4>0)", "P1=3&1", "0.875&-1.75", "~", "!~", "IF (P1~P2)", "##", "##1", "@0", "@", "#1J!",
    "#1J=*", "#1J^*", "CMDS\"P1\"", "CMDR^A", "SENDR\"X\"", "SEND^@", "NX1", "TZ1", "I5=2", "I5=0", "&1 B0",
    "OPEN ROT", "OPEN ROTARY 5", "&1 X10 Y10 F5",
)
#: Separators, every line end among them.
SEPARATORS = (" ", " ", " ", "", "\n", "\n", "\r\n", "\r", "\t", "\x0b", "\x0c", "\x1c", "\x85", "\u2028", "\x00")

#: Real PMAC text to mutate.
CORPUS = (
    "CLOSE\nI10=3713707\nI8008=$AF8018\nI8009=64\nI5193=@I8009\nI5194=8388607\nM103->X:$07801B,0,24,S\n"
    "&1 #1->100X\n",
    "OPEN PROG 1 CLEAR\nLINEAR ABS\nTA20 TS0 F640\nDWELL 0\nI8008=$9F8018\nP103=M103\nX20\nX0\nCLOSE\n",
    "OPEN PLC 1 CLEAR\nIF (I8008=$9F8018)\n  I8008=$BF8018\nENDIF\nCLOSE\n",
    "I8000=$078000 I8001=$403501 I8002=2048 I5193=@I8002 I5194=8388607\n&1 #1->1X #2->10Y\n"
    "OPEN PROG 2 CLEAR\nLINEAR INC TA10 TS5 F(P1*2) X(P2+1) Y-3\nN10 P1=P1+1\nIF (P1<3 AND P2!=1) GOTO10\n"
    "WHILE (P3 < 2) P3=P3+1\nRAPID X1 DELAY 5 TM100 X2\nCALL 2\nRETURN\nCLOSE\nENABLE PLC 0\n",
    "OPEN PLC 0 CLEAR\nP1=P1+1 IF (P1=3) CMD\"&1 B2 R\" ELSE P2=ABS(-P1)/INT(2.5)%3&1|2^4\nCLOSE\n",
    "OPEN PLC 1 CLEAR\nP1=P1+1\nP4=P1/(P1-2) P5=P4%(P1-3) P6=P6*2+1\nN10 IF (P1>5) GOSUB10\nCLOSE\n"
    "ENABLE PLC 1\n",
    # a project's file: preprocessor, template macros, I-variable ranges, kinematics, PLCs with timers and CMD
    "#define TICKS P50\n#define TIMER I5111\n#define ANGLE 30\nI100,4,100=1 I130,4,100=2000 I5150=1 I5113=5\n"
    "&1 #1->I #2->I\nOPEN FORWARD 1 CLEAR\nQ7=(P1*COS(ANGLE)-P2*SIN(ANGLE))/1000\nQ8=P2/1000\nCLOSE\n"
    "OPEN INVERSE 1 CLEAR\nP1=Q7*1000\nP2=(Q7+Q8)*1000\nCLOSE\nOPEN PROG 1 CLEAR\nLINEAR ABS TA10 TS5 F(Q20+100)\n"
    "P10=0\nWHILE (P10<2)\nX(P(200+P10)) Y(Q(P10))\nP10=P10+1\nENDWHILE\nCIRCLE1 X0 Y0 R5\nPVT20 X1:0\nCLOSE\n"
    "OPEN PLC $(PLC) CLEAR\nIF (TIMER<0)\nAND (TICKS<3)\nTICKS=TICKS+1 SEND1\"TICK\" TIMER=100\nENDIF\nCLOSE\n"
    "ENABLE PLC 1\n",
    "I5=3\nM0..8191->*\nM103->X:$07800B,0,24,S M162->D:$8B\nUNDEFINE ALL\n&1 #1->1000X #2->500X+500Y\n"
    "OPEN PROG 1 CLEAR\nSPLINE1 TM20\nX1 Y2\nX2 Y3\nRAPID X0\nHOME1 FRAX(X,Y)\nCMD^A\nCLOSE\n"
    "OPEN PLC 1 CLEAR ADDRESS &1 IF (M1=0) CMD\"&1B1R\" DISABLE PLC 1..2 CLOSE\nDEFINE GATHER\nMS0,MI910=1\n",
)


def generate(rng: random.Random, *, max_tokens: int = 40) -> str:
    """A soup of tokens and separators (with an occasional random character)."""
    parts: list[str] = []
    for _ in range(rng.randrange(max_tokens + 1)):
        parts.append(rng.choice(TOKENS) if rng.random() < 0.9 else chr(rng.randrange(1, 0x2100)))
        parts.append(rng.choice(SEPARATORS))
    return "".join(parts)


def mutate(text: str, rng: random.Random, *, edits: int = 4) -> str:
    """``text`` with a few random edits: characters or tokens inserted, deleted, replaced; lines duplicated."""
    chars = list(text)
    for _ in range(rng.randrange(1, edits + 1)):
        at = rng.randrange(len(chars) + 1)
        kind = rng.randrange(6)
        if kind == 0 and chars:
            del chars[min(at, len(chars) - 1)]
        elif kind == 1:
            chars[at:at] = list(rng.choice(TOKENS))
        elif kind == 2 and chars:
            chars[min(at, len(chars) - 1)] = chr(rng.randrange(1, 0x250))
        elif kind == 3:
            chars[at:at] = list(rng.choice(SEPARATORS))
        elif kind == 4:
            lines = "".join(chars).split("\n")
            line = rng.choice(lines)
            lines.insert(rng.randrange(len(lines) + 1), line * rng.randrange(1, 4))
            chars = list("\n".join(lines))
        else:
            chars[at:at] = list("(" * rng.randrange(1, 40))
    return "".join(chars)


def draw(rng: random.Random) -> str:
    """One input: generated, a mutated corpus file, or two corpus files joined and mutated."""
    choice = rng.randrange(3)
    if choice == 0:
        return generate(rng)
    if choice == 1:
        return mutate(rng.choice(CORPUS), rng)
    return mutate(rng.choice(CORPUS) + rng.choice(CORPUS), rng, edits=8)


def _load_and_run(text: str) -> None:
    with Simulation() as sim:
        pmac = Pmac(sim)
        pmac.load(text, source="fuzz.pmc", defines={"PLC": "1"})
        pmac.command("&1 B1 R", source="fuzz command")
        pmac.start()
        sim.run(until=sim.ticks("3 ms"))


READERS: dict[str, Callable[[str], object]] = {
    "preprocess": lambda text: preprocess(text, source="fuzz.pmc", defines={"PLC": "1"}),
    "parse_setup": lambda text: parse_setup(text, source="fuzz.pmc"),
    "parse_text": lambda text: parse_text(text, source="fuzz.pmc"),
    "command": lambda text: Pmac(Simulation()).programs.parse_command(text.split("\n", 1)[0], source="fuzz"),
    "load_and_run": _load_and_run,
}


def feed(text: str, *, readers: tuple[str, ...] = tuple(READERS)) -> str | None:
    """Give ``text`` to each reader; the name of the first that raised a non-project error, else None."""
    for name in readers:
        try:
            READERS[name](text)
        except CosimError:
            continue
        except Exception:  # what the fuzzing is looking for: anything that is not our error
            return name
    return None
