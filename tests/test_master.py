"""The master: a plant is advanced only when it must be, and sampling never changes the result.

Gate pattern used below (enable on throughout)::

    gate   ____|‾‾‾‾‾‾‾‾‾‾‾‾|_______|‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾|______
           0  0.3ms       2.1ms   3.05ms            7.5ms   10ms
"""

from __future__ import annotations

from fractions import Fraction
from functools import partial
from pathlib import Path

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


def test_samples_land_on_k_times_period() -> None:
    _, _, sim = laser_run(sample_ns=250 * US)
    t, power = sim.trace.edges("laser.power")
    assert t.tolist() == [k * 250 * US for k in range(40)]  # [0, until): nothing runs at until itself
    assert power[0] == 0.0 and power.max() > 10.0


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
