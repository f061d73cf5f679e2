"""PoKeys host application: refill over a link, read pointer by accepted count, stalls and underruns.

Job: 300 slots of 10 pulses on x. Link 'fixed': 0.2 ms each way, no jitter. Host period 1 ms.

    prefill 20, stall 100..160 ms:
    t [ms]        100          120                         160  160.2  161
    host          |== stalled ====================================|fill
    buffer level  19 18 ... 1   0 ................................ 0     >0
    underrun                    |1 (slots 120..160: 41 slots) .............|0 at 161
    prefill 100: the level never drops below 39, no underrun
"""

from __future__ import annotations

import numpy as np
import pytest

from cosim.controllers.pokeys import EngineState, PulseEngine, encode_entry
from cosim.controllers.pokeys.host import HostApp, Stall
from cosim.controllers.pokeys.link import PROFILES, Link, LinkProfile
from cosim.errors import ConfigurationError
from cosim.kernel import Simulation

MS = 1_000_000
FIXED = LinkProfile("fixed", latency_ns=200_000, jitter_ns=0)
JOB = [encode_entry((10, 0, 0))] * 300


def _run(sim: Simulation, prefill: int, **host: object) -> tuple[PulseEngine, HostApp]:
    engine = PulseEngine(sim)
    app = HostApp(sim, engine, JOB, link=FIXED, prefill_slots=prefill, stalls=[Stall(100 * MS, 60 * MS)],
                  **host)  # type: ignore[arg-type]
    sim.run(until=500 * MS)
    return engine, app


def test_host_stall_causes_an_underrun_reported_with_start_and_length(sim: Simulation) -> None:
    engine, app = _run(sim, prefill=20)
    assert [(u.t_start, u.length, u.slots) for u in engine.underruns] == [(120 * MS, 41 * MS, 41)]
    t, v = sim.trace.edges("pokeys.underrun")
    assert t.tolist() == [0, 120 * MS, 161 * MS] and v.tolist() == [0, 1, 0]
    assert engine.status().positions == (3000, 0, 0) and app.finished  # slots are late, not lost
    pulses = sim.trace.pulses("pokeys.x.step")[0]
    assert not np.any((pulses >= 120 * MS) & (pulses < 161 * MS))


def test_enough_prefill_rides_out_the_same_stall(sim: Simulation) -> None:
    engine, _ = _run(sim, prefill=100)
    assert engine.underruns == []
    t, level = sim.trace.edges("pokeys.buffer_level")
    running = (t > 10 * MS) & (t < 250 * MS)
    assert level[running].min() == 39  # 99 after the 100 ms slot, minus the slots 101..160 ms
    assert engine.status().positions == (3000, 0, 0)


def test_the_end_of_the_job_is_not_an_underrun(sim: Simulation) -> None:
    engine, app = _run(sim, prefill=100)
    assert app.finished and engine.buffer.level == 0 and engine.state == EngineState.BUFFER
    assert engine.underruns == [] and sim.trace.edges("pokeys.underrun")[1].tolist() == [0]


def test_host_advances_its_read_pointer_by_the_accepted_count_only(sim: Simulation) -> None:
    engine = PulseEngine(sim)
    engine.fill_buffer([encode_entry((0, 0, 0))] * 120)  # someone left 120 slots in the buffer
    job = [encode_entry((k % 20 + 1, 0, 0)) for k in range(200)]
    app = HostApp(sim, engine, job, link=FIXED, prefill_slots=128)
    sim.run(until=400 * MS)
    # full: 8 taken, buffer mode starts, then one slot frees up per slot
    assert [(f.offered, f.accepted) for f in app.fills[:2]] == [(18, 8), (18, 1)]
    seg = sim.trace.segments("pokeys.x.step")
    assert seg["count"].tolist() == [k % 20 + 1 for k in range(200)]  # every slot once, in order
    assert (seg["t0"][0] - 5_000) % MS == 0 and engine.state == EngineState.BUFFER


def test_link_delays_are_seeded_from_the_simulation() -> None:
    def delays(seed: int, link: str) -> list[int]:
        sim = Simulation(seed=seed)
        link_ = Link(sim, link)
        return [link_.delay() for _ in range(200)]

    assert delays(3, "usb") == delays(3, "usb") != delays(4, "usb")
    for name in ("usb", "ethernet"):
        p = PROFILES[name]
        d = delays(1, name)
        assert p.latency_ns <= min(d) and max(d) <= p.latency_ns + p.jitter_ns and len(set(d)) > 100
    assert max(delays(1, "ethernet")) < min(delays(1, "usb")) + PROFILES["usb"].jitter_ns


@pytest.mark.parametrize("link", ["usb", "ethernet"])
def test_a_job_over_either_link_runs_without_underrun(sim: Simulation, link: str) -> None:
    engine = PulseEngine(sim)
    HostApp(sim, engine, JOB, link=link, prefill_slots=30)
    sim.run(until=400 * MS)
    assert engine.underruns == [] and engine.status().positions == (3000, 0, 0)


@pytest.mark.parametrize(("make", "message"), [
    (lambda s, e: HostApp(s, e, JOB, link="can"), r"link = 'can' is not allowed \(allowed: usb, ethernet"),
    (lambda s, e: HostApp(s, e, JOB, prefill_slots=129), r"prefill_slots = 129 is not allowed \(allowed: 1..128"),
    (lambda s, e: HostApp(s, e, [(30, 0, 0)]), r"host job slot 0 axis x: pulse count = 30|pulses per slot"),
    (lambda s, e: Stall(0, 0), r"stall duration_ns = 0 is not allowed"),
])
def test_bad_host_settings_are_refused(sim: Simulation, make: object, message: str) -> None:
    engine = PulseEngine(sim)
    with pytest.raises(ConfigurationError, match=message):
        make(sim, engine)  # type: ignore[operator]
