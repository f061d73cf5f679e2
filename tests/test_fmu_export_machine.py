"""The exported machine's own bookkeeping, without an FMU: step counts and values at any instant.

    segments recorded (ahead of time) ──> _PulseWatch.position(t) == Trace.positions_at(t)
                                          for t rising, and t - 1 asked after t (a left limit)
"""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from cosim.fmu_export.machine import _PulseWatch, _Watch
from cosim.trace import Trace

segment = st.tuples(st.integers(0, 3), st.integers(1, 400), st.integers(0, 40), st.integers(0, 1))


@settings(max_examples=60, deadline=None)
@given(st.lists(segment, max_size=8), st.integers(1, 37))
def test_the_step_count_at_each_instant_equals_the_traces_pulse_positions(segments: list[tuple[int, int, int, int]],
                                                                         stride: int) -> None:
    trace = Trace()
    trace.declare("dev.x.step", "pulse")
    watch = _PulseWatch()
    t0 = 0
    for gap, duration, count, direction in segments:
        t0 += gap * 100
        trace.record_segment("dev.x.step", t0, duration, count, direction)
        watch.segment(t0, duration, count, direction)
    ticks = list(range(-1, t0 + 500, stride))
    expected = trace.positions_at("dev.x.step", ticks).tolist()
    got = []
    for t in ticks:
        got.append(watch.position(t))
        assert watch.position(t - 1) == trace.positions_at("dev.x.step", [t - 1])[0]
    assert got == expected


def test_a_value_watch_keeps_the_value_before_the_instant_of_its_last_change() -> None:
    watch = _Watch()
    watch.update(0, 0.0)
    watch.update(100, 1.0)
    watch.update(100, 2.0)  # a second change at the same instant: the value before the instant stays 0
    assert (watch.at(100, left=True), watch.at(100, left=False)) == (0.0, 2.0)
    assert watch.at(101, left=True) == 2.0  # a later instant: nothing changed there
