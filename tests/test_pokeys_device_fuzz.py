"""Fuzzing: 100,000 random and mutated packets never crash or hang the device; it answers correctly afterwards.

In-process, hypothesis draws 2,500 packets per device model (56E and 57E) from structured
strategies (random bytes, well-formed requests of every pulse-engine sub-command, large fills,
mutations of those); each drawn packet is followed by 19 byte-level mutants of it (flips,
interesting values, truncation, new payload, with or without a repaired checksum) made by a
``random.Random`` seeded from the hypothesis draw. 2 x 2,500 x 20 = 100,000 packets go to
:meth:`Device.handle` over the engine model, with a few slots run between batches. Every packet
must get exactly what the protocol notes prescribe, judged here from the notes' rules and not
from the device's code:

* a 64-byte frame with 0xBB, a right checksum and a command other than 0xB0: one 64-byte reply
  with 0xAA, the same command and ID, a right checksum;
* 512 bytes made of 8 well-formed, consecutive 0xB0 parts: one reply with 0xB0 and part 7's ID;
* anything else: no reply.

A smaller run sends packets through the real UDP socket of a running server, then checks that the
next reply it gets is the right answer to a status request (nothing stray, nothing late).
"""

from __future__ import annotations

import random
import socket

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cosim.controllers.pokeys import PulseEngine
from cosim.kernel import Simulation
from cosim.pokeys_device import Device, DeviceIdentity, PulseEngineAdapter
from cosim.pokeys_device.packets import build_large_fill, build_request
from cosim.pokeys_device.rig import VirtualPoKeys
from cosim.pokeys_device.server import BackgroundServer, DeviceServer

#: The pulse engine's time slot: "1 millisecond time slots" (PoKeys pulse engine documentation).
SLOT_NS = 1_000_000

MUTANTS = 19
#: A reply that has not come after this long is a hang, even on a machine loaded with other work [s].
HANG_S = 30.0
BATCHES_PER_MODEL = 2_500
SOCKET_PACKETS = 1_500

V1_SUBS = [0x00, 0x01, 0x02, 0x03, 0x05, 0x06, 0x10, 0x11, 0x12, 0x13, 0x14, 0x15, 0x20, 0x30, 0x35, 0x36, 0x37]
V2_SUBS = [0x00, 0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x08, 0x0A, 0x0B, 0x10, 0x11, 0x18, 0x19, 0x20, 0x21, 0x22,
           0x37, 0xF0, 0xFE, 0xFF]
COMMANDS = [0x00, 0x03, 0x04, 0x06, 0x8F, 0xE0, 0x30, 0x40, 0xC0, 0xCB, 0xCC, 0xCD, 0xDA, 0xDD]

small = st.integers(0, 255)
params = st.tuples(small, small, small, small)
payload = st.one_of(st.binary(max_size=56), st.binary(min_size=56, max_size=56).map(lambda b: b[:8] + bytes(48)))


def _request(command: int, p: tuple[int, int, int, int], request_id: int, data: bytes) -> bytes:
    return build_request(command, *p, request_id=request_id, payload=data)


engine_requests = st.one_of(
    st.builds(lambda sub, p, i, d: _request(0x80, (sub, *p[1:]), i, d), st.sampled_from(V1_SUBS), params, small,
              payload),
    st.builds(lambda sub, p, i, d: _request(0x85, (sub, *p[1:]), i, d), st.sampled_from(V2_SUBS), params, small,
              payload),
    st.builds(_request, st.sampled_from(COMMANDS) | small, params, small, payload),
)
large_fills = st.builds(
    lambda fmt, slots, axes, data, first: build_large_fill(fmt, slots, axes, data, first_id=first),
    st.sampled_from([0xFF, 0xFE]) | small, small, st.integers(0, 15) | small, st.binary(max_size=448), small)


def _mutate(packet: bytes, edits: list[tuple[int, int]], fix_checksum: bool, cut: int) -> bytes:
    data = bytearray(packet)
    for index, value in edits:
        data[index % len(data)] = value
    if fix_checksum:
        for start in range(0, len(data) - 7, 64):
            data[start + 7] = sum(data[start:start + 7]) & 0xFF
    return bytes(data[:cut] if cut else data)


mutated = st.builds(_mutate, engine_requests | large_fills, st.lists(st.tuples(st.integers(0, 511), small),
                                                                   max_size=4),
                    st.booleans(), st.sampled_from([0, 0, 0, 1, 8, 63, 65, 100, 511]))
packets = st.one_of(st.binary(max_size=600), engine_requests, large_fills, mutated)


INTERESTING = [0x00, 0x01, 0x7F, 0x80, 0x81, 0xAA, 0xB0, 0xBB, 0xFE, 0xFF]


