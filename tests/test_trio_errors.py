"""Trio bad input: each error names the parameter, the value and the allowed range (and the program line)."""

from __future__ import annotations

from fractions import Fraction

import pytest

from cosim.controllers.trio import TrioController, TrioProcess
from cosim.controllers.trio.basic import BasicProgram
from cosim.errors import ConfigurationError
from cosim.kernel import Simulation

#: (BASIC statement on line 3 after BASE(3) and ATYPE=35, the same through Python, expected message)
BAD_INPUT = [
    ("PWM_CYCLE=70000", lambda p: p.set("PWM_CYCLE", 70000),
     r"PWM_CYCLE = 70000 is not allowed \(allowed: integer 0..65535\)"),
    ("PWM_CYCLE=-1", lambda p: p.set("PWM_CYCLE", -1), r"PWM_CYCLE = -1 is not allowed \(allowed: integer 0..65535\)"),
    ("PWM_MARK=65536", lambda p: p.set("PWM_MARK", 65536),
     r"PWM_MARK = 65536 is not allowed \(allowed: integer 0..65535\)"),
    ("PWM_CONTROL(3,1,ON,15999,16000)", lambda p: p.pwm_control(3, 1, 1, 15999, 16000),
     r"PWM_CONTROL\(3\) table end = 16000 is not allowed \(allowed: 0..15999 \(TABLE size 16000\)\)"),
    ("PWM_CONTROL(3,1,ON,1003,1000)", lambda p: p.pwm_control(3, 1, 1, 1003, 1000),
     r"PWM_CONTROL\(3\) table end = 1000 is not allowed \(allowed: >= table start 1003\)"),
    ("PWM_CONTROL(3,2,ON,1000,1003)", lambda p: p.pwm_control(3, 2, 1, 1000, 1003),
     r"PWM_CONTROL\(3\) GT/LT flag = 2 is not allowed \(allowed: 1 \(GT\) or 0 \(LT\)\)"),
    ("PWM_CONTROL(3,-1,ON,1000,1003)", lambda p: p.pwm_control(3, -1, 1, 1000, 1003),
     r"PWM_CONTROL\(3\) GT/LT flag = -1 is not allowed \(allowed: 1 \(GT\) or 0 \(LT\)\)"),
    ("PWM_CONTROL(1) AXIS(1)", lambda p: p.pwm_control(1, axis=1),
     r"PWM_CONTROL axis = 1 is not allowed \(allowed: 2, 3 \(the axes with the PWM feature\)\)"),
    ("PWM_CONTROL(7)", lambda p: p.pwm_control(7), r"PWM_CONTROL mode = 7 is not allowed \(allowed: 0..6\)"),
    ("PWM_CONTROL(2.5)", lambda p: p.pwm_control(2.5), r"PWM_CONTROL mode = 2.5 is not allowed \(allowed: 0..6\)"),
    ("UNITS=0", lambda p: p.set("UNITS", 0), r"UNITS = 0 is not allowed \(allowed: > 0\)"),
    ("UNITS=-16", lambda p: p.set("UNITS", -16), r"UNITS = -16 is not allowed \(allowed: > 0\)"),
    ("ATYPE AXIS(0)=35", lambda p: p.set("ATYPE", 35, axis=0),
     r"axis of ATYPE=35 = 0 is not allowed \(allowed: 2, 3 \(the axes with the PWM feature\)\)"),
    ("ATYPE=2", lambda p: p.set("ATYPE", 2),
     r"ATYPE = 2 is not allowed \(allowed: 0 \(virtual\), 1 \(stepper\), 35 \(stepper output with PWM\)\)"),
    ("SERVO=2", lambda p: p.set("SERVO", 2), r"SERVO = 2 is not allowed \(allowed: ON/OFF \(1, 0 or TRUE = -1\)\)"),
]


@pytest.mark.parametrize(("statement", "call", "message"), BAD_INPUT, ids=[b[0] for b in BAD_INPUT])
def test_bad_input_in_a_program_names_line_parameter_value_and_range(statement: str, call: object,
                                                                      message: str) -> None:
    sim = Simulation(seed=1)
    trio = TrioController(sim)
    BasicProgram.parse(f"BASE(3)\nATYPE=35\n{statement}\nWDOG=ON\n", name="job.bas").start(trio)
    with pytest.raises(ConfigurationError, match=rf"^job.bas line 3: {message}$"):
        sim.run(until=1000)
    assert sim.trace.value_at("trio.wdog", 0) == 0  # the program stopped at the bad line


