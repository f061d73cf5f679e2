"""The RS274/NGC language as LinuxCNC 2.9 runs it, construct by construct (issue 26, items 1-7).

Each test runs a few lines through the interpreter and reads the canonical calls, the layer that
is compared with LinuxCNC's ``rs274`` (``test_gcode_linuxcnc.py``). The numbers are LinuxCNC's:
from its G-code reference (``linuxcnc-doc-en``: "Parameters", "Expressions", "O Codes",
"G-Codes", "M-Codes") or, where the reference gives no number, what ``rs274`` 2.9 prints for the
same lines (quoted in the test).
"""

from __future__ import annotations

import math
from fractions import Fraction
from pathlib import Path

import pytest

from cosim.controllers.pokeys.gcode import HostSetup, Tool, canonical, read_program, read_text, toolpath
from cosim.controllers.pokeys.gcode.canon import CanonProgram
from cosim.controllers.pokeys.pathplan import HostAxis, PathSettings, plan_toolpath
from cosim.controllers.pokeys.toolpath import Line, Output, PathControl, Pause
from cosim.errors import ConfigurationError

F = Fraction
TOOLS = [Tool(1, z_offset=F(254, 10), diameter=6), Tool(2, z_offset=10, diameter=3)]


def run(text: str, **options: object) -> CanonProgram:
    return canonical(read_text(text, source="p.nc"), tools=TOOLS, **options)  # type: ignore[arg-type]


def calls(text: str, *names: str, **options: object) -> list[tuple[object, ...]]:
    """The calls of the given names as (name, arguments as floats)."""
    out = []
    for c in run(text, **options).calls:
        if c.name in names:
            out.append((c.name, *(a if isinstance(a, str | tuple) else float(a) for a in c.args)))  # type: ignore
    return out


def ends(text: str, **options: object) -> list[tuple[float, ...]]:
    """x, y, z of every straight move."""
    return [tuple(float(v) for v in c.args[:3]) for c in run(text, **options).calls  # type: ignore[arg-type]
            if c.name in ("STRAIGHT_TRAVERSE", "STRAIGHT_FEED")]


def messages(text: str) -> list[str]:
    return [str(c.args[0]) for c in run(text).calls if c.name == "MESSAGE"]


# -- 1. parameters and expressions --------------------------------------------------------------
def test_a_parameter_setting_takes_effect_after_the_line() -> None:
    """Reference: "if parameter 3 has been previously set to 15 and the line #3=6 G1 X#3 is interpreted, a straight
    move to a point where X equals 15 will occur and the value of parameter 3 will be 6"."""
    assert ends("#3=15\n#3=6 G1 X#3 F1\nG1 X#3\nM2\n") == [(15, 0, 0), (6, 0, 0)]
    assert ends("#2=7\n#7=3\nG0 X##2 Y#[1+1]\nM2\n") == [(3, 7, 0)]  # "##2: the value of the parameter whose index
    #                                                                 is the value of parameter 2"


def test_named_parameters_local_global_and_exists() -> None:
    """Reference: #<_endmill_dia> = 0.049; #<_endmill_rad> = [#<_endmill_dia>/2.0]; names lose case and spaces."""
    assert ends("#<_endmill_dia> = 0.049\n#<_endmill_rad> = [#<_endmill_dia>/2.0]\nG0 X#<_EndMill_ Rad>\nM2\n") == \
        [(pytest.approx(0.0245), 0, 0)]
    text = ("o1 if [EXISTS[#<_global>]]\n(DEBUG, yes)\no1 else\n(DEBUG, no)\no1 endif\n#<_global>=4711\n"
            "o2 if [EXISTS[#<_global>]]\n(DEBUG, now #<_global>)\no2 endif\nM2\n")
    assert messages(text) == [" no", " now 4711.000000"]
    with pytest.raises(ConfigurationError, match=r"p.nc:1:4: X word: Named parameter #<nothing> not defined"):
        run("G0 X#<nothing>\nM2\n")
    with pytest.raises(ConfigurationError, match=r"Cannot assign to read-only parameter #<_x>"):
        run("#<_x> = 3\nM2\n")
    with pytest.raises(ConfigurationError, match=r"Parameter number out of range: #5603"):
        run("G0 X#5603\nM2\n")


