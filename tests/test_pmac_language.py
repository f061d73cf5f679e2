"""Coordinate systems, kinematics and program constructs of the Turbo PMAC language (issue 27, items 4 and 5).

Each test runs a few lines written as the reference writes them on the default servo clock (I10 =
3,713,707: servo cycle k at floor(k * 442,708.37) ns) and asserts what the controller does, in
simulated time.
"""

from __future__ import annotations

import itertools
from fractions import Fraction

import pytest

from cosim.controllers.pmac import Pmac
from cosim.errors import ConfigurationError
from cosim.job import JobState
from cosim.kernel import Simulation


def _run(sim: Simulation, pmac: Pmac, cycles: int) -> None:
    if not pmac.started:
        pmac.start()
    sim.run(until=pmac.clock.t(cycles) + 1)


def test_a_motor_on_a_linear_combination_of_axes(sim: Simulation) -> None:
    """``#3->500X+300Y+100``: motor 3 = 500 X + 300 Y + 100 counts."""
    pmac = Pmac(sim)
    pmac.load("&1 #1->1X #2->1Y #3->500X+300Y+100\nOPEN PROG 1 CLEAR\nLINEAR ABS TA0 TS0 TM1\nX2 Y-1\nCLOSE\n",
              source="c.pmc")
    pmac.command("&1 B1 R")
    _run(sim, pmac, 20)
    assert pmac.motors[3].cmd == 500 * 2 + 300 * -1 + 100


def test_address_selects_the_q_variables_and_the_cmd_target_of_a_plc(sim: Simulation) -> None:
    pmac = Pmac(sim)
    pmac.load("I5=2\n&2 Q5=7\nOPEN PLC 1 CLEAR\nADDRESS &2\nP1=Q5\nCMD\"Q6=8\"\nDISABLE PLC 1\nCLOSE\nENABLE PLC 1\n",
              source="a.pmc")
    _run(sim, pmac, 2)
    memory = pmac.programs.memory
    assert memory.p[1] == 7  # &2's Q5
    pmac.command("&2 P2=Q6")  # the PLC's CMD wrote Q6 of &2
    assert memory.p[2] == 8


KINEMATICS = """\
I5150=1 I5113=0                 ; kinematic programs on, no segmentation
&1 #1->I #2->I
OPEN FORWARD 1 CLEAR
Q7=P1/1000 Q8=(P2-P1)/1000      ; X from motor 1, Y from the difference
CLOSE
OPEN INVERSE 1 CLEAR
P1=Q7*1000 P2=(Q7+Q8)*1000      ; motor 1 follows X, motor 2 X + Y
CLOSE
OPEN PROG 1 CLEAR
LINEAR ABS TA0 TS0 TM2
X1 Y2
CLOSE
"""


def test_inverse_kinematics_gives_the_motor_positions_of_each_move(sim: Simulation) -> None:
    """Axis positions in Q7 (X) and Q8 (Y) in, motor counts in P1 and P2 out (the Turbo User Manual's registers)."""
    pmac = Pmac(sim)
    pmac.load(KINEMATICS, source="k.pmc")
    pmac.command("&1 B1 R")
    _run(sim, pmac, 20)
    assert (pmac.motors[1].cmd, pmac.motors[2].cmd) == (1000, 3000)
    assert pmac.job.state == JobState.DONE


def test_forward_kinematics_finds_the_axes_at_run_and_pmatch(sim: Simulation) -> None:
    pmac = Pmac(sim)
    pmac.load(KINEMATICS.replace("X1 Y2", "X(Q7+1)"), source="k.pmc")  # a move relative to where X is found
    pmac.command("&1 B1 R")
    _run(sim, pmac, 20)  # motors at 1000 and 1000: X = 1, Y = 0
    assert (pmac.motors[1].cmd, pmac.motors[2].cmd) == (1000, 1000)
    pmac.command("&1 B1 R")
    _run(sim, pmac, 40)
    assert (pmac.motors[1].cmd, pmac.motors[2].cmd) == (2000, 2000)
    pmac.command("&1 PMATCH")
    assert pmac.coordinate_system(1).position("X") == 2


