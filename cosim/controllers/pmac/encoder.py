"""Encoder channels: 1/T sub-count extension and the position-capture register.

The master encoder reaches the controller as an :class:`EncoderSource`: anything whose
``sample(t_ns)`` returns the count and the timestamps of the last two count edges
(:class:`EncoderSample`). The conveyor FMU (through a small adapter), :class:`SignalEncoder`
(a count :class:`~cosim.signals.Signal`) or the analytic stand-in of
:mod:`cosim.controllers.pmac.testbench` can stand behind it.

1/T extension
-------------
Between edges the position is extrapolated from the time since the last edge divided by the
time between the last two edges, truncated to ``2^-bits`` count (5 bits = 1/32 count for the
standard 1/T entry, 8 bits = 1/256 for the Turbo triggered time-base entry). The fraction is
clamped below one count, so the estimate never passes the next edge. It is measured from the
boundary the last edge crossed: ``count`` for an upward edge, ``count + 1`` for a downward one.

Capture
-------
A channel's capture register latches the position when its trigger input is at the active
level while the capture flag is clear; the flag then stays set and later triggers are ignored
until the capture register is *read*. Reading re-arms the hardware, and because the capture is
level-triggered, a trigger input that is still active at the read latches again at once. The
latched value is the 1/T-extended position at the trigger instant, to 1/256 count (the model's
reading of the Turbo triggered entry's 1/256-count time zero).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

from cosim import validate
from cosim.controllers.pmac.units import REG_MASK
from cosim.errors import ConfigurationError
from cosim.signals import Signal

if TYPE_CHECKING:
    from cosim.kernel import Simulation

#: Fraction bits of the standard 1/T extension (1/32 count).
ONE_OVER_T_BITS = 5
#: Fraction bits of the Turbo triggered time-base entry and of the capture (1/256 count).
TRIGGERED_BITS = 8
#: Offset of the capture register from a channel's address (X:$07800B for $078008).
CAPTURE_OFFSET = 3


@dataclass(frozen=True)
class EncoderSample:
    """What the 1/T hardware knows about an encoder at one instant.

    Parameters
    ----------
    count : int
        Quadrature count [counts].
    last_edge_t_ns, prev_edge_t_ns : int or None
        Instants of the last and the previous count edge [ns] (None before there were any).
    direction : int
        +1 if the last edge counted up, -1 if down.
    """

    count: int
    last_edge_t_ns: int | None = None
    prev_edge_t_ns: int | None = None
    direction: int = 1


class EncoderSource(Protocol):
    """Anything that reports an encoder's count and edge timestamps at an instant."""

    def sample(self, t_ns: int) -> EncoderSample:
        """The encoder state at ``t_ns`` (never earlier than a previous call)."""
        ...