@pytest.mark.parametrize(("expression", "value"), [
    ("[2.0 / 3 * 1.5 - 5.5 / 11.0]", 0.5),          # the reference's precedence example
    ("[1 + acos[0] - [2 ** [4.0/2]]]", 87),          # acos[0] = 90 degrees
    ("[2**3**2]", 64),                               # rs274: left to right
    ("FIX[2.8]", 2), ("FIX[-2.8]", -3), ("FUP[2.8]", 3), ("FUP[-2.8]", -2),  # the reference's examples
    ("[-7 MOD 3]", 2), ("[1 MOD -3]", 1),          # rs274: never negative
    ("ROUND[2.5]", 3), ("ROUND[-2.5]", -3), ("ATAN[1]/[1]", 45), ("SIN[30]", 0.5), ("SQRT[16]", 4),
    ("ABS[-3]", 3), ("EXP[0]", 1), ("LN[1]", 0), ("TAN[45]", 1), ("ASIN[1]", 90), ("COS[60]", 0.5),
    ("[1 EQ 1.00001]", 1), ("[1 EQ 1.001]", 0), ("[1 NE 1.00001]", 0),  # equal within 0.0001
    ("[2 GT 1]", 1), ("[2 GE 2]", 1), ("[2 LT 1]", 0), ("[1 LE 1]", 1),
    ("[1 AND 0 OR 1]", 1), ("[1 XOR 1]", 0), ("[0 OR 0]", 0), ("[-2**2]", 4), ("[2*-1]", -2),
])
def test_every_operator_and_function_of_the_reference(expression: str, value: float) -> None:
    (x, _, _), = ends(f"G0 X{expression}\nM2\n")
    assert x == pytest.approx(value, abs=1e-12)


@pytest.mark.parametrize(("expression", "message"), [
    ("[1/0]", "Attempt to divide by zero"), ("LN[-1]", "Zero or negative argument to ln"),
    ("SQRT[-1]", "Negative argument to sqrt"), ("ACOS[2]", "Argument to acos out of range"),
    ("[-2**0.5]", "Attempt to raise negative to non integer power"),
])
def test_expression_errors_are_linuxcncs(expression: str, message: str) -> None:
    with pytest.raises(ConfigurationError, match=rf"p.nc:1:4: X word: {re_escape(message)}"):
        run(f"G0 X{expression}\nM2\n")


def re_escape(text: str) -> str:
    import re

    return re.escape(text)


def test_system_parameters_hold_coordinate_systems_homes_offsets_and_tool_data() -> None:
    """Reference: 5220 coordinate system number, 5241.. G55, 5161.. G28 home, 5211.. G92, 5400 tool, 5410 diameter."""
    out = messages("G10 L2 P2 X5 Y6\nG55\n(DEBUG, %d#5220 #5241 #5242)\nG0 X1 Y1\nG28.1\n(DEBUG, %.1f#5161 #5162)\n"
                   "G92 X0\n(DEBUG, %.1f#5211 #5210)\nT1 M6\n(DEBUG, %d#5400 %.1f#5410 #<_current_tool>)\nM2\n")
    assert out == [" 2 5 6", " 6.0 7.0", " 1.0 1.0", " 1 6.0 1.0"]  # G92 X0 at X1 of G55


def test_debug_and_print_expand_parameters_in_the_reference_formats() -> None:
    """Reference: %lf default (6 decimals), %d no decimals, %f four, %.xf x decimals; MSG is not expanded."""
    program = run("#1=2.5\n(MSG, hello #1)\n(DEBUG, v=#1 %d#1 %f#1 %.2f#1)\n(PRINT, p=#1)\n#5599=0\n(DEBUG, hidden)\n"
                  "M2\n")
    texts = [(c.name, c.args[0]) for c in program.calls if c.name in ("MESSAGE", "PRINT")]
    assert texts == [("MESSAGE", " hello #1"), ("MESSAGE", " v=2.500000 2 2.5000 2.50"), ("PRINT", " p=2.500000")]


# -- 2. O-codes ---------------------------------------------------------------------------------
def test_subroutines_with_arguments_and_return_values() -> None:
    """Reference: call arguments are #1..#30 in the sub; endsub/return [value] sets #<_value>, #<_value_returned>."""
    text = ("o<sq> sub\nG1 X#1 F#2\no<sq> endsub [#1*2]\no100 sub\no100 return [7]\no100 endsub\n"
            "o<sq> call [3] [200]\n(DEBUG, %d#<_value> #<_value_returned> #1)\no100 call\n(DEBUG, %d#<_value>)\nM2\n")
    assert messages(text) == [" 6 1 0", " 7"]  # %d holds for the rest of the line
    assert calls(text, "STRAIGHT_FEED", "SET_FEED_RATE")[:2] == [("SET_FEED_RATE", 200),
                                                                  ("STRAIGHT_FEED", 3, 0, 0, 0, 0, 0, 0, 0, 0)]


