"""Every axis parameter of the manual is accepted and range-checked (issue 28, item 3).

Those that change timing act: software limits FS_LIMIT / RS_LIMIT (TRM 8-177: "when the limit is hit
the controller will ramp down the speed to zero then cancel the move; bit 10 in the axis status is set
in RS_LIMIT"), hardware limits FWD_IN / REV_IN, REP_DIST / REP_OPTION, JOGSPEED with the jog inputs,
CREEP and DATUM_IN (see test_trio_homing). The others (gains and the like) are stored, read back as
written, and listed in the run's notes as "set, not modelled" with where they were set.
"""

from __future__ import annotations

from fractions import Fraction

import pytest

from cosim.controllers.trio import TrioController
from cosim.controllers.trio.basic import BasicProgram
from cosim.controllers.trio.params import AXIS_PARAMS
from cosim.errors import ConfigurationError
from cosim.job import JobState
from cosim.kernel import Simulation

MS = 1_000_000
#: A valid value for each parameter (an input number, an ON/OFF, a positive number...).
VALID = {"ATYPE": 1, "INVERT_STEP": 1, "SERVO": 1, "AXIS_ENABLE": 0, "VERIFY": 1, "FE_LIMIT_MODE": 1,
         "AXIS_DISPLAY": 2, "ENCODER_BITS": 25, "ENCODER_CONTROL": 1, "PP_STEP": -3, "ERRORMASK": 256,
         "REP_OPTION": 1, "MERGE": 1, "SRAMP": 50, "PWM_CYCLE": 1000, "PWM_MARK": 400, "MICROSTEP": 1}


@pytest.mark.parametrize("name", sorted(AXIS_PARAMS))
def test_every_axis_parameter_is_written_and_read_back(name: str) -> None:
    sim = Simulation(seed=1)
    trio = TrioController(sim, encoder_at_atype=0)
    value = VALID.get(name, 7 if AXIS_PARAMS[name].default != -1 else 5)
    BasicProgram.parse(f"BASE(3)\n{name} = {value}\nVR(0) = {name}\n", name="t.bas").start(trio)
    sim.run(until=MS)
    assert trio.vr(0) == value
    listed = [item.name for item in sim.notes.unmodelled()]
    assert (f"{name}(axis 3)" in listed) == (not AXIS_PARAMS[name].acts)


def test_a_parameter_not_modelled_is_listed_with_its_value_and_where() -> None:
    sim = Simulation(seed=1)
    trio = TrioController(sim)
    BasicProgram.parse("BASE(1)\nP_GAIN = 1.5\nI_GAIN AXIS(2) = 0.25\n", name="tune.bas").start(trio)
    sim.run(until=MS)
    items = {item.name: (item.value, item.where) for item in sim.notes.unmodelled()}
    assert items == {"P_GAIN(axis 1)": (1.5, "tune.bas:2"), "I_GAIN(axis 2)": (0.25, "tune.bas:3")}
    assert trio.get_param("P_GAIN", axis=1) == Fraction(3, 2)


@pytest.mark.parametrize(("text", "message"), [
    ("DATUM_IN = 40", r"DATUM_IN = 40 is not allowed \(allowed: -1 \(none\) or an input 0..31\)"),
    ("FWD_IN = -2", r"FWD_IN = -2 is not allowed \(allowed: -1 \(none\) or an input 0..31\)"),
    ("SRAMP = 300", r"SRAMP = 300 is not allowed \(allowed: 0..250 ms\)"),
    ("REP_OPTION = 4", r"REP_OPTION = 4 is not allowed \(allowed: 0..3"),
    ("REP_DIST = 0", r"REP_DIST = 0 is not allowed"),
    ("CREEP = -1", r"CREEP = -1 is not allowed"),
    ("FE_LIMIT_MODE = 2", r"FE_LIMIT_MODE = 2 is not allowed \(allowed: 0..1\)"),
    ("MERGE = 2", r"MERGE = 2 is not allowed \(allowed: ON/OFF"),
])
def test_axis_parameters_are_range_checked_at_their_line(text: str, message: str) -> None:
    sim = Simulation(seed=1)
    BasicProgram.parse(f"BASE(1)\n{text}\n", name="t.bas").start(TrioController(sim))
    with pytest.raises(ConfigurationError, match=rf"t.bas line 2: {message}"):
        sim.run(until=MS)


