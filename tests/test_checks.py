"""Timing checks: each rule on a passing and a failing trace, with the exact violations it reports."""

from __future__ import annotations

import dataclasses
import doctest
import json
import textwrap
from collections.abc import Callable, Iterable, Mapping
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

import cosim.checks
from cosim.checks import (
    MAX_REPORTED,
    Bound,
    Check,
    CheckResult,
    DirectionSetup,
    Duration,
    EdgeAtPosition,
    EdgeRef,
    IntervalsAbove,
    IntervalsBelow,
    MaxPulseRate,
    MinPulseSpacing,
    NoUnderrun,
    PulseRef,
    PulsesPerWindow,
    ValueAt,
    Violation,
    base,
    direction,
    duration,
    edge_position,
    levels,
    pulse_timing,
    result,
)
from cosim.controllers.pokeys import EngineState, PulseEngine, encode_entry
from cosim.errors import ConfigurationError
from cosim.kernel import Simulation
from cosim.runner import run_scenario
from cosim.scenario import load
from cosim.signals import PulseTrain, Signal
from cosim.timebase import TimeBase
from cosim.trace import Trace

STEP = "dev.x.step"
DIR = "dev.x.dir"


def make_trace(*, pulses: Mapping[str, Iterable[tuple[int, int]]] | None = None,
               segments: Mapping[str, Iterable[tuple[int, int, int, int]]] | None = None,
               signals: Mapping[str, tuple[str, Iterable[tuple[int, float]]]] | None = None,
               end_t: int = 0, timebase: TimeBase | None = None) -> Trace:
    """A trace from literal lists: pulses ``(t, dir)``, segments ``(t0, duration, count, dir)``, records ``(t, v)``."""
    trace = Trace(timebase)
    for name, items in (pulses or {}).items():
        trace.declare(name, "pulse")
        for t, d in items:
            trace.record_pulse(name, t, d)
    for name, segs in (segments or {}).items():
        if name not in trace.info:
            trace.declare(name, "pulse")
        for t0, dur, count, d in segs:
            trace.record_segment(name, t0, dur, count, d)
    for name, (kind, recs) in (signals or {}).items():
        trace.declare(name, kind)
        for t, v in recs:
            trace.record(name, t, v)
    trace.end_t = end_t
    return trace


def steps(*times: int, d: int = 1) -> dict[str, list[tuple[int, int]]]:
    return {STEP: [(t, d) for t in times]}


def found(res: CheckResult) -> list[tuple[int, float, float | str]]:
    """The reported violations as ``(t_ns, value, limit)``."""
    return [(v.t_ns, v.value, v.limit) for v in res.violations]


# -- results ----------------------------------------------------------------------------------
def test_result_dict_has_exactly_the_runner_fields_in_plain_json_types() -> None:
    trace = make_trace(pulses=steps(0, 1000, 1400))
    data = MinPulseSpacing(STEP, 500).evaluate(trace).to_dict()
    assert set(data) == {"name", "outcome", "passed", "checked", "n_violations", "violations", "measured", "signal",
                         "description", "nothing_checked"}
    assert data == {
        "name": "MinPulseSpacing(dev.x.step)", "outcome": "FAIL", "passed": False, "checked": 3, "n_violations": 1,
        "violations": [{"t_ns": 1400, "value": 400, "limit": 500,
                        "detail": "pulse 2 only 400 ns after pulse 1 at 1000 ns", "unit": "ns"}],
        "measured": {"min_spacing_ns": 400}, "signal": STEP,
        "description": "dev.x.step: pulses at least 500 ns apart", "nothing_checked": "",
    }
    assert json.loads(json.dumps(data)) == data  # plain ints, no numpy scalars
    assert all(type(v) is int for v in (data["checked"], data["violations"][0]["t_ns"], data["violations"][0]["value"]))


def test_summary_is_one_line() -> None:
    trace = make_trace(pulses=steps(0, 1000, 1400))
    assert MinPulseSpacing(STEP, 500, name="x spacing").evaluate(trace).summary() == (
        "FAIL x spacing: 3 checked, 1 violation; first at t=1400 ns: 400 vs limit 500 "
        "(pulse 2 only 400 ns after pulse 1 at 1000 ns)")
    assert MinPulseSpacing(STEP, 400).evaluate(trace).summary() == (
        "PASS MinPulseSpacing(dev.x.step): 3 checked, 0 violations")


