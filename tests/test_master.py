"""The master: a plant is advanced only when it must be, and sampling never changes the result.

Gate pattern used below (enable on throughout)::

    gate   ____|‾‾‾‾‾‾‾‾‾‾‾‾|_______|‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾|______
           0  0.3ms       2.1ms   3.05ms            7.5ms   10ms
"""

from __future__ import annotations

from fractions import Fraction
from functools import partial
from pathlib import Path

import numpy as np
import pytest

from cosim.controllers.scripted import play
from cosim.errors import ConfigurationError, FmuError
from cosim.export import read_trace, write_trace
from cosim.kernel import Simulation
from cosim.master import Plant
from cosim.plants.laser import pwm_energy
from cosim.signals import Signal

pytestmark = pytest.mark.fmu

US = 1_000
MS = 1_000_000
GATE = [(300 * US, 1), (2_100 * US, 0), (3_050 * US, 1), (7_500 * US, 0)]


def laser_run(*, fmi_version: int = 3, sample_ns: int | None = None, reads_ns: tuple[int, ...] = (),
              seed: int = 0) -> tuple[float, int, Simulation]:
    sim = Simulation(seed=seed)
    gate = Signal(sim, "ctl.laser.gate")
    laser = Plant.load(sim, "Laser", name="laser", fmi_version=fmi_version,
                       parameters={"enable": True, "pwm_period": 1000, "pwm_on": 400})
    laser.drive("gate", gate, convert=bool)
    play(sim, [(t, {gate: v}) for t, v in GATE])
    if sample_ns:
        laser.record(["power", "energy"], period=sample_ns)
    for t in reads_ns:
        sim.call_at(t, 40, lambda: laser.read("energy"))
    sim.run(until=10 * MS)
    energy = float(laser.read("energy"))
    sim.close()
    return energy, laser.steps, sim


def closed_form() -> float:
    windows = [(Fraction(a, 10**9), Fraction(b, 10**9)) for (a, _), (b, _) in zip(GATE[::2], GATE[1::2], strict=True)]
    energy, _ = pwm_energy(windows, period=1000, on=400, peak_power=40.0, tau_rise=100e-6, tau_fall=100e-6,
                           t_end=Fraction(1, 100))
    return energy


@pytest.mark.parametrize("fmi_version", [2, 3])
def test_plant_steps_only_at_input_changes_and_reads(fmi_version: int) -> None:
    energy, steps, _ = laser_run(fmi_version=fmi_version)
    assert energy == pytest.approx(closed_form(), rel=1e-9)
    assert steps == len(GATE) + 1  # one doStep per gate change, one for the final read


@pytest.mark.parametrize("sample_ns", [None, 10 * US, 1 * US, 333_331])
def test_result_does_not_depend_on_sampling(sample_ns: int | None) -> None:
    energy, _, _ = laser_run(sample_ns=sample_ns)
    assert energy == pytest.approx(closed_form(), rel=1e-12)


def test_result_does_not_depend_on_random_extra_reads() -> None:
    rng = __import__("numpy").random.default_rng(3)
    reads = tuple(sorted({int(t) for t in rng.integers(1, 10 * MS, size=300)}))
    energy, steps, _ = laser_run(reads_ns=reads)
    assert steps >= len(reads)
    assert energy == pytest.approx(closed_form(), rel=1e-12)


def test_samples_land_on_k_times_period_and_at_every_input_change() -> None:
    """Every 250 us, and at the gate changes off that grid (300 us, 2.1 ms, 3.05 ms; 7.5 ms is on it)."""
    _, steps, sim = laser_run(sample_ns=250 * US)
    t, power = sim.trace.edges("laser.power")
    assert t.tolist() == sorted([k * 250 * US for k in range(40)] + [300 * US, 2_100 * US, 3_050 * US])
    assert power[0] == 0.0 and power.max() > 10.0
    # the Laser takes the samples inside its own steps: a step per gate change (4), one when the run stops
    # at 10 ms (to 9.75 ms, the last sample before it), one for the read; not one per sample
    assert steps == 4 + 1 + 1


