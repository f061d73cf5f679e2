"""Homing of one axis, decided slot by slot from the home switch read at the slot start.

1. search: move towards the home switch (negative, or positive with ``invert_homing``) at
   ``homing_speed_pct`` (10 %) of the maximum speed until the switch reads tripped;
2. back off: reverse, at ``homing_return_pct`` (1 %) of the maximum speed, until the switch
   changes state again (reads released) - the document says "when the switch is tripped"; we read
   it as the second change of state;
3. at that slot start the position counter is reset to 0 and the axis stops. It does not move
   back to position 0.

Speeds start without a ramp. Pulses per slot carry the remainder exactly: slot k of a phase has
``floor((k+1)*r) - floor(k*r)`` pulses for a rate of ``r`` pulses per slot.
"""

from __future__ import annotations

from fractions import Fraction

from cosim.controllers.pokeys.states import AxisState


class HomingAxis:
    """The homing sequence of one axis.

    Parameters
    ----------
    search_per_slot, back_per_slot : Fraction
        Search and back-off speeds [pulses/slot].
    toward_negative : bool
        Search direction (the back-off goes the other way).
    """

    def __init__(self, search_per_slot: Fraction, back_per_slot: Fraction, *, toward_negative: bool) -> None:
        self.search = search_per_slot
        self.back = back_per_slot
        self.search_sign = -1 if toward_negative else 1
        self.phase = AxisState.HOMING_START
        self._k = 0

    @property
    def done(self) -> bool:
        """True once the counter was reset at the switch."""
        return self.phase == AxisState.HOME

    def step(self, home_tripped: bool) -> tuple[int, bool]:
        """One slot: ``(signed pulses, reset_counter_now)`` for the home switch read at its start."""
        if self.phase in (AxisState.HOMING_START, AxisState.HOMING_SEARCH):
            if not home_tripped:
                self.phase = AxisState.HOMING_SEARCH
                return self.search_sign * self._next(self.search), False
            self.phase = AxisState.HOMING_BACK
            self._k = 0
        if self.phase == AxisState.HOMING_BACK:
            if home_tripped:
                return -self.search_sign * self._next(self.back), False
            self.phase = AxisState.HOME
            return 0, True
        return 0, False

    def _next(self, rate: Fraction) -> int:
        k = self._k
        self._k += 1
        return int((k + 1) * rate) - int(k * rate)
