"""Every FMI variable type and arrays through the master, and a plant that ends the run (TypesTest FMU).

The test model (fmu_src/TypesTest) copies each <type>_in to <type>_out, doubles vec_in into vec_out,
integrates speed into position, and at parameter times::

    event_stage  1 ____________________|‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾ 2
    position     0 ...................................... 0.7 m     (speed 2 m/s)
                 0                   0.2 s        0.35 s: terminate_time -> the run ends here (TERMINATED)
                                            0.25 s: error_time -> doStep fails (ERROR), when asked
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from cosim.checks.levels import Bound
from cosim.controllers.scripted import play
from cosim.errors import ConfigurationError, FmuError, PlantTerminated
from cosim.export import read_trace
from cosim.kernel import Simulation
from cosim.master import Plant
from cosim.runner import Result, run_scenario
from cosim.scenario import Run, ScenarioFile
from cosim.signals import Signal

pytestmark = pytest.mark.fmu

MS = 1_000_000  # ns
#: Inputs at the ends of their types' ranges (FMI 3.0 has every type).
FMI3_VALUES: dict[str, object] = {
    "speed": -2.5, "f32_in": 1.25, "i8_in": -128, "u8_in": 255, "i16_in": -32768, "u16_in": 1000,
    "i32_in": 2147483647, "u32_in": 4294967295, "i64_in": -9223372036854775808, "u64_in": 18446744073709551615,
    "flag_in": True, "text_in": "héllo wörld", "blob_in": b"\x00\xffab", "mode_in": 3,
}
#: FMI 2.0 has Real, Integer, Boolean, String and Enumeration.
FMI2_VALUES: dict[str, object] = {"speed": -2.5, "i32_in": -2147483648, "flag_in": True, "text_in": "héllo wörld",
                                  "mode_in": 3}


def types_plant(sim: Simulation, fmi_version: int, **parameters: Any) -> Plant:
    return Plant.load(sim, "TypesTest", name="types", fmi_version=fmi_version, parameters=parameters)


@pytest.mark.parametrize("fmi_version", [2, 3])
def test_every_type_is_set_and_read_back_through_the_master(fmi_version: int) -> None:
    values = FMI3_VALUES if fmi_version == 3 else FMI2_VALUES
    with Simulation() as sim:
        plant = types_plant(sim, fmi_version)
        plant.set(values)
        for name, value in values.items():
            if name == "speed":
                continue
            out = plant.read(name.replace("_in", "_out"))
            assert out == value and type(out) is type(value), name
        plant.set({"mode_in": "slow"})  # an Enumeration also by its item name
        assert plant.read("mode_out") == 2


@pytest.mark.parametrize("fmi_version", [2, 3])
def test_variables_carry_the_declared_type_unit_and_range(fmi_version: int) -> None:
    with Simulation() as sim:
        fmu = types_plant(sim, fmi_version).fmu
        speed, mode = fmu.variable("speed"), fmu.variable("mode_in")
        assert (speed.type, speed.unit, speed.causality) == ("Real" if fmi_version == 2 else "Float64", "m/s", "input")
        assert mode.items == {"off": 1, "slow": 2, "fast": 3} and mode.limits() == (1, 3)
        if fmi_version == 3:
            assert (fmu.variable("f32_in").type, fmu.variable("f32_in").unit) == ("Float32", "V")
            assert fmu.variable("u16_in").limits() == (1, 1000)
            assert (fmu.variable("vec_in").shape, fmu.variable("matrix_out").shape) == ((3,), (2, 3))
        else:
            assert "f32_in" not in fmu.variables and "vec_in" not in fmu.variables


def test_arrays_are_read_and_set_as_numpy_arrays() -> None:
    with Simulation() as sim:
        plant = types_plant(sim, 3)
        assert np.asarray(plant.read("vec_in")).tolist() == [1.0, 2.0, 3.0]
        plant.set({"vec_in": np.array([0.5, -1.0, 4.0])})
        vec = plant.read("vec_out")
        assert isinstance(vec, np.ndarray) and vec.dtype == np.float64 and vec.tolist() == [1.0, -2.0, 8.0]
        matrix = plant.read("matrix_out")
        assert isinstance(matrix, np.ndarray) and matrix.dtype == np.int16
        assert matrix.tolist() == [[0, 1, 2], [10, 11, 12]]  # element (i, j) = 10 i + j: row-major
        with pytest.raises(ConfigurationError, match=r"^types \(TypesTest.fmu\): shape of vec_in = \(2,\) is not "
                                                     r"allowed \(allowed: \(3,\) or 3 elements\)$"):
            plant.set({"vec_in": [1.0, 2.0]})


@pytest.mark.parametrize(("name", "value", "allowed"), [
    ("i8_in", 128, "-128..127"),
    ("u8_in", -1, "0..255"),
    ("i16_in", 32768, "-32768..32767"),
    ("u16_in", 0, "1..1000"),  # the variable's own declared range
    ("u16_in", 1001, "1..1000"),
    ("u32_in", 2**32, "0..4294967295"),
    ("i64_in", 2**63, "-9223372036854775808..9223372036854775807"),
    ("u64_in", 2**64, "0..18446744073709551615"),
    ("mode_in", 4, "1..3 (1 off, 2 slow, 3 fast)"),
    ("i32_in", 1.5, "-2147483648..2147483647"),
])
def test_integers_outside_their_range_never_reach_the_fmu(name: str, value: object, allowed: str) -> None:
    with Simulation() as sim:
        plant = types_plant(sim, 3)
        before = plant.read(name)
        with pytest.raises(ConfigurationError) as info:
            plant.set({name: value})
        assert str(info.value) == f"types (TypesTest.fmu): {name} = {value!r} is not allowed (allowed: {allowed})"
        assert plant.read(name) == before and not plant.fmu.log


@pytest.mark.parametrize("fmi_version", [2, 3])
def test_an_int32_input_does_not_wrap(fmi_version: int) -> None:
    """Issue 22, finding 2: pwm_period = 2**32 + 1000 used to store 1000."""
    with Simulation() as sim:
        laser = Plant.load(sim, "Laser", name="laser", fmi_version=fmi_version)
        with pytest.raises(ConfigurationError, match=r"^laser \(Laser.fmu\): pwm_period = 4294968296 is not allowed "
                                                     r"\(allowed: 0..2147483647\)$"):
            laser.set({"pwm_period": 2**32 + 1000})
        assert laser.read("pwm_period") == 1000


def test_numbers_booleans_and_array_elements_are_recorded_strings_are_refused() -> None:
    with Simulation() as sim:
        plant = types_plant(sim, 3, speed=2.0, u64_in=2**53)
        plant.record(["position", "event_stage", "flag_out", "u64_out", "vec_out", "matrix_out"], period=100 * MS)
        with pytest.raises(ConfigurationError, match=r"types\.text_out is a String variable: the trace records "
                                                     "numbers and Booleans only"):
            plant.record(["text_out"], period=100 * MS)
        sim.run(until=300 * MS)
        trace = sim.trace
    assert trace.edges("types.position")[1].tolist() == [0.0, 0.2, 0.4]
    assert trace.edges("types.event_stage")[1].tolist() == [1.0, 1.0, 2.0]
    assert trace.edges("types.u64_out")[1].tolist() == [2.0**53] * 3
    assert trace.edges("types.vec_out.2")[1].tolist() == [6.0] * 3 and trace.info["types.vec_out.2"].unit == "m"
    assert trace.edges("types.matrix_out.1.2")[1].tolist() == [12.0] * 3


@pytest.mark.parametrize(("fmi_version", "grid"), [(3, None), (2, 10 * MS)])
def test_a_watched_output_changes_at_the_event(fmi_version: int, grid: int | None) -> None:
    """FMI 3.0: early return at 0.2 s exactly; FMI 2.0: at the end of the step holding it (a 10 ms grid here)."""
    with Simulation() as sim:
        plant = types_plant(sim, fmi_version)
        stage = plant.watch("event_stage", kind="int")
        if grid:
            plant.record(["position"], period=grid)
        for refused in ("text_out", "vec_out") if fmi_version == 3 else ("text_out",):
            with pytest.raises(ConfigurationError, match="a watched output must be a number or a Boolean"):
                plant.watch(refused)
        moving = plant.watch("position", signal="types.watched_position", kind="real")
        sim.run(until=300 * MS)
        assert sim.trace.edges(stage.name)[0].tolist() == [0, 200 * MS]
        assert sim.trace.info[moving.name].unit == "m"  # the FMU's declared unit


# -- a plant that ends the run --------------------------------------------------------------------------
def scenario(function: Callable[[Run], None], until: str = "1 s") -> ScenarioFile:
    return ScenarioFile(name="types_end", path=Path(__file__), description="", parameters=(), until=until,
                        function=function)


def sampled(fmi_version: int, plants: list[Plant], **parameters: object) -> Callable[[Run], None]:
    def recipe(run: Run) -> None:
        plant = types_plant(run.sim, fmi_version, speed=2.0, **parameters)
        plants.append(plant)
        plant.record(["position", "event_stage"], period=50 * MS)
        run.check(Bound("types.position", upper=0.7, name="position up to 0.7 m"))

    return recipe


@pytest.mark.parametrize(("fmi_version", "in_event_mode", "how"), [
    (2, False, "returned Discard (fmi2Terminated: the FMU asks to end the simulation)"),
    (3, False, "asked to terminate from doStep at t=0.35 s"),
    (3, True, "asked to terminate in event mode at t=0.35 s"),
])
def test_a_terminate_request_ends_the_run_at_its_tick(tmp_path: Path, fmi_version: int, in_event_mode: bool,
                                                      how: str) -> None:
    plants: list[Plant] = []
    recipe = sampled(fmi_version, plants, terminate_time=0.35, terminate_in_event_mode=in_event_mode)
    result = run_scenario(scenario(recipe), out=tmp_path)
    assert result.verdict == "TERMINATED" and result.error is None
    terminated = result.terminated or {}
    assert (terminated["plant"], terminated["fmu"], terminated["t_ticks"]) == ("types", "TypesTest.fmu", 350 * MS)
    assert how in terminated["reason"]
    assert terminated["log"][-1].endswith("terminate_time = 0.34999999999999998 s reached: the model asks to end "
                                          "the simulation")
    assert result.simulated_s == 0.35 and [c["passed"] for c in result.checks] == [True]  # checked up to then
    written = json.loads((tmp_path / "result.json").read_text())
    assert written["verdict"] == "TERMINATED" and written["terminated"]["t_ticks"] == 350 * MS
    trace = read_trace(tmp_path)
    assert trace.end_t == 350 * MS
    t, position = trace.edges("types.position")
    assert t.tolist() == [k * 50 * MS for k in range(8)] and position[-1] == pytest.approx(0.7, abs=1e-12)
    fmu = plants[0].fmu
    assert fmu.terminated == terminated["reason"] and fmu._fmu is None  # terminated and freed


def test_a_watched_plant_ends_the_run_before_anything_else_at_its_tick() -> None:
    """Other activity every 5 ms: the last at 345 ms; the one at 350 ms (the terminate tick) never runs."""
    ended: list[Simulation] = []

    def recipe(run: Run) -> None:
        plant = types_plant(run.sim, 3, terminate_time=0.35)
        plant.watch("event_stage", kind="int")
        tick = Signal(run.sim, "ctl.tick", kind="int")
        play(run.sim, [(k * 5 * MS, {tick: k}) for k in range(1, 100)])
        ended.append(run.sim)

    result = run_scenario(scenario(recipe))
    assert result.verdict == "TERMINATED" and result.terminated is not None
    assert result.terminated["t_ticks"] == 350 * MS and ended[0].now == 350 * MS
    assert ended[0].trace.edges("ctl.tick")[0][-1] == 345 * MS
    assert ended[0].trace.edges("types.event_stage")[0].tolist() == [0, 200 * MS]


def test_a_terminated_plant_keeps_its_last_values_and_cannot_go_on() -> None:
    with Simulation() as sim:
        plant = types_plant(sim, 2, speed=2.0, terminate_time=0.35)
        plant.record(["position"], period=100 * MS)
        with pytest.raises(PlantTerminated) as info:
            sim.run(until=500 * MS)
        assert info.value.t == 350 * MS and "FMU log:" in str(info.value)
        assert plant.read("position") == pytest.approx(0.7, abs=1e-12)  # the value at its last instant
        with pytest.raises(PlantTerminated):
            plant.fmu.advance_to(500 * MS)
    with pytest.raises(FmuError, match=r"types \(TypesTest.fmu\) is closed"):  # freed with its simulation
        plant.read("position")


@pytest.mark.parametrize("fmi_version", [2, 3])
def test_an_fmu_error_keeps_error_and_puts_the_fmu_log_in_the_result(tmp_path: Path, fmi_version: int) -> None:
    result: Result = run_scenario(scenario(sampled(fmi_version, [], error_time=0.25)), out=tmp_path)
    assert result.verdict == "ERROR" and result.terminated is None
    written = json.loads((tmp_path / "result.json").read_text())
    assert "[Error] logStatusError: error_time = 0.25 s reached: the model fails here as asked" in written["error"]
    assert read_trace(tmp_path).edges("types.position")[0][-1] == 200 * MS  # kept up to the error
