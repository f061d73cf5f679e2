"""The Conveyor FMU: exact belt motion, 1/T encoder timestamps and registration-mark events.

Timing picture of the mark test (from rest, speed_cmd 0.5 m/s, tau 50 ms; marks every 250 mm,
10 mm long, the first at 50 mm)::

    speed_cmd ‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾
    speed     /‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾
    mark      _______|‾|_________________________________|‾|_________________ ...
              0      147.38 ms (50 mm)                   650 ms (300 mm)
                       168.27 ms (60 mm)                   670 ms (310 mm)

On FMI 3.0 each mark edge ends the FMU's step (early return) and is published at the first
nanosecond tick at or after the exact instant.
"""

from __future__ import annotations

import doctest
import math
import shutil
import zipfile
from pathlib import Path

import control
import numpy as np
import pytest
from encoder_oracle import one_over_t_position
from fmpy import simulate_fmu
from fmpy.build import build_platform_binary
from fmpy.validation import validate_fmu

import cosim.plants.conveyor
from cosim import fmudesc
from cosim.errors import ConfigurationError, FmuError
from cosim.fmu import Fmu
from cosim.fmubuild import SOURCE_DIR, ensure_fmu
from cosim.kernel import Simulation
from cosim.master import Plant
from cosim.plants.conveyor import ConveyorParameters, linear_model, mark_edge_times, position_at
from cosim.presets import load_preset

pytestmark = pytest.mark.fmu

MS = 1_000_000  # ns
VERSIONS = (2, 3)
BELT = ConveyorParameters()
REFERENCE_START = {"speed_cmd": 0.5, "ripple_amplitude": 0.02, "ripple_frequency": 5.0}


@pytest.fixture(scope="module", params=VERSIONS, ids=["fmi2", "fmi3"])
def conveyor_fmu(request: pytest.FixtureRequest) -> Path:
    return ensure_fmu("Conveyor", request.param)


def ns(t_s: float) -> int:
    """The first nanosecond tick at or after ``t_s`` (a time within float noise of a tick is that tick)."""
    ticks = t_s * 1e9
    return round(ticks) if abs(ticks - round(ticks)) <= 1e-6 else math.ceil(ticks)


def advance(fmu: Fmu, t: int) -> None:
    """Advance to ``t`` through any early returns at mark edges (FMI 3.0)."""
    while fmu.t < t:
        fmu.advance_to(t)


def run_with_events(fmu: Fmu, t_end: int) -> list[tuple[int, bool]]:
    """Advance to ``t_end``, collecting ``(tick, mark)`` wherever the FMU returned early."""
    events = []
    while fmu.t < t_end:
        reached = fmu.advance_to(t_end)
        if reached < t_end:
            events.append((reached, bool(fmu.get("mark"))))
    return events


# -- standard conformance --------------------------------------------------------------------------
def test_validates_without_problems(conveyor_fmu: Path) -> None:
    assert validate_fmu(str(conveyor_fmu)) == []


def test_fmu_holds_its_sources_and_offers_events_on_fmi3(conveyor_fmu: Path) -> None:
    archive = zipfile.ZipFile(conveyor_fmu)
    assert {"sources/model.c", "sources/encoder.c", "sources/model.h", "documentation/readme.md"} <= set(
        archive.namelist())
    description = archive.read("modelDescription.xml").decode()
    if "fmi3" in conveyor_fmu.parts:
        assert 'hasEventMode="true"' in description
        assert 'mightReturnEarlyFromDoStep="true"' in description


def test_simulates_standalone_in_fmpy(conveyor_fmu: Path) -> None:
    result = simulate_fmu(str(conveyor_fmu), start_values={"speed_cmd": 0.5}, stop_time=1.0, output_interval=0.01)
    assert result["position"][-1] == pytest.approx(float(position_at(BELT, 1.0, speed_cmd=0.5)), rel=1e-12)
    assert result["marks_seen"][-1] == 2  # leading edges at 50 mm and 300 mm; 0.475 m travelled


# -- motion ------------------------------------------------------------------------------------------
def test_speed_step_response_matches_the_linear_model(conveyor_fmu: Path) -> None:
    grid = np.arange(0, 101) * 2 * MS
    with Fmu(conveyor_fmu, parameters={"speed_cmd": 1.0}) as fmu:
        rows = []
        for t in grid:
            advance(fmu, int(t))
            rows.append((fmu.get("speed"), fmu.get("position")))
    got = np.array(rows)
    for column, output in enumerate(("speed", "position")):
        expected = control.step_response(linear_model(BELT, output=output), T=grid * 1e-9).outputs
        assert np.max(np.abs(got[:, column] - expected)) < 1e-9 * np.max(np.abs(expected)), output


