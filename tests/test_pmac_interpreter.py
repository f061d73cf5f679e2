"""Motion programs from text: calculated one move ahead in the servo cycle, moves exactly as the Python objects.

Most tests run at I10 = 2^21 (250 us servo cycles) and %100, so a program at F1000 (1 unit/ms) moves
0.25 units per cycle; the program is started with ``&1 B1 R`` before the servo clock, so it begins at
cycle 1 (coordinate systems start one cycle after the conversion table).
"""

from __future__ import annotations

from fractions import Fraction

import pytest
from cycle_probe import record_each_cycle

from cosim import rigs
from cosim.controllers.pmac import Pmac
from cosim.controllers.pmac.motion import Delay, Dwell, LinearMove, Move
from cosim.errors import ConfigurationError
from cosim.kernel import Simulation
from cosim.plants.analytic import IdealConveyor

PROGRAM = """\
OPEN PROG 1 CLEAR
LINEAR ABS
TA10 TS2 F64000 X100      ; trapezoid with S-curve ends
DELAY 5                   ; runs with the time base
TA4 TS3 F32000 X-50.5     ; TA < 2 TS: a pure S-curve of 6 ms
DWELL 3                   ; real time: breaks synchronism (reported)
TA0 TS0 F64000 X0         ; no ramp at all
TA20 TS10 TM30 X40        ; a move time instead of a feedrate
CLOSE
"""
ITEMS = [LinearMove(100, 64_000, 10, ts_ms=2), Delay(5), LinearMove(Fraction("-50.5"), 32_000, 4, ts_ms=3),
         Dwell(3), LinearMove(0, 64_000, 0), Move({"X": 40}, tm_ms=30, ta_ms=20, ts_ms=10)]


def _follow(sim: Simulation, *, text: bool) -> tuple[list[Fraction], rigs.Rig]:  # type: ignore[type-arg]
    """A slave under external time base from a master that speeds up and slows down; X each cycle."""
    ms = sim.ticks("1 ms")
    belt = IdealConveyor(sim, speed_counts_per_ms=48, phases=[(30 * ms, Fraction(1, 2)), (30 * ms, Fraction(-3, 4))])
    rig = rigs.external_time_base(sim, belt, scale_factor=2048, ix94=8_388_607)  # Ix94 at its maximum
    if text:
        rig.pmac.load(PROGRAM, source="follow.pmc")
        rig.pmac.command("&1 B1 R")
    else:
        rig.cs.run_program(ITEMS)
    rows = record_each_cycle(sim, rig.pmac.clock, lambda k, t: rig.cs.position("X"), cycles=700)
    rig.pmac.start()
    sim.run(until=rig.pmac.clock.t(700))
    return rows, rig


def test_a_program_from_text_moves_exactly_as_the_python_objects_under_external_time_base() -> None:
    """LINEAR with TA, TS, F and TM, DELAY and DWELL, under a master at 48 -> 63 -> 40.5 counts/ms:
    the same position at every one of 700 servo cycles (310 ms), as exact fractions."""
    with Simulation() as sim_a:
        from_text, rig_a = _follow(sim_a, text=True)
    with Simulation() as sim_b:
        from_objects, rig_b = _follow(sim_b, text=False)
    assert len(from_text) == len(from_objects) == 700
    assert from_text == from_objects
    assert len(set(from_text)) > 250  # it moved in most cycles
    assert from_text[-1] == 40 and min(from_text) == Fraction("-50.5") and max(from_text) == 100
    assert rig_a.cs.program_done and rig_b.cs.program_done
    assert [n for _, n in rig_a.cs.notes] == [n for _, n in rig_b.cs.notes]  # DWELL under external time base
    assert any("DWELL under external time base" in n for _, n in rig_a.cs.notes)


def _pmac(sim: Simulation, setup: str, program: str, *, command: str = "&1 B1 R") -> Pmac:
    pmac = Pmac(sim, i10=2**21)
    pmac.load(setup, source="setup.pmc")
    pmac.load(program, source="prog.pmc")
    if command:
        pmac.command(command)
    return pmac


def _run(sim: Simulation, pmac: Pmac, cycles: int, probe):  # type: ignore[no-untyped-def]
    rows = record_each_cycle(sim, pmac.clock, probe, cycles=cycles)
    pmac.start()
    sim.run(until=pmac.clock.t(cycles))
    return rows


