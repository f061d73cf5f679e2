"""Trio BASIC as real programs use it: expressions, blocks, loops, GOSUB/GOTO, WAIT, TICKS, PRINT, I/O.

Documented behaviour written as literals: TRM 8-146 (``10 OR 18.9`` is 26), 8-149 (``10 XOR (2.1*9)`` is
24), 8-137 (comparisons give TRUE = -1 and FALSE = 0; ``maybe = 1 <= 0`` is 0), the OR example
``IF KEY OR IN(0) = ON`` (a comparison binds tighter than OR), TRM 8-30 (DEFPOS at the next servo tick).
"""

from __future__ import annotations

from collections.abc import Generator
from fractions import Fraction
from typing import Any

import pytest

from cosim.controllers.trio import TrioController
from cosim.controllers.trio.basic import BasicProgram
from cosim.errors import ConfigurationError
from cosim.kernel import Simulation
from cosim.timebase import Priority

MS = 1_000_000


def run(text: str, *, until_ms: int = 5, trio: TrioController | None = None) -> TrioController:
    if trio is None:
        trio = TrioController(Simulation(seed=1), encoder_at_atype=0)
    BasicProgram.parse(text, name="t.bas").start(trio)
    trio.sim.run(until=until_ms * MS)
    return trio


def values(text: str, count: int) -> list[int | Fraction]:
    """Run ``text`` (which stores its results in VR(0), VR(1), ...) and return the first ``count`` VRs."""
    trio = run(text)
    return [trio.vr(k) for k in range(count)]


@pytest.mark.parametrize(("expression", "value"), [
    ("2 + 3 * 4 - 6 / 2", 11),              # * and / before + and -
    ("-2 * 3 + 1", -5),
    ("(2 + 3) * 4", 20),
    ("7 / 2", Fraction(7, 2)),              # exact division
    ("10 OR (2.1 * 9)", 26),                # TRM 8-146: bitwise on the integer parts, 01010 OR 10010
    ("10 XOR (2.1 * 9)", 24),               # TRM 8-149
    ("10 XOR 2.1 * 9", 24),                 # * binds tighter than XOR
    ("12 AND 10", 8),
    ("1 <= 0", 0),                          # TRM 8-137: FALSE is 0
    ("1 < 2", -1),                          # TRUE is -1
    ("4 OR 1 = 1", -1),                     # 4 OR (1 = 1): a comparison binds tighter than OR
    ("NOT 0", -1), ("NOT -1", 0), ("NOT 5", -6),   # bitwise on the integer part
    ("NOT 1 = 2", -1),                      # NOT (1 = 2)
    ("1 < 2 AND 3 < 4", -1),
    ("17 MOD 5 + 1", 3),
    ("ABS(-3.5) + INT(-2.7) + SGN(-4)", Fraction(1, 2)),  # 3.5 - 2 - 1
    ("SQR(16)", 4),
    ("$1F + .5e1", 36),
])
def test_expressions_follow_the_manuals_operators_and_precedence(expression: str, value: int | Fraction) -> None:
    assert values(f"VR(0) = {expression}\n", 1) == [value]


def test_sqr_of_a_non_square_is_rounded_down_to_the_variable_resolution() -> None:
    (r,) = values("VR(0) = SQR(2)\n", 1)
    assert r * r <= 2 < (r + Fraction(1, 2**32)) ** 2


