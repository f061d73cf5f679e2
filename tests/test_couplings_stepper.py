"""PoKeys engine coupled to Stepper FMUs: the FMUs count exactly the engine's pulses, slot by slot.

    slot         |s                  |s+1                |s+2 (empty)
    engine       |.  |  .  .  .  .   |.  |  .  .  .  .   |
    step_rate    ____|‾‾‾‾ n/1ms ‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾|____    set at t0 = slot start + 5 us, once per change
    FMU pulses       t0 + k*1ms/n    (engine: t0 + (k*1ms)//n, less than 1 ns earlier)
    counters     position == pulses emitted == commanded_steps
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import numpy as np
import pytest

from cosim.controllers.pokeys import AXES, AxisConfig, EngineConfig, EngineState, PulseEngine, encode_entry
from cosim.controllers.pokeys.host import HostApp
from cosim.controllers.pokeys.planner import Move, plan, to_entries
from cosim.couplings.stepper import StepperCoupling, couple_stepper
from cosim.couplings.switches import couple_switches
from cosim.errors import ConfigurationError
from cosim.kernel import Simulation
from cosim.master import Plant
from cosim.presets import load_preset
from cosim.signals import PulseTrain, Signal, StepDirPort

pytestmark = pytest.mark.fmu

MS = 1_000_000
PRESET = "nema17_17hs16_2004s1"
PITCH_M = 0.008 / (200 * 16)  # carriage travel of one pulse: 8 mm lead, 200 steps x 16 microsteps


def stepper(sim: Simulation, name: str, **parameters: float) -> Plant:
    return Plant.load(sim, "Stepper", name=name, fmi_version=3,
                      parameters={**load_preset(PRESET), "limit_neg_position": -1.0, **parameters})


def test_three_axis_job_near_25_khz_counters_equal_pulses_and_commanded_steps(sim: Simulation) -> None:
    config = EngineConfig(axes=tuple(AxisConfig(max_speed_hz=24_000, accel=400_000, decel=400_000)
                                     for _ in AXES))
    engine = PulseEngine(sim, config)
    plants = [stepper(sim, f"stepper_{a}") for a in AXES]
    couplings = [couple_stepper(engine.step_dir(i), plant) for i, plant in enumerate(plants)]
    far = (3_000, -2_250, 1_500)
    counts = plan([Move(far)], config.axes)
    HostApp(sim, engine, to_entries(counts), link="usb", prefill_slots=64)
    sim.run(until=300 * MS)

    assert engine.state == EngineState.BUFFER and engine.underruns == []
    for i, a in enumerate(AXES):
        segments = sim.trace.segments(f"pokeys.{a}.step")
        assert int(segments["count"].max()) == {"x": 24, "y": 18, "z": 12}[a] <= 25  # no slot above 25 pulses
        emitted = sim.trace.pulses(f"pokeys.{a}.step")
        pulses = int(np.where(emitted[1] == 1, 1, -1).sum())
        commanded = int(plants[i].read("commanded_steps"))
        assert engine.positions[i].value == pulses == commanded == far[i]
        # the FMU's last pulse is the engine's, less than 1 ns later (exact t0 + k*1ms/n vs floored)
        lag_ns = float(plants[i].read("last_pulse_time")) * 1e9 - int(emitted[0][-1])
        assert -1e-3 < lag_ns < 1.0
        # inputs set at most once per slot, and far less while the rate holds
        assert couplings[i].settings <= len(segments["count"]) + 1
        assert plants[i].steps < len(counts)
    # the recorded commanded_steps end at the counter (what the scenario check compares)
    t, v = sim.trace.edges("stepper_x.commanded_steps")
    assert int(v[-1]) == 3_000 and int(t[-1]) == sim.trace.segments("pokeys.x.step")["t0"][-1] + engine.slot_ticks


def test_constant_count_sets_the_rate_once_and_zero_after_the_last_slot(sim: Simulation) -> None:
    engine = PulseEngine(sim)
    plant = stepper(sim, "stepper_x")
    coupling = couple_stepper(engine.step_dir(0), plant)
    engine.fill_buffer([encode_entry((7, 0, 0))] * 5 + [encode_entry((0, 0, 0)), encode_entry((-3, 0, 0))])
    engine.set_state(EngineState.BUFFER)
    sim.run(until=10 * MS)
    # 7 kHz from 5 us to 5.005 ms, 0 in slot 5, -3 kHz in slot 6, 0 after it: four input changes;
    # commanded_steps is recorded at the coupling and at both stops
    t, v = sim.trace.edges("stepper_x.commanded_steps")
    assert t.tolist() == [0, 5 * MS + 5_000, 7 * MS + 5_000]
    assert v.tolist() == [0, 35, 32]
    assert coupling.settings == 4 and coupling.rate_hz == 0.0
    assert int(plant.read("commanded_steps")) == engine.positions[0].value == 32


class RecordingPlant:
    """Test double: records ``(t, step_rate)`` and counts pulses the way the FMU does (rate held per slot)."""

    name = "double"

    def __init__(self, sim: Simulation) -> None:
        self.sim = sim
        self.sets: list[tuple[int, float]] = []

    def variable_names(self) -> list[str]:
        return ["step_rate", "step_phase", "commanded_steps", "limit_pos"]

    def set(self, values: Mapping[str, float]) -> None:
        if "step_rate" in values:
            self.sets.append((self.sim.now, values["step_rate"]))

    def setter(self, variables: Sequence[str]) -> Callable[[Sequence[float]], None]:
        return lambda values: self.set(dict(zip(variables, values, strict=True)))

    def read(self, variable: str) -> object:
        return 0

    def watch(self, variable: str, *, signal: str | None = None, kind: str = "bit") -> Signal:
        return Signal(self.sim, signal or f"double.x.{variable}")


def test_without_direction_setup_the_next_slot_continues_the_rate_at_the_same_instant(sim: Simulation) -> None:
    engine = PulseEngine(sim, EngineConfig(dir_setup_ns=0))
    plant = RecordingPlant(sim)
    couple_stepper(engine.step_dir(1), plant)
    engine.fill_buffer([encode_entry((0, -25, 0))] * 3 + [encode_entry((0, 2, 0))])
    engine.set_state(EngineState.BUFFER)
    sim.run(until=6 * MS)
    assert plant.sets == [(0, 0.0), (0, -25_000.0), (3 * MS, 2_000.0), (4 * MS, 0.0)]


def test_inverted_direction_turns_the_motor_the_other_way(sim: Simulation) -> None:
    engine = PulseEngine(sim, EngineConfig(axes=(AxisConfig(invert_direction=True), AxisConfig(), AxisConfig())))
    plant = stepper(sim, "stepper_x")
    couple_stepper(engine.step_dir(0), plant)
    engine.fill_buffer([encode_entry((4, 0, 0)), encode_entry((-10, 0, 0))])
    engine.set_state(EngineState.BUFFER)
    sim.run(until=3 * MS)
    assert engine.positions[0].value == -6
    assert int(plant.read("commanded_steps")) == 6


def test_limit_trip_from_the_fmu_stops_pulses_at_the_next_slot_boundary(sim: Simulation) -> None:
    """The carriage reaches limit+ inside slot s; the engine sees it at the start of s+1 and stops.

        slot          | s-1     | s       | s+1
        x.step        |.........|.........|              last pulse: the last one of slot s
        x.limit_pos   ______________|‾‾‾‾‾‾‾‾‾‾‾‾         FMU event (exact, FMI 3.0 early return)
        state         2 ..................|100
    """
    x = AxisConfig(max_speed_hz=20_000, accel=1_000_000, decel=1_000_000, limit_pos_enabled=True)
    engine = PulseEngine(sim, EngineConfig(axes=(x, AxisConfig(), AxisConfig())))
    plant = stepper(sim, "stepper_x", limit_pos_position=1_000 * PITCH_M)
    couple_stepper(engine.step_dir(0), plant)
    couple_switches(plant, engine.switch_port(0), variables={"limit_neg": None, "home": None})
    HostApp(sim, engine, to_entries(plan([Move((4_000, 0, 0))], engine.config.axes)), link="usb")
    sim.run(until=200 * MS)

    t_sw, v_sw = sim.trace.edges("pokeys.x.limit_pos")
    t_trip = int(t_sw[v_sw == 1][0])
    boundary = engine.t0 + -(-(t_trip - engine.t0) // engine.slot_ticks) * engine.slot_ticks  # first slot start >= trip
    segments = sim.trace.segments("pokeys.x.step")
    last = int(np.flatnonzero(segments["t0"] < boundary)[-1])
    t0, n = int(segments["t0"][last]), int(segments["count"][last])
    pulses = sim.trace.pulses("pokeys.x.step")[0]
    assert int(pulses[-1]) == t0 + ((n - 1) * engine.slot_ticks) // n < boundary  # the exact last pulse
    t_state, v_state = sim.trace.edges("pokeys.state")
    assert int(t_state[v_state == 100][0]) == boundary
    assert engine.state == EngineState.STOP_LIMIT
    assert 950 < engine.positions[0].value < 1_100  # the rotor lags the command a little
    assert int(plant.read("commanded_steps")) == engine.positions[0].value == pulses.size


@pytest.mark.parametrize("axis", [3, -1])
def test_bad_axis_is_refused(sim: Simulation, axis: int) -> None:
    engine = PulseEngine(sim)
    with pytest.raises(ConfigurationError, match=rf"step_dir: axis = {axis} is not allowed \(allowed: 0\.\.2"):
        engine.step_dir(axis)
    with pytest.raises(ConfigurationError, match=rf"switch_port: axis = {axis} is not allowed"):
        engine.switch_port(axis)


def test_a_mapping_to_a_variable_the_plant_lacks_names_the_role_and_the_closest_names(sim: Simulation) -> None:
    engine, plant = PulseEngine(sim), stepper(sim, "stepper_x")
    with pytest.raises(ConfigurationError, match=r"role 'limit_pos' is mapped to 'torqe', which stepper_x does not "
                                                 r"have; did you mean torque"):
        couple_switches(plant, engine.switch_port(0), variables={"limit_pos": "torqe"})
    with pytest.raises(ConfigurationError, match=r"switch coupling role = 'torque' is not allowed "
                                                 r"\(allowed: limit_pos, limit_neg, home\)"):
        couple_switches(plant, engine.switch_port(0), variables={"torque": "torque"})
    with pytest.raises(ConfigurationError, match=r"role 'step_rate' is required"):
        couple_stepper(engine.step_dir(0), plant, variables={"step_rate": None})


def test_a_plant_with_other_names_is_coupled_through_a_mapping(sim: Simulation) -> None:
    """The stepper coupling drives any plant whose variables are mapped onto its roles."""
    engine = PulseEngine(sim, EngineConfig(dir_setup_ns=0))
    plant = RenamedPlant(sim)
    couple_stepper(engine.step_dir(1), plant, variables={"step_rate": "rate", "step_phase": "phase",
                                                         "commanded_steps": None})
    engine.fill_buffer([encode_entry((0, 4, 0))])
    engine.set_state(EngineState.BUFFER)
    sim.run(until=3 * MS)
    assert plant.sets == [(0, {"rate": 0.0, "phase": 0.0}), (0, {"rate": 4_000.0}), (1 * MS, {"rate": 0.0})]


class RenamedPlant(RecordingPlant):
    """A plant whose rate input is called ``rate`` (no commanded_steps output)."""

    def __init__(self, sim: Simulation) -> None:
        super().__init__(sim)
        self.sets_by_name: list[tuple[int, dict[str, float]]] = []

    def variable_names(self) -> list[str]:
        return ["rate", "phase"]

    def set(self, values: Mapping[str, float]) -> None:
        self.sets.append((self.sim.now, dict(values)))  # type: ignore[arg-type]


# -- how the segments reach the plant -------------------------------------------------------------------
def three_axis_job(sim: Simulation, *,
                   fmi_version: int | None) -> tuple[PulseEngine, list[Plant], list[StepperCoupling]]:
    """The 3-axis job of the first test; plants of ``fmi_version`` (None: no plants)."""
    config = EngineConfig(axes=tuple(AxisConfig(max_speed_hz=24_000, accel=400_000, decel=400_000) for _ in AXES))
    engine = PulseEngine(sim, config)
    plants = [] if fmi_version is None else [
        Plant.load(sim, "Stepper", name=f"stepper_{a}", fmi_version=fmi_version,
                   parameters={**load_preset(PRESET), "limit_neg_position": -1.0}) for a in AXES]
    couplings = [couple_stepper(engine.step_dir(i), plant) for i, plant in enumerate(plants)]
    HostApp(sim, engine, to_entries(plan([Move((3_000, -2_250, 1_500))], config.axes)), link="usb", prefill_slots=64)
    return engine, plants, couplings


@pytest.mark.parametrize("fmi_version", [3, 2])
def test_couplings_cost_no_kernel_event_per_slot_and_keep_the_engines_shortcut(fmi_version: int) -> None:
    """The job runs with as many kernel steps as without plants, plus two per instant where a run of
    segments ends (the coupling's stop there, and the engine's next slot, which it cannot skip to
    past that event). FMI 3.0: the segments way, the plants stepped once per 64 rows or so; FMI 2.0:
    the rate way, the rate set at each slot start: single segments, so its job without plants is
    taken with single segments too (runs of slots also go past the host's quiet cycles)."""
    steps, stops = {}, set()
    for plants in (None, fmi_version):
        with Simulation(seed=1) as sim:
            engine, fmus, couplings = three_axis_job(sim, fmi_version=plants)
            if plants is None and fmi_version == 2:
                for train in engine.steps:
                    train.subscribe(lambda *segment: None)  # takes single segments only, as the rate way
            sim.run(until=300 * MS)
            steps[plants] = sim.env._steps
            for i, (plant, coupling) in enumerate(zip(fmus, couplings, strict=True)):
                assert int(plant.read("commanded_steps")) == engine.positions[i].value
                assert coupling.way == ("segments" if fmi_version == 3 else "rate")
                assert coupling.deferred == 0 and coupling.rate_hz == 0.0
                segments = sim.trace.segments(f"pokeys.{AXES[i]}.step")
                ends, starts = segments["t0"] + segments["duration"], set(segments["t0"].tolist())
                stops |= {int(t) for t in ends if int(t) not in starts}
                assert plant.steps < (len(ends) // 60 + 5 if fmi_version == 3 else len(ends) + 5)
    assert 1 <= len(stops) < 20
    assert steps[fmi_version] - steps[None] == 2 * len(stops)


class PhaseRecorder(RecordingPlant):
    """Test double: records ``(t, {variable: value})`` of every setter call."""

    def __init__(self, sim: Simulation) -> None:
        super().__init__(sim)
        self.calls: list[tuple[int, dict[str, float]]] = []

    def setter(self, variables: Sequence[str]) -> Callable[[Sequence[float]], None]:
        return lambda values: self.calls.append((self.sim.now, dict(zip(variables, values, strict=True))))


def test_the_rate_is_set_at_the_slot_start_with_the_phase_of_the_first_pulse_at_t0(sim: Simulation) -> None:
    """7 pulses per 1 ms slot 5 us after the slot start: the rate is set at the slot start with phase
    1 - 5 us * 7 kHz = 0.965, so the train's first pulse falls at 5 us; the next slot (4 pulses) the
    same way; 0 at the end of the run (5 us after the third slot start)."""
    engine = PulseEngine(sim)
    plant = PhaseRecorder(sim)
    coupling = couple_stepper(engine.step_dir(0), plant)
    engine.fill_buffer([encode_entry((7, 0, 0)), encode_entry((7, 0, 0)), encode_entry((4, 0, 0))])
    engine.set_state(EngineState.BUFFER)
    sim.run(until=5 * MS)
    assert plant.calls == [(0, {"step_rate": 7_000.0, "step_phase": 1 - 5_000 * 7 / 1e6}),
                           (2 * MS, {"step_rate": 4_000.0, "step_phase": 1 - 5_000 * 4 / 1e6}),
                           (3 * MS + 5_000, {"step_rate": 0.0})]
    assert coupling.way == "rate" and coupling.deferred == 0 and coupling.settings == 3


def test_a_segment_announced_more_than_a_pulse_period_ahead_is_set_at_its_start(sim: Simulation) -> None:
    """A controller announcing at t = 0 a segment that starts at 30 us with pulses 25 us apart: no
    phase in [0, 1) puts the first pulse there, so the rate is set at 30 us by a kernel event."""
    train = PulseTrain(sim, "ctl.x.step")
    port = StepDirPort(train, Signal(sim, "ctl.x.dir"))
    plant = PhaseRecorder(sim)
    coupling = couple_stepper(port, plant)
    train.emit(30_000, 1 * MS, 40, 1)
    sim.run(until=2 * MS)
    assert plant.calls == [(30_000, {"step_rate": 40_000.0}), (1 * MS + 30_000, {"step_rate": 0.0})]
    assert coupling.deferred == 1