def test_if_elseif_else_while_do_repeat_break_continue() -> None:
    text = ("#1=2\no1 if [#1 EQ 1]\n(DEBUG, one)\no1 elseif [#1 EQ 2]\n(DEBUG, two)\no1 else\n(DEBUG, other)\n"
            "o1 endif\n#2=0\no2 while [#2 LT 5]\n#2=[#2+1]\no3 if [#2 EQ 2]\no2 continue\no3 endif\n"
            "o4 if [#2 EQ 4]\no2 break\no4 endif\n(DEBUG, w%d#2)\no2 endwhile\n#3=0\no5 do\n#3=[#3+1]\n"
            "o5 while [#3 LT 3]\n(DEBUG, do%d#3)\no6 repeat [3]\n(DEBUG, r)\no6 endrepeat\nM2\n")
    assert messages(text) == [" two", " w1", " w3", " do3", " r", " r", " r"]


def test_a_subroutine_file_is_found_on_the_search_path(tmp_path: Path) -> None:
    subs = tmp_path / "subs"
    subs.mkdir()
    (subs / "peck.ngc").write_text("o<peck> sub\nG1 Z#1 F100\no<peck> endsub\nM2\n")
    assert ends("o<peck> call [-2]\nM2\n", search_path=[subs]) == [(0, 0, -2)]
    with pytest.raises(ConfigurationError, match=r"p.nc:1:9: O-word `call` o<peck>: the subroutine is not defined; "
                                                 r"no peck.ngc on the subroutine search path"):
        run("o<peck> call [-2]\nM2\n")


def test_o_word_errors_name_the_o_word() -> None:
    with pytest.raises(ConfigurationError, match=r"p.nc:1:4: O-word `if` o1: no matching endif"):
        run("o1 if [0]\nM2\n")
    with pytest.raises(ConfigurationError, match=r"p.nc:1:6: O-word `endsub` o<a> outside a subroutine"):
        run("o<a> endsub\nM2\n")
    with pytest.raises(ConfigurationError, match=r"O-word `while`: no other words are allowed"):
        run("o1 while [1] G0 X1\nM2\n")
    with pytest.raises(ConfigurationError, match=r"p.nc:1: the program runs more than 1000 lines"):
        _endless()


def _endless() -> None:
    from cosim.controllers.pokeys.gcode.flow import ProgramError
    from cosim.controllers.pokeys.gcode.interpreter import Interpreter

    try:
        Interpreter(max_lines=1000).run(read_text("o1 while [1]\no1 endwhile\nM2\n", source="p.nc"))
    except ProgramError as exc:
        raise ConfigurationError(str(exc)) from None


def test_an_if_needs_its_endif_only_when_the_program_gets_there() -> None:
    """rs274 2.9 runs ``O1 if [1]`` / ``M2`` (no endif: the program ends in the branch) and refuses ``O1 if [0]`` /
    ``M2`` (it looks for the endif)."""
    assert run("O1 if [1]\nG0 X1\nM2\n").end == "M2"
    with pytest.raises(ConfigurationError, match=r"p.nc:1:4: O-word `if` o1: no matching endif"):
        run("O1 if [0]\nG0 X1\nM2\n")


# -- 3. motion ----------------------------------------------------------------------------------
def test_arcs_in_the_three_planes_with_helix_turns_and_absolute_centres() -> None:
    """rs274: G18 G2 X5 Z0 I1 K1 from (X3, Z0): ARC_FEED(0, 5, 1, 4, -1, 7) (first axis Z, second X, normal Y);
    G3 with P2: rotation 2."""
    text = ("G21 G0 X3 Y7\nG18 G2 X5 Z0 I1 K1 F100\nG17 G3 X5 Y7 I-2 J0 P2 Z1\nG19 G2 Y7 Z3 J0 K1\n"
            "G17 G90.1 G2 X9 Y7 I7 J7\nM2\n")
    arcs = calls(text, "ARC_FEED")
    assert [a[1:7] for a in arcs] == [(0, 5, 1, 4, -1, 7), (5, 7, 3, 7, 2, 1), (7, 3, 7, 2, -1, 5),
                                      (9, 7, 7, 7, -1, 3)]