def test_statements_between_moves_run_one_move_early_and_dwell_stops_the_lookahead(sim: Simulation) -> None:
    """``X1 P1=1 X2 P2=1 X3 DWELL0 P3=1 X4`` at 1 unit/ms (4 cycles a move):

        cycle   1    4     8    12   13    16
        X       .25  1     2    3    3.25  4
        P1      1                               set with X1's calculation, before X1 moves
        P2           1                          when X1 ends and X2 starts (X3 is calculated then)
        P3                      1               only when X3 and the DWELL are done
    """
    pmac = _pmac(sim, "&1 #1->1X", "OPEN PROG 1 CLEAR\nLINEAR ABS TA0 TS0 F1000\nX1 P1=1 X2 P2=1 X3 DWELL0 P3=1 X4\n"
                                   "CLOSE")
    p = pmac.programs.memory.p
    rows = _run(sim, pmac, 18, lambda k, t: (pmac.coordinate_system(1).position("X"), p[1], p[2],
                                              p[3]))
    x = [r[0] for r in rows]
    assert x == [0, *(Fraction(k, 4) for k in range(1, 13)), *(3 + Fraction(k, 4) for k in range(1, 5)), 4]
    assert [r[1] for r in rows].index(1) == 1
    assert [r[2] for r in rows].index(1) == 4
    assert [r[3] for r in rows].index(1) == 12


def test_a_loop_without_moves_makes_one_pass_per_servo_cycle(sim: Simulation) -> None:
    pmac = _pmac(sim, "&1 #1->1X", "OPEN PROG 1 CLEAR\nLINEAR ABS TA0 TS0 F1000\nP1=0\nWHILE (P1 < 5)\n P1=P1+1\n"
                                   "ENDWHILE\nX1\nCLOSE")
    rows = _run(sim, pmac, 10, lambda k, t: (pmac.programs.memory.p[1], pmac.coordinate_system(1).position("X")))
    assert [r[0] for r in rows] == [0, 1, 2, 3, 4, 5, 5, 5, 5, 5]
    assert [r[1] for r in rows] == [0] * 6 + [Fraction(1, 4), Fraction(1, 2), Fraction(3, 4), 1]


@pytest.mark.parametrize(
    ("setup", "program", "checks"),
    [
        # INC: each move relative to the end of the one before
        ("&1 #1->1X", "INC TA0 TS0 F1000 X1\nX1", {4: {"X": 1}, 6: {"X": Fraction(3, 2)}, 8: {"X": 2}}),
        # TM8 with TA2: 2 ms ramps, plateau 10/8 units/ms; at 2 ms the ramp has covered 1.25 units
        ("&1 #1->1X", "ABS TA2 TS0 TM8 X10", {8: {"X": Fraction(5, 4)}, 40: {"X": 10}}),
        # RAPID at the motor's jog speed: I122 = 10 counts/ms, #1->2X: 5 units/ms, no ramp (I120 = I121 = 0)
        ("&1 #1->2X I120=0 I121=0 I122=10", "RAPID ABS X50", {4: {"X": 5}, 40: {"X": 50}}),
        # two axes: the vector feedrate 5 units/ms along a 3-4-5 path
        ("&1 #1->1X #2->1Y", "LINEAR ABS TA0 TS0 F5000 X30 Y40", {4: {"X": 3, "Y": 4}, 40: {"X": 30, "Y": 40}}),
        # an irrational path length still ends exactly on the targets
        ("&1 #1->1X #2->1Y", "LINEAR ABS TA1 TS0 F1000 X1 Y1", {20: {"X": 1, "Y": 1}}),
        # the defaults Ix87 (TA 0), Ix88 (TS 50), Ix89 (F 1000): pure S-curves of 2 x 50 ms, move time 100 ms
        ("&1 #1->1X", "X1", {200: {"X": Fraction(1, 12)}, 400: {"X": Fraction(1, 2)}, 800: {"X": 1}}),
    ],
)
def test_inc_tm_rapid_vector_feedrate_and_defaults(sim: Simulation, setup: str, program: str,
                                                   checks: dict[int, dict[str, Fraction]]) -> None:
    pmac = _pmac(sim, setup, f"OPEN PROG 1 CLEAR\n{program}\nCLOSE")
    cs = pmac.coordinate_system(1)
    axes = sorted({a for c in checks.values() for a in c})
    rows = _run(sim, pmac, max(checks) + 1, lambda k, t: {a: cs.position(a) for a in axes})
    for cycle, expected in checks.items():
        assert rows[cycle] == expected, cycle