def test_only_the_first_twenty_violations_are_listed_but_all_are_counted() -> None:
    trace = make_trace(segments={STEP: [(0, 3000, 31, 1)]})  # 30 gaps of 96 or 97 ns
    res = MinPulseSpacing(STEP, 100).evaluate(trace)
    assert res.n_violations == 30 and len(res.violations) == MAX_REPORTED == 20
    assert len(res.to_dict()["violations"]) == 20
    assert [v.t_ns for v in res.violations] == [(k * 3000) // 31 for k in range(1, 21)]


def test_violation_to_dict_converts_numpy_scalars() -> None:
    v = Violation(np.int64(5), np.float64(1.5), np.int64(2), "x")  # type: ignore[arg-type]
    assert v.to_dict() == {"t_ns": 5, "value": 1.5, "limit": 2, "detail": "x"}
    assert type(v.to_dict()["limit"]) is int


# -- empty signals, unknown signals, wrong kinds ----------------------------------------------------
EMPTY_CASES: list[tuple[Callable[[], Check], str]] = [
    (lambda: MinPulseSpacing(STEP, 10), STEP),
    (lambda: MaxPulseRate(STEP, 1000), STEP),
    (lambda: MaxPulseRate(STEP, 1000, window=100), STEP),
    (lambda: PulsesPerWindow(STEP, 5, 100), STEP),
    (lambda: DirectionSetup(STEP, DIR, 10), STEP),
    (lambda: EdgeAtPosition("dev.x.gate", STEP, [], 0), "dev.x.gate"),
    (lambda: Bound("dev.x.level", lower=0), "dev.x.level"),
    (lambda: NoUnderrun("dev.x.level"), "dev.x.level"),
    (lambda: IntervalsAbove("dev.x.level", 3), "dev.x.level"),
    (lambda: ValueAt("dev.x.level", 100, 0), "dev.x.level"),
]


def _empty_trace() -> Trace:
    return make_trace(pulses={STEP: []}, signals={DIR: ("bit", []), "dev.x.gate": ("bit", []),
                                                  "dev.x.level": ("int", [])})


@pytest.mark.parametrize(("make", "signal"), EMPTY_CASES)
def test_a_check_that_examined_nothing_neither_passes_nor_fails(make: Callable[[], Check], signal: str) -> None:
    res = make().evaluate(_empty_trace())
    assert (res.outcome, res.passed, res.checked, res.n_violations, res.violations) == ("UNCHECKED", False, 0, 0, ())
    assert res.nothing_checked == f"signal {signal} had no data: nothing was checked"
    assert res.summary() == f"UNCHECKED {res.name}: 0 checked (signal {signal} had no data: nothing was checked)"


@pytest.mark.parametrize(("make", "signal"), EMPTY_CASES)
def test_allow_empty_accepts_an_empty_signal(make: Callable[[], Check], signal: str) -> None:
    res = dataclasses.replace(make(), allow_empty=True).evaluate(_empty_trace())
    assert res.passed and res.outcome == "PASS" and res.checked == 0 and res.violations == ()
    assert res.nothing_checked == ""
    assert res.summary() == f"PASS {res.name}: 0 checked (nothing to examine; allowed for this check)"


def test_duration_without_a_start_event_is_unchecked_saying_so() -> None:
    trace = make_trace(signals={"dev.limit": ("bit", [(0, 0)])}, pulses=steps(100))
    res = Duration(EdgeRef("dev.limit", 1), PulseRef(STEP, "last"), max=500).evaluate(trace)
    assert res.outcome == "UNCHECKED" and not res.passed and res.checked == 0 and res.violations == ()
    assert res.nothing_checked == "no change of dev.limit to 1 in the trace: nothing was measured"


def test_unknown_signal_names_it_the_check_and_close_names() -> None:
    trace = make_trace(pulses=steps(0))
    with pytest.raises(KeyError, match=r"MinPulseSpacing\(dev\.x\.stp\): no signal named 'dev\.x\.stp' in the "
                                       r"trace; did you mean dev\.x\.step\?"):
        MinPulseSpacing("dev.x.stp", 10).evaluate(trace)
    with pytest.raises(KeyError, match=r"did you mean dev\.x\.step"):
        DirectionSetup(STEP, "dev.x.step_dir", 10).evaluate(trace)


def test_a_signal_of_the_wrong_kind_is_a_configuration_error() -> None:
    trace = make_trace(signals={DIR: ("bit", [(0, 1)])})
    with pytest.raises(ConfigurationError, match=r"signal dev\.x\.dir is a bit signal; this check needs a pulse"):
        MinPulseSpacing(DIR, 10).evaluate(trace)


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: MinPulseSpacing(STEP, 0), r"MinPulseSpacing\(dev\.x\.step\): min_spacing = 0 is not allowed "
                                           r"\(allowed: >= 1 ticks\)"),
        (lambda: MinPulseSpacing(STEP, 1.5),  # type: ignore[arg-type]
         r"min_spacing = 1\.5 is not allowed \(allowed: an integer number"),
        (lambda: MaxPulseRate(STEP, 0), r"max_rate_hz = 0 is not allowed \(allowed: > 0\)"),
        (lambda: MaxPulseRate(STEP, float("nan")), r"max_rate_hz = nan is not allowed"),
        (lambda: MaxPulseRate(STEP, 10, window=0), r"window = 0 is not allowed"),
        (lambda: PulsesPerWindow(STEP, -1, 100), r"max_count = -1 is not allowed \(allowed: >= 0\)"),
        (lambda: PulsesPerWindow(STEP, 25, 0), r"window = 0 is not allowed \(allowed: >= 1 ticks\)"),
        (lambda: DirectionSetup(STEP, DIR, -5), r"setup = -5 is not allowed"),
        (lambda: DirectionSetup(STEP, DIR, 5, positive_level=2), r"positive_level = 2 is not allowed \(allowed: 0, 1"),
        (lambda: EdgeAtPosition("d.gate", STEP, [(10, 2)], 0), r"expected\[0\] value = 2 is not allowed"),
        (lambda: EdgeAtPosition("d.gate", STEP, [(10, 1)], 0, times=[5]), r"times and tol_time go together"),
        (lambda: EdgeAtPosition("d.gate", STEP, [(10, 1)], 0, tol_time=5, times=[5, 6]),
         r"len\(times\) = 2 is not allowed \(allowed: 1 \(one per expected edge\)\)"),
        (lambda: Bound("d.err"), r"Bound\(d\.err\): give lower, upper or both"),
        (lambda: Bound("d.err", lower=2, upper=1), r"lower = 2 is not allowed \(allowed: <= upper \(1\)\)"),
        (lambda: IntervalsBelow("d.lvl", 1, max_duration=-1), r"max_duration = -1 is not allowed"),
        (lambda: IntervalsBelow("d.lvl", 1, start=10, until=10), r"start = 10 is not allowed \(allowed: < until"),
        (lambda: ValueAt("d.lvl", 10, 0, tol=-1), r"tol = -1 is not allowed \(allowed: >= 0\)"),
        (lambda: Duration(EdgeRef("d.a"), EdgeRef("d.b")), r"give min, max or equals"),
        (lambda: Duration(EdgeRef("d.a"), EdgeRef("d.b"), equals=5, max=9), r"equals \(with tol\) excludes"),
        (lambda: Duration(EdgeRef("d.a"), EdgeRef("d.b"), min=9, max=5), r"min = 9 is not allowed"),
        (lambda: EdgeRef("d.a", which="all"), r"which = 'all' is not allowed \(allowed: each, first, last\)"),
        # non-finite and absurdly large numbers (issue 22): our error, never a crash
        (lambda: IntervalsBelow("d.lvl", float("nan")),
         r"^IntervalsBelow\(d\.lvl\): threshold = nan is not allowed \(allowed: a finite number\)$"),
        (lambda: Bound("d.err", upper=float("inf")), r"^Bound\(d\.err\): upper = inf is not allowed"),
        (lambda: ValueAt("d.lvl", 10, float("nan")), r"^ValueAt\(d\.lvl\): expected = nan is not allowed"),
        (lambda: ValueAt("d.lvl", 10, 0, tol=float("nan")), r"^ValueAt\(d\.lvl\): tol = nan is not allowed"),
        (lambda: MaxPulseRate(STEP, 10**5000),
         r"max_rate_hz = 1e\+5000 is not allowed \(allowed: a finite number of magnitude <= 1e300\)$"),
        (lambda: EdgeRef("d.a", value=10**5000),  # type: ignore[arg-type]
         r"^change of d\.a: value = 1e\+5000 is not allowed \(allowed: a finite number\)$"),
        (lambda: Duration(EdgeRef("d.a"), EdgeRef("d.b"), max=float("nan")),  # type: ignore[arg-type]
         r"max = nan is not allowed \(allowed: an integer number of ticks\)$"),
    ],
)
def test_bad_parameters_name_the_parameter_value_and_range(make: Callable[[], object], message: str) -> None:
    with pytest.raises(ConfigurationError, match=message):
        make()


