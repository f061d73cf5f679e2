"""Trio BASIC values and declarations as the Motion Coordinator runs them (issue 28, item 1).

Variables are created on first assignment; ``DIM name AS INTEGER / FLOAT / BOOLEAN / STRING`` and
arrays; ``CONSTANT "name", value``; ``GLOBAL "name", vr`` (an alias of a VR, shared by every
program); strings and the string functions; PRINT in its forms (TRM: ``PRINT FREE`` shows
``47104.0000``: four decimal places); INPUT and GET from a channel fed from outside; ``ON BASICERROR``,
``ERROR_LINE``, ``RUN_ERROR``.
"""

from __future__ import annotations

from fractions import Fraction

import pytest

from cosim.controllers.trio import TrioController
from cosim.controllers.trio.basic import BasicProgram
from cosim.errors import ConfigurationError
from cosim.kernel import Simulation

MS = 1_000_000


def run(text: str, *, until_ms: int = 5, trio: TrioController | None = None) -> TrioController:
    if trio is None:
        trio = TrioController(Simulation(seed=1), encoder_at_atype=0)
    BasicProgram.parse(text, name="t.bas").start(trio)
    trio.sim.run(until=until_ms * MS)
    return trio


def printed(trio: TrioController) -> list[str]:
    return [line.text for line in trio.console.lines]


def test_a_variable_is_created_on_first_assignment_even_if_never_read() -> None:
    """The controller creates ``i`` and ``axis_number`` when they are assigned: no refusal (issue 28)."""
    trio = run("i = 5\naxis_number = 3\nVR(0) = 1\n")
    assert trio.vr(0) == 1


def test_dim_as_types_keep_their_kind() -> None:
    """DIM n AS INTEGER keeps the integer part, BOOLEAN is TRUE (-1) for any non-zero value, STRING(4) keeps
    four characters, FLOAT (and an undeclared variable) keeps the value."""
    trio = run('DIM n AS INTEGER, ok AS BOOLEAN, s AS STRING(4), f AS FLOAT\n'
               'n = 7 / 2\nok = 5\ns = "abcdef"\nf = 7 / 2\n'
               'VR(0) = n\nVR(1) = ok\nVR(2) = LEN(s)\nVR(3) = f\nPRINT s\n')
    assert [trio.vr(k) for k in range(4)] == [3, -1, 4, Fraction(7, 2)]
    assert printed(trio) == ["abcd"]


def test_dim_arrays_start_at_zero_and_check_their_index() -> None:
    trio = run("DIM a(5), grid(2, 3) AS INTEGER\nFOR k = 0 TO 4\n  a(k) = k * k\nNEXT k\n"
               "grid(1, 2) = 9.7\nVR(0) = a(4)\nVR(1) = grid(1, 2)\nVR(2) = a(0)\n")
    assert [trio.vr(k) for k in range(3)] == [16, 9, 0]
    with pytest.raises(ConfigurationError, match=r"t.bas line 2: A index = 5 is not allowed \(allowed: 0..4\)"):
        run("DIM a(5)\na(5) = 1\n")


def test_an_array_used_before_its_dim_runs_stops_the_program_at_its_line() -> None:
    """DIM is a statement: the array exists from the moment it runs (GOTO past it, or a DIM further down)."""
    with pytest.raises(ConfigurationError, match=r"t.bas line 4: array A is used before its DIM runs"):
        run("GOTO later\nVR(0) = a(1)\nlater:\nVR(0) = a(1)\nDIM a(5)\n")
    trio = TrioController(Simulation(seed=1))
    BasicProgram.parse("INPUT #1, a(2)\nDIM a(5)\n", name="t.bas").start(trio)
    trio.sim.call_at(MS, 1, lambda: trio.channel(1).feed("7\r"))
    with pytest.raises(ConfigurationError, match=r"t.bas line 1: array A is used before its DIM runs"):
        trio.sim.run(until=5 * MS)


def test_constant_and_global_are_known_to_every_program_of_a_machine() -> None:
    """CONSTANT "name", value and GLOBAL "name", vr in one program; the other uses the names."""
    main, helper = BasicProgram.parse_all([
        ("main.bas", 'CONSTANT "top_speed", 250\nGLOBAL "count", 20\ncount = top_speed / 2\nRUN "HELPER", 2\n'),
        ("helper.bas", "WAIT UNTIL count > 0\ncount = count + top_speed\n"),
    ])
    trio = TrioController(Simulation(seed=1))
    helper.install(trio)
    main.start(trio)
    trio.sim.run(until=5 * MS)
    assert trio.vr(20) == 375


