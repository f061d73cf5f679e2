"""The byte-level test vectors of the PoKeys protocol notes (section 7), reproduced exactly.

Each vector runs in-process against :class:`Device` (no sockets), over the real engine model
(``PulseEngine`` in a :class:`Simulation`, advanced slot by slot) and over the in-memory fake::

    t = 0 ms        V5 enable, state 2; V6 fill 18 slots       (reply before any slot ran)
    t = 0..18 ms    18 slot starts pop the 18 slots
    t = 18 ms + 1   V7 status: positions 18 x (10, -5, 127)

The notes' vectors V6/V7 and V12 put 127 pulses per slot on z and assume they are applied as
given (the notes' convention). The fake does that; the engine model is a PoKeys56E / 57E, whose
generator emits at most 25 pulses per slot, and refuses those fills as its Python API does: the
same request bytes then get ``accepted = 0``.
"""

from __future__ import annotations

import pytest
from pokeys_fake_engine import FakeEngine

from cosim.controllers.pokeys import EngineConfig, PulseEngine
from cosim.kernel import Simulation
from cosim.pokeys_device import Device, DeviceIdentity, PulseEngineAdapter
from cosim.pokeys_device.packets import build_large_fill, checksum, encode_entries, from_hexdump

#: The pulse engine's time slot: "1 millisecond time slots" (PoKeys pulse engine documentation).
SLOT_NS = 1_000_000