# -- MinPulseSpacing ---------------------------------------------------------------------------------
def test_min_pulse_spacing_passes_at_exactly_the_limit() -> None:
    """t [ns]: 0 | 1000 | 2000 | 3000 |   -> gaps 1000, min 1000."""
    res = MinPulseSpacing(STEP, 1000).evaluate(make_trace(pulses=steps(0, 1000, 2000, 3000)))
    assert res.passed and res.checked == 4 and res.measured == {"min_spacing_ns": 1000}


def test_min_pulse_spacing_reports_each_pulse_that_came_too_early() -> None:
    """t [ns]: 0 | 1000 | 1400 | 2400 | 2500 |   gaps 1000, 400!, 1000, 100!"""
    res = MinPulseSpacing(STEP, 500).evaluate(make_trace(pulses=steps(0, 1000, 1400, 2400, 2500)))
    assert found(res) == [(1400, 400, 500), (2500, 100, 500)]
    assert res.n_violations == 2 and res.measured == {"min_spacing_ns": 100}


def test_min_pulse_spacing_follows_the_segment_placement_rule(sim: Simulation) -> None:
    """Two 3-pulse segments of 1 us: pulse k at t0 + (k*1000)//3.

    t [ns]   0     333   666   1000  1333  1666
    step     |     |     |     |     |     |
    gap         333   333   334   333   333
    """
    step = PulseTrain(sim, STEP)
    step.emit(0, 1000, 3, 1)
    step.emit(1000, 1000, 3, 1)
    res = MinPulseSpacing(STEP, 334).evaluate(sim.trace)
    assert [(v.t_ns, v.value) for v in res.violations] == [(333, 333), (666, 333), (1333, 333), (1666, 333)]
    assert MinPulseSpacing(STEP, 333).evaluate(sim.trace).passed


# -- MaxPulseRate ------------------------------------------------------------------------------------
def test_max_rate_is_exact_at_the_limit() -> None:
    """25 kHz allows 40 000 ns spacing; 39 999 ns is too fast.

    t [ns]: 0 | 40000 | 79999 |
    """
    res = MaxPulseRate(STEP, 25_000).evaluate(make_trace(pulses=steps(0, 40_000, 79_999)))
    assert found(res) == [(79_999, 1e9 / 39_999, 25_000)]
    assert res.measured == {"max_rate_hz": 1e9 / 39_999}
    assert MaxPulseRate(STEP, 25_000).evaluate(make_trace(pulses=steps(0, 40_000, 80_000))).passed


def test_max_rate_uses_integer_arithmetic_where_the_period_is_not_whole() -> None:
    """3 Hz: 1/3 s = 333 333 333.3 ns, so 333 333 334 ns is the shortest allowed spacing."""
    ok = make_trace(pulses=steps(0, 333_333_334, 666_666_668))
    assert MaxPulseRate(STEP, 3).evaluate(ok).passed
    bad = make_trace(pulses=steps(0, 333_333_334, 666_666_667))
    assert [v.t_ns for v in MaxPulseRate(STEP, 3).evaluate(bad).violations] == [666_666_667]
    assert MaxPulseRate(STEP, Fraction(3)).evaluate(bad).n_violations == 1


