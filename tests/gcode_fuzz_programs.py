"""Fuzz inputs for the G-code reader: generated programs, mutations of real ones, random text.

Used by ``tests/test_gcode_fuzz.py`` (a few hundred inputs in the suite) and ``bench/fuzz_gcode.py``
(the long run). :func:`exercise` runs one input through the whole front end: parse, interpret
(bounded: an endless loop is refused after ``MAX_LINES`` lines), tool path. Any exception that is
not one of cosim's own errors is a crash.
"""

from __future__ import annotations

import random
from fractions import Fraction
from pathlib import Path

from cosim.controllers.pokeys.gcode import HostSetup, Tool, toolpath
from cosim.controllers.pokeys.gcode.flow import ProgramError, SourceFile, parse_text
from cosim.controllers.pokeys.gcode.interpreter import Interpreter
from cosim.controllers.pokeys.gcodejob import GcodeJob
from cosim.controllers.pokeys.pathplan import HostAxis, PathSettings
from cosim.controllers.pokeys.toolpath import Arc, Line
from cosim.errors import CosimError

ROOT = Path(__file__).resolve().parent.parent
SEEDS = [ROOT / "examples" / "pokeys_router" / "pocket.nc", ROOT / "examples" / "pokeys_cam" / "job.ngc",
         ROOT / "examples" / "pokeys_cam" / "subs" / "pocket.ngc"]
MAX_LINES = 20_000
TOOLS = [Tool(1, z_offset=10, diameter=6), Tool(2, z_offset=20, diameter=3)]
#: Live runs plan a job only if it would take at most this long (by the static tool path's moves) [min].
MAX_MINUTES = 10
#: The live runs' axes: x, y, z at 400 steps/mm, a at 100 steps/degree; and the most slots they plan.
LIVE_AXES = [*(HostAxis(400, 50, 1000, name=a) for a in "xyz"), HostAxis(100, 360, 3600, name="a")]
MAX_SLOTS = 2_000_000
LETTERS = "GMXYZABCIJKRFSPQLDHTN@^$"
G_CODES = ["0", "1", "2", "3", "4", "5", "5.1", "5.2", "10", "17", "18", "19", "20", "21", "28", "28.1", "30", "33",
           "38.2", "40", "41", "41.1", "42", "43", "43.1", "49", "52", "53", "54", "55", "59.3", "61", "61.1", "64",
           "73", "76", "80", "81", "82", "83", "84", "85", "86", "89", "90", "90.1", "91", "91.1", "92", "92.1", "92.2",
           "92.3", "93", "94", "95", "96", "97", "98", "99", "7", "8", "12", "99.9"]
M_CODES = ["0", "1", "2", "3", "4", "5", "6", "7", "8", "9", "19", "30", "48", "49", "50", "51", "52", "53", "60", "61",
           "62", "63", "64", "65", "66", "67", "68", "70", "71", "72", "73", "100", "150", "200"]
FUNCS = ["sin", "cos", "tan", "asin", "acos", "abs", "exp", "ln", "sqrt", "fix", "fup", "round"]
OPS = ["+", "-", "*", "/", "**", "mod", "eq", "ne", "gt", "ge", "lt", "le", "and", "or", "xor"]
KEYWORDS = ["sub", "endsub", "call", "if", "elseif", "else", "endif", "while", "endwhile", "do", "repeat", "endrepeat",
            "break", "continue", "return"]


def number(rng: random.Random) -> str:
    kind = rng.random()
    if kind < 0.6:
        return f"{rng.uniform(-50, 50):.{rng.randint(0, 4)}f}"
    if kind < 0.8:
        return str(rng.randint(-3, 12))
    return rng.choice(["0", "-0", ".5", "5.", "1e3", "99999999999999999999", "0.0000001", "-", ".", "1..2"])


def expression(rng: random.Random, depth: int = 0) -> str:
    roll = rng.random()
    if depth > 3 or roll < 0.35:
        return number(rng)
    if roll < 0.5:
        return parameter(rng, depth)
    if roll < 0.65:
        return f"{rng.choice(FUNCS)}[{expression(rng, depth + 1)}]"
    if roll < 0.7:
        return f"atan[{expression(rng, depth + 1)}]/[{expression(rng, depth + 1)}]"
    if roll < 0.73:
        return f"exists[#<{rng.choice(['a', '_b', 'x'])}>]"
    return f"[{expression(rng, depth + 1)} {rng.choice(OPS)} {expression(rng, depth + 1)}]"


