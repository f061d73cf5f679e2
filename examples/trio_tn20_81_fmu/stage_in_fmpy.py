"""The TN20-81 program as an FMU driving a stage model of your own, in fmpy.

The machine file ``tn20_81.toml`` beside this script is exported as an FMI 3.0 FMU (its controller
only: ``plants = "outside"``), then stepped with fmpy's FMI 3.0 API next to a stage model (here a
few lines of Python: a carriage on a stiff, damped drive following the commanded position). The
FMU returns early at every edge of the laser gate, so each mark is taken at the stage position of
the edge's exact instant, not at the next communication point::

    python examples/trio_tn20_81_fmu/stage_in_fmpy.py
"""

from __future__ import annotations

import math
import tempfile
from dataclasses import dataclass
from pathlib import Path

from fmpy import extract, read_model_description
from fmpy.fmi3 import FMU3Slave

from cosim.fmu_export.package import export_fmu

HERE = Path(__file__).resolve().parent
STEPS_PER_MM = 16  # UNITS = 16 in tn20_81.bas


@dataclass
class Stage:
    """Your stage: a carriage on a drive of natural frequency ``f_hz`` and damping ``zeta`` [mm, mm/s]."""

    f_hz: float = 50.0
    zeta: float = 0.7
    x_mm: float = 0.0
    v_mm_s: float = 0.0

    def advance(self, dt_s: float, target_mm: float) -> None:
        """Follow ``target_mm`` for ``dt_s`` seconds (semi-implicit Euler, 0.1 ms sub-steps)."""
        omega = 2 * math.pi * self.f_hz
        n = max(1, round(dt_s / 1e-4))
        for _ in range(n):
            accel = omega**2 * (target_mm - self.x_mm) - 2 * self.zeta * omega * self.v_mm_s
            self.v_mm_s += accel * dt_s / n
            self.x_mm += self.v_mm_s * dt_s / n


@dataclass(frozen=True)
class Mark:
    """A gate edge: when [s], the gate after it, the commanded and the stage position there [mm]."""

    t_s: float
    gate: bool
    commanded_mm: float
    stage_mm: float


def engrave(fmu_path: Path, *, stop_s: float = 0.9, step_s: float = 1e-3) -> list[Mark]:
    """Run the machine FMU with the stage model; the laser gate's edges."""
    md = read_model_description(str(fmu_path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmu = FMU3Slave(guid=md.guid, unzipDirectory=extract(str(fmu_path)),
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="engraver")
    fmu.instantiate(eventModeUsed=True, earlyReturnAllowed=True)
    fmu.enterInitializationMode(startTime=0.0, stopTime=stop_s)
    fmu.exitInitializationMode()
    fmu.updateDiscreteStates()  # FMI 3.0: event mode first, when the importer uses it
    fmu.enterStepMode()
    stage, marks, t, k = Stage(), [], 0.0, 0
    while t < stop_s - step_s / 2:
        commanded_mm = fmu.getInt32([vr["x_steps"]])[0] / STEPS_PER_MM
        event, _, early, reached = fmu.doStep(t, (k + 1) * step_s - t)
        stage.advance(reached - t, commanded_mm)
        t = reached
        if event:  # an edge of the gate or the direction at `reached`: before it, then after it
            before = fmu.getBoolean([vr["laser_gate"]])[0]
            fmu.enterEventMode()
            fmu.updateDiscreteStates()
            fmu.enterStepMode()
            after = fmu.getBoolean([vr["laser_gate"]])[0]
            if after != before:
                steps = fmu.getInt32([vr["x_steps"]])[0]
                marks.append(Mark(t, after, steps / STEPS_PER_MM, stage.x_mm))
        if not early:
            k += 1
    fmu.terminate()
    fmu.freeInstance()
    return marks


def main() -> list[Mark]:
    with tempfile.TemporaryDirectory() as tmp:
        fmu = export_fmu(HERE / "tn20_81.toml", Path(tmp) / "tn20_81.fmu").path
        marks = engrave(fmu)
    for mark in marks:
        print(f"t = {mark.t_s * 1e3:10.6f} ms  gate {'on ' if mark.gate else 'off'}  commanded "
              f"{mark.commanded_mm:8.4f} mm  stage {mark.stage_mm:8.4f} mm")
    return marks


if __name__ == "__main__":
    main()
