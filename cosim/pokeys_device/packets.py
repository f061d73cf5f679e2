"""Framing and checksum of PoKeys network packets, as pure functions.

Every request is a 64-byte frame (the large fill 0xB0 is 8 frames in one 512-byte request);
every reply is one 64-byte frame::

    [0]      header: 0xBB request, 0xAA reply
    [1]      command (the reply echoes it)
    [2..5]   parameters 1-4 (command-specific)
    [6]      request ID (the reply echoes it; never checked for sequence)
    [7]      checksum = (sum of [0..6]) mod 256 - only the header is protected
    [8..63]  payload, zero-filled

Offsets are 0-based, as in the protocol notes (a vendor manual's "byte 9" is ``[8]``).
A request that cannot be framed raises a :class:`PacketError` subclass; the device answers such
a request with no reply at all and counts it under the error's ``reason``.

Examples
--------
>>> frame = build_request(0x00, request_id=0x01)
>>> frame[:8].hex(" ")
'bb 00 00 00 00 00 01 bc'
>>> reply = new_reply(frame)
>>> seal(reply)[:8].hex(" ")
'aa 00 00 00 00 00 01 ab'
"""

from __future__ import annotations

import struct
from collections.abc import Sequence
from dataclasses import dataclass

from cosim.errors import ConfigurationError, CosimError

PORT = 20055
"""UDP and TCP port of the device."""
FRAME_BYTES = 64
"""Size of every request frame and of every reply."""
HEADER_BYTES = 8
PAYLOAD_BYTES = FRAME_BYTES - HEADER_BYTES
REQUEST_HEADER = 0xBB
REPLY_HEADER = 0xAA
MULTIPART_COMMAND = 0xB0
"""Large buffer fill: 8 consecutive frames in one request."""
MULTIPART_PARTS = 8
MULTIPART_BYTES = MULTIPART_PARTS * FRAME_BYTES
MULTIPART_DATA_BYTES = MULTIPART_PARTS * PAYLOAD_BYTES
"""448 data bytes: the payloads of the 8 parts, concatenated."""
PART_INDEX_MASK = 0x07
PART_START = 0x08
PART_STOP = 0x10


class PacketError(CosimError):
    """A request the device cannot frame; it is answered with silence and counted.

    Parameters
    ----------
    reason : str
        Short counter key (``bad_length``, ``bad_header``, ``bad_checksum``, ``bad_multipart``).
    message : str
        What was wrong, for the log.
    """

    reason = "malformed"

    def __init__(self, message: str) -> None:
        super().__init__(message)


class BadLength(PacketError):
    """A request that is not 64 bytes long (512 for the large fill)."""

    reason = "bad_length"


class BadHeader(PacketError):
    """A frame whose ``[0]`` is not 0xBB (or not 0xAA for a reply)."""

    reason = "bad_header"


class BadChecksum(PacketError):
    """A frame whose ``[7]`` is not the sum of ``[0..6]`` mod 256."""

    reason = "bad_checksum"


class BadMultipart(PacketError):
    """A large-fill request whose parts are out of order or disagree."""

    reason = "bad_multipart"


def checksum(frame: bytes | bytearray) -> int:
    """Checksum of a frame header: ``(sum of [0..6]) mod 256``.

    >>> hex(checksum(bytes.fromhex("bb0000000000 01")))
    '0xbc'
    """
    return sum(frame[:7]) & 0xFF


def check_frame(frame: bytes | bytearray, *, header: int = REQUEST_HEADER) -> bytes:
    """Return ``frame`` as bytes if it is a well-formed 64-byte frame, else raise.

    Raises
    ------
    BadLength, BadHeader, BadChecksum
    """
    if len(frame) != FRAME_BYTES:
        raise BadLength(f"frame of {len(frame)} bytes (allowed: {FRAME_BYTES})")
    if frame[0] != header:
        raise BadHeader(f"header [0] = 0x{frame[0]:02X} (allowed: 0x{header:02X})")
    if frame[7] != checksum(frame):
        raise BadChecksum(f"checksum [7] = 0x{frame[7]:02X}, sum of [0..6] gives 0x{checksum(frame):02X}")
    return bytes(frame)


def build_request(command: int, p1: int = 0, p2: int = 0, p3: int = 0, p4: int = 0, *, request_id: int,
                  payload: bytes | bytearray = b"") -> bytes:
    """A 64-byte request frame (host side).

    Parameters
    ----------
    command : int
        ``[1]``.
    p1, p2, p3, p4 : int
        Parameters ``[2..5]`` (0..255).
    request_id : int
        ``[6]`` (0..255).
    payload : bytes
        ``[8..]``, at most 56 bytes, zero-filled.
    """
    if len(payload) > PAYLOAD_BYTES:
        raise BadLength(f"payload of {len(payload)} bytes (allowed: 0..{PAYLOAD_BYTES})")
    frame = bytearray(FRAME_BYTES)
    frame[0:7] = bytes((REQUEST_HEADER, command, p1, p2, p3, p4, request_id & 0xFF))
    frame[8:8 + len(payload)] = payload
    frame[7] = checksum(frame)
    return bytes(frame)


