"""Pulse-train segments and their exact pulse instants.

A controller that holds a pulse frequency over a slot or a servo cycle emits one *segment*
``(t0, duration, count, direction)`` instead of ``count`` events. Its pulses are placed by one
documented rule, in exact integer arithmetic::

    pulse k (k = 0 .. count-1) is at  t0 + offset + (k * duration) // count

so the first pulse of a segment is at ``t0 + offset`` and the pulses are spread evenly over
``duration`` with the integer remainder falling to the later gaps (floor). Pulse instants are
the *active edge* of the step signal.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

IntArray = npt.NDArray[np.int64]


def materialize_pulses(
    seg_t0: npt.ArrayLike,
    seg_duration: npt.ArrayLike,
    seg_count: npt.ArrayLike,
    *,
    offset: npt.ArrayLike = 0,
    first: npt.ArrayLike = 0,
    stop: npt.ArrayLike | None = None,
) -> IntArray:
    """Exact pulse instants of many segments, vectorised (no Python loop).

    Parameters
    ----------
    seg_t0 : array of int
        Segment start times [ticks].
    seg_duration : array of int
        Segment durations [ticks], > 0 where count > 0.
    seg_count : array of int
        Pulses in each segment (>= 0).
    offset : int or array of int
        Offset of the first pulse from ``t0`` [ticks].
    first, stop : int or array of int, optional
        Only pulses ``k = first .. stop-1`` of each segment (default: all, ``0 .. count-1``), placed
        as in the whole segment: for reading a long segment in pieces.

    Returns
    -------
    numpy.ndarray of int64
        Pulse instants [ticks], in segment order.

    Examples
    --------
    >>> materialize_pulses([0, 1000], [1000, 1000], [3, 2]).tolist()
    [0, 333, 666, 1000, 1500]
    >>> materialize_pulses([0, 1000], [1000, 1000], [3, 2], first=[1, 0], stop=[3, 1]).tolist()
    [333, 666, 1000]
    """
    t0 = np.asarray(seg_t0, dtype=np.int64)
    duration = np.asarray(seg_duration, dtype=np.int64)
    count = np.asarray(seg_count, dtype=np.int64)
    if count.size and count.min() < 0:
        raise ValueError(f"seg_count has a negative value {int(count.min())} (allowed: >= 0)")
    k_first = np.broadcast_to(np.asarray(first, dtype=np.int64), t0.shape)
    k_stop = count if stop is None else np.broadcast_to(np.asarray(stop, dtype=np.int64), t0.shape)
    taken = k_stop - k_first
    total = int(taken.sum())
    if total == 0:
        return np.empty(0, dtype=np.int64)
    # Each segment's values repeated over its pulses (np.repeat streams; indexing by a segment number gathers),
    # the arithmetic in place: k, then k * duration, then // count, then + t0 + offset.
    starts = np.cumsum(taken) - taken
    k = np.arange(total, dtype=np.int64)
    k -= np.repeat(starts - k_first, taken)
    k *= np.repeat(duration, taken)
    k //= np.repeat(count, taken)
    k += np.repeat(t0 + np.broadcast_to(np.asarray(offset, dtype=np.int64), t0.shape), taken)
    return k
