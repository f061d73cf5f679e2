"""The planner's one speed rule: a chain of straight segments into per-slot counts, in integers.

A chain is a polyline in steps, travelled along one integer path coordinate ``s`` (the
*odometer*): segment ``k`` covers ``length`` path quanta, and an axis inside it is at
``start + trunc(delta * lam / length)`` after ``lam`` quanta of it (truncated towards the
segment's start, as :func:`~cosim.controllers.pokeys.planner.plan_move` always did). Every
segment ends on its end point in whole steps, so the counts of a chain add up to its end point
exactly, whatever the speeds were: the fractional remainder is carried from slot to slot, never
rounded away.

Speeds are integers in quanta per slot, one per slot. Each slot takes the highest speed ``u``

* within the current segment's limits: ``u <= vmax`` and ``v - decel <= u <= v + accel`` (``v``
  the previous slot's speed);
* from which the path can still slow to the corner speed ``W`` at the end of the segment:
  decelerating ``decel`` per slot, the slots faster than ``W`` must end before the corner
  (:func:`~cosim.controllers.pokeys.profile.fastest_arriving`). A slot that reaches or passes a
  corner is therefore never faster than the corner allows. A corner with ``W = 0`` is an exact
  stop: the path lands on it at the end of a slot and starts again from rest.

The corner speeds are first lowered by a backward pass, so that from ``W`` at a corner the path
can slow to the next corner's speed within the next segment; then looking one corner ahead is
enough, and the slot rule never needs more deceleration than ``decel`` (each slot's choice leaves
the next slot's ``u - decel`` feasible). With ``vmax`` below every axis' limit scaled by the
segment's geometry (``vmax * |delta| / length <= limit``), no axis count of a slot exceeds its
limit, also in a slot that passes a corner (its counts are the sum of two parts, each bounded by
its share of the slot). The backward pass uses only integers too.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from operator import sub

from cosim.controllers.pokeys.profile import fastest_arriving
from cosim.errors import ConfigurationError
from cosim.validate import integer

#: Most slots a chain is planned into: 4 hours of 1 ms slots. A job is planned whole before it runs, about
#: 100 bytes a slot, so a longer one is refused with its length instead of filling the memory (a fuzzed arc
#: of 18.5 m radius at F33 would have taken 58 hours: 24 GB, and the process was killed).
MAX_PLANNED_SLOTS = 14_400_000

Counts = tuple[int, ...]


@dataclass(frozen=True)
class Segment:
    """One straight piece of a chain.

    Parameters
    ----------
    start, end : tuple of int
        End points [steps], one per axis.
    length : int
        Path length [quanta], > 0.
    vmax, accel, decel : int
        Speed limit [quanta/slot] and acceleration, deceleration [quanta/slot^2], each >= 1.
    corner : int
        Highest speed at which the path may pass the segment's end [quanta/slot]; 0 = exact stop.
        The last segment of a chain always ends at rest.
    """

    start: tuple[int, ...]
    end: tuple[int, ...]
    length: int
    vmax: int
    accel: int
    decel: int
    corner: int = 0

    def __post_init__(self) -> None:
        for name in ("length", "vmax", "accel", "decel"):
            integer(getattr(self, name), f"segment {name}", low=1)
        integer(self.corner, "segment corner", low=0)
        if len(self.start) != len(self.end):
            raise ConfigurationError.out_of_range("segment end axes", len(self.end), f"{len(self.start)} (as start)")


def corner_speeds(segments: Sequence[Segment]) -> list[int]:
    """The corner speeds the slot rule uses: each segment's ``corner`` lowered by the backward pass."""
    n = len(segments)
    speeds = [0] * n
    for k in range(n - 2, -1, -1):
        here, after = segments[k], segments[k + 1]
        w_next = speeds[k + 1]
        reach = fastest_arriving(after.length - (1 if w_next > 0 else 0), after.decel, w_next)
        speeds[k] = min(here.corner, here.vmax, after.vmax, reach)
    return speeds


def _too_long() -> ConfigurationError:
    return ConfigurationError(f"the job would take more than {MAX_PLANNED_SLOTS:,} slots (4 hours of 1 ms slots) "
                              "at its feeds: cosim plans a job whole before it runs; split the program or raise its "
                              "feeds")