def test_r_arcs_take_linuxcncs_centre_and_its_tolerance() -> None:
    """G2 from (10, 0) to (0, 0) with R4.999: rs274 prints ARC_FEED(0, 0, 5, 0, -1, ...); R4.99 is refused."""
    (arc,) = calls("G0 X10\nG2 X0 Y0 R4.999 F100\nM2\n", "ARC_FEED")
    assert arc[1:6] == (0, 0, pytest.approx(5, abs=1e-4), pytest.approx(0, abs=0.1), -1)
    with pytest.raises(ConfigurationError, match="Arc radius too small to reach end point"):
        run("G0 X10\nG2 X0 Y0 R4.99 F100\nM2\n")


def test_splines_dwell_and_the_feed_modes() -> None:
    """G5: control points start + (I, J) and end + (P, Q); G93: the feed of a move is its length times F
    (3-4-5 triangle: 5 mm at F2 is 10 mm/min); G95: F per revolution times S; G4 P seconds."""
    (spline,) = calls("G21 G0 X0 Y0\nG5 X10 Y0 I2 J3 P-2 Q3 F100\nM2\n", "SPLINE_FEED")
    assert spline[1] == 3 and tuple(float(v) for v in spline[2]) == (2, 3, 8, 3, 10, 0)  # type: ignore[union-attr]
    assert calls("G93 G1 X3 Y4 F2\nM2\n", "SET_FEED_RATE")[0] == ("SET_FEED_RATE", 10)
    with pytest.raises(ConfigurationError, match=r"F word missing with inverse time G1 move"):
        run("G93 G1 X3 Y4 F2\nX5\nM2\n")
    path = read_program("G21 M3 S1000\nG95 G1 X10 F0.1\nM2\n")
    (feed,) = [s.feed for s in path.steps if isinstance(s, Line)]
    assert feed == F(1000) * F(1, 10) / 60  # 100 mm/min
    assert calls("G4 P1.5\nM2\n", "DWELL") == [("DWELL", 1.5)]


def test_canned_cycles_with_retract_modes_and_repeats() -> None:
    """rs274 (G21, from Z5): G81 R1 Z-2 at X1 Y1 then X2 in G99; G91 G81 X1 Z-1 R-2 L3 from X3 Z5 drills at X4, 5, 6
    with R at Z3, bottom Z2; G83 Q0.7 pecks 0.3, -0.4, -1.1, -1.8, -2 with a rapid back to 0.254 mm above each."""
    drill = ends("G21 G0 Z5\nG99 G81 X1 Y1 Z-2 R1 F50\nX2\nM2\n")
    assert drill == [(0, 0, 5), (1, 1, 5), (1, 1, 1), (1, 1, -2), (1, 1, 1), (2, 1, 1), (2, 1, -2), (2, 1, 1)]
    repeats = ends("G21 G0 X3 Y1 Z5\nG91 G81 X1 Y0 Z-1 R-2 L3 F50\nM2\n")
    assert [p for p in repeats if p[2] == 2] == [(4, 1, 2), (5, 1, 2), (6, 1, 2)]
    peck = ends("G21 G0 Z5\nG83 X1 Y1 Z-2 R1 Q0.7 F50\nM2\n")
    assert [round(p[2], 4) for p in peck[3:]] == [0.3, 1, 0.554, -0.4, 1, -0.146, -1.1, 1, -0.846, -1.8, 1, -1.546,
                                                  -2, 1]
    old_z = ends("G21 G0 Z5\nG98 G81 X1 Y1 Z-2 R1 F50\nM2\n")
    assert old_z[-1] == (1, 1, 5)  # G98: back to the height before the cycle
    dwell = calls("G21 G0 Z5\nG82 X1 Y1 Z-2 R1 P0.5 F50\nM2\n", "DWELL", "STRAIGHT_FEED")
    assert dwell == [("STRAIGHT_FEED", 1, 1, -2, 0, 0, 0, 0, 0, 0), ("DWELL", 0.5)]
    with pytest.raises(ConfigurationError, match=r"R clearance plane unspecified in canned cycle G81"):
        run("G81 X1 Z-1 F10\nM2\n")
    with pytest.raises(ConfigurationError, match=r"p.nc:1:18: Cannot do zero repeats of cycle"):  # rs274's message
        run("G81 X1 Y1 Z-1 R1 L0 F10\nM2\n")


