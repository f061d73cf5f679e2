"""A PoKeys network client written from the protocol notes (not vendor code): for tests, examples, the bench.

Why here and not in ``tests/``: ``bench/bench_pokeys_device.py`` (a host program beside a running
server) uses it as much as the tests do, and it is the example host a user can start from; nothing
in the device package needs it.

It behaves like the library where that matters for a device: 64-byte requests with an 8-bit
request ID incremented before every send (also re-sends and each part of a large fill), a reply
accepted only with header 0xAA, the request's ID and a right checksum, re-sends with a new ID when
nothing came. Unlike the library it counts what it discarded (:attr:`PoKeysClient.stale_replies`,
:attr:`PoKeysClient.bad_replies`), so a test can assert that every request got exactly one reply.

>>> # with a device running on 127.0.0.1:20055
>>> # client = PoKeysClient(transport="udp"); client.identify().type_name   -> 'PoKeys57E'
"""

from __future__ import annotations

import socket
import time
from collections.abc import Sequence
from typing import TYPE_CHECKING

from cosim.errors import ConfigurationError, CosimError
from cosim.pokeys_device.identity import DeviceData, Discovered, decode_device_data, decode_discovery
from cosim.pokeys_device.layouts import (
    PARAMS_V1_SLICE,
    RECORD_SLICE,
    AxisRecord,
    ParamsV1,
    StatusV1,
    StatusV2,
    get_status_v1,
    get_status_v2,
    status_check,
)
from cosim.pokeys_device.packets import (
    FRAME_BYTES,
    PAYLOAD_BYTES,
    PORT,
    PacketError,
    build_large_fill,
    build_request,
    check_reply,
    encode_entries,
    put_i32,
)

if TYPE_CHECKING:
    from cosim.pokeys_device.device import Device


class NoReply(CosimError):
    """The device did not answer a request (after every re-send)."""


