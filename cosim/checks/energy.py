"""Energy per unit of path length: the even marking a laser engraver wants, through corners and arcs.

The path length comes from the positions of the path axes (e.g. ``trio.axis3.dpos`` and
``trio.axis2.dpos`` [mm]), the energy from a cumulative energy output sampled during the run
(e.g. ``laser.energy`` [J]). Between consecutive energy samples the path advances by the distance
between the axes' positions at those samples (held values; the chord, which is the path itself on
lines and shorter by a relative ``(chord / radius)**2 / 24`` on arcs). Where a ``gate`` signal is
given, only stretches during which it stays 1 count. Each stretch is cut into windows of at least
``window`` path length; the energy per length of every window must lie in ``[lower, upper]``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from cosim import validate
from cosim.checks.base import Check, Clock, Findings, fmt, held_index, records, unit_of
from cosim.checks.result import MAX_REPORTED, Violation
from cosim.errors import ConfigurationError

if TYPE_CHECKING:
    from cosim.trace import Trace


@dataclass(frozen=True)
class EnergyPerLength(Check):
    """Energy per path length over windows of ``window`` length stays within ``[lower, upper]``.

    Parameters
    ----------
    signal : str
        Cumulative energy [J], sampled (e.g. ``laser.energy`` recorded every 100 us).
    positions : sequence of str
        Position signals of the path axes [units], e.g. ``["trio.axis3.dpos", "trio.axis2.dpos"]``.
    lower, upper : float
        Allowed energy per length [J/unit].
    window : float
        Shortest path length a window covers [units], > 0.
    gate : str, optional
        A bit signal: only stretches where it stays 1 are windows (the laser was gated on).

    Notes
    -----
    Measured: ``windows``, ``min_j_per_unit``, ``max_j_per_unit``, ``mean_j_per_unit`` (the mean of
    the windows). One violation per window outside the bounds, at its end.
    """

    signal: str
    positions: Sequence[str]
    lower: float
    upper: float
    window: float = 1.0
    gate: str | None = None

    def __post_init__(self) -> None:
        validate.finite(self.lower, "lower", where=self.where)
        validate.finite(self.upper, "upper", where=self.where)
        validate.positive(self.window, "window", unit="units", where=self.where)
        if isinstance(self.positions, str) or not isinstance(self.positions, Sequence):
            raise ConfigurationError.out_of_range("positions", self.positions, "a list of position signals, e.g. "
                                                  "[\"trio.axis3.dpos\", \"trio.axis2.dpos\"]", where=self.where)
        if not self.positions:
            raise ConfigurationError.out_of_range("positions", list(self.positions), "one or more position signals",
                                                  where=self.where)

    def examine(self, trace: Trace, clock: Clock) -> Findings:
        t, energy = records(trace, self.signal, self)
        found = Findings(self.signal, description=f"energy per length of {self.signal} over windows of at least "
                                                  f"{fmt(self.window)} units along {', '.join(self.positions)}"
                                                  f" within [{fmt(self.lower)}, {fmt(self.upper)}]")
        if t.size < 2:
            return found
        coords = []
        for name in self.positions:
            tp, p = records(trace, name, self)
            coords.append(p[np.maximum(held_index(tp, t), 0)])
        step = np.sqrt(sum(np.diff(c) ** 2 for c in coords))
        gained = np.diff(energy)
        usable = np.ones(step.size, dtype=bool)
        if self.gate is not None:
            tg, g = records(trace, self.gate, self)
            level = held_index(tg, t)
            on = (level >= 0) & (g[np.maximum(level, 0)] > 0)
            usable = on[:-1] & on[1:] & (level[:-1] == level[1:])  # gated on, no gate edge in between
        window = float(self.window) * (1 - 1e-9)  # lengths are sums of float distances
        ratios: list[tuple[int, float]] = []
        length = joules = 0.0
        for k in range(step.size):
            if not usable[k]:
                length = joules = 0.0
                continue
            length += float(step[k])
            joules += float(gained[k])
            if length >= window:
                ratios.append((k + 1, joules / length))
                length = joules = 0.0
        found.checked = len(ratios)
        if not ratios:
            return found
        values = np.array([r for _, r in ratios])
        found.measured = {"windows": len(ratios), "min_j_per_unit": float(values.min()),
                          "max_j_per_unit": float(values.max()), "mean_j_per_unit": float(values.mean())}
        bad = [(k, r) for k, r in ratios if not self.lower <= r <= self.upper]
        found.n_violations = len(bad)
        unit = f"{unit_of(trace, self.signal) or 'J'}/{unit_of(trace, self.positions[0]) or 'unit'}"  # J/mm
        for k, r in bad[:MAX_REPORTED]:
            found.violations.append(Violation(clock.t_ns(t[k]), r, f"{fmt(self.lower)}..{fmt(self.upper)}",
                                              f"{fmt(r)} J per unit over the window ending here", unit=unit))
        return found