V1_REQUEST = "00: BB 00 00 00 00 00 01 BC"
V1_REPLY = "00: AA 00 4E 9B 20 3C 01 F0"
V2_REPLY = """
00: AA 00 7D 7B 37 0F 01 E9 50 4B 45 78 7B 7D 00 00
16: 37 0F 1F 00 4D 61 72 20 31 34 20 32 30 32 35 53
32: 69 6D 50 6F 4B 65 79 73 00 00 00 00 00 00 00 00
"""
V3_CLASSIC = "00 4E 9B 20 3C 7F 00 00 01 00 7F 00 00 01"
V3_EXTENDED = "00 00 00 37 0F 7F 00 00 01 00 7F 00 00 01 7B 7D 00 00 1F"
V4 = ("00: BB 80 30 00 00 00 09 74", "00: AA 80 30 00 00 00 09 63 03 19 80 0A")
V5_ENABLE = ("00: BB 80 06 01 00 00 0A 4C", "00: AA 80 06 00 00 00 0A 3A")
V5_STATE = ("00: BB 80 02 00 00 00 0B 48 02", "00: AA 80 02 00 00 00 0B 37")
V6_REQUEST = """
00: BB 80 35 12 00 00 0C 8E 0A 85 7F 0A 85 7F 0A 85
16: 7F 0A 85 7F 0A 85 7F 0A 85 7F 0A 85 7F 0A 85 7F
32: 0A 85 7F 0A 85 7F 0A 85 7F 0A 85 7F 0A 85 7F 0A
48: 85 7F 0A 85 7F 0A 85 7F 0A 85 7F 0A 85 7F 00 00
"""
V6_REPLY = """
00: AA 80 35 00 00 00 0C 6B 12 00 00 00 00 00 00 00
16: 00 00 00 00 00 00 00 00 02 02 02 02 00 00 00 00
"""
V7_STATUS = ("00: BB 80 00 00 00 00 0D 48", """
00: AA 80 00 00 00 00 0D 37 B4 00 00 00 A6 FF FF FF
16: EE 08 00 00 00 00 00 02 01 01 01 01 00 00 00 00
""")
V7_FREE = ("00: BB 80 37 00 00 00 0E 80", "00: AA 80 37 00 00 00 0E 6F 80")
V8_SET = """
00: BB 80 11 00 00 00 0F 5B 00 00 C8 41 00 00 A0 41
16: 00 00 20 41 CD CC CC 3D CD CC CC 3D CD CC CC 3D
32: CD CC 4C 3E CD CC 4C 3E CD CC 4C 3E 0A 32 00 00
"""
V8_REPLY = "00: AA 80 11 00 00 00 0F 4A"
V9 = ("00: BB 85 00 15 00 00 06 5B", """
00: AA 85 00 00 00 00 06 35 00 01 00 00 00 00 00 00
48: 00 00 00 00 00 00 00 00 08 19 80 0A 00 00 00 6F
""")
V10_SETUP = ("00: BB 85 01 00 00 00 07 48 03 00 01", "00: AA 85 01 00 00 00 07 37")
V10_SET_AXIS = ("""
00: BB 85 11 00 00 00 08 59 01 00 00 00 00 00 00 00
16: 00 00 C8 41 CD CC CC 3D CD CC CC 3D 00 00 00 00
""", "00: AA 85 11 00 00 00 08 48")
V10_GET_AXIS = ("00: BB 85 10 00 00 00 0B 5B", """
00: AA 85 10 00 00 00 0B 4A 01 00 00 00 00 00 00 00
16: 00 00 C8 41 CD CC CC 3D CD CC CC 3D 00 00 00 00
""")
V11 = ("00: BB 85 02 03 00 00 0C 51", "00: AA 85 02 00 00 00 0C 3D")
V12_FILL = ("""
00: BB 85 FF 12 03 00 0D 61 0A 85 7F 0A 85 7F 0A 85
16: 7F 0A 85 7F 0A 85 7F 0A 85 7F 0A 85 7F 0A 85 7F
32: 0A 85 7F 0A 85 7F 0A 85 7F 0A 85 7F 0A 85 7F 0A
48: 85 7F 0A 85 7F 0A 85 7F 0A 85 7F 0A 85 7F 00 00
""", """
00: AA 85 12 00 00 00 0D 4E 03 01 03 00 00 00 00 01
16: 02 02 02 00 00 00 00 00 00 00 00 00 00 00 00 00
48: 00 00 00 00 00 00 00 00 08 19 80 0A 00 00 00 00
""")
V12_STATUS = ("00: BB 85 00 1D 00 00 0E 6B", """
00: AA 85 00 00 00 00 0E 3D 03 01 03 00 00 00 00 01
16: 01 01 01 00 00 00 00 00 B4 00 00 00 A6 FF FF FF
32: EE 08 00 00 00 00 00 00 00 00 00 00 00 00 00 00
48: 00 00 00 00 00 00 00 00 08 19 80 0A 00 00 00 77
""")
V13_FILL = ("""
00: BB 85 FE 09 03 00 0F 59 E8 03 F4 81 00 00 E8 03
16: F4 81 00 00 E8 03 F4 81 00 00 E8 03 F4 81 00 00
32: E8 03 F4 81 00 00 E8 03 F4 81 00 00 E8 03 F4 81
48: 00 00 E8 03 F4 81 00 00 E8 03 F4 81 00 00 00 00
""", """
00: AA 85 09 00 00 00 0F 47 03 01 03 00 00 00 00 01
16: 02 02 02 00 00 00 00 00 B4 00 00 00 A6 FF FF FF
32: EE 08 00 00 00 00 00 00 00 00 00 00 00 00 00 00
48: 00 00 00 00 00 00 00 00 08 19 80 0A 00 00 00 00
""")
V14_HEADERS = ["BB B0 08 FF 95 03 20 2A", "BB B0 01 FF 95 03 21 24", "BB B0 02 FF 95 03 22 26",
               "BB B0 03 FF 95 03 23 28", "BB B0 04 FF 95 03 24 2A", "BB B0 05 FF 95 03 25 2C",
               "BB B0 06 FF 95 03 26 2E", "BB B0 17 FF 95 03 27 40"]
V14_REPLY_HEADER = "AA B0 80 00 00 00 27 01"
V15 = ("00: BB 40 0C 01 00 00 21 29", "00: AA 40 00 00 00 00 21 0B")


def frame(text: str) -> bytes:
    return from_hexdump(text)


