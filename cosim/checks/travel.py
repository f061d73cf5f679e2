"""An axis stays within its travel: its position never leaves ``[low, high]`` (the machine's soft limits).

The position is read from the trace: an int/real position signal as recorded (``pokeys.x.position``
in pulses, ``trio.axis3.dpos`` in user units, ``pmac.motor1.cmd_pos`` in counts), or a step pulse
train's signed count. ``scale`` turns the signal's unit into the travel's (400 pulses per mm)::

    travel       0 mm ......................... 300 mm
    position     0 ──────────────────────────────────/‾‾‾‾‾ 400 mm ‾‾‾‾\\___    FAIL at the instant it passed
                                                     ^ 300 mm                  300 mm, reaching 400 mm
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from cosim import validate
from cosim.checks.base import Check, Clock, Findings, Floats, Ints, as_number, fmt, pulse_chunks, record_chunks
from cosim.checks.result import MAX_REPORTED, Violation

if TYPE_CHECKING:
    from cosim.trace import Trace


@dataclass(frozen=True)
class Travel(Check):
    """The position of an axis stays within ``[low, high]`` over the whole run.

    Parameters
    ----------
    signal : str
        The axis position: an int/real signal, or a pulse train (its signed pulse count).
    low, high : float
        The travel, in ``unit`` (inclusive).
    scale : float
        Signal units per ``unit`` (e.g. 400 pulses per mm; default 1: the signal's own unit), > 0.
    unit : str
        The travel's unit, for messages (``mm``).

    Notes
    -----
    ``checked`` counts the positions examined (records, or pulses). One violation per excursion
    (a run of positions outside the travel): ``t_ns`` = the first position outside, ``value`` =
    the farthest position of the excursion [unit], ``limit`` = the bound it passed. Measured:
    ``min`` and ``max`` [unit].

    Examples
    --------
    >>> from cosim.trace import Trace
    >>> trace = Trace()
    >>> trace.declare("pokeys.x.position", "int", unit="pulses")
    >>> for t, v in [(0, 0), (1_000_000_000, 120_000), (2_000_000_000, 160_000), (3_000_000_000, 0)]:
    ...     trace.record("pokeys.x.position", t, v)
    >>> Travel("pokeys.x.position", 0, 300, scale=400, unit="mm").evaluate(trace).summary()
    'FAIL Travel(pokeys.x.position): 4 checked, 1 violation; first at t=2000000000 ns: 400 vs limit 300 (...)'
    """

    signal: str
    low: float
    high: float
    scale: float = 1
    unit: str = ""

    def __post_init__(self) -> None:
        validate.finite(self.low, "low", where=self.where)
        validate.finite(self.high, "high", where=self.where)
        validate.in_range(self.low, "low", high=self.high, allowed=f"<= high ({fmt(self.high)})", where=self.where)
        validate.positive(self.scale, "scale", where=self.where)

    def examine(self, trace: Trace, clock: Clock) -> Findings:
        unit = f" {self.unit}" if self.unit else ""
        rule = f"{fmt(self.low)}..{fmt(self.high)}{unit}"
        found = Findings(self.signal, description=f"{self.signal} within its travel {rule}",
                         empty_detail=f"no position of {self.signal} was recorded: the travel was not examined")
        scale = Fraction(str(self.scale)) if isinstance(self.scale, float) else Fraction(self.scale)
        bounds = (float(Fraction(str(self.low)) * scale), float(Fraction(str(self.high)) * scale))
        lowest, highest = np.inf, -np.inf
        excursion: list[float] | None = None  # [t, farthest, side] of the excursion still open
        previous = 0
        for t, position in self._positions(trace):
            found.checked += position.size
            if not position.size:
                continue
            lowest, highest = min(lowest, float(position.min())), max(highest, float(position.max()))
            side = np.where(position > bounds[1], 1, np.where(position < bounds[0], -1, 0))
            starts = _run_starts(side, previous)
            ends = [*starts[1:].tolist(), side.size] if starts.size else []
            head = int(starts[0]) if starts.size else side.size
            if excursion is not None and head:  # the excursion goes on into this chunk
                excursion[1] = _farther(excursion[1], position[:head], excursion[2])
            for i, end in zip(starts.tolist(), ends, strict=True):
                if excursion is not None:
                    self._close(found, excursion, clock, unit)
                    excursion = None
                if side[i]:
                    excursion = [float(t[i]), _farther(float(position[i]), position[i:end], float(side[i])),
                                 float(side[i])]
            previous = int(side[-1])
        if excursion is not None:
            self._close(found, excursion, clock, unit)
        if found.checked:
            found.measured.update(min=as_number(lowest / float(scale)), max=as_number(highest / float(scale)))
        return found

    def _close(self, found: Findings, excursion: list[float], clock: Clock, unit: str) -> None:
        t, farthest, side = excursion
        bound = self.high if side > 0 else self.low
        found.n_violations += 1
        if len(found.violations) < MAX_REPORTED:
            value = as_number(round(farthest / float(self.scale), 9))
            found.violations.append(Violation(
                clock.t_ns(int(t)), value, as_number(bound),
                f"{self.signal} went {'past' if side > 0 else 'below'} {fmt(bound)}{unit}, to {fmt(value)}{unit}",
                unit=self.unit))

    def _positions(self, trace: Trace) -> Iterator[tuple[Ints, Floats]]:
        info = trace.info.get(self.signal)
        if info is not None and info.kind == "pulse":
            count = 0
            for t, direction in pulse_chunks(trace, self.signal, self):
                steps = np.cumsum(direction.astype(np.int64) * 2 - 1) + count
                count = int(steps[-1]) if steps.size else count
                yield t, steps.astype(np.float64)
            return
        yield from record_chunks(trace, self.signal, self)


def _farther(farthest: float, positions: Floats, side: float) -> float:
    """The farthest position outside the travel on ``side`` (1 above, -1 below)."""
    return max(farthest, float(positions.max())) if side > 0 else min(farthest, float(positions.min()))


def _run_starts(side: npt.NDArray[np.int64], before: int) -> npt.NDArray[np.int64]:
    """Indices where ``side`` differs from the value before it (``before`` for the first)."""
    previous = np.concatenate(([before], side[:-1]))
    return np.flatnonzero(side != previous)
