"""The Trio laser engraver machine (examples/trio_engraver) and Trio programs run from their text by the CLI.

engraver.toml: two programs (engrave.bas moves an outline with arcs, gatefeed.bas loads the gating FIFO) on a
EURO205X, two Stepper FMUs and the Laser FMU.
"""

from __future__ import annotations

import json
import shutil
from fractions import Fraction
from math import ceil, floor
from pathlib import Path

import numpy as np
import pytest
from test_trio_basic import closed_form_position

from cosim.checks import EnergyPerLength
from cosim.cli import main
from cosim.controllers.trio.basic import example
from cosim.export import read_trace
from cosim.machine import load_machine
from cosim.runner import run_scenario
from cosim.trace import Trace

MS = 1_000_000
ENGRAVER = Path(__file__).resolve().parent.parent / "examples" / "trio_engraver"


@pytest.mark.fmu
def test_the_engraver_machine_runs_two_programs_and_passes_its_checks(tmp_path: Path) -> None:
    result = run_scenario(load_machine(ENGRAVER / "engraver.toml"), out=tmp_path / "out")
    assert result.verdict == "PASS", result.table()
    figures = {k: v["value"] for k, v in result.figures.items()}
    # X: 50 + 50 mm of long edges and 4 x 5 mm across the corners; Y: 2 x 20 + 4 x 5 mm; 80 steps/mm
    assert (figures["axis3_step_pulses"], figures["axis2_step_pulses"]) == (9600, 4800)
    assert figures["axis3_late_positions"] == 0 and figures["peak_mark_clocks"] == 500
    assert figures["printed_lines"] == 5  # lid, start, two FIFO loads (process 2), done
    energy = next(c for c in result.checks if c["name"].startswith("laser energy per mm"))
    assert energy["checked"] >= 100 and 0.39 < energy["measured"]["mean_j_per_unit"] < 0.41
    trace = read_trace(tmp_path / "out")
    t_print, _ = trace.edges("trio.print")
    assert t_print[1:3].tolist() == [0, 30 * MS]  # "waiting for the lid" at 0, "engraving" when IN(0) closed


@pytest.mark.fmu
def test_set_changes_a_machine_file_key(tmp_path: Path) -> None:
    """--set until="2 s": the job is cut short, the outline does not close and the run fails (exit 1)."""
    code = main(["run", str(ENGRAVER / "engraver.toml"), "--set", 'until="2 s"', "--out", str(tmp_path / "o")])
    assert code == 1


@pytest.mark.fmu
def test_without_the_speed_link_the_corners_get_more_energy_per_mm(tmp_path: Path) -> None:
    """The same job with a fixed mark (PWM_MARK=500, PWM_CONTROL(1)): the energy per mm check fails where the
    axes slow down into and out of every move."""
    folder = tmp_path / "engraver"
    shutil.copytree(ENGRAVER, folder)
    program = folder / "engrave.bas"
    text = program.read_text()
    linked = "PWM_CONTROL(2, 1000000, 0, 600, 3)"
    assert linked in text
    program.write_text(text.replace(linked, "PWM_MARK = 500\nPWM_CONTROL(1)"))
    result = run_scenario(load_machine(folder / "engraver.toml"))
    energy = next(c for c in result.checks if c["name"].startswith("laser energy per mm"))
    assert not energy["passed"] and energy["measured"]["max_j_per_unit"] > 0.44


def gate_counts(trace: Trace, axis: int = 3) -> list[tuple[int, int, int]]:
    """(t, level, signed count of the pulses whose leading edge is at or before t) of each gate edge."""
    t, v = trace.edges(f"trio.axis{axis}.gate")
    tp, dp = trace.pulses(f"trio.axis{axis}.step")
    count = np.concatenate([[0], np.cumsum(dp.astype(np.int64) * 2 - 1)])
    at = np.searchsorted(tp, t[1:], side="right")
    return [(int(a), int(b), int(count[i])) for a, b, i in zip(t[1:], v[1:], at, strict=True)]


