"""Trio BASIC: the note's example program runs from its text; the subset's statements; errors with lines."""

from __future__ import annotations

from collections.abc import Callable
from decimal import Decimal, localcontext
from fractions import Fraction
from math import ceil, floor

import numpy as np
import pytest

from cosim.controllers.trio import TrioController, basic
from cosim.controllers.trio.basic import EXAMPLES, BasicProgram, example
from cosim.errors import ConfigurationError, TimingViolation
from cosim.kernel import Simulation

MS = 1_000_000
PERIOD = Fraction(1, 1000)  # SERVO_PERIOD = 1 ms
#: TRM 8-165: the falling edge of a step pulse is the active edge; the pulse falls 100 ns (the model's
#: default step pulse width) after it starts, so a step is counted 100 ns after its leading edge.
ACTIVE = 100


# -- the note's example, against a closed form written here (not the model's profile code) ---------
def closed_form_position(length: Fraction, speed: Fraction, accel: Fraction,
                         decel: Fraction) -> tuple[Callable[[Fraction], Fraction], Fraction]:
    """s(t) [units] and the duration [s] of a rest-to-rest trapezoid (triangle if too short)."""
    if length >= speed**2 / (2 * accel) + speed**2 / (2 * decel):
        peak = speed
    else:
        with localcontext() as ctx:
            ctx.prec = 60
            q = 2 * length * accel * decel / (accel + decel)
            peak = Fraction((Decimal(q.numerator) / Decimal(q.denominator)).sqrt())
    t1 = peak / accel
    t2 = t1 + (length - peak**2 / (2 * accel) - peak**2 / (2 * decel)) / peak
    t3 = t2 + peak / decel

    def s(t: Fraction) -> Fraction:
        if t <= t1:
            return accel * t * t / 2
        if t <= t2:
            return peak**2 / (2 * accel) + peak * (t - t1)
        if t <= t3:
            return length - decel * (t3 - t) ** 2 / 2
        return length

    return s, t3


def edge_time(t_start: int, steps: list[int], n: int) -> int:
    """Active (falling) edge of the n-th step of a move whose step count after cycle j is steps[j+1]."""
    j = next(j for j in range(len(steps) - 1) if steps[j + 1] >= n)
    before, count = steps[j], steps[j + 1] - steps[j]
    return t_start + j * MS + ((n - before - 1) * MS) // count + ACTIVE


@pytest.mark.parametrize(("speed", "accel", "decel"), [
    (1000, 1000, 1000),  # the controller's defaults: a triangle
    (100, 1000, 1000),
    (250, 2000, 500),
    (2000, 800, 1200),   # asymmetric triangle
])
def test_note_example_gates_at_the_exact_counts_and_pulse_times(speed: int, accel: int, decel: int) -> None:
    """tn20_81.bas, unmodified, with UNITS=16; SPEED/ACCEL/DECEL preset on axis 3.

    forward  0 -> 300:  GT 110 115 195 220  -> counts 1761 1841 3121 3521  (ON OFF ON OFF)
    reverse 300 -> 0:   LT 220 195 115 110  -> counts 3519 3119 1839 1759  (ON OFF ON OFF)

    The program starts at t = 0 after the servo tick; MOVEABS(300) is loaded at 1 ms; WAIT IDLE
    returns at the tick after the move's last cycle, and MOVEABS(0) is loaded one tick later. Each
    gate edge is at the active (falling) edge of the pulse that reaches its count.
    """
    sim = Simulation(seed=1)
    trio = TrioController(sim)
    for name, value in (("SPEED", speed), ("ACCEL", accel), ("DECEL", decel)):
        trio.set_param(name, value, axis=3)
    example().start(trio)
    s, duration = closed_form_position(Fraction(300), Fraction(speed), Fraction(accel), Fraction(decel))
    cycles = ceil(duration / PERIOD)
    steps = [floor(16 * s(j * PERIOD)) for j in range(cycles + 1)]
    t_forward = 1 * MS
    t_reverse = t_forward + (cycles + 1) * MS
    sim.run(until=t_reverse + (cycles + 2) * MS)

    expected = [(edge_time(t_forward, steps, n), level, n) for n, level in
                ((1761, 1), (1841, 0), (3121, 1), (3521, 0))]
    expected += [(edge_time(t_reverse, steps, 4800 - m), level, m) for m, level in
                 ((3519, 1), (3119, 0), (1839, 1), (1759, 0))]
    t, v = sim.trace.edges("trio.axis3.gate")
    tp, dp = sim.trace.pulses("trio.axis3.step")
    count = np.concatenate([[0], np.cumsum(dp.astype(np.int64) * 2 - 1)])
    found = [(int(a), int(b), int(count[np.searchsorted(tp, a, side="right")])) for a, b in zip(t[1:], v[1:],
                                                                                               strict=True)]
    assert found[:8] == expected
    assert trio.gate(3).late == []
    assert sim.trace.value_at("trio.wdog", 0) == 1 and sim.trace.value_at("trio.axis3.pwm_mark", 0) == 400