def mutants(packet: bytes, seed: int, n: int) -> list[bytes]:
    """``n`` byte-level mutants of ``packet`` (deterministic for a seed)."""
    rng = random.Random(seed)
    out = []
    for _ in range(n):
        data = bytearray(packet or build_request(0x85, 0x00, request_id=rng.randrange(256)))
        op = rng.randrange(6)
        if op == 0:
            for _ in range(rng.randrange(1, 4)):
                data[rng.randrange(len(data))] ^= 1 << rng.randrange(8)
        elif op == 1:
            data[rng.randrange(min(len(data), 64))] = rng.choice(INTERESTING)
        elif op == 2:
            data = data[:rng.randrange(len(data) + 1)] + bytearray(rng.randbytes(rng.randrange(3)))
        elif op == 3 and len(data) >= 8:
            data[1] = rng.choice([0x80, 0x85, 0xB0, rng.randrange(256)])
            data[2] = rng.choice(V1_SUBS + V2_SUBS + [rng.randrange(256)])
        elif op == 4 and len(data) > 8:
            data[8:] = rng.randbytes(len(data) - 8)
        elif len(data) > 8:
            data[2:6] = rng.randbytes(4)
        if rng.random() < 0.7:
            for start in range(0, len(data) - 7, 64):
                data[start + 7] = sum(data[start:start + 7]) & 0xFF
        out.append(bytes(data))
    return out


def expected_reply(packet: bytes) -> tuple[int, int] | None:
    """``(command, ID)`` the reply must carry, from the protocol notes' framing rules; None: no reply."""

    def framed(frame: bytes) -> bool:
        return len(frame) == 64 and frame[0] == 0xBB and frame[7] == sum(frame[:7]) & 0xFF

    if len(packet) == 64 and framed(packet) and packet[1] != 0xB0:
        return packet[1], packet[6]
    if len(packet) == 512:
        parts = [packet[64 * i:64 * (i + 1)] for i in range(8)]
        flags = [0x08, 1, 2, 3, 4, 5, 6, 0x17]
        if all(framed(p) and p[1] == 0xB0 and p[2] == f and p[3:6] == parts[0][3:6]
               for p, f in zip(parts, flags, strict=True)):
            return 0xB0, parts[7][6]
    return None


def check_reply(packet: bytes, reply: bytes | None) -> None:
    expected = expected_reply(packet)
    if expected is None:
        assert reply is None, f"reply to a packet that must get none: {packet[:16].hex(' ')}"
        return
    assert reply is not None and len(reply) == 64, f"no 64-byte reply to {packet[:8].hex(' ')}"
    assert (reply[0], reply[1], reply[6], reply[7]) == (0xAA, expected[0], expected[1], sum(reply[:7]) & 0xFF)


def status_is_answered_correctly(device: Device, model: str) -> None:
    if model == "56E":
        reply = device.handle(build_request(0x80, 0x00, request_id=0x33))
        assert reply is not None and reply[:3] == b"\xaa\x80\x00" and reply[6] == 0x33
    else:
        reply = device.handle(build_request(0x85, 0x00, 0x41, request_id=0x34))
        assert reply is not None and reply[6] == 0x34 and reply[63] == 0x41 + 0x5A and reply[9] == 1


def fuzz_in_process(model: str) -> int:
    """Feed the batches to one device; return how many packets it handled."""
    sim = Simulation(seed=1)
    device = Device(DeviceIdentity.preset(model), PulseEngineAdapter(PulseEngine(sim)))
    handled = 0

    @settings(max_examples=BATCHES_PER_MODEL, deadline=None, database=None, derandomize=True,
              suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
    @given(packet=packets, seed=st.integers(0, 2**32 - 1), slots=st.integers(0, 3))
    def feed(packet: bytes, seed: int, slots: int) -> None:
        nonlocal handled
        for data in [packet, *mutants(packet, seed, MUTANTS)]:
            check_reply(data, device.handle(data))
            handled += 1
        if slots:
            sim.run(until=sim.now + slots * SLOT_NS)

    feed()
    assert device.log.counts["internal_error"] == 0, list(device.log.recent)[-5:]
    status_is_answered_correctly(device, model)
    return handled


def test_100k_random_and_mutated_packets_in_process() -> None:
    # how long it takes is measured in bench/bench_pokeys_device_fuzz.py (process CPU time), not asserted here
    assert fuzz_in_process("56E") + fuzz_in_process("57E") >= 100_000


def test_fuzzed_packets_through_the_udp_socket_then_a_correct_status() -> None:
    rig = VirtualPoKeys.create(DeviceIdentity.preset("57E"))
    with BackgroundServer(DeviceServer(rig.device, pacer=rig.pacer, port=0)) as running, \
            socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        address = ("127.0.0.1", running.server.udp_port)

        @settings(max_examples=SOCKET_PACKETS, deadline=None, database=None, derandomize=True,
                  suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
        @given(packet=packets.filter(lambda p: 0 < len(p) <= 512))
        def send(packet: bytes) -> None:
            sock.sendto(packet, address)
            if expected_reply(packet) is not None:
                sock.settimeout(HANG_S)
                reply, _ = sock.recvfrom(2048)
                check_reply(packet, reply)

        send()
        sock.sendto(build_request(0x85, 0x00, 0x21, request_id=0xEE), address)
        sock.settimeout(HANG_S)
        reply, _ = sock.recvfrom(2048)
        assert (reply[0], reply[1], reply[6], reply[63]) == (0xAA, 0x85, 0xEE, 0x21 + 0x5A)
    assert rig.device.log.counts["internal_error"] == 0
    assert rig.pacer.report().slots > 0
