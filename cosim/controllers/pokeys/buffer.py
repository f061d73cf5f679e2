"""The 128-slot buffer of slot entries, and the axis-byte encoding.

One slot entry holds one byte per axis (x, y, z on pulse engine v1: 3 bytes; up to 8 axes on v2).
Bits 0..6 of a byte are the pulse count of that axis in the slot; the MSB (bit 7) is the direction
bit: set means the direction output is activated, which is the negative counting direction
(``0x85`` = 5 pulses towards negative). Whether a count is one the device can emit is the
device model's business (:mod:`.models`), checked by the engine when it takes a fill.

>>> encode_entry((10, -5, 127)).hex()
'0a857f'
>>> decode_entry(bytes.fromhex('0a857f'))
(10, -5, 127)
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterable, Sequence
from itertools import islice

from cosim.controllers.pokeys.limits import AXIS_NAMES, BUFFER_SLOTS, COUNT_MASK, DIRECTION_BIT, ENTRY_BYTES
from cosim.errors import ConfigurationError
from cosim.validate import integer

Entry = bytes
"""One slot: one byte per axis, x first."""


def encode_axis(count: int, *, negative: bool | None = None, where: str = "") -> int:
    """One axis byte from a signed pulse count.

    Parameters
    ----------
    count : int
        Signed pulses in the slot, -127..127 (7 bits and a direction bit).
    negative : bool, optional
        Direction bit for ``count == 0`` (keeps the direction output where it was); by default
        the sign of ``count``.
    where : str
        Location for the error message.
    """
    integer(count, "pulse count", low=-COUNT_MASK, high=COUNT_MASK,
            allowed=f"-{COUNT_MASK}..{COUNT_MASK} (7-bit count and a direction bit)", where=where)
    neg = count < 0 if count != 0 or negative is None else negative
    return abs(count) | (DIRECTION_BIT if neg else 0)


def decode_axis(byte: int) -> tuple[int, bool]:
    """``(count, direction_bit)`` of an axis byte: count 0..127, bit set = negative."""
    return byte & COUNT_MASK, bool(byte & DIRECTION_BIT)


def signed_count(byte: int) -> int:
    """Signed pulse count of an axis byte (``0x85`` -> -5)."""
    return -(byte & COUNT_MASK) if byte & DIRECTION_BIT else byte & COUNT_MASK


def encode_entry(counts: Sequence[int], *, negative: Sequence[bool] | None = None, where: str = "") -> Entry:
    """A slot entry from signed counts ``(x, y, z, ...)`` (``negative``: direction bits for zeros)."""
    if not 1 <= len(counts) <= len(AXIS_NAMES):
        raise ConfigurationError.out_of_range("axes in a slot entry", len(counts), f"1..{len(AXIS_NAMES)}",
                                              where=where)
    dirs = negative if negative is not None else (None,) * len(counts)
    return bytes(encode_axis(c, negative=d, where=f"{where}{' ' if where else ''}axis {AXIS_NAMES[i]}")
                 for i, (c, d) in enumerate(zip(counts, dirs, strict=True)))


def decode_entry(entry: Entry) -> tuple[int, ...]:
    """Signed counts ``(x, y, z, ...)`` of a slot entry."""
    return tuple(signed_count(b) for b in entry)


def check_entry(entry: object, *, axes: int = ENTRY_BYTES, where: str = "") -> Entry:
    """Accept an entry of ``axes`` bytes (bytes-like) or a sequence of ``axes`` signed counts; return the bytes."""
    if isinstance(entry, bytes | bytearray | memoryview):
        raw = bytes(entry)
        if len(raw) != axes:
            raise ConfigurationError.out_of_range("slot entry length", len(raw), f"{axes} bytes", where=where)
        return raw
    if isinstance(entry, Sequence):
        if len(entry) != axes:
            raise ConfigurationError.out_of_range("axes in a slot entry", len(entry), str(axes), where=where)
        return encode_entry(list(entry), where=where)
    raise ConfigurationError.out_of_range("slot entry", entry, f"{axes} bytes or {axes} signed counts", where=where)


def split_packet(data: bytes, n_slots: int, *, axes: int = ENTRY_BYTES) -> list[Entry]:
    """The first ``n_slots`` entries of fill-buffer payload bytes (slot-major, ``axes`` bytes per slot)."""
    integer(n_slots, "number of slots", low=0, high=len(data) // axes)
    return [data[i * axes:(i + 1) * axes] for i in range(n_slots)]


class SlotBuffer:
    """A FIFO of slot entries with a fixed depth.

    Parameters
    ----------
    depth_slots : int
        Capacity (128 on the device).

    Examples
    --------
    >>> buf = SlotBuffer(4)
    >>> buf.fill([b'\\x01\\x00\\x00'] * 6)   # as many as fit are accepted
    4
    >>> buf.level, buf.free
    (4, 0)
    """

    def __init__(self, depth_slots: int = BUFFER_SLOTS) -> None:
        self.depth_slots = integer(depth_slots, "buffer depth", low=1, high=65535, unit="slots")
        self._slots: deque[Entry] = deque()
        self.taken = 0
        """Entries taken from the buffer so far (the host's job follows its slots by this count)."""

    @property
    def level(self) -> int:
        """Queued slots."""
        return len(self._slots)

    @property
    def free(self) -> int:
        """Free slots (what the free-space query returns)."""
        return self.depth_slots - len(self._slots)

    def fill(self, entries: Iterable[Entry]) -> int:
        """Append as many entries as fit, in order; return how many were accepted."""
        accepted = 0
        room = self.free
        for entry in entries:
            if accepted == room:
                break
            self._slots.append(entry)
            accepted += 1
        return accepted

    def pop(self) -> Entry | None:
        """The oldest entry, or None if the buffer is empty."""
        if not self._slots:
            return None
        self.taken += 1
        return self._slots.popleft()

    def clear(self) -> int:
        """Drop every queued entry (clear-buffer command); return how many were dropped."""
        dropped = len(self._slots)
        self._slots.clear()
        return dropped

    def peek_all(self) -> list[Entry]:
        """A copy of the queued entries, oldest first."""
        return list(self._slots)

    def peek(self, count: int) -> list[Entry]:
        """The oldest ``count`` queued entries (fewer if fewer are queued), oldest first."""
        return list(islice(self._slots, count))

    def drop(self, count: int) -> None:
        """Take the oldest ``count`` entries (as ``count`` calls of :meth:`pop`; they must be queued)."""
        if count > len(self._slots):
            raise ConfigurationError.out_of_range("entries to take", count, f"0..{len(self._slots)} (queued)")
        popleft = self._slots.popleft
        for _ in range(count):
            popleft()
        self.taken += count
