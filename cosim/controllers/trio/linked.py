"""Moves that follow another axis or the TABLE: CONNECT, MOVELINK, CAMBOX and CAM.

Each runs on the base axis, from the servo tick it is loaded at, one cycle at a time:

* ``CONNECT(ratio, driving axis)``: an electronic gearbox. Each cycle the demand moves by ``ratio``
  counts per count the driving axis' measured position (MPOS, latched at the tick) has moved since
  the connection [?: the ratio in counts per count, as the TRM's "edges of the base axis per edge of
  the driving axis"]. It runs until CANCEL, which lets go and decelerates at DECEL from the speed of the last cycle.
* ``MOVELINK(distance, link dist, link acc, link dec, link axis[, option[, link pos]])``: the axis
  moves ``distance`` [units] while the link axis moves ``link dist`` [its units], speeding up over
  the first ``link acc`` and slowing down over the last ``link dec`` of the link's travel
  (parabolic blends: the position of the base axis is a trapezoid profile whose "time" is the link
  axis' travel).
* ``CAMBOX(start, end, multiplier, link dist, link axis[, option[, link pos]])``: the axis follows the
  TABLE from ``start`` to ``end`` (linearly between the points) as the link axis moves ``link dist``;
  the TABLE values times ``multiplier`` are counts (TRM: TABLE values are in encoder edges; the
  multiplier is usually UNITS), relative to the first point.
* ``CAM(start, end, multiplier, distance)``: the same, over time: the TABLE is run through in
  ``distance / SPEED`` seconds.

Link options (MOVELINK, CAMBOX): 0 starts at once; 1 starts at the registration event of the link
axis (REGIST ... MARK), the link travel counted from its REG_POS; 2 starts when the link axis
reaches ``link pos``. Other options are accepted and listed as not modelled (start at once).
The link travel is signed: a link axis that moves back takes the base axis back along the profile.
"""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING, Any

from cosim.controllers.trio.motion import Move
from cosim.controllers.trio.profile import Stop
from cosim.errors import ConfigurationError

if TYPE_CHECKING:
    from cosim.controllers.trio.axis import Axis


class GenericMove(Move):
    """A move evaluated with exact fractions each cycle (not a straight line: no closed-form window)."""

    def __init__(self, axes: tuple[int, ...], kind: str, values: tuple[Fraction, ...], origin: str = "") -> None:
        super().__init__(axes, kind, values, origin)
        self._straight = None
        self.monotonic = False
        self.axis_list: list[Axis] = []
        self.start_count = Fraction(0)
        self.last = Fraction(0)
        self.period_s = Fraction(1, 1000)

    def load(self, axes: dict[int, Axis], t: int, period_s: Fraction) -> None:
        self.axis_list = [axes[a] for a in self.axes]
        self.axis_objects = tuple(self.axis_list)
        base = self.axis_list[0]
        self.start_count = base.demand
        self.last = self.start_count
        self.start_counts = (self.start_count,)
        self.units = (base.units,)
        self.t_start = t
        self.period_s = period_s
        self._period = (period_s.numerator, period_s.denominator)
        self.begin()

    def begin(self) -> None:
        """Called once the move is loaded."""

    def target(self) -> Fraction:
        """The base axis' demand [counts] at the end of the cycle just counted in :attr:`cycles`."""
        raise NotImplementedError

    def advance(self) -> None:
        self.cycles += 1
        demand = self.target()
        base = self.axis_list[0]
        change = (demand - self.last) / base.units / self.period_s
        self.v_num, self.v_den = change.numerator, change.denominator
        self.last = demand
        self.nums, self.dens = [demand.numerator], [demand.denominator]

    def heading(self, axis: int) -> int:
        """The direction of the last cycle (a generic move has no fixed heading)."""
        return 0

    def stop(self, period_s: Fraction, decel: Fraction) -> None:
        """CANCEL: the axis lets go of what it follows and decelerates at DECEL from the speed of its last
        cycle to rest [?: the TRM's CANCEL of a linked move, with the model's deceleration]."""
        self.cancel_requested = False
        self.cancelling = True
        speed = Fraction(self.v_num, self.v_den)
        sign = 1 if speed >= 0 else -1
        profile = Stop(Fraction(0), Fraction(0), abs(speed), decel)
        start, first = self.last, self.cycles
        units = self.axis_list[0].units

        def stopping() -> Fraction:
            t = (self.cycles - first) * period_s
            if t >= profile.t_end:
                self.done = True
            return start + sign * profile.position(t) * units
        self.target = stopping  # type: ignore[method-assign]


