"""The analytic conveyor stand-in: exact positions, exact edge instants, mark events."""

from __future__ import annotations

from fractions import Fraction

import pytest

from cosim.errors import ConfigurationError
from cosim.kernel import Simulation
from cosim.plants.analytic import IdealConveyor


def test_constant_speed_edges_every_15625_ns(sim: Simulation) -> None:
    belt = IdealConveyor(sim, speed_counts_per_ms=64)
    assert [belt.time_at(n) for n in range(4)] == [0, 15_625, 31_250, 46_875]
    assert belt.time_at(-2) == -31_250  # before t = 0 the belt ran at its initial speed
    assert belt.sample(40_000).count == 2
    assert belt.sample(40_000).last_edge_t == 31_250 and belt.sample(40_000).prev_edge_t == 15_625


def test_piecewise_acceleration_is_exact(sim: Simulation) -> None:
    """0 -> 64 counts/ms in 10 ms (6.4 counts/ms^2), then constant.

        speed  /‾‾‾‾‾‾
              0    10 ms
    """
    belt = IdealConveyor(sim, phases=[(10_000_000, Fraction(32, 5))])
    assert belt.position(10_000_000) == 320
    assert belt.speed_counts_per_ms(10_000_000) == 64
    assert belt.position(5_000_000) == 80
    assert belt.position(20_000_000) == 320 + 640
    for n in (1, 80, 319, 320, 321, 500):
        t = belt.time_at(n)
        assert t is not None
        assert belt.position(t) >= n > belt.position(t - 1)
    assert belt.sample(1).last_edge_t is None  # stopped before t = 0: no edges yet


def test_marks_become_signal_edges_at_exact_crossings(sim: Simulation) -> None:
    belt = IdealConveyor(sim, speed_counts_per_ms=64, marks=[Fraction(1, 2), 10], mark_width_counts=1)
    sim.run(until=1_000_000)
    t, v = sim.trace.edges("conveyor.mark")
    assert t.tolist() == [0, 7_813, 23_438, 156_250, 171_875]
    assert v.tolist() == [0, 1, 0, 1, 0]
    assert belt.mark_times == [(7_813, 23_438), (156_250, 171_875)]


def test_stopping_conveyor_never_reaches_far_positions(sim: Simulation) -> None:
    belt = IdealConveyor(sim, speed_counts_per_ms=64, phases=[(10_000_000, Fraction(-32, 5))])
    assert belt.position(10**9) == 320
    assert belt.time_at(321) is None


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"speed_counts_per_ms": -1}, "speed_counts_per_ms = -1 is not allowed"),
        ({"phases": [(1000, -1)]}, "acceleration of the phase ending at tick 1000 = -1"),
        ({"phases": [(0, 1)]}, "phase duration_ticks = 0"),
        ({"marks": [0]}, "mark position = 0 is not allowed"),
        ({"mark_width_counts": 0, "marks": [5]}, "mark_width_counts = 0"),
    ],
)
def test_bad_conveyor_parameters(sim: Simulation, kwargs: dict[str, object], message: str) -> None:
    with pytest.raises(ConfigurationError, match=message):
        IdealConveyor(sim, **kwargs)  # type: ignore[arg-type]