class ClientBase:
    """Requests, replies and the typed commands; subclasses move the bytes.

    Parameters
    ----------
    timeout_s : float
        Wait for one reply [s] before re-sending.
    sends : int
        Sends per request (the first and the re-sends).
    first_id : int
        Request ID before the first send (the ID is incremented before every send).
    """

    def __init__(self, *, timeout_s: float = 0.5, sends: int = 3, first_id: int = 0) -> None:
        self.timeout_s = timeout_s
        self.sends = sends
        self.request_id = first_id & 0xFF
        self.stale_replies = 0
        self.bad_replies = 0
        self.resends = 0

    def _send(self, data: bytes) -> None:
        raise NotImplementedError

    def _receive(self, deadline: float) -> bytes | None:
        raise NotImplementedError

    # -- one request, one reply -----------------------------------------------------------------
    def next_id(self) -> int:
        """Increment the request ID (wrapping 255 -> 0) and return it."""
        self.request_id = (self.request_id + 1) & 0xFF
        return self.request_id

    def request(self, command: int, p1: int = 0, p2: int = 0, p3: int = 0, p4: int = 0, *,
                payload: bytes | bytearray = b"") -> bytes:
        """Send a request and return its checked 64-byte reply (re-sending with a new ID if none came)."""
        for attempt in range(self.sends):
            if attempt:
                self.resends += 1
            request_id = self.next_id()
            self._send(build_request(command, p1, p2, p3, p4, request_id=request_id, payload=payload))
            reply = self._wait(request_id)
            if reply is not None:
                return reply
        raise NoReply(f"no reply to command 0x{command:02X} after {self.sends} sends")

    def send_raw(self, data: bytes) -> bytes | None:
        """Send bytes as they are and return the next reply frame, if one comes within the timeout."""
        self._send(data)
        return self._receive(time.monotonic() + self.timeout_s)

    def _wait(self, request_id: int) -> bytes | None:
        deadline = time.monotonic() + self.timeout_s
        while True:
            frame = self._receive(deadline)
            if frame is None:
                return None
            try:
                return check_reply(frame, request_id)
            except PacketError:
                if len(frame) == FRAME_BYTES and frame[0] == 0xAA and frame[6] != request_id:
                    self.stale_replies += 1
                else:
                    self.bad_replies += 1

    # -- identification ---------------------------------------------------------------------------
    def identify(self) -> DeviceData:
        """The connect handshake: 0x00, 0x03, 0xE0, (0x06, 0x04 x3 for a classic device), 0x8F.

        For a PoKeys56E with pulse engine v1 it ends with 0x80/0x30 (engine info), as the
        PEv1-era library does.
        """
        data = self.request(0x00)
        self.request(0x03)
        self.request(0xE0)
        extended = bytes(data[8:12]) in (b"PKEx", b"PK58")
        self.request(0x06)
        if not extended:
            for part in range(3):
                self.request(0x04, part)
        options = self.request(0x8F)[8]
        info = decode_device_data(data, options=options)
        if info.pe_v1:
            self.pe_info()
        return info

    # -- pulse engine v1 (0x80) --------------------------------------------------------------------
    def pe_info(self) -> bytes:
        """0x80/0x30: ``[8..11]`` axes, kHz, buffer slots, slot time."""
        return self.request(0x80, 0x30)[8:12]

    def pe_status(self) -> StatusV1:
        """0x80/0x00."""
        return get_status_v1(self.request(0x80, 0x00))

    def pe_enable(self, enabled: bool = True, *, charge_pump: bool = False) -> None:
        """0x80/0x06."""
        self.request(0x80, 0x06, int(enabled), int(charge_pump))

    def pe_set_state(self, state: int) -> None:
        """0x80/0x02 with ``[8]`` = state (0 stopped, 1 internal, 2 buffer)."""
        self.request(0x80, 0x02, payload=bytes((state,)))

    def pe_set_positions(self, positions: Sequence[int]) -> None:
        """0x80/0x01: x, y, z."""
        self.request(0x80, 0x01, payload=_i32s(positions))

    def pe_move(self, references: Sequence[int], *, speed_mode: bool = False) -> None:
        """0x80/0x05: references of the internal controller (positions, or speeds with ``speed_mode``)."""
        self.request(0x80, 0x05, 10 if speed_mode else 0, payload=_i32s(references))

    def pe_get_params(self) -> ParamsV1:
        """0x80/0x10."""
        return ParamsV1.from_bytes(self.request(0x80, 0x10)[PARAMS_V1_SLICE])

    def pe_set_params(self, params: ParamsV1) -> None:
        """0x80/0x11."""
        self.request(0x80, 0x11, payload=params.to_bytes())

    def pe_get_switches(self) -> bytes:
        """0x80/0x12: limit+, limit-, home enables, direction and homing-direction inversion (bit per axis)."""
        return self.request(0x80, 0x12)[8:13]

    def pe_set_switches(self, limit_pos: int = 0, limit_neg: int = 0, home: int = 0, invert: int = 0,
                        invert_homing: int = 0) -> None:
        """0x80/0x13 (bitmaps: bit 0 = x)."""
        self.request(0x80, 0x13, payload=bytes((limit_pos, limit_neg, home, invert, invert_homing)))

    def pe_homing(self, axes: Sequence[int]) -> None:
        """0x80/0x20: home the given axes."""
        self.request(0x80, 0x20, payload=bytes(int(a in axes) for a in range(3)))

    def pe_fill(self, slots: Sequence[Sequence[int]]) -> tuple[int, StatusV1]:
        """0x80/0x35: offer up to 18 slots of (x, y, z) signed counts; returns (accepted, status)."""
        offered = list(slots[:18])
        reply = self.request(0x80, 0x35, len(offered), payload=encode_entries(offered, width=1))
        return reply[8], get_status_v1(reply, offset=9, with_enable=False)

    def pe_clear(self) -> None:
        """0x80/0x36."""
        self.request(0x80, 0x36)

    def pe_free(self) -> int:
        """0x80/0x37: free slots."""
        return self.request(0x80, 0x37)[8]

    # -- pulse engine v2 (0x85) ------------------------------------------------------------------------
    def v2_status(self) -> StatusV2:
        """0x85/0x00 with the library's check byte; raises if ``[63]`` does not match it."""
        check = (0x10 + self.request_id) % 199
        reply = self.request(0x85, 0x00, check)
        if reply[63] != status_check(check):
            raise NoReply(f"status check byte [63] = 0x{reply[63]:02X}, expected 0x{status_check(check):02X}")
        return get_status_v2(reply)

    def v2_setup(self, enabled_axes: int, *, charge_pump: int = 0, generator: int = 1, buffer_slots: int = 0,
                 emergency_inverted: int = 0, power_mask: int = 0) -> int:
        """0x85/0x01; returns the result byte ``[3]`` (0 = OK)."""
        payload = bytes((enabled_axes, charge_pump, generator, buffer_slots, emergency_inverted, power_mask))
        return self.request(0x85, 0x01, payload=payload)[3]

    def v2_set_state(self, state: int, *, limit_override: int = 0, output_mask: int = 0) -> None:
        """0x85/0x02 (0 stopped, 3 running)."""
        self.request(0x85, 0x02, state, limit_override, output_mask)

    def v2_set_positions(self, positions: dict[int, int]) -> None:
        """0x85/0x03 for the given axes."""
        values = [positions.get(a, 0) for a in range(8)]
        self.request(0x85, 0x03, sum(1 << a for a in positions), payload=_i32s(values))

    def v2_get_axis(self, axis: int) -> AxisRecord:
        """0x85/0x10."""
        return AxisRecord.from_bytes(self.request(0x85, 0x10, axis)[RECORD_SLICE])

    def v2_set_axis(self, axis: int, record: AxisRecord) -> None:
        """0x85/0x11."""
        self.request(0x85, 0x11, axis, payload=record.to_bytes())

    def v2_move(self, references: Sequence[int]) -> None:
        """0x85/0x20: up to 8 references (positions, or speeds in pulses/s)."""
        self.request(0x85, 0x20, payload=_i32s(list(references) + [0] * (8 - len(references))))

    def v2_homing(self, axes: Sequence[int]) -> None:
        """0x85/0x21 with zero offsets."""
        self.request(0x85, 0x21, sum(1 << a for a in axes))

    def v2_finish_homing(self, state: int = 0, *, skip_state_change: bool = True) -> None:
        """0x85/0x22."""
        self.request(0x85, 0x22, state, int(skip_state_change))

    def v2_clear(self) -> None:
        """0x85/0xF0."""
        self.request(0x85, 0xF0)

    def v2_fill(self, slots: Sequence[Sequence[int]], *, width: int = 1) -> tuple[int, StatusV2]:
        """0x85/0xFF (8-bit) or 0xFE (16-bit): offers as many slots as fit; returns (accepted, status)."""
        axes = len(slots[0]) if slots else 3
        offered = list(slots[:PAYLOAD_BYTES // (axes * width)])
        reply = self.request(0x85, 0xFF if width == 1 else 0xFE, len(offered), axes,
                             payload=encode_entries(offered, width=width))
        return reply[2], get_status_v2(reply)

    def v2_fill_large(self, slots: Sequence[Sequence[int]], *, width: int = 1) -> tuple[int, StatusV2]:
        """0xB0: one 512-byte request of 8 parts; returns (accepted, status)."""
        axes = len(slots[0]) if slots else 3
        offered = list(slots[:448 // (axes * width)])
        first = self.next_id()
        self.request_id = (first + 7) & 0xFF
        data = build_large_fill(0xFF if width == 1 else 0xFE, len(offered), axes,
                                encode_entries(offered, width=width), first_id=first)
        self._send(data)
        reply = self._wait(self.request_id)
        if reply is None:
            raise NoReply("no reply to a large fill (0xB0)")
        return reply[2], get_status_v2(reply)



class PoKeysClient(ClientBase):
    """Talks to a PoKeys (or the virtual one) over UDP or TCP.

    Parameters
    ----------
    host : str
    port : int
    transport : {'udp', 'tcp'}
    timeout_s, sends, first_id
        See :class:`ClientBase`.
    """

    def __init__(self, host: str = "127.0.0.1", port: int = PORT, *, transport: str = "udp", timeout_s: float = 0.5,
                 sends: int = 3, first_id: int = 0) -> None:
        if transport not in ("udp", "tcp"):
            raise ConfigurationError.out_of_range("transport", transport, "udp, tcp")
        super().__init__(timeout_s=timeout_s, sends=sends, first_id=first_id)
        self.address = (host, port)
        self.transport = transport
        if transport == "udp":
            self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        else:
            self.sock = socket.create_connection(self.address, timeout=timeout_s)
            self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._stream = bytearray()

    def close(self) -> None:
        """Close the socket."""
        self.sock.close()

    def __enter__(self) -> PoKeysClient:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _send(self, data: bytes) -> None:
        if self.transport == "udp":
            self.sock.sendto(data, self.address)
        else:
            self.sock.sendall(data)

    def _receive(self, deadline: float) -> bytes | None:
        while True:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                return None
            self.sock.settimeout(remaining)
            try:
                if self.transport == "udp":
                    data, _ = self.sock.recvfrom(2048)
                    return data
                while len(self._stream) < FRAME_BYTES:
                    chunk = self.sock.recv(FRAME_BYTES - len(self._stream))
                    if not chunk:
                        raise NoReply("the device closed the TCP connection")
                    self._stream += chunk
                frame = bytes(self._stream[:FRAME_BYTES])
                del self._stream[:FRAME_BYTES]
                return frame
            except TimeoutError:
                return None


class DirectClient(ClientBase):
    """The same commands against a :class:`~cosim.pokeys_device.device.Device` in-process (no sockets).

    Time moves only when the caller runs the simulation, so tests can assert exact instants.
    """

    def __init__(self, device: Device, *, first_id: int = 0) -> None:
        super().__init__(timeout_s=0.0, sends=1, first_id=first_id)
        self.device = device
        self._replies: list[bytes] = []

    def _send(self, data: bytes) -> None:
        reply = self.device.handle(data)
        if reply is not None:
            self._replies.append(reply)

    def _receive(self, deadline: float) -> bytes | None:
        return self._replies.pop(0) if self._replies else None


def discover(port: int = PORT, *, address: str = "127.0.0.1", timeout_s: float = 0.3,
             serial: int = 0) -> list[Discovered]:
    """Send an empty datagram and collect up to 16 discovery replies (stops at ``serial`` if found)."""
    found: list[Discovered] = []
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_BROADCAST, 1)
        sock.sendto(b"", (address, port))
        deadline = time.monotonic() + timeout_s
        while len(found) < 16:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                break
            sock.settimeout(remaining)
            try:
                data, _ = sock.recvfrom(2048)
            except TimeoutError:
                break
            device = decode_discovery(data)
            if device is not None:
                found.append(device)
                if serial and device.serial == serial:
                    break
    return found


def _i32s(values: Sequence[int]) -> bytes:
    out = bytearray(4 * len(values))
    for i, value in enumerate(values):
        put_i32(out, 4 * i, value)
    return bytes(out)