def test_max_rate_on_a_10_ns_time_base_reports_nanoseconds() -> None:
    """Ticks of 10 ns: 25 kHz needs 4000 ticks; a gap of 3999 ticks at tick 7999 = 79 990 ns."""
    trace = make_trace(pulses=steps(0, 4000, 7999), timebase=TimeBase(Fraction(1, 10**8)))
    res = MaxPulseRate(STEP, 25_000).evaluate(trace)
    assert found(res) == [(79_990, 1e8 / 3999, 25_000)]
    assert res.violations[0].detail == "pulse 2 39990 ns after the one before (at least 40000 ns needed)"


def test_two_pulses_at_the_same_tick_are_an_infinite_rate() -> None:
    res = MaxPulseRate(STEP, 1e6).evaluate(make_trace(pulses=steps(0, 1000, 1000)))
    assert found(res) == [(1000, float("inf"), 1_000_000)]


def test_windowed_rate_averages_over_the_window() -> None:
    """25 kHz over 1 ms = at most 25 pulses in any [t, t + 1 ms) starting at a pulse.

    A 30 us gap is too fast instantaneously but fine on average.
    """
    jitter = make_trace(pulses=steps(0, 30_000, 80_000))
    assert not MaxPulseRate(STEP, 25_000).evaluate(jitter).passed
    assert MaxPulseRate(STEP, 25_000, window=1_000_000).evaluate(jitter).passed
    even = make_trace(segments={STEP: [(0, 1_000_000, 25, 1), (1_000_000, 1_000_000, 25, 1)]})
    res = MaxPulseRate(STEP, 25_000, window=1_000_000).evaluate(even)
    assert res.passed and res.measured == {"max_rate_hz": 25_000.0, "max_pulses_per_window": 25}


def test_windowed_rate_reports_the_window_that_holds_too_many() -> None:
    """26 pulses in [0, 1 ms): the window starting at pulse 0 holds 26, the one at pulse 1 only 25."""
    res = MaxPulseRate(STEP, 25_000, window=1_000_000).evaluate(make_trace(segments={STEP: [(0, 1_000_000, 26, 1)]}))
    assert found(res) == [(0, 26_000.0, 25_000)]
    assert res.violations[0].detail == "26 pulses in [0, 1000000) ns, at most 25 allowed"


# -- PulsesPerWindow ---------------------------------------------------------------------------------
def test_pulses_per_window_passes_with_25_per_slot() -> None:
    res = PulsesPerWindow(STEP, 25, 1_000_000).evaluate(
        make_trace(segments={STEP: [(0, 1_000_000, 25, 1), (1_000_000, 1_000_000, 25, 0)]}))
    assert res.passed and res.checked == 50
    assert res.measured == {"max_pulses_per_window": 25, "windows_with_pulses": 2}


def test_pulses_per_window_reports_the_overfull_slot_at_its_start() -> None:
    """slot 0 [0, 1 ms): 25 pulses; slot 1 [1 ms, 2 ms): 26 pulses."""
    trace = make_trace(segments={STEP: [(0, 1_000_000, 25, 1), (1_000_000, 1_000_000, 26, 1)]})
    res = PulsesPerWindow(STEP, 25, 1_000_000).evaluate(trace)
    assert found(res) == [(1_000_000, 26, 25)]
    assert res.violations[0].detail == "26 pulses in [1000000, 2000000) ns"


def test_pulses_per_window_aligns_windows_on_start_and_counts_pulses_before_it() -> None:
    """Windows of 1000 ns from start=500: [-500, 500) [500, 1500) [1500, 2500).

    t [ns]:  0 100 | 600 700 1400 | 1500 1600
    count:   2     | 3 (too many) | 2
    """
    trace = make_trace(pulses=steps(0, 100, 600, 700, 1400, 1500, 1600))
    res = PulsesPerWindow(STEP, 2, 1000, start=500).evaluate(trace)
    assert found(res) == [(500, 3, 2)] and res.checked == 7


# -- DirectionSetup ----------------------------------------------------------------------------------
DIR_EDGES = ("bit", [(0, 1), (1000, 0), (3000, 1)])


def test_direction_setup_passes_with_enough_setup() -> None:
    """setup 1000 ns; the initial level counts as held since before the run.

    t [ns]   0    100  500  1000      2000      3000      4000 4500
    dir      1‾‾‾‾‾‾‾‾‾‾‾‾‾‾0_________________ 1‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾
    step          +    +              -                   +    +
    """
    trace = make_trace(pulses={STEP: [(100, 1), (500, 1), (2000, 0), (4000, 1), (4500, 1)]},
                       signals={DIR: DIR_EDGES})
    res = DirectionSetup(STEP, DIR, 1000).evaluate(trace)
    assert res.passed and res.checked == 5
    assert res.measured == {"min_setup_ns": 1000, "setup_violations": 0, "direction_mismatches": 0}


def test_direction_setup_reports_short_setup_and_wrong_direction() -> None:
    """t [ns]   0       1000  1500  2000      3000  3200
    dir         1‾‾‾‾‾‾‾0_______________________1‾‾‾‾‾‾‾‾
    step                      -     +!           +
                        500 ns <1000   level 0 but dir 1   200 ns < 1000
    """
    trace = make_trace(pulses={STEP: [(1500, 0), (2000, 1), (3200, 1)]}, signals={DIR: DIR_EDGES})
    res = DirectionSetup(STEP, DIR, 1000).evaluate(trace)
    assert found(res) == [(1500, 500, 1000), (2000, 0, 1), (3200, 200, 1000)]
    assert [v.detail for v in res.violations] == [
        "pulse 0: dev.x.dir changed to 0 at 1000 ns, only 500 ns before",
        "pulse 1: dir 1 but dev.x.dir is 0",
        "pulse 2: dev.x.dir changed to 1 at 3000 ns, only 200 ns before",
    ]
    assert res.measured == {"min_setup_ns": 200, "setup_violations": 2, "direction_mismatches": 1}


