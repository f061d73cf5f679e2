"""Shared fixtures: a fresh simulation and a log list (the SimPy testing habit)."""

from __future__ import annotations

import pytest

from cosim.kernel import Simulation


@pytest.fixture
def sim() -> Simulation:
    with Simulation(seed=1) as simulation:
        yield simulation


@pytest.fixture
def log() -> list[object]:
    return []
