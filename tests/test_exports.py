"""Exports other tools read in full: the VCD and its digital companion, the GTKWave view, the wide CSV.

    t [ns]      0        1000          2000       3000 (end)
    count       0 (then 4 at 0)  5, 3 (one tick)   9
    gate        0________1‾‾‾‾‾‾‾‾‾‾‾‾‾0__________
    step                 | | |          |  |         (3 pulses up from 1000, 2 down from 2000)

A viewer shows the last value recorded at a tick (count is 4 from 0 and 3 at 1000), the file
ends at the run's end (3000), and every name in its list says which signal it is.
"""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pandas as pd
import pytest
import vcdvcd

from cosim.controllers.pokeys import PulseEngine, uniform_axes
from cosim.controllers.pokeys.config import EngineConfig
from cosim.controllers.pokeys.host import HostApp
from cosim.controllers.pokeys.planner import Move, plan, to_entries
from cosim.export import write_trace
from cosim.kernel import Simulation
from cosim.trace import Trace


def _trace() -> Trace:
    trace = Trace()
    trace.declare("dev.axis1.step", "pulse", pulse_width=100)
    trace.declare("dev.axis1.gate", "bit")
    trace.declare("dev.axis1.count", "int")
    trace.declare("dev.power", "real", unit="W")
    for t, v in [(0, 0), (0, 4), (1000, 5), (1000, 3), (2000, 9)]:
        trace.record("dev.axis1.count", t, v)
    for t, v in [(0, 0), (1000, 1), (2000, 0)]:
        trace.record("dev.axis1.gate", t, v)
    for t, v in [(0, 0.0), (1000, 12.5), (1000, 2.5)]:
        trace.record("dev.power", t, v)
    trace.record_segment("dev.axis1.step", 1000, 1000, 3, 1)
    trace.record_segment("dev.axis1.step", 2000, 1000, 2, 0)
    trace.end_t = 3000
    return trace


def _vars(vcd: Path) -> list[tuple[str, str, str]]:
    """(type, scope path, name) of every ``$var``, from the header."""
    scopes: list[str] = []
    found = []
    for line in vcd.read_text().splitlines():
        if line.startswith("$scope"):
            scopes.append(line.split()[2])
        elif line.startswith("$upscope"):
            scopes.pop()
        elif line.startswith("$var"):
            found.append((line.split()[1], ".".join(scopes), line.split()[4]))
        elif line.startswith("$enddefinitions"):
            break
    return found


def test_a_tick_with_several_records_shows_the_last_one(tmp_path: Path) -> None:
    write_trace(_trace(), tmp_path, formats=("vcd",))
    vcd = vcdvcd.VCDVCD(str(tmp_path / "trace.vcd"))
    count = [(t, int(v, 2)) for t, v in vcd["dev.axis1.dev_axis1_count"].tv]
    assert count == [(0, 4), (1000, 3), (2000, 9)]  # not 5, the larger value at 1000
    assert [(t, float(v)) for t, v in vcd["dev.dev_power"].tv] == [(0, 0.0), (1000, 2.5)]


def test_the_vcd_ends_at_the_end_of_the_run(tmp_path: Path) -> None:
    write_trace(_trace(), tmp_path, formats=("vcd",))
    for name in ("trace.vcd", "trace_digital.vcd"):
        stamps = [line for line in (tmp_path / name).read_text().splitlines() if line.startswith("#")]
        assert stamps[-1] == "#3000"  # the last change is the fall of the last pulse, at 2600


def test_every_name_is_unique_and_says_which_signal_it_is(tmp_path: Path) -> None:
    with Simulation() as sim:
        PulseEngine(sim)
        sim.run(until=1_000_000)
        write_trace(sim.trace, tmp_path, formats=("vcd",))
        signals = sim.trace.names()
    found = _vars(tmp_path / "trace.vcd")
    names = [name for _, _, name in found]
    assert len(set(names)) == len(names) == len(signals)
    assert {(scope, name) for _, scope, name in found} == {
        (s.rpartition(".")[0], s.replace(".", "_")) for s in signals}
    assert {"pokeys_x_step", "pokeys_y_step", "pokeys_z_step", "pokeys_buffer_level"} <= set(names)


