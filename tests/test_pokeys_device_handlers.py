"""Pulse engine commands over the engine model, in simulated time (no sockets, no wall clock).

The client's commands go through :class:`DirectClient` into :meth:`Device.handle`; the test runs
the simulation between commands, so every instant is exact::

    slot        |0 ms |1 ms |2 ms |3 ms |4 ms |5 ms |
    x.step      |10   |10   |10   |10   |10   |        limit+ trips at pulse 50 (4.905 ms)
    state       2 ...........................|100      seen at the 5 ms slot start: hard stop
"""

from __future__ import annotations

import pytest

from cosim.controllers.pokeys import EngineConfig, PulseEngine, Status
from cosim.couplings.ideal_axis import PositionSwitch
from cosim.kernel import Simulation
from cosim.pokeys_device import Device, DeviceIdentity, PulseEngineAdapter
from cosim.pokeys_device.layouts import (
    CFG_ENABLED,
    CFG_INTERNAL_PLANNER,
    CFG_POSITION_MODE,
    SW_HOME,
    SW_LIMIT_POS,
    AxisRecord,
    ParamsV1,
)
from cosim.pokeys_device.packets import build_request
from cosim.testing.pokeys_client import DirectClient

#: The pulse engine's time slot: "1 millisecond time slots" (PoKeys pulse engine documentation).
SLOT_NS = 1_000_000


def make(sim: Simulation, model: str) -> tuple[PulseEngine, Device, DirectClient]:
    engine = PulseEngine(sim, EngineConfig.for_model(model))
    device = Device(DeviceIdentity.preset(model), PulseEngineAdapter(engine))
    return engine, device, DirectClient(device)


def run_to(sim: Simulation, t_ns: int) -> None:
    sim.run(until=t_ns)


BUFFER_AXIS = AxisRecord(config=CFG_ENABLED, max_speed=25.0, accel=0.1, decel=0.1)


def start_v2(client: DirectClient, record: AxisRecord = BUFFER_AXIS) -> None:
    client.v2_setup(3)
    for axis in range(3):
        client.v2_set_axis(axis, record)
    client.v2_set_state(3)


def test_v1_disabled_engine_moves_nothing_until_enabled(sim: Simulation) -> None:
    engine, _, client = make(sim, "56E")
    client.pe_set_state(2)
    accepted, status = client.pe_fill([(5, 0, 0)] * 4)
    assert accepted == 4 and status.engine_state == 2 and status.axis_states == (0, 0, 0)
    run_to(sim, 3 * SLOT_NS)
    assert engine.steps[0].position == 0 and client.pe_free() == 124
    client.pe_enable(True)  # at 3 ms: the 3 ms slot start pops the first slot
    run_to(sim, 7 * SLOT_NS + 1)
    assert client.pe_status().positions == (20, 0, 0)
    assert sim.trace.segments("pokeys.x.step")["t0"].tolist() == [3_005_000, 4_005_000, 5_005_000, 6_005_000]


def test_v1_limit_trip_is_seen_in_the_status_and_no_pulse_follows_the_slot_boundary(sim: Simulation) -> None:
    engine, _, client = make(sim, "56E")
    PositionSwitch(sim, engine.steps[0], engine.switches.limit_pos[0], lambda p: p >= 50)
    client.pe_set_switches(limit_pos=0b001)
    client.pe_enable(True)
    client.pe_set_state(2)
    client.pe_fill([(10, 0, 0)] * 10)
    run_to(sim, 10 * SLOT_NS)
    status = client.pe_status()
    assert (status.engine_state, status.axis_states[0], status.limit_pos) == (100, 30, 0b001)
    t, _ = sim.trace.pulses("pokeys.x.step")
    assert t[-1] == 4 * SLOT_NS + 5_000 + (9 * SLOT_NS) // 10 == 4_905_000  # pulse 50, in the slot before the stop
    assert status.positions[0] == 50 and client.pe_free() == 128 - 5


