"""A plant's encoder and registration-mark outputs as a controller's encoder input and trigger.

A controller reads an encoder through :class:`~cosim.encoders.EncoderSource`. :class:`PlantEncoder`
is one over a plant that publishes its encoder as outputs (the Conveyor and Servo FMUs): it reads
them at the instant the controller samples (reading advances the plant to now) and converts the
edge instants [s] to ticks once, here, with
:meth:`~cosim.timebase.TimeBase.ticks_from_seconds_ceil` (the first tick at or after the edge:
the tick from which the new count is visible). :func:`watch_mark` publishes a registration
sensor as the bit signal a capture input takes.

Encoder roles (Conveyor/Servo FMU names as defaults): ``count`` (``encoder_count``),
``direction`` (``edge_direction``), ``t_last_edge`` and ``t_prev_edge`` [s]. Mark role: ``mark``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from fractions import Fraction
from typing import TYPE_CHECKING

from cosim.couplings.roles import required, resolve
from cosim.encoders import EncoderSample
from cosim.errors import ConfigurationError
from cosim.master import Plant, PlantLike
from cosim.signals import Signal

if TYPE_CHECKING:
    from cosim.controllers.pmac.ports import EncoderPort

ROLES: dict[str, str | None] = {"count": "encoder_count", "direction": "edge_direction",
                                "t_last_edge": "t_last_edge", "t_prev_edge": "t_prev_edge"}
"""Encoder roles and the Conveyor/Servo FMU outputs that play them."""
MARK_ROLES: dict[str, str | None] = {"mark": "mark"}
"""Registration-mark role and the Conveyor FMU output that plays it."""


class PlantEncoder:
    """An :class:`~cosim.encoders.EncoderSource` over a plant's encoder outputs.

    Parameters
    ----------
    plant : PlantLike
        A Conveyor or Servo plant (or any plant with the roles of :data:`ROLES`).
    start : int, optional
        The plant's start time [ticks] (default: now; build the adapter right after loading the
        plant). The FMUs report the start time as edge instant before there were edges; such an
        instant is taken as "no edge yet", so the 1/T extension only uses real edges.
    variables : mapping role -> variable, optional
        The plant's names for the roles, where they differ.

    Notes
    -----
    ``sample(t)`` may only be called at ``t == sim.now``: the plant is read at the instant the
    controller samples it (the servo interrupt, or a capture trigger).
    """

    def __init__(self, plant: PlantLike, *, start: int | None = None,
                 variables: Mapping[str, str | None] | None = None) -> None:
        self.plant = plant
        self.sim = plant.sim
        self.start = self.sim.now if start is None else start
        self._env = self.sim.env
        names = resolve(plant, "encoder", ROLES, variables)
        self._count, self._direction = required(names, "count"), required(names, "direction")
        self._last, self._prev = required(names, "t_last_edge"), required(names, "t_prev_edge")
        resolution = self.sim.timebase.resolution_s  # ticks = seconds * den / num
        self._per_s = (resolution.denominator, resolution.numerator)
        nan = float("nan")
        self._recent: tuple[float, int, float, int] = (nan, 0, nan, 0)  # the last two instants [s] and their ticks
        # An FMU plant is read in one prepared call per FMI type (Int32 count and direction, Float64
        # instants: two calls instead of four reads), into one-element boxes: the same values as read().
        self._boxes: tuple[list[float], ...] = ([0], [0.0], [0.0], [0])  # count, last, prev, direction
        self._fill: Callable[[int], None] | None = None
        if isinstance(plant, Plant):
            self._fill = plant.fmu.sampler([self._count, self._last, self._prev, self._direction],
                                           [box.__setitem__ for box in self._boxes])
            self._advance = plant.advance

    def _read(self) -> tuple[int, float, float, int]:
        """Count, last and previous edge instants [s] and direction of the plant now (advanced to now)."""
        fill = self._fill
        if fill is not None:
            self._advance()
            fill(0)  # each sink stores its value at index 0 of its box
            count, last, prev, direction = self._boxes
            return int(count[0]), float(last[0]), float(prev[0]), int(direction[0])
        read = self.plant.read
        return int(read(self._count)), float(read(self._last)), float(read(self._prev)), int(read(self._direction))

    def _ticks_ceil(self, t_s: float) -> int:
        """:meth:`cosim.timebase.TimeBase.ticks_from_seconds_ceil` in integers (the same rule, the same tick).

        The float is exactly ``n / d`` (``d`` a power of two), so the time in ticks is exactly
        ``A / B = q + r / B``; within 10^-6 tick of a whole tick (float noise of a time that was on
        one) it is that tick, else the next tick up. Since ``0 <= r < B``, that is ``q`` when
        ``r <= B / 10^6`` and ``q + 1`` otherwise (a remainder within 10^-6 of the next tick rounds
        to it as the ceiling does). The last two instants are kept: an edge read as ``t_last_edge``
        is read again as ``t_prev_edge`` after the next edge.
        """
        recent = self._recent
        if t_s == recent[0]:
            return recent[1]
        if t_s == recent[2]:
            return recent[3]
        n, d = t_s.as_integer_ratio()
        den, num = self._per_s
        b = d * num
        q, r = divmod(n * den, b)
        ticks = q if 1_000_000 * r <= b else q + 1
        self._recent = (t_s, ticks, recent[0], recent[1])
        return ticks

    def _edge(self, t_s: float) -> int | None:
        t = self._ticks_ceil(t_s)
        return t if t > self.start else None

    def sample(self, t: int) -> EncoderSample:
        """Count, last two edge instants [ticks] and direction of the plant's encoder now."""
        if t != self.sim.now:
            raise ConfigurationError.out_of_range("t of PlantEncoder.sample", t,
                                                  f"the current time {self.sim.now} (a plant is read now)")
        count, last_s, prev_s, direction = self._read()
        last = self._edge(last_s)
        prev = self._edge(prev_s) if last is not None else None
        return EncoderSample(count, last, prev, 1 if direction >= 0 else -1)

    def extended(self, t: int, fraction_bits: int) -> int:
        """``extend_one_over_t(self.sample(t), t, fraction_bits)`` without building the sample (the servo cycle's)."""
        if t != self._env._now:
            self.sample(t)  # raises: a plant is read now
        fill = self._fill
        if fill is not None:  # _read(), inline (twice per servo cycle)
            self._advance()
            fill(0)
            count_box, last_box, prev_box, direction_box = self._boxes
            count, last_s, prev_s, direction = (int(count_box[0]), float(last_box[0]), float(prev_box[0]),
                                                int(direction_box[0]))
        else:
            count, last_s, prev_s, direction = self._read()
        scale = 1 << fraction_bits
        last = self._ticks_ceil(last_s)
        if last <= self.start:
            return count * scale
        up = direction >= 0
        boundary = count if up else count + 1
        prev = self._ticks_ceil(prev_s)
        if prev <= self.start or last <= prev or t <= last:
            return boundary * scale
        frac = min(scale - 1, ((t - last) * scale) // (last - prev))
        return boundary * scale + frac if up else boundary * scale - frac

    def position(self, *, fraction_bits: int = 5) -> Fraction:
        """1/T-extended position now [counts], truncated to ``2^-fraction_bits`` count."""
        now = self.sim.now
        return Fraction(self.extended(now, fraction_bits), 1 << fraction_bits)


def watch_mark(plant: PlantLike, *, signal: str | None = None,
               variables: Mapping[str, str | None] | None = None) -> Signal:
    """The plant's registration sensor as a bit signal changing at its exact (tick-ceiled) edges.

    Parameters
    ----------
    plant : PlantLike
        A Conveyor plant loaded from its FMI 3.0 build (early return locates the mark edges), or
        an analytic plant whose mark is exact by construction.
    signal : str, optional
        Signal name (default ``<plant>.mark``).
    variables : mapping role -> variable, optional
        The plant's name for ``mark``.

    Raises
    ------
    ConfigurationError
        If the plant is an FMU that is not FMI 3.0 with early return (FMI 2.0 would publish the
        mark only at the end of a step, up to a servo period late).
    """
    fmu = getattr(plant, "fmu", None)
    version = getattr(fmu, "fmi_version", None)
    if fmu is not None and not (version == 3 and getattr(fmu, "early_return", False)):
        raise ConfigurationError.out_of_range(f"FMI version of {plant.name} for the capture trigger", version,
                                              "3 (FMI 3.0 with early return, to locate mark edges exactly)")
    names = resolve(plant, "mark", MARK_ROLES, variables)
    return plant.watch(required(names, "mark"), signal=signal)


def couple_encoder(port: EncoderPort, plant: PlantLike, *,
                   variables: Mapping[str, str | None] | None = None) -> PlantEncoder:
    """A plant's encoder (and its mark output, if the port has a trigger) as a PMAC encoder channel.

    Parameters
    ----------
    port : EncoderPort
        The controller's encoder input (``pmac.encoder_port(...)``, or a machine file's
        ``encoder = { channel = "$078018", trigger = "mark" }``).
    plant : PlantLike
        A Conveyor plant (FMI 3.0 for a trigger) or any plant with the roles of :data:`ROLES`.
    variables : mapping role -> variable, optional
        The plant's names for the encoder roles, where they differ.
    """
    encoder = PlantEncoder(plant, variables=variables)
    trigger = watch_mark(plant, variables={"mark": port.trigger}) if port.trigger is not None else None
    port.connect(encoder, trigger)
    return encoder