def new_reply(request: bytes | bytearray) -> bytearray:
    """A zeroed reply frame for ``request``: ``[0]`` = 0xAA, ``[1]`` and ``[6]`` echoed.

    Fill in the command's fields at their offsets, then :func:`seal` it.
    """
    reply = bytearray(FRAME_BYTES)
    reply[0] = REPLY_HEADER
    reply[1] = request[1]
    reply[6] = request[6]
    return reply


def seal(reply: bytearray) -> bytes:
    """Write the checksum into ``[7]`` and return the finished 64-byte reply."""
    reply[7] = checksum(reply)
    return bytes(reply)


def check_reply(frame: bytes | bytearray, request_id: int) -> bytes:
    """Accept a reply as the library does: 64 bytes, 0xAA, the request's ID, a right checksum.

    Raises
    ------
    BadLength, BadHeader, BadChecksum
        ``BadHeader`` also for a reply carrying another request ID (the library re-sends then).
    """
    reply = check_frame(frame, header=REPLY_HEADER)
    if reply[6] != request_id & 0xFF:
        raise BadHeader(f"reply ID [6] = 0x{reply[6]:02X} (expected: 0x{request_id & 0xFF:02X})")
    return reply


# -- the large fill (0xB0) -------------------------------------------------------------------------
@dataclass(frozen=True)
class LargeFill:
    """A reassembled 0xB0 request.

    Attributes
    ----------
    entry_format : int
        ``[3]`` of the parts: 0xFF 8-bit entries, 0xFE 16-bit entries.
    offered_slots : int
        ``[4]``: new slots offered.
    axes_per_slot : int
        ``[5]``: N, entries per slot.
    data : bytes
        The 448 data bytes (part 0 ``[8..63]`` + ... + part 7 ``[8..63]``).
    last_id : int
        Request ID of part 7: the reply carries it.
    """

    entry_format: int
    offered_slots: int
    axes_per_slot: int
    data: bytes
    last_id: int


def part_flags(index: int) -> int:
    """``[2]`` of part ``index``: the index, plus the start bit on part 0 and the stop bit on part 7."""
    return index | (PART_START if index == 0 else 0) | (PART_STOP if index == MULTIPART_PARTS - 1 else 0)


def parse_large_fill(request: bytes | bytearray) -> LargeFill:
    """Check and reassemble a 512-byte 0xB0 request (8 frames, each with its own ID and checksum).

    Raises
    ------
    BadLength, BadHeader, BadChecksum, BadMultipart
    """
    if len(request) != MULTIPART_BYTES:
        raise BadLength(f"large fill of {len(request)} bytes (allowed: {MULTIPART_BYTES})")
    parts = [check_frame(request[i * FRAME_BYTES:(i + 1) * FRAME_BYTES]) for i in range(MULTIPART_PARTS)]
    first = parts[0]
    for i, part in enumerate(parts):
        if part[1] != MULTIPART_COMMAND or part[2] != part_flags(i):
            raise BadMultipart(f"part {i}: [1..2] = {part[1]:02X} {part[2]:02X} "
                               f"(allowed: B0 {part_flags(i):02X})")
        if part[3:6] != first[3:6]:
            raise BadMultipart(f"part {i}: [3..5] = {part[3:6].hex(' ')} differ from part 0's {first[3:6].hex(' ')}")
    return LargeFill(first[3], first[4], first[5], b"".join(p[HEADER_BYTES:] for p in parts), parts[-1][6])


def build_large_fill(entry_format: int, offered_slots: int, axes_per_slot: int, data: bytes | bytearray, *,
                     first_id: int) -> bytes:
    """A 512-byte 0xB0 request (host side); part ``i`` carries ID ``first_id + i`` (mod 256)."""
    if len(data) > MULTIPART_DATA_BYTES:
        raise BadLength(f"large-fill data of {len(data)} bytes (allowed: 0..{MULTIPART_DATA_BYTES})")
    padded = bytes(data).ljust(MULTIPART_DATA_BYTES, b"\0")
    return b"".join(
        build_request(MULTIPART_COMMAND, part_flags(i), entry_format, offered_slots, axes_per_slot,
                      request_id=(first_id + i) & 0xFF, payload=padded[i * PAYLOAD_BYTES:(i + 1) * PAYLOAD_BYTES])
        for i in range(MULTIPART_PARTS))