class Rig:
    """A device over the engine model or the fake, with a way to let ``n`` slots run."""

    def __init__(self, model: str, engine: str) -> None:
        identity = DeviceIdentity.preset(model)
        if engine == "model":
            self.sim = Simulation(seed=1)
            self.model = PulseEngine(self.sim, EngineConfig.for_model(model))
            self.adapter: PulseEngineAdapter | FakeEngine = PulseEngineAdapter(self.model)
        else:
            self.fake = FakeEngine()
            self.adapter = self.fake
        self.engine = engine
        self.device = Device(identity, self.adapter)
        self._slots = 0

    def ask(self, request: str | bytes) -> bytes:
        reply = self.device.handle(frame(request) if isinstance(request, str) else request)
        assert reply is not None
        return reply

    def run_slots(self, n: int) -> None:
        """Let ``n`` more slot starts pop the buffer (slot k starts at k ms)."""
        if self.engine == "model":
            self._slots += n
            self.sim.run(until=self._slots * SLOT_NS + 1)
        else:
            self.fake.tick(n)


ENGINES = ["model", "fake"]


def test_v1_checksum_and_classic_device_data() -> None:
    request = frame(V1_REQUEST)
    assert request[7] == checksum(request) == 0xBC
    assert Rig("56E", "fake").ask(request) == frame(V1_REPLY)


@pytest.mark.parametrize("model, hw_type", [("57E", 0x1F), ("57CNC", 0x20)])
def test_v2_extended_device_data(model: str, hw_type: int) -> None:
    expected = bytearray(frame(V2_REPLY))
    expected[18] = hw_type
    expected[7] = checksum(expected)
    assert Rig(model, "fake").ask(V1_REQUEST) == bytes(expected)


def test_v3_discovery_replies() -> None:
    assert Rig("56E", "fake").device.discovery() == bytes.fromhex(V3_CLASSIC)
    assert Rig("57E", "fake").device.discovery() == bytes.fromhex(V3_EXTENDED)


@pytest.mark.parametrize("engine", ENGINES)
def test_v4_to_v5_pulse_engine_v1_info_and_enable(engine: str) -> None:
    rig = Rig("56E", engine)
    assert rig.ask(V4[0]) == frame(V4[1])
    assert rig.ask(V5_ENABLE[0]) == frame(V5_ENABLE[1])
    assert rig.ask(V5_STATE[0]) == frame(V5_STATE[1])


def test_v6_v7_fill_and_status_as_the_notes_give_them_on_an_engine_without_a_per_slot_limit() -> None:
    rig = Rig("56E", "fake")
    for request in (V4[0], V5_ENABLE[0], V5_STATE[0]):
        rig.ask(request)
    assert rig.ask(V6_REQUEST) == frame(V6_REPLY)  # before the first new slot has run
    rig.run_slots(18)
    assert rig.ask(V7_STATUS[0]) == frame(V7_STATUS[1])
    assert rig.ask(V7_FREE[0]) == frame(V7_FREE[1])


def test_v6_on_the_56e_model_is_refused_for_127_pulses_on_z() -> None:
    rig = Rig("56E", "model")
    for request in (V4[0], V5_ENABLE[0], V5_STATE[0]):
        rig.ask(request)
    expected = bytearray(frame(V6_REPLY))
    expected[8] = 0  # accepted: none
    expected[25:28] = bytes((1, 1, 1))  # axis states: ready, as nothing is queued
    assert rig.ask(V6_REQUEST) == bytes(expected)
    rig.run_slots(18)
    status = rig.adapter.status()
    assert status.positions == (0, 0, 0) and status.queued_slots == 0 and status.refused_fills == 1
    assert rig.device.log.counts["rejected"] == 1
    assert rig.ask(V7_FREE[0])[8] == 128


@pytest.mark.parametrize("engine", ENGINES)
def test_v8_parameters_are_returned_exactly_as_set(engine: str) -> None:
    rig = Rig("56E", engine)
    request = frame(V8_SET)
    assert rig.ask(request) == frame(V8_REPLY)
    reply = rig.ask(bytes.fromhex("BB 80 10 00 00 00 10 5B") + bytes(56))
    assert reply[8:47] == request[8:47]
    settings = rig.adapter.settings()
    assert [a.max_speed_hz for a in settings.axes[:3]] == [25_000, 20_000, 10_000]
    assert {a.accel for a in settings.axes[:3]} == {100_000} and {a.decel for a in settings.axes[:3]} == {200_000}
    assert (settings.homing_speed_pct, settings.homing_return_pct) == (10, 50)


