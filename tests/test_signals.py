"""Signals refuse values their kind cannot hold, and pulse segments that are not whole ticks and counts."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest

from cosim.errors import ConfigurationError
from cosim.kernel import Simulation
from cosim.signals import PulseTrain, Signal


def test_an_int_signal_takes_whole_numbers_and_refuses_the_rest(sim: Simulation) -> None:
    count = Signal(sim, "dev.count", kind="int")
    for value, held in ((7, 7), (8.0, 8), (np.int64(9), 9), (Fraction(20, 2), 10), (True, 1)):
        count.set(value)  # type: ignore[arg-type]
        assert count.value == held and type(count.value) is int
    for bad, shown in ((2.5, "2.5"), (float("nan"), "nan"), (float("inf"), "inf"), (Fraction(5, 2), "2.5")):
        with pytest.raises(ConfigurationError, match=rf"^signal dev\.count = {shown} is not allowed"):
            count.set(bad)  # type: ignore[arg-type]
    assert count.value == 1


@pytest.mark.parametrize(("segment", "message"), [
    ((0, 1000, -1, 1), r"segment count = -1 is not allowed \(allowed: >= 0\)"),
    ((0, 0, 3, 1), r"segment duration = 0 is not allowed \(allowed: >= 1 ticks\)"),
    ((0, 1000, 3, 2), r"segment direction = 2 is not allowed \(allowed: 0 or 1\)"),
    ((0.5, 1000, 3, 1), r"segment start = 0\.5 is not allowed \(allowed: an integer \[ticks\]\)"),
    ((0, 1000, 2.5, 1), r"segment count = 2\.5 is not allowed \(allowed: an integer\)"),
])
def test_a_pulse_segment_must_be_whole_ticks_and_counts(sim: Simulation, segment: tuple[float, ...],
                                                        message: str) -> None:
    train = PulseTrain(sim, "dev.x.step")
    with pytest.raises(ConfigurationError, match=rf"^dev\.x\.step: {message}$"):
        train.emit(*segment)  # type: ignore[arg-type]
    assert train.position == 0
