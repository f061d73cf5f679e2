"""Homing of one axis, decided slot by slot from the home switch read at the slot start.

1. search: move towards the home switch (negative, or positive with ``invert_homing``) at
   ``homing_speed_pct`` (10 %) of the maximum speed until the switch reads tripped;
2. back off: reverse, at ``homing_return_pct`` (1 %) of the maximum speed, until the switch
   changes state again (reads released);
3. at that slot start the axis stops. It does not move back to position 0.

The vendor documents say the counter is reset "when the switch is tripped" after the reversal.
Two readings, chosen by ``EngineConfig.homing_reset``:

``"release"`` (default)
    "tripped" as the switch's next change of state: the counter is reset to 0 where the switch
    releases on the slow return, at the slot start that reads it released (the home position is
    the release point, approached slowly). Pulse engine v2's default homing algorithm (axis record
    ``[43]`` = 0x83 in PoKeysLib: on activation reverse and reduce the speed, on release stop, then
    axis state 8 "resetting the position counters") does this.
``"trip"``
    "tripped" as the level: the counter is reset to 0 at the slot start that reads the switch
    tripped at the end of the search (the home position is the trip point, approached at the
    search speed); the slow return runs as above and the axis stops where the switch releases,
    its counter holding the back-off distance.

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
    reset_at : {'release', 'trip'}
        Where the counter is reset (see the module text).
    """

    def __init__(self, search_per_slot: Fraction, back_per_slot: Fraction, *, toward_negative: bool,
                 reset_at: str = "release") -> None:
        self.search = search_per_slot
        self.back = back_per_slot
        self.search_sign = -1 if toward_negative else 1
        self.reset_at_trip = reset_at == "trip"
        self.phase = AxisState.HOMING_START
        self._k = 0

    @property
    def done(self) -> bool:
        """True once the counter was reset at the switch."""
        return self.phase == AxisState.HOME

    def step(self, home_tripped: bool) -> tuple[int, bool]:
        """One slot: ``(signed pulses, reset the counter before them)`` for the home switch read at its start."""
        if self.phase in (AxisState.HOMING_START, AxisState.HOMING_SEARCH):
            if not home_tripped:
                self.phase = AxisState.HOMING_SEARCH
                return self.search_sign * self._next(self.search), False
            self.phase = AxisState.HOMING_BACK
            self._k = 0
            if self.reset_at_trip:
                return -self.search_sign * self._next(self.back), True
        if self.phase == AxisState.HOMING_BACK:
            if home_tripped:
                return -self.search_sign * self._next(self.back), False
            self.phase = AxisState.HOME
            return 0, not self.reset_at_trip
        return 0, False

    def _next(self, rate: Fraction) -> int:
        k = self._k
        self._k += 1
        return int((k + 1) * rate) - int(k * rate)
