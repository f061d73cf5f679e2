"""G-code text into checked blocks and a tool path: the LinuxCNC milling subset, every refusal with file:line.

    pocket.nc ──read_text──> Blocks (words, exact values) ──interpret──> Toolpath (machine units)
                  └─ unsupported word, letter twice, not G-code: "pocket.nc:LINE: reason"
"""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import pytest

from cosim.controllers.pokeys.gcode import load_program, read_program, read_text
from cosim.controllers.pokeys.toolpath import Arc, Line, Pause, Spindle
from cosim.errors import ConfigurationError

F = Fraction


def test_words_comments_line_numbers_and_case_are_read_exactly() -> None:
    blocks = read_text("%\nN10 g1 x-2.5 Y.25 (a comment) f1200 ; the rest is a comment\n\n(only a comment)\n"
                       "N20G0X1Z 3\n%\n", source="p.nc")
    assert [b.line for b in blocks.blocks] == [2, 5]
    first = blocks.blocks[0]
    assert [(w.letter, w.value) for w in first.words] == [("N", 10), ("G", 1), ("X", F(-5, 2)), ("Y", F(1, 4)),
                                                          ("F", 1200)]
    assert blocks.blocks[1].get("Z") == 3 and blocks.blocks[1].codes("G") == [0]


def test_codes_of_different_modal_groups_share_a_line() -> None:
    (block,) = read_text("G90 G21 G17 G40 G49 G80 G94 G54\n").blocks
    assert block.codes("G") == [90, 21, 17, 40, 49, 80, 94, 54]


@pytest.mark.parametrize(("text", "message"), [
    ("G0 X1\nG5 X2\n", r"^p.nc:2: G5 is not supported \(supported: G0, G1, G2, G3, G4, G92, G17, G20, G21"),
    ("G0 X1\nM7\n", r"^p.nc:2: M7 is not supported \(supported: M3, M4, M5, M2, M30\)"),
    ("G61.1\n", r"^p.nc:1: G61.1 is not supported"),
    ("G18\n", r"^p.nc:1: G18 is not supported"),
    ("M6 T1\n", r"^p.nc:1: M6 is not supported"),
    ("T1\n", r"^p.nc:1: the word T1 is not supported \(letters: G, M, X, Y, Z, I, J, R, F, S, P, N"),
    ("G1 A10 F100\n", r"^p.nc:1: the word A10 is not supported"),
    ("G2 X1 K3 F100\n", r"^p.nc:1: K3 is not supported \(arcs are in the XY plane"),
    ("G1 X1 X2 F100\n", r"^p.nc:1: X appears twice \(X1 and X2\): one word per letter per line"),
    ("G0 G1 X1\n", r"^p.nc:1: G0 and G1 are both motion codes: one per line"),
    ("M3 M5\n", r"^p.nc:1: M3 and M5 are both spindle codes"),
    ("G0 X#1\n", r"^p.nc:1: not G-code: unexpected '#' at column 5 \(parameters are not supported\)"),
    ("G0 X[1+2]\n", r"^p.nc:1: not G-code: unexpected '\[' at column 5 \(expressions are not supported\)"),
    ("G0 X1 (open\n", r"^p.nc:1: not G-code: unexpected '\(' at column 7 \(a comment is not closed"),
    ("/G0 X1\n", r"^p.nc:1: not G-code: unexpected '/' at column 1 \(block delete is not supported\)"),
    ("G0 X\n", r"^p.nc:1: not G-code: the letter 'X' at column 4 is followed by the end of the line, not a number"),
    ("[machine]\nuntil = 1\n", r"^p.nc:1: not G-code: unexpected '\['"),
    ("def main():\n", r"^p.nc:1: not G-code: the letter 'D' at column 1 is followed by 'e', not a number"),
])
def test_unsupported_words_and_text_that_is_not_gcode_are_refused_with_file_and_line(text: str,
                                                                                    message: str) -> None:
    with pytest.raises(ConfigurationError, match=message):
        read_program(text, source="p.nc")


def test_a_binary_file_is_not_gcode(tmp_path: Path) -> None:
    path = tmp_path / "job.nc"
    path.write_bytes(b"G0 X1\nPNG\x00\x01")
    with pytest.raises(ConfigurationError, match=r"job.nc:2: not G-code: the file holds NUL bytes"):
        load_program(path)
    path.write_bytes(b"G0 X1\nG1 X\xff\n")
    with pytest.raises(ConfigurationError, match=r"job.nc:2: not G-code: not a UTF-8 text file \(byte 0xff"):
        load_program(path)