def test_example_file_is_the_notes_program() -> None:
    program = example("tn20_81")
    lines = [line.split("'")[0].strip() for line in program.text.splitlines()]
    assert (EXAMPLES / "tn20_81.bas").read_text() == program.text
    assert lines[:3] == ["WDOG=OFF", "BASE(3)", "PWM_CONTROL(0)"]
    assert [x for x in lines if x][-8:] == ["REPEAT", "PWM_CONTROL(3,1,ON,1000,1003)", "MOVEABS(300)", "WAIT IDLE",
                                            "PWM_CONTROL(3,0,ON,2000,2003)", "MOVEABS(0)", "WAIT IDLE", "UNTIL FALSE"]


# -- the subset -------------------------------------------------------------------------------
def run_text(text: str, *, until_ms: int = 5, base: tuple[int, ...] = (0,)) -> TrioController:
    sim = Simulation(seed=1)
    trio = TrioController(sim, encoder_at_atype=0)
    BasicProgram.parse(text, name="t.bas").start(trio, base=base)
    sim.run(until=until_ms * MS)
    return trio


def test_expressions_variables_tables_loops_and_comments() -> None:
    trio = run_text("""' a comment line
base(2) : units = 4   ' lower case, two statements on a line
x = 3 + 4 * 2 - 10 / 4
VR(7) = x * 2
TABLE(10, x, VR(7), $1F, -1.25e1, ABS(-3), INT(-2.7))
total = 0
FOR i = 1 TO 5 STEP 2
  total = total + i
NEXT i
n = 0
WHILE n < 3
  n = n + 1
WEND
IF TABLE(11) = 17 AND NOT (x > 9) THEN PWM_MARK AXIS(3) = total * 10 + n
IF x <> 8.5 OR n = 0 THEN
  PWM_MARK AXIS(3) = 1
ELSE
  PWM_CYCLE AXIS(3) = 1000
ENDIF
k = 0
REPEAT
  k = k + 1
UNTIL k >= 4 OR UNITS AXIS(2) <> 4
TABLE(20, k, i)
""")
    assert trio.table_memory[10:16] == [Fraction(17, 2), 17, 31, Fraction(-25, 2), 3, -2]
    assert trio.get_param("PWM_MARK", axis=3) == 93 and trio.get_param("PWM_CYCLE", axis=3) == 1000
    assert trio.get_param("UNITS", axis=2) == 4 and trio.vr(7) == 17 and sum(trio.vr_memory) == 17
    assert trio.table_memory[20:22] == [4, 7]


def test_axis_modifier_and_base_direct_axis_functions() -> None:
    """PWM_CONTROL and parameters act on the BASE axis, or on the axis an AXIS() modifier names."""
    trio = run_text("BASE(2)\nPWM_CYCLE=200\nPWM_MARK AXIS(3)=300\nPWM_CONTROL(1) AXIS(3)\nBASE(3)\nPWM_CYCLE=1000\n")
    pwm2, pwm3 = trio.pwm(2), trio.pwm(3)
    assert (pwm2.cycle, pwm2.mark, pwm2.on) == (200, 0, False)
    assert (pwm3.cycle, pwm3.mark, pwm3.on) == (1000, 300, True)
    assert trio.sim.trace.value_at("trio.axis3.pwm_mark", 0) == 300
    assert trio.sim.trace.value_at("trio.axis2.pwm_mark", 0) == 0


