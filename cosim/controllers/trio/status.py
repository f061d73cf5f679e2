"""What an axis reports about itself: AXISSTATUS bits, MTYPE / NTYPE, REMAIN.

AXISSTATUS (TRM: RS_LIMIT sets bit 10; SERVO on a stepper sets the following error bit; the other
bits as the status table lists them [?: the table itself was not re-read]):

=====  =====  ==================================================================
bit    value  set while
=====  =====  ==================================================================
4      16     the forward hardware limit (FWD_IN) is active
5      32     the reverse hardware limit (REV_IN) is active
6      64     a DATUM sequence runs
8      256    the following error exceeded FE_LIMIT (until DATUM(0))
9      512    DPOS is at or beyond FS_LIMIT (while the software limits are on)
10     1024   DPOS is at or below RS_LIMIT
11     2048   the running move is being cancelled (decelerating to rest)
=====  =====  ==================================================================
"""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from cosim.controllers.trio.axis import Axis

#: MTYPE / NTYPE values by move kind [?: the model's numbering where the manual's table was not at hand].
MOVE_TYPES = {"MOVE": 1, "MOVEABS": 2, "MOVECIRC": 4, "FORWARD": 10, "REVERSE": 11, "DATUM": 12, "CAM": 13,
              "FWD_JOG": 14, "REV_JOG": 15, "CAMBOX": 20, "CONNECT": 21, "MOVELINK": 22}

FWD_LIMIT, REV_LIMIT, DATUMING, FE_EXCEEDED, FS_BIT, RS_BIT, CANCELLING = 16, 32, 64, 256, 512, 1024, 2048


def limits_on(axis: Axis) -> bool:
    """The software limits act while they are inside the repeat distance (TRM)."""
    rep = Fraction(axis.params["REP_DIST"])
    return Fraction(axis.params["FS_LIMIT"]) < rep or Fraction(axis.params["RS_LIMIT"]) > -rep


def axis_status(controller: Any, axis: Axis) -> int:
    """The AXISSTATUS of ``axis`` now (see the module doc)."""
    bits = 0
    read = controller.read_input
    fwd, rev = axis.params["FWD_IN"], axis.params["REV_IN"]
    if fwd >= 0 and not read(fwd):
        bits |= FWD_LIMIT
    if rev >= 0 and not read(rev):
        bits |= REV_LIMIT
    move = axis.current
    if move is not None and move.kind == "DATUM" and not move.done:
        bits |= DATUMING
    if axis.fe_exceeded:
        bits |= FE_EXCEEDED
    rep = Fraction(axis.params["REP_DIST"])
    dpos = axis.dpos
    fs, rs = Fraction(axis.params["FS_LIMIT"]), Fraction(axis.params["RS_LIMIT"])
    if fs < rep and dpos >= fs:
        bits |= FS_BIT
    if rs > -rep and dpos <= rs:
        bits |= RS_BIT
    if move is not None and (move.cancelling or move.cancel_requested) and not move.done:
        bits |= CANCELLING
    return bits


def move_type(move: Any) -> int:
    """MTYPE / NTYPE of ``move`` (0: none)."""
    return 0 if move is None else MOVE_TYPES.get(move.kind, 0)


def remaining(axis: Axis) -> Fraction:
    """REMAIN: the distance to the end of the running move along its path [units] (0: none or endless)."""
    move = axis.current
    if move is None or move.end_s is None or move.profile is None:
        return Fraction(0)
    return move.end_s - move.travelled