@pytest.mark.parametrize(("text", "message"), [
    ("VR(0) = -7 MOD 2\n", r"t.bas line 1: MOD operand = -7 is not allowed \(allowed: >= 0"),
    ("VR(0) = 7 MOD 0\n", r"t.bas line 1: MOD by zero"),
    ("VR(0) = SQR(-1)\n", r"t.bas line 1: SQR argument = -1 is not allowed \(allowed: >= 0\)"),
    ("VR(-1) = 3\n", r"t.bas line 1: VR index = -1 is not allowed \(allowed: 0..1023\)"),
    ("VR(0) = VR(1024)\n", r"t.bas line 1: VR index = 1024 is not allowed \(allowed: 0..1023\)"),
    ("FOR i = 1 TO 3 STEP 0\nNEXT i\n", r"t.bas line 1: FOR STEP = 0 is not allowed \(allowed: not 0\)"),
    ("GOSUB a\na:\nRETURN\n", r"t.bas line 3: RETURN without GOSUB"),  # returns to a: and meets RETURN again
    ("GOTO inner\nFOR i = 1 TO 2\ninner:\nNEXT i\n", r"t.bas line 4: NEXT I without its FOR"),
    ("a:\nGOSUB a\n", r"t.bas line 2: GOSUB nesting = 65 is not allowed \(allowed: 1..64\)"),
])
def test_run_time_errors_name_the_line_and_the_allowed_values(text: str, message: str) -> None:
    with pytest.raises(ConfigurationError, match=message):
        run(text)


def test_vr_range_from_python() -> None:
    trio = TrioController(Simulation())
    with pytest.raises(ConfigurationError, match=r"^VR index = -1 is not allowed \(allowed: 0..1023\)$"):
        trio.vr(-1)
    assert TrioController(Simulation(), vr_size=16).vr(15) == 0


def test_if_elseif_else_endif_and_the_one_line_forms() -> None:
    text = """n = 0
FOR i = 1 TO 4
  IF i = 1 THEN
    TABLE(i, 10)
  ELSEIF i = 2 THEN
    TABLE(i, 20)
  ELSEIF i = 3 THEN
    TABLE(i, 30)
  ELSE
    TABLE(i, 40)
  ENDIF
  IF i > 2 THEN n = n + 1
  IF i = 4 THEN VR(0) = 1 ELSE VR(1) = VR(1) + 1
NEXT i
VR(2) = n
"""
    trio = run(text)
    assert trio.table_memory[1:5] == [10, 20, 30, 40]
    assert [trio.vr(k) for k in range(3)] == [1, 3, 2]


def test_a_one_line_if_followed_by_another_statement_on_its_line_is_refused() -> None:
    """On one line, ``IF c THEN a : b`` would run b whatever c is; the model refuses to guess."""
    with pytest.raises(ConfigurationError, match=r"t.bas line 2, column 17: a one-line IF governs one statement"):
        BasicProgram.parse("x = 1\nIF x THEN y=1 : VR(0)=2\nVR(1)=y\n", name="t.bas")


def test_for_loops_count_up_down_and_are_skipped_when_already_past_the_end() -> None:
    text = """a = 0
FOR i = 10 TO 1 STEP -3
  a = a * 100 + i
NEXT i
VR(0) = a
VR(1) = i
b = 0
FOR j = 5 TO 1
  b = 99
NEXT j
VR(2) = b
VR(3) = j
"""
    assert values(text, 4) == [10070401, -2, 0, 5]


def test_gosub_return_goto_and_labels() -> None:
    text = """n = 0
again:
GOSUB bump
IF n < 3 THEN GOTO again
GOTO finish
VR(1) = 99   ' never runs
bump:
  n = n + 1
  GOSUB twice
  RETURN
twice:
  VR(2) = VR(2) + 2
  RETURN
finish:
VR(0) = n
"""
    assert values(text, 3) == [3, 0, 6]


