"""The bundled runs with Stepper FMUs record the same trace as before the Stepper's speed work (issue 19).

The stepper coupling, the Stepper's solver and the way segments reach it changed; the controller's
pulses and edges, the switch inputs and the ``commanded_steps`` the couplings record must not. Each
digest covers every pulse (instant, direction) and every change (instant, value) of every signal
of the trace, which is what the run's VCD shows; the literals were taken with the code before the
change (commit 61776df; the mill's again with the code before the merge of that change, after the
PoKeys machines gained the spindle signals of G-code jobs: the same before and after the merge).
"""

from __future__ import annotations

import hashlib

import numpy as np
import pytest

from cosim.catalog import load
from cosim.fmubuild import CHECKOUT
from cosim.kernel import Simulation
from cosim.runner import run_scenario
from cosim.trace import Trace

pytestmark = pytest.mark.fmu


#: Signals added after the digests were taken (the third wave's job signal, cosim.job): left out.
ADDED_LATER = frozenset({"pokeys.job"})


def trace_digest(trace: Trace) -> str:
    """SHA-256 over every signal's name, pulses or changes: instants as int64, values as float64."""
    h = hashlib.sha256()
    for name in sorted(set(trace.names()) - ADDED_LATER):
        t, v = trace.pulses(name) if trace.info[name].kind == "pulse" else trace.edges(name)
        h.update(name.encode())
        h.update(np.asarray(t, dtype="<i8").tobytes())
        h.update(np.asarray(v, dtype="<f8").tobytes())
    return h.hexdigest()


@pytest.mark.parametrize(("run", "digest"), [
    ("pokeys_job", "4f30237ea95d673bcc86046b962a51a559d1347e8b8cde192a3a9026566929a0"),
    ("examples/pokeys_mill/mill.toml", "82b995f06a929a23dcf3753eeb86f88a7e5e8560c030ff483e4363f8287b3763"),
])
def test_every_pulse_and_edge_of_the_bundled_stepper_runs_is_unchanged(run: str, digest: str,
                                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    assert CHECKOUT is not None
    traces: list[Trace] = []
    close = Simulation.close

    def keep_trace(self: Simulation) -> None:
        traces.append(self.trace)
        close(self)

    monkeypatch.setattr(Simulation, "close", keep_trace)
    result = run_scenario(load(CHECKOUT / run if run.endswith(".toml") else run))
    assert result.verdict == "PASS", result.table()
    assert trace_digest(traces[-1]) == digest