class PartCollector:
    """Collects the 8 frames of a large fill arriving one by one on a TCP stream.

    :meth:`add` returns the whole 512-byte request after the part with the stop bit, None before;
    a part out of sequence drops what was collected and raises :class:`BadMultipart`.
    """

    def __init__(self) -> None:
        self._parts: list[bytes] = []

    @property
    def collecting(self) -> bool:
        """True between a start part and its stop part."""
        return bool(self._parts)

    def add(self, frame: bytes) -> bytes | None:
        """Add one checked 0xB0 frame."""
        index = len(self._parts)
        if frame[2] != part_flags(index):
            self._parts.clear()
            if frame[2] == part_flags(0):  # a new start: begin again from this part
                self._parts.append(frame)
                raise BadMultipart(f"part {index} missing: a new large fill started")
            raise BadMultipart(f"part with [2] = 0x{frame[2]:02X} out of sequence (expected 0x{part_flags(index):02X})")
        self._parts.append(frame)
        if len(self._parts) < MULTIPART_PARTS:
            return None
        request = b"".join(self._parts)
        self._parts.clear()
        return request


# -- field helpers (little-endian unless the name says otherwise) -----------------------------------
def get_i32(frame: bytes | bytearray, offset: int) -> int:
    """int32 LE at ``[offset..offset+3]``."""
    return int(struct.unpack_from("<i", frame, offset)[0])


def put_i32(frame: bytearray, offset: int, value: int) -> None:
    """Write an int32 LE; values outside int32 wrap as two's complement (as the device's counters do)."""
    struct.pack_into("<I", frame, offset, value & 0xFFFFFFFF)


def get_u32(frame: bytes | bytearray, offset: int) -> int:
    """uint32 LE."""
    return int(struct.unpack_from("<I", frame, offset)[0])


def get_u16(frame: bytes | bytearray, offset: int) -> int:
    """uint16 LE."""
    return int(struct.unpack_from("<H", frame, offset)[0])


def get_f32(frame: bytes | bytearray, offset: int) -> float:
    """float32 LE."""
    return float(struct.unpack_from("<f", frame, offset)[0])


def put_f32(frame: bytearray, offset: int, value: float) -> None:
    """Write a float32 LE."""
    struct.pack_into("<f", frame, offset, value)


def put_text(frame: bytearray, offset: int, text: str, size: int) -> None:
    """ASCII text, NUL-padded (or cut) to ``size`` bytes."""
    raw = text.encode("ascii", "replace")[:size]
    frame[offset:offset + size] = raw.ljust(size, b"\0")


def hexdump(frame: bytes | bytearray, *, skip_zero_rows: bool = True) -> str:
    """16-byte rows labelled with the offset of their first byte, as in the protocol notes' vectors."""
    rows = []
    for start in range(0, len(frame), 16):
        row = frame[start:start + 16]
        if skip_zero_rows and start and not any(row):
            continue
        rows.append(f"{start:02d}: " + " ".join(f"{b:02X}" for b in row))
    return "\n".join(rows)


def from_hexdump(text: str, *, size: int = FRAME_BYTES) -> bytes:
    """The bytes of a vector written as in the protocol notes (``'16: 37 0F ...'``); missing rows are zero."""
    frame = bytearray(size)
    for line in text.strip().splitlines():
        label, _, body = line.partition(":")
        if not body:
            label, body = "0", label
        data = bytes.fromhex(body)
        start = int(label)
        frame[start:start + len(data)] = data
    return bytes(frame)


def signed_entries(data: bytes | bytearray, slots: int, axes: int, *, width: int) -> list[tuple[int, ...]]:
    """Signed pulse counts of ``slots`` slot-major entries, MSB = negative direction.

    Parameters
    ----------
    data : bytes
        Entry bytes, slot ``s`` axis ``a`` at ``(s * axes + a) * width``.
    slots, axes : int
        How many slots, and N entries per slot.
    width : {1, 2}
        Bytes per entry: 8-bit (bits 0-6 count, bit 7 negative) or 16-bit LE (bits 0-14, bit 15).

    >>> signed_entries(bytes.fromhex("0a857f"), 1, 3, width=1)
    [(10, -5, 127)]
    """
    sign_bit = 0x80 if width == 1 else 0x8000
    out = []
    for s in range(slots):
        counts = []
        for a in range(axes):
            i = (s * axes + a) * width
            raw = data[i] if width == 1 else data[i] | data[i + 1] << 8
            count = raw & (sign_bit - 1)
            counts.append(-count if raw & sign_bit else count)
        out.append(tuple(counts))
    return out


def encode_entries(slots: Sequence[Sequence[int]], *, width: int) -> bytes:
    """Slot-major entry bytes from signed counts (host side); the inverse of :func:`signed_entries`."""
    sign_bit = 0x80 if width == 1 else 0x8000
    out = bytearray()
    for slot in slots:
        for count in slot:
            if abs(count) >= sign_bit:
                raise ConfigurationError.out_of_range(f"pulse count in a {8 * width}-bit entry", count,
                                                      f"-{sign_bit - 1}..{sign_bit - 1}")
            raw = abs(count) | (sign_bit if count < 0 else 0)
            out += raw.to_bytes(width, "little")
    return bytes(out)
