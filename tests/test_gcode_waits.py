"""M66 waits on the machine's inputs and M0 pauses resumed by cycle start (issue 26, item 6).

LinuxCNC's reference (M-codes, "M66 Wait on Input"): ``M66 P- | E- <L->``; P a digital input, E an
analog one; L the wait type, "Mode 0: IMMEDIATE - no waiting, returns immediately. The current value
of the input is stored in parameter #5399", 1 RISE, 2 FALL, 3 HIGH, 4 LOW; "Q- specifies the timeout
in seconds for waiting. If the timeout is exceeded, the wait is interrupt, and the variable #5399
will be holding the value -1 ... A Q value of zero is an error if the L-word is non-zero"; "Mode 0 is
the only one permitted for an analog input"; "It is an error to program M66 with both a P-word and
an E-word"; its example ``M66 P0 L3 Q5`` "wait up to 5 seconds for digital input 0 to turn on".
M0: "pause a running program temporarily ... Pressing the cycle start button will restart the
program at the following line".

The machine (job.toml, a 56E over Ethernet, prefill 64 slots)::

    t [s]      0.003 ──G1 X10 F600 (1 s + 10 ms ramp)── 1.013   wait starts (first idle slot taken)
    din0       ____________________________________________________________/‾‾‾‾‾‾ 2.5 s
    waiting    ________________________________________/‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾\\___ 2.564 s
    host       reads din0 at each 1 ms cycle: high at 2.500 s -> the next piece after the 64 idle slots queued
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from gcode_machines import ROUTER_AXES

from cosim.controllers.pokeys.gcode import canonical, read_text
from cosim.errors import ConfigurationError
from cosim.export import read_trace
from cosim.machine import load_machine
from cosim.machine.check import check_machine
from cosim.runner import run_scenario

MACHINE = f"""
[machine]
until = "10 s"

[controller]
family = "pokeys"
{ROUTER_AXES}
[host]
link = "ethernet"

[[program]]
file = "job.nc"
"""
MS = 1_000_000


def edges(out: Path, name: str) -> list[tuple[int, float]]:
    """(t [ns], value) of every change of ``name`` in the run's trace (the first: its value at 0)."""
    t, values = read_trace(out).edges(name)
    return [(int(a), float(b)) for a, b in zip(t, values, strict=True)]


def stimulus(signal: str, times: list[str], values: list[float]) -> str:
    return f'\n[[stimulus]]\nsignal = "{signal}"\nat = {json.dumps(times)}\nvalues = {json.dumps(values)}\n'


def run(tmp_path: Path, program: str, extra: str = "", host: str = "") -> tuple[dict, str, Path]:  # type: ignore[type-arg]
    """Run the machine on ``program``: the result, the console and the result folder."""
    (tmp_path / "job.nc").write_text(program)
    (tmp_path / "job.toml").write_text(MACHINE.replace('link = "ethernet"\n', f'link = "ethernet"\n{host}') + extra)
    result = run_scenario(load_machine(tmp_path / "job.toml"), out=tmp_path / "out")
    assert result.error is None, result.error
    return json.loads((tmp_path / "out" / "result.json").read_text()), (tmp_path / "out" / "console.txt").read_text(), \
        tmp_path / "out"


WAIT = "G21 G90\nG1 X10 F600\nM66 P0 L3 Q5\n(DEBUG, r=#5399)\nG1 X20\nM2\n"


def test_m66_l3_waits_for_the_input_to_turn_on_and_5399_holds_its_value(tmp_path: Path) -> None:
    """The reference's example, input 0 on at 2.5 s: the wait ends at the host's cycle at 2.5 s, #5399 = 1; the
    next move starts after the 64 idle slots the host had queued (2.564 s) and takes 1.01 s."""
    result, console, out = run(tmp_path, WAIT, stimulus("pokeys.din0", ["0 s", "2.5 s"], [0, 1]))
    assert result["verdict"] == "PASS"
    assert "2564.000000 ms  [gcode]  MSG: r=1.000000" in console
    assert edges(out, "pokeys.waiting") == [(0, 0), (1013 * MS, 1), (2564 * MS, 0)]
    assert result["figures"]["job_s"]["value"] == pytest.approx(2.564 + 1.01, abs=0.002)