def extend_one_over_t(sample: EncoderSample, t_ns: int, fraction_bits: int) -> int:
    """1/T-extended position at ``t_ns`` in units of ``2^-fraction_bits`` count (truncated).

    Examples
    --------
    >>> s = EncoderSample(count=10, last_edge_t_ns=15_625, prev_edge_t_ns=0)
    >>> extend_one_over_t(s, 15_625 + 7_812, 5)  # half a count after the edge, in 1/32 count
    335
    """
    scale = 1 << fraction_bits
    last, prev = sample.last_edge_t_ns, sample.prev_edge_t_ns
    if last is None:
        return sample.count * scale
    boundary = sample.count if sample.direction >= 0 else sample.count + 1
    if prev is None or last <= prev or t_ns <= last:
        return boundary * scale
    frac = min(scale - 1, ((t_ns - last) * scale) // (last - prev))
    return boundary * scale + frac if sample.direction >= 0 else boundary * scale - frac


class SignalEncoder:
    """An :class:`EncoderSource` from a count signal: its change instants are the edge times.

    Parameters
    ----------
    count : Signal
        Integer signal holding the quadrature count; the plant sets it at each edge.
    """

    def __init__(self, count: Signal) -> None:
        if count.kind != "int":
            raise ConfigurationError.out_of_range(f"kind of encoder count signal {count.name}", count.kind, "int")
        self._count = count
        self._last: int | None = None
        self._prev: int | None = None
        self._direction = 1
        self._value = int(count.value)
        count.subscribe(self._on_edge)

    def _on_edge(self, signal: Signal) -> None:
        new = int(signal.value)
        self._direction = 1 if new > self._value else -1
        self._value = new
        self._prev, self._last = self._last, signal.sim.now

    def sample(self, t_ns: int) -> EncoderSample:
        """The count and the instants of its last two changes."""
        return EncoderSample(self._value, self._last, self._prev, self._direction)


class EncoderChannel:
    """A servo-IC encoder channel: position with 1/T extension and a capture register.

    Parameters
    ----------
    sim : Simulation
    address : int
        Channel base address as written in conversion-table entries (e.g. ``0x078008``);
        the capture register is at ``address + 3``.
    encoder : EncoderSource
        The master (or motor) encoder.
    trigger : Signal, optional
        Capture trigger input (bit), e.g. the registration-mark sensor (the flag selected by
        I7mn3 on the real card).
    trigger_level : int
        Active level of the trigger (1 = high, like the default I7mn2 polarity).
    name : str
        Signal name part: the capture flag is recorded as ``pmac.<name>.capture_flag``.
    """

    def __init__(self, sim: Simulation, address: int, encoder: EncoderSource, *, trigger: Signal | None = None,
                 trigger_level: int = 1, name: str | None = None, device: str = "pmac") -> None:
        trigger_level = int(validate.flag(trigger_level, "trigger_level", allowed="0 or 1"))
        self.sim = sim
        self.address = address
        self.encoder = encoder
        self.trigger = trigger
        self.trigger_level = trigger_level
        self.name = name or f"ch{address:x}"
        self.capture_flag = False
        self.captured_pos256: int | None = None
        self.capture_t_ns: int | None = None
        self.captures: list[tuple[int, int]] = []
        self._flag = Signal(sim, f"{device}.{self.name}.capture_flag", kind="bit",
                            description=f"capture flag of encoder channel ${address:06X}")
        if trigger is not None:
            trigger.subscribe(self._on_trigger)
            if trigger.value == trigger_level:
                self._latch()

    def position(self, t_ns: int, fraction_bits: int) -> int:
        """1/T-extended position at ``t_ns`` [2^-fraction_bits count], unwrapped."""
        return extend_one_over_t(self.encoder.sample(t_ns), t_ns, fraction_bits)

    def count(self, t_ns: int) -> int:
        """Whole-count position at ``t_ns`` [counts]."""
        return self.encoder.sample(t_ns).count

    def _on_trigger(self, signal: Signal) -> None:
        if signal.value == self.trigger_level and not self.capture_flag:
            self._latch()

    def _latch(self) -> None:
        t = self.sim.now
        self.captured_pos256 = self.position(t, 8)
        self.capture_t_ns = t
        self.captures.append((t, self.captured_pos256))
        self.capture_flag = True
        self._flag.set(1)

    def read_capture(self) -> int:
        """Read the capture register: returns the captured position [1/256 count] and re-arms.

        A trigger input still at its active level latches again immediately (level trigger).
        Before any capture the register reads 0.
        """
        value = self.captured_pos256 if self.captured_pos256 is not None else 0
        self.capture_flag = False
        self._flag.set(0)
        if self.trigger is not None and self.trigger.value == self.trigger_level:
            self._latch()
        return value

    def read_register(self, offset: int) -> int:
        """X-register ``address + offset``: 0 = count (24 bits), 3 = capture (whole counts, re-arms)."""
        if offset == 0:
            return self.count(self.sim.now) & REG_MASK
        if offset == CAPTURE_OFFSET:
            return (self.read_capture() >> TRIGGERED_BITS) & REG_MASK
        raise ConfigurationError.out_of_range(
            f"register offset of encoder channel ${self.address:06X}", offset,
            f"0 (position), {CAPTURE_OFFSET} (capture)")