def parameter(rng: random.Random, depth: int = 0) -> str:
    roll = rng.random()
    if roll < 0.5:
        return f"#{rng.choice(['1', '2', '3', '31', '100', '5220', '5221', '5400', '5603', '0', '-1'])}"
    if roll < 0.8:
        return f"#<{rng.choice(['a', 'b', '_g', '_x', '_value', '_metric', 'depth', 'x y'])}>"
    return f"#[{expression(rng, depth + 1)}]"


def word(rng: random.Random) -> str:
    letter = rng.choice(LETTERS)
    if letter == "G":
        return "G" + rng.choice(G_CODES)
    if letter == "M":
        return "M" + rng.choice(M_CODES)
    value = number(rng) if rng.random() < 0.7 else expression(rng)
    return letter + value


def line(rng: random.Random) -> str:
    roll = rng.random()
    if roll < 0.12:
        label = rng.choice(["100", "101", "<a>", "<pocket>", "<missing>", "[#1]"])
        args = " ".join(f"[{expression(rng)}]" for _ in range(rng.randint(0, 3)))
        return f"o{label} {rng.choice(KEYWORDS)} {args}".rstrip()
    if roll < 0.22:
        return f"{parameter(rng)} = {expression(rng)}"
    if roll < 0.27:
        return rng.choice(["(MSG, hello)", "(DEBUG, x=#1 %d#<_x>)", "(PRINT, #<a>)", "; comment", "%", "",
                           "(unclosed", "/G0 X1", "N10 G1 X1 F100"])
    words = [word(rng) for _ in range(rng.randint(1, 6))]
    return " ".join(words)


def coord(rng: random.Random) -> str:
    return f"{rng.uniform(-40, 40):.3f}" if rng.random() < 0.8 else f"[{expression(rng, 2)}]"


def valid_line(rng: random.Random) -> str:
    """A line LinuxCNC would usually run: moves, arcs, cycles, modes, outputs, O-word blocks."""
    x, y, z = coord(rng), coord(rng), f"{rng.uniform(-5, 5):.2f}"
    return rng.choice([
        f"G0 X{x} Y{y}", f"G1 X{x} Y{y} Z{z}", f"G1 X{x} F{rng.randint(1, 3000)}", f"G91 G1 X{x} G90",
        f"G2 X{x} Y{y} R{rng.uniform(-60, 60):.2f}", f"G3 X{x} Y{y} I{coord(rng)} J{coord(rng)}",
        f"G18 G2 X{x} Z{z} I1 K1 G17", f"G64 P{rng.uniform(0, 1):.3f}", "G61", "G61.1", "M3 S10000", "M5", "M8",
        "M9", "M7", f"G4 P{rng.uniform(0, 0.5):.2f}", f"G81 X{x} Y{y} Z-2 R1", f"G83 X{x} Y{y} Z-3 R1 Q0.7", "G80",
        "T1 M6", "T2 M6 G43", "G49", f"G92 X{x}", "G92.1", "G55", "G54", f"G10 L2 P2 X{x}", "G20", "G21",
        f"#<a> = {expression(rng)}", f"#1 = [#1 + {number(rng)}]", "o<a> call [1] [2]", "G41.1 D2", "G40",
        f"o1 if [#1 gt {number(rng)}]\nG0 X1\no1 else\nG0 X2\no1 endif", "o2 repeat [3]\nG91 G0 X1 G90\no2 endrepeat",
        "#9=0\no3 while [#9 lt 3]\n#9=[#9+1]\no3 endwhile", "M62 P1", "M66 P0 L0", "M70\nG20\nM72",
        f"G5 X{x} Y{y} I1 J1 P-1 Q1", "(MSG, step)", "M1", "M0", f"G53 G0 Z{z}", "G28", "G38.2 Z-10 F100",
    ])


def generate(rng: random.Random) -> str:
    """A program of plausible lines, usually with a motion preamble and an end."""
    lines = ["G21 G90 G17 F600" if rng.random() < 0.7 else ""]
    if rng.random() < 0.3:
        lines += ["o<a> sub", "G1 X#1 Y#2", "o<a> endsub"]
    lines += [valid_line(rng) if rng.random() < 0.75 else line(rng) for _ in range(rng.randint(1, 25))]
    if rng.random() < 0.8:
        lines.append(rng.choice(["M2", "M30", "%"]))
    return "\n".join(lines) + "\n"