@pytest.mark.parametrize(("text", "message"), [
    ('CONSTANT "top", 5\ntop = 6\n', r"t.bas line 2, column 1: TOP is a constant; it cannot be assigned"),
    ('CONSTANT "x", y\ny = 1\n', r"the value of CONSTANT X must be known before the program runs"),
    ("DIM d AS DOUBLE\n", r"t.bas line 1, column 10: DIM ... AS DOUBLE is not a type \(allowed: INTEGER, FLOAT, "
                          r"BOOLEAN, STRING\)"),
    ("DIM d AS INTEGER(5)\n", r"DIM ... AS INTEGER\(...\): only STRING takes a length"),
    ('GLOBAL "g", -1\n', r"GLOBAL G: the VR index must be a number >= 0"),
])
def test_declarations_are_refused_naming_the_construct(text: str, message: str) -> None:
    with pytest.raises(ConfigurationError, match=message):
        BasicProgram.parse(text, name="t.bas")


@pytest.mark.parametrize(("expression", "shown"), [
    ('"ab" + "cd"', "abcd"),
    ("CHR(65) + CHR(66)", "AB"),
    ("HEX(255)", "FF"),
    ("HEX(-1)", "FFFFFFFF"),
    ("STR(1.5)", "1.5000"),
    ("STR(2, 8)", "  2.0000"),
    ('LEFT("conveyor", 3)', "con"),
    ('RIGHT("conveyor", 3)', "yor"),
    ('MID("conveyor", 4, 3)', "vey"),
    ('MID("conveyor", 4)', "veyor"),
    ('UCASE("Trio")', "TRIO"),
    ('LCASE("Trio")', "trio"),
])
def test_string_functions(expression: str, shown: str) -> None:
    assert printed(run(f"PRINT {expression}\n")) == [shown]


def test_string_functions_that_give_numbers() -> None:
    trio = run('VR(0) = LEN("hello")\nVR(1) = VAL("12.5mm")\nVR(2) = VAL("$1F")\nVR(3) = INSTR("a,b,c", ",")\n'
               'VR(4) = INSTR(3, "a,b,c", ",")\nVR(5) = "ab" < "ac"\n')
    assert [trio.vr(k) for k in range(6)] == [5, Fraction(25, 2), 31, 2, 4, -1]


def test_print_in_all_its_forms() -> None:
    """; joins, , puts a tab, a trailing ; keeps the line open, [w, d] formats, #n names the channel, parentheses."""
    trio = run('x = 3.14159\nPRINT "x = "; x\nPRINT x[8, 2]; "|"; x[0]; "|"; -2[5, 1]\nPRINT "a", "b"\n'
               'PRINT "no end";\nPRINT " here"\nPRINT #5, "on channel 5"\nPRINT ("parenthesised")\n? "query"\n'
               'PRINT HEX(10); CHR(33)\n')
    assert printed(trio) == ["x = 3.1416", "    3.14|3| -2.0", "a\tb", "no end here", "[#5] on channel 5",
                             "parenthesised", "query", "A!"]


def test_input_and_get_wait_for_their_channel() -> None:
    """INPUT #1 reads the number at the start of a line; GET #1 the code of one character; KEY #... sees one waiting.
    The text arrives at 2 ms and 4 ms (a stimulus of the machine file does the same)."""
    sim = Simulation(seed=1)
    trio = TrioController(sim)
    BasicProgram.parse("INPUT #1, n\nVR(0) = n\nVR(3) = TICKS\nGET #1, k\nVR(1) = k\nVR(2) = KEY\n",
                       name="t.bas").start(trio)
    sim.call_at(2 * MS, 1, lambda: trio.channel(1).feed("42.5\r"))
    sim.call_at(4 * MS, 1, lambda: trio.channel(1).feed("y"))
    sim.run(until=6 * MS)
    assert [trio.vr(k) for k in range(4)] == [Fraction(85, 2), ord("y"), 0, -2]


def test_on_basicerror_goto_runs_the_handler_with_error_line_and_run_error() -> None:
    trio = run("ON BASICERROR GOTO handler\nx = 1\ny = x / 0\nVR(9) = 1\nhandler:\nVR(0) = ERROR_LINE\n"
               "VR(1) = RUN_ERROR\n")
    assert (trio.vr(0), trio.vr(1), trio.vr(9)) == (3, 2, 0)  # line 3, error 2 (division by zero)


def test_on_basicerror_gosub_returns_after_the_failing_statement() -> None:
    trio = run("ON BASICERROR GOSUB fix\nVR(0) = 1 / 0\nVR(1) = 7\nSTOP\nfix:\nVR(2) = RUN_ERROR\nRETURN\n")
    assert (trio.vr(1), trio.vr(2)) == (7, 2)


def test_an_error_without_a_handler_stops_the_run_and_the_job() -> None:
    sim = Simulation(seed=1)
    trio = TrioController(sim)
    BasicProgram.parse("WA(2)\nVR(0) = SQR(-1)\n", name="t.bas").start(trio, job=True)
    with pytest.raises(ConfigurationError, match=r"t.bas line 2: SQR argument = -1 is not allowed"):
        sim.run(until=5 * MS)
    assert sim.trace.edges("trio.job")[1].tolist() == [0, 1, 3]  # IDLE, RUNNING at 0, ERROR at 2 ms
    assert sim.trace.edges("trio.job")[0].tolist()[-1] == 2 * MS
    assert any("SQR argument" in line.text for line in sim.trace.console())