def test_a_kinematic_system_without_an_inverse_program_is_refused_at_the_move(sim: Simulation) -> None:
    pmac = Pmac(sim)
    pmac.load("I5150=1\n&1 #1->I\nOPEN PROG 1 CLEAR\nX1\nCLOSE\n", source="k.pmc")
    pmac.command("&1 B1 R")
    with pytest.raises(ConfigurationError, match=r"k.pmc:4:1: coordinate system 1 has motors #n->I \(#1\) and "
                                                 r"I5150=1, but no OPEN INVERSE program"):
        _run(sim, pmac, 5)


def test_one_line_buffers_enable_ranges_and_and_or_lines(sim: Simulation) -> None:
    pmac = Pmac(sim)
    pmac.load("I5=2\nOPEN PLC 1 CLEAR P1=P1+1 CLOSE\nOPEN PLC 2 CLEAR P2=P2+1 CLOSE\nOPEN PLC 3 CLEAR P3=P3+1 CLOSE\n"
              "OPEN PLC 4 CLEAR\nIF (P1>0)\nAND (P2>0)\nOR (P9=1)\nP4=1\nENDIF\nCLOSE\nENABLE PLC 1..2,4\n",
              source="o.pmc")
    pmac.programs.configure_scan(period=pmac.clock.t(1))
    _run(sim, pmac, 3)
    memory = pmac.programs.memory
    assert memory.p[1] > 0 and memory.p[2] > 0 and memory.p[3] == 0 and memory.p[4] == 1
    pmac.command("DISABLE PLC 1..4")
    assert pmac.programs.enabled == set()


def test_and_binds_tighter_than_or_across_continued_lines(sim: Simulation) -> None:
    """``IF (P1=1)`` / ``OR (P2=1)`` / ``AND (P3=1)`` is P1=1 OR (P2=1 AND P3=1)."""
    pmac = Pmac(sim)
    pmac.load("I5=2\nOPEN PLC 1 CLEAR\nIF (P1=1)\nOR (P2=1)\nAND (P3=1)\nP4=P4+1\nENDIF\nDISABLE PLC 1\nCLOSE\n"
              "P1=1 P2=0 P3=0\nENABLE PLC 1\n", source="o.pmc")
    _run(sim, pmac, 2)
    assert pmac.programs.memory.p[4] == 1


def test_cmd_and_control_characters_act_at_the_instant_the_program_reaches_them(sim: Simulation) -> None:
    pmac = Pmac(sim)
    pmac.load("I5=2\n&1 #1->1X\nOPEN PROG 1 CLEAR\nLINEAR TA0 TS0 F1000 X1000\nCLOSE\n"
              "OPEN PLC 1 CLEAR\nIF (P1=0) CMD\"&1B1R\" P1=1\nIF (P1=1 AND M1=0) P1=2\nCLOSE\n"
              "OPEN PLC 2 CLEAR\nIF (P1=2) COMMAND^A DISABLE PLC 2\nCLOSE\nM1->*\nENABLE PLC 1\n", source="c.pmc")
    pmac.programs.configure_scan(period=sim.ticks("10 ms"), offset=sim.ticks("10 ms"))
    pmac.start()
    sim.run(until=sim.ticks("11 ms"))
    assert pmac.job.state == JobState.RUNNING  # started by the CMD at 10 ms
    pmac.command("ENABLE PLC 2")
    sim.run(until=sim.ticks("21 ms"))  # ^A at 20 ms: every program aborted
    assert pmac.job.state == JobState.ABORTED
    position = pmac.coordinate_system(1).position("X")
    assert 0 < position < 1000
    sim.run(until=sim.ticks("30 ms"))
    assert pmac.coordinate_system(1).position("X") == position  # stopped where it was


def test_send_and_display_write_to_the_console(sim: Simulation) -> None:
    pmac = Pmac(sim)
    pmac.load("I5=2 P7=2.5\nOPEN PLC 3 CLEAR\nSEND1\"READY\"\nDISPLAY 40,6.2,P7\nDISABLE PLC 3\nCLOSE\nENABLE PLC 3\n",
              source="s.pmc")
    _run(sim, pmac, 1)
    assert [(line.source, line.text) for line in sim.trace.console()] == [("pmac.plc3", "READY"),
                                                                        ("pmac.plc3", "  2.50")]


