"""Incremental encoders as a controller's input sees them: counts, edge instants, 1/T extension.

Shared by the controllers that read encoders (the PMAC's conversion table and capture) and the
plants and couplings that provide them, so the 1/T rule exists once. Times are integer ticks of
the simulation's resolution.

An encoder reaches a controller as an :class:`EncoderSource`: anything whose ``sample(t)``
returns the count and the instants of the last two count edges (:class:`EncoderSample`). A
plant's encoder outputs (through :class:`cosim.couplings.encoder.PlantEncoder`), a count
:class:`~cosim.signals.Signal` (:class:`SignalEncoder`) or an analytic plant
(:class:`cosim.plants.analytic.IdealConveyor`) can stand behind it.

1/T extension
-------------
Between edges the position is extrapolated from the time since the last edge divided by the
time between the last two edges, truncated to ``2^-bits`` count (5 bits = 1/32 count for the
standard PMAC 1/T entry, 8 bits = 1/256 for the Turbo triggered time-base entry). The fraction
is clamped below one count, so the estimate never passes the next edge. It is measured from the
boundary the last edge crossed: ``count`` for an upward edge, ``count + 1`` for a downward one.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

from cosim.errors import ConfigurationError
from cosim.signals import Signal


@dataclass(frozen=True)
class EncoderSample:
    """What the 1/T hardware knows about an encoder at one instant.

    Parameters
    ----------
    count : int
        Quadrature count [counts].
    last_edge_t, prev_edge_t : int or None
        Instants of the last and the previous count edge [ticks] (None before there were any).
    direction : int
        +1 if the last edge counted up, -1 if down.
    """

    count: int
    last_edge_t: int | None = None
    prev_edge_t: int | None = None
    direction: int = 1


class EncoderSource(Protocol):
    """Anything that reports an encoder's count and edge timestamps at an instant."""

    def sample(self, t: int) -> EncoderSample:
        """The encoder state at tick ``t`` (never earlier than a previous call)."""
        ...


def extend_one_over_t(sample: EncoderSample, t: int, fraction_bits: int) -> int:
    """1/T-extended position at tick ``t`` in units of ``2^-fraction_bits`` count (truncated).

    Examples
    --------
    >>> s = EncoderSample(count=10, last_edge_t=15_625, prev_edge_t=0)
    >>> extend_one_over_t(s, 15_625 + 7_812, 5)  # half a count after the edge, in 1/32 count
    335
    """
    scale = 1 << fraction_bits
    last, prev = sample.last_edge_t, sample.prev_edge_t
    if last is None:
        return sample.count * scale
    boundary = sample.count if sample.direction >= 0 else sample.count + 1
    if prev is None or last <= prev or t <= last:
        return boundary * scale
    frac = min(scale - 1, ((t - last) * scale) // (last - prev))
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

    def sample(self, t: int) -> EncoderSample:
        """The count and the instants of its last two changes."""
        return EncoderSample(self._value, self._last, self._prev, self._direction)
