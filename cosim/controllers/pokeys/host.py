"""The host application: keeps the slot buffer filled over a link with delays and stalls.

The host holds the whole job as slot entries (see :mod:`~cosim.controllers.pokeys.planner`) and a
read pointer. Every ``period_ns`` (cycle k at ``start_ns + k * period_ns``, priority HOST) it

1. waits out an injected stall if the cycle falls inside one (the host process is frozen: an OS
   hiccup, a busy GUI thread);
2. offers the next slots, at most ``max_slots_per_fill`` (18 fit one 64-byte packet) and only as
   many as keep its estimate of the queued slots at ``prefill_slots``;
3. waits one link delay, the device accepts as many as fit, one link delay back, and the host
   advances its read pointer **by the accepted count only**.

Before the job starts the host fills the buffer with up to ``prefill_slots`` slots, then switches
the engine to buffer mode (one more round trip). Its estimate of the queued slots is
``slots accepted - slots elapsed since buffer mode began``, from its own clock. The engine is told
that a job is running (:meth:`PulseEngine.mark_job`) from the start until the device accepts the
last slot, so an empty buffer in between is recorded as an underrun.
"""

from __future__ import annotations

from collections.abc import Generator, Sequence
from dataclasses import dataclass
from typing import Any

from cosim.controllers.pokeys.buffer import Entry, check_entry, signed_count
from cosim.controllers.pokeys.engine import PulseEngine
from cosim.controllers.pokeys.limits import (
    AXES,
    BUFFER_SLOTS,
    COUNT_MASK,
    FILL_SLOTS_PER_PACKET,
    MAX_PULSES_PER_SLOT,
    SLOT_NS,
    check_int_range,
    check_slot_count,
)
from cosim.controllers.pokeys.link import Link, LinkProfile
from cosim.controllers.pokeys.states import EngineState
from cosim.errors import ConfigurationError
from cosim.kernel import Simulation
from cosim.timebase import Priority


@dataclass(frozen=True)
class Stall:
    """The host does nothing in ``[t_start_ns, t_start_ns + duration_ns)``."""

    t_start_ns: int
    duration_ns: int

    def __post_init__(self) -> None:
        check_int_range(self.t_start_ns, "stall t_start_ns", 0, 2**62, "ns")
        check_int_range(self.duration_ns, "stall duration_ns", 1, 2**62, "ns")

    @property
    def t_end_ns(self) -> int:
        """First instant after the stall [ns]."""
        return self.t_start_ns + self.duration_ns


@dataclass(frozen=True)
class FillRecord:
    """One fill-buffer round trip as the host saw it."""

    t_send_ns: int
    t_device_ns: int
    t_reply_ns: int
    offered: int
    accepted: int