def test_the_digital_companion_holds_the_bits_and_pulses_as_in_the_full_vcd(tmp_path: Path) -> None:
    write_trace(_trace(), tmp_path, formats=("vcd",))
    assert {v[0] for v in _vars(tmp_path / "trace_digital.vcd")} == {"wire"}
    full = vcdvcd.VCDVCD(str(tmp_path / "trace.vcd"))
    digital = vcdvcd.VCDVCD(str(tmp_path / "trace_digital.vcd"))
    assert sorted(digital.references_to_ids) == ["dev.axis1.dev_axis1_gate", "dev.axis1.dev_axis1_step"]
    for name in digital.references_to_ids:
        assert digital[name].tv == full[name].tv


def test_the_gtkwave_view_shows_every_signal_grouped_by_scope(tmp_path: Path) -> None:
    write_trace(_trace(), tmp_path, formats=("vcd",))
    lines = (tmp_path / "trace.gtkw").read_text().splitlines()
    assert '[dumpfile] "trace.vcd"' in lines and '[savefile] "trace.gtkw"' in lines
    shown = [line for line in lines if line and line[0] not in "[*@-"]
    assert shown == ["dev.dev_power", "dev.axis1.dev_axis1_step", "dev.axis1.dev_axis1_gate",
                     "dev.axis1.dev_axis1_count"]  # device first, then its axis: pulses, bits, ints
    vcd = vcdvcd.VCDVCD(str(tmp_path / "trace.vcd"))
    assert set(shown) == set(vcd.references_to_ids)
    groups = [line[1:] for line in lines if line.startswith("-") and line != "-"]
    assert groups == ["dev", "dev", "dev.axis1", "dev.axis1"]  # each group opened and closed
    flags = dict(zip(lines[1:], lines, strict=False))  # the @ line before each signal
    assert [flags[s] for s in shown] == ["@8420", "@28", "@28", "@420"]


def test_the_wide_csv_has_one_column_per_signal_and_time_in_seconds(tmp_path: Path) -> None:
    write_trace(_trace(), tmp_path, formats=("csv",))
    wide = pd.read_csv(tmp_path / "trace_wide.csv", dtype={"time_s": str})
    assert list(wide.columns) == ["time_s", "dev.axis1.step", "dev.axis1.gate", "dev.axis1.count", "dev.power"]
    assert wide["time_s"].tolist() == ["0.000000000", "0.000001000", "0.000002000", "0.000003000"]
    assert wide["dev.axis1.step"].tolist() == [0, 1, 2, 1]  # position: pulses at or before the instant
    assert wide["dev.axis1.gate"].tolist() == [0, 1, 0, 0]
    assert wide["dev.axis1.count"].tolist() == [4, 3, 9, 9]
    assert wide["dev.power"].tolist() == [0.0, 2.5, 2.5, 2.5]


SIGROK = shutil.which("sigrok-cli")


def _pokeys_run(tmp_path: Path, until_ns: int) -> tuple[Path, int]:
    """PoKeys engine and host on a 3-axis move, written with its VCDs; and its x pulse count."""
    with Simulation() as sim:
        config = EngineConfig(axes=uniform_axes(max_speed_hz=24_000, accel=400_000, decel=400_000))
        engine = PulseEngine(sim, config)
        HostApp(sim, engine, to_entries(plan([Move((40_000, -30_000, 20_000))], config.axes)), prefill_slots=8)
        sim.run(until=until_ns)
        return write_trace(sim.trace, tmp_path, formats=("vcd",)), sim.trace.pulses("pokeys.x.step")[0].size


def _sigrok(vcd: Path, out: Path, *options: str) -> list[str]:
    subprocess.run([str(SIGROK), "-i", str(vcd), *options, "-O", "vcd", "-o", str(out)], check=True,
                   capture_output=True, timeout=120)
    return out.read_text().splitlines()


@pytest.mark.skipif(SIGROK is None, reason="sigrok-cli is not installed (python3 tasks.py test installs it)")
def test_sigrok_reads_the_digital_vcd_of_a_pokeys_run_to_its_end(tmp_path: Path) -> None:
    folder, _ = _pokeys_run(tmp_path, 1_700_000_000)  # 1.7 s; the buffer level changes from the start
    lines = _sigrok(folder / "trace_digital.vcd", tmp_path / "sigrok.vcd", "-I", "vcd:downsample=1000")
    assert "$timescale 1 us $end" in lines
    assert lines[-1] == "#1700000"  # every sample up to the end of the run: 1.7 s in us