@pytest.mark.parametrize("engine", ENGINES)
def test_v9_v2_status_at_power_on_carries_the_check_byte(engine: str) -> None:
    assert Rig("57E", engine).ask(V9[0]) == frame(V9[1])


def configure_v2(rig: Rig) -> None:
    """V10 and V11: setup, axes 0..2 in buffer mode, state running."""
    assert rig.ask(V10_SETUP[0]) == frame(V10_SETUP[1])
    set_axis = frame(V10_SET_AXIS[0])
    assert rig.ask(set_axis) == frame(V10_SET_AXIS[1])
    for axis in (1, 2):
        other = bytearray(set_axis)
        other[3] = axis
        other[7] = checksum(other)
        rig.ask(bytes(other))
    assert rig.ask(V10_GET_AXIS[0]) == frame(V10_GET_AXIS[1])
    assert rig.ask(V11[0]) == frame(V11[1])


@pytest.mark.parametrize("engine", ENGINES)
def test_v10_v11_v2_setup_axes_running(engine: str) -> None:
    configure_v2(Rig("57E", engine))


def test_v12_v2_8bit_fill_as_the_notes_give_it_on_an_engine_without_a_per_slot_limit() -> None:
    rig = Rig("57E", "fake")
    configure_v2(rig)
    assert rig.ask(V12_FILL[0]) == frame(V12_FILL[1])
    rig.run_slots(18)
    assert rig.ask(V12_STATUS[0]) == frame(V12_STATUS[1])


def test_v12_on_the_57e_model_is_refused_for_127_pulses_on_z() -> None:
    rig = Rig("57E", "model")
    configure_v2(rig)
    reply = rig.ask(V12_FILL[0])
    assert reply[2] == 0 and reply[16:19] == bytes((1, 1, 1))  # none accepted, nothing queued
    assert rig.device.log.counts["rejected"] == 1 and rig.adapter.status().refused_fills == 1


def test_v13_v2_16bit_fill_integrates_exactly_what_was_sent() -> None:
    rig = Rig("57E", "fake")
    configure_v2(rig)
    rig.ask(V12_FILL[0])
    rig.run_slots(18)
    assert rig.ask(V13_FILL[0]) == frame(V13_FILL[1])
    rig.run_slots(9)
    assert rig.fake.positions[:3] == [9180, -4590, 2286]


def test_v13_on_the_engine_model_refuses_counts_above_its_per_slot_limit() -> None:
    rig = Rig("57E", "model")
    configure_v2(rig)
    reply = rig.ask(V13_FILL[0])
    assert reply[2] == 0  # not accepted: the host keeps the slots
    assert rig.device.log.counts["rejected"] == 1 and rig.adapter.status().refused_fills == 1


@pytest.mark.parametrize("engine", ENGINES)
def test_v14_large_fill_accepts_up_to_the_buffer_limit_and_answers_with_the_last_part_id(engine: str) -> None:
    rig = Rig("57E", engine)
    request = build_large_fill(0xFF, 149, 3, encode_entries([(1, 0, 0)] * 149, width=1), first_id=0x20)
    assert [request[i * 64:i * 64 + 8] for i in range(8)] == [bytes.fromhex(h) for h in V14_HEADERS]
    assert request[8:14] == bytes.fromhex("01 00 00 01 00 00")
    reply = rig.ask(request)
    assert len(reply) == 64 and reply[:8] == bytes.fromhex(V14_REPLY_HEADER)
    assert rig.adapter.status().queued_slots == 128


@pytest.mark.parametrize("model", ["56E", "57E"])
def test_v15_benign_reply_to_a_command_that_is_not_modelled(model: str) -> None:
    assert Rig(model, "fake").ask(V15[0]) == frame(V15[1])
