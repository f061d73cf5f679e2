"""G-code text into a syntax tree and a tool path: LinuxCNC's reading rules, every refusal with file:line:column.

    pocket.nc ──syntax──> SourceLine ──interpreter──> canonical calls ──program──> Toolpath (machine units)
                  └─ not G-code, a construct the machine cannot simulate: "pocket.nc:LINE:COLUMN: reason"
"""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import pytest

from cosim.controllers.pokeys.gcode import canonical, load_program, read_program, read_text
from cosim.controllers.pokeys.gcode.syntax import Binary, Func, GcodeSyntaxError, Neg, Num, Param, parse_line
from cosim.controllers.pokeys.toolpath import Arc, Line, Pause, Spindle
from cosim.errors import ConfigurationError

F = Fraction


def test_spaces_case_comments_and_line_numbers_are_read_as_linuxcnc_reads_them() -> None:
    """LinuxCNC drops spaces and case outside comments: ``G0 X [ 1 + 2 ] Y 1 . 5`` is ``g0x[1+2]y1.5``."""
    line = parse_line("N10 g1 x-2.5 Y.25 (a Comment) f1200 ; the rest", 4)
    assert line.number == 4 and line.line_number == 10
    assert [(w.letter, w.literal) for w in line.words] == [("G", 1), ("X", F(-5, 2)), ("Y", F(1, 4)), ("F", 1200)]
    assert line.comments == ("a Comment", " the rest")
    spaced = parse_line("G0 X [ 1 + 2 ] Y 1 . 5")
    assert spaced.words[1].expr == Binary("+", Num(F(1)), Num(F(2))) and spaced.words[2].literal == F(3, 2)
    assert parse_line("G0 X#<_x> Y##1").words[2].expr == Param(Param(Num(F(1))))
    assert parse_line("X-sin[30]").words[0].expr == Neg(Func("sin", (Num(F(30)),)))
    assert parse_line("/G0 X1").block_delete


@pytest.mark.parametrize(("text", "column", "reason"), [
    ("G0 X", 5, "the letter 'X' at column 4 is followed by the end of the line, not a value"),
    ("G0 X1 (open", 7, "a comment is not closed on its line"),
    ("G0 X1 (a (b) c)", 10, "a comment opens inside a comment"),
    ("G0 X1 )", 7, "')' closes a comment that was never opened"),
    ("def main():", 2, "the letter 'D' at column 1 is followed by 'e', not a value"),
    ("[machine]", 1, "unexpected '['"),
    ("o100", 5, "an O-word needs a keyword after its label"),
    ("G0 X[1+2", 9, "'[' opened at column 5 is not closed properly"),
])
def test_text_that_is_not_gcode_is_refused_with_its_column(text: str, column: int, reason: str) -> None:
    with pytest.raises(GcodeSyntaxError) as info:
        parse_line(text)
    assert info.value.column == column and reason in info.value.reason


def test_o_words_that_the_old_reader_took_for_letters_now_read() -> None:
    """The issue's examples: ``O100 sub`` was "the letter 'S' at column 6 is followed by 'u'"."""
    assert parse_line("O100 sub").oword.keyword == "sub"  # type: ignore[union-attr]
    assert parse_line("o<touchoff> call [1] [2.5]").oword.args == (Num(F(1)), Num(F(5, 2)))  # type: ignore[union-attr]
    assert parse_line("G0 X[2 ^ 3]" if False else "G1 @1 ^90 F1").words[2].letter == "^"


def test_a_binary_file_is_not_gcode(tmp_path: Path) -> None:
    path = tmp_path / "job.nc"
    path.write_bytes(b"G0 X1\nPNG\x00\x01")
    with pytest.raises(ConfigurationError, match=r"job.nc:2: not G-code: the file holds NUL bytes"):
        load_program(path)
    path.write_bytes(b"G0 X1\nG1 X\xff\n")
    with pytest.raises(ConfigurationError, match=r"job.nc:2: not G-code: not a UTF-8 text file \(byte 0xff"):
        load_program(path)


@pytest.mark.parametrize(("text", "message"), [
    ("G38.2 Z-1 F10\n", r"^p.nc:1:1: G38.2 needs a probe input: add probe = true to \[host\] in the machine file"),
    ("M3 S100\nG33 Z-1 K1\n", r"^p.nc:2:1: G33 \(spindle-synchronised motion\) needs a spindle encoder"),
    ("G76 P0.05 Z-1 I-0.07 J0.01 K0.03\n", r"^p.nc:1:1: G76 \(threading\) is spindle-synchronised"),
    ("G0 X1 M101\n", r"^p.nc:1:7: M101 is a user M code"),
    ("G1 A10 F100\n", r"^p.nc:1:4: A word: the machine has no A axis \(its axes: X, Y, Z\) \(LinuxCNC: Bad "
                      r"character 'a' used\)"),
    ("o<nothere> call\n", r"^p.nc:1:12: O-word `call` o<nothere>: the subroutine is not defined; no nothere.ngc on "
                          r"the subroutine search path"),
    ("G5.2 X1 Y1 P1 L3 F10\n", r"^p.nc:1:1: G5.2 \(NURBS\) is not supported"),
    ("G71 Q1 X1 Z1 D1 I1 R1\n", r"^p.nc:1:1: G71 \(lathe roughing cycle\) is not supported"),
])
def test_what_this_machine_cannot_simulate_is_refused_by_name_with_file_line_and_column(text: str,
                                                                                        message: str) -> None:
    with pytest.raises(ConfigurationError, match=message):
        read_program(text, source="p.nc", axes="xyz")