def profile_chain(segments: Sequence[Segment]) -> list[Counts]:
    """Per-slot signed counts of a chain, from rest at its first start point to rest at its last end point."""
    if not segments:
        return []
    corners = corner_speeds(segments)
    n = len(segments)
    k, lam, v = 0, 0, 0
    seg = segments[0]
    pos = list(seg.start)
    out: list[Counts] = []
    # the current segment's numbers, read once per segment (the loop runs once per slot)
    length, vmax, accel, decel, w = seg.length, seg.vmax, seg.accel, seg.decel, corners[0]
    parts = _parts(seg)
    cruise = arriving_distance(vmax, decel, w)  # from this far before the corner on, vmax is not braked
    while not (k == n - 1 and lam == length):
        if len(out) > MAX_PLANNED_SLOTS:
            raise _too_long()
        remaining = length - lam - (1 if w > 0 else 0)
        if v == vmax and remaining >= cruise:  # cruising: the slots at vmax before the brake point or the
            # segment's end, at once (each as below: u = vmax, no corner reached)
            m = min((remaining - cruise) // vmax, (length - 1 - lam) // vmax - 1) + 1
            if len(out) + m > MAX_PLANNED_SLOTS:
                raise _too_long()
            if m > 0:
                lams = range(lam + vmax, lam + (m + 1) * vmax, vmax)
                steps, ends = [], []
                for (s, d), before in zip(parts, pos, strict=True):
                    now = [s + d * x // length for x in lams] if d >= 0 else [s - -d * x // length for x in lams]
                    steps.append(list(map(sub, now, [before, *now[:-1]])))
                    ends.append(now[-1])
                out.extend(zip(*steps, strict=True))
                pos = ends
                lam += m * vmax
                continue
        if remaining >= cruise:  # fastest_arriving(remaining, decel, w) >= vmax: it does not bind
            u = max(max(0, v - decel), min(v + accel, vmax))
        else:
            u = max(max(0, v - decel), min(v + accel, vmax, fastest_arriving(remaining, decel, w)))
        if u <= 0:
            raise RuntimeError(f"planner: no progress at segment {k} of {n} ({seg})")
        lam += u
        landed = False
        if lam >= length and k < n - 1:
            while lam >= length and k < n - 1:
                if corners[k] == 0:
                    if lam != length:
                        raise RuntimeError(f"planner: passed the exact stop at the end of segment {k} ({seg})")
                    landed = True
                lam -= length
                k += 1
                seg = segments[k]
                length = seg.length
            vmax, accel, decel, w = seg.vmax, seg.accel, seg.decel, corners[k]
            parts = _parts(seg)
            cruise = arriving_distance(vmax, decel, w)
        if lam > length:
            raise RuntimeError(f"planner: passed the end of the chain by {lam - length} quanta")
        # each axis at start + trunc(delta * lam / length), truncated towards the segment's start
        now = [s + d * lam // length if d >= 0 else s - -d * lam // length for s, d in parts]
        out.append(tuple(map(sub, now, pos)))
        pos = now
        v = 0 if landed else u
    return out


def arriving_distance(u: int, decel: int, speed: int) -> int:
    """What the slots faster than ``speed`` cover decelerating ``decel`` per slot from ``u`` [quanta]:
    the ``T`` that :func:`~cosim.controllers.pokeys.profile.fastest_arriving` inverts, so
    ``fastest_arriving(remaining, decel, speed) >= u`` wherever ``remaining >= arriving_distance(u, decel, speed)``.

    Examples
    --------
    >>> arriving_distance(6, 1, 3)   # 6, 5, 4 are faster than 3
    15
    >>> arriving_distance(3, 1, 3), arriving_distance(4, 2, 0)
    (0, 6)
    """
    if u <= speed:
        return 0
    m = -(-(u - speed) // decel)  # slots faster than speed: u - j decel > speed for j < m
    return m * u - decel * m * (m - 1) // 2


def _parts(seg: Segment) -> list[tuple[int, int]]:
    """``(start, end - start)`` of each axis of ``seg``."""
    return [(a, b - a) for a, b in zip(seg.start, seg.end, strict=True)]