def test_direction_change_at_the_pulse_tick_is_zero_setup_and_wrong_direction() -> None:
    trace = make_trace(pulses={STEP: [(1000, 1)]}, signals={DIR: DIR_EDGES})
    res = DirectionSetup(STEP, DIR, 10).evaluate(trace)
    assert found(res) == [(1000, 0, 10)]
    assert res.violations[0].detail.endswith("only 0 ns before; pulse dir 1 needs level 1, level is 0")


def test_inverted_direction_polarity_and_pulses_before_the_first_direction_record() -> None:
    """positive_level=0: level 0 means dir 1. The direction is first recorded at 100 ns."""
    trace = make_trace(pulses={STEP: [(50, 1), (200, 1), (300, 0)]}, signals={DIR: ("bit", [(100, 0)])})
    res = DirectionSetup(STEP, DIR, 0, positive_level=0).evaluate(trace)
    assert found(res) == [(50, 0, 0), (300, 0, 1)]
    assert [v.detail for v in res.violations] == ["pulse 0: dev.x.dir has no value yet",
                                                  "pulse 2: dir 0 but dev.x.dir is 0"]


def test_direction_setup_on_a_simulated_controller(sim: Simulation) -> None:
    """A controller reverses: direction at 10 us, next pulses 2 us later (setup 2 us holds, 3 us does not)."""
    step = PulseTrain(sim, STEP)
    dir_out = Signal(sim, DIR, initial=1)

    def reverse() -> object:
        step.emit(0, 10_000, 10, 1)
        yield sim.at(10_000)
        dir_out.set(0)
        step.emit(12_000, 10_000, 10, 0)

    sim.process(reverse())  # type: ignore[arg-type]
    sim.run(until=30_000)
    assert DirectionSetup(STEP, DIR, 2_000).evaluate(sim.trace).passed
    assert DirectionSetup(STEP, DIR, 3_000).evaluate(sim.trace).violations[0] == Violation(
        12_000, 2_000, 3_000, "pulse 10: dev.x.dir changed to 0 at 10000 ns, only 2000 ns before", unit="ns")


# -- EdgeAtPosition ----------------------------------------------------------------------------------
GATE = "dev.x.gate"
# pulse k at 100*(k+1) ns: the position at t (pulses at t included) is t // 100
RAMP = {STEP: [(100, 10_000, 100, 1)]}


def test_edges_at_their_positions_pass() -> None:
    """position = t // 100.   gate rises at 1000 ns (pos 10), falls at 5000 ns (pos 50)."""
    trace = make_trace(segments=RAMP, signals={GATE: ("bit", [(0, 0), (1000, 1), (5000, 0)])})
    res = EdgeAtPosition(GATE, STEP, [(10, 1), (50, 0)], 0).evaluate(trace)
    assert res.passed and res.checked == 2
    assert res.measured == {"worst_position_error_counts": 0, "edges_expected": 2, "edges_found": 2}


def test_missing_and_extra_edges_are_violations() -> None:
    """tol 2 counts.

    t [ns]   0     1000 1030 1060            5300
    gate     0_____1‾‾‾‾0____1‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾0____
    pos            10   10   10              53    expected: rise at 10, fall at 50
    """
    gate = ("bit", [(0, 0), (1000, 1), (1030, 0), (1060, 1), (5300, 0)])
    res = EdgeAtPosition(GATE, STEP, [(10, 1), (50, 0)], 2).evaluate(make_trace(segments=RAMP, signals={GATE: gate}))
    assert found(res) == [(1000, 50, "edge to 0 at 50 ± 2 counts"), (1030, 10, "no edge"), (1060, 10, "no edge"),
                          (5300, 53, "no edge")]
    assert res.violations[0].detail == "missing edge 1: no change to 0 within ±2 counts of position 50"
    assert res.violations[3].detail == "unexpected edge to 0 at position 53"
    assert res.n_violations == 4 and res.checked == 5
    assert res.measured["worst_position_error_counts"] == 0


def test_edge_position_follows_the_signed_pulse_count_through_a_reversal() -> None:
    """10 pulses up (100..1000 ns), then 10 down (1100..2000 ns): position 5 is passed twice.

    t [ns]   0    500   1000  1500   2000
    pos      0     5     10     5      0
    gate     0_____1‾‾‾‾‾‾‾‾‾‾‾‾0_______       expected: rise at 5, fall at 5 (on the way back)
    """
    segments = {STEP: [(100, 1000, 10, 1), (1100, 1000, 10, 0)]}
    good = make_trace(segments=segments, signals={GATE: ("bit", [(0, 0), (500, 1), (1500, 0)])})
    assert EdgeAtPosition(GATE, STEP, [(5, 1), (5, 0)], 0).evaluate(good).passed
    late = make_trace(segments=segments, signals={GATE: ("bit", [(0, 0), (500, 1), (1700, 0)])})
    res = EdgeAtPosition(GATE, STEP, [(5, 1), (5, 0)], 1).evaluate(late)
    assert found(res) == [(500, 5, "edge to 0 at 5 ± 1 counts"), (1700, 3, "no edge")]


