"""Trio BASIC against hostile input (issue 22): any line end, deep nesting, programs that never wait.

Each case used to crash (IndexError on a bare CR, RecursionError on deep nesting) or hang; each now runs or
stops with a :class:`~cosim.errors.ConfigurationError` / :class:`~cosim.errors.TimingViolation` that names the
program line.
"""

from __future__ import annotations

import pytest

from cosim.controllers.trio import TrioController
from cosim.controllers.trio.basic import BasicProgram
from cosim.controllers.trio.compiler import MAX_NESTING
from cosim.errors import ConfigurationError, TimingViolation
from cosim.kernel import Simulation

MS = 1_000_000
#: Every line end Python's str.splitlines knows: LF, CRLF, CR, VT, FF, FS, GS, RS, NEL, LS, PS.
LINE_ENDS = ["\n", "\r\n", "\r", "\x0b", "\x0c", "\x1c", "\x1d", "\x1e", "\x85", "\u2028", "\u2029"]


@pytest.mark.parametrize("end", LINE_ENDS, ids=[repr(e) for e in LINE_ENDS])
def test_any_line_end_is_a_line_end(end: str) -> None:
    """``BasicProgram.parse('BASE(3)\\rATYPE=35\\r')`` raised IndexError; every line end now counts as one line."""
    sim = Simulation(seed=1)
    trio = TrioController(sim)
    BasicProgram.parse(f"BASE(3){end}ATYPE=35{end}UNITS=4 ' four{end}", name="t.bas").start(trio)
    sim.run(until=MS)
    assert (trio.get_param("ATYPE", axis=3), trio.get_param("UNITS", axis=3)) == (35, 4)
    with pytest.raises(ConfigurationError, match=r"^t.bas line 3, column 1: unknown keyword FOO"):
        BasicProgram.parse(f"BASE(3){end}ATYPE=35{end}FOO{end}", name="t.bas")
    with pytest.raises(ConfigurationError, match=r"^t.bas line 2, column 7: syntax error, unexpected '='"):
        BasicProgram.parse(f"BASE(3){end}ATYPE==35{end}", name="t.bas")


def test_a_long_sum_is_flat_and_runs() -> None:
    """1000 terms: a flat list of operands, not a 1000-deep tree."""
    sim = Simulation(seed=1)
    trio = TrioController(sim)
    BasicProgram.parse("VR(0) = " + " + ".join(["1"] * 1000) + "\n").start(trio)
    sim.run(until=MS)
    assert trio.vr(0) == 1000


@pytest.mark.parametrize(("text", "message"), [
    ("IF 1 THEN\n" * 500 + "x = 1\n" + "ENDIF\n" * 500,
     rf"t.bas line {MAX_NESTING + 2}, column 1: blocks nested deeper than 64 levels"),
    ("FOR i = 1 TO 2\n" * 100 + "NEXT i\n" * 100, r"t.bas line 66, column 1: blocks nested deeper than 64 levels"),
    ("VR(0) = " + "(1 + " * 1000 + "1" + ")" * 1000 + "\n", r"t.bas line 1, column \d+: expression nested deeper "
                                                             r"than 64 levels"),
    ("VR(0) = " + "NOT " * 500 + "1\n", r"t.bas line 1, column \d+: expression nested deeper than 64 levels"),
    ("VR(0) = " + "-" * 500 + "1\n", r"t.bas line 1, column \d+: expression nested deeper than 64 levels"),
])
def test_deep_nesting_is_refused_before_running(text: str, message: str) -> None:
    with pytest.raises(ConfigurationError, match=message):
        BasicProgram.parse(text, name="t.bas")


def test_nesting_up_to_the_limit_runs() -> None:
    depth = MAX_NESTING
    text = "n = 0\n" + "IF 1 THEN\n" * depth + "n = 64\n" + "ENDIF\n" * depth + "VR(0) = n + " + "(" * 40 + "1" + \
        ")" * 40 + "\n"
    sim = Simulation(seed=1)
    trio = TrioController(sim)
    BasicProgram.parse(text).start(trio)
    sim.run(until=MS)
    assert trio.vr(0) == 65


def test_a_program_that_never_waits_stops_at_100000_statements_in_a_servo_period() -> None:
    """Twelve statements in a loop without a wait: the guard (100000 statements in one servo period, a fraction
    of a second of wall time) stops it with the line and the advice to wait."""
    body = "".join(f"  v{k} = v{k} + 1\n" for k in range(10))
    text = "".join(f"v{k} = 0\n" for k in range(10)) + "REPEAT\n" + body + "UNTIL v0 < 0\nVR(0) = v1 + v2 + v3 + " \
        "v4 + v5 + v6 + v7 + v8 + v9\n"
    sim = Simulation(seed=1)
    BasicProgram.parse(text, name="busy.bas").start(TrioController(sim))
    with pytest.raises(TimingViolation, match=r"^busy.bas line \d+: process 1 ran 100000 statements in the servo "
                                              r"period from t = 0 ns to 0 ns; .* \(wait with WAIT UNTIL, WAIT IDLE "
                                              r"or WA\)$"):
        sim.run(until=MS)


def test_a_loop_that_waits_a_few_ns_at_a_time_stops_within_its_servo_period() -> None:
    """WA(0.000001) waits 1 ns: without a per-servo-period rule 30 ms of it took 30 million loops (minutes of wall
    time in the long fuzz run); the loop (4 statements and 1 ns a turn) stops in the first servo period, at 100000
    statements: 25000 ns."""
    sim = Simulation(seed=1)
    BasicProgram.parse("n = 0\nWHILE n >= 0\n  n = n + 1\n  WA(0.000001)\nWEND\n", name="crawl.bas").start(
        TrioController(sim))
    with pytest.raises(TimingViolation, match=r"^crawl.bas line \d+: process 1 ran 100000 statements in the servo "
                                              r"period from t = 0 ns to 25000 ns"):
        sim.run(until=30 * MS)


def test_a_polling_loop_that_waits_each_servo_cycle_runs_for_ever() -> None:
    sim = Simulation(seed=1)
    trio = TrioController(sim)
    BasicProgram.parse("n = 0\nWHILE IN(0) = OFF\n  n = n + 1\n  VR(0) = n\n  WA(1)\nWEND\n").start(trio)
    sim.run(until=1000 * MS)
    assert trio.vr(0) == 1000
