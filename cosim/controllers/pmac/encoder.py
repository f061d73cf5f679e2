"""Encoder channels: 1/T sub-count extension and the position-capture register.

The master encoder reaches the controller as an :class:`~cosim.encoders.EncoderSource` (see
:mod:`cosim.encoders` for the 1/T extension, which this module applies).

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

from typing import TYPE_CHECKING

from cosim import validate
from cosim.controllers.pmac.units import REG_MASK
from cosim.encoders import EncoderSource, extend_one_over_t
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
        self.capture_t: int | None = None
        self.captures: list[tuple[int, int]] = []
        extended = getattr(encoder, "extended", None)  # a source may extend without building a sample
        self._extended = extended if callable(extended) else None
        self._flag = Signal(sim, f"{device}.{self.name}.capture_flag", kind="bit",
                            description=f"capture flag of encoder channel ${address:06X}")
        if trigger is not None:
            trigger.subscribe(self._on_trigger)
            if trigger.value == trigger_level:
                self._latch()

    def position(self, t: int, fraction_bits: int) -> int:
        """1/T-extended position at ``t`` [2^-fraction_bits count], unwrapped."""
        if self._extended is not None:
            return self._extended(t, fraction_bits)
        return extend_one_over_t(self.encoder.sample(t), t, fraction_bits)

    def count(self, t: int) -> int:
        """Whole-count position at ``t`` [counts]."""
        return self.encoder.sample(t).count

    def _on_trigger(self, signal: Signal) -> None:
        if signal.value == self.trigger_level and not self.capture_flag:
            self._latch()

    def _latch(self) -> None:
        t = self.sim.now
        self.captured_pos256 = self.position(t, 8)
        self.capture_t = t
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