@pytest.mark.skipif(SIGROK is None, reason="sigrok-cli is not installed (python3 tasks.py test installs it)")
def test_sigrok_sees_every_step_pulse(tmp_path: Path) -> None:
    folder, pulses = _pokeys_run(tmp_path, 40_000_000)  # the first 40 ms, read at 1 GHz
    lines = _sigrok(folder / "trace_digital.vcd", tmp_path / "sigrok.vcd")
    code = next(line.split()[3] for line in lines if line.startswith("$var") and line.endswith("pokeys_x_step $end"))
    rises = sum(1 for line in lines for change in line.split()[1:] if change == f"1{code}")
    assert rises == pulses > 100
    assert lines[-1] == "#40000000"


def _shown(changes: list[tuple[int, object]], initial: object) -> list[tuple[int, object]]:
    """What a viewer shows: the last value at each tick, only where it differs from the one before."""
    last: dict[int, object] = {}
    for t, value in changes:
        last.pop(t, None)
        last[t] = value
    shown, current = [], initial
    for t, value in last.items():
        if value != current:
            shown.append((t, value))
            current = value
    return shown


def _expected(trace: Trace, name: str) -> list[tuple[int, object]]:
    """A signal's VCD changes from the trace, one record or pulse at a time (the rules, written plainly)."""
    info = trace.info[name]
    if info.kind == "pulse":
        times = trace.pulses(name)[0].tolist()
        widths = [info.pulse_width] * len(times)
        if info.varying_width:  # a PWM output: pulse k of a segment rises at t0 + k*duration//count, width wide
            seg = trace.segments(name)
            pulses = sorted((t0 + k * duration // count, width) for t0, duration, count, width in zip(
                seg["t0"].tolist(), seg["duration"].tolist(), seg["count"].tolist(), seg["width"].tolist(),
                strict=True) for k in range(count))
            times, widths = [t for t, _ in pulses], [w for _, w in pulses]
        falls = [(t + w, 0) for t, w in zip(times, widths, strict=True)]
        events = sorted(falls + [(t, 1) for t in times])  # fall first
        return _shown(events, 0)
    t, v = trace.edges(name)
    values: list[object] = [float(x) if info.kind == "real" else int(x) for x in v.tolist()]
    return _shown(list(zip(t.tolist(), values, strict=True)), 0.0 if info.kind == "real" else 0)


def _in_vcd(vcd: vcdvcd.VCDVCD, reference: str, kind: str) -> list[tuple[int, object]]:
    def value(text: str) -> object:
        if kind == "real":
            return float(text)
        number = int(text, 2)
        return number - (1 << 64) if kind == "int" and number >= 1 << 63 else number

    return _shown([(t, value(v)) for t, v in vcd[reference].tv], 0.0 if kind == "real" else 0)


@pytest.mark.fmu
@pytest.mark.parametrize(("scenario", "overrides"), [("pokeys_job", {"steppers": "false"}),
                                                      ("trio_raster_starved", {})])
def test_the_vcd_of_a_bundled_run_shows_every_record_and_pulse_of_its_trace(
        scenario: str, overrides: dict[str, str], tmp_path: Path) -> None:
    from cosim.export import read_trace
    from cosim.runner import run_scenario
    from cosim.scenario import load

    result = run_scenario(load(scenario), overrides=overrides, out=tmp_path, formats=("vcd", "parquet"))
    assert result.verdict == ("HAZARD SHOWN" if scenario == "trio_raster_starved" else "PASS")
    trace = read_trace(tmp_path)
    vcd = vcdvcd.VCDVCD(str(tmp_path / "trace.vcd"))
    for name, info in trace.info.items():
        scopes, _, _ = name.rpartition(".")
        reference = f"{scopes}.{name.replace('.', '_')}"
        assert _in_vcd(vcd, reference, info.kind) == _expected(trace, name), name
    assert vcd.endtime == trace.end_t