def test_the_note_program_with_other_units_table_and_targets_runs_from_its_text_through_the_cli(
        tmp_path: Path) -> None:
    """tn20_81.bas with UNITS=10, positions 37.35 40.05 88.8 120 and MOVEABS(150) / MOVEABS(-5), run by
    ``cosim run variant.bas --machine note.toml``. Expected counts in closed form: GT at the first count above
    p x 10 (374, 401, 889, 1201), LT at the first count below (1199, 887, 400, 373); each edge at the active
    (falling, 100 ns after the leading) edge of the pulse that reaches the count, in a trapezoid (here a
    triangle: SPEED 1000, ACCEL = DECEL = 1000 units/s^2) evaluated at the end of each 1 ms servo cycle."""
    text = example("tn20_81").text
    for old, new in (("UNITS=16", "UNITS=10"), ("TABLE(1000,110,115,195,220)", "TABLE(1000,37.35,40.05,88.8,120)"),
                     ("TABLE(2000,220,195,115,110)", "TABLE(2000,120,88.8,40.05,37.35)"),
                     ("MOVEABS(300)", "MOVEABS(150)"), ("MOVEABS(0)", "MOVEABS(-5)")):
        assert old in text
        text = text.replace(old, new)
    (tmp_path / "variant.bas").write_text(text)
    (tmp_path / "note.toml").write_text('[machine]\nuntil = "2 s"\n[controller]\nfamily = "trio"\n'
                                        '[job]\ncheck = true\n'
                                        '[[program]]\nfile = "unused.bas"\n')
    (tmp_path / "unused.bas").write_text("WA(1)\n")
    out = tmp_path / "out"
    # the variant repeats for ever, and note.toml has no checks: this test checks the trace
    assert main(["run", str(tmp_path / "variant.bas"), "--machine", str(tmp_path / "note.toml"),
                 "--set", "job.check=false", "--out", str(out), "--allow-unchecked"]) == 0
    trace = read_trace(out)

    def steps(length: int) -> list[int]:
        s, duration = closed_form_position(Fraction(length), Fraction(1000), Fraction(1000), Fraction(1000))
        return [floor(10 * s(Fraction(j, 1000))) for j in range(ceil(duration * 1000) + 1)]

    def active_edge(t_start: int, counts: list[int], n: int) -> int:
        j = next(j for j in range(len(counts) - 1) if counts[j + 1] >= n)
        return t_start + j * MS + ((n - counts[j] - 1) * MS) // (counts[j + 1] - counts[j]) + 100

    forward, back = steps(150), steps(155)
    t_back = MS + len(forward) * MS  # loaded one tick after WAIT IDLE returned
    expected = [(active_edge(MS, forward, n), level, n) for n, level in ((374, 1), (401, 0), (889, 1), (1201, 0))]
    expected += [(active_edge(t_back, back, 1500 - n), level, n)
                 for n, level in ((1199, 1), (887, 0), (400, 1), (373, 0))]
    assert gate_counts(trace)[:8] == expected


def test_energy_per_length_on_a_synthetic_trace() -> None:
    """One unit of path per 10 ticks; 0.5 J per unit until t = 200, then 1 J per unit. The gate is off from 205 to
    255: the 20 units before count as 10 windows of 2 units at 0.5 J/unit, the 14 after as 7 windows at 1 J/unit
    (violations); the two sample intervals with a gate edge in them count in none."""
    trace = Trace()
    for name, kind in (("e", "real"), ("x", "real"), ("y", "real"), ("g", "bit")):
        trace.declare(name, kind)
    for k in range(41):
        trace.record("e", k * 10, k / 2 if k <= 20 else 10 + (k - 20))
        trace.record("x", k * 10, 0.6 * k)
        trace.record("y", k * 10, 0.8 * k)
    trace.record("g", 0, 1)
    trace.record("g", 205, 0)
    trace.record("g", 255, 1)
    result = EnergyPerLength("e", ["x", "y"], lower=0.45, upper=0.55, window=2.0, gate="g").evaluate(trace)
    assert (result.checked, result.n_violations) == (17, 7)
    assert result.measured["min_j_per_unit"] == pytest.approx(0.5) and result.measured["max_j_per_unit"] == (
        pytest.approx(1.0))
    assert result.violations[0].t_ns == 280  # the first window after the gate is back: 260..280


@pytest.mark.fmu
def test_a_bad_program_is_refused_by_the_cli_with_file_line_column_and_nothing_runs(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    program = tmp_path / "job.bas"
    program.write_text("BASE(3)\nUNITS = 80\nMOVECIRC(1, 2, 3, 4)\n")
    out = tmp_path / "out"
    code = main(["run", str(program), "--machine", str(ENGRAVER / "engraver.toml"), "--out", str(out)])
    assert code == 2
    assert ("job.bas line 3, column 1: number of MOVECIRC arguments = 4 is not allowed (allowed: 5: "
            "MOVECIRC(end1, end2, centre1, centre2, direction))") in capsys.readouterr().out
    assert not (out / "trace_meta.json").exists() or read_trace(out).end_t == 0  # nothing was simulated


@pytest.mark.fmu
def test_a_program_error_at_run_time_ends_the_run_with_its_line_and_the_trace_so_far(tmp_path: Path) -> None:
    """Axis 2 drives the Y stepper; the program makes it virtual and moves it at 5 ms: the run stops there."""
    program = tmp_path / "job.bas"
    program.write_text("BASE(2)\nATYPE = 0\nWA(5)\nMOVE(10)\n")
    out = tmp_path / "out"
    assert main(["run", str(program), "--machine", str(ENGRAVER / "engraver.toml"), "--out", str(out)]) != 0
    result = json.loads((out / "result.json").read_text())
    assert result["verdict"] == "ERROR"
    assert "job.bas line 4: MOVE on axis 2: its step/direction output drives a plant, but ATYPE = 0" in result["error"]
    assert read_trace(out).end_t == 5 * MS
