"""A raster engraving job for the gating FIFO: thousands of gate positions per line, refilled by the host.

Bidirectional lines on the gated axis (x); the other axis (y) steps over between lines::

    y  line 2  <---------------------------------  LT: x_end .. x_start
       line 1  --------------------------------->  GT: x_start .. x_end
       line 0  <---------------------------------
    positions  |ON|OFF|ON|OFF| ...  every ``pitch`` units from ``margin``

Each line's positions sit in TABLE; the host loads them into the FIFO ``chunk`` positions at a
time: as many as fit before the move starts, then one chunk every ``refill_ms`` (0: as fast as
the FIFO frees space; each load waits while it does not fit). If the host refills more slowly
than the axis consumes positions, the FIFO runs empty and positions are passed before they are
loaded: the gate fires them late and ``trio.axisN.gate_late`` names them.
"""

from __future__ import annotations

from collections.abc import Generator
from dataclasses import dataclass
from fractions import Fraction
from math import ceil, floor
from typing import Any

from cosim import validate
from cosim.controllers.trio.params import FIFO_DEPTH
from cosim.controllers.trio.process import TrioProcess


@dataclass(frozen=True)
class RasterJob:
    """The job's geometry and host refill policy.

    Parameters
    ----------
    lines : int
        Raster lines (even lines forward with GT, odd lines back with LT).
    positions : int
        Gate positions per line (ON/OFF alternating, starting ON).
    pitch : Fraction
        Distance between positions [units].
    margin : Fraction
        Run-up before the first and after the last position [units].
    line_spacing : Fraction
        Step-over between lines [units of the other axis].
    chunk : int
        Positions per PWM_CONTROL(3) load (1..256).
    refill_ms : Fraction
        Host refill period [ms]; 0 refills as soon as the FIFO has room.
    table_start : int
        First TABLE location used.
    """

    lines: int = 3
    positions: int = 2000
    pitch: Fraction = Fraction(1, 20)
    margin: Fraction = Fraction(5)
    line_spacing: Fraction = Fraction(1, 10)
    chunk: int = 64
    refill_ms: Fraction = Fraction(5)
    table_start: int = 0

    def __post_init__(self) -> None:
        validate.integer(self.lines, "lines", low=1, where="RasterJob")
        validate.integer(self.positions, "positions", low=1, where="RasterJob")
        validate.integer(self.chunk, "chunk", low=1, high=FIFO_DEPTH, where="RasterJob")
        validate.integer(self.table_start, "table_start", low=0, where="RasterJob")
        exact = {"pitch": validate.positive(self.pitch, "pitch", unit="units", where="RasterJob"),
                 "margin": validate.exact(self.margin, "margin", where="RasterJob"),
                 "line_spacing": validate.exact(self.line_spacing, "line_spacing", where="RasterJob"),
                 "refill_ms": validate.positive(self.refill_ms, "refill_ms", unit="ms", zero=True, where="RasterJob")}
        for name, value in exact.items():
            object.__setattr__(self, name, value)

    @property
    def x_end(self) -> Fraction:
        """End of a forward line [units]."""
        return 2 * self.margin + (self.positions - 1) * self.pitch

    def line_positions(self, line: int) -> list[Fraction]:
        """Gate positions of ``line`` in the order the axis meets them [units]."""
        ahead = [self.margin + k * self.pitch for k in range(self.positions)]
        return ahead if line % 2 == 0 else [self.x_end - p for p in ahead]

    def expected_edges(self, units: Fraction) -> list[tuple[int, int]]:
        """``(count, level)`` of every gate edge: GT at the first count above, LT at the first below."""
        edges = []
        for line in range(self.lines):
            forward = line % 2 == 0
            for k, position in enumerate(self.line_positions(line)):
                counts = position * units
                edges.append((floor(counts) + 1 if forward else ceil(counts) - 1, 1 - (k & 1)))
        return edges

    def fill_table(self, p: TrioProcess) -> None:
        """Write every line's positions into TABLE."""
        for line in range(self.lines):
            p.table(self.table_start + line * self.positions, *self.line_positions(line))

    def run(self, p: TrioProcess, *, x_axis: int = 3, y_axis: int = 2) -> Generator[Any, Any, None]:
        """The host program (a SimPy process body): load, move, refill, step over, for every line."""
        for line in range(self.lines):
            forward = line % 2 == 0
            first = self.table_start + line * self.positions
            chunks = [(k, min(k + self.chunk, self.positions) - 1) for k in range(0, self.positions, self.chunk)]
            preload = max(1, FIFO_DEPTH // self.chunk)
            for k0, k1 in chunks[:preload]:
                yield p.pwm_control(3, int(forward), 1 - (k0 & 1), first + k0, first + k1, axis=x_axis)
            yield p.moveabs(self.x_end if forward else 0, axis=x_axis)
            for k0, k1 in chunks[preload:]:
                if self.refill_ms:
                    yield p.wa(self.refill_ms)
                yield p.pwm_control(3, int(forward), 1 - (k0 & 1), first + k0, first + k1, axis=x_axis)
            yield p.wait_idle(axis=x_axis)
            if line + 1 < self.lines:
                yield p.move(self.line_spacing, axis=y_axis)
                yield p.wait_idle(axis=y_axis)