@pytest.mark.parametrize(("text", "message"), [
    ("GOTO nowhere\n", r"t.bas line 1, column 6: label NOWHERE is not defined \(labels: none\)"),
    ("a:\nb:\na:\n", r"t.bas line 3, column 1: label A is defined twice"),
    ("FOR i = 1 TO 2\nNEXT j\n", r"t.bas line 2, column 6: NEXT j closes FOR i"),
    ("RETURN:\n", r"t.bas line 1, column 1: RETURN is a keyword, not a label"),
    ("MOVECIRC(1, 2, 3, 4)\n", r"t.bas line 1, column 1: number of MOVECIRC arguments = 4 is not allowed \(allowed: "
                               r"5: MOVECIRC\(end1, end2, centre1, centre2, direction\)\)"),
    ("OP(8, ON, 3)\n", r"t.bas line 1, column 1: number of OP arguments = 3 is not allowed \(allowed: 1..2: "
                       r"OP\(output, ON/OFF\) or OP\(bit pattern\)\)"),
    ("x = IN(1, 2, 3)\nVR(0)=x\n", r"t.bas line 1, column 5: number of IN arguments = 3 is not allowed \(allowed: "
                                  r"0..2: IN\(input\) or IN\(first, last\)\)"),
    ("WA(1, 2)\n", r"t.bas line 1, column 1: number of WA arguments = 2 is not allowed \(allowed: 1: WA\(ms\)\)"),
    ("CANCEL(1, 2)\n", r"t.bas line 1, column 1: number of CANCEL arguments = 2 is not allowed \(allowed: 0..1: "
                       r"CANCEL or CANCEL\(1\)\)"),
    ("PWM_CONTROL(3, 1, ON)\n", r"t.bas line 1, column 1: number of PWM_CONTROL\(3\) arguments = 3 is not allowed "
                                r"\(allowed: 5, the mode and 4 more\)"),
    ("DATUM(3, 4)\n", r"t.bas line 1, column 1: number of DATUM arguments = 2 is not allowed \(allowed: 1: "
                      r"DATUM\(sequence 0..6\)\)"),
    ("MOVECIRC(1,2,3,4,0) AXIS(2)\n", r"t.bas line 1, column 21: MOVECIRC takes no AXIS\(\) modifier"),
    ("x = ON AXIS(2)\nVR(0)=x\n", r"t.bas line 1, column 5: ON is a constant; it takes no AXIS\(\)"),
    ("TICKS AXIS(1) = 3\n", r"t.bas line 1, column 1: TICKS is not an axis parameter"),
    ("PRINT #1 x\n", r"t.bas line 1, column 10: syntax error, unexpected 'x'"),
])
def test_bad_programs_are_refused_with_file_line_column_and_the_allowed_values(text: str, message: str) -> None:
    with pytest.raises(ConfigurationError, match=message):
        BasicProgram.parse(text, name="t.bas")


def test_wait_until_ticks_and_wa() -> None:
    """TICKS counts down once per servo tick (1 ms): TICKS = 5 at t = 0, WAIT UNTIL TICKS < 0 returns at 6 ms."""
    trio = run("TICKS = 5\nWAIT UNTIL TICKS < 0\nVR(0) = TICKS\nWDOG = ON\nWA(2.5)\nWDOG = OFF\nVR(1) = TICKS\n",
               until_ms=20)
    assert trio.sim.trace.edges("trio.wdog")[0].tolist() == [0, 6 * MS, 8_500_000]
    assert (trio.vr(0), trio.vr(1)) == (-1, -3)


def test_print_writes_lines_with_their_simulated_time_to_the_console_and_counts_them_in_the_trace() -> None:
    text = """x = 1 / 3
PRINT "x = "; x
PRINT "a", "b", 2
PRINT "no end";
WA(1)
PRINT " here"
PRINT
"""
    trio = run(text)
    lines = [(c.t, c.process, c.line, c.text) for c in trio.console.lines]
    assert lines == [(0, 1, 2, "x = 0.3333"), (0, 1, 3, "a\tb\t2.0000"), (MS, 1, 6, "no end here"), (MS, 1, 7, "")]
    assert trio.sim.trace.edges("trio.print")[0].tolist() == [0, 0, 0, MS, MS]  # the initial 0, then each line
    assert "t.bas:2  x = 0.3333" in trio.console.text()