def test_with_allow_unsupported_a_line_is_skipped_and_listed() -> None:
    path = read_program("G21 G90\nM6 T1\nG0 X1\nM8\nG1 X2 F60\n", source="p.nc", allow_unsupported=True)
    assert path.skipped == ("p.nc:2: M6 is not supported (supported: M3, M4, M5, M2, M30); line skipped",
                            "p.nc:4: M8 is not supported (supported: M3, M4, M5, M2, M30); line skipped")
    assert [s.end[0] for s in path.steps if isinstance(s, Line)] == [1, 2]
    with pytest.raises(ConfigurationError, match=r"p\.nc:2: not G-code"):  # a syntax error is never skipped
        read_program("G0 X1\nG0 X#2\n", source="p.nc", allow_unsupported=True)


# -- interpretation -----------------------------------------------------------------------------
def test_absolute_incremental_units_and_feeds_in_machine_units() -> None:
    path = read_program("G21 G90 G0 X10 Y5\nG91 G1 X2.5 Z-1 F600\nG20 G1 X1 F10\nG90 Y0\n")
    assert path.steps == (
        Line((F(10), F(5), F(0)), None, 1),
        Line((F(25, 2), F(5), F(-1)), F(10), 2),  # F600 mm/min = 10 mm/s
        Line((F(25, 2) + F(254, 10), F(5), F(-1)), F(254, 10) * 10 / 60, 3),  # 1 inch incremental, F10 in/min
        Line((F(25, 2) + F(254, 10), F(0), F(-1)), F(254, 10) * 10 / 60, 4),
    )
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
                          Spindle(False, False, F(8000), 4), Spindle(True, True, F(8000), 5))


@pytest.mark.parametrize(("text", "message"), [
    ("G0 X1\nG1 X2\n", r"^p.nc:2: G1 with no feed rate: give F"),
    ("G0 X1\nG2 X2 I1 J0\n", r"^p.nc:2: G2 with no feed rate"),
    ("G1 X2 F0\n", r"^p.nc:1: G1 with feed rate F0: a feed move needs F > 0"),
    ("G0 X10\nG2 X0 Y0 I-4 J0 F100\n", r"^p.nc:2: G2: the end point is not on the arc: radius to the start 4, "
                                        r"to the end 6 \(they differ by 2; allowed: 0.005 machine units\)"),
    ("G0 X10\nG2 X0 Y0 R4 F100\n", r"^p.nc:2: G2 R4: the radius is too small to reach the end point \(the end "
                                   r"is 10 away: R must be at least 5\)"),
    ("G0 X10\nG2 X10 R4 F100\n", r"^p.nc:2: G2 R4 with the end point on the start point: an R arc cannot be a "
                                 r"full circle"),
    ("G2 X10 Y1 F100\n", r"^p.nc:1: G2 needs I and J \(centre offsets\) or R"),
    ("G2 X10 R5 I5 F100\n", r"^p.nc:1: G2 with both R and I/J"),
    ("G2 X0 I0 J0 F100\n", r"^p.nc:1: G2 with a zero radius"),
    ("X10\n", r"^p.nc:1: axis words with no motion mode: give G0, G1, G2 or G3 first"),
    ("G4\n", r"^p.nc:1: G4 needs P, the dwell time in seconds"),
    ("G4 P-1\n", r"^p.nc:1: G4 P-1: the dwell time is >= 0 s"),
    ("G0 G4 P1 X3\n", r"^p.nc:1: G4 with axis words: a dwell does not move"),
    ("G92\n", r"^p.nc:1: G92 needs axis words"),
    ("G1 X1 P2 F10\n", r"^p.nc:1: P without G4: P is the dwell time of G4"),
    ("G1 X1 I2 F10\n", r"^p.nc:1: I, J or R on a straight move \(G1\)"),
    ("G0 X1\nI2\n", r"^p.nc:2: I, J or R without an arc"),
])
def test_bad_programs_are_refused_before_anything_runs(text: str, message: str) -> None:
    with pytest.raises(ConfigurationError, match=message):
        read_program(text, source="p.nc")


def test_an_end_point_within_the_tolerance_makes_a_slight_spiral() -> None:
    """LinuxCNC's tolerance: 0.005 mm (0.0005 in); the arc ends exactly on the programmed point."""
    path = read_program("G0 X10\nG3 X0 Y10.004 I-10 J0 F100\n")
    assert path.end == (0, F(10004, 1000), 0)
    with pytest.raises(ConfigurationError, match="not on the arc"):
        read_program("G0 X10\nG3 X0 Y10.006 I-10 J0 F100\n")
    with pytest.raises(ConfigurationError, match=r"allowed: 0.0005 machine units"):
        read_program("G0 X1\nG3 X0 Y1.0006 I-1 J0 F1\n", units="inch")