def test_edge_times_against_an_int_position_signal() -> None:
    """Position register: 10 at 1000 ns, 50 at 4800 ns; the fall is expected at 5000 ± 100 ns.

    t [ns]   0     1000            4800   5000
    pos      0     10              50
    gate     0_____1‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾0                   200 ns early
    """
    trace = make_trace(signals={"dev.x.pos": ("int", [(0, 0), (1000, 10), (4800, 50)]),
                                GATE: ("bit", [(0, 0), (1000, 1), (4800, 0)])})
    res = EdgeAtPosition(GATE, "dev.x.pos", [(10, 1), (50, 0)], 0, tol_time=100, times=[1000, 5000]).evaluate(trace)
    assert found(res) == [(4800, -200, 100)]
    assert res.violations[0].detail == "edge 1 to 0 -200 ns off its expected time 5000 ns"
    assert res.measured["worst_time_error_ns"] == 200
    relaxed = EdgeAtPosition(GATE, "dev.x.pos", [(10, 1), (50, 0)], 0, tol_time=200, times=[1000, 5000])
    assert relaxed.evaluate(trace).passed


# -- Bound ----------------------------------------------------------------------------------------
ERROR = ("real", [(0, 0.0), (100, 1.5), (200, -2.0), (300, 0.5)])


def test_bound_passes_inside_inclusive_limits() -> None:
    res = Bound("dev.x.ferr", lower=-2, upper=2).evaluate(make_trace(signals={"dev.x.ferr": ERROR}))
    assert res.passed and res.checked == 4
    assert res.measured == {"max": 1.5, "min": -2, "max_abs": 2}


def test_bound_reports_each_value_outside() -> None:
    """t [ns]: 0 -> 0.0, 100 -> 1.5 (> 1), 200 -> -2.0 (< -1.5), 300 -> 0.5."""
    res = Bound("dev.x.ferr", lower=-1.5, upper=1).evaluate(make_trace(signals={"dev.x.ferr": ERROR}))
    assert found(res) == [(100, 1.5, 1), (200, -2, -1.5)]
    assert [v.detail for v in res.violations] == ["dev.x.ferr = 1.5 is above the upper bound",
                                                  "dev.x.ferr = -2 is below the lower bound"]
    one_sided = Bound("dev.x.ferr", upper=1.0).evaluate(make_trace(signals={"dev.x.ferr": ERROR}))
    assert found(one_sided) == [(100, 1.5, 1)]


def test_bound_treats_nan_as_outside() -> None:
    res = Bound("dev.x.ferr", lower=0).evaluate(make_trace(signals={"dev.x.ferr": ("real", [(0, 1.0), (50, np.nan)])}))
    assert res.n_violations == 1 and res.violations[0].t_ns == 50 and res.violations[0].limit == ">= 0"


# -- NoUnderrun, IntervalsBelow, IntervalsAbove --------------------------------------------------------
LEVEL = "dev.buffer_level"
#   t [ns]   0     1000          3000  3500          6000        8000 (end)
#   level    0     5             0     2             0
#   below 1  ######              #####               ###########
BUFFER = {LEVEL: ("int", [(0, 0), (1000, 5), (3000, 0), (3500, 2), (6000, 0)])}


def test_no_underrun_from_the_job_start_allows_the_final_emptying() -> None:
    trace = make_trace(signals=BUFFER, end_t=8000)
    res = NoUnderrun(LEVEL, start=1000).evaluate(trace)
    assert found(res) == [(3000, 500, "never < 1")]
    assert res.violations[0].detail == "dev.buffer_level < 1 from 3000 to 3500 ns (lowest 0)"
    assert res.measured == {"intervals": 1, "total_ns": 500, "longest_ns": 500, "final_ns": 2000, "min_value": 0}


def test_no_underrun_without_start_or_allowance_reports_every_interval() -> None:
    trace = make_trace(signals=BUFFER, end_t=8000)
    res = NoUnderrun(LEVEL, allow_final=False).evaluate(trace)
    assert found(res) == [(0, 1000, "never < 1"), (3000, 500, "never < 1"), (6000, 2000, "never < 1")]
    assert res.violations[2].detail.endswith("(lowest 0, still at the end)")
    assert res.measured["total_ns"] == 3500 and res.measured["intervals"] == 3


def test_no_underrun_passes_when_the_level_never_drops() -> None:
    trace = make_trace(signals={LEVEL: ("int", [(0, 3), (1000, 5), (3000, 1)])}, end_t=5000)
    res = NoUnderrun(LEVEL).evaluate(trace)
    assert res.passed and res.checked == 3 and res.measured == {"intervals": 0, "total_ns": 0, "longest_ns": 0,
                                                               "min_value": 1}


def test_intervals_are_cut_at_start_and_until() -> None:
    """start=500 cuts [0, 1000) to 500 ns; until=6000 ignores the final interval."""
    trace = make_trace(signals=BUFFER, end_t=8000)
    res = IntervalsBelow(LEVEL, 1, start=500, until=6000).evaluate(trace)
    assert found(res) == [(500, 500, "never < 1"), (3000, 500, "never < 1")]
    assert res.checked == 4  # the records before 6000 ns


def test_a_zero_length_underrun_at_one_tick_still_counts() -> None:
    """The level drops to 0 and is refilled at the same tick (500 ns): someone may have seen 0."""
    trace = make_trace(signals={LEVEL: ("int", [(0, 3), (500, 0), (500, 3)])}, end_t=1000)
    assert found(NoUnderrun(LEVEL).evaluate(trace)) == [(500, 0, "never < 1")]