@pytest.mark.parametrize(("statement", "call", "message"), BAD_INPUT, ids=[b[0] for b in BAD_INPUT])
def test_bad_input_from_python_raises_the_same_message(statement: str, call: object, message: str) -> None:
    sim = Simulation(seed=1)
    p = TrioProcess(TrioController(sim), base=(3,))
    with pytest.raises(ConfigurationError, match=rf"^{message}$"):
        call(p)  # type: ignore[operator]


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"n_axes": 2}, r"n_axes = 2 is not allowed \(allowed: 4..64\)"),
    ({"table_size": 0}, r"table_size = 0 is not allowed \(allowed: >= 1 entries\)"),
    ({"servo_period_us": 750}, r"SERVO_PERIOD = 750 is not allowed"),
    ({"servo_period_us": float("nan")}, r"SERVO_PERIOD = nan is not allowed \(allowed: a finite number\)"),
    ({"encoder_at_atype": 2**29}, r"encoder_at_atype = 536870912 is not allowed \(allowed: 0..536870911"),
])
def test_bad_controller_configuration(kwargs: dict[str, int], message: str) -> None:
    with pytest.raises(ConfigurationError, match=message):
        TrioController(Simulation(), **kwargs)  # type: ignore[arg-type]


#: Non-finite and absurdly large numbers (issue 22): a clear error at once, never a crash or a hang. A Trio
#: variable is a 32-bit integer part and a 32-bit fraction (TRM 11-13): -2147483648 <= value < 2147483648.
FINITE = r"\(allowed: a finite number\)"
HUGE = r"\(allowed: a finite number of magnitude <= 1e300\)"
WORD = r"\(allowed: -2147483648 <= value < 2147483648 \(a 32-bit integer part\)\)"
HUGE_LITERALS = [
    ("PWM_MARK=1e5000", 10, rf"number = '1e5000' is not allowed {WORD}"),
    ("TABLE(0,1e400)", 9, rf"number = '1e400' is not allowed {WORD}"),
    ("VR(0)=1e99999999", 7, rf"number = '1e99999999' is not allowed {WORD}"),
    ("x=1e99999999999999999999999:VR(0)=x", 3, rf"number = '1e99999999999999999999999' is not allowed {WORD}"),
    ("VR(0)=2147483648", 7, rf"number = '2147483648' is not allowed {WORD}"),
    ("VR(0)=$80000000", 7, r"number = '\$80000000' is not allowed \(allowed: \$0..\$7FFFFFFF \(-2147483648 <= value.*"),
    ("VR(0)=1." + "1" * 40, 7, r"number = '1.1+' is not allowed \(allowed: at most 30 significant digits\)"),
]


@pytest.mark.parametrize(("statement", "column", "message"), HUGE_LITERALS, ids=[b[0][:30] for b in HUGE_LITERALS])
def test_huge_literals_are_refused_before_the_program_runs(statement: str, column: int, message: str) -> None:
    with pytest.raises(ConfigurationError, match=rf"^job.bas line 3, column {column}: {message}$"):
        BasicProgram.parse(f"BASE(3)\nATYPE=35\n{statement}\n", name="job.bas")


GROWTH = [
    ("x=2\nFOR i=1 TO 40\n  x=x*x\nNEXT i\nVR(0)=x", 3, r"value = 4294967296 is not allowed"),
    ("x=2147483647\nx=x+1\nVR(0)=x", 2, r"value = 2147483648 is not allowed"),
    ("x=-2147483647-1\nx=x-1\nVR(0)=x", 2, r"value = -2147483649 is not allowed"),
    ("x=65536\nx=-x*x/2\nVR(0)=x", 2, r"value = -4294967296 is not allowed"),
    ("TABLE(0,1e9*3)", 1, r"value = 3000000000 is not allowed"),
    ("PWM_MARK=1e9*1e9", 1, r"value = 1000000000000000000 is not allowed"),
]


@pytest.mark.parametrize(("text", "line", "message"), GROWTH, ids=[g[0][:25] for g in GROWTH])
def test_values_beyond_a_trio_variable_stop_the_program_at_their_line(text: str, line: int, message: str) -> None:
    """x = x * x forty times used to run for hours with exact numbers; now the first square beyond 2**31 stops it."""
    sim = Simulation(seed=1)
    BasicProgram.parse(f"BASE(3)\n{text}\n", name="job.bas").start(TrioController(sim))
    with pytest.raises(ConfigurationError, match=rf"^job.bas line {line + 1}: {message} {WORD}$"):
        sim.run(until=1000)