def test_feed_hold_slews_to_zero_at_ix95_and_r_slews_back(sim: Simulation) -> None:
    """%100 = I10 = 2,097,152; I5195 = 524,288: four cycles down to 0, four back."""
    pmac = _pmac(sim, "&1 #1->1X I5195=524288", "OPEN PROG 1 CLEAR\nTA0 TS0 F1000 X100\nCLOSE")
    cs = pmac.coordinate_system(1)

    def host():  # type: ignore[no-untyped-def]
        from cosim.timebase import Priority
        yield sim.at(pmac.clock.t(10) + 1, Priority.HOST)
        pmac.command("H")
        yield sim.at(pmac.clock.t(20) + 1, Priority.HOST)
        pmac.command("R")

    sim.process(host())
    rows = _run(sim, pmac, 26, lambda k, t: cs.actual)
    assert rows[10:26] == [2**21, 3 * 2**19, 2**20, 2**19, 0, 0, 0, 0, 0, 0, 0, 2**19, 2**20, 3 * 2**19, 2**21,
                           2**21]


def test_plc_background_scans_at_their_period_and_a_while_loop_ends_a_scan(sim: Simulation) -> None:
    """Scans at 50 us + k * 100 us. PLC 1: P3 counts passes through its top; each WHILE pass ends the scan.

        scan   1: P3=1, P1=1 | 2: P1=2 | 3: P1=3 | 4: loop done, P2=1 | 5: P3=2, P2=2 | ...
    """
    plc = "OPEN PLC 1 CLEAR\nP3=P3+1\nWHILE (P1 < 3)\n P1=P1+1\nENDWHILE\nP2=P2+1\nCLOSE"
    pmac = _pmac(sim, "I5=2\n&1 #1->1X", plc, command="ENABLE PLC 1")
    pmac.programs.configure_scan(period=sim.ticks("100 us"), offset=sim.ticks("50 us"))
    pmac.start()
    sim.run(until=sim.ticks("550 us"))  # scans at 50, 150, 250, 350, 450 us (not yet 550)
    p = pmac.programs.memory.p
    assert pmac.programs.scans == 5
    assert (p[1], p[2], p[3]) == (3, 2, 2)


def test_plc_0_runs_every_servo_cycle_and_plcs_start_and_stop_each_other(sim: Simulation) -> None:
    text = ("OPEN PLC 0 CLEAR\nP1=P1+1\nIF (P1=3) ENABLE PLC 2\nIF (P1=5) DISABLE PLC 0\nCLOSE\n"
            "OPEN PLC 2 CLEAR\nP2=P2+1\nCLOSE\n")
    pmac = _pmac(sim, "I5=3", text, command="ENABLE PLC 0")
    pmac.programs.configure_scan(period=sim.ticks("1 ms"))
    pmac.start()
    sim.run(until=pmac.clock.t(12))  # servo cycles 1..11 run PLC 0 (cycle 0 is the table's first)
    p = pmac.programs.memory.p
    assert p[1] == 5  # disabled itself at its 5th scan
    assert p[2] == 2  # background scans at 1 ms and 2 ms after PLC 0 enabled it in cycle 3 (0.75 ms)


def test_a_plc_starts_a_motion_program_with_cmd(sim: Simulation) -> None:
    text = "OPEN PROG 3 CLEAR\nTA0 TS0 F1000 X1\nCLOSE\nOPEN PLC 1 CLEAR\nCMD\"&1 B3 R\"\nDISABLE PLC 1\nCLOSE\n"
    pmac = _pmac(sim, "I5=2\n&1 #1->1X", text, command="ENABLE PLC 1")
    pmac.programs.configure_scan(period=sim.ticks("1 ms"), offset=sim.ticks("600 us"))
    rows = _run(sim, pmac, 6, lambda k, t: pmac.coordinate_system(1).position("X"))
    assert rows == [0, 0, 0, Fraction(1, 4), Fraction(1, 2), Fraction(3, 4)]  # issued at 0.6 ms, runs from cycle 3


def test_m_variables_read_and_write_registers(sim: Simulation) -> None:
    """M103 on the capture register (a read re-arms it); M8000 on the method digit of I8000's table line."""
    from cosim.signals import Signal

    belt = IdealConveyor(sim, speed_counts_per_ms=64)
    trigger = Signal(sim, "sensor", kind="bit")
    pmac = Pmac(sim)
    channel = pmac.add_channel(0x078008, belt, trigger=trigger)
    pmac.load("I8000=$978008 I8001=256 I5193=@I8001\nM103->X:$07800B,0,24,S M8000->Y:$3501,20,4\n"
              "M1->* M2->X:$078008,0,8,S", source="setup.pmc")
    pmac.start()
    sim.run(until=sim.ticks("1 ms"))
    trigger.set(1)  # latches the capture at 1 ms: 64 counts
    trigger.set(0)
    assert channel.capture_flag
    pmac.command("P1=M103 M8000=11 P2=M8000 M1=1/3 P3=M1*3")
    memory = pmac.programs.memory
    assert memory.p[1] == 64 and not channel.capture_flag  # read and re-armed
    assert pmac.get_ivar(8000) == 0xB78008 and memory.p[2] == 11
    assert memory.p[3] == 1
    sim.run(until=sim.ticks("3 ms"))  # 192 counts: the low 8 bits as a signed field are -64
    pmac.command("P4=M2")
    assert memory.p[4] == 192 - 256
    with pytest.raises(ConfigurationError, match=r"^cmd:1:1: M103->X:\$07800B,0,24,S: X registers are read-only"):
        pmac.command("M103=5", source="cmd")
    with pytest.raises(ConfigurationError, match=r"^cmd:1:1: I5194 \(Ix94, time-base slew limit\) = 2.5 is not "
                                                 r"allowed \(allowed: integers 0..8388607"):
        pmac.command("I5194=5/2", source="cmd")