def _moving(text: str, *, until_ms: int, inputs: dict[int, list[tuple[int, int]]] | None = None,
            ) -> TrioController:
    sim = Simulation(seed=1)
    trio = TrioController(sim)
    for channel, changes in (inputs or {}).items():
        signal = trio.input(channel)
        signal.set(1)
        for t_ms, level in changes:
            sim.call_at(t_ms * MS, 1, lambda signal=signal, level=level: signal.set(level))
    BasicProgram.parse(text, name="t.bas").start(trio, job=True)
    sim.run(until=until_ms * MS)
    return trio


def test_forward_software_limit_ramps_down_and_cancels() -> None:
    """FS_LIMIT = 50, MOVE(100) at SPEED 100, ACCEL = DECEL = 1000: DPOS reaches 50 at 551 ms (5 units of
    ramp, then 45 at 100 units/s, from the tick at 1 ms); the move decelerates from there (5 units) and
    ends at 55. AXISSTATUS has bit 9 (512); the job stops: LIMIT."""
    trio = _moving("BASE(0)\nSPEED = 100\nFS_LIMIT = 50\nMOVE(100)\nWAIT IDLE\nVR(0) = AXISSTATUS\n"
                   "VR(1) = DPOS\n", until_ms=800)
    assert (trio.vr(0), trio.vr(1)) == (512, 55)
    assert trio.job.state == JobState.LIMIT
    t, _ = trio.sim.trace.edges("trio.job")
    assert t.tolist()[-1] == 551 * MS


def test_reverse_software_limit_sets_bit_10() -> None:
    trio = _moving("BASE(0)\nSPEED = 100\nRS_LIMIT = -20\nMOVE(-100)\nWAIT IDLE\nVR(0) = AXISSTATUS\n",
                   until_ms=800)
    assert trio.vr(0) == 1024


def test_forward_hardware_limit_is_active_low_and_cancels_the_move() -> None:
    """FWD_IN = 5: input 5 goes OFF (the switch opens) at 100 ms, before the servo tick there, which cancels the
    move: it has run 1000 x 0.099^2 / 2 = 4.9005 units at 99 units/s and stops 4.9005 further, at 9.801.
    AXISSTATUS shows 16 while the input is OFF; the job stops: LIMIT."""
    trio = _moving("BASE(0)\nFWD_IN = 5\nSPEED = 100\nMOVE(100)\nWAIT IDLE\nVR(0) = AXISSTATUS\nVR(1) = DPOS\n",
                   until_ms=400, inputs={5: [(100, 0)]})
    assert (trio.vr(0), trio.vr(1)) == (16, Fraction(9801, 1000))
    assert trio.job.state == JobState.LIMIT


def test_rep_dist_wraps_dpos_and_mpos() -> None:
    """REP_DIST = 10 (REP_OPTION 0: -10..10): FORWARD at 100 units/s from the tick at 1 ms. At the tick at
    200 ms the demand has run 100 x 0.2 - 5 = 15 units: DPOS wrapped by 2 x REP_DIST, -5. With REP_OPTION = 1
    (0..10) from then on, at 300 ms (25 units run) DPOS is 25 - 20 = 5."""
    trio = _moving("BASE(0)\nREP_DIST = 10\nSPEED = 100\nFORWARD\nWA(200)\nVR(0) = DPOS\nVR(2) = MPOS\n"
                   "REP_OPTION = 1\nWA(100)\nVR(1) = DPOS\nCANCEL\n", until_ms=400)
    assert (trio.vr(0), trio.vr(1), trio.vr(2)) == (-5, 5, -5)


def test_jog_inputs_move_the_axis_at_jogspeed() -> None:
    """FWD_JOG = 4, JOGSPEED = 50, ACCEL = DECEL = 1000: input 4 is set (OFF) from 10 ms to 210 ms; the axis
    jogs forward from the tick at 10 ms (50 units/s after 50 ms), decelerates from 210 ms (1.25 units) and
    stops: 200 ms x 50 - 1.25 (the ramp) + 1.25 (the stop) = 10 units."""
    trio = _moving("BASE(0)\nFWD_JOG = 4\nJOGSPEED = 50\nWA(300)\nVR(0) = DPOS\nVR(1) = MTYPE\n",
                   until_ms=400, inputs={4: [(10, 0), (210, 1)]})
    assert (trio.vr(0), trio.vr(1)) == (10, 0)
    assert max(trio.sim.trace.edges("trio.axis0.vp_speed")[1]) == 50
