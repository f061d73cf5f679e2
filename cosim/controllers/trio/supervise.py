"""What the servo cycle watches besides the moves: limits, jog inputs, the repeat distance.

At each servo tick, before the moves run (inputs as they are at the tick):

* **Hardware limits** ``FWD_IN`` / ``REV_IN`` (inputs, active low): a move going towards an active
  limit is cancelled (decelerating at DECEL) and the controller's job stops (``trio.job`` LIMIT);
  moves away from it run.
* **Software limits** ``FS_LIMIT`` / ``RS_LIMIT``, on while inside the repeat distance (TRM: "when the
  limit is hit the controller will ramp down the speed to zero then cancel the move"): a move going
  towards a limit DPOS has reached is cancelled the same way.
* **Jog inputs** (see :mod:`.datum`).

After the moves, **REP_DIST**: DPOS and MPOS are kept in ``-REP_DIST..REP_DIST`` (``REP_OPTION`` bit 0:
``0..REP_DIST``) by shifting both by ``2 REP_DIST`` (``REP_DIST``) when the demand leaves the range
[?: the amounts as recalled from the TRM]; the step and encoder counts are not touched.
"""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING, Any

from cosim.controllers.trio.datum import JogMove, jog_direction
from cosim.controllers.trio.status import limits_on
from cosim.job import JobState

if TYPE_CHECKING:
    from cosim.controllers.trio.axis import Axis


def supervised(axis: Axis) -> bool:
    """The axis needs :func:`before_moves` at every tick (limits, jog inputs configured)."""
    p = axis.params
    return p["FWD_IN"] >= 0 or p["REV_IN"] >= 0 or p["FWD_JOG"] >= 0 or p["REV_JOG"] >= 0 or limits_on(axis)


def before_moves(controller: Any, axis: Axis) -> None:
    """Limits and jog inputs of ``axis`` at this tick."""
    read = controller.read_input
    p = axis.params
    direction = axis.direction()
    move = axis.current
    if move is not None and not move.done and direction:
        reason = _limit(axis, read, direction)
        if reason is not None and not move.cancel_requested and not move.cancelling:
            move.cancel_requested = True
            controller.job.stop(JobState.LIMIT, f"axis {axis.number}: {reason} cancels the "
                                                f"{move.kind}{' (' + move.origin + ')' if move.origin else ''}")
    jog = jog_direction(axis, read)
    if isinstance(move, JogMove):
        if jog != move.sign and not move.cancelling:
            move.cancel_requested = True
    elif jog and axis.idle and _limit(axis, read, jog) is None:
        fast = p["FAST_JOG"]
        speed = Fraction(p["SPEED"] if fast >= 0 and not read(fast) else p["JOGSPEED"])
        if speed > 0:
            controller.buffers.start_now(JogMove((axis.number,), jog, speed))


def _limit(axis: Axis, read: Any, direction: int) -> str | None:
    p = axis.params
    channel = p["FWD_IN"] if direction > 0 else p["REV_IN"]
    if channel >= 0 and not read(channel):
        return f"the {'forward' if direction > 0 else 'reverse'} limit ({'FWD_IN' if direction > 0 else 'REV_IN'} " \
               f"input {channel})"
    if limits_on(axis):
        dpos = axis.dpos
        if direction > 0 and dpos >= Fraction(p["FS_LIMIT"]) and Fraction(p["FS_LIMIT"]) < Fraction(p["REP_DIST"]):
            return f"FS_LIMIT = {float(p['FS_LIMIT']):g}"
        if direction < 0 and dpos <= Fraction(p["RS_LIMIT"]) and Fraction(p["RS_LIMIT"]) > -Fraction(p["REP_DIST"]):
            return f"RS_LIMIT = {float(p['RS_LIMIT']):g}"
    return None


def wrap(axis: Axis) -> None:
    """REP_DIST: shift DPOS and MPOS back into range when the demand has left it."""
    rep = axis.params["REP_DIST"]
    units = axis.params["UNITS"]
    span = rep * units  # counts
    position = Fraction(axis.dnum, axis.dden) - axis.origin
    if axis.params["REP_OPTION"] & 1:
        low, high, step = 0, span, span
        if position >= high:
            axis.origin += step
        elif position < low:
            axis.origin -= step
    else:
        if position > span:
            axis.origin += 2 * span
        elif position < -span:
            axis.origin -= 2 * span


def within_range(axis: Axis) -> bool:
    """DPOS is inside the repeat distance (no wrap due), in integers: ``(num a - b den) / (den c)`` is DPOS."""
    a, b, c = axis._scales()
    rep = axis.params["REP_DIST"]
    rn, rd = rep.numerator, rep.denominator
    den = axis.dden
    x = (axis.dnum * a - b * den) * rd  # DPOS * den * c * rd
    span = rn * den * c
    if axis.params["REP_OPTION"] & 1:
        return 0 <= x < span
    return -span <= x <= span