def test_disturbance_and_ripple_follow_the_closed_form(conveyor_fmu: Path, sim: Simulation) -> None:
    belt = ConveyorParameters(ripple_amplitude=0.05, ripple_frequency=7.0, ripple_phase=0.3, speed_start=0.2,
                              position_start=-0.1)
    instants = np.sort(sim.rng.integers(1, 500 * MS, size=50))
    with Fmu(conveyor_fmu, parameters={**belt.as_fmu_parameters(), "speed_cmd": 0.4, "disturbance": -0.03}) as fmu:
        for t in instants:
            advance(fmu, int(t))
            assert fmu.get("position") == pytest.approx(
                float(position_at(belt, t * 1e-9, speed_cmd=0.4, disturbance=-0.03)), abs=1e-12)


# -- encoder -----------------------------------------------------------------------------------------
@pytest.mark.parametrize("speed_cmd", [0.5, -0.3])
def test_one_over_t_position_error_is_below_1_256_count_at_constant_speed(conveyor_fmu: Path, speed_cmd: float,
                                                                           sim: Simulation) -> None:
    """After settling (1 s = 20 drive time constants), at 300 random instants within 200 ms."""
    instants = np.sort(sim.rng.integers(1000 * MS, 1200 * MS, size=300))
    errors = []
    with Fmu(conveyor_fmu, parameters={"speed_cmd": speed_cmd}) as fmu:
        advance(fmu, 1000 * MS)
        for t in instants:
            advance(fmu, int(t))
            estimate = one_over_t_position(
                edge_count=int(fmu.get("edge_count")), edge_direction=int(fmu.get("edge_direction")),
                t_last_edge_s=float(fmu.get("t_last_edge")), t_prev_edge_s=float(fmu.get("t_prev_edge")),
                t_s=t * 1e-9)
            exact = float(position_at(BELT, t * 1e-9, speed_cmd=speed_cmd)) * BELT.counts_per_metre
            errors.append(estimate - exact)
            assert fmu.get("edge_direction") == (1 if speed_cmd > 0 else -1)
    assert np.max(np.abs(errors)) < 1 / 256
    assert np.max(np.abs(errors)) < 1e-4  # in fact limited by rounding of the positions


def test_encoder_counts_the_floor_of_the_position(conveyor_fmu: Path) -> None:
    with Fmu(conveyor_fmu, parameters={"speed_cmd": 0.5, "position_start": -0.0123}) as fmu:
        for t in range(0, 200 * MS + 1, 7 * MS):
            advance(fmu, t)
            assert fmu.get("encoder_count") == math.floor(fmu.get("position") * BELT.counts_per_metre)


# -- mark events -------------------------------------------------------------------------------------
def test_mark_edges_end_the_step_within_1_us_of_the_exact_instant_on_fmi3() -> None:
    """From rest: the edge instants solve the drive's transient; each is reached to the ns tick."""
    times, rising = mark_edge_times(BELT, speed_cmd=0.5, t_end_s=1.5)
    with Fmu(ensure_fmu("Conveyor", 3), parameters={"speed_cmd": 0.5}) as fmu:
        events = run_with_events(fmu, 1500 * MS)
        assert [tick for tick, _ in events] == [ns(t) for t in times]
        assert [mark for _, mark in events] == rising.tolist()
        assert fmu.get("marks_seen") == 3
        assert fmu.get("t_last_mark") == pytest.approx(times[rising][-1], abs=1e-9)
    assert max(abs(tick * 1e-9 - t) for (tick, _), t in zip(events, times, strict=True)) < 1e-6


def test_mark_edges_backwards_are_events_too() -> None:
    """Moving back at 0.5 m/s from 200 mm: into mark 0 at its trailing edge (60 mm), out at 50 mm."""
    belt = ConveyorParameters(speed_start=-0.5, position_start=0.2)
    with Fmu(ensure_fmu("Conveyor", 3), parameters={**belt.as_fmu_parameters(), "speed_cmd": -0.5}) as fmu:
        events = run_with_events(fmu, 400 * MS)
        assert events == [(280 * MS, True), (300 * MS, False)]
        assert (fmu.get("marks_seen"), fmu.get("t_last_mark")) == (1, pytest.approx(0.28, abs=1e-12))