def test_g87_back_boring_and_g88_manual_retract_as_rs274_runs_them() -> None:
    """The reference: G87 and G88 are "accepted, but the behavior is undefined"; rs274 2.9 (G21 G0 Z5, S100 M3,
    G87 X1 Y1 Z-1 R1 I0.5 J0.25 K-0.5) prints: traverses (1 1 5) (1 1 1) (1.5 1.25 1), STOP_SPINDLE_TURNING,
    ORIENT_SPINDLE(0, 0, 2), traverses (1.5 1.25 -1) (1 1 -1), START_SPINDLE_CLOCKWISE, feeds (1 1 -0.5) (1 1 -1),
    STOP, ORIENT, traverses (1.5 1.25 -1) (1.5 1.25 1) (1 1 1), START_SPINDLE_CLOCKWISE; under G91 K is from the
    bottom; G88 P1.5 feeds to the bottom, DWELL(1.5), STOP_SPINDLE_TURNING, PROGRAM_STOP,
    START_SPINDLE_CLOCKWISE."""
    names = ("STRAIGHT_TRAVERSE", "STRAIGHT_FEED", "STOP_SPINDLE_TURNING", "ORIENT_SPINDLE", "START_SPINDLE_CLOCKWISE",
             "DWELL", "PROGRAM_STOP")
    back = [(c[0], *c[1:4]) if c[0].startswith("STRAIGHT") else c
            for c in calls("G21 G0 Z5\nS100 M3\nG87 X1 Y1 Z-1 R1 I0.5 J0.25 K-0.5 F100\nM2\n", *names)]
    assert back[2:] == [
        ("STRAIGHT_TRAVERSE", 1, 1, 5), ("STRAIGHT_TRAVERSE", 1, 1, 1), ("STRAIGHT_TRAVERSE", 1.5, 1.25, 1),
        ("STOP_SPINDLE_TURNING", 0), ("ORIENT_SPINDLE", 0, 0, 2), ("STRAIGHT_TRAVERSE", 1.5, 1.25, -1),
        ("STRAIGHT_TRAVERSE", 1, 1, -1), ("START_SPINDLE_CLOCKWISE", 0), ("STRAIGHT_FEED", 1, 1, -0.5),
        ("STRAIGHT_FEED", 1, 1, -1), ("STOP_SPINDLE_TURNING", 0), ("ORIENT_SPINDLE", 0, 0, 2),
        ("STRAIGHT_TRAVERSE", 1.5, 1.25, -1), ("STRAIGHT_TRAVERSE", 1.5, 1.25, 1), ("STRAIGHT_TRAVERSE", 1, 1, 1),
        ("START_SPINDLE_CLOCKWISE", 0), ("STOP_SPINDLE_TURNING", 0)]
    incremental = ends("G21 G0 Z5\nS100 M3 G91\nG87 X1 Y1 Z-1 R1 I0.5 J0.25 K-0.5 F100\nM2\n")
    assert (1, 1, 4.5) in incremental  # rs274: STRAIGHT_FEED(1.0000, 1.0000, 4.5000, ...) (R 6, bottom 5)
    manual = calls("G21 G0 Z5\nS100 M3\nG88 X1 Y1 Z-1 R1 P1.5 F100\nM2\n", *names)
    assert manual[4:9] == [("STRAIGHT_FEED", 1, 1, -1, 0, 0, 0, 0, 0, 0), ("DWELL", 1.5), ("STOP_SPINDLE_TURNING", 0),
                           ("PROGRAM_STOP",), ("START_SPINDLE_CLOCKWISE", 0)]
    with pytest.raises(ConfigurationError, match=r"p.nc:2:1: K word missing with g87"):
        run("S100 M3\nG87 X1 Y1 Z-1 R1 I1 J1 F100\nM2\n")


@pytest.mark.parametrize(("spindle", "cycle", "message"), [
    ("", "G86 X1 Y1 Z-1 R1 P1", "Spindle not turning in g86"), ("", "G84 X1 Y1 Z-1 R1", "Spindle not turning in G84"),
    ("S100 M4", "G84 X1 Y1 Z-1 R1", "Spindle turning counterclockwise in G84"),
    ("S100 M3", "G74 X1 Y1 Z-1 R1", "Spindle turning clockwise in G74"),
    ("", "G87 X1 Y1 Z-1 R1 I1 J1 K0", "Spindle not turning in g87"),
    ("", "G88 X1 Y1 Z-1 R1 P1", "Spindle not turning in g88")])
def test_cycles_that_need_the_spindle_refuse_as_rs274(spindle: str, cycle: str, message: str) -> None:
    """rs274 2.9's messages, spelling included."""
    with pytest.raises(ConfigurationError, match=rf"p.nc:2:1: {message}"):
        run(f"G21 {spindle}\n{cycle} F100\nM2\n")


