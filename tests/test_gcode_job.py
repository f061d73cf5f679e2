"""A G-code program as the PoKeys machine's job: the job signal, the host's outputs, the console, subroutine files.

    job.nc ──host──> slots ──engine──> pokeys.job:        1 (from 0) ....................... 2 (buffer drained)
                                       pokeys.coolant_flood  1 (M8) ......... 0 (M9)
                                       pokeys.tool_changing            1 (1 s) 0
                                       pokeys.paused                              1 (0.5 s) 0
                                       console "gcode": MSG text at the slot the host reaches it

Times come from the machine file (``tool_change_time = "1 s"``, ``pause_time = "500 ms"``) and the
1 ms slot of the engine; the checks read the trace as run.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from cosim.export import read_trace
from cosim.job import JobState
from cosim.machine import load_machine
from cosim.runner import run_scenario

MS = 1_000_000

MACHINE = """
[machine]
until = "10 s"

[controller]
family = "pokeys"
[controller.axis.x]
steps_per_unit = 400
max_velocity = 50
max_accel = 1000
limit_pos_enabled = true
[controller.axis.y]
steps_per_unit = 400
max_velocity = 50
max_accel = 1000
[controller.axis.z]
steps_per_unit = 400
max_velocity = 20
max_accel = 500

[host]
link = "ethernet"
path_mode = "exact_stop"
tool_change_time = "1 s"
pause_time = "500 ms"
subroutine_path = ["subs"]
[[host.tool]]
number = 1
diameter = 3.0
z_offset = 10.0

[[program]]
file = "job.nc"
"""


def run(tmp_path: Path, program: str, machine: str = MACHINE) -> tuple[object, object]:
    (tmp_path / "job.nc").write_text(program)
    (tmp_path / "job.toml").write_text(machine)
    result = run_scenario(load_machine(tmp_path / "job.toml"), out=tmp_path / "out")
    assert result.error is None
    return result, read_trace(tmp_path / "out")


def console(tmp_path: Path, source: str) -> list[str]:
    """The run's console lines of ``source`` (console.txt: ``   1013.000000 ms  [source]  text``)."""
    lines = (tmp_path / "out" / "console.txt").read_text().splitlines()
    return [line.split("]  ", 1)[1] for line in lines if f"[{source}]  " in line]


def edges(trace: object, name: str) -> list[tuple[int, float]]:
    t, v = trace.edges(name)  # type: ignore[attr-defined]
    return [(int(a), float(b)) for a, b in zip(t, v, strict=True)]


def test_the_job_is_done_when_m2_is_reached_and_the_buffer_has_drained(tmp_path: Path) -> None:
    result, trace = run(tmp_path, "G21 G1 X10 F600\nM2\n")
    job = edges(trace, "pokeys.job")
    assert [v for _, v in job] == [JobState.IDLE, JobState.RUNNING, JobState.DONE]
    assert job[1][0] == 0
    # the last slot with pulses ends before DONE, and DONE is at a slot start after it
    steps_t, _ = trace.pulses("pokeys.x.step")  # type: ignore[attr-defined]
    assert steps_t[-1] < job[2][0] and job[2][0] % MS == 0
    assert result.figures["job_s"]["value"] > 0  # type: ignore[attr-defined]


def test_a_program_without_an_end_is_reported_as_linuxcnc_reports_it(tmp_path: Path) -> None:
    _, trace = run(tmp_path, "G21 G1 X10 F600\n")
    assert edges(trace, "pokeys.job")[-1][1] == JobState.ERROR
    (line,) = console(tmp_path, "pokeys.job")
    assert "File ended with no percent sign or program end" in line


def test_a_limit_switch_stops_the_job_with_state_limit(tmp_path: Path) -> None:
    machine = MACHINE + """
[[stimulus]]
signal = "pokeys.x.limit_pos"
at = ["200 ms"]
values = [1]
"""
    _, trace = run(tmp_path, "G21 G1 X100 F600\nM2\n", machine)
    job = edges(trace, "pokeys.job")
    assert job[-1][1] == JobState.LIMIT and job[-1][0] == 201 * MS  # the slot after the trip reads the switch
    assert console(tmp_path, "pokeys.job") == ["LIMIT: pokeys: stopped by a limit switch (engine state 100)"]


def test_the_emergency_input_stops_the_job_with_state_emergency(tmp_path: Path) -> None:
    machine = MACHINE + """
[[stimulus]]
signal = "pokeys.emergency"
at = ["300 ms"]
values = [1]
"""
    _, trace = run(tmp_path, "G21 G1 X100 F600\nM2\n", machine)
    assert edges(trace, "pokeys.job")[-1][1] == JobState.EMERGENCY
    assert console(tmp_path, "pokeys.job") == ["EMERGENCY: pokeys: stopped by the emergency input (engine state 101)"]


def test_coolant_tool_change_and_pause_are_signals_with_the_machine_files_times(tmp_path: Path) -> None:
    _, trace = run(tmp_path, "G21 M8\nG1 X5 F600\nM9\nT1 M6\nM0\nG1 X0\nM2\n")
    flood = edges(trace, "pokeys.coolant_flood")
    changing = edges(trace, "pokeys.tool_changing")
    paused = edges(trace, "pokeys.paused")
    tool = edges(trace, "pokeys.tool")
    assert [v for _, v in flood] == [0, 1, 0] and [v for _, v in changing] == [0, 1, 0]
    assert changing[2][0] - changing[1][0] == 1000 * MS  # tool_change_time = "1 s"
    assert paused[2][0] - paused[1][0] == 500 * MS  # pause_time = "500 ms"
    assert tool[-1] == (changing[2][0], 1)
    assert flood[2][0] <= changing[1][0] <= paused[1][0]


def test_messages_go_to_the_console_and_subroutines_come_from_the_machine_files_path(tmp_path: Path) -> None:
    (tmp_path / "subs").mkdir()
    (tmp_path / "subs" / "slot.ngc").write_text("o<slot> sub\n(PRINT, slot to #1)\nG1 X#1 F600\no<slot> endsub\nM2\n")
    _, trace = run(tmp_path, "G21 (MSG, start)\no<slot> call [4]\n(DEBUG, done %d#<_x>)\nM2\n")
    assert console(tmp_path, "gcode") == ["MSG: start", "slot to 4.000000", "MSG: done 4"]
    x = edges(trace, "pokeys.x.position")
    assert x[-1][1] == 1600  # X4 mm at 400 steps/mm


@pytest.mark.parametrize(("key", "value", "message"), [
    ("tool_change_position", "[1, 2]", r"job.toml: host.tool_change_position = \[1, 2\] is not allowed \(allowed: "
                                       r"\[x, y, z\] in machine units\)"),
    ("subroutine_path", "3", r"job.toml: host.subroutine_path = 3 is not allowed \(allowed: a folder or a list"),
])
def test_bad_host_settings_are_refused(tmp_path: Path, key: str, value: str, message: str) -> None:
    from cosim.errors import ConfigurationError
    from cosim.machine.check import check_machine

    (tmp_path / "job.nc").write_text("G0 X1\nM2\n")
    machine = MACHINE.replace('subroutine_path = ["subs"]', "") + ""
    (tmp_path / "job.toml").write_text(machine.replace("[[host.tool]]", f"{key} = {value}\n[[host.tool]]"))
    with pytest.raises(ConfigurationError, match=message):
        check_machine(load_machine(tmp_path / "job.toml"))