@pytest.mark.parametrize("sample_ns", [100 * US, 250 * US, MS])
def test_samples_inside_the_plants_steps_are_bit_identical_to_a_step_per_sample(
        sample_ns: int, monkeypatch: pytest.MonkeyPatch) -> None:
    """The Laser stops inside a step at each sample instant as a doStep there would (the same float operations):
    power and energy equal those of the ordinary way, a doStep per sample, to the last bit."""
    _, inside, batched = laser_run(sample_ns=sample_ns)
    from cosim import sampleschedule

    monkeypatch.setattr(sampleschedule, "capacity", lambda *args: 0)
    _, each, ordinary = laser_run(sample_ns=sample_ns)
    for name in ("laser.power", "laser.energy"):
        for got, expected in zip(batched.trace.edges(name), ordinary.trace.edges(name), strict=True):
            assert got.tobytes() == expected.tobytes(), name
    assert inside < each


def test_forty_thousand_samples_cost_one_step_in_sixty_four() -> None:
    """The engraver's case: the laser recorded every 100 us for 4 s, nothing else stepping it: 40,000 samples,
    the Laser stepped every 64th sample (its sample_schedule holds 64), 625 steps, not 40,000."""
    with Simulation() as sim:
        laser = Plant.load(sim, "Laser", name="laser", parameters={"enable": True, "gate": True, "pwm_period": 1000,
                                                                    "pwm_on": 400})
        laser.record(["power", "energy"], period=100 * US)
        sim.run(until=4_000 * MS)
        t, _ = sim.trace.edges("laser.power")
        assert t.tolist() == [k * 100 * US for k in range(40_000)]
        assert laser.steps == 625


def test_a_gate_change_is_sampled_at_its_tick_without_a_step_of_its_own() -> None:
    """Sampled every 1 ms: the laser power has a sample at each gate change (300 us: still 0 W; 2.1 ms:
    the highest so far), and the FMU steps exactly as often as with no samples at the changes (4 gate changes,
    the samples up to 10 ms delivered when the run stops, the final read: the grid's samples ride inside
    those steps)."""
    _, steps, sim = laser_run(sample_ns=MS)
    t, power = sim.trace.edges("laser.power")
    assert t.tolist() == sorted([k * MS for k in range(10)] + [300 * US, 2_100 * US, 3_050 * US, 7_500 * US])
    at = dict(zip(t.tolist(), power.tolist(), strict=True))
    assert at[300 * US] == 0.0 and at[2_100 * US] == max(v for k, v in at.items() if k <= 2_100 * US) > 0.0
    assert steps == 4 + 1 + 1


def test_inputs_set_on_a_hot_path_add_no_samples_and_a_plant_event_does() -> None:
    """A Stepper at 4000 steps/s from 1.5 ms (set with a setter, as a coupling does every slot: no sample
    there) reaches its limit switch at 0.1 mm: the watched switch turns on at an event of the FMU, and the
    carriage position has a sample at that very tick."""
    with Simulation() as sim:
        stepper = Plant.load(sim, "Stepper", name="stepper", parameters={"limit_pos_position": 1e-4})
        stepper.watch("limit_pos")
        stepper.record(["carriage_position"], period=MS)
        set_rate = stepper.setter(["step_rate"])
        sim.call_at(1_500 * US, 30, lambda: set_rate([4000.0]))
        sim.run(until=20 * MS)
        t_switch, on = sim.trace.edges("stepper.limit_pos")
        trip = int(t_switch[on == 1][0])
        t, _ = sim.trace.edges("stepper.carriage_position")
    assert trip % MS != 0  # an instant off the sampling grid
    assert t.tolist() == sorted([k * MS for k in range(20)] + [trip])


def test_unknown_variable_names_the_plant_and_suggests() -> None:
    with Simulation() as sim:
        laser = Plant.load(sim, "Laser", name="laser")
        unknown = r"laser \(Laser\.fmu\) has no variable named 'gat'; did you mean gate"
        with pytest.raises(ConfigurationError, match=unknown):
            laser.drive("gat", Signal(sim, "ctl.gate"))
        with pytest.raises(ConfigurationError, match=r"laser\.energy is an output, not an input"):
            laser.drive("energy", Signal(sim, "ctl.x"))


