"""What the docs show is what the code does: sample outputs rerun by their command, one direction convention.

    docs/*.md, README.md ──<!-- sample: cosim ... -->──> docs/samples.py --check ──> the command's output today

Direction outputs, one convention per device, stated in the README's signal table and the device's page:

    pokeys.x.dir   1 = activated = negative (the slot entry's MSB), unless invert_direction
    trio.axisN.dir 1 = positive
"""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Generator
from pathlib import Path
from typing import Any

import pytest

from cosim.controllers.pokeys import EngineState, PulseEngine
from cosim.controllers.trio import ON, TrioController, TrioProcess
from cosim.kernel import Simulation
from cosim.timebase import Priority

ROOT = Path(__file__).resolve().parent.parent
MS = 1_000_000

pytestmark = pytest.mark.fmu


def test_every_sample_output_in_the_docs_is_what_its_command_prints_today() -> None:
    """... and leaves no results in the checkout (a results/x400 there made a later `cosim main` refuse results/)."""
    before = set((ROOT / "results").glob("*")) if (ROOT / "results").is_dir() else set()
    done = subprocess.run([sys.executable, str(ROOT / "docs" / "samples.py"), "--check"], cwd=ROOT,
                          capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stdout + done.stderr + "\n(rerun: python docs/samples.py)"
    after = set((ROOT / "results").glob("*")) if (ROOT / "results").is_dir() else set()
    assert after <= before


def test_the_samples_cover_the_machine_file_page() -> None:
    text = (ROOT / "docs" / "machines.md").read_text()
    assert text.count("<!-- sample: cosim ") >= 6


def _row(page: str, signal: str) -> str:
    return next(line for line in (ROOT / page).read_text().splitlines() if line.startswith(f"| `{signal}`"))


def test_pokeys_dir_is_1_for_negative_pulses_as_the_readme_and_the_pokeys_page_say(sim: Simulation) -> None:
    assert "1 = activated = negative" in _row("README.md", "pokeys.x.dir")
    assert "1 = activated = the entry's MSB set = negative" in _row("docs/pokeys.md", "pokeys.x.dir")
    engine = PulseEngine(sim)
    engine.fill_buffer([(-20, 0, 0), (20, 0, 0)])
    engine.set_state(EngineState.BUFFER)
    sim.run(until=3 * MS)
    t, level = sim.trace.edges("pokeys.x.dir")
    pulse_t, direction = sim.trace.pulses("pokeys.x.step")
    assert list(zip(t.tolist(), level.tolist(), strict=True)) == [(0, 0), (0, 1), (1 * MS, 0)]
    assert set(direction[pulse_t < 1 * MS].tolist()) == {0} and set(direction[pulse_t >= 1 * MS].tolist()) == {1}


def test_trio_dir_is_1_for_positive_steps_as_the_readme_and_the_trio_page_say(sim: Simulation) -> None:
    assert "1 = positive" in _row("README.md", "trio.axis3.dir")
    assert "1 = positive" in _row("docs/trio.md", "trio.axisN.dir")
    trio = TrioController(sim, encoder_at_atype=0)
    process = TrioProcess(trio, base=(3,))
    for name, value in (("ATYPE", 35), ("SERVO", ON), ("UNITS", 1), ("SPEED", 1000), ("ACCEL", 10**6),
                        ("DECEL", 10**6)):
        process.set(name, value)

    def job() -> Generator[Any, Any, None]:
        yield sim.at(0, Priority.HOST)
        yield process.move(-2)
        yield process.move(2)

    sim.process(job())
    sim.run(until=10 * MS)
    t, level = sim.trace.edges("trio.axis3.dir")
    pulse_t, direction = sim.trace.pulses("trio.axis3.step")
    assert direction.tolist() == [0, 0, 1, 1]
    assert [int(level[t <= p][-1]) for p in pulse_t.tolist()] == [0, 0, 1, 1]
