"""PoKeys homing: search at 10 % of max speed, back off at 1 % until the switch changes again, stop.

x: max speed 10 kHz -> search 1 pulse/slot, back-off 0.1 pulse/slot (one pulse every 10 slots).
Home switch covers x <= -20 (position counted from the pulses).

    t [ms]   0.5      1 ... 20.005     21          30.005      31
    state    21 (homing) .....................................  20 (home)
    axis     11       12 (search, -1/slot)  13 (back, +0.1/slot)  10
    home     0 ................... 1 ...................... 0
    pulses   -1 per slot from 1 ms   one +1 pulse at 30.005 ms   none after
    counter  1234 -> ... -> reset to 0          release: at 31 ms, where the switch released (stays 0)
                                                trip:    at 21 ms, where it tripped; +1 at 30 ms
    (the axis stays at -19 either way: no move back to 0)

The vendor text says the counter is reset "when the switch is tripped" after the reversal. Every
test runs with both readings (``EngineConfig.homing_reset``): ``release`` (default, pulse engine
v2's default homing algorithm) and ``trip``; where they differ, the expectation names the reading.
"""

from __future__ import annotations

import pytest

from cosim.controllers.pokeys import AxisConfig, AxisState, EngineConfig, EngineState, PulseEngine
from cosim.couplings.ideal_axis import PositionSwitch
from cosim.errors import ConfigurationError
from cosim.kernel import Simulation
from cosim.timebase import Priority

MS = 1_000_000
READINGS = ["release", "trip"]


@pytest.fixture(params=READINGS)
def reading(request: pytest.FixtureRequest) -> str:
    return str(request.param)


