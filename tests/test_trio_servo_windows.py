"""The servo ticks the controller skips or computes in closed form give the very trace of running every tick.

:mod:`cosim.controllers.trio.servo` runs a tick as a kernel event only where its outcome can depend on
something else (issue 29). These tests run random programs of straight moves, stops, DEFPOS, gating and
readers at random instants twice, with the shortcuts and with every tick explicit, and compare every
signal of the trace: instants and values, pulse by pulse.
"""

from __future__ import annotations

import hashlib
import random
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cosim.controllers.trio import TrioController
from cosim.controllers.trio.basic import BasicProgram
from cosim.controllers.trio.servo import ServoLoop
from cosim.kernel import Simulation
from cosim.timebase import Priority

MS = 1_000_000


def program(rng: random.Random) -> str:
    axis = rng.choice([0, 3])
    lines = [f"BASE({axis})", f"ATYPE = {rng.choice([0, 1, 35] if axis == 3 else [0, 1])}", "SERVO = ON",
             f"UNITS = {rng.choice([1, 16, 80, 2.5])}", f"SPEED = {rng.choice([50, 100, 333])}",
             f"ACCEL = {rng.choice([500, 1000, 7777])}", f"DECEL = {rng.choice([500, 2000])}",
             "FE_LIMIT = 100000", "PWM_CONTROL(6) AXIS(3)", "PWM_CONTROL(5) AXIS(3)", "TABLE(0, 3, 7, 12, 20)",
             "PWM_CONTROL(3, 1, ON, 0, 3) AXIS(3)"]
    for _ in range(rng.randint(2, 6)):
        roll = rng.random()
        if roll < 0.35:
            lines.append(f"MOVE({rng.choice([-1, 1]) * rng.randint(1, 30)})")
        elif roll < 0.5:
            lines.append(f"MOVEABS({rng.randint(-20, 40)})")
        elif roll < 0.6:
            lines += ["FORWARD", f"WA({rng.randint(5, 200)})", "CANCEL"]
        elif roll < 0.7:
            lines += [f"WA({rng.randint(1, 150)})", "CANCEL"]
        elif roll < 0.8:
            lines += ["WAIT IDLE", f"DEFPOS({rng.randint(-5, 5)})"]
        elif roll < 0.9:
            lines.append(f"WA({rng.randint(0, 300)})")
        else:
            lines += ["WAIT IDLE", "VR(0) = DPOS + MPOS + VP_SPEED"]
    lines.append("WAIT IDLE")
    return "\n".join(lines) + "\n"


def digests(text: str, reads: list[int], *, shortcuts: bool) -> dict[str, str]:
    previous = ServoLoop.shortcuts
    ServoLoop.shortcuts = shortcuts
    try:
        sim = Simulation(seed=3)
        trio = TrioController(sim, encoder_at_atype=0)
        seen: list[Any] = []

        def reader() -> Any:  # a plant sample reading the controller (after the servo at the same instant)
            for t in reads:
                yield sim.at(t, Priority.SAMPLE)
                seen.append((trio.axes[3].dpos, trio.axes[0].demand, trio.axes[3].steps))

        sim.process(reader())
        BasicProgram.parse(text, name="r.bas").start(trio)
        sim.run(until=2000 * MS)
    finally:
        ServoLoop.shortcuts = previous
    out = {"reads": repr(seen)}
    for name in sim.trace.names():
        t, v = sim.trace.pulses(name) if sim.trace.info[name].kind == "pulse" else sim.trace.edges(name)
        out[name] = hashlib.sha256(np.asarray(t, "<i8").tobytes() + np.asarray(v, "<f8").tobytes()).hexdigest()
    return out


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow], database=None)
@given(st.integers(min_value=0, max_value=2**32 - 1))
def test_shortcuts_change_no_signal(seed: int) -> None:
    rng = random.Random(seed)
    text = program(rng)
    reads = sorted(rng.randrange(0, 1900 * MS) for _ in range(rng.randint(0, 5)))
    assert digests(text, reads, shortcuts=True) == digests(text, reads, shortcuts=False), text


@pytest.mark.parametrize("text", [
    "BASE(3)\nATYPE = 35\nSERVO = ON\nUNITS = 16\nFE_LIMIT = 1000\nPWM_CONTROL(6)\nPWM_CONTROL(5)\n"
    "TABLE(0, 110, 115, 195, 220)\nPWM_CONTROL(3, 1, ON, 0, 3)\nMOVEABS(300)\nWAIT IDLE\n",
    "BASE(0)\nATYPE = 1\nUNITS = 80\nSPEED = 100\nFORWARD\nWA(700)\nCANCEL\nWAIT IDLE\n",
])
def test_the_note_and_a_forward_move_give_the_same_trace(text: str) -> None:
    reads = [5 * MS, 333 * MS, 1000 * MS]
    assert digests(text, reads, shortcuts=True) == digests(text, reads, shortcuts=False)


def test_the_tn20_81_run_is_mostly_closed_form() -> None:
    """The note's program at its default speed: far fewer explicit ticks than servo periods."""
    sim = Simulation(seed=1)
    trio = TrioController(sim, encoder_at_atype=0)
    BasicProgram.parse("BASE(3)\nATYPE = 35\nSERVO = ON\nUNITS = 16\nMOVEABS(300)\nWAIT IDLE\nMOVEABS(0)\n",
                       name="t.bas").start(trio)
    sim.run(until=2000 * MS)
    assert trio.servo.implicit + trio.servo.skipped > 1900
