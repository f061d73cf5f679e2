"""PMAC text: one grammar for online commands and buffers; every error names file:line:column before anything runs."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import pytest

from cosim.cli import main
from cosim.controllers.pmac import Pmac
from cosim.controllers.pmac.nodes import (
    Assign,
    If,
    MDefine,
    MotorDef,
    Num,
)
from cosim.controllers.pmac.program import MAX_BLOCKS, Jump, JumpUnless, MoveStmt, Sub, parse_text
from cosim.controllers.pmac.syntax import MAX_PARENS, parse_line
from cosim.errors import ConfigurationError
from cosim.kernel import Simulation
from cosim.plants.analytic import IdealConveyor

SETUP = """\
I8000=$078008 I8001=$403501 I8002=2048 I5193=@I8002 I5194=8388607
&1 #1->1X #2->10Y
M103->X:$07800B,0,24,S
"""


def _pmac(sim: Simulation) -> Pmac:
    pmac = Pmac(sim)
    pmac.add_channel(0x078008, IdealConveyor(sim, speed_counts_per_ms=64))
    pmac.load(SETUP, source="setup.pmc")
    return pmac


def test_a_file_mixes_online_commands_and_buffers_in_order() -> None:
    text = ("CLOSE\nI5194=8388607\n&1 #1->1000X\nOPEN PROG 7 CLEAR\nLINEAR ABS TA20 F64000\n X1000 Y(P1+2)\n"
            "N10 IF (M103 != 0) P1=P1+1\nGOTO10\nCLOSE\nOPEN PLC 2\nCLEAR\nENABLE PLC 2\nCLOSE\n")
    parsed = parse_text(text, source="cell.pmc")
    kinds = [type(item).__name__ for item in parsed.items]
    assert kinds == ["Assign", "CsSelect", "MotorDef", "Buffer", "Buffer"]
    motor = parsed.items[2]
    assert isinstance(motor, MotorDef) and (motor.motor, motor.scale, motor.axis) == (1, 1000, "X")
    prog, plc = parsed.buffers()
    assert (prog.kind, prog.number, prog.clear, plc.kind, plc.number, plc.clear) == ("PROG", 7, True, "PLC", 2, True)
    code = prog.code.instrs
    # LINEAR, ABS, TA, F | move X Y | IF test, P1=P1+1 | GOTO 10 (back to the IF test)
    assert isinstance(code[4], MoveStmt) and [w.axis for w in code[4].axes] == ["X", "Y"]
    assert isinstance(code[5], JumpUnless) and code[5].target == 7 and isinstance(code[6], Assign)
    assert isinstance(code[7], Jump) and (code[7].target, code[7].back) == (5, True)
    assert prog.code.labels == {10: 5}


def test_blocks_compile_to_jumps() -> None:
    """IF/ELSE/ENDIF and WHILE/ENDWHILE, block and one-line forms, and a one-line ELSE."""
    text = ("OPEN PLC 1 CLEAR\n"
            "IF (P1 > 0)\n P2=1\nELSE\n P2=2\nENDIF\n"       # 0: test->4, 1: P2=1, 2: jump->5, 3: P2=2 (4 is ELSE body)
            "WHILE (P3 < 3) P3=P3+1\n"                        # 4: test->7, 5: P3=P3+1, 6: jump back->4
            "IF (P4=1) P5=1\nELSE P5=2\n"                    # 7: test->10, 8: P5=1, 9: jump->11, 10: P5=2
            "N20 GOSUB20 RETURN\nCLOSE\n")
    (plc,) = parse_text(text).buffers()
    code = plc.code.instrs
    tests = {i: c.target for i, c in enumerate(code) if isinstance(c, JumpUnless)}
    jumps = {i: (c.target, c.back) for i, c in enumerate(code) if isinstance(c, Jump)}
    assert tests == {0: 3, 4: 7, 7: 10}
    assert jumps == {2: (4, False), 6: (4, True), 9: (11, False)}
    assert isinstance(code[11], Sub) and code[11].target == 11


def test_case_comments_spacing_and_every_line_end() -> None:
    """Keywords in any case, ; comments, X1000Y500 without spaces; LF, CR LF, CR, FF, VT and NEL all end lines."""
    for eol in ("\n", "\r\n", "\r", "\f", "\v", "\x85", "\u2028"):
        text = eol.join(["open prog 1 clear", "linear abs ta20 f100 ; comment", "x1000y500", "close", ""])
        (prog,) = parse_text(text, source="p.pmc").buffers()
        assert len(prog.code.instrs) == 5
    assert parse_text("\ufeffI10=3713707").items  # a byte-order mark is not a character of the text


def test_i_variable_constants_are_checked_where_they_are_written() -> None:
    stmts = parse_line("I5194=8388607 I8008=$9F8018 P1=-(3+4)*2", context="online", source="s", line=1)
    assert isinstance(stmts[2], Assign)
    values = [s.expr.value for s in stmts[:2] if isinstance(s, Assign) and isinstance(s.expr, Num)]
    assert values == [8388607, 0x9F8018]


@pytest.mark.parametrize(
    ("text", "message"),
    [
        # unknown command, in an online line and in a buffer
        ("I10=3713707\nFROB 3", r"^bad.pmc:2:1: unknown command 'FROB'$"),
        ("OPEN PROG 1\nLINEAR\n  TA10 FEED100\nCLOSE", r"^bad.pmc:3:8: unknown command 'FEED100'$"),
        ("LINEAR X100", r"^bad.pmc:1:1: 'LINEAR' is a program statement: write it between OPEN PROG n"),
        ("OPEN PROG 1\n&1 B1 R\nCLOSE", r"^bad.pmc:2:1: '&1' is an online command, not allowed inside a program"),
        ("P1=1e5", r"^bad.pmc:1:5: syntax error: unexpected 'e5' \(PMAC numbers are written without an exponent\)"),
        ("OPEN PROG 1\nX(1+\nCLOSE", r"^bad.pmc:2:5: the statement is incomplete at the end of the line$"),
        # variables out of their range
        ("P8192=1", r"^bad.pmc:1:1: P-variable number = 8192 is not allowed \(allowed: 0..8191\)$"),
        ("OPEN PLC 1\nP1=M9000\nCLOSE", r"^bad.pmc:2:4: M-variable number = 9000 is not allowed \(allowed: 0..8191\)$"),
        ("OPEN PLC 1\nI5194=9000000\nCLOSE",
         r"^bad.pmc:2:1: I5194 \(Ix94, time-base slew limit\) = 9000000 is not allowed \(allowed: integers 0..8388607"),
        ("OPEN PLC 1\nI130=9000000\nCLOSE", r"^bad.pmc:2:1: I130 \(Ixx30, PID proportional gain\) = 9000000 is not "
                                           r"allowed \(allowed: integers -8388608..8388607\)$"),
        ("&17", r"^bad.pmc:1:1: coordinate system &n = 17 is not allowed \(allowed: 1..16\)$"),
        ("#33->X", r"^bad.pmc:1:1: motor #n = 33 is not allowed \(allowed: 1..32\)$"),
        ("OPEN PLC 32\nCLOSE", r"^bad.pmc:1:1: PLC number = 32 is not allowed \(allowed: 0..31\)$"),
        ("M1->X:$078000,20,8", r"^bad.pmc:1:1: M1 width = 8 is not allowed \(allowed: 1..4: offset \+ width <= 24"),
        ("P1=123456789012345678",
         r"^bad.pmc:1:4: number = 123456789012345678 is not allowed \(allowed: at most 15 integer and 30 fraction"),
        ("P1=$FFFFFFFFFFFF",
         r"^bad.pmc:1:4: \$FFFFFFFFFFFF = 2.81475e\+14 is not allowed \(allowed: \|value\| < 2\^47"),
        # CLOSE missing, blocks, labels
        ("OPEN PROG 3 CLEAR\nX10\n", r"^bad.pmc:1:1: OPEN PROG 3 has no CLOSE \(the file ends inside the buffer\)$"),
        # a buffer on one line needs its CLOSE there or later; after CLOSE the line is online commands again
        ("OPEN PROG 1 CLEAR X10", r"^bad.pmc:1:1: OPEN PROG 1 has no CLOSE \(the file ends inside the buffer\)$"),
        ("OPEN PLC 1 CLEAR P1=1 CLOSE X10", r"^bad.pmc:1:29: 'X10' is a program statement: write it between OPEN"),
        ("OPEN PROG 1\nCLOSE X10", r"^bad.pmc:2:7: 'X10' is a program statement: write it between OPEN PROG n"),
        # fuzzing found it: a rotary buffer takes no number, what follows is its content
        ("OPEN ROTARY 8388607", r"^bad.pmc:1:13: OPEN ROTARY 8388607: a rotary buffer takes no number \(OPEN ROTARY "
                                r"opens every coordinate system's rotary buffer; &n chooses"),
        ("CLEAR", r"^bad.pmc:1:1: CLEAR outside a buffer"),
        ("OPEN PLC 1\nIF (P1=1)\nP2=1\nCLOSE", r"^bad.pmc:2:1: IF without ENDIF in PLC 1$"),
        ("OPEN PLC 1\nWHILE (P1<1)\nENDIF\nCLOSE",
         r"^bad.pmc:3:1: ENDIF without IF \(the open block is the WHILE at bad.pmc:2:1\)$"),
        ("OPEN PLC 1\nELSE\nCLOSE", r"^bad.pmc:2:1: ELSE without IF$"),
        ("OPEN PROG 1\nN10 X1\nGOTO 20\nCLOSE",
         r"^bad.pmc:3:1: GOTO 20 jumps into nothing: PROG 1 has no label N20 \(its labels: N10\)$"),
        ("OPEN PLC 1\nGOSUB 5\nCLOSE", r"^bad.pmc:2:1: GOSUB 5 jumps into nothing: PLC 1 has no label N5"),
        ("OPEN PROG 1\nN1 X1\nN1 X2\nCLOSE", r"^bad.pmc:3:1: label N1 appears twice in PROG 1$"),
        ("OPEN PROG 1\nX1 Y2 X3\nCLOSE", r"^bad.pmc:2:7: axis X appears twice in one move$"),
        ("OPEN PLC 1\nLINEAR\nCLOSE", r"^bad.pmc:2:1: LINEAR is a motion-program statement, not allowed in PLC 1$"),
        ("OPEN PLC 1\nX10\nCLOSE", r"^bad.pmc:2:1: a move is a motion-program statement, not allowed in PLC 1$"),
        ("OPEN PLC 1\nCMD\"&1 LINEAR\"\nCLOSE",
         r"^bad.pmc:2:8: 'LINEAR' is a program statement: write it between OPEN PROG n"),
        # nesting depth
        ("P1=" + "(" * (MAX_PARENS + 1) + "1" + ")" * (MAX_PARENS + 1),
         rf"^bad.pmc:1:{4 + MAX_PARENS}: parentheses nested deeper than {MAX_PARENS} levels$"),
        ("OPEN PLC 1\n" + "IF (P1=1)\n" * (MAX_BLOCKS + 1) + "ENDIF\n" * (MAX_BLOCKS + 1) + "CLOSE",
         rf"^bad.pmc:{2 + MAX_BLOCKS}:1: IF/WHILE nested deeper than {MAX_BLOCKS} levels$"),
        ("OPEN PLC 1\n" + "IF (P1=1) " * (MAX_BLOCKS + 1) + "P1=2\nCLOSE",
         rf"^bad.pmc:2:{1 + 10 * MAX_BLOCKS}: IF/WHILE nested deeper than {MAX_BLOCKS} levels$"),
    ],
)
def test_bad_text_is_refused_with_file_line_and_column(text: str, message: str) -> None:
    with pytest.raises(ConfigurationError, match=message):
        parse_text(text, source="bad.pmc")


@pytest.mark.parametrize(
    ("program", "commands", "message"),
    [
        # a move on an axis not defined in the coordinate system that runs the program
        ("OPEN PROG 1\nX10 Z5\nCLOSE", "&1 B1 R", r"^prog.pmc:2:5: axis Z is not defined in coordinate system 1 "
                                                r"\(its axes: X, Y; define one with &1 #n->Z\)$"),
        ("OPEN PROG 1\nX10\nCLOSE", "&2 B1 R", r"^prog.pmc:2:1: axis X is not defined in coordinate system 2 "
                                              r"\(its axes: none"),
        ("OPEN PROG 1\nCALL 2\nCLOSE\nOPEN PROG 2\nZ1\nCLOSE", "&1 B1",
         r"^prog.pmc:5:1: axis Z is not defined in coordinate system 1"),
        # jumps into nothing across buffers
        ("OPEN PROG 1\nCALL 9\nCLOSE", "", r"^prog.pmc:2:1: PROG 9 does not exist \(motion programs: 1\)$"),
        ("OPEN PROG 1\nX1\nCLOSE", "&1 B4 R", r"^cmd:1:4: PROG 4 does not exist \(motion programs: 1\)$"),
        ("OPEN PLC 1\nCMD\"&1B5R\"\nCLOSE", "", r"^prog.pmc:2:7: PROG 5 does not exist"),
        # an M-variable that nothing defines, or that names a register the model does not have
        ("OPEN PLC 1\nP1=M7\nCLOSE", "", r"^prog.pmc:2:4: M7 is not defined \(define it first"),
        # G, M, T, D codes call PROG 1000..1003 at label N(code * 1000)
        ("OPEN PROG 1\nG1\nCLOSE", "", r"^prog.pmc:2:1: PROG 1000 does not exist \(motion programs: 1\)$"),
    ],
)
def test_errors_that_need_the_whole_machine_are_found_before_the_run(sim: Simulation, program: str, commands: str,
                                                                     message: str) -> None:
    pmac = _pmac(sim)
    with pytest.raises(ConfigurationError, match=message):
        pmac.load(program, source="prog.pmc")
        lines = [pmac.programs.parse_command(commands, source="cmd")] if commands else []
        pmac.programs.check_commands(lines)
        pmac.start()
    assert sim.now == 0


def test_a_bad_file_applies_nothing(sim: Simulation) -> None:
    """The whole file is parsed before any of it is applied."""
    pmac = Pmac(sim)
    with pytest.raises(ConfigurationError, match=r"^s.pmc:3:1: unknown command 'FROB'"):
        pmac.load("I5194=1000\nOPEN PLC 1\nFROB\nCLOSE", source="s.pmc")
    assert pmac.cs == {} and pmac.programs.plcs == {}


def test_m_variable_definitions() -> None:
    (stmt,) = parse_line("M8008->Y:$3509,20,4", context="online", source="s", line=1)
    assert isinstance(stmt, MDefine) and stmt.target is not None
    assert (stmt.target.space, stmt.target.address, stmt.target.offset, stmt.target.width, stmt.target.signed) == (
        "Y", 0x3509, 20, 4, False)
    (plain,) = parse_line("M1->*", context="online", source="s", line=1)
    assert isinstance(plain, MDefine) and plain.target is None


def test_one_line_if_governs_the_rest_of_its_line() -> None:
    stmts = parse_line("IF (I8008=$9F8018) I8008=$BF8018 P1=P1+1", context="program", source="s", line=1)
    assert isinstance(stmts[0], If) and stmts[0].inline
    (prog,) = parse_text("OPEN PLC 1\nIF (I8008=$9F8018) I8008=$BF8018 P1=P1+1\nP2=1\nCLOSE").buffers()
    test = prog.code.instrs[0]
    assert isinstance(test, JumpUnless) and test.target == 3  # skips both statements, not P2=1


PLANTLESS_MACHINE = """\
[machine]
until = "10 ms"
[controller]
family = "pmac"
setup = ["setup.pmc"]
[[program]]
file = "prog.pmc"
[[command]]
at = "0 ms"
text = "&1 B1 R"
"""


@pytest.mark.parametrize(
    ("program", "message"),
    [
        ("OPEN PROG 1\nX10 Z5\nCLOSE\n", "prog.pmc:2:5: axis Z is not defined in coordinate system 1"),
        ("OPEN PROG 1\nX10\n", "prog.pmc:1:1: OPEN PROG 1 has no CLOSE"),
        ("OPEN PROG 1\nGOTO 7\nCLOSE\n", "prog.pmc:2:1: GOTO 7 jumps into nothing"),
        ("OPEN PROG 1\nSTOPP\nCLOSE\n", "prog.pmc:2:1: unknown command 'STOPP'"),
        ("OPEN PROG 1\nP9999=1\nCLOSE\n", "prog.pmc:2:1: P-variable number = 9999 is not allowed"),
    ],
)
def test_bad_programs_exit_2_through_cosim_run_with_nothing_run(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                                program: str, message: str) -> None:
    (tmp_path / "setup.pmc").write_text("&1 #1->1X\n")
    (tmp_path / "prog.pmc").write_text(program)
    (tmp_path / "m.toml").write_text(PLANTLESS_MACHINE)
    assert main(["run", str(tmp_path / "m.toml"), "--out", str(tmp_path / "out")]) == 2
    assert message in capsys.readouterr().out
    import json

    result = json.loads((tmp_path / "out" / "result.json").read_text())
    assert result["verdict"] == "ERROR" and result["simulated_s"] == 0
    assert main(["check-machine", str(tmp_path / "m.toml")]) == 2


def test_constant_expressions_are_exact() -> None:
    (stmt,) = parse_line("P1=(1/3+1/6)*$10-INT(-2.5)+ABS(-0.25)", context="online", source="s", line=1)
    from cosim.controllers.pmac.nodes import constant

    assert isinstance(stmt, Assign) and constant(stmt.expr) == Fraction(8) + 3 + Fraction(1, 4)