def _homing(sim: Simulation, *, invert: bool = False, **config: object) -> PulseEngine:
    x = AxisConfig(max_speed_hz=10_000, home_enabled=True, invert_homing=invert)
    engine = PulseEngine(sim, EngineConfig(axes=(x, AxisConfig(home_enabled=True), AxisConfig()), **config))  # type: ignore[arg-type]
    sign = -1 if not invert else 1
    PositionSwitch(sim, engine.steps[0], engine.switches.home[0], lambda p: sign * p >= 20)
    engine.set_position(0, 1234)  # the counter is arbitrary before homing
    sim.call_at(MS // 2, Priority.HOST, lambda: engine.start_homing([0]))
    return engine


def test_homing_sequence_and_timing(sim: Simulation, reading: str) -> None:
    _homing(sim, homing_reset=reading)
    sim.run(until=60 * MS)
    t, d = sim.trace.pulses("pokeys.x.step")
    assert t[:20].tolist() == [k * MS + 5_000 for k in range(1, 21)]  # search: 1 per slot, negative
    assert set(d[:20].tolist()) == {0}
    assert t[20:].tolist() == [30 * MS + 5_000] and d[20] == 1  # back-off: 1 % = one pulse per 10 slots
    assert sim.trace.edges("pokeys.x.home")[0].tolist() == [0, 20 * MS + 5_000, 30 * MS + 5_000]
    states = sim.trace.edges("pokeys.x.axis_state")
    assert list(zip(states[0].tolist(), states[1].tolist(), strict=True)) == [
        (0, 0), (MS // 2, 11), (MS, 12), (21 * MS, 13), (31 * MS, 10)]
    assert list(zip(*[a.tolist() for a in sim.trace.edges("pokeys.state")], strict=True)) == [
        (0, 0), (MS // 2, 21), (31 * MS, 20)]


def test_homing_resets_the_counter_at_the_switch_and_does_not_return_to_zero(sim: Simulation, reading: str) -> None:
    engine = _homing(sim, homing_reset=reading)
    sim.run(until=60 * MS)
    t, v = sim.trace.edges("pokeys.x.position")
    changes = list(zip(t.tolist(), v.tolist(), strict=True))
    if reading == "release":  # 0 where the switch released (the axis at -19)
        assert changes[-3:] == [(20 * MS, 1214), (30 * MS, 1215), (31 * MS, 0)]
    else:  # 0 where it tripped (the axis at -20), then the back-off pulse counts
        assert changes[-3:] == [(20 * MS, 1214), (21 * MS, 0), (30 * MS, 1)]
    assert engine.steps[0].position == -19  # where the axis really stands: it stays there
    assert int(sim.trace.pulses("pokeys.x.step")[0][-1]) == 30 * MS + 5_000  # nothing after the reset
    assert engine.status().axis_states[0] == AxisState.HOME


def test_homing_direction_can_be_inverted(sim: Simulation, reading: str) -> None:
    engine = _homing(sim, invert=True, homing_reset=reading)
    sim.run(until=60 * MS)
    d = sim.trace.pulses("pokeys.x.step")[1]
    assert set(d[:20].tolist()) == {1} and d[20] == 0
    assert engine.state == EngineState.HOME and engine.steps[0].position == 19
    assert engine.status().positions[0] == {"release": 0, "trip": -1}[reading]


def test_homing_speeds_are_parameters(sim: Simulation, reading: str) -> None:
    _homing(sim, homing_speed_pct=20, homing_return_pct=5, homing_reset=reading)
    sim.run(until=60 * MS)
    t = sim.trace.pulses("pokeys.x.step")[0]
    # search 2 pulses/slot: -20 reached in slot 10; back-off 0.5/slot: first pulse in the 2nd slot
    assert t[:2].tolist() == [MS + 5_000, MS + 505_000] and t[19] == 10 * MS + 505_000
    assert t[20:].tolist() == [12 * MS + 5_000]


def test_homing_an_axis_already_on_its_switch_backs_off_first(sim: Simulation, reading: str) -> None:
    engine = PulseEngine(sim, EngineConfig(axes=(AxisConfig(max_speed_hz=10_000, home_enabled=True),
                                                 AxisConfig(), AxisConfig()), homing_reset=reading))
    PositionSwitch(sim, engine.steps[0], engine.switches.home[0], lambda p: p <= 0)
    engine.set_position(0, 77)
    engine.start_homing([0])
    sim.run(until=30 * MS)
    d = sim.trace.pulses("pokeys.x.step")[1]
    assert d.tolist() == [1] and engine.state == EngineState.HOME
    assert engine.status().positions[0] == {"release": 0, "trip": 1}[reading]


def test_limit_switch_stops_homing(sim: Simulation, reading: str) -> None:
    x = AxisConfig(max_speed_hz=10_000, home_enabled=True, limit_neg_enabled=True)
    engine = PulseEngine(sim, EngineConfig(axes=(x, AxisConfig(), AxisConfig()), homing_reset=reading))
    PositionSwitch(sim, engine.steps[0], engine.switches.limit_neg[0], lambda p: p <= -5)
    engine.start_homing([0])
    sim.run(until=30 * MS)
    assert engine.state == EngineState.STOP_LIMIT and engine.steps[0].position == -5


def test_homing_needs_the_home_switch_enabled_and_a_valid_axis(sim: Simulation) -> None:
    engine = PulseEngine(sim)
    with pytest.raises(ConfigurationError, match=r"start_homing: home switch of axis y enabled = False"):
        engine.start_homing([1])
    with pytest.raises(ConfigurationError, match=r"start_homing: axis = 3 is not allowed \(allowed: 0..2"):
        engine.start_homing([3])


def test_several_axes_home_together_and_the_engine_is_home_when_the_last_one_is(sim: Simulation,
                                                                               reading: str) -> None:
    fast = AxisConfig(max_speed_hz=10_000, home_enabled=True)
    slow = AxisConfig(max_speed_hz=5_000, home_enabled=True)
    engine = PulseEngine(sim, EngineConfig(axes=(fast, slow, AxisConfig()), homing_reset=reading))
    PositionSwitch(sim, engine.steps[0], engine.switches.home[0], lambda p: p <= -10)
    PositionSwitch(sim, engine.steps[1], engine.switches.home[1], lambda p: p <= -10)
    engine.start_homing([0, 1])
    sim.run(until=100 * MS)
    # x: 1 pulse/slot -> on the switch in slot 9, back-off pulse in slot 19, homed at 20 ms;
    # y: 0.5 pulse/slot -> on the switch in slot 19, back-off (0.05/slot) pulse in slot 39, homed at 40 ms
    x_states = sim.trace.edges("pokeys.x.axis_state")
    y_states = sim.trace.edges("pokeys.y.axis_state")
    assert (int(x_states[0][-1]), int(x_states[1][-1])) == (20 * MS, 10)
    assert (int(y_states[0][-1]), int(y_states[1][-1])) == (40 * MS, 10)
    t, v = sim.trace.edges("pokeys.state")
    assert (int(t[-1]), int(v[-1])) == (40 * MS, 20)
    assert engine.status().positions[:2] == {"release": (0, 0), "trip": (1, 1)}[reading]
