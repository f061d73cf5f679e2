"""One time unit: the same PoKeys run at 1 ns and at 10 ns resolution gives the same physical times.

Every period of the engine and the host comes from the simulation's resolution (``sim.ticks``), so
a run at 10 ns ticks places every edge and pulse at the same instant [ns] as at 1 ns, as long as
the instants are whole multiples of 10 ns. Pulse k of a slot with n pulses is at
``slot_start + dir_setup + (k * 1 ms) // n``, floored to the resolution: it is a multiple of 10 ns
for n dividing 100 000 (1, 2, 4, 5, 8, 10, 16, 20, 25), which is what this job uses.

The job (3 axes, buffered by the host over a fixed 200 us link, no FMUs)::

    t [ms]   0 ......... 20 ............ 35 .......   limit+ x trips   150.5      200.5
    host     prefill 10  | stalled 15 ms |  refills      (state 100)      jog off   homing x: search 2/slot,
    buffer   ~10 ....... 0 (underrun) .. refilled ...                     the limit back-off 0.2/slot
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest

from cosim.controllers.pokeys import AxisConfig, EngineConfig, EngineState, PulseEngine, encode_entry
from cosim.controllers.pokeys.host import HostApp, Stall
from cosim.controllers.pokeys.link import LinkProfile
from cosim.couplings.ideal_axis import PositionSwitch
from cosim.errors import ConfigurationError
from cosim.kernel import Simulation
from cosim.timebase import Priority, TimeBase

NS = TimeBase()
TEN_NS = TimeBase(Fraction(1, 10**8))
MS = 1_000_000  # [ns]
FIXED = LinkProfile("fixed", latency_ns=200_000, jitter_ns=0)
EVEN = (1, 2, 4, 5, 8, 10, 16, 20, 25)  # pulses per slot whose instants are whole multiples of 10 ns
JOB = [encode_entry((EVEN[k % 9], -EVEN[(k + 3) % 9], EVEN[(2 * k) % 9] if k % 4 else 0)) for k in range(120)]


def _run(timebase: TimeBase) -> tuple[dict[str, list[tuple[int, int]]], PulseEngine]:
    """Every recorded signal of the run as ``[(t_ns, value or direction)]``, and the engine."""
    sim = Simulation(timebase=timebase, seed=1)
    x = AxisConfig(max_speed_hz=20_000, limit_pos_enabled=True, home_enabled=True)
    engine = PulseEngine(sim, EngineConfig(axes=(x, AxisConfig(), AxisConfig())))
    PositionSwitch(sim, engine.steps[0], engine.switches.limit_pos[0], lambda p: p >= 900)
    PositionSwitch(sim, engine.steps[0], engine.switches.home[0], lambda p: p <= 700)
    HostApp(sim, engine, JOB, link=FIXED, prefill_slots=10, stalls=[Stall(20 * MS, 15 * MS)])

    def home() -> None:
        engine.set_state(EngineState.STOPPED)
        engine.start_homing([0])

    sim.call_at(sim.ticks("150.5 ms"), Priority.HOST, lambda: engine.jog(0, -2_000))  # off the limit (ignored)
    sim.call_at(sim.ticks("200.5 ms"), Priority.HOST, home)
    sim.run(until=sim.ticks("400 ms"))
    ns_per_tick = int(timebase.resolution_s * 10**9)
    signals = {}
    for name in sim.trace.names():
        if sim.trace.info[name].kind == "pulse":
            t, d = sim.trace.pulses(name)
        else:
            t, d = sim.trace.edges(name)
        signals[name] = list(zip((t * ns_per_tick).tolist(), d.astype(np.int64).tolist(), strict=True))
    return signals, engine


def test_the_same_run_at_1_ns_and_at_10_ns_gives_the_same_edges_and_pulses_in_physical_time() -> None:
    fine, fine_engine = _run(NS)
    coarse, coarse_engine = _run(TEN_NS)
    assert coarse_engine.slot_ticks == 100_000 and fine_engine.slot_ticks == 1_000_000
    assert sorted(coarse) == sorted(fine)
    for name in fine:
        assert coarse[name] == fine[name], name
    # the run is not empty: pulses on every axis, an underrun, a limit stop, homing done
    assert all(len(fine[f"pokeys.{a}.step"]) > 100 for a in "xyz")
    assert [(u.t_start, u.slots) for u in coarse_engine.underruns] == [
        (u.t_start // 10, u.slots) for u in fine_engine.underruns] != []
    states = [v for _, v in fine["pokeys.state"]]
    assert 100 in states and states[-1] == 20
    # buffer mode from the 1 ms slot: 1 pulse, then 2 (the second 500 us later), 5 us after the slot start
    assert fine["pokeys.x.step"][:3] == [(MS + 5_000, 1), (2 * MS + 5_000, 1), (2 * MS + 505_000, 1)]


def test_pulse_instants_are_floored_to_the_resolution() -> None:
    """3 pulses in a slot: 1 ms / 3 is 333 333.3 ns, floored to 333 333 ns at 1 ns and 333 330 ns at 10 ns."""
    placed = []
    for timebase in (NS, TEN_NS):
        sim = Simulation(timebase=timebase)
        engine = PulseEngine(sim)
        engine.fill_buffer([encode_entry((3, 0, 0))])
        engine.set_state(EngineState.BUFFER)
        sim.run(until=sim.ticks("1 ms"))
        placed.append((sim.trace.pulses("pokeys.x.step")[0] * int(timebase.resolution_s * 10**9)).tolist())
    assert placed == [[5_000, 338_333, 671_666], [5_000, 338_330, 671_660]]


def test_a_coarse_resolution_gets_1_ms_slots_not_1_s() -> None:
    sim = Simulation(timebase=TimeBase(Fraction(1, 10**6)))  # 1 us ticks
    engine = PulseEngine(sim)
    engine.fill_buffer([encode_entry((25, 0, 0))] * 2)
    engine.set_state(EngineState.BUFFER)
    sim.run(until=sim.ticks("3 ms"))
    t = sim.trace.pulses("pokeys.x.step")[0].tolist()
    assert engine.slot_ticks == 1_000 and t[:2] == [5, 45] and t[25] == 1_005 and len(t) == 50


@pytest.mark.parametrize(("fields", "message"), [
    ({"dir_setup_ns": 5_005}, r"dir_setup_ns = 5005 ns is not a whole number of ticks of the resolution 10 ns"),
    ({"pulse_width_ns": 2_001}, r"pulse_width_ns = 2001 ns is not a whole number of ticks of the resolution 10 ns"),
])
def test_a_time_that_is_not_a_whole_number_of_ticks_is_refused(fields: dict[str, int], message: str) -> None:
    with pytest.raises(ConfigurationError, match=message):
        PulseEngine(Simulation(timebase=TEN_NS), EngineConfig(**fields))  # type: ignore[arg-type]


def test_host_times_in_ns_that_are_not_whole_ticks_are_refused() -> None:
    sim = Simulation(timebase=TEN_NS)
    engine = PulseEngine(sim)
    with pytest.raises(ConfigurationError, match=r"stall t_start_ns = 1000005 ns is not a whole number of ticks"):
        HostApp(sim, engine, JOB, link=FIXED, stalls=[Stall(1_000_005, 10 * MS)])
