"""Device models: the per-slot pulse limit and the entry format belong to the device, and both routes agree.

    model    axes   pulses per 1 ms slot   source
    56E      3      25                      vendor document (pulse engine v1): "up to 25 pulses per 1 ms slot"
    57E      3      25                      protocol notes 5.1: internal generator, 3 channels, 25 kHz
    57CNC    8      125                     protocol notes 5.1: external generator, 8 channels, 125 kHz

A fill with an entry above the limit is refused as a whole on every route: the Python API raises
(nothing queued), the virtual device answers ``accepted = 0``; both record the refusal in the
engine (``refusals``, ``pokeys.refused_fills``, ``Status.refused_fills``) and the device's checks fail.
The numbers below are the documents' numbers, written as literals.
"""

from __future__ import annotations

import pytest

from cosim.controllers.pokeys import AxisState, EngineConfig, EngineState, PulseEngine, encode_entry, uniform_axes
from cosim.errors import ConfigurationError
from cosim.kernel import Simulation
from cosim.pokeys_device import Device, DeviceIdentity, PulseEngineAdapter
from cosim.pokeys_device.layouts import CFG_ENABLED, AxisRecord
from cosim.pokeys_device.packets import build_request
from cosim.pokeys_device.rig import VirtualPoKeys
from cosim.testing.pokeys_client import DirectClient

MS = 1_000_000


def _slot(axes: int, axis: int, count: int) -> tuple[int, ...]:
    return tuple(count if a == axis else 0 for a in range(axes))


def _device(sim: Simulation, model: str) -> tuple[PulseEngine, DirectClient]:
    engine = PulseEngine(sim, EngineConfig.for_model(model))
    client = DirectClient(Device(DeviceIdentity.preset(model), PulseEngineAdapter(engine)))
    if model == "56E":
        client.pe_enable(True)
        client.pe_set_state(2)
    else:
        client.v2_setup(len(engine.axis_names))
        for axis in range(len(engine.axis_names)):
            client.v2_set_axis(axis, AxisRecord(config=CFG_ENABLED, max_speed=25.0, accel=0.1, decel=0.1))
        client.v2_set_state(3)
    return engine, client


@pytest.mark.parametrize("axis", [0, 1, 2])
@pytest.mark.parametrize("sign", [1, -1])
def test_56e_api_accepts_25_and_refuses_26_pulses_on_every_axis(sim: Simulation, axis: int, sign: int) -> None:
    engine = PulseEngine(sim)
    assert engine.fill_buffer([_slot(3, axis, sign * 25)]).accepted == 1
    name = "xyz"[axis]
    with pytest.raises(ConfigurationError, match=rf"fill_buffer slot 1 axis {name}: pulses per slot = {sign * 26} "
                                                 r"is not allowed \(allowed: -25..25"):
        engine.fill_buffer([_slot(3, axis, 1), _slot(3, axis, sign * 26)])
    assert engine.buffer.level == 1  # nothing of the refused fill
    assert [(r.slot, r.axis, r.count, r.limit) for r in engine.refusals] == [(1, axis, sign * 26, 25)]
    assert engine.status().refused_fills == 1


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_virtual_56e_accepts_25_and_refuses_26_pulses_on_every_axis_of_a_fill(sim: Simulation, axis: int) -> None:
    engine, client = _device(sim, "56E")
    assert client.pe_fill([_slot(3, axis, 25)] * 2)[0] == 2
    accepted, status = client.pe_fill([_slot(3, axis, 25), _slot(3, axis, 26)])
    assert accepted == 0 and engine.buffer.level == 2 and status.engine_state == 2
    assert [(r.slot, r.axis, r.count, r.limit) for r in engine.refusals] == [(1, axis, 26, 25)]
    assert client.device.log.counts["rejected"] == 1
    sim.run(until=5 * MS)
    assert engine.steps[axis].position == 50  # 25 per slot, never more: no 26 (or 127) kHz from a 56E


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_virtual_57e_refuses_26_and_127_pulses_on_every_axis_of_8_and_16_bit_fills(sim: Simulation,
                                                                                   axis: int) -> None:
    engine, client = _device(sim, "57E")
    assert client.v2_fill([_slot(3, axis, -25)])[0] == 1
    for width, count in ((1, 26), (1, 127), (2, 26), (2, 1000)):
        assert client.v2_fill([_slot(3, axis, count)], width=width)[0] == 0
    assert [(r.axis, r.count) for r in engine.refusals] == [(axis, 26), (axis, 127), (axis, 26), (axis, 1000)]
    assert engine.buffer.level == 1


