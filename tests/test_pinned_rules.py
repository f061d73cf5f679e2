"""Vendor rules a mutation run found unpinned (110 of 113 mutants caught), pinned with the documents' numbers.

Each expectation is written from the document, never from the code's own constants:

* Trio TRM 8-165: the FALLING edge of the step output is the active edge by default (INVERT_STEP=ON makes it
  the rising one). A drive coupled to the step output counts a pulse there, at its trailing edge: the
  leading edge plus the step pulse width (100 ns, the model's default width)::

      step   ____|‾‾‾‾‾‾‾‾|_______        leading edge at the servo tick t, falling (active) edge at t + 100 ns
      drive  ______________^ counted at t + 100 ns, not at t

* PoKeys pulse engine documentation (17/1/2012): "up to 25 pulses per 1 millisecond time slot (which equates
  to 25 kHz maximum pulse frequency supported)": a PoKeys56U slot with 25 pulses runs, one with 26 is refused.

* Turbo PMAC User Manual p. 237: each background cycle runs one scan of every active PLC 1..31, "starting from
  lowest numbered to highest". How long a background cycle takes depends on the controller's load, which no
  manual gives as a number; the model's default is one scan every 200 us from t = 0 (docs/pmac.md,
  ``plc_scan_period``)::

      t [us]    0     200   400   600   800   1000
      scan      1     2     3     4     5     6        PLC 1 before PLC 2 in each
"""

from __future__ import annotations

from collections.abc import Generator
from typing import Any

import pytest

from cosim.controllers.pmac import Pmac
from cosim.controllers.pokeys import EngineConfig, EngineState, PulseEngine
from cosim.controllers.trio import ON, TrioController, TrioProcess
from cosim.couplings.stepper import couple_stepper
from cosim.errors import ConfigurationError
from cosim.kernel import Simulation
from cosim.master import Plant
from cosim.presets import load_preset
from cosim.timebase import Priority

MS = 1_000_000


@pytest.mark.fmu
def test_trio_a_coupled_drive_counts_each_step_at_its_falling_active_edge_100_ns_after_the_leading_one(
        sim: Simulation) -> None:
    trio = TrioController(sim, encoder_at_atype=0)
    process = TrioProcess(trio, base=(3,))
    for name, value in (("ATYPE", 35), ("SERVO", ON), ("UNITS", 1), ("SPEED", 1000), ("ACCEL", 10**6),
                        ("DECEL", 10**6)):
        process.set(name, value)
    drive = Plant.load(sim, "Stepper", name="drive", fmi_version=3,
                       parameters={**load_preset("nema17_17hs16_2004s1"), "limit_neg_position": -1.0})
    couple_stepper(trio.step_dir(3), drive)

    def job() -> Generator[Any, Any, None]:
        yield sim.at(0, Priority.HOST)
        yield process.move(1)  # one step

    sim.process(job())
    sim.run(until=5 * MS)
    (leading,), _ = sim.trace.pulses("trio.axis3.step")
    assert leading % MS == 0  # the pulse starts at a servo tick
    counted_ns = float(drive.read("last_pulse_time")) * 1e9
    assert counted_ns == pytest.approx(leading + 100, abs=1e-3)  # the falling edge, 100 ns later
    assert int(drive.read("commanded_steps")) == 1


@pytest.mark.parametrize(("pulses", "accepted"), [(25, True), (26, False), (-25, True), (-26, False)])
def test_pokeys56u_runs_at_most_25_pulses_per_1_ms_slot(sim: Simulation, pulses: int, accepted: bool) -> None:
    engine = PulseEngine(sim, EngineConfig.for_model("56U"))
    entry = (pulses, 0, 0)
    if not accepted:
        with pytest.raises(ConfigurationError, match=f"{abs(pulses)}"):
            engine.fill_buffer([entry])
        assert engine.buffer.level == 0  # nothing of the command is queued
        return
    engine.fill_buffer([entry])
    engine.set_state(EngineState.BUFFER)
    sim.run(until=2 * MS)
    t, direction = sim.trace.pulses("pokeys.x.step")
    assert t.size == 25 and (t[-1] - t[0]) < MS  # all 25 in one 1 ms slot
    assert set(direction.tolist()) == {1 if pulses > 0 else 0}
    assert engine.device.max_rate_hz == 25_000  # "equates to 25 kHz maximum pulse frequency"


def test_pmac_background_plcs_scan_every_200_us_from_0_lowest_number_first(sim: Simulation) -> None:
    """I5=2: the background PLCs may run (its default 1 runs PLC 0 only, Turbo Software Reference)."""
    pmac = Pmac(sim)
    pmac.load("I5=2\nOPEN PLC 2 CLEAR\nP2=P2+1\nCLOSE\nOPEN PLC 1 CLEAR\nP1=P2\nCLOSE\n", source="plcs.pmc")
    pmac.command("ENABLE PLC 2")
    pmac.command("ENABLE PLC 1")
    pmac.start()
    p = pmac.programs.memory.p
    counts = []
    for t_ns in (199_999, 200_001, 400_001, 1_000_001):
        sim.run(until=t_ns)
        counts.append((pmac.programs.scans, p[1], p[2]))
    # scan k: PLC 1 copies P2 as PLC 2 left it in scan k - 1, then PLC 2 counts
    assert counts == [(1, 0, 1), (2, 1, 2), (3, 2, 3), (6, 5, 6)]