def test_v1_homing_resets_the_counter_at_the_switch(sim: Simulation) -> None:
    engine, _, client = make(sim, "56E")
    PositionSwitch(sim, engine.steps[0], engine.switches.home[0], lambda p: p <= -30)
    client.pe_set_switches(home=0b001)
    client.pe_enable(True)
    client.pe_homing([0])
    run_to(sim, 200 * SLOT_NS)
    status = client.pe_status()
    assert (status.engine_state, status.axis_states[0], status.positions[0]) == (20, 10, 0)
    assert engine.steps[0].position == -29  # stopped where the switch released, no return to zero


def test_v1_internal_move_runs_to_the_reference_within_the_parameters(sim: Simulation) -> None:
    _, _, client = make(sim, "56E")
    client.pe_set_params(ParamsV1((10.0, 10.0, 10.0), (0.1,) * 3, (0.1,) * 3, 10, 1, 0))
    client.pe_enable(True)
    client.pe_move([2000, -400, 0])
    assert client.pe_status().engine_state == 0  # the reference waits for state 1
    client.pe_set_state(1)
    run_to(sim, 400 * SLOT_NS)
    status = client.pe_status()
    assert status.positions == (2000, -400, 0) and status.engine_state == 1
    assert max(sim.trace.segments("pokeys.x.step")["count"]) == 10  # 10 kHz: 10 pulses per slot at most


def test_v1_parameters_out_of_range_are_kept_or_clamped_and_counted(sim: Simulation) -> None:
    engine, device, client = make(sim, "56E")
    client.pe_set_params(ParamsV1((0.0, 40.0, float("nan")), (0.2,) * 3, (-1.0, 0.2, 0.2), 0, 1, 7))
    axes = engine.config.axes
    assert [a.max_speed_hz for a in axes] == [25_000, 25_000, 25_000]  # kept, clamped, kept
    assert [a.decel for a in axes] == [100_000, 200_000, 200_000]
    assert engine.config.homing_speed_pct == 10 and engine.config.emergency_polarity == 0
    assert device.log.counts["ignored_value"] == 6  # speed 0, 40, NaN; deceleration -1; homing 0 %; polarity 7


def test_v1_state_the_engine_refuses_is_counted_and_still_answered(sim: Simulation) -> None:
    _, device, client = make(sim, "56E")
    client.pe_enable(True)
    client.pe_set_state(100)
    assert device.log.counts["rejected"] == 1 and client.pe_status().engine_state == 0


@pytest.mark.parametrize("model, command", [("56E", 0x80), ("57E", 0x85)])
def test_unknown_pulse_engine_subcommand_gets_the_benign_reply_with_the_echo(sim: Simulation, model: str,
                                                                           command: int) -> None:
    _, device, client = make(sim, model)
    reply = client.request(command, 0x7E, 1, 2, 3, payload=b"\xff" * 56)
    assert reply[2] == 0x7E and reply[3:6] == bytes(3) and reply[8:] == bytes(56)
    assert device.log.counts["unknown_subcommand"] == 1


def test_v2_fill_drives_only_enabled_buffer_mode_axes(sim: Simulation) -> None:
    _, _, client = make(sim, "57E")
    client.v2_setup(3)
    client.v2_set_axis(0, BUFFER_AXIS)
    client.v2_set_axis(1, AxisRecord(config=CFG_ENABLED | CFG_INTERNAL_PLANNER | CFG_POSITION_MODE, max_speed=25.0,
                                     accel=0.1, decel=0.1))
    client.v2_set_state(3)
    accepted, status = client.v2_fill([(5, 5, 5)] * 10)
    assert accepted == 10 and status.axis_states[:3] == (2, 2, 0)
    run_to(sim, 11 * SLOT_NS)
    assert client.v2_status().positions[:3] == (50, 0, 0)
    assert client.request(0x85, 0xFF, 10, 0)[2] == 0  # N = 0 axes per slot: nothing accepted


