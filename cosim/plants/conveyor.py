"""Conveyor plant: belt motion in closed form, registration-mark edge instants, linear model.

The Conveyor FMU (``fmu_src/Conveyor``) is a master axis driven by a speed command::

    dv/dt = (speed_cmd - v) / tau_drive
    dx/dt = v + disturbance + ripple_amplitude * sin(2 pi ripple_frequency t + ripple_phase)

With constant inputs from the start (t = 0) the position is closed form (:func:`position_at`);
:func:`mark_edge_times` finds from it the instants at which the mark sensor switches (marks at
``mark_offset + k * mark_pitch``, each ``mark_length`` long). Tests use both as the exact
reference for the FMU's encoder timestamps and mark events; :func:`linear_model` is the
small-signal model of the drive (python-control).

Examples
--------
>>> import numpy as np
>>> belt = ConveyorParameters(speed_start=0.5)      # already at speed
>>> times, rising = mark_edge_times(belt, speed_cmd=0.5, t_end_s=0.7)
>>> np.round(times, 12).tolist(), rising.tolist()   # mark 0 from 50 to 60 mm, mark 1 from 300 mm
([0.1, 0.12, 0.6, 0.62], [True, False, True, False])
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from cosim import validate
from cosim.errors import ConfigurationError
from cosim.plants.params import from_mapping

#: FMU parameters that only steer the FMU's solver.
_FMU_ONLY = frozenset({"max_step"})

FloatArray = npt.NDArray[np.float64]
_RTOL = 4 * float(np.finfo(float).eps)  # the smallest relative tolerance Brent's method accepts


@dataclass(frozen=True)
class ConveyorParameters:
    """The belt, encoder and mark sensor of the Conveyor FMU, named as its parameters (SI units).

    Defaults are the FMU's defaults (see ``models/presets/conveyor_web_200mm_wheel.toml``).

    Parameters
    ----------
    tau_drive : float
        Time constant of the drive [s], > 0.
    counts_per_metre : float
        Encoder quadrature counts per metre [counts/m], > 0.
    mark_pitch, mark_length : float
        Mark spacing and length [m], ``mark_pitch > mark_length > 0``.
    mark_offset : float
        Position of the leading edge of mark 0 [m].
    ripple_amplitude, ripple_frequency, ripple_phase : float
        Speed ripple [m/s], [Hz], [rad]; none unless amplitude and frequency are > 0.
    speed_start, position_start : float
        Drive speed [m/s] and belt position [m] at t = 0.
    """

    tau_drive: float = 0.05
    counts_per_metre: float = 50_000.0
    mark_pitch: float = 0.25
    mark_length: float = 0.01
    mark_offset: float = 0.05
    ripple_amplitude: float = 0.0
    ripple_frequency: float = 0.0
    ripple_phase: float = 0.0
    speed_start: float = 0.0
    position_start: float = 0.0

    def __post_init__(self) -> None:
        where = "ConveyorParameters"
        for name in ("tau_drive", "counts_per_metre", "mark_pitch", "mark_length"):
            validate.positive(getattr(self, name), name, where=where)
        for name in ("ripple_amplitude", "ripple_frequency"):
            validate.positive(getattr(self, name), name, zero=True, where=where)
        for name in ("mark_offset", "ripple_phase", "speed_start", "position_start"):
            validate.finite(getattr(self, name), name, where=where)
        validate.in_range(self.mark_pitch, "mark_pitch", low=self.mark_length, low_open=True,
                          allowed=f"> mark_length = {self.mark_length!r}", where=where)

    @classmethod
    def from_mapping(cls, values: Mapping[str, Any]) -> ConveyorParameters:
        """From FMU parameter values (e.g. a preset); solver-only parameters are ignored."""
        return from_mapping(cls, values, model="Conveyor", solver_only=_FMU_ONLY)

    def as_fmu_parameters(self) -> dict[str, float]:
        """The values as FMU start values (``Plant.load(..., parameters=...)``)."""
        return asdict(self)

    @property
    def has_ripple(self) -> bool:
        return self.ripple_amplitude > 0 and self.ripple_frequency > 0


def position_at(params: ConveyorParameters, t_s: npt.ArrayLike, *, speed_cmd: float,
                disturbance: float = 0.0) -> FloatArray:
    """Belt position [m] at ``t_s`` [s] for inputs held constant from t = 0 (closed form).

    ``x0 + (c + d) t + (v0 - c) tau (1 - exp(-t/tau)) + (A / w) (cos(phi) - cos(w t + phi))``
    """
    p = params
    t = np.asarray(t_s, dtype=np.float64)
    x = (p.position_start + (speed_cmd + disturbance) * t
         + (p.speed_start - speed_cmd) * p.tau_drive * -np.expm1(-t / p.tau_drive))
    if p.has_ripple:
        w = 2 * math.pi * p.ripple_frequency
        x = x + p.ripple_amplitude / w * (math.cos(p.ripple_phase) - np.cos(w * t + p.ripple_phase))
    return np.asarray(x, dtype=np.float64)


def mark_edge_positions(params: ConveyorParameters, x_min: float, x_max: float) -> tuple[FloatArray, FloatArray]:
    """Belt positions [m] of the mark edges in ``[x_min, x_max]``: (leading edges, trailing edges)."""
    p = params
    k0 = math.floor((x_min - p.mark_offset - p.mark_length) / p.mark_pitch)
    k1 = math.ceil((x_max - p.mark_offset) / p.mark_pitch)
    k = np.arange(k0, k1 + 1)
    leading = p.mark_offset + k * p.mark_pitch
    trailing = leading + p.mark_length
    return (leading[(leading >= x_min) & (leading <= x_max)].astype(np.float64),
            trailing[(trailing >= x_min) & (trailing <= x_max)].astype(np.float64))


def mark_edge_times(params: ConveyorParameters, *, speed_cmd: float, t_end_s: float, disturbance: float = 0.0,
                    grid_s: float = 1e-4) -> tuple[FloatArray, npt.NDArray[np.bool_]]:
    """Instants [s] in ``(0, t_end_s]`` at which the mark sensor switches, and whether it turns on.

    For inputs held constant from t = 0. Crossings of each edge are bracketed on a ``grid_s``
    grid (fine enough that the belt does not pass an edge and come back within one grid step)
    and solved with Brent's method to 1e-15 s.
    """
    from scipy.optimize import brentq

    grid = np.linspace(0.0, t_end_s, max(2, math.ceil(t_end_s / grid_s) + 1))
    x = position_at(params, grid, speed_cmd=speed_cmd, disturbance=disturbance)
    leading, trailing = mark_edge_positions(params, float(x.min()), float(x.max()))

    def position(t: float, edge: float) -> float:
        return float(position_at(params, t, speed_cmd=speed_cmd, disturbance=disturbance)) - edge

    found: list[tuple[float, bool]] = []
    for edges, is_leading in ((leading, True), (trailing, False)):
        for edge in edges:
            above = x >= edge
            for j in np.flatnonzero(above[1:] != above[:-1]):
                t = float(brentq(position, grid[j], grid[j + 1], args=(edge,), xtol=1e-15, rtol=_RTOL))
                moving_up = bool(above[j + 1])
                found.append((t, moving_up == is_leading))  # on: a leading edge forwards, a trailing one backwards
    found.sort()
    return (np.array([t for t, _ in found], dtype=np.float64), np.array([on for _, on in found], dtype=np.bool_))


def linear_model(params: ConveyorParameters, *, output: str = "speed") -> Any:
    """Transfer function from ``speed_cmd`` [m/s] to ``speed`` [m/s] or ``position`` [m] (python-control).

    ``1 / (tau_drive s + 1)``, and that over ``s`` for the position; the disturbance and the ripple
    add to the speed outside this model.
    """
    import control

    if output == "speed":
        return control.tf([1.0], [params.tau_drive, 1.0])
    if output == "position":
        return control.tf([1.0], [params.tau_drive, 1.0, 0.0])
    raise ConfigurationError.out_of_range("output", output, "'speed' or 'position'")