def test_fmu_error_mid_run_raises_with_its_message_and_keeps_the_trace(tmp_path: Path) -> None:
    sim = Simulation()
    rate = Signal(sim, "ctl.stepper.step_rate", kind="real", initial=0.0)
    stepper = Plant.load(sim, "Stepper", name="stepper")
    stepper.drive("step_rate", rate)
    play(sim, [(1 * MS, {rate: 500.0}), (2 * MS, {rate: 2e7})])
    with pytest.raises(FmuError) as info:
        try:
            sim.run(until=5 * MS)
        finally:
            write_trace(sim.trace, tmp_path / "out")
    assert "input step_rate = 20000000 Hz is not allowed (allowed: -10000000..10000000 Hz)" in str(info.value)
    trace = read_trace(tmp_path / "out")
    t, v = trace.edges("ctl.stepper.step_rate")
    assert t.tolist() == [0, 1 * MS, 2 * MS] and v.tolist() == [0.0, 500.0, 2e7]


@pytest.mark.parametrize("fmi_version", [2, 3])
def test_setter_advances_then_sets_in_one_call_like_set(fmi_version: int) -> None:
    """A prepared setter gives the same run as set(): 7 kHz from 1 ms, 3 kHz from 2 ms, read at 3 ms."""
    def run(prepared: bool) -> tuple[int, float, int]:
        with Simulation() as sim:
            plant = Plant.load(sim, "Stepper", name="stepper", fmi_version=fmi_version)
            set_rate = plant.setter(["step_rate"])
            for t_ms, rate_hz in ((1, 7_000.0), (2, 3_000.0)):
                if prepared:
                    sim.call_at(t_ms * MS, 40, partial(set_rate, [rate_hz]))
                else:
                    sim.call_at(t_ms * MS, 40, partial(plant.set, {"step_rate": rate_hz}))
            sim.run(until=3 * MS)
            return int(plant.read("commanded_steps")), float(plant.read("angle")), plant.steps

    results = [run(False), run(True)]
    assert results[0] == results[1]
    assert results[0][0] == 7 + 3 and results[0][2] == 3  # two sets and the final read: three doSteps


@pytest.mark.parametrize("fmi_version", [2, 3])
def test_setter_refused_value_names_variable_value_and_range(fmi_version: int) -> None:
    with Simulation() as sim:
        plant = Plant.load(sim, "Stepper", name="stepper", fmi_version=fmi_version)
        with pytest.raises(FmuError, match=r"setting step_rate = 20000000.0 failed") as info:
            plant.setter(["step_rate"])([2e7])
        assert "input step_rate = 20000000 Hz is not allowed (allowed: -10000000..10000000 Hz)" in str(info.value)
        with pytest.raises(ConfigurationError, match=r"Float64 variables only; got enable \(Boolean\)"):
            plant.setter(["enable"])
        with pytest.raises(ConfigurationError, match=r"0 values for 1 variables \(step_rate\)"):
            plant.setter(["step_rate"])([])


def test_before_step_hooks_see_every_step_and_its_target_before_it_is_taken() -> None:
    """Samples every 1 ms (the sample loop: pwm_periods is an output the Laser does not sample inside its steps)
    and a read at 1.5 ms (an output needed): each step to t is announced as t while the FMU is still at the
    previous instant."""
    with Simulation() as sim:
        laser = Plant.load(sim, "Laser", name="laser", parameters={"enable": True, "pwm_period": 1000, "pwm_on": 400})
        seen: list[tuple[int, int]] = []
        laser.before_step(lambda t: seen.append((t, laser.fmu.t)))
        laser.record(["power", "pwm_periods"], period=MS)
        sim.call_at(1_500 * US, 40, lambda: laser.read("energy"))
        sim.run(until=3 * MS + 1)
    assert seen == [(MS, 0), (1_500 * US, MS), (2 * MS, 1_500 * US), (3 * MS, 2 * MS)]


def test_before_step_hooks_see_the_look_ahead_steps_of_a_watched_plant() -> None:
    with Simulation() as sim:
        stepper = Plant.load(sim, "Stepper", name="stepper")
        stepper.watch("limit_pos")
        seen: list[int] = []
        stepper.before_step(seen.append)
        for t in (2 * MS, 5 * MS):
            sim.call_at(t, 40, lambda: None)
        sim.run(until=7 * MS)
    assert seen == [2 * MS, 5 * MS, 7 * MS]  # the look-ahead steps to each next instant, the last to until