def test_m66_times_out_after_q_seconds_and_5399_is_minus_one(tmp_path: Path) -> None:
    """No input: the wait from 1.013 s ends Q = 5 s later, at 6.013 s, with #5399 = -1 (the reference)."""
    result, console, out = run(tmp_path, WAIT)
    assert "6077.000000 ms  [gcode]  MSG: r=-1.000000" in console  # 6.013 s + the 64 idle slots queued
    assert edges(out, "pokeys.waiting") == [(0, 0), (1013 * MS, 1), (6077 * MS, 0)]
    assert result["verdict"] == "PASS"


def test_what_the_program_does_after_m66_depends_on_the_value_read(tmp_path: Path) -> None:
    """As in LinuxCNC the interpreter stops at the M66 until the input is read: o1 if [#5399 LT 0] takes the branch
    of the timeout only when the input stayed off."""
    program = ("G21 G90\nG1 X10 F600\nM66 P1 L3 Q2\no1 if [#5399 LT 0]\n(MSG, no part)\nG0 Y50\no1 else\nG1 X20\n"
               "o1 endif\nM2\n")
    (tmp_path / "off").mkdir()
    (tmp_path / "on").mkdir()
    _, console, _ = run(tmp_path / "off", program, host="digital_inputs = 2\n")
    assert "MSG: no part" in console
    _, console, _ = run(tmp_path / "on", program, stimulus("pokeys.din1", ["1.5 s"], [1]), host="digital_inputs = 2\n")
    assert "MSG: no part" not in console


@pytest.mark.parametrize(("mode", "times", "values", "ends_ms", "read"), [
    # L1 rise: on before the wait starts (1.013 s): it must go off, then on again
    (1, ["0 s", "0.5 s", "2 s", "3 s"], [0, 1, 0, 1], 3000, 1),
    # L2 fall: off at the start: it must go on, then off
    (2, ["0 s", "2 s", "3 s"], [0, 1, 0], 3000, 0),
    # L4 low: off already: at the host's cycle at the wait's start
    (4, ["0 s"], [0], 1013, 0),
    # L3 high: a pulse between two host cycles (2.0002 s to 2.0008 s) is not seen: the wait times out
    (3, ["0 s", "2.0002 s", "2.0008 s"], [0, 1, 0], 6013, -1),
])
def test_the_wait_types_as_the_reference_names_them(tmp_path: Path, mode: int, times: list[str],
                                                      values: list[float], ends_ms: int, read: int) -> None:
    program = f"G21 G90\nG1 X10 F600\nM66 P0 L{mode} Q5\n(DEBUG, r=#5399)\nM2\n"
    _, console, out = run(tmp_path, program, stimulus("pokeys.din0", times, values))
    assert edges(out, "pokeys.waiting")[1:] == [(1013 * MS, 1), ((ends_ms + 64) * MS, 0)]
    assert f"MSG: r={read:.6f}" in console


def test_m66_l0_reads_an_analog_input_at_once(tmp_path: Path) -> None:
    """Mode 0: "no waiting ... the current value of the input is stored in parameter #5399"."""
    _, console, out = run(tmp_path, "G21\nG1 X10 F600\nM66 E2 L0\n(DEBUG, volts=#5399)\nM2\n",
                          stimulus("pokeys.ain2", ["0 s", "0.5 s"], [0.0, 2.5]))
    assert "MSG: volts=2.500000" in console
    assert "pokeys.waiting" not in read_trace(out).info  # L0 does not wait