def test_fmi2_counts_marks_with_exact_instants_on_a_coarse_grid() -> None:
    """No early return: the step goes past the edges, the counters and timestamps stay exact."""
    times, rising = mark_edge_times(BELT, speed_cmd=0.5, t_end_s=1.5)
    with Fmu(ensure_fmu("Conveyor", 2), parameters={"speed_cmd": 0.5}) as fmu:
        for t in range(100 * MS, 1500 * MS + 1, 100 * MS):
            assert fmu.advance_to(t) == t
            seen = int(np.count_nonzero(rising[times <= t * 1e-9]))
            assert fmu.get("marks_seen") == seen
            if seen:
                assert fmu.get("t_last_mark") == pytest.approx(times[rising][seen - 1], abs=1e-9)


def test_early_returns_do_not_change_the_trajectory() -> None:
    """The FMI 3.0 run (stopping at 6 mark edges) ends where the FMI 2.0 run (one step) does."""
    parameters = {"speed_cmd": 0.5, "ripple_amplitude": 0.1, "ripple_frequency": 3.0}
    with Fmu(ensure_fmu("Conveyor", 3), parameters=parameters) as fmi3, \
            Fmu(ensure_fmu("Conveyor", 2), parameters=parameters) as fmi2:
        assert len(run_with_events(fmi3, 1500 * MS)) == 6
        fmi2.advance_to(1500 * MS)
        for name in ("position", "speed", "t_last_edge", "t_prev_edge", "t_last_mark"):
            assert fmi3.get(name) == pytest.approx(fmi2.get(name), rel=1e-12), name
        for name in ("encoder_count", "marks_seen", "mark"):
            assert fmi3.get(name) == fmi2.get(name), name


@pytest.mark.parametrize("use_event_mode", [True, False], ids=["event mode", "no event mode"])
def test_fmpy_with_early_return_stops_at_the_mark_edges(use_event_mode: bool) -> None:
    """Another importer: fmpy returns early at each edge; with event mode the output changes there."""
    result = simulate_fmu(str(ensure_fmu("Conveyor", 3)), start_values={"speed_cmd": 0.5}, stop_time=1.0,
                          output_interval=0.1, early_return_allowed=True, use_event_mode=use_event_mode)
    times, rising = mark_edge_times(BELT, speed_cmd=0.5, t_end_s=1.0)
    off_grid = ~np.isclose(result["time"] * 10, np.round(result["time"] * 10), rtol=0, atol=1e-9)
    settled = result[off_grid]
    if use_event_mode:  # sampled at each edge before and after event mode
        assert settled["mark"][0::2].tolist() == (~rising).tolist()
        settled = settled[1::2]
    assert settled["time"].tolist() == pytest.approx(times.tolist(), abs=1e-12)
    assert settled["mark"].tolist() == rising.tolist()
    assert result["marks_seen"][-1] == 2


def test_watched_mark_sensor_is_published_at_the_edge_ticks(sim: Simulation) -> None:
    """In a simulation the master turns each early return into a signal edge at its tick (FMI 3.0)."""
    belt = Plant.load(sim, "Conveyor", name="belt", fmi_version=3, parameters={"speed_cmd": 0.5})
    belt.watch("mark", signal="belt.mark")
    sim.run(until=1500 * MS)
    t, value = sim.trace.edges("belt.mark")
    times, rising = mark_edge_times(BELT, speed_cmd=0.5, t_end_s=1.5)
    assert t.tolist() == [0, *[ns(x) for x in times]]
    assert value.tolist() == [0.0, *rising.astype(float).tolist()]


# -- errors ------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("parameters", "message"),
    [
        ({"mark_pitch": 0.01}, "parameter mark_pitch = 0.01 m is not allowed (allowed: > mark_length = 0.01 m)"),
        ({"mark_pitch": 0.005}, "parameter mark_pitch = 0.0050000000000000001 m is not allowed "
                                "(allowed: > mark_length = 0.01 m)"),
        ({"counts_per_metre": 0.0}, "parameter counts_per_metre = 0 counts/m is not allowed (allowed: > 0 counts/m)"),
        ({"tau_drive": -0.05}, "parameter tau_drive = -0.050000000000000003 s is not allowed (allowed: > 0 s)"),
        ({"mark_length": 0.0}, "parameter mark_length = 0 m is not allowed (allowed: > 0 m)"),
        ({"ripple_amplitude": -1.0}, "parameter ripple_amplitude = -1 m/s is not allowed (allowed: >= 0 m/s)"),
    ],
)
def test_bad_parameters_fail_at_initialisation_naming_the_parameter(conveyor_fmu: Path,
                                                                     parameters: dict[str, float],
                                                                     message: str) -> None:
    with pytest.raises(FmuError) as info:
        Fmu(conveyor_fmu, parameters=parameters)
    assert message in str(info.value)