def test_an_ahead_writer_sets_a_schedule_without_stepping_the_plant() -> None:
    """Segment rows written at t = 0 for 5 pulses in [2 ms, 3 ms): nothing steps the FMU until the
    read at 1.5 ms (no pulse yet) and the one at 4 ms (all five)."""
    with Simulation() as sim:
        stepper = Plant.load(sim, "Stepper", name="stepper")
        rows = np.zeros((64, 3))
        write = stepper.ahead_writer("step_segments", rows)
        rows[0] = (2e-3, 1e-3, 5)
        write()
        assert (stepper.steps, stepper.fmu.t) == (0, 0)
        reads: list[int] = []
        for t in (1_500 * US, 4 * MS):
            sim.call_at(t, 40, lambda: reads.append(int(stepper.read("commanded_steps"))))
        sim.run(until=5 * MS)
        assert reads == [0, 5] and stepper.steps == 2
        assert float(stepper.read("last_pulse_time")) == pytest.approx(2e-3 + 4 * 1e-3 / 5, abs=1e-15)
        with pytest.raises(ConfigurationError, match=r"needs a C-contiguous float64 numpy array of 192 elements"):
            stepper.ahead_writer("step_segments", np.zeros((64, 2)))
        with pytest.raises(ConfigurationError, match=r"takes a Float64 array of an FMI 3.0 FMU; got step_rate"):
            stepper.ahead_writer("step_rate", np.zeros(1))


# -- rows of grid samples stepped in C (cosim.gridloop) ------------------------------------------------

GridRun = tuple[dict[str, tuple[list[int], bytes]], int, str | None, int]


def grid_run(model: str, fmi_version: int, parameters: dict[str, float], *, outputs: list[str], period: int,
             until: int, python_loop: bool, monkeypatch: pytest.MonkeyPatch) -> GridRun:
    """A plant recorded on a grid, nothing else stepping it: the samples, the steps, how it ended, and how many
    rows the C loop ran (the Python loop when ``python_loop``)."""
    from cosim import gridloop
    from cosim.errors import PlantTerminated

    rows = [0]
    real_run = gridloop.GridRow.run

    def counted(self: gridloop.GridRow, *args: int) -> int:
        rows[0] += 1
        return real_run(self, *args)

    monkeypatch.setattr(gridloop.GridRow, "run", counted)
    monkeypatch.setattr(gridloop, "_LOADED", [None] if python_loop else [])
    with Simulation() as sim:
        plant = Plant.load(sim, model, name="p", fmi_version=fmi_version, parameters=parameters)
        sample = plant.record(outputs, period=period)
        ended = None
        try:
            sim.run(until=until)
            sample()
        except (PlantTerminated, FmuError) as exc:
            ended = f"{type(exc).__name__}: {exc}"
        samples = {}
        for name in outputs:
            t, v = sim.trace.edges(f"p.{name}")
            samples[name] = (t.tolist(), v.tobytes())
    return samples, plant.steps, ended, rows[0]


@pytest.mark.parametrize("fmi_version", [2, 3])
def test_the_servo_on_the_pmac_grid_stepped_in_c_gives_the_python_loops_samples_to_the_last_bit(
        fmi_version: int, monkeypatch: pytest.MonkeyPatch) -> None:
    """The Servo turning (u_cmd = 2 V) recorded every 442 us for 0.5 s, eleven outputs of three FMI types: the
    C loop makes the doSteps and getter calls the Python loop makes, so every sample is the same, to the bit."""
    outputs = ["angle", "speed", "current", "motor_voltage", "torque", "stuck", "encoder_count", "edge_count",
               "edge_direction", "t_last_edge", "t_prev_edge"]
    run = partial(grid_run, "Servo", fmi_version, {"u_cmd": 2.0}, outputs=outputs, period=442 * US, until=500 * MS,
                  monkeypatch=monkeypatch)
    in_c, steps_c, ended_c, rows = run(python_loop=False)
    in_python, steps_python, ended_python, _ = run(python_loop=True)
    assert in_c["angle"][0][:3] == [0, 442_000, 884_000]
    assert in_c["angle"][0][-2:] == [499_902_000, 500_000_000]  # 1131 x 442 us, then the end of the run
    assert steps_c == steps_python == 1132
    assert rows >= 1
    assert np.frombuffer(in_c["encoder_count"][1])[-1] > 0  # the motor turned: the encoder counted
    assert in_c == in_python
    assert ended_c is ended_python is None