class HostApp:
    """A host application streaming a job into the engine's slot buffer.

    Parameters
    ----------
    sim : Simulation
    engine : PulseEngine
    entries : sequence
        The job: slot entries (3 bytes each, or 3 signed counts).
    link : {'usb', 'ethernet'} or LinkProfile
        Delay model of the link; delays come from ``sim.rng``.
    period_ns : int
        Host loop period [ns] (default 1 ms).
    prefill_slots : int
        Slots queued before buffer mode starts, and the level the host keeps (1..128).
    max_slots_per_fill : int
        Slots per fill command (1..128; 18 fit one packet).
    stalls : sequence of Stall
        Injected host stalls.
    start_ns : int
        When the host starts [ns].
    """

    def __init__(self, sim: Simulation, engine: PulseEngine, entries: Sequence[object], *,
                 link: str | LinkProfile = "usb", period_ns: int = 1_000_000, prefill_slots: int = BUFFER_SLOTS,
                 max_slots_per_fill: int = FILL_SLOTS_PER_PACKET, stalls: Sequence[Stall] = (),
                 start_ns: int = 0) -> None:
        self.sim = sim
        self.engine = engine
        self.entries: list[Entry] = [_checked(e, i) for i, e in enumerate(entries)]
        self.link = Link(sim, link)
        self.period_ns = check_int_range(period_ns, "period_ns", 1, 10**10, "ns")
        self.prefill_slots = check_int_range(prefill_slots, "prefill_slots", 1, BUFFER_SLOTS, "slots")
        self.max_slots_per_fill = check_int_range(max_slots_per_fill, "max_slots_per_fill", 1, BUFFER_SLOTS, "slots")
        self.stalls = sorted(stalls, key=lambda s: s.t_start_ns)
        for s in self.stalls:
            if not isinstance(s, Stall):
                raise ConfigurationError.out_of_range("stall", s, "Stall(t_start_ns, duration_ns)")
        self.start_ns = sim.timebase.check_ticks(start_ns, name="start_ns")
        self.read_pointer = 0
        self.fills: list[FillRecord] = []
        self.t_buffer_mode_ns: int | None = None
        self.t_last_accepted_ns: int | None = None
        sim.process(self.refill_buffer())

    @property
    def finished(self) -> bool:
        """Every slot of the job was accepted by the device."""
        return self.read_pointer >= len(self.entries)

    def stall_end(self, t: int) -> int | None:
        """End of the stall containing ``t`` [ns], or None."""
        for s in self.stalls:
            if s.t_start_ns <= t < s.t_end_ns:
                return s.t_end_ns
        return None

    def refill_buffer(self) -> Generator[Any, Any, None]:
        """SimPy process: prefill, start buffer mode, then refill every period until the job is sent."""
        sim = self.sim
        yield sim.at(self.start_ns, Priority.HOST)
        self.engine.mark_job(True)
        k = 0
        while not self.finished:
            end = self.stall_end(sim.now)
            if end is not None:
                yield sim.at(end, Priority.HOST)
            started = self.t_buffer_mode_ns is not None
            want = self.prefill_slots - self._estimated_level() if started else self.prefill_slots - self.read_pointer
            want = min(want, self.max_slots_per_fill, len(self.entries) - self.read_pointer)
            full = False
            if want > 0:
                full = (yield from self._fill(want)) < want
            if not started and (self.read_pointer >= self.prefill_slots or self.finished or full):
                yield from self._start_buffer_mode()
                continue
            k = max(k + 1, -(-(sim.now - self.start_ns) // self.period_ns))
            yield sim.at(self.start_ns + k * self.period_ns, Priority.HOST)

    def _estimated_level(self) -> int:
        assert self.t_buffer_mode_ns is not None
        elapsed = (self.sim.now - self.t_buffer_mode_ns) // SLOT_NS + 1
        return self.read_pointer - elapsed

    def _fill(self, want: int) -> Generator[Any, Any, int]:
        t_send = self.sim.now
        yield self.sim.after(self.link.delay(), Priority.HOST)
        t_device = self.sim.now
        offered = self.entries[self.read_pointer:self.read_pointer + want]
        reply = self.engine.fill_buffer(offered)
        if self.read_pointer + reply.accepted >= len(self.entries):
            self.engine.mark_job(False)  # the device holds the whole job now
        yield self.sim.after(self.link.delay(), Priority.HOST)
        self.read_pointer += reply.accepted
        if reply.accepted:
            self.t_last_accepted_ns = t_device
        self.fills.append(FillRecord(t_send, t_device, self.sim.now, len(offered), reply.accepted))
        return reply.accepted

    def _start_buffer_mode(self) -> Generator[Any, Any, None]:
        t_send = self.sim.now
        yield self.sim.after(self.link.delay(), Priority.HOST)
        self.engine.set_state(EngineState.BUFFER)
        self.t_buffer_mode_ns = t_send  # the host's own clock: when it sent the command
        yield self.sim.after(self.link.delay(), Priority.HOST)


def _checked(entry: object, index: int) -> Entry:
    raw = check_entry(entry, where=f"host job slot {index}")
    for a, byte in enumerate(raw):
        if byte & COUNT_MASK > MAX_PULSES_PER_SLOT:
            check_slot_count(signed_count(byte), where=f"host job slot {index} axis {AXES[a]}")
    return raw