def test_python_parameters_refuse_what_the_fmu_refuses() -> None:
    with pytest.raises(ConfigurationError, match=r"mark_pitch = 0.01 is not allowed \(allowed: > mark_length"):
        ConveyorParameters(mark_pitch=0.01, mark_length=0.01)
    with pytest.raises(ConfigurationError, match="counts_per_metre = 0"):
        ConveyorParameters(counts_per_metre=0)
    with pytest.raises(ConfigurationError, match=r"^ConveyorParameters: speed_start = nan is not allowed"):
        ConveyorParameters(speed_start=float("nan"))
    with pytest.raises(ConfigurationError, match=r"^ConveyorParameters: tau_drive = inf is not allowed"):
        ConveyorParameters(tau_drive=float("inf"))
    with pytest.raises(ConfigurationError, match="not Conveyor parameters: pitch"):
        ConveyorParameters.from_mapping({"pitch": 0.2})


def test_python_defaults_are_the_fmu_defaults() -> None:
    spec = fmudesc.load_spec(SOURCE_DIR / "Conveyor")
    for name, value in BELT.as_fmu_parameters().items():
        assert spec.variable(name).start == value, name


# -- instances, presets ------------------------------------------------------------------------------
def test_two_instances_are_independent(conveyor_fmu: Path) -> None:
    with Fmu(conveyor_fmu, parameters={"speed_cmd": 0.5}) as a, Fmu(conveyor_fmu, parameters={"speed_cmd": 0.25}) as b:
        advance(a, 800 * MS)
        advance(b, 800 * MS)
        assert a.get("position") == pytest.approx(float(position_at(BELT, 0.8, speed_cmd=0.5)), rel=1e-12)
        assert b.get("position") == pytest.approx(float(position_at(BELT, 0.8, speed_cmd=0.25)), rel=1e-12)
        assert (a.get("marks_seen"), b.get("marks_seen")) == (2, 1)


def test_preset_runs_with_marks_at_its_pitch(conveyor_fmu: Path) -> None:
    preset = load_preset("conveyor_web_200mm_wheel")
    belt = ConveyorParameters.from_mapping(preset)
    with Fmu(conveyor_fmu, parameters={**preset, "speed_cmd": 0.5, "speed_start": 0.5}) as fmu:
        advance(fmu, 2000 * MS)
        assert fmu.get("marks_seen") == math.floor((1.0 - belt.mark_offset) / belt.mark_pitch) + 1
        assert fmu.get("encoder_count") == 50_000  # 1 m at 50,000 counts/m (0.2 m wheel, 2500 lines)


# -- rebuild and reference ---------------------------------------------------------------------------
def test_rebuilds_from_its_own_sources_in_a_clean_folder(conveyor_fmu: Path, tmp_path: Path) -> None:
    unzipped = tmp_path / "fmu"
    with zipfile.ZipFile(conveyor_fmu) as zf:
        zf.extractall(unzipped)
    shutil.rmtree(unzipped / "binaries")
    (tmp_path / "build").mkdir()
    build_platform_binary(str(unzipped), str(tmp_path / "build"))  # what another tool would do
    rebuilt = shutil.make_archive(str(tmp_path / "Conveyor"), "zip", unzipped)
    result = simulate_fmu(rebuilt, start_values={"speed_cmd": 0.5}, stop_time=1.0, output_interval=0.01)
    assert result["position"][-1] == pytest.approx(float(position_at(BELT, 1.0, speed_cmd=0.5)), rel=1e-12)


def test_matches_the_reference_result(conveyor_fmu: Path) -> None:
    reference = np.genfromtxt(SOURCE_DIR / "Conveyor" / "reference.csv", delimiter=",", names=True, dtype=None,
                              encoding="utf-8")
    result = simulate_fmu(str(conveyor_fmu), start_values=REFERENCE_START, stop_time=1.0, output_interval=0.01)
    assert result["time"].tolist() == pytest.approx(reference["time"].tolist(), abs=1e-12)
    for name in ("position", "speed", "t_last_edge", "t_prev_edge", "t_last_mark"):
        assert result[name].tolist() == pytest.approx(reference[name].tolist(), rel=1e-9, abs=1e-12), name
    for name in ("encoder_count", "marks_seen", "mark"):
        assert result[name].tolist() == reference[name].tolist(), name


def test_docstring_examples() -> None:
    failures, _ = doctest.testmod(cosim.plants.conveyor)
    assert failures == 0
