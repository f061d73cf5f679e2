"""The servo ticks the controller skips or computes in closed form give the very trace of running every tick.

:mod:`cosim.controllers.trio.servo` runs a tick as a kernel event only where its outcome can depend on
something else (issue 29). These tests run random programs of straight moves, stops, DEFPOS, gating and
readers at random instants twice, with the shortcuts and with every tick explicit, and compare every
signal of the trace: instants and values, pulse by pulse.
"""

from __future__ import annotations

import hashlib
import random
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from run_digests import run_with_trace, signal_digests

from cosim.controllers.trio import TrioController
from cosim.controllers.trio.basic import BasicProgram
from cosim.controllers.trio.compiler import Compiler
from cosim.controllers.trio.servo import ServoLoop
from cosim.controllers.trio.syntax import parse
from cosim.kernel import Simulation
from cosim.timebase import Priority

MS = 1_000_000
ENGRAVER = Path(__file__).resolve().parent.parent / "examples" / "trio_engraver"


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


def digests(text: str, reads: list[int], *, shortcuts: bool, other: str | None = None) -> dict[str, str]:
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
        if other is not None:  # a second program, in process 2
            BasicProgram.parse(other, name="o.bas").start(trio, process=2)
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


@pytest.mark.parametrize("wait_ms", [0, 1, 37, 250, 999])
@pytest.mark.parametrize("text", [
    # WAIT UNTIL on memory only (VR, a variable): its checks at every tick do not end the windows
    "BASE(3)\nATYPE = 35\nUNITS = 16\nlimit = 1\nFORWARD\nWAIT UNTIL VR(1) >= limit\nCANCEL\nOP(8, ON)\n"
    "WAIT IDLE\n",
    # WAIT UNTIL on the position: the windows end where it may hold
    "BASE(0)\nATYPE = 1\nUNITS = 80\nSPEED = 40\nMOVE(30)\nWAIT UNTIL DPOS > VR(1) + 9.5\nOP(9, ON)\n"
    "WAIT UNTIL MPOS > 20\nOP(10, ON)\nWAIT IDLE\n",
])
def test_wait_until_sees_the_same_instants_in_closed_form(text: str, wait_ms: int) -> None:
    """Process 2 writes VR(1) after ``wait_ms``: the waiting program goes on at the same servo tick, whether the
    ticks in between ran or were computed in closed form (the outputs it switches then say when)."""
    other = f"WA({wait_ms})\nVR(1) = 1\n"
    reads = [3 * MS, 400 * MS]
    closed = digests(text, reads, shortcuts=True, other=other)
    assert closed == digests(text, reads, shortcuts=False, other=other)
    assert any(name.startswith("trio.op.") for name in closed)


ARC_AXES = ("FOR ax = {a} TO {b} STEP {step}\n  BASE(ax)\n  ATYPE = {atype}\n  SERVO = ON\n  UNITS = {units}\n"
            "  SPEED = 150\n  ACCEL = 900\n  DECEL = 900\n  FE_LIMIT = 1000\nNEXT ax\nBASE({a}, {b})\n")


@pytest.mark.parametrize("text", [
    # quarter circles both ways, a full circle, a line between: stepper axes nobody listens to
    ARC_AXES.format(a=0, b=1, step=1, atype=1, units=80)
    + "MOVECIRC(10, 10, 10, 0, 0)\nMOVE(-3, 4)\nMOVECIRC(-10, -10, 0, -10, 1)\nMOVECIRC(0, 0, 7.5, 2.5, 0)\n"
    "WAIT IDLE\n",
    # on the PWM axes with the gate counting: an arc towards a gate position runs explicitly
    ARC_AXES.format(a=3, b=2, step=-1, atype=35, units=16)
    + "PWM_CONTROL(6) AXIS(3)\nPWM_CONTROL(5) AXIS(3)\nTABLE(0, 3, 7, 12, 20)\nPWM_CONTROL(3, 1, ON, 0, 3) AXIS(3)\n"
    "MOVECIRC(20, 20, 20, 0, 0)\nMOVECIRC(-20, 20, 0, 20, 0)\nWAIT IDLE\n",
])
def test_arcs_give_the_same_trace_in_closed_form(text: str) -> None:
    """A MOVECIRC's cycles computed in closed form (the sines and cosines of each cycle in integers) give every
    signal, pulse by pulse, of every tick run."""
    reads = [7 * MS, 450 * MS, 1200 * MS]
    assert digests(text, reads, shortcuts=True) == digests(text, reads, shortcuts=False)