def test_unmodelled_commands_are_listed_with_their_place(sim: Simulation) -> None:
    pmac = Pmac(sim)
    pmac.load("DEFINE GATHER\nGATHER\nEND GATHER\nDELETE GATHER\nMS0,MI910=$F\nFRAX(X,Y)\n#1HMZ\nLIST PLC 1\n",
              source="u.pmc")
    listed = {(item.name, item.where) for item in sim.notes.unmodelled()}
    assert {("DEFINE", "u.pmc:1:1"), ("GATHER", "u.pmc:2:1"), ("END", "u.pmc:3:1"), ("DELETE", "u.pmc:4:1"),
            ("MS", "u.pmc:5:1"), ("FRAX", "u.pmc:6:1"), ("#1 HMZ", "u.pmc:7:3"), ("LIST", "u.pmc:8:1")} <= listed


def test_circle_moves_in_the_normal_plane(sim: Simulation) -> None:
    """CIRCLE1 (clockwise seen with NORMAL K-1) from (10,0) about (0,0) to (0,-10): a quarter circle of 5 pi units."""
    pmac = Pmac(sim)
    pmac.load("&1 #1->1X #2->1Y\nOPEN PROG 1 CLEAR\nLINEAR ABS TA0 TS0 F10000 X10 Y0\nCIRCLE1 TM100 X0 Y-10 I-10 J0\n"
              "CLOSE\n", source="c.pmc")
    pmac.command("&1 B1 R")
    _run(sim, pmac, 3 + 230)  # 1 ms to (10, 0), then the 100 ms arc (TA0): 226 servo cycles
    cs = pmac.coordinate_system(1)
    assert (cs.position("X"), cs.position("Y")) == (0, -10)
    pmac2 = Pmac(sim2 := Simulation())
    pmac2.load("&1 #1->1X #2->1Y\nOPEN PROG 1 CLEAR\nLINEAR ABS TA0 TS0 F10000 X10 Y0\nCIRCLE1 TM100 X0 Y-10 I-10 J0\n"
               "CLOSE\n", source="c.pmc")
    pmac2.command("&1 B1 R")
    pmac2.start()
    sim2.run(until=pmac2.clock.t(3) + sim2.ticks("50 ms"))  # half way along the arc: 45 degrees
    x, y = float(pmac2.coordinate_system(1).position("X")), float(pmac2.coordinate_system(1).position("Y"))
    assert x * x + y * y == pytest.approx(100, rel=1e-9) and x > 0 > y


def test_pvt_moves_are_cubics_between_positions_and_velocities(sim: Simulation) -> None:
    """``PVT100`` then ``X100:1500``: rest to 100 units at 1500 units/s in 100 ms; at 50 ms the cubic is at 31.25."""
    pmac = Pmac(sim)
    pmac.load("&1 #1->1X\nOPEN PROG 1 CLEAR\nPVT100\nX100:1500\nX200:0\nCLOSE\n", source="p.pmc")
    pmac.command("&1 B1 R")
    pmac.start()
    t0 = pmac.clock.t(1)  # the program starts at servo cycle 1
    sim.run(until=t0 + sim.ticks("50 ms") + 1)
    cs = pmac.coordinate_system(1)
    # Hermite at s = 1/2: 100 / 2 + (s^3 - s^2) T v1 = 50 - 0.125 * 100 ms * 1.5 units/ms (plus < 1 cycle)
    assert abs(float(cs.position("X")) - 31.25) < 0.6
    sim.run(until=t0 + sim.ticks("200 ms") + pmac.clock.t(2))
    assert cs.position("X") == 200


def test_spline1_passes_through_its_points(sim: Simulation) -> None:
    pmac = Pmac(sim)
    pmac.load("&1 #1->1X\nOPEN PROG 1 CLEAR\nSPLINE1 TM50\nX10\nX30\nX40\nCLOSE\n", source="s.pmc")
    pmac.command("&1 B1 R")
    pmac.start()
    cs = pmac.coordinate_system(1)
    seen = []
    for k in range(1, 400):
        sim.run(until=pmac.clock.t(k) + 1)
        seen.append(cs.position("X"))
    assert (seen[-1] == 40 and 10 in seen) or any(abs(float(v) - 10) < 0.25 for v in seen)
    assert all(b >= a for a, b in itertools.pairwise(seen))  # monotonic through the points