def test_intervals_below_with_a_longest_allowed_duration() -> None:
    trace = make_trace(signals=BUFFER, end_t=8000)
    assert IntervalsBelow(LEVEL, 1, max_duration=500, start=1000, allow_final=True).evaluate(trace).passed
    res = IntervalsBelow(LEVEL, 1, max_duration=499, start=1000, allow_final=True).evaluate(trace)
    assert found(res) == [(3000, 500, 499)]


def test_intervals_above_on_sampled_power() -> None:
    """Power above 10 W for at most 150 ns at a time.

    t [ns]   0    100        300         700   800
    power    0    12         9           11    0
    above         ##########             #####
                  200 ns (too long)      100 ns
    """
    trace = make_trace(signals={"laser.power": ("real", [(0, 0), (100, 12.0), (300, 9.0), (700, 11.0), (800, 0)])})
    res = IntervalsAbove("laser.power", 10, max_duration=150).evaluate(trace)
    assert found(res) == [(100, 200, 150)]
    assert res.violations[0].detail == "laser.power > 10 from 100 to 300 ns (highest 12)"
    assert res.measured == {"intervals": 1, "total_ns": 200, "longest_ns": 200, "max_value": 12}
    assert IntervalsAbove("laser.power", 10, max_duration=200).evaluate(trace).passed


# -- Duration --------------------------------------------------------------------------------------
LIMIT = "dev.x.limit"


def test_limit_trip_to_last_pulse() -> None:
    """The limit switch trips at 2000 ns; the last pulse is at 2600 ns: 600 ns.

    t [ns]   0 ...            2000        2600
    limit    0________________1‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾
    step     | | | | | | | | | | | | | | | | |   (every 100 ns up to 2600)
    """
    trace = make_trace(signals={LIMIT: ("bit", [(0, 0), (2000, 1)])}, segments={STEP: [(0, 2700, 27, 1)]})
    res = Duration(EdgeRef(LIMIT, 1), PulseRef(STEP, "last"), max=500).evaluate(trace)
    assert found(res) == [(2000, 600, 500)]
    assert res.violations[0].detail == "last pulse of dev.x.step 600 ns after the start"
    assert res.measured == {"durations": 1, "min_ns": 600, "max_ns": 600}
    assert Duration(EdgeRef(LIMIT, 1), PulseRef(STEP, "last"), max=600).evaluate(trace).passed


GATE_ON = ("bit", [(0, 0), (1000, 1), (3000, 0), (5000, 1), (7000, 0)])


def test_each_gate_on_to_power_ok_is_measured() -> None:
    """t [ns]   1000      3000     5000            7000
    gate        1‾‾‾‾‾‾‾‾‾0________1‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾0
    power_ok      1200 ‾‾‾‾‾‾0              5900 ‾‾0
                  200 ns                    900 ns (too slow)
    """
    ok = ("bit", [(0, 0), (1200, 1), (3100, 0), (5900, 1), (7100, 0)])
    trace = make_trace(signals={"laser.gate": GATE_ON, "laser.power_ok": ok}, end_t=8000)
    spec = Duration(EdgeRef("laser.gate", 1), EdgeRef("laser.power_ok", 1), max=500)
    res = spec.evaluate(trace)
    assert found(res) == [(5000, 900, 500)] and res.checked == 2
    assert res.measured == {"durations": 2, "min_ns": 200, "max_ns": 900}
    fast = Duration(EdgeRef("laser.gate", 1), EdgeRef("laser.power_ok", 1), min=300).evaluate(trace)
    assert found(fast) == [(1000, 200, 300)]
    exact = Duration(EdgeRef("laser.gate", 1), EdgeRef("laser.power_ok", 1), equals=200, tol=100).evaluate(trace)
    assert found(exact) == [(5000, 900, "200 ± 100 ns")]


def test_a_start_without_an_end_in_its_window_is_a_violation() -> None:
    """The second gate-on (5000 ns) gets no power_ok before the end of the trace (8000 ns)."""
    trace = make_trace(signals={"laser.gate": GATE_ON, "laser.power_ok": ("bit", [(0, 0), (1200, 1)])}, end_t=8000)
    res = Duration(EdgeRef("laser.gate", 1), EdgeRef("laser.power_ok", 1), max=500).evaluate(trace)
    assert found(res) == [(5000, 3000, "<= 500 ns")]
    assert res.violations[0].detail == "no change of laser.power_ok to 1 within 3000 ns"


def test_the_end_must_come_before_the_next_start() -> None:
    """power_ok only rises at 5100 ns: that answers the second gate-on, not the first."""
    ok = ("bit", [(0, 0), (5100, 1)])
    trace = make_trace(signals={"laser.gate": GATE_ON, "laser.power_ok": ok}, end_t=8000)
    res = Duration(EdgeRef("laser.gate", 1), EdgeRef("laser.power_ok", 1), max=500).evaluate(trace)
    assert found(res) == [(1000, 4000, "<= 500 ns")]
    first_only = Duration(EdgeRef("laser.gate", 1, which="last"), EdgeRef("laser.power_ok", 1), max=500)
    assert first_only.evaluate(trace).passed and first_only.evaluate(trace).checked == 1


# -- ValueAt ----------------------------------------------------------------------------------------
def test_final_position_of_a_pulse_train() -> None:
    """10 pulses up from 0 ns, 4 down from 1000 ns: position 6 at the end (and 6 = 0..500 ns at 500)."""
    trace = make_trace(segments={STEP: [(0, 1000, 10, 1), (1000, 1000, 4, 0)]}, end_t=2000)
    assert ValueAt(STEP, None, 6).evaluate(trace).passed
    assert ValueAt(STEP, 500, 6).evaluate(trace).measured == {"value": 6}
    res = ValueAt(STEP, None, 7).evaluate(trace)
    assert found(res) == [(2000, 6, 7)]
    assert res.violations[0].detail == "position of dev.x.step is 6, expected 7"