def test_the_tn20_81_run_is_mostly_closed_form() -> None:
    """The note's program at its default speed: far fewer explicit ticks than servo periods."""
    sim = Simulation(seed=1)
    trio = TrioController(sim, encoder_at_atype=0)
    BasicProgram.parse("BASE(3)\nATYPE = 35\nSERVO = ON\nUNITS = 16\nMOVEABS(300)\nWAIT IDLE\nMOVEABS(0)\n",
                       name="t.bas").start(trio)
    sim.run(until=2000 * MS)
    assert trio.servo.implicit + trio.servo.skipped > 1900


def _machine_digests(machine: Path, *, shortcuts: bool) -> tuple[dict[str, str], int]:
    """Every signal of a machine file's run (instants and values), and the ticks computed in closed form."""
    previous = ServoLoop.shortcuts
    ServoLoop.shortcuts = shortcuts
    loops: list[ServoLoop] = []
    init = ServoLoop.__init__

    def remember(self: ServoLoop, controller: Any) -> None:
        init(self, controller)
        loops.append(self)

    try:
        ServoLoop.__init__ = remember  # type: ignore[method-assign]
        result, trace = run_with_trace(str(machine))
    finally:
        ServoLoop.__init__ = init  # type: ignore[method-assign]
        ServoLoop.shortcuts = previous
    assert result.verdict == "PASS", result.table()
    return signal_digests(trace), loops[-1].implicit


@pytest.mark.fmu
def test_steppers_that_pull_their_pulses_see_the_same_pulses_in_closed_form(tmp_path: Path) -> None:
    """The engraver (two Stepper FMUs on the segments way, a speed-linked laser, process 2 waiting on VR), with
    both carriages and their angles recorded every 700 us: the samples step the plants inside the windows, so
    the plants pull the pulses of the ticks computed in closed form. Every signal is the one every tick gives."""
    folder = tmp_path / "engraver"
    shutil.copytree(ENGRAVER, folder)
    machine = folder / "engraver.toml"
    text = machine.read_text()
    for plant in ("stage_x", "stage_y"):
        record = 'record = { variables = ["carriage_position", "angle"], period = "700 us" }'
        text = text.replace(f"[plant.{plant}]", f"[plant.{plant}]\n{record}")
    machine.write_text(text)
    closed, implicit = _machine_digests(machine, shortcuts=True)
    explicit, none = _machine_digests(machine, shortcuts=False)
    assert implicit > 2000 and none == 0  # of 3866 servo cycles in motion, most in closed form
    assert "stage_x.carriage_position" in closed
    assert closed == explicit


@pytest.mark.parametrize(("condition", "memory"), [
    ("VR(1) >= limit", True), ("NOT (VR(2) = 3 OR TABLE(7) < -1.5)", True), ("level = ON AND x(2) > 0", True),
    ("speed_vr > 2", True), ("DPOS > 1", False), ("IN(0) = ON", False), ("TICKS < 0", False),
    ("VR(1) > MPOS AXIS(2)", False), ("ABS(VR(1)) > 1", False), ("IDLE", False), ("VR(DPOS) = 1", False),
])
def test_a_wait_until_on_memory_only_is_told_from_one_on_the_controller(condition: str, memory: bool) -> None:
    """Only a condition on numbers, constants, VR (also by a GLOBAL name), TABLE and the program's own variables
    and arrays checks memory only; a parameter, an input, a function or the time reads the controller."""
    text = f"GLOBAL speed_vr, 9\nDIM x(4)\nlimit = 1\nlevel = 0\nWAIT UNTIL {condition}\n"
    compiler = Compiler("w.bas")
    compiler.compile(parse(text, "w.bas"))
    wait = next(parse(text, "w.bas").find_data("wait_until"))
    assert compiler.memory_only(wait.children[0]) is memory