def test_an_m0_pause_ends_at_the_operators_cycle_start(tmp_path: Path) -> None:
    """cycle_start = true: M0 after the first move pauses (pokeys.paused) until cycle start rises at 3 s; a press
    during the motion before (0.5 s) does not count."""
    result, _, out = run(tmp_path, "G21 G90\nG1 X10 F600\nM0\nG1 X20\nM2\n",
                         stimulus("pokeys.cycle_start", ["0.5 s", "0.6 s", "3 s", "3.1 s"], [1, 0, 1, 0]),
                         host="cycle_start = true\n")
    assert result["verdict"] == "PASS"
    assert edges(out, "pokeys.paused") == [(0, 0), (1013 * MS, 1), (3064 * MS, 0)]


def test_a_pause_nobody_resumes_leaves_the_job_running_and_says_why(tmp_path: Path) -> None:
    result, _, _ = run(tmp_path, "G21 G90\nG1 X10 F600\nM0\nG1 X20\nM2\n", host="cycle_start = true\n")
    assert result["verdict"] == "FAIL"
    assert any("no [[stimulus]] drives pokeys.cycle_start: an M0 pause lasts until the run ends" in n
               for n in result["notes"])


def test_an_m66_on_the_line_that_ends_the_program_reads_and_the_job_ends(tmp_path: Path) -> None:
    """M2 runs after M66 on its line (RS274/NGC's order of execution): the wait ends the job's motion, then the end."""
    result, _, out = run(tmp_path, "G21 G90\nG1 X10 F600\nM66 P0 L3 Q1 M2\nG1 X20\n")
    assert result["verdict"] == "PASS"
    assert edges(out, "pokeys.waiting")[1:] == [(1013 * MS, 1), ((2013 + 64) * MS, 0)]
    assert edges(out, "pokeys.x.position")[-1][1] == 4000  # X10: the line after M2 never runs


def test_a_program_error_after_a_wait_stops_the_job_with_its_place(tmp_path: Path) -> None:
    result, console, _ = run(tmp_path, "G21 G90\nG1 X10 F600\nM66 P0 L0\nG2 X0 Y0 I-1 J0\nM2\n")
    assert result["verdict"] == "FAIL"
    assert "[pokeys.job]  ERROR: " in console and "job.nc:4:10: Radius to end of arc differs" in console


@pytest.mark.parametrize(("line", "message"), [
    ("M66 P0 L3", "Zero timeout with wait type != immediate return"),
    ("M66 E0 L3 Q1", "Can't select analog input with wait type != immediate return"),
    ("M66 P1 E1", "Invalid to select both a digital and an analog input with M66"),
    ("M66 L3 Q1", "Need to have either a valid P or a valid E word with M66"),
])
def test_m66_errors_are_linuxcncs(line: str, message: str) -> None:
    """rs274 2.9's messages for the reference's errors."""
    with pytest.raises(ConfigurationError, match=rf"p.nc:1:1: {message}"):
        canonical(read_text(f"{line}\nM2\n", source="p.nc"))


def test_an_input_the_machine_has_not_got_is_refused_naming_the_key(tmp_path: Path) -> None:
    (tmp_path / "job.nc").write_text("G21\nM66 P4 L0\nM2\n")
    (tmp_path / "job.toml").write_text(MACHINE)
    with pytest.raises(ConfigurationError, match=r"job.nc:2:1: M66 P4: the machine has digital inputs 0..3 "
                                                 r"\(host.digital_inputs = 4"):
        check_machine(load_machine(tmp_path / "job.toml"))


def test_pause_time_and_cycle_start_are_one_or_the_other(tmp_path: Path) -> None:
    (tmp_path / "job.nc").write_text("G21\nM0\nM2\n")
    (tmp_path / "job.toml").write_text(MACHINE.replace('link = "ethernet"\n',
                                                       'link = "ethernet"\ncycle_start = true\npause_time = "2 s"\n'))
    with pytest.raises(ConfigurationError, match=r"host.pause_time: a pause ends after pause_time or at "
                                                 r"cycle_start, not both"):
        check_machine(load_machine(tmp_path / "job.toml"))