def test_a_program_fault_stops_the_job_with_the_reason(sim: Simulation) -> None:
    pmac = Pmac(sim)
    pmac.load("&1 #1->1X\nOPEN PROG 1 CLEAR\nX1\nP1=1/0\nCLOSE\n", source="f.pmc")
    pmac.command("&1 B1 R")
    with pytest.raises(ConfigurationError, match=r"division by zero"):
        _run(sim, pmac, 10)
    assert pmac.job.state == JobState.ERROR
    (line,) = [line.text for line in sim.trace.console() if line.source == "pmac.job"]
    assert line.startswith("ERROR: f.pmc:4:") and "division by zero" in line


def test_home_and_jog_are_accepted_and_listed(sim: Simulation) -> None:
    pmac = Pmac(sim)
    pmac.load("&1 #1->1X\nOPEN PROG 1 CLEAR\nHOME1\nTA0 TS0 TM1 X1\nCLOSE\n#1J+\n#1J/\n", source="h.pmc")
    pmac.command("&1 B1 R")
    _run(sim, pmac, 10)
    names = {item.name for item in sim.notes.unmodelled()}
    assert {"HOME", "#1 J+", "#1 J/"} <= names
    assert pmac.coordinate_system(1).position("X") == 1


def test_times_and_feedrates_of_the_modal_state(sim: Simulation) -> None:
    """``F`` is in axis units per Isx90 ms: with I5190=60000 (per minute) F6000 is 100 units/s."""
    pmac = Pmac(sim)
    pmac.load("I5190=60000\n&1 #1->1X\nOPEN PROG 1 CLEAR\nLINEAR TA0 TS0 F6000 X1\nCLOSE\n", source="f.pmc")
    pmac.command("&1 B1 R")
    _run(sim, pmac, 1 + 23)  # 10 ms at 0.1 units/ms: 22.6 cycles
    assert pmac.coordinate_system(1).position("X") == 1
    assert Fraction(pmac.get_ivar(5190)) == 60000


def test_the_job_is_done_when_every_started_motion_program_has_ended(sim: Simulation) -> None:
    """Two programs from cycle 1 (442,708 ns); TM20 needs 46 cycles of I10 = 3,713,707 (46 x I10 >= 20 x 2^23).

        pmac.job   0 (idle) | 1 (running) from 442,708 ns ....................| 2 (done) at cycle 46: 20,364,585 ns
        PLC 1      scanning all along: PLCs are not the job
    """
    pmac = Pmac(sim)
    pmac.load("I5=2\n&1 #1->1X\n&2 #2->1Y\n"
              "OPEN PROG 1 CLEAR TA0 TS0 TM10 X1 CLOSE\nOPEN PROG 2 CLEAR TA0 TS0 TM20 Y1 CLOSE\n"
              "OPEN PLC 1 CLEAR P1=P1+1 CLOSE\nENABLE PLC 1\n", source="j.pmc")
    pmac.command("&1 B1 R &2 B2 R")
    _run(sim, pmac, 60)
    times, values = sim.trace.edges("pmac.job")
    assert [(int(t), int(v)) for t, v in zip(times, values, strict=True)] == [(0, 0), (442_708, 1), (20_364_585, 2)]
    assert pmac.programs.memory.p[1] > 60


def test_the_rotary_buffer_example_of_the_reference_loads_and_is_listed_not_modelled(sim: Simulation) -> None:
    """OPEN ROT: lines go to the addressed system's rotary buffer (``&1 X10 Y10 F5``); B0 points at it."""
    pmac = Pmac(sim)
    pmac.load("&1 #1->1X #2->1Y\n&2 #3->1X #4->1Y\n&2 DEFINE ROT 100\n&1 DEFINE ROT 100\n&1 B0 &2 B0\nOPEN ROT\n"
              "&1 X10 Y10 F5\n&2 X30 Y30 F10\nCLOSE\n&1R &2R\n", source="rot.pmc")
    listed = {(item.name, item.where) for item in sim.notes.unmodelled()}
    assert {("&1 B0", "rot.pmc:5:4"), ("&1 R", "rot.pmc:10:3"), ("&2 R", "rot.pmc:10:7")} <= listed
    _run(sim, pmac, 5)
    assert pmac.job.state == JobState.IDLE  # nothing runs: the rotary buffer is kept, not run


def test_open_rotary_takes_no_number(sim: Simulation) -> None:
    pmac = Pmac(sim)
    with pytest.raises(ConfigurationError, match=r"^r.pmc:2:13: OPEN ROTARY 8388607: a rotary buffer takes no number"):
        pmac.load("CLOSE\nOPEN ROTARY 8388607\nCLOSE\n", source="r.pmc")
