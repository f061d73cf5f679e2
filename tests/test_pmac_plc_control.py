"""Which PLC programs run: I5 and ENABLE / DISABLE PLC, as the Turbo PMAC Software Reference has them.

I5 (PLC program control; range 0..3, default 1): 0 foreground and background PLCs off, 1 foreground
(PLC 0) on and background (PLC 1..31) off, 2 foreground off and background on, 3 both on. An
individual PLC still needs ENABLE PLC to run. ENABLE / DISABLE PLC over numbers that hold no program
(download files disable 2..31 whatever exists) do nothing to them.

Servo clock 2^21 / 442,708 ns cycles (default I10); background scans every 1 ms (at 1, 2, 3 ... ms).
"""

from __future__ import annotations

import pytest

from cosim.controllers.pmac import Pmac
from cosim.kernel import Simulation

PLCS = ("OPEN PLC 0 CLEAR\nP10=P10+1\nCLOSE\n"  # foreground: counts servo cycles
        "OPEN PLC 1 CLEAR\nP11=P11+1\nCLOSE\n")  # background: counts scans


def _counts(sim: Simulation, setup: str) -> tuple[int, int]:
    pmac = Pmac(sim)
    pmac.load(setup + PLCS + "ENABLE PLC 0,1\n", source="setup.pmc")
    pmac.programs.configure_scan(period=sim.ticks("1 ms"), offset=sim.ticks("1 ms"))
    pmac.start()
    sim.run(until=sim.ticks("5 ms") + 1)  # servo cycles 1..11 (cycle 0 is the table's first); scans at 1..5 ms
    memory = pmac.programs.memory
    return int(memory.p[10]), int(memory.p[11])


@pytest.mark.parametrize(("setup", "plc0_scans", "plc1_scans"), [
    ("", 11, 0),  # I5 left at its default 1: only PLC 0
    ("I5=0\n", 0, 0),
    ("I5=1\n", 11, 0),
    ("I5=2\n", 0, 5),
    ("I5=3\n", 11, 5),
])
def test_i5_permits_the_foreground_and_background_plcs(sim: Simulation, setup: str, plc0_scans: int,
                                                       plc1_scans: int) -> None:
    assert _counts(sim, setup) == (plc0_scans, plc1_scans)


def test_enabling_a_plc_that_i5_keeps_off_is_in_the_notes(sim: Simulation) -> None:
    pmac = Pmac(sim)
    pmac.load(PLCS + "ENABLE PLC 1\n", source="p.pmc")
    pmac.start()
    assert any("ENABLE PLC 1 at p.pmc:7:1: I5 = 1 keeps the background PLCs 1..31 off" in text
               for text in sim.notes.texts())
    assert not any(item.name == "I5" for item in sim.notes.unmodelled())  # I5 acts: not "set, not modelled"


def test_i5_set_after_the_enable_in_the_same_file_counts_and_leaves_no_note(sim: Simulation) -> None:
    pmac = Pmac(sim)
    pmac.load(PLCS + "ENABLE PLC 0,1\nI5=3\n", source="late.pmc")
    pmac.start()
    assert not any("I5 = " in text for text in sim.notes.texts())


def test_a_plc_that_sets_i5_starts_the_background(sim: Simulation) -> None:
    """PLC 0 counts to 3 (servo cycle 3 at 1.33 ms) and sets I5=3: background PLC 1 scans from 2 ms on."""
    pmac = Pmac(sim)
    pmac.load("OPEN PLC 0 CLEAR\nP10=P10+1\nIF (P10=3) I5=3\nCLOSE\nOPEN PLC 1 CLEAR\nP11=P11+1\nCLOSE\n"
              "ENABLE PLC 0,1\n", source="w.pmc")
    pmac.programs.configure_scan(period=sim.ticks("1 ms"), offset=sim.ticks("1 ms"))
    pmac.start()
    sim.run(until=sim.ticks("5 ms") + 1)
    assert pmac.get_ivar(5) == 3
    assert pmac.programs.memory.p[11] == 4  # scans at 2, 3, 4, 5 ms


def test_disable_plc_over_a_range_with_missing_programs(sim: Simulation) -> None:
    """``DISABLE PLC 2..31`` of a real download file, with PLC 5 and 6 only: accepted, they stop, a note."""
    pmac = Pmac(sim)
    pmac.load("I5=2\nOPEN PLC 5 CLEAR\nP5=P5+1\nCLOSE\nOPEN PLC 6 CLEAR\nP6=P6+1\nCLOSE\nENABLE PLC 2..31\n"
              "DISABLE PLC 2..31\nENABLE PLC 6\n", source="dl.pmc")
    assert pmac.programs.enabled == {6}
    notes = sim.notes.texts()
    assert any("DISABLE PLC at dl.pmc:9:1: no PLC program 2..4, 7..31 (no effect on them; PLC programs: 5, 6)"
               in text for text in notes)
    pmac.programs.configure_scan(period=sim.ticks("1 ms"), offset=sim.ticks("1 ms"))
    pmac.start()
    sim.run(until=sim.ticks("3 ms") + 1)
    assert (pmac.programs.memory.p[5], pmac.programs.memory.p[6]) == (0, 3)


def test_a_program_enabling_a_missing_plc_runs_and_the_notes_say_so(sim: Simulation) -> None:
    pmac = Pmac(sim)
    pmac.load("I5=2\nOPEN PLC 1 CLEAR\nENABLE PLC 3\nP1=P1+1\nDISABLE PLC 1\nCLOSE\nENABLE PLC 1\n", source="m.pmc")
    pmac.programs.configure_scan(period=sim.ticks("1 ms"), offset=sim.ticks("1 ms"))
    pmac.start()
    sim.run(until=sim.ticks("2 ms") + 1)
    assert pmac.programs.memory.p[1] == 1
    assert any("ENABLE PLC at m.pmc:3:1: no PLC program 3 (no effect on it; PLC programs: 1)" in text
               for text in sim.notes.texts())