def test_run_time_errors_name_the_statement(sim: Simulation) -> None:
    pmac = _pmac(sim, "&1 #1->1X", "OPEN PROG 1 CLEAR\nP1=0\nTA0 TS0 F(1/P1) X1\nCLOSE")
    pmac.start()
    with pytest.raises(ConfigurationError, match=r"^prog.pmc:3:11: division by zero \(1 / 0\)$"):
        sim.run(until=pmac.clock.t(3))


def test_numbers_stay_bounded_in_48_bits(sim: Simulation) -> None:
    """P1=P1/3: exact while the denominator fits 48 bits (3^30 < 2^48), then the nearest value with one that
    does (within 2^-49); growth past 2^47 is an error."""
    text = "OPEN PLC 1 CLEAR\nIF (P2=0) P1=1\nWHILE (P2 < 40) P1=P1/3 P2=P2+1 IF (P2=30) P3=P1\nCLOSE"
    pmac = _pmac(sim, "I5=2", text, command="ENABLE PLC 1")
    pmac.programs.configure_scan(period=sim.ticks("10 us"))
    pmac.start()
    sim.run(until=sim.ticks("1 ms"))
    p = pmac.programs.memory.p
    assert p[2] == 40 and p[3] == Fraction(1, 3**30)
    assert p[1].denominator <= 2**48 and abs(p[1] - Fraction(1, 3**40)) <= Fraction(1, 2**49)
    with pytest.raises(ConfigurationError, match=r"^cmd:1:4: 70368744177664 \* 2 = 1.40737e\+14 is not allowed "
                                                 r"\(allowed: \|value\| < 2\^47"):
        pmac.command("P5=$400000000000*2", source="cmd")


@pytest.mark.parametrize(("scan_us", "offset_us", "dummy_read", "stale"), [
    (100, 0, False, True),      # light load: armed before a servo cycle sees the entry frozen
    (100, 0, True, False),      # light load with the manual's dummy read
    (5000, 0, False, False),    # heavy load: the frozen entry's reads reset the trigger logic first
])
def test_the_stale_capture_hazard_depends_on_the_plc_scan(sim: Simulation, scan_us: int, offset_us: int,
                                                          dummy_read: bool, stale: bool) -> None:
    """The manual's recipe as text on an exact 64 counts/ms belt with marks at 500 and 1500 counts; the
    entry runs from power-up (mark 1's capture is never read); B1 R at 12 ms."""
    belt = IdealConveyor(sim, speed_counts_per_ms=64, marks=[500, 1500], mark_width_counts=5)
    pmac = Pmac(sim)
    pmac.add_channel(0x078008, belt, trigger=belt.mark)
    pmac.load("I5=2 I8000=$A78008 I8001=256 I5193=@I8001 I5194=8388607\nM103->X:$07800B,0,24,S\n&1 #1->1X")
    read = "P103=M103\n" if dummy_read else ""
    pmac.load(f"OPEN PROG 1 CLEAR\nLINEAR ABS TA10 F64000\nDWELL0\nI8000=$978008\n{read}X3000\nCLOSE\n"
              "OPEN PLC 1 CLEAR\nIF (I8000=$978008) I8000=$B78008\nCLOSE\nENABLE PLC 1")
    pmac.programs.configure_scan(period=sim.ticks(scan_us, "us"), offset=sim.ticks(offset_us, "us"))
    from cosim.timebase import Priority
    sim.call_at(sim.ticks("12 ms"), Priority.HOST, lambda: pmac.command("&1 B1 R"))
    pmac.start()
    sim.run(until=sim.ticks("40 ms"))
    entry = pmac.table.entry_at(0x3501)
    (start,) = entry.starts  # type: ignore[union-attr]
    if stale:
        assert start.stale and start.time_zero_pos256 == 500 * 256 and start.t < belt.mark_times[1][0]
    else:
        assert not start.stale and start.capture_t == belt.mark_times[1][0]
        assert abs(Fraction(start.time_zero_pos256, 256) - 1500) <= Fraction(1, 256)
