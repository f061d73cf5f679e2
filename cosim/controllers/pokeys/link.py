"""The host-device link: one-way delays with seeded jitter, per profile.

A delay is ``latency_ns + jitter`` with the jitter drawn uniformly from ``0..jitter_ns`` whole
nanoseconds by the simulation's random generator (``sim.rng``), so a run is reproducible from its
seed; the delay is then floored to the simulation's resolution (the same draws at every
resolution, so the same physical delays up to one tick).

Profiles (assumptions, not from the vendor document; make your own with :class:`LinkProfile`):

``usb``       USB HID, 1 ms interrupt frames: 0.5 ms + 0..1 ms each way
``ethernet``  UDP on a quiet LAN: 0.1 ms + 0..0.2 ms each way
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

from cosim.errors import ConfigurationError
from cosim.kernel import Simulation
from cosim.validate import integer


@dataclass(frozen=True)
class LinkProfile:
    """Delay model of a link.

    Parameters
    ----------
    name : str
    latency_ns : int
        Fixed part of a one-way delay [ns].
    jitter_ns : int
        Random part, uniform in ``0..jitter_ns`` [ns].
    """

    name: str
    latency_ns: int
    jitter_ns: int

    def __post_init__(self) -> None:
        integer(self.latency_ns, "latency_ns", low=0, high=10**10, unit="ns", where=f"link {self.name}")
        integer(self.jitter_ns, "jitter_ns", low=0, high=10**10, unit="ns", where=f"link {self.name}")


PROFILES: dict[str, LinkProfile] = {
    "usb": LinkProfile("usb", latency_ns=500_000, jitter_ns=1_000_000),
    "ethernet": LinkProfile("ethernet", latency_ns=100_000, jitter_ns=200_000),
}


def profile(link: str | LinkProfile) -> LinkProfile:
    """A profile by name (``usb``, ``ethernet``) or as given."""
    if isinstance(link, LinkProfile):
        return link
    if link not in PROFILES:
        raise ConfigurationError.out_of_range("link", link, ", ".join(PROFILES))
    return PROFILES[link]


class Link:
    """One link between a host and the device, drawing its delays from ``sim.rng``."""

    BATCH = 1024
    """Delays drawn from ``sim.rng`` at a time (the sequence depends only on the seed)."""

    def __init__(self, sim: Simulation, link: str | LinkProfile) -> None:
        self.sim = sim
        self.profile = profile(link)
        self._drawn: list[int] = []
        self._ns_per_tick: Fraction = sim.timebase.resolution_s * 10**9
        self._tick_is_ns = self._ns_per_tick == 1
        #: The shortest one-way delay [ticks]: the latency, floored as :meth:`delay` floors every delay.
        self.min_delay = int(self.profile.latency_ns // self._ns_per_tick)

    def delay_ns(self) -> int:
        """One one-way delay [ns], drawn from ``sim.rng``."""
        p = self.profile
        if not p.jitter_ns:
            return p.latency_ns
        if not self._drawn:
            self._drawn = (p.latency_ns + self.sim.rng.integers(0, p.jitter_ns + 1, size=self.BATCH)).tolist()[::-1]
        return self._drawn.pop()

    def next_delay(self) -> int:
        """A lower bound of what the next :meth:`delay` returns [ticks], drawing nothing: that delay itself
        where it is drawn already (from the batch), else the shortest one (the latency)."""
        if not self._drawn:
            return self.min_delay
        ns = self._drawn[-1]
        if self._tick_is_ns:
            return ns
        return int(ns // self._ns_per_tick)

    def delay(self) -> int:
        """One one-way delay [ticks]: :meth:`delay_ns` floored to the simulation's resolution."""
        ns = self.delay_ns()
        if self._tick_is_ns:
            return ns
        return int(ns // self._ns_per_tick)