# -- 4. coordinates and tools ---------------------------------------------------------------------
def test_work_offsets_g10_g92_g53_and_g28_as_rs274_prints_them() -> None:
    """rs274: at X-2, G92 X10 gives SET_G92_OFFSET(-12); G10 L2 P2 X5 Y6 then G55 X1 Y1 is 6, 7 in G54."""
    out = calls("G21 G0 X-2\nG92 X10\nG0 X0\nG92.1\nG10 L2 P2 X5 Y6\nG55 G0 X1 Y1\nG54 G0 Z0\nG53 G0 X0\n"
                "G10 L20 P1 X2\nG0 X2\nM2\n", "SET_G92_OFFSET", "SET_G5X_OFFSET", "STRAIGHT_TRAVERSE")
    assert out[1] == ("SET_G92_OFFSET", -12, 0, 0, 0, 0, 0, 0, 0, 0)
    assert ("STRAIGHT_TRAVERSE", 6, 7, 0, 0, 0, 0, 0, 0, 0) in out  # G54 Z0 after G55 X1 Y1
    machine = [c for c in out if c[0] == "STRAIGHT_TRAVERSE"]
    assert machine[4][1] == 0  # G53 X0 in G54 (no offset): 0
    assert ("SET_G5X_OFFSET", 1, -2, 0, 0, 0, 0, 0, 0, 0, 0) in out  # G10 L20 P1 X2 at X0: the origin moves to -2
    home = ends("G21 G0 X5 Y6\nG28.1\nG0 X0 Y0\nG28 X1\nM2\n")
    assert home[-2:] == [(1, 0, 0), (5, 0, 0)]  # through X1 to the stored X only


def test_tools_length_offsets_and_units() -> None:
    """rs274: T1 M6 gives SELECT_TOOL(1) START_CHANGE STOP_SPINDLE_TURNING CHANGE_TOOL(1); G43 uses the table's
    length; the position in program coordinates moves by the offset; G20 converts it."""
    out = calls("T1 M6\nG43\nG0 X0\nG49\nG0 X1\nG43.1 Z2\nM61 Q2\nG20\nM2\n", "SELECT_TOOL", "CHANGE_TOOL",
                "USE_TOOL_LENGTH_OFFSET", "STRAIGHT_TRAVERSE", "CHANGE_TOOL_NUMBER", "USE_LENGTH_UNITS")
    assert out[:2] == [("SELECT_TOOL", 1), ("CHANGE_TOOL", 1)]
    assert out[2] == ("USE_TOOL_LENGTH_OFFSET", 0, 0, 25.4, 0, 0, 0, 0, 0, 0)
    assert out[3] == ("STRAIGHT_TRAVERSE", 0, 0, -25.4, 0, 0, 0, 0, 0, 0)  # the same machine point, 25.4 lower
    assert out[5] == ("STRAIGHT_TRAVERSE", 1, 0, 0, 0, 0, 0, 0, 0, 0)
    assert ("CHANGE_TOOL_NUMBER", 2) in out and out[-1] == ("USE_LENGTH_UNITS", "INCHES")
    with pytest.raises(ConfigurationError, match=r"p.nc:1:1: Requested tool 7 not found in the tool table"):
        run("T7 M6\nM2\n")