@pytest.mark.parametrize("axis", range(8))
def test_57cnc_drives_8_axes_and_accepts_125_but_not_126_pulses_per_slot(axis: int) -> None:
    sim = Simulation()
    engine, client = _device(sim, "57CNC")
    assert engine.axis_names == ("x", "y", "z", "a", "b", "c", "u", "v")
    assert client.v2_fill([_slot(8, axis, 125), _slot(8, axis, -125)])[0] == 2
    assert client.v2_fill([_slot(8, axis, 126)])[0] == 0
    assert client.v2_fill([_slot(8, axis, -126)], width=2)[0] == 0
    with pytest.raises(ConfigurationError, match=r"pulses per slot = 126 is not allowed \(allowed: -125..125"):
        engine.fill_buffer([_slot(8, axis, 126)])
    sim.run(until=3 * MS)
    t = sim.trace.pulses(f"pokeys.{engine.axis_names[axis]}.step")[0]
    assert len(t) == 250 and t[1] - t[0] == 8_000  # 125 kHz: 8 us apart
    assert client.v2_status().info[:2] == bytes((8, 125))  # status [56], [57]: 8 axes, 125 kHz


def test_v1_x_byte_0xff_is_the_reserved_special_command_never_minus_127(sim: Simulation) -> None:
    engine, client = _device(sim, "56E")
    payload = bytes((0xFF, 0, 0))
    reply = client.request(0x80, 0x35, 1, payload=payload)
    assert reply[8] == 0 and engine.buffer.level == 0
    assert client.device.log.counts["special_entry"] == 1 and client.device.log.counts["rejected"] == 1
    assert "reserved 'special command'" in engine.refusals[0].reason
    with pytest.raises(ConfigurationError, match=r"fill_buffer slot 0 axis x: x byte = '0xFF' is not allowed"):
        engine.fill_buffer([b"\xff\x00\x00"])


def test_v2_byte_0xff_is_minus_127_refused_above_the_limit_and_0xfd_is_minus_125_on_a_57cnc() -> None:
    sim = Simulation()
    engine, client = _device(sim, "57CNC")
    request = build_request(0x85, 0xFF, 2, 8, request_id=client.next_id(), payload=bytes((0xFF,) + (0,) * 7) * 2)
    assert client.send_raw(request) is not None
    assert engine.buffer.level == 0 and engine.refusals[-1].count == -127
    request = build_request(0x85, 0xFF, 1, 8, request_id=client.next_id(), payload=bytes((0xFD,) + (0,) * 7))
    reply = client.send_raw(request)
    assert reply is not None and reply[2] == 1 and engine.buffer.peek_all() == [bytes((0xFD,) + (0,) * 7)]


def test_a_refused_fill_is_in_the_device_summary_and_fails_its_checks() -> None:
    rig = VirtualPoKeys.create(DeviceIdentity.preset("56E"))
    client = DirectClient(rig.device)
    client.pe_enable(True)
    client.pe_set_state(2)
    assert client.pe_fill([(25, 0, 0), (0, 0, -26)])[0] == 0
    assert client.pe_fill([(25, -25, 25)] * 4)[0] == 4
    rig.sim.run(until=10 * MS)
    summary = rig.finish()
    refused = [c for c in rig.results if c.name.startswith("no fill refused")]
    assert len(refused) == 1 and not refused[0].passed and not summary["passed"] and summary["verdict"] == "FAIL"
    assert [r.passed for r in rig.results if not r.name.startswith("no fill refused")] == [True] * 9
    assert [(r["axis"], r["count"], r["limit"]) for r in summary["refusals"]] == [("z", -26, 25)]


def test_engine_axes_and_status_follow_the_model(sim: Simulation) -> None:
    engine = PulseEngine(sim, EngineConfig.for_model("57CNC", axes=uniform_axes(8, max_speed_hz=125_000)))
    engine.fill_buffer([encode_entry((1, 2, 3, 4, 5, 6, 7, 125))])
    engine.set_state(EngineState.BUFFER)
    sim.run(until=MS // 2)
    status = engine.status()
    assert status.positions == (1, 2, 3, 4, 5, 6, 7, 125) and status.axis_states == (AxisState.RUNNING,) * 8
    assert sim.trace.pulses("pokeys.v.step")[0].size == 125 and engine.config.pulse_width_ns == 2_000
