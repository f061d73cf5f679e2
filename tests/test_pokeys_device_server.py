"""The virtual device on real sockets, in real time: discovery, handshake, buffered jobs, a limit trip, bad packets.

Each test starts a server on free ports of 127.0.0.1 (its own event loop in a thread, the engine
paced one slot per wall-clock millisecond) and drives it with the client written from the
protocol notes. A job is a few hundred slots, so each test takes a fraction of a second::

    host   fill 18 | fill 18 | ... (as many as the device accepts) ... | poll until the buffer is empty
    device  128-slot buffer, one slot popped per 1 ms of wall clock
    after stop: positions == pulses recorded == sum of the slots the device accepted
"""

from __future__ import annotations

import socket
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager

import pytest

from cosim.controllers.pokeys import PulseEngine
from cosim.couplings.ideal_axis import PositionSwitch
from cosim.errors import ConfigurationError
from cosim.kernel import Simulation
from cosim.pokeys_device import DeviceIdentity
from cosim.pokeys_device.layouts import CFG_ENABLED, SW_LIMIT_POS, AxisRecord
from cosim.pokeys_device.packets import build_request
from cosim.pokeys_device.rig import VirtualPoKeys, Wiring
from cosim.pokeys_device.server import BackgroundServer, DeviceServer
from cosim.testing.pokeys_client import PoKeysClient, discover

#: The pulse engine's time slot: "1 millisecond time slots" (PoKeys pulse engine documentation).
SLOT_NS = 1_000_000

AXIS = AxisRecord(config=CFG_ENABLED, max_speed=25.0, accel=0.1, decel=0.1)
POLL_S = 0.003
#: Wall-time guards only (nothing here asserts a duration): how long a client waits for a reply before it resends,
#: how long a probe that expects no reply listens, and (wait_until) how long a state may take to show. Generous, so a
#: machine busy with other work does not turn a slow loopback reply into a resend or a failure.
REPLY_S = 5.0
SILENT_S = 0.3


@contextmanager
def serving(model: str, *, wire: Wiring | None = None, serial: int | None = None
            ) -> Iterator[tuple[VirtualPoKeys, int]]:
    rig = VirtualPoKeys.create(DeviceIdentity.preset(model, serial=serial), wire=wire)
    with BackgroundServer(DeviceServer(rig.device, pacer=rig.pacer, port=0)) as running:
        assert running.server.tcp_port == running.server.udp_port
        yield rig, running.server.udp_port


