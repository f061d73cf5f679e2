"""The host planner for tool paths: a G-code program's moves into per-slot counts, as a host does it.

Rules, in order:

1. **Steps.** Every programmed point becomes whole steps per axis: ``round(position * steps_per_unit)``,
   halves away from zero, from the exact position (incremental programs accumulate exact
   fractions, never rounded steps: no drift). The program's end point in steps is where the
   engine's counters end.
2. **Arcs** are split into chords of equal angle, as few as keep the chord within
   ``arc_tolerance`` of the arc (sagitta ``r * (1 - cos(angle / 2)) <= arc_tolerance``, at most a
   quarter turn each); chord points are computed in double precision and rounded to steps, the
   arc's end point is exact.
3. **Speeds.** A feed move runs at ``F * feed_override`` along its path (the XYZ length in
   machine units; a move without XYZ motion: its UVW length, else its ABC length in degrees, as
   :func:`~cosim.controllers.pokeys.toolpath.feed_axes` says; the other axes move in proportion),
   a rapid at the axes' limits; either is slowed so that no axis exceeds its
   ``max_velocity`` nor the engine's pulses per slot (25 on a 56E), nor accelerates faster than its
   ``max_accel``. A feed the machine cannot run is slowed and **said so** (:attr:`PlannedJob.notes`,
   one per program line with the feed it got and the axis that limits it).
4. **Corners.** ``mode = "exact_stop"`` (default, LinuxCNC's ``G61.1``): every segment, arc chords
   included, ends at rest; so does a segment whose feed axes differ from the next one's (XYZ, UVW,
   ABC: their path speeds are in different units). ``mode = "blend"``: corners are passed at the *junction-deviation
   speed* (the rule of grbl and Marlin): the speed at which a circular arc tangent to both segments
   and passing ``tolerance`` from the corner could be taken at the acceleration limit,
   ``v^2 = a * tolerance * sin(theta/2) / (1 - sin(theta/2))`` with ``theta`` the angle between the
   two directions (180 deg: straight on; 0: reversal, stop). The path itself passes every
   programmed point (no rounding of corners); the velocity changes direction in one slot at the
   corner, within what the arc would need. The look-ahead is the chain of segments up to the next
   stop (dwell, spindle change, program end), with the backward pass of
   :mod:`~cosim.controllers.pokeys.trajectory`.
5. **Slots** follow :func:`~cosim.controllers.pokeys.trajectory.profile_chain`: integer speeds in
   path quanta (10^-9 machine units) per slot, exact remainders; ``G4`` adds empty slots
   (``ceil(P * 1000)``); a spindle change takes effect at the slot after the motion before it
   (:attr:`PlannedJob.outputs`).

Corner speeds come from floating point (IEEE 754 operations only, on exact inputs); positions and
counts are exact integers.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from functools import cached_property
from math import isqrt, lcm

from cosim.controllers.pokeys.limits import AXIS_NAMES, MAX_PULSES_PER_SLOT, SLOTS_PER_S
from cosim.controllers.pokeys.toolpath import (
    LINEAR_GROUPS,
    Arc,
    Line,
    Message,
    Output,
    PathControl,
    Pause,
    Point,
    Spindle,
    Toolpath,
    Wait,
    feed_axes,
)
from cosim.controllers.pokeys.trajectory import Counts, Segment, profile_chain
from cosim.errors import ConfigurationError
from cosim.validate import choice, in_range, integer, positive

QUANTA_PER_UNIT = 10**9
"""Path quanta per machine unit (1 pm on a mm machine): the resolution of speeds along the path."""
MODES = ("exact_stop", "blend")
MAX_CHORD_ANGLE = math.pi / 2


@dataclass(frozen=True)
class HostAxis:
    """One axis as the host's motor tuning sets it.

    Parameters
    ----------
    steps_per_unit : number
        Steps (pulses) per machine unit [steps/unit], > 0.
    max_velocity : number
        Highest speed [units/s], > 0 (the engine's pulses per slot bound it too).
    max_accel : number
        Highest acceleration and deceleration [units/s^2], > 0.
    name : str
        For messages.
    """

    steps_per_unit: int | Fraction | float
    max_velocity: int | Fraction | float
    max_accel: int | Fraction | float
    name: str = "x"

    def __post_init__(self) -> None:
        where = f"axis {self.name}"
        positive(self.steps_per_unit, "steps_per_unit", unit="steps/unit", where=where)
        positive(self.max_velocity, "max_velocity", unit="units/s", where=where)
        positive(self.max_accel, "max_accel", unit="units/s^2", where=where)

    @cached_property
    def spu(self) -> Fraction:
        """Steps per unit, exactly."""
        return positive(self.steps_per_unit, "steps_per_unit")

    def steps(self, position: Fraction) -> int:
        """The step a position [units] falls on: nearest, halves away from zero."""
        spu = self.spu  # position * spu = num / den, rounded in integers: floor(x + 1/2), or -floor(-x + 1/2)
        num, den = position.numerator * spu.numerator, position.denominator * spu.denominator
        return (2 * num + den) // (2 * den) if num >= 0 else -((den - 2 * num) // (2 * den))


@dataclass(frozen=True)
class PathSettings:
    """How the host plans a tool path (see the module docstring).

    Parameters
    ----------
    mode : {'exact_stop', 'blend'}
        Stop at every segment end, or pass corners at the junction-deviation speed.
    tolerance : number
        Junction deviation for ``blend`` [units], > 0.
    arc_tolerance : number
        Largest distance between an arc and its chords [units], > 0.
    feed_override : number
        Factor on every programmed feed (0 < f <= 10; rapids are not overridden).
    units : str
        The machine units' name, for notes.
    """

    mode: str = "exact_stop"
    tolerance: int | Fraction | float = Fraction(5, 100)
    arc_tolerance: int | Fraction | float = Fraction(1, 100)
    feed_override: int | Fraction | float = 1
    units: str = "mm"

    def __post_init__(self) -> None:
        choice(self.mode, "mode", MODES)
        positive(self.tolerance, "tolerance", unit="units")
        positive(self.arc_tolerance, "arc_tolerance", unit="units")
        in_range(self.feed_override, "feed_override", low=0, low_open=True, high=10)


@dataclass(frozen=True)
class PlannedJob:
    """A planned tool path: what the host streams and what it found.

    Attributes
    ----------
    counts : list of tuple
        Signed counts per slot, one per engine axis.
    end_steps : tuple of int
        The program's end point [steps] (x, y, z): where the counters end.
    notes : tuple of str
        Feeds the planner slowed, one per program line (``file:line: ...``).
    outputs : tuple of (int, Spindle)
        Spindle states with the index of the slot they start at (``len(counts)``: after the job).
    segments : int
        Straight segments planned (lines and arc chords).
    """

    counts: list[Counts]
    end_steps: tuple[int, ...]
    notes: tuple[str, ...] = ()
    outputs: tuple[tuple[int, Spindle | Output | Message], ...] = ()
    segments: int = 0
    skipped: tuple[str, ...] = field(default=())


def plan_toolpath(toolpath: Toolpath, axes: Sequence[HostAxis], *, settings: PathSettings | None = None,
                  max_pulses_per_slot: int = MAX_PULSES_PER_SLOT, n_axes: int = 3) -> PlannedJob:
    """Plan ``toolpath`` for its ``axes`` (x, y, z and the others of :attr:`Toolpath.axes`, one HostAxis each)
    into per-slot counts of ``n_axes`` engine axes (each tool path axis drives the engine axis of its name).

    Examples
    --------
    >>> from cosim.controllers.pokeys.gcode import read_program
    >>> path = read_program("G21 G90\\nG1 X10 Y5.0013 F600\\nM2")
    >>> job = plan_toolpath(path, [HostAxis(400, 50, 500, name=a) for a in "xyz"])
    >>> [sum(c[a] for c in job.counts) for a in range(3)], job.end_steps   # 5.0013 mm x 400 = 2000.52
    ([4000, 2001, 0], (4000, 2001, 0))
    """
    settings = settings or PathSettings()
    names = toolpath.axes
    if len(axes) != len(names) or not all(isinstance(a, HostAxis) for a in axes):
        raise ConfigurationError.out_of_range("tool path axes", len(axes),
                                              f"{len(names)} HostAxis ({', '.join(names)})")
    integer(max_pulses_per_slot, "max_pulses_per_slot", low=1, high=127, unit="pulses")
    integer(n_axes, "n_axes", low=3, high=len(AXIS_NAMES))
    for name in names:
        if name not in AXIS_NAMES[:n_axes]:
            raise ConfigurationError.out_of_range("tool path axis", name,
                                                  f"an engine axis ({', '.join(AXIS_NAMES[:n_axes])})")
    builder = _Builder(toolpath, list(axes), settings, max_pulses_per_slot, n_axes)
    for step in toolpath.steps:
        if isinstance(step, Line):
            builder.line(step.end, step.feed, step.line)
        elif isinstance(step, Arc):
            builder.arc(step)
        elif isinstance(step, Pause):
            builder.flush()
            slots = math.ceil(step.seconds * SLOTS_PER_S)
            builder.counts.extend([(0,) * n_axes] * slots)
        elif isinstance(step, PathControl):
            builder.path_control(step)
        elif isinstance(step, Wait):
            raise ConfigurationError(f"{toolpath.source}:{step.line}: a tool path that waits on {step.input} is "
                                     "planned piece by piece, as it runs (cosim.controllers.pokeys.gcodejob)")
        else:
            builder.flush()
            builder.outputs.append((len(builder.counts), step))
    builder.flush()
    end = tuple(builder.steps)
    return PlannedJob(builder.counts, end, tuple(builder.notes.values()), tuple(builder.outputs), builder.n_segments,
                      toolpath.skipped)


class _Builder:
    """Collects the segments of the chain up to the next stop, then profiles it."""

    def __init__(self, toolpath: Toolpath, axes: list[HostAxis], settings: PathSettings, limit: int,
                 n_axes: int) -> None:
        self.source = toolpath.source
        self.axes = axes
        self.settings = settings
        self.n_axes = n_axes
        self.names = toolpath.axes
        self.position: Point = (*toolpath.start, *(Fraction(0),) * (len(axes) - len(toolpath.start)))
        self.steps = [a.steps(p) for a, p in zip(axes, self.position, strict=True)]
        self.engine = [AXIS_NAMES.index(name) for name in self.names]  # engine axis of each tool path axis
        self.plain = self.engine == list(range(len(axes)))  # the first axes of the engine, in order
        self.groups = {g: [i for i, name in enumerate(self.names) if name in g] for g in (*LINEAR_GROUPS, "abc")}
        self.spu = [a.spu for a in axes]
        per_slot = [a.spu * positive(a.max_velocity, "max_velocity") / SLOTS_PER_S for a in axes]
        self.engine_bound = [v > limit for v in per_slot]
        self.vlim = [min(v, Fraction(limit)) for v in per_slot]
        self.alim = [a.spu * positive(a.max_accel, "max_accel") / SLOTS_PER_S**2 for a in axes]
        # the same in integers for segment(): a move of d steps is d * unit_factor / unit_den units
        # numerators and denominators read once (Fraction's are properties: a call each time)
        self.vlim_nd = [(v.numerator, v.denominator) for v in self.vlim]
        self.alim_nd = [(a.numerator, a.denominator) for a in self.alim]
        self.wanted: dict[Fraction, tuple[Fraction, int, int]] = {}  # feed -> quanta per slot, as a fraction p / q
        self.unit_den = lcm(*(spu.numerator for spu in self.spu))
        self.unit_factor = [spu.denominator * (self.unit_den // spu.numerator) for spu in self.spu]
        self.override = in_range(settings.feed_override, "feed_override", low=0, low_open=True, high=10)
        self.blend = settings.mode == "blend"
        self.deviation = float(positive(settings.tolerance, "tolerance")) * QUANTA_PER_UNIT
        self.exact_path = False
        self.chain: list[tuple[Segment, tuple[float, ...]]] = []
        self.corner_modes: list[tuple[bool, bool, float]] = []
        self.along: list[int] | None = None  # the feed axes of the last segment
        self.counts: list[Counts] = []
        self.notes: dict[int, str] = {}
        self.outputs: list[tuple[int, Spindle | Output | Message]] = []
        self.n_segments = 0

    def path_control(self, step: PathControl) -> None:
        """G61 / G61.1 / G64 P: how the corners after this point are passed (the machine's tolerance if no P)."""
        self.blend = step.mode == "blend"
        self.exact_path = step.mode == "exact_path"
        tolerance = step.tolerance if step.tolerance is not None else self.settings.tolerance
        self.deviation = float(positive(tolerance, "tolerance")) * QUANTA_PER_UNIT

    # -- geometry --------------------------------------------------------------------------------
    def line(self, end: Point, feed: Fraction | None, line: int) -> None:
        group = feed_axes(self.position, end, self.names)
        self.position = end
        self.segment([a.steps(p) for a, p in zip(self.axes, end, strict=True)], feed, line, group or "xyz")

    def arc(self, arc: Arc) -> None:
        i, j, k = {"xy": (0, 1, 2), "zx": (2, 0, 1), "yz": (1, 2, 0)}[arc.plane]
        start, end = self.position, arc.end
        cx, cy = float(arc.center[0]), float(arc.center[1])
        x0, y0, x1, y1 = float(start[i]) - cx, float(start[j]) - cy, float(end[i]) - cx, float(end[j]) - cy
        r0, r1 = math.hypot(x0, y0), math.hypot(x1, y1)
        a0, a1 = math.atan2(y0, x0), math.atan2(y1, x1)
        full = (start[i], start[j]) == (end[i], end[j])
        sweep = 2 * math.pi if full else ((a0 - a1) if arc.clockwise else (a1 - a0)) % (2 * math.pi)
        sweep += 2 * math.pi * (arc.turns - 1)
        tol = float(positive(self.settings.arc_tolerance, "arc_tolerance"))
        r = max(r0, r1)
        step = MAX_CHORD_ANGLE if tol >= r else min(MAX_CHORD_ANGLE, 2 * math.acos(1 - tol / r))
        n = max(1, math.ceil(sweep / step))
        sign = -1 if arc.clockwise else 1
        z0, z1 = float(start[k]), float(end[k])
        others = [(float(a), float(b)) for a, b in zip(start[3:], end[3:], strict=True)]  # linear with the angle
        for step in range(1, n):
            f = step / n
            angle, radius = a0 + sign * sweep * f, r0 + (r1 - r0) * f
            on_plane = [0.0, 0.0, 0.0]
            on_plane[i], on_plane[j], on_plane[k] = (cx + radius * math.cos(angle), cy + radius * math.sin(angle),
                                                     z0 + (z1 - z0) * f)
            point = (*on_plane, *(a + (b - a) * f for a, b in others))
            self.segment([a.steps(Fraction(p)) for a, p in zip(self.axes, point, strict=True)], arc.feed, arc.line)
        self.line(end, arc.feed, arc.line)

    # -- one segment -----------------------------------------------------------------------------
    def segment(self, target: list[int], feed: Fraction | None, line: int, group: str = "xyz") -> None:
        deltas = [t - s for t, s in zip(target, self.steps, strict=True)]
        if not any(deltas):
            return
        # Exact integer arithmetic throughout (as Fractions would give it, at a tenth of the cost):
        # axis a moves units[a] / den units; the length is the ceiling of the length along the feed axes
        # (XYZ; see feed_axes) in quanta, or of the next group that moves in whole steps.
        den = self.unit_den
        units = [d * f for d, f in zip(deltas, self.unit_factor, strict=True)]
        along = self.groups[group]
        if not any(units[a] for a in along):
            along = next(g for g in self.groups.values() if any(units[a] for a in g))
        square = sum(units[a] * units[a] for a in along) * QUANTA_PER_UNIT**2  # the length^2 in quanta, times den^2
        length = isqrt(square // (den * den))
        length += length * length * den * den < square
        moving = [(a, abs(d)) for a, d in enumerate(deltas) if d]
        # the slowest axis' bound on the path speed, vlim[a] * length / d (the first such axis on a tie)
        best, best_n, best_d = -1, 0, 1
        vlim, alim = self.vlim_nd, self.alim_nd
        for a, d in moving:
            n, m = vlim[a][0] * length, vlim[a][1] * d
            if best < 0 or n * best_d < best_n * m:
                best, best_n, best_d = a, n, m
        accel = max(1, min(alim[a][0] * length // (alim[a][1] * d) for a, d in moving))
        vmax = best_n // best_d
        if feed is not None:
            known = self.wanted.get(feed)
            if known is None:
                wanted = feed * self.override * QUANTA_PER_UNIT / SLOTS_PER_S
                known = self.wanted[feed] = (wanted, wanted.numerator, wanted.denominator)
            wanted, p, q = known
            if p * best_d > best_n * q:  # wanted > best_n / best_d: the axes slow the feed
                self.note(line, wanted, (Fraction(best_n, best_d), best), length, deltas,
                          rotary=along == self.groups["abc"])
            vmax = min(vmax, p // q)
        vmax = max(1, vmax)
        direction = tuple(u / den for u in units)  # correctly rounded, as float(Fraction(u, den))
        norm = math.sqrt(sum(u * u for u in direction))
        start, end = self._engine_counts(self.steps), self._engine_counts(target)
        self.steps = target
        self.chain.append((Segment(start, end, length, vmax, accel, accel), tuple(u / norm for u in direction)))
        # path speeds along different feed axes (mm along XYZ, degrees along ABC) do not meet: a stop between them
        same = self.along in (None, along)
        self.along = along
        self.corner_modes.append((self.blend and same, self.exact_path and same, self.deviation))
        self.n_segments += 1

    def _engine_counts(self, steps: list[int]) -> tuple[int, ...]:
        """Steps of the tool path's axes as a point of the engine's axes (0 on the others)."""
        if self.plain:
            return (*steps, *([0] * (self.n_axes - len(steps))))
        out = [0] * self.n_axes
        for index, value in zip(self.engine, steps, strict=True):
            out[index] = value
        return tuple(out)

    def note(self, line: int, wanted: Fraction, bound: tuple[Fraction, int], length: int, deltas: list[int], *,
             rotary: bool = False) -> None:
        if line in self.notes:
            return
        a = bound[1]
        name = self.axes[a].name
        per_min = 60 * SLOTS_PER_S
        rate = wanted * abs(deltas[a]) / length * SLOTS_PER_S
        units = "deg" if rotary else self.settings.units  # of the feed
        axis_units = "deg" if self.names[a] in "abc" else self.settings.units
        why = (f"the engine's {self.vlim[a]} pulses per slot" if self.engine_bound[a]
               else f"its max_velocity {float(self.vlim[a] * SLOTS_PER_S / self.spu[a]):g} {axis_units}/s")
        self.notes[line] = (f"{self.source}:{line}: feed {float(wanted * per_min / QUANTA_PER_UNIT):g} "
                            f"{units}/min needs {float(rate):.0f} pulses/s on {name}, more than {why}: "
                            f"slowed to {float(bound[0] * per_min / QUANTA_PER_UNIT):g} {units}/min")

    # -- chains ----------------------------------------------------------------------------------
    def flush(self) -> None:
        """Profile the chain collected so far (it ends at rest) and start a new one."""
        if not self.chain:
            return
        segments = [seg for seg, _ in self.chain]
        for k in range(len(segments) - 1):
            blend, exact_path, deviation = self.corner_modes[k + 1]  # the mode in force for the move after the corner
            if not blend and not exact_path:
                continue
            corner = self.corner(segments[k], segments[k + 1], self.chain[k][1], self.chain[k + 1][1], deviation,
                                 straight_only=exact_path)
            segments[k] = Segment(segments[k].start, segments[k].end, segments[k].length, segments[k].vmax,
                                  segments[k].accel, segments[k].decel, corner)
        self.counts.extend(profile_chain(segments))
        self.chain = []
        self.corner_modes = []

    def corner(self, first: Segment, second: Segment, e1: tuple[float, ...], e2: tuple[float, ...],
               deviation: float, *, straight_only: bool = False) -> int:
        """The junction-deviation speed between two segments [quanta/slot] (G61: straight on or rest)."""
        cos_theta = -sum(a * b for a, b in zip(e1, e2, strict=True))
        limit = min(first.vmax, second.vmax)
        if cos_theta < -0.999999:  # straight on
            return limit
        if cos_theta > 0.999999 or straight_only:  # reversal, or a corner under exact path
            return 0
        sin_half = math.sqrt(0.5 * (1 - cos_theta))
        radius = deviation * sin_half / (1 - sin_half)
        return min(limit, math.floor(math.sqrt(min(first.accel, second.accel) * radius)))