def mutate(rng: random.Random, text: str) -> str:
    """``text`` with a few characters inserted, deleted or replaced, lines swapped or line ends changed."""
    chars = list(text)
    for _ in range(rng.randint(1, 8)):
        if not chars:
            break
        i = rng.randrange(len(chars))
        op = rng.random()
        alphabet = "GMXYZIJKRFPQO#<>[]()=+-*/.;%0123456789 \n\t\r@^$"
        if op < 0.3:
            chars.insert(i, rng.choice(alphabet))
        elif op < 0.6:
            del chars[i]
        else:
            chars[i] = rng.choice(alphabet)
    out = "".join(chars)
    if rng.random() < 0.2:
        lines = out.split("\n")
        rng.shuffle(lines)
        out = "\n".join(lines)
    if rng.random() < 0.1:
        out = out.replace("\n", rng.choice(["\r\n", "\r", "\n\n"]))
    return out


def random_text(rng: random.Random) -> str:
    size = rng.randint(0, 200)
    return "".join(chr(rng.choice([rng.randint(32, 126), rng.randint(0, 0x2FF), 10])) for _ in range(size))


def seeds() -> list[str]:
    return [p.read_text() for p in SEEDS if p.is_file()]


def short(rng: random.Random) -> str:
    """One to three lines (a word, a setting, an O-word, a whole construct), perhaps mutated."""
    lines = [valid_line(rng) if rng.random() < 0.5 else line(rng) for _ in range(rng.randint(1, 3))]
    text = "\n".join(lines) + rng.choice(["\nM2\n", "\n", ""])
    return mutate(rng, text) if rng.random() < 0.3 else text


def draw(rng: random.Random, seed_texts: list[str]) -> str:
    """70 % short inputs, 15 % generated programs, 10 % mutated programs, 5 % random text."""
    roll = rng.random()
    if roll < 0.7:
        return short(rng)
    if roll < 0.85:
        return generate(rng)
    if roll < 0.95:
        return mutate(rng, rng.choice(seed_texts) if seed_texts and roll < 0.9 else generate(rng))
    return random_text(rng)


def exercise(text: str, *, live: bool = False) -> int:
    """Parse, interpret and convert ``text``; 1 if it ran to a tool path, 0 if refused with cosim's error.

    ``live``: as a machine file runs it (a 57CNC with an A axis), the interpreter live on 4 digital and 4
    analog inputs, the job planned piece by piece between its waits (M66: the interpreter goes on with
    #5399 = 1, 0, -1, 2.5 in turn; M0: cycle start)."""
    try:
        source = parse_text(text, "fuzz.nc")
        inputs = {"digital": 4, "analog": 4} if live else None
        interp = Interpreter(machine_units="mm", tools=TOOLS, search_path=[ROOT / "examples" / "pokeys_cam" / "subs"],
                             probe=True, axes="xyza" if live else "xyzabc", max_lines=MAX_LINES,
                             max_calls=MAX_LINES * 4, inputs=inputs)
        if not live:
            toolpath(interp.run(source), HostSetup(arc_tolerance=Fraction(1, 10)))
            return 1
        if _minutes(source) > MAX_MINUTES:
            return 1  # read and run; a job of hours (a mutated X368908) would only cost the planner's time
        setup = HostSetup(arc_tolerance=Fraction(1, 10), axes="xyza", cycle_start=True, inputs=True)
        job = GcodeJob(interp, source, setup, LIVE_AXES, settings=PathSettings(arc_tolerance=Fraction(1, 10)),
                       n_axes=8, max_pulses_per_slot=125)
        values = [1.0, 0.0, -1.0, 2.5]
        piece = job.next_piece()
        while piece.wait is not None and len(job.counts) < MAX_SLOTS:
            piece = job.next_piece(values[job.pieces % 4] if piece.wait.reads else None)
    except (ProgramError, CosimError):
        return 0
    return 1


def _minutes(source: SourceFile) -> float:
    """About how long the program's moves take [min]: each move's largest axis distance over its feed (a rapid at
    3000 units/min), the program run once without inputs."""
    path = toolpath(Interpreter(tools=TOOLS, search_path=[ROOT / "examples" / "pokeys_cam" / "subs"], probe=True,
                                max_lines=MAX_LINES, max_calls=MAX_LINES * 4).run(source))
    here, total = (0.0, 0.0, 0.0), 0.0
    for step in path.steps:
        if isinstance(step, Line | Arc):
            end = tuple(float(v) for v in step.end[:3])
            total += max(abs(a - b) for a, b in zip(end, here, strict=True)) / float(step.feed * 60 if step.feed
                                                                                      else 3000)
            here = end
    return total