def test_value_of_a_register_at_an_instant() -> None:
    """count: 0 until 1000 ns, then 7; a record at the instant counts."""
    trace = make_trace(signals={"dev.count": ("int", [(100, 0), (1000, 7)]), "dev.power": ("real", [(0, 10.4)])})
    assert ValueAt("dev.count", 999, 0).evaluate(trace).passed
    assert found(ValueAt("dev.count", 1000, 0).evaluate(trace)) == [(1000, 7, 0)]
    assert ValueAt("dev.power", 10, 10.0, tol=0.5).evaluate(trace).passed
    assert found(ValueAt("dev.power", 10, 10.0, tol=0.25).evaluate(trace)) == [(10, 10.4, "10 ± 0.25")]
    before = ValueAt("dev.count", 50, 0).evaluate(trace)  # no value yet: nothing to compare, not a pass
    assert not before.passed and before.checked == 0 and not before.violations
    assert before.nothing_checked == "value of dev.count at 50 ns is not a number: nothing to compare"
    trace.end_t = 2000
    assert ValueAt("dev.count", 2000, 7).evaluate(trace).passed
    after = ValueAt("dev.count", 2001, 7).evaluate(trace)  # not simulated
    assert not after.passed and after.checked == 0 and "lies after the run's end" in after.nothing_checked


# -- in a scenario run ------------------------------------------------------------------------------
SCRIPT = '''
"""Two 1 ms slots of step pulses."""
from cosim.checks import MaxPulseRate, PulsesPerWindow
from cosim.scenario import Param, Run
from cosim.signals import PulseTrain

PARAMETERS = (Param("second", 25, "", (1, 100), "pulses in slot 2"),)
UNTIL = "2 ms"
RATE_OF = "pokeys.x.step"


def scenario(run: Run) -> None:
    step = PulseTrain(run.sim, "pokeys.x.step")
    step.emit(0, 1_000_000, 25, 1)
    step.emit(1_000_000, 1_000_000, run.p.second, 1)
    run.check(PulsesPerWindow("pokeys.x.step", 25, run.sim.ticks("1 ms")))
    run.check(MaxPulseRate(RATE_OF, 25_000, window=run.sim.ticks("1 ms")))
'''


def test_checks_in_a_scenario_run_land_in_result_json(tmp_path: Path) -> None:
    path = tmp_path / "slots.py"
    path.write_text(textwrap.dedent(SCRIPT))
    result = run_scenario(load(path), overrides={"second": "26"}, out=tmp_path / "out")
    assert result.verdict == "FAIL"
    data = json.loads((tmp_path / "out" / "result.json").read_text())
    assert data["checks"][0]["violations"] == [{"t_ns": 1_000_000, "value": 26, "limit": 25,
                                                "detail": "26 pulses in [1000000, 2000000) ns", "unit": "pulses"}]
    assert run_scenario(load(path)).verdict == "PASS"


def test_a_misspelled_signal_in_a_scenario_is_an_error_with_a_suggestion(tmp_path: Path) -> None:
    path = tmp_path / "slots.py"
    path.write_text(textwrap.dedent(SCRIPT).replace('RATE_OF = "pokeys.x.step"', 'RATE_OF = "pokeys.x.stpe"'))
    result = run_scenario(load(path))
    assert result.verdict == "ERROR" and result.error is not None
    assert "no signal named 'pokeys.x.stpe' in the trace; did you mean pokeys.x.step?" in result.error


# -- the examples in the docstrings hold ------------------------------------------------------------
@pytest.mark.parametrize("module", [cosim.checks, base, direction, duration, edge_position, levels, pulse_timing,
                                    result], ids=lambda m: m.__name__)
def test_docstring_examples(module: object) -> None:
    failures, _ = doctest.testmod(module, optionflags=doctest.ELLIPSIS)  # type: ignore[arg-type]
    assert failures == 0


def test_the_custom_check_of_the_docs_runs_as_shown() -> None:
    """docs/checks.md, 'Writing your own check': its code, on the slots 0 2 4 6 14 14 10 (then 0)."""
    text = (Path(__file__).parents[1] / "docs" / "checks.md").read_text()
    section = text.split("## Writing your own check", 1)[1]
    namespace: dict[str, object] = {}
    exec(section.split("```python\n", 1)[1].split("```", 1)[0], namespace)  # the page's own code
    sim = Simulation()
    engine = PulseEngine(sim)
    engine.fill_buffer([encode_entry((c, 0, 0)) for c in (0, 2, 4, 6, 14, 14, 10)])
    engine.set_state(EngineState.BUFFER)
    sim.run(until=10_000_000)
    check = namespace["MaxCountStep"]("pokeys.x.step", 1_000_000, 4)  # type: ignore[operator]
    result = check.evaluate(sim.trace)
    assert result.summary() in section  # the output the page shows
    assert [v.t_ns for v in result.violations] == [4_000_000, 7_000_000]  # 6 -> 14, then 10 -> 0
    with pytest.raises(ConfigurationError, match=r"^MaxCountStep\(pokeys\.x\.step\): slot = 0 is not allowed "
                                                 r"\(allowed: >= 1 ticks\)$"):
        namespace["MaxCountStep"]("pokeys.x.step", 0, 4)  # type: ignore[operator]
