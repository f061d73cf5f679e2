"""Switch inputs of the pulse engine and their evaluation at slot starts.

All switch inputs expect normally-closed switches between the input pin and ground, so a closed
(untouched) switch pulls the pin low and an open one - tripped, or a broken wire - lets it go
high. The model's switch signals carry the *input level*: **1 = tripped** for the limit and home
inputs. The emergency input follows ``emergency_polarity`` (0, the default: 1 = emergency;
1: 0 = emergency).

The engine reads every input once per slot, at the slot start (priority SLOT); a change in
between is seen at the next slot start.
"""

from __future__ import annotations

from dataclasses import dataclass

from cosim.controllers.pokeys.config import EngineConfig
from cosim.controllers.pokeys.limits import AXIS_NAMES
from cosim.kernel import Simulation
from cosim.signals import Signal

TRIPPED = 1
"""Input level of a tripped limit or home switch (normally-closed switch to ground)."""


@dataclass(frozen=True)
class SwitchSample:
    """Tripped states read at one slot start (bitmaps: bit 0 = x, bit 1 = y, bit 2 = z, one bit per axis)."""

    limit_pos: int
    limit_neg: int
    home: int
    emergency: bool

    @property
    def stop_candidate(self) -> bool:
        """Any limit or the emergency input tripped (enabled or not)."""
        return bool(self.limit_pos or self.limit_neg or self.emergency)

    def home_tripped(self, axis: int) -> bool:
        """Home switch of ``axis`` tripped."""
        return bool(self.home >> axis & 1)


class SwitchInputs:
    """The limit, home and emergency inputs as bit signals.

    Parameters
    ----------
    sim : Simulation
    config : EngineConfig
    name : str
        Device prefix of the signal names (``pokeys``).

    Attributes
    ----------
    limit_pos, limit_neg, home : list of Signal
        Per axis ``<name>.<axis>.limit_pos`` / ``limit_neg`` / ``home``.
    emergency : Signal
        ``<name>.emergency``.
    """

    def __init__(self, sim: Simulation, config: EngineConfig, *, name: str) -> None:
        self.config = config
        nc = "normally closed: 1 = tripped (input high)"
        names = AXIS_NAMES[:len(config.axes)]
        self.limit_pos = [Signal(sim, f"{name}.{a}.limit_pos", description=f"limit+ switch {a}, {nc}") for a in names]
        self.limit_neg = [Signal(sim, f"{name}.{a}.limit_neg", description=f"limit- switch {a}, {nc}") for a in names]
        self.home = [Signal(sim, f"{name}.{a}.home", description=f"home switch {a}, {nc}") for a in names]
        self.emergency_level = 1 if config.emergency_polarity == 0 else 0
        self.emergency = Signal(sim, f"{name}.emergency", initial=1 - self.emergency_level,
                                description=f"emergency input, {self.emergency_level} = emergency")
        self._cached: SwitchSample | None = None
        for signal in (*self.limit_pos, *self.limit_neg, *self.home, self.emergency):
            signal.subscribe(self._changed)

    def _changed(self, _signal: Signal) -> None:
        self._cached = None

    def reconfigure(self, config: EngineConfig) -> None:
        """Evaluate the inputs with ``config``'s enables and emergency polarity from now on.

        A polarity change leaves a healthy emergency input healthy: the input stands for a switch
        wired for the configured polarity, so its level moves to the new healthy level (a plant
        or script that drives it sets it again).
        """
        level = 1 if config.emergency_polarity == 0 else 0
        healthy = self.emergency.value != self.emergency_level
        self.config = config
        self.emergency_level = level
        self._cached = None
        if healthy:
            self.emergency.set(1 - level)

    def sample(self) -> SwitchSample:
        """Read every input now (tripped states, whether enabled or not)."""
        if self._cached is None:  # re-read only after an input changed
            self._cached = SwitchSample(
                limit_pos=_bitmap(self.limit_pos), limit_neg=_bitmap(self.limit_neg), home=_bitmap(self.home),
                emergency=self.emergency.value == self.emergency_level,
            )
        return self._cached

    def enabled_limits_tripped(self, sample: SwitchSample) -> list[int]:
        """Axes whose enabled limit switch (either side) is tripped in ``sample``."""
        tripped = []
        for i, axis in enumerate(self.config.axes):
            pos = axis.limit_pos_enabled and sample.limit_pos >> i & 1
            neg = axis.limit_neg_enabled and sample.limit_neg >> i & 1
            if pos or neg:
                tripped.append(i)
        return tripped

    def emergency_tripped(self, sample: SwitchSample) -> bool:
        """Enabled emergency input active in ``sample``."""
        return self.config.emergency_enabled and sample.emergency


def _bitmap(signals: list[Signal]) -> int:
    return sum(1 << i for i, s in enumerate(signals) if s.value == TRIPPED)