def test_a_fraction_finer_than_a_trio_variable_is_rounded_to_2_to_the_minus_32() -> None:
    """1/3 stays exact; (1/3)**40 is below 2**-33 and becomes 0; 1/2**33 rounds half away from zero to 2**-32."""
    sim = Simulation(seed=1)
    trio = TrioController(sim)
    BasicProgram.parse("a=1/3\nb=1\nFOR i=1 TO 40\n  b=b*a\nNEXT i\nVR(0)=a\nVR(1)=b\nVR(2)=1/65536/65536/2\n"
                       "VR(3)=1/65536/65536 + 1/3\n").start(trio)
    sim.run(until=1000)
    assert trio.vr(0) == Fraction(1, 3) and trio.vr(1) == 0 and trio.vr(2) == Fraction(1, 4294967296)
    assert trio.vr(3) == Fraction(round((Fraction(1, 4294967296) + Fraction(1, 3)) * 4294967296), 4294967296)


NON_FINITE_FROM_PYTHON = [
    ("PWM_MARK inf", lambda p: p.set("PWM_MARK", float("inf")), rf"PWM_MARK = inf is not allowed {FINITE}"),
    ("PWM_MARK 1e5000", lambda p: p.set("PWM_MARK", 10**5000),
     r"PWM_MARK = 1e\+5000 is not allowed \(allowed: integer 0..65535\)"),
    ("UNITS nan", lambda p: p.set("UNITS", float("nan")), rf"UNITS = nan is not allowed {FINITE}"),
    ("SERVO nan", lambda p: p.set("SERVO", float("nan")),
     r"SERVO = nan is not allowed \(allowed: ON/OFF \(1, 0 or TRUE = -1\)\)"),
    ("TABLE nan", lambda p: p.table(0, float("nan")), rf"TABLE\(0\) = nan is not allowed {FINITE}"),
    ("TABLE 1e400", lambda p: p.table(0, Fraction(10**400)), rf"TABLE\(0\) = 1e\+400 is not allowed {HUGE}"),
    ("MOVE -inf", lambda p: p.move(float("-inf")), rf"MOVE value = -inf is not allowed {FINITE}"),
    ("WA nan", lambda p: p.wa(float("nan")), rf"WA time = nan is not allowed {FINITE}"),
    ("PWM_CONTROL(2) nan", lambda p: p.pwm_control(2, float("nan"), 0, 100, 3),
     rf"PWM_CONTROL\(2\) multiplier = nan is not allowed {FINITE}"),
]


@pytest.mark.parametrize(("case", "call", "message"), NON_FINITE_FROM_PYTHON,
                         ids=[b[0] for b in NON_FINITE_FROM_PYTHON])
def test_non_finite_and_huge_values_from_python_are_refused(case: str, call: object, message: str) -> None:
    p = TrioProcess(TrioController(Simulation(seed=1)), base=(3,))
    p.set("ATYPE", 35)
    with pytest.raises(ConfigurationError, match=rf"^{message}$"):
        call(p)  # type: ignore[operator]


@pytest.mark.parametrize(("position", "accepted"), [
    (Fraction(268_435_455, 16), True), (Fraction(268_435_456, 16), False), (Fraction(-268_435_456, 16), True),
    (Fraction(10**200), False)])
def test_a_gate_position_must_fit_the_29_bit_compare(position: Fraction, accepted: bool) -> None:
    """TN20-81: the FIFO compares against the 29-bit PWM_ENCODER: position x UNITS in -2**28 .. 2**28 - 1
    (268435456 = 2**28). 1e300 used to overflow in the comparison (issue 22)."""
    p = TrioProcess(TrioController(Simulation(seed=1)), base=(3,))
    p.set("ATYPE", 35)
    p.set("UNITS", 16)
    p.table(0, position)
    if accepted:
        p.pwm_control(3, 1, 1, 0, 0)
    else:
        with pytest.raises(ConfigurationError, match=r"PWM_CONTROL\(3\) position TABLE\(0\) x UNITS = .* is not "
                                                     r"allowed \(allowed: -268435456 <= counts < 268435456"):
            p.pwm_control(3, 1, 1, 0, 0)