def test_allow_unsupported_skips_only_the_word_never_the_geometry_words_on_its_line() -> None:
    """The issue's case: ``G17 G20 G90 G94 G54 M0 M5 M9`` lost its G20. Here M101 goes, G20 stays."""
    path = read_program("G17 G20 G90 G94 G54 M101 M5 M9\nG0 X1\nM2\n", source="p.nc", allow_unsupported=True)
    assert path.skipped == ("p.nc:1:21: M101: M101 is a user M code (a program M101 that LinuxCNC runs from its "
                            "configuration): cosim cannot run it; word skipped",)
    assert [s.end for s in path.steps if isinstance(s, Line)] == [(F(254, 10), 0, 0)]  # X1 inch = 25.4 mm
    probe = read_program("G21 G38.2 Z-5 F100\nG0 X2\nM2\n", source="p.nc", allow_unsupported=True)
    assert probe.skipped[0].startswith("p.nc:1:5: G38.2 and its axis words: G38.2 needs a probe input")
    assert [s.end for s in probe.steps if isinstance(s, Line)] == [(2, 0, 0)]


def test_a_file_without_m2_m30_or_percent_is_reported_as_linuxcnc_does() -> None:
    """LinuxCNC: "File ended with no percent sign or program end". The moves run; the end is marked missing."""
    assert read_program("G0 X1\n").ending == ""
    assert read_program("G0 X1\nM30\n").ending == "M30"
    assert read_program("%\nG0 X1\n%\nG0 X99\n").ending == "%"
    assert [s.end for s in read_program("%\nG0 X1\n%\nG0 X99\n").steps if isinstance(s, Line)] == [(1, 0, 0)]


# -- the tool path in machine units -------------------------------------------------------------
def test_absolute_incremental_units_and_feeds_in_machine_units() -> None:
    path = read_program("G21 G90 G0 X10 Y5\nG91 G1 X2.5 Z-1 F600\nG20 G1 X1 F10\nG90 Y0\n")
    assert [s for s in path.steps if isinstance(s, Line)] == [
        Line((F(10), F(5), F(0)), None, 1),
        Line((F(25, 2), F(5), F(-1)), F(10), 2),  # F600 mm/min = 10 mm/s
        Line((F(25, 2) + F(254, 10), F(5), F(-1)), F(254, 10) * 10 / 60, 3),  # 1 inch incremental, F10 in/min
        Line((F(25, 2) + F(254, 10), F(0), F(-1)), F(254, 10) * 10 / 60, 4),  # G90 Y0: inches, still Y 0
    ]
    inch = read_program("G21 G0 X25.4\n", units="inch")
    assert inch.steps[0] == Line((F(1), F(0), F(0)), None, 1)


def test_g92_sets_the_current_point_and_later_moves_are_offset() -> None:
    path = read_program("G0 X10 Y10\nG92 X0 Y0\nG0 X5\nG1 Y-2 F60\n")
    assert [s.end for s in path.steps if isinstance(s, Line)] == [(10, 10, 0), (15, 10, 0), (15, 8, 0)]
    assert path.end == (15, 8, 0)


def test_arcs_ij_and_r_forms_and_full_circles() -> None:
    path = read_program("G0 X10 Y0\nG3 X0 Y10 I-10 J0 F600\nG2 X10 Y0 R10\nG3 X0 Y10 R-10\nG3 I-10\n"
                        "G2 X0 Y10 Z-3 I10 J0\n")
    arcs = [s for s in path.steps if isinstance(s, Arc)]
    assert arcs[0].center == (0, 0) and not arcs[0].clockwise and arcs[1].clockwise
    # G2 R10 from (0, 10) to (10, 0): the quarter turn clockwise around (0, 0);
    # G3 R-10 back to (0, 10): the three-quarter turn counter-clockwise around (10, 10)
    assert tuple(float(c) for c in arcs[1].center) == pytest.approx((0, 0), abs=1e-12)
    assert tuple(float(c) for c in arcs[2].center) == pytest.approx((10, 10), abs=1e-12)
    assert arcs[3].end == (0, 10, 0) and arcs[3].center == (-10, 10)  # full circle with I only
    assert arcs[4].end == (0, 10, -3) and arcs[4].center == (10, 10)  # a helical full turn