class LinkedMove(GenericMove):
    """CONNECT, MOVELINK, CAMBOX: the base axis follows the link axis' measured position.

    Parameters
    ----------
    link : int
        The link (driving) axis.
    option, link_pos :
        Link option (0, 1, 2) and the position of option 2 [units of the link axis].
    """

    def __init__(self, axes: tuple[int, ...], kind: str, values: tuple[Fraction, ...], origin: str = "", *,
                 link: int, option: int = 0, link_pos: Fraction = Fraction(0), table: Any = None) -> None:
        super().__init__(axes, kind, values, origin)
        self.link = link
        self.option = option
        self.link_pos = link_pos
        self.table = table
        self.link_axis: Axis | None = None
        self.m0: Fraction | None = None  # the link's measured position [counts] where the travel counts from
        self.ratio = values[0] if kind == "CONNECT" else Fraction(0)

    def begin(self) -> None:
        self.link_axis = self.link_axis or self._link()
        if self.option in (0,) or self.kind == "CONNECT":
            self.m0 = self._measured()

    def _link(self) -> Axis:
        raise ConfigurationError("internal: the link axis is set by the controller")  # pragma: no cover

    def _measured(self) -> Fraction:
        assert self.link_axis is not None
        return Fraction(self.link_axis.mnum, self.link_axis.mden)

    def travel(self) -> Fraction | None:
        """The link axis' travel since the link started [its units] (None: not started yet)."""
        link = self.link_axis
        assert link is not None
        if self.m0 is None:
            if self.option == 1 and link.mark:
                self.m0 = link.reg_pos_counts
            elif self.option == 2:
                position = (self._measured() - link.origin) / link.units
                reached = position >= self.link_pos if self.link_pos >= 0 else position <= self.link_pos
                if reached:
                    self.m0 = self.link_pos * link.units + link.origin
            if self.m0 is None:
                return None
        return (self._measured() - self.m0) / link.units

    def target(self) -> Fraction:
        if self.kind == "CONNECT":
            assert self.m0 is not None
            return self.start_count + self.ratio * (self._measured() - self.m0)
        travel = self.travel()
        if travel is None:
            return self.last
        units = self.axis_list[0].units
        if self.kind == "MOVELINK":
            distance, link_dist, link_acc, link_dec = self.values[:4]
            if travel >= link_dist:
                self.done = True
            return self.start_count + movelink_position(travel, distance, link_dist, link_acc, link_dec) * units
        start, end, multiplier, link_dist = self.values[:4]
        if travel >= link_dist:
            self.done = True
        return self.start_count + cam_offset(self.table, start, end, multiplier, travel / link_dist)


class CamMove(GenericMove):
    """CAM: the base axis runs through the TABLE over ``distance / SPEED`` seconds."""

    def __init__(self, axes: tuple[int, ...], values: tuple[Fraction, ...], origin: str = "", *, table: Any,
                 speed: Fraction) -> None:
        super().__init__(axes, "CAM", values, origin)
        self.table = table
        self.speed = speed

    def target(self) -> Fraction:
        start, end, multiplier, distance = self.values[:4]
        covered = self.cycles * self.period_s * self.speed
        if covered >= distance:
            self.done = True
        return self.start_count + cam_offset(self.table, start, end, multiplier, covered / distance)


def movelink_position(travel: Fraction, distance: Fraction, link_dist: Fraction, link_acc: Fraction,
                      link_dec: Fraction) -> Fraction:
    """MOVELINK: the base axis' distance [units] after ``travel`` of the link axis (clamped to the move).

    Examples
    --------
    >>> [float(movelink_position(Fraction(m), Fraction(100), Fraction(200), Fraction(40), Fraction(40))) for m in
    ...  (0, 20, 40, 100, 160, 200, 250)]
    [0.0, 3.125, 12.5, 50.0, 87.5, 100.0, 100.0]
    """
    m = min(max(travel, Fraction(0)), link_dist)
    ratio = distance / (link_dist - link_acc / 2 - link_dec / 2)
    if link_acc and m < link_acc:
        return ratio * m * m / (2 * link_acc)
    if link_dec and m > link_dist - link_dec:
        left = link_dist - m
        return distance - ratio * left * left / (2 * link_dec)
    return ratio * (m - link_acc / 2)


def cam_offset(table: Any, start: Fraction, end: Fraction, multiplier: Fraction, share: Fraction) -> Fraction:
    """The offset [counts] of a CAM / CAMBOX after ``share`` (0..1) of its way through TABLE ``start..end``.

    ``table(n)`` reads TABLE(n); between two points the value is interpolated linearly.

    Examples
    --------
    >>> points = [0, 10, 30, 60]
    >>> [cam_offset(points.__getitem__, Fraction(0), Fraction(3), Fraction(2), Fraction(k, 6)) for k in (0, 1, 3, 6)]
    [Fraction(0, 1), Fraction(10, 1), Fraction(40, 1), Fraction(120, 1)]
    """
    share = min(max(share, Fraction(0)), Fraction(1))
    p = start + (end - start) * share
    i = p.numerator // p.denominator
    value = Fraction(table(i))
    if p != i:
        value += (p - i) * (Fraction(table(i + 1)) - value)
    return (value - Fraction(table(int(start)))) * multiplier
