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
     r"ATYPE = 2 is not allowed \(allowed: 0 \(virtual\), 35 \(stepper output with PWM\)\)"),
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


#: Non-finite and absurdly large numbers (issue 22): a clear error at once, never a crash or a hang.
FINITE = r"\(allowed: a finite number\)"
HUGE = r"\(allowed: a finite number of magnitude <= 1e300\)"
HUGE_IN_BASIC = [
    ("PWM_MARK=1e5000", rf"number = '1e5000' is not allowed {HUGE}"),
    ("TABLE(0,1e400)", rf"number = '1e400' is not allowed {HUGE}"),
    ("VR(0)=1e99999999", rf"number = '1e99999999' is not allowed {HUGE}"),
    ("TABLE(0,1e300*1e300)", rf"TABLE\(0\) = 1e\+600 is not allowed {HUGE}"),
    ("PWM_MARK=1e300*1e300", r"PWM_MARK = 1e\+600 is not allowed \(allowed: integer 0..65535\)"),
]


@pytest.mark.parametrize(("statement", "message"), HUGE_IN_BASIC, ids=[b[0] for b in HUGE_IN_BASIC])
def test_huge_numbers_in_a_program_are_refused_at_their_line(statement: str, message: str) -> None:
    sim = Simulation(seed=1)
    BasicProgram.parse(f"BASE(3)\nATYPE=35\n{statement}\n", name="job.bas").start(TrioController(sim))
    with pytest.raises(ConfigurationError, match=rf"^job.bas line 3: {message}$"):
        sim.run(until=1000)


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