def test_wait_until_is_checked_at_every_servo_tick() -> None:
    """WAIT UNTIL MPOS > 5: WDOG goes on at the first servo tick where more than 5 units were counted."""
    trio = run_text("BASE(3)\nATYPE=35\nSERVO=ON\nUNITS=2\nSPEED=50\nMOVE(10)\nWAIT UNTIL MPOS > 5\nWDOG=ON\n",
                    until_ms=400)
    t_on = int(trio.sim.trace.edges("trio.wdog")[0][-1])
    tp, _ = trio.sim.trace.pulses("trio.axis3.step")
    counted = int(tp[10]) + ACTIVE  # the 11th pulse (MPOS 5.5) counts at its active edge
    assert t_on == -(-counted // MS) * MS  # the first servo tick at or after it


def test_wa_waits_milliseconds() -> None:
    trio = run_text("WA(2.5)\nWDOG=ON\nWA(1)\nWDOG=OFF\n")
    assert trio.sim.trace.edges("trio.wdog")[0].tolist() == [0, 2_500_000, 3_500_000]


@pytest.mark.parametrize(("text", "message"), [
    ("MOVE(1\n", r"t.bas line 1, column 7: syntax error, unexpected end of line \(expected: \), .*\n    MOVE\(1$"),
    ("BASE(3)\nUNITS==3\n", r"t.bas line 2, column 7: syntax error, unexpected '='"),
    ("BASE(3)\n\nMOVX(3)\n", r"t.bas line 3, column 1: unknown keyword MOVX; did you mean MOVE, PMOVE, MOVESP\? "
                            r"\(not a Trio BASIC command; see docs/trio.md\)"),
    ("UNIT=16\n", r"t.bas line 1, column 1: unknown keyword UNIT; did you mean UNITS.*assigned but never read"),
    ("x = SPED + 1\nVR(1) = x\n", r"t.bas line 1, column 5: unknown keyword SPED; did you mean SPEED"),
    ("DPOS=3\n", r"t.bas line 1, column 1: DPOS is read-only \(use DEFPOS\)"),
    ("SERVO_PERIOD=500\n", r"t.bas line 1, column 1: SERVO_PERIOD is read-only"),
    ("x = MOVE(3)\nVR(1)=x\n", r"t.bas line 1, column 5: MOVE\(...\) is a command, not a function"),
    ("VR(3)\n", r"t.bas line 1, column 1: VR\(...\) is a function, not a command"),
    ("TABLE(3)\n", r"t.bas line 1, column 1: number of TABLE arguments = 1 is not allowed \(allowed: 2 or more: "
                   r"TABLE\(start, value, value, ...\)\)"),
    ("UNITS\n", r"t.bas line 1, column 1: UNITS is a parameter; write UNITS = value"),
    ("WDOG AXIS(3) = ON\n", r"t.bas line 1, column 1: WDOG is not an axis parameter"),
    ("IF 1 THEN\n  FOO\nENDIF\n", r"t.bas line 2, column 3: unknown keyword FOO"),
])
def test_program_errors_are_found_before_running_with_line_numbers(text: str, message: str) -> None:
    with pytest.raises(ConfigurationError, match=message):
        BasicProgram.parse(text, name="t.bas")


@pytest.mark.parametrize(("text", "error", "message"), [
    ("x = 1\ny = x / 0\nVR(1) = y\n", ConfigurationError, r"t.bas line 2: division by zero"),
    ("IF 0 THEN x = 1\nVR(1) = x\n", ConfigurationError, r"t.bas line 2: variable X is read before the program "),
    ("MOVE(1, 2)\n", ConfigurationError, r"t.bas line 1: number of MOVE values = 2 is not allowed \(allowed: 1..1"),
    ("BASE(1, 1)\n", ConfigurationError, r"t.bas line 1: BASE\(1, 1\) names an axis twice"),
    ("BASE(5)\n", ConfigurationError, r"t.bas line 1: axis = 5 is not allowed \(allowed: 0..3\)"),
])
def test_run_time_errors_carry_the_line_number(text: str, error: type[Exception], message: str) -> None:
    with pytest.raises(error, match=message):
        run_text(text)


def test_a_loop_that_never_waits_is_an_error(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(basic, "MAX_STATEMENTS_PER_SERVO_PERIOD", 500)
    with pytest.raises(TimingViolation, match=r"t.bas line 4: process 1 ran 500 statements in the servo period from "
                                              r"t = 0 ns to 0 ns; statements take no simulated time"):
        run_text("x = 0\nREPEAT\n  x = x + 1\nUNTIL x < 0\n")