def test_spindle_words_and_dwell_become_records_and_m2_ends_the_program() -> None:
    path = read_program("M3 S12000\nG4 P0.5\nS8000\nM5\nM4\nM2\nG0 X99\n")
    assert path.steps == (Spindle(True, False, F(12000), 1), Pause(F(1, 2), 2), Spindle(True, False, F(8000), 3),
                          Spindle(False, False, F(8000), 4), Spindle(True, True, F(8000), 5),
                          Spindle(False, False, F(8000), 6))  # M2 stops the spindle (LinuxCNC's program end)


@pytest.mark.parametrize(("text", "message"), [
    ("G0 X1\nG1 X2\n", r"^p.nc:2:1: Cannot do G1 with zero feed rate"),
    ("G1 X2 F0\n", r"^p.nc:1:1: Cannot do G1 with zero feed rate"),
    ("G0 X10\nG2 X0 Y0 I-4 J0 F100\n", r"^p.nc:2:10: Radius to end of arc differs from radius to start: G2 "
                                        r"start=\(X10.0000,Y0.0000\) center=\(X6.0000,Y0.0000\) "
                                        r"end=\(X0.0000,Y0.0000\) r1=4.0000 r2=6.0000"),
    ("G0 X10\nG2 X0 Y0 R4 F100\n", r"^p.nc:2:10: G2 R4: Arc radius too small to reach end point \(the end is 10 "
                                   r"away: R must be at least 5\)"),
    ("G0 X10\nG2 X10 R4 F100\n", r"^p.nc:2:8: G2 R4: Current point same as end point of arc"),
    ("G2 X10 Y1 F100\n", r"^p.nc:1:1: I and J words missing for arc in xy plane"),
    ("G2 X10 R5 I5 F100\n", r"^p.nc:1:8: G2: give the centre one way, R or IJ"),
    ("G2 X0 I0 J0 F100\n", r"^p.nc:1:7: Zero radius arc"),
    ("X10\n", r"^p.nc:1:1: Cannot use axis values without a G code that uses them"),
    ("G4\n", r"^p.nc:1:1: Dwell time missing with G4"),
    ("G4 P-1\n", r"^p.nc:1:1: Dwell time P-1 is negative"),
    ("G92\n", r"^p.nc:1:1: All axes missing with G92"),
    ("G1 X1 P2 F10\n", r"^p.nc:1:7: P word with nothing on the line that uses it"),
    ("G1 X1 I2 F10\n", r"^p.nc:1:7: I word with nothing on the line that uses it"),
    ("G17 K1 G2 X1 I1 F1\n", r"^p.nc:1:5: K word given for arc in xy plane"),
    ("G0 G1 X1\n", r"^p.nc:1:4: G0 and G1: two G codes from the same modal group \(motion\)"),
    ("M3 M5\n", r"^p.nc:1:4: M3 and M5: two M codes from the same modal group"),
    ("G1 X1 X2 F1\n", r"^p.nc:1:7: Multiple X words on one line"),
    ("G99.5\n", r"^p.nc:1:1: Unknown G code used: G99.5"),
])
def test_bad_programs_are_refused_before_anything_runs_with_linuxcncs_reason(text: str, message: str) -> None:
    with pytest.raises(ConfigurationError, match=message):
        read_program(text, source="p.nc")


def test_an_end_point_within_linuxcncs_tolerance_makes_a_slight_spiral() -> None:
    """LinuxCNC 2.9 refuses when the radii differ by more than 0.02 * sqrt(2) mm (0.002 * sqrt(2) in) *and* 0.1 %
    (rs274: a 10 mm arc ending at Y10.028 runs, at Y10.029 it is refused; at 100 mm, 100.1 runs, 100.11 not)."""
    path = read_program("G0 X10\nG3 X0 Y10.028 I-10 J0 F100\n")
    assert path.end == (0, F(10028, 1000), 0)
    with pytest.raises(ConfigurationError, match="Radius to end of arc differs"):
        read_program("G0 X10\nG3 X0 Y10.029 I-10 J0 F100\n")
    read_program("G0 X100\nG3 X0 Y100.1 I-100 J0 F100\n")
    with pytest.raises(ConfigurationError, match="Radius to end of arc differs"):
        read_program("G0 X100\nG3 X0 Y100.11 I-100 J0 F100\n")
    read_program("G20 G0 X1\nG3 X0 Y1.0028 I-1 J0 F1\n")
    with pytest.raises(ConfigurationError, match=r"allowed: 0.002828 in or 0.1 %"):
        read_program("G20 G0 X1\nG3 X0 Y1.0029 I-1 J0 F1\n")


def test_the_canonical_program_is_the_layer_between_text_and_tool_path() -> None:
    program = canonical(read_text("G21 G0 X1\nG1 Y2 F60\nM2\n"))
    assert [(c.name, c.args[:3]) for c in program.motion()] == [("STRAIGHT_TRAVERSE", (1, 0, 0)),
                                                                 ("STRAIGHT_FEED", (1, 2, 0))]
    assert program.end == "M2" and program.calls[-1].name == "PROGRAM_END"
