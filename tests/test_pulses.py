"""The pulse rule of :mod:`cosim.pulses`: pulse k of a segment at ``t0 + offset + (k * duration) // count``."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from cosim.pulses import materialize_pulses


def test_three_and_two_pulses_over_1000_ticks() -> None:
    assert materialize_pulses([0, 1000], [1000, 1000], [3, 2]).tolist() == [0, 333, 666, 1000, 1500]
    assert materialize_pulses([0, 1000], [1000, 1000], [3, 2], offset=5).tolist() == [5, 338, 671, 1005, 1505]
    assert materialize_pulses([0, 1000], [1000, 1000], [3, 2], first=[1, 0], stop=[3, 1]).tolist() == [333, 666, 1000]
    assert materialize_pulses([0], [1000], [0]).tolist() == []


segment = st.tuples(st.integers(0, 10**12), st.integers(1, 10**9), st.integers(0, 40), st.integers(0, 40),
                    st.integers(0, 40), st.integers(-5, 5))


@settings(max_examples=200, deadline=None)
@given(st.lists(segment, max_size=12))
def test_every_pulse_is_where_the_rule_puts_it(segments: list[tuple[int, int, int, int, int, int]]) -> None:
    t0 = [s[0] for s in segments]
    duration = [s[1] for s in segments]
    count = [s[2] for s in segments]
    first = [min(s[3], s[2]) for s in segments]
    stop = [max(f, min(s[4], s[2])) for f, s in zip(first, segments, strict=True)]
    offset = [s[5] for s in segments]
    expected = [t + o + (k * d) // c for t, d, c, f, e, o in zip(t0, duration, count, first, stop, offset, strict=True)
                for k in range(f, e)]
    got = materialize_pulses(t0, duration, count, offset=offset, first=first, stop=stop)
    assert got.tolist() == expected
    assert materialize_pulses(t0, duration, count).tolist() == [
        t + (k * d) // c for t, d, c in zip(t0, duration, count, strict=True) for k in range(c)]
