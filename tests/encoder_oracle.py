"""Test oracle: the 1/T position in floats, unclamped and untruncated, to measure an FMU's edge instants.

The product's 1/T extension (:func:`cosim.encoders.extend_one_over_t`) works on integer ticks and
truncates to the hardware's resolution; the FMU tests need the exact float estimate instead, to
show that the FMU's edge instants are right to far below one tick.
"""

from __future__ import annotations


def one_over_t_position(*, edge_count: int, edge_direction: int, t_last_edge_s: float, t_prev_edge_s: float,
                        t_s: float) -> float:
    """Encoder position [counts] at ``t_s`` extended between edges from the edge timestamps.

    ``edge_count + edge_direction * (t - t_last_edge) / (t_last_edge - t_prev_edge)``: the
    fraction of a count is the time since the last edge over the time between the last two, as in
    1/T encoder hardware (which also truncates it to its resolution and clamps it below one
    count; this function does neither). Before there are two edges the edge count is returned.

    Parameters
    ----------
    edge_count : int
        The count boundary the last edge crossed (the FMU's ``edge_count``) [counts].
    edge_direction : int
        +1 or -1 (the FMU's ``edge_direction``).
    t_last_edge_s, t_prev_edge_s : float
        Instants of the last two edges [s].
    t_s : float
        Instant of the estimate [s], at or after the last edge.
    """
    if not t_last_edge_s > t_prev_edge_s:
        return float(edge_count)
    return edge_count + edge_direction * (t_s - t_last_edge_s) / (t_last_edge_s - t_prev_edge_s)