def test_cutter_radius_compensation_as_linuxcnc_computes_it() -> None:
    """rs274 for this path with a 6 mm tool (T1): the entry move ends 3 mm left of its end, perpendicular; the convex
    corner at (0, 0) gets an arc around it; the concave corner before X5 Y5 is met where the offset paths cross."""
    text = ("G21 G0 X-10 Y-10\nG41 D1\nG1 X0 Y0 F100\nX20\nY10\nG3 X10 Y20 R10\nG1 X0\nX5 Y5\nY0\nG40\n"
            "G0 X-10 Y-10\nM2\n")
    moves = [(c.name, *(round(float(a), 4) for a in c.args[:6])) for c in run(text).calls
             if c.name in ("STRAIGHT_FEED", "STRAIGHT_TRAVERSE", "ARC_FEED")]
    assert moves == [
        ("STRAIGHT_TRAVERSE", -10, -10, 0, 0, 0, 0), ("STRAIGHT_FEED", -2.1213, 2.1213, 0, 0, 0, 0),
        ("ARC_FEED", 0, 3, 0, 0, -1, 0), ("STRAIGHT_FEED", 17, 3, 0, 0, 0, 0), ("STRAIGHT_FEED", 17, 10, 0, 0, 0, 0),
        ("ARC_FEED", 10, 17, 10, 10, 1, 0), ("STRAIGHT_FEED", 4.1623, 17, 0, 0, 0, 0),
        ("STRAIGHT_FEED", 7.846, 5.9487, 0, 0, 0, 0), ("ARC_FEED", 8, 5, 5, 5, -1, 0),
        ("STRAIGHT_FEED", 8, 0, 0, 0, 0, 0), ("STRAIGHT_TRAVERSE", -10, -10, 0, 0, 0, 0)]
    with pytest.raises(ConfigurationError, match=r"Length of cutter compensation entry move is not greater than the "
                                                 r"tool radius"):
        run("G41 D1\nG1 X2 F100\nM2\n")
    with pytest.raises(ConfigurationError, match=r"Cannot turn cutter radius comp on when already on"):
        run("G41.1 D0\nG42.1 D0\nM2\n")
    with pytest.raises(ConfigurationError, match=r"Cannot change tools with cutter radius compensation on"):
        run("G41 D1\nT2 M6\nM2\n")
    assert ends("G41.1 D0\nG1 X10 F100\nG40\nM2\n") == [(10, 0, 0)]


# -- 5. path control ------------------------------------------------------------------------------
def test_g61_g61_1_and_g64_p_q_become_path_control_and_change_the_job_time() -> None:
    """rs274: G64 P0.1 Q0.05 prints SET_MOTION_CONTROL_MODE(CANON_CONTINUOUS, 0.1) SET_NAIVECAM_TOLERANCE(0.05)."""
    assert calls("G64 P0.1 Q0.05\nG61\nG61.1\nM2\n", "SET_MOTION_CONTROL_MODE", "SET_NAIVECAM_TOLERANCE") == [
        ("SET_MOTION_CONTROL_MODE", "CONTINUOUS", 0.1), ("SET_NAIVECAM_TOLERANCE", 0.05),
        ("SET_MOTION_CONTROL_MODE", "EXACT_PATH", 0), ("SET_MOTION_CONTROL_MODE", "EXACT_STOP", 0)]
    # rs274: a negative P or Q is as none: G64 P-1 Q-2 prints CONTINUOUS, 0.000000 and NAIVECAM 0.0000
    assert calls("G64 P-1 Q-2\nM2\n", "SET_MOTION_CONTROL_MODE", "SET_NAIVECAM_TOLERANCE") == [
        ("SET_MOTION_CONTROL_MODE", "CONTINUOUS", 0), ("SET_NAIVECAM_TOLERANCE", 0)]
    square = "G1 X20 F3000\nY20\nX0\nY0\n" * 3 + "M2\n"
    axes = [HostAxis(400, 50, 500, name=a) for a in "xyz"]

    def slots(mode: str) -> int:
        path = read_program(f"G21 {mode}\n{square}")
        assert any(isinstance(s, PathControl) for s in path.steps)
        return len(plan_toolpath(path, axes, settings=PathSettings(mode="exact_stop")).counts)

    exact, exact_path, fine, coarse = slots("G61.1"), slots("G61"), slots("G64 P0.01"), slots("G64 P1")
    assert exact == exact_path  # square corners: G61 stops at each as G61.1 does
    assert coarse < fine < exact  # a larger tolerance passes the corners faster


# -- 6. program flow and I/O ----------------------------------------------------------------------
def test_pauses_coolant_tool_change_and_outputs_become_host_outputs() -> None:
    program = canonical(read_text("G21 M8\nM7\nT1 M6\nM0\nM1\nM62 P3\nM65 P3\nM67 E1 Q2.5\nM9\nM2\n", source="p.nc"),
                        tools=TOOLS)
    path = toolpath(program, HostSetup(tool_change_time=F(4), tool_change_position=(F(0), F(0), F(50)),
                                       pause_time=F(2)))
    steps = [(s.name, s.value) if isinstance(s, Output) else (type(s).__name__, getattr(s, "seconds", None))
             for s in path.steps if not isinstance(s, PathControl)]
    assert steps == [("coolant_flood", 1), ("coolant_mist", 1), ("Line", None), ("tool_changing", 1), ("Pause", 4),
                     ("tool", 1), ("tool_changing", 0), ("paused", 1), ("Pause", 2), ("paused", 0), ("dout3", 1),
                     ("dout3", 0), ("aout1", 2.5), ("coolant_mist", 0), ("coolant_flood", 0)]
    assert "p.nc:5: M1 does not stop: the optional stop switch is off (host.optional_stop)" in path.notes


