"""Structure and processes of Trio BASIC (issue 28, item 2) and the job signal.

INCLUDE, labels, GOSUB and ON ... GOSUB, RUN / STOP / HALT / PROCESS, PROC(n), PROC_STATUS,
PROCNUMBER, the priorities of TRM 7-12 (the servo period is shared by three time slots; the Euro 205's
high-priority tasks are processes 5 and 4), WAIT IDLE / LOADED / UNTIL and TICKS; the ``trio.job``
signal: the processes a machine starts, until each has stopped.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from cosim.controllers.trio import TrioController
from cosim.controllers.trio.basic import BasicProgram
from cosim.errors import ConfigurationError
from cosim.job import JobState
from cosim.kernel import Simulation

MS = 1_000_000


def test_include_compiles_another_file_in_place_and_its_errors_name_it(tmp_path: Path) -> None:
    (tmp_path / "defs.bas").write_text('CONSTANT "speed_mm", 40\n')
    (tmp_path / "subs.bas").write_text("sub_set:\n  VR(1) = speed_mm\n  RETURN\n")
    (tmp_path / "main.bas").write_text('INCLUDE "defs"\nGOSUB sub_set\nVR(0) = speed_mm + 2\nSTOP\nINCLUDE "subs"\n')
    trio = TrioController(Simulation(seed=1))
    BasicProgram.load(tmp_path / "main.bas").start(trio)
    trio.sim.run(until=MS)
    assert (trio.vr(0), trio.vr(1)) == (42, 40)
    (tmp_path / "bad.bas").write_text("x = 1\nMOVX(2)\n")
    (tmp_path / "uses.bas").write_text('INCLUDE "bad"\n')
    with pytest.raises(ConfigurationError, match=r"^bad.bas line 2, column 1: unknown keyword MOVX"):
        BasicProgram.load(tmp_path / "uses.bas")
    with pytest.raises(ConfigurationError, match=r'uses2.bas line 1, column 9: INCLUDE "nothere": no program nothere'):
        (tmp_path / "uses2.bas").write_text('INCLUDE "nothere"\n')
        BasicProgram.load(tmp_path / "uses2.bas")


def test_on_goto_and_on_gosub_jump_to_the_nth_label() -> None:
    """ON n GOSUB a, b, c: n = 2 calls b; an n outside 1..3 goes on with the next statement."""
    trio = TrioController(Simulation(seed=1))
    BasicProgram.parse("n = 2\nON n GOSUB a, b, c\nON 7 GOTO a, b\nVR(5) = 1\nSTOP\na:\nVR(0) = 1\nRETURN\n"
                       "b:\nVR(0) = 2\nRETURN\nc:\nVR(0) = 3\nRETURN\n", name="t.bas").start(trio)
    trio.sim.run(until=MS)
    assert (trio.vr(0), trio.vr(5)) == (2, 1)


def test_run_stop_proc_status_procnumber_and_ticks_of_another_process() -> None:
    """main starts helper on process 3 (RUN "HELPER", 3), reads its PROC_STATUS and TICKS PROC(3), then
    stops it (STOP "HELPER")."""
    sim = Simulation(seed=1)
    trio = TrioController(sim)
    BasicProgram.parse("TICKS = 100\nVR(20) = PROCNUMBER\nWHILE TRUE\n  WA(1)\nWEND\n", name="helper.bas").install(trio)
    BasicProgram.parse('RUN "HELPER", 3\nWA(5)\nVR(0) = PROC_STATUS PROC(3)\nVR(1) = TICKS PROC(3)\n'
                       'VR(2) = PROCNUMBER\nSTOP "HELPER"\nWA(1)\nVR(3) = PROC_STATUS PROC(3)\n',
                       name="main.bas").start(trio)
    sim.run(until=10 * MS)
    assert [trio.vr(k) for k in range(4)] == [1, 95, 1, 0]
    assert trio.vr(20) == 3


def test_halt_stops_every_program() -> None:
    """loop.bas counts at 0, 1 and 2 ms; at 3 ms boss.bas (waiting since 0) runs first and HALTs both."""
    sim = Simulation(seed=1)
    trio = TrioController(sim)
    BasicProgram.parse("WHILE TRUE\n  VR(1) = VR(1) + 1\n  WA(1)\nWEND\n", name="loop.bas").start(trio, process=2)
    BasicProgram.parse("WA(3)\nHALT\nVR(2) = 1\n", name="boss.bas").start(trio, process=1)
    sim.run(until=10 * MS)
    assert trio.processes == {} and trio.vr(1) == 3 and trio.vr(2) == 0


def test_process_prints_the_running_programs() -> None:
    sim = Simulation(seed=1)
    trio = TrioController(sim)
    BasicProgram.parse("WA(5)\n", name="other.bas").start(trio, process=4)
    BasicProgram.parse("PROCESS\n", name="t.bas").start(trio, process=1)
    sim.run(until=MS)
    assert [c.text for c in trio.console.lines] == ["Process 1: t.bas running", "Process 4: other.bas running"]


def test_high_priority_processes_run_first_at_an_instant() -> None:
    """TRM 7-12: on a Euro 205 processes 5 and 4 are the high-priority tasks. Started at the same instant,
    5 runs first, then 4, then the others in the order they became ready."""
    sim = Simulation(seed=1)
    trio = TrioController(sim)
    for number in (1, 4, 2, 5):
        BasicProgram.parse(f"VR(VR(0) + 1) = {number}\nVR(0) = VR(0) + 1\n", name=f"p{number}.bas").start(
            trio, process=number)
    sim.run(until=MS)
    assert [trio.vr(k) for k in range(1, 5)] == [5, 4, 1, 2]


def test_wait_loaded_returns_when_the_next_move_buffer_empties() -> None:
    """Two MOVEs of 9 units at 100 units/s (0.1 s each, ramps of 10 ms): the first runs from the tick at 1 ms
    (its last cycle ends at 101 ms), the second waits in the next-move buffer and loads at 101 ms, where
    WAIT LOADED returns; it ends at 201 ms, where WAIT IDLE returns."""
    sim = Simulation(seed=1)
    trio = TrioController(sim)
    BasicProgram.parse("BASE(0)\nSPEED = 100\nACCEL = 10000\nDECEL = 10000\nMOVE(9)\nMOVE(9)\nWAIT LOADED\n"
                       "VR(0) = TICKS\nWAIT IDLE\nVR(1) = TICKS\n", name="t.bas").start(trio)
    sim.run(until=300 * MS)
    assert (trio.vr(0), trio.vr(1)) == (-101, -201)


def test_the_job_is_the_processes_started_as_parts_until_each_stops() -> None:
    """A job part finishes when its process ends; a process started with job=False (a background task) is
    not waited for; RUN from a job process makes a part."""
    sim = Simulation(seed=1)
    trio = TrioController(sim)
    BasicProgram.parse("WA(3)\n", name="child.bas").install(trio)
    BasicProgram.parse('WA(2)\nRUN "CHILD"\n', name="main.bas").start(trio, process=1, job=True)
    BasicProgram.parse("WHILE TRUE\n  WA(1)\nWEND\n", name="beat.bas").start(trio, process=5, job=False)
    sim.run(until=10 * MS)
    t, v = sim.trace.edges("trio.job")
    assert list(zip(t.tolist(), v.tolist(), strict=True)) == [(0, 0), (0, 1), (5 * MS, 2)]
    assert trio.job.state == JobState.DONE