def test_outputs_inputs_and_read_back() -> None:
    """OP(8, ON) at 0, OFF at 1 ms; input 3 driven from outside at 4.5 ms; WAIT UNTIL IN(3) = ON sees it at the
    5 ms servo tick and sets output 9."""
    sim = Simulation(seed=1)
    trio = TrioController(sim)
    BasicProgram.parse("OP(8, ON)\nVR(0) = READ_OP(8)\nWA(1)\nOP(8, OFF)\nVR(1) = OP(8)\n"
                       "WAIT UNTIL IN(3) = ON\nOP(9, ON)\n", name="io.bas").start(trio)
    assert [s.name for s in trio.io.inputs()] == ["trio.in.3"]  # created when the program starts: drivable
    assert len(trio.inputs()) == 32  # every input the controller has, for a machine file's stimuli

    def stimulus() -> Generator[Any, Any, None]:
        yield sim.at(4_500_000, Priority.HOST)
        trio.input(3).set(1)

    sim.process(stimulus())
    sim.run(until=10 * MS)
    assert sim.trace.edges("trio.op.8")[0].tolist() == [0, 0, MS]
    assert sim.trace.edges("trio.op.9")[0].tolist() == [0, 5 * MS]
    assert (trio.vr(0), trio.vr(1)) == (1, 0)
    assert {"trio.op.8", "trio.op.9"} <= {s.name for s in trio.outputs()}


def test_outputs_0_to_7_are_inputs_only() -> None:
    with pytest.raises(ConfigurationError, match=r"t.bas line 1: output = 7 is not allowed \(allowed: 8..31 \(0..7 "
                                                 r"are inputs only\)\)"):
        run("OP(7, ON)\n")


def test_two_programs_run_in_their_own_processes_with_their_own_base_and_variables() -> None:
    """main.bas (process 1, BASE(3)) starts helper.bas on process 3 with RUN; helper sets BASE(2) and its own x;
    they meet through VR(10)."""
    sim = Simulation(seed=1)
    trio = TrioController(sim)
    helper = BasicProgram.parse("BASE(2)\nUNITS = 8\nx = 5\nVR(11) = x\nWA(3)\nVR(10) = 1\n", name="helper.bas")
    helper.install(trio)
    main = BasicProgram.parse("BASE(3)\nUNITS = 4\nx = 1\nRUN \"HELPER\", 3\nWAIT UNTIL VR(10) = 1\n"
                              "VR(12) = x\nPRINT \"done\"\n", name="main.bas")
    first = main.start(trio, base=(0,))
    assert first.number == 1 and trio.processes[1] is first
    sim.run(until=10 * MS)
    assert (trio.get_param("UNITS", axis=3), trio.get_param("UNITS", axis=2)) == (4, 8)
    assert (trio.vr(11), trio.vr(12)) == (5, 1)
    assert [(c.t, c.process, c.program) for c in trio.console.lines] == [(3 * MS, 1, "main.bas")]
    assert trio.processes == {}


@pytest.mark.parametrize(("process", "message"), [
    (6, r"process = 6 is not allowed \(allowed: 1..5 \(the user processes of a Euro 205\)\)"),
    (0, r"process = 0 is not allowed"),
    (2, r"process 2 already runs a.bas"),
])
def test_process_numbers_are_checked(process: int, message: str) -> None:
    trio = TrioController(Simulation())
    BasicProgram.parse("WA(1)\n", name="a.bas").start(trio, process=2)
    with pytest.raises(ConfigurationError, match=message):
        BasicProgram.parse("WA(1)\n", name="b.bas").start(trio, process=process)


def test_run_of_an_unknown_program_names_the_known_ones() -> None:
    with pytest.raises(ConfigurationError, match=r"t.bas line 1: RUN program = 'nope' is not allowed \(allowed: a "
                                                 r"program the machine loads: T\)"):
        run("RUN \"nope\"\n")


def test_axis_parameters_are_read_and_written_with_axis_modifiers() -> None:
    trio = run("BASE(2)\nSPEED = 50\nSPEED AXIS(3) = 70\nVR(0) = SPEED + SPEED AXIS(3)\nVR(1) = DPOS AXIS(1)\n"
               "VR(2) = IDLE AND LOADED AXIS(3)\nVR(3) = SERVO_PERIOD\n")
    assert [trio.vr(k) for k in range(4)] == [120, 0, -1, 1000]