def job_slots(n: int) -> list[tuple[int, int, int]]:
    """Up to 25 pulses per slot on x, reversing y, a slow z."""
    return [(min(25, 1 + k // 4), -(k % 26) if k < n // 2 else k % 26, k % 3) for k in range(n)]


def client_for(port: int, transport: str) -> PoKeysClient:
    return PoKeysClient("127.0.0.1", port, transport=transport, timeout_s=REPLY_S)


def wait_until(condition: object, *, timeout_s: float = 30.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not condition():  # type: ignore[operator]
        assert time.monotonic() < deadline, "timed out"
        time.sleep(POLL_S)


def send_all(fill: Callable[[Sequence[tuple[int, ...]]], tuple[int, object]],
             slots: Sequence[tuple[int, ...]]) -> None:
    """Offer 18 slots per packet until the device has accepted them all (it takes what fits)."""
    sent = 0
    while sent < len(slots):
        accepted, _ = fill(slots[sent:sent + 18])
        sent += accepted
        if not accepted:
            time.sleep(POLL_S)


def stream_v1(client: PoKeysClient, slots: Sequence[tuple[int, ...]]) -> None:
    client.pe_enable(True)
    client.pe_set_state(2)
    send_all(client.pe_fill, slots)
    wait_until(lambda: client.pe_free() == 128)


def stream_v2(client: PoKeysClient, slots: Sequence[tuple[int, ...]]) -> None:
    client.v2_setup(3)
    for axis in range(3):
        client.v2_set_axis(axis, AXIS)
    client.v2_set_state(3)
    send_all(client.v2_fill, slots)
    wait_until(lambda: client.v2_status().axis_states[:3] == (1, 1, 1))


@pytest.mark.parametrize("model, transport", [("56E", "udp"), ("56E", "tcp"), ("57E", "udp"), ("57E", "tcp")])
def test_buffered_job_final_positions_equal_the_pulses_sent(model: str, transport: str) -> None:
    slots = job_slots(220)
    expected = tuple(sum(s[a] for s in slots) for a in range(3))
    with serving(model) as (rig, port), client_for(port, transport) as client:
        info = client.identify()
        assert (info.serial, info.type_name) == ((20123, "PoKeys56E") if model == "56E" else (32123, "PoKeys57E"))
        (stream_v1 if model == "56E" else stream_v2)(client, slots)
        positions = client.pe_status().positions if model == "56E" else client.v2_status().positions[:3]
        assert positions == expected
        assert (client.stale_replies, client.bad_replies, client.resends) == (0, 0, 0)
    summary = rig.finish()
    assert tuple(summary["pulses"]) == tuple(summary["positions"]) == expected
    assert summary["passed"] and summary["verdict"] == "PASS", summary["checks"]
    assert summary["packets"].keys() <= {"request", "tcp_connection"}


def test_discovery_answers_an_empty_datagram_with_the_serial_and_type() -> None:
    for model, serial, hw_type in (("56E", 20777, 0), ("57CNC", 4_000_000_000, 32)):
        with serving(model, serial=serial) as (_, port):
            (found,) = discover(port, timeout_s=1.0, serial=serial)
            assert (found.serial, found.hw_type, found.device_ip) == (serial, hw_type, "127.0.0.1")


@pytest.mark.parametrize("transport", ["udp", "tcp"])
def test_identification_handshake_runs_twice_on_one_socket(transport: str) -> None:
    with serving("56E") as (rig, port), client_for(port, transport) as client:
        first, second = client.identify(), client.identify()
        assert first == second and (first.type_id, first.serial, first.pe_v1, first.pe_v2) == (11, 20123, True, False)
        assert client.pe_info() == bytes((3, 25, 128, 10))
    assert rig.device.log.counts["request"] == 2 * (1 + 1 + 1 + 1 + 3 + 1 + 1) + 1


def test_limit_trip_is_seen_by_the_client_in_the_status() -> None:
    def wire(sim: Simulation, engine: PulseEngine) -> None:
        PositionSwitch(sim, engine.steps[0], engine.switches.limit_pos[0], lambda p: p >= 100)

    with serving("57E", wire=wire) as (rig, port), client_for(port, "udp") as client:
        client.v2_setup(3)
        client.v2_set_axis(0, AxisRecord(config=CFG_ENABLED, switches=SW_LIMIT_POS, max_speed=25.0, accel=0.1,
                                         decel=0.1))
        client.v2_set_state(3)
        client.v2_fill([(10, 0, 0)] * 18)
        wait_until(lambda: client.v2_status().engine_state == 100)
        status = client.v2_status()
        assert (status.limit_pos, status.axis_states[0], status.positions[0]) == (0b001, 30, 100)
    rig.finish()
    t_pulses, _ = rig.sim.trace.pulses("pokeys.x.step")
    t_state, state = rig.sim.trace.edges("pokeys.state")
    slot0 = int(t_pulses[0]) - 5_000  # the slot that took the first filled entry (when the fill came in)
    assert slot0 % SLOT_NS == 0 and t_pulses.size == 100
    assert t_pulses[-1] == slot0 + 9 * SLOT_NS + 5_000 + (9 * SLOT_NS) // 10  # pulse 100 ends slot 9
    assert t_state[state == 100][0] == slot0 + 10 * SLOT_NS  # seen at the next slot start: hard stop


@pytest.mark.parametrize("transport", ["udp", "tcp"])
def test_malformed_packets_get_no_reply_and_the_session_stays_in_step(transport: str) -> None:
    good = build_request(0x85, 0x00, 0x20, request_id=0x40)
    bad = [
        b"\xaa" + good[1:],  # wrong header
        good[:7] + bytes((good[7] ^ 0xFF,)) + good[8:],  # wrong checksum
        good[:64 if transport == "tcp" else 40],  # short datagram (a whole frame on TCP: a good one)
        build_request(0xB0, 0x08, 0xFF, 3, 3, request_id=1),  # a lone large-fill part
    ]
    with serving("57E") as (rig, port), client_for(port, transport) as client:
        client.timeout_s = SILENT_S
        replies = [client.send_raw(data) for data in bad]
        client.timeout_s = REPLY_S
        expected = [None, None, None if transport == "udp" else "reply", None]
        assert [None if r is None else "reply" for r in replies] == expected
        status = client.v2_status()  # raises unless the reply has the right ID and check byte
        assert status.activated == 1 and client.stale_replies == 0
    counts = rig.device.log.counts
    # a datagram with a wrong header or checksum is a bad frame; on a stream such bytes start no frame: skipped
    if transport == "udp":
        assert counts["bad_header"] == counts["bad_checksum"] == 1
    else:
        assert counts["resync"] == 2 and counts["bad_header"] == counts["bad_checksum"] == 0
    assert counts["bad_length" if transport == "udp" else "request"] >= 1


def test_a_tcp_stream_with_stray_bytes_is_answered_again_from_its_next_request() -> None:
    """3 stray bytes before a request: the device skips them and answers it (it used to fall silent)."""
    with serving("57E") as (rig, port), client_for(port, "tcp") as client:
        client.timeout_s = SILENT_S
        assert client.send_raw(b"\x01\xbb\x07") is None  # an 0xBB among them whose checksum is wrong
        client.timeout_s = REPLY_S
        status = client.v2_status()
        assert status.activated == 1 and client.stale_replies == 0
        assert client.v2_status().activated == 1  # and the stream stays in step
    assert rig.device.log.counts["resync"] >= 1


def test_large_fill_over_tcp_is_collected_from_its_8_frames() -> None:
    with serving("57E") as (_, port), client_for(port, "tcp") as client:
        client.v2_setup(3)
        client.v2_set_axis(0, AXIS)
        accepted, status = client.v2_fill_large([(1, 0, 0)] * 149)
        assert accepted == 128 and status.enabled_axes == 3
        assert client.v2_status().engine_state == 0


def test_a_non_loopback_address_is_refused_unless_asked_for() -> None:
    rig = VirtualPoKeys.create()
    for address in ("0.0.0.0", "192.0.2.7"):
        with pytest.raises(ConfigurationError, match=r"address = '.*' is not allowed .*allow_remote=True"):
            DeviceServer(rig.device, host=address)
    assert DeviceServer(rig.device, host="0.0.0.0", allow_remote=True).advertise_ip == "127.0.0.1"
    assert DeviceServer(rig.device, host="localhost").port == 20055
    with pytest.raises(ConfigurationError, match="port"):
        DeviceServer(rig.device, port=70000)


def test_udp_and_tcp_share_one_device_and_one_port() -> None:
    with serving("57E") as (_, port):
        with client_for(port, "udp") as udp, client_for(port, "tcp") as tcp:
            udp.v2_set_positions({0: 1234})
            assert tcp.v2_status().positions[0] == 1234
        probe = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        assert probe.connect_ex(("127.0.0.1", port)) == 0
        probe.close()
