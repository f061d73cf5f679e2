"""What the command handlers share: the packet log, the axis-state convention, wire-value checks.

The packet log counts every request by outcome (``request``, ``discovery``, ``bad_length``,
``bad_header``, ``bad_checksum``, ``bad_multipart``, ``unknown_command``, ``unknown_subcommand``,
``rejected`` - a command the engine refused -, ``ignored_value`` - a field out of range that was
not applied -, ``internal_error``, ``resync`` - stray TCP bytes skipped -, ``socket_error``) and
keeps the most recent messages. Nothing in it raises: a
simulated device answers or stays silent, it never stops.
"""

from __future__ import annotations

import logging
import math
from collections import Counter, deque
from collections.abc import Iterator
from contextlib import contextmanager
from fractions import Fraction

from cosim.controllers.pokeys import MAX_RATE_HZ
from cosim.errors import ConfigurationError

log = logging.getLogger("cosim.pokeys_device")

MAX_ACCEL = 10**12
"""Largest acceleration applied [pulses/s^2]; larger wire values are clamped to it."""


class PacketLog:
    """Counters of requests by outcome, and the last ``keep`` messages.

    Parameters
    ----------
    keep : int
        Messages kept in :attr:`recent`.
    """

    def __init__(self, *, keep: int = 200) -> None:
        self.counts: Counter[str] = Counter()
        self.recent: deque[str] = deque(maxlen=keep)

    def count(self, kind: str, message: str = "") -> None:
        """Count one event of ``kind``; keep and log ``message`` if given."""
        self.counts[kind] += 1
        if message:
            self.recent.append(f"{kind}: {message}")
            log.debug("%s: %s", kind, message)

    @contextmanager
    def rejecting(self, what: str) -> Iterator[None]:
        """Run an engine command; a ConfigurationError is counted as ``rejected``, not raised."""
        try:
            yield
        except ConfigurationError as exc:
            self.count("rejected", f"{what}: {exc}")

    @property
    def malformed(self) -> int:
        """Requests answered with silence because they could not be framed."""
        return sum(n for kind, n in self.counts.items() if kind.startswith("bad_"))

    def summary(self) -> str:
        """One line: every counter."""
        return ", ".join(f"{kind} {n}" for kind, n in sorted(self.counts.items())) or "no packets"


def reported_axis_state(engine_axis_state: int, *, enabled: bool, queued: bool) -> int:
    """Axis state for a status reply (the protocol notes' convention, 4.6 and 5.7).

    Homing, homed, error and limit states (10 and up) come from the engine; otherwise
    0 while the axis (or the engine) is disabled, 2 while slots are queued or a move is in
    progress, else 1.
    """
    if engine_axis_state >= 10:
        return engine_axis_state
    if not enabled:
        return 0
    return 2 if queued else 1


def speed_hz(per_ms: float, old: int | Fraction | float, *, what: str, notes: PacketLog,
             high: int = MAX_RATE_HZ) -> int | Fraction | float:
    """A maximum speed from the wire (float32 pulses/ms) as whole pulses/s, 1..``high`` (the model's, 25000).

    Not finite or not positive: keep ``old`` (counted as ``ignored_value``); above ``high``: ``high``.
    """
    if not math.isfinite(per_ms) or per_ms <= 0:
        notes.count("ignored_value", f"{what} = {per_ms!r} pulses/ms (allowed: > 0); kept {old} pulses/s")
        return old
    hz = round(per_ms * 1000)
    if not 1 <= hz <= high:
        notes.count("ignored_value", f"{what} = {per_ms!r} pulses/ms is outside 0.001..{high // 1000}; clamped")
    return max(1, min(high, hz))


def accel_hz2(per_ms2: float, old: int | Fraction | float, *, what: str,
              notes: PacketLog) -> int | Fraction | float:
    """An acceleration from the wire (float32 pulses/ms^2) as whole pulses/s^2 (> 0)."""
    if not math.isfinite(per_ms2) or per_ms2 <= 0:
        notes.count("ignored_value", f"{what} = {per_ms2!r} pulses/ms^2 (allowed: > 0); kept {old} pulses/s^2")
        return old
    return max(1, min(MAX_ACCEL, round(per_ms2 * 1_000_000)))


def percent(value: int, old: int, *, what: str, notes: PacketLog) -> int:
    """A speed percentage 1..100 from the wire (0 or more than 100: keep ``old``)."""
    if 1 <= value <= 100:
        return value
    notes.count("ignored_value", f"{what} = {value} % (allowed: 1..100); kept {old} %")
    return old


def bits(mask: int, count: int) -> list[int]:
    """Indices of the set bits of ``mask`` below ``count``."""
    return [i for i in range(count) if mask >> i & 1]