@pytest.mark.parametrize("fmi_version", [2, 3])
@pytest.mark.parametrize("parameters", [{}, {"terminate_time": 0.35}, {"terminate_time": 0.36}, {"error_time": 0.35}],
                         ids=["event", "terminate-between-samples", "terminate-on-a-sample", "error"])
def test_rows_in_c_stop_where_the_plant_needs_more_than_a_sample_as_the_python_loop_does(
        fmi_version: int, parameters: dict[str, float], monkeypatch: pytest.MonkeyPatch) -> None:
    """TypesTest (speed 1 m/s, its time event at 0.2 s) every 30 ms: the event (FMI 3.0: an early return, sampled
    at 200 ms), a terminate request between samples (at 350 ms: the run ends there) or on one (360 ms: that sample
    is the FMU's last values) and a doStep failing (at 0.35 s) leave the same samples, steps and message in C as
    in Python."""
    run = partial(grid_run, "TypesTest", fmi_version, {"speed": 1.0, **parameters}, outputs=["position", "event_stage"],
                  period=30 * MS, until=500 * MS, monkeypatch=monkeypatch)
    in_c, steps_c, ended_c, rows = run(python_loop=False)
    in_python, steps_python, ended_python, _ = run(python_loop=True)
    times = in_c["position"][0]
    name = next((k for k in ("terminate_time", "error_time") if k in parameters), "")
    last = {"": 500, "terminate_time": 330 if parameters.get("terminate_time") == 0.35 else 360, "error_time": 330}
    expected = [k * 30 * MS for k in range(last[name] // 30 + 1)] + ([500 * MS] if not name else [])
    if fmi_version == 3:  # the early return at the time event: a sample there
        expected = sorted([*expected, 200 * MS])
    assert times == expected
    assert rows >= 1
    assert (in_c, steps_c, ended_c) == (in_python, steps_python, ended_python)
    if name == "terminate_time":
        assert ended_c is not None and f"terminated at t={int(parameters[name] * 1000)}000000 ticks" in ended_c
    if name == "error_time":
        assert ended_c is not None and ended_c.startswith("FmuError") and "failed with status Error" in ended_c


def test_without_a_c_compiler_or_with_a_failing_one_the_python_loop_runs_and_the_build_is_not_retried(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """No compiler on PATH: no C loop (the grid is stepped in Python, same samples). A compiler that fails: the
    failure is kept beside the library's name (``.failed``, its message) and not tried again on the next run."""
    from cosim import gridloop

    monkeypatch.setenv("COSIM_FMU_CACHE", str(tmp_path / "cache"))
    monkeypatch.setenv("PATH", str(tmp_path / "nothing"))
    monkeypatch.setattr(gridloop, "_LOADED", [])
    assert gridloop.library() is None
    samples, steps, ended, rows = grid_run("TypesTest", 3, {"speed": 1.0}, outputs=["position"], period=100 * MS,
                                           until=300 * MS, python_loop=False, monkeypatch=monkeypatch)
    assert samples["position"][0] == [0, 100 * MS, 200 * MS, 300 * MS]
    assert (steps, ended, rows) == (3, None, 0)

    monkeypatch.undo()
    monkeypatch.setenv("COSIM_FMU_CACHE", str(tmp_path / "cache"))
    broken = tmp_path / "gridloop.c"
    broken.write_text("this is not C\n")
    monkeypatch.setattr(gridloop, "SOURCE", broken)
    monkeypatch.setattr(gridloop, "_LOADED", [])
    assert gridloop.library() is None
    failed = list((tmp_path / "cache").glob("gridloop-*.failed"))
    assert len(failed) == 1 and b"error" in failed[0].read_bytes()
    calls = []
    monkeypatch.setattr("subprocess.run", lambda *args, **kwargs: calls.append(args))
    monkeypatch.setattr(gridloop, "_LOADED", [])
    assert gridloop.library() is None
    assert calls == []  # not compiled again