def test_v2_limit_override_bits_let_an_axis_pass_its_limit(sim: Simulation) -> None:
    engine, _, client = make(sim, "57E")
    PositionSwitch(sim, engine.steps[0], engine.switches.limit_pos[0], lambda p: p >= 20)
    start_v2(client, AxisRecord(config=CFG_ENABLED, switches=SW_LIMIT_POS, max_speed=25.0, accel=0.1, decel=0.1))
    client.v2_set_state(3, limit_override=0b001)
    client.v2_fill([(10, 0, 0)] * 5)
    run_to(sim, 6 * SLOT_NS)
    status = client.v2_status()
    assert status.engine_state == 3 and status.positions[0] == 50 and status.limit_pos == 0b001
    client.v2_set_state(3)  # override off: the tripped limit stops the engine at the next slot
    run_to(sim, 7 * SLOT_NS + 1)
    assert client.v2_status().engine_state == 100 and client.v2_status().axis_states[0] == 30


def test_v2_homing_and_positions_beyond_the_modelled_axes(sim: Simulation) -> None:
    engine, _, client = make(sim, "57E")
    PositionSwitch(sim, engine.steps[2], engine.switches.home[2], lambda p: p <= -10)
    start_v2(client, AxisRecord(config=CFG_ENABLED, switches=SW_HOME, max_speed=25.0, accel=0.1, decel=0.1))
    client.v2_set_positions({2: 500, 6: -7})
    client.v2_homing([2])
    run_to(sim, 1000 * SLOT_NS)
    status = client.v2_status()
    assert status.engine_state == 20 and status.axis_states[2] == 10 and status.positions[2] == 0
    assert status.positions[6] == -7
    client.v2_finish_homing(0, skip_state_change=False)
    assert client.v2_status().engine_state == 0


def test_v2_planner_axis_moves_to_the_reference_in_running_state(sim: Simulation) -> None:
    _, _, client = make(sim, "57E")
    start_v2(client, AxisRecord(config=CFG_ENABLED | CFG_INTERNAL_PLANNER | CFG_POSITION_MODE, max_speed=5.0,
                                accel=0.01, decel=0.01))
    client.v2_move([300, -200, 0])
    run_to(sim, 400 * SLOT_NS)
    status = client.v2_status()
    assert status.positions[:3] == (300, -200, 0) and status.engine_state == 3


def test_io_commands_answer_benignly_and_echo_poextbus(sim: Simulation) -> None:
    _, device, client = make(sim, "57E")
    assert client.request(0x30, 12)[2:4] == b"\0\0"  # [2] must be 0, or the library reports an error
    data = bytes(range(1, 11))
    assert client.request(0xDA, 1, payload=data)[8:18] == data
    assert client.request(0xDA, 2)[8:18] == data
    pins = bytes([2, 4] * 27 + [8])
    client.request(0xC0, 1, payload=pins)
    assert client.request(0xC0, 0, 0)[8:63] == pins
    reply = client.request(0x77, 5, 6, payload=b"\xff" * 56)
    assert reply[2:6] == bytes(4) and reply[8:] == bytes(56) and device.log.counts["unknown_command"] == 1


def test_v2_status_check_byte_follows_the_request(sim: Simulation) -> None:
    _, _, client = make(sim, "57E")
    for check in (0, 0x15, 198, 0xFF):
        reply = client.device.handle(build_request(0x85, 0x00, check, request_id=9))
        assert reply is not None and reply[63] == (check + 0x5A) & 0xFF and reply[3] == 0


def test_device_underruns_are_the_engines_records(sim: Simulation) -> None:
    engine, device, client = make(sim, "56E")
    client.pe_enable(True)
    client.pe_set_state(2)
    client.pe_fill([(1, 0, 0)] * 3)  # slots 0..2; 3..6 find the buffer empty
    run_to(sim, 6 * SLOT_NS + 500_000)
    client.pe_fill([(1, 0, 0)] * 2)  # data again at 7 ms; empty from 9 ms on: the end of the job
    run_to(sim, 20 * SLOT_NS)
    assert [(u.t_start, u.t_end, u.slots) for u in engine.underruns] == [(3 * SLOT_NS, 7 * SLOT_NS, 4)]
    assert isinstance(device.adapter.status(), Status) and device.adapter.settings() is engine.config