def test_overrides_waits_and_saved_states() -> None:
    """M48-M53 switch LinuxCNC's overrides; M66 waits (L0: at once); M70/M72 save and restore the modal state;
    M73 in a subroutine restores it on return (rs274 m73-demo: USE_LENGTH_UNITS back to MM)."""
    assert [c[0] for c in calls("M49\nM50 P1\nM51 P0\nM52 P1\nM53 P0\nM2\n", "DISABLE_FEED_OVERRIDE",
                                "ENABLE_FEED_OVERRIDE", "DISABLE_SPEED_OVERRIDE", "ENABLE_ADAPTIVE_FEED",
                                "DISABLE_FEED_HOLD")] == ["DISABLE_FEED_OVERRIDE", "DISABLE_SPEED_OVERRIDE",
                                                          "ENABLE_FEED_OVERRIDE", "DISABLE_SPEED_OVERRIDE",
                                                          "ENABLE_ADAPTIVE_FEED", "DISABLE_FEED_HOLD"]
    assert calls("M66 P2 L3 Q5\nM2\n", "WAIT") == [("WAIT", 2, 1, 3, 5)]
    units = calls("G21\nM70\nG20\nM72\no<s> sub\nM73\nG20\no<s> endsub\no<s> call\nM2\n", "USE_LENGTH_UNITS")
    assert [u[1] for u in units] == ["MM", "INCHES", "MM", "INCHES", "MM"]


def test_m19_orients_the_spindle_as_rs274_prints_it() -> None:
    """Reference: M19 R- (0-360 degrees) Q- (seconds to wait) P- (0 shortest, 1 clockwise, 2 counter-clockwise). rs274
    2.9: M19 R45 Q1 P1 -> ORIENT_SPINDLE(0, 45.0000, 1), SPINDLE.0.WAIT_ORIENT_COMPLETE(1.0000); M19 P2 ->
    ORIENT_SPINDLE(0, 0.0000, 2); a bare M19 prints nothing; R-10: "R value must be within 0..360 with M19"."""
    assert calls("M19 R45 Q1 P1\nM19 P2\nM19\nM2\n", "ORIENT_SPINDLE", "WAIT_ORIENT_COMPLETE") == [
        ("ORIENT_SPINDLE", 0, 45, 1), ("WAIT_ORIENT_COMPLETE", 0, 1), ("ORIENT_SPINDLE", 0, 0, 2)]
    for line, message in [("M19 R-10", "R value must be within 0..360 with M19"),
                          ("M19 P3", "P value must be 0,1,or 2 with M19"),
                          ("M19 R10 Q0", "Q word with M19 requires a value > 0")]:
        with pytest.raises(ConfigurationError, match=rf"p.nc:1:1: {message}"):
            run(f"{line}\nM2\n")


def test_program_end_resets_as_linuxcnc_and_stops_the_spindle_and_coolant() -> None:
    """rs274 for M8 / M2: ... STOP_SPINDLE_TURNING, FLOOD_OFF, PROGRAM_END; M30 adds PALLET_SHUTTLE."""
    names = [c.name for c in run("M8\nM30\n").calls]
    assert names[-4:] == ["SET_SPINDLE_MODE", "FLOOD_OFF", "PALLET_SHUTTLE", "PROGRAM_END"]


# -- 7. more axes ---------------------------------------------------------------------------------
def test_rotary_axes_on_a_machine_that_has_them_and_refused_on_one_that_has_not() -> None:
    assert run("G0 A90 B-10 C5\nM2\n").motion()[0].args[3:6] == (90, -10, 5)
    with pytest.raises(ConfigurationError, match=r"p.nc:1:4: A word: the machine has no A axis"):
        run("G0 A90\nM2\n", axes="xyz")
    path = read_program("G0 X1 A90\nM2\n", axes="xyza")
    assert any("A moves: the host planner drives x, y, z" in n for n in path.notes)


def test_math_constants_stay_exact_where_the_program_writes_decimals() -> None:
    """Numbers written in the program are exact; a function makes a double (as LinuxCNC's)."""
    path = read_program("G0 X0.1\nG0 X[0.1+0.2]\nG0 X[SIN[30]]\nM2\n")
    assert [s.end[0] for s in path.steps if isinstance(s, Line)] == [F(1, 10), F(3, 10), F(math.sin(math.pi / 6))]
    assert isinstance(path.steps[0], Line) and not isinstance(path.steps[0], Pause)
