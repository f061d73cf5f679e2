"""One time unit: the same machine at 1 ns and at 10 ns resolution gives the same edges in physical time.

Controllers derive every period from the simulation's resolution (``sim.ticks``), so a run at
10 ns per tick must show every edge of the 1 ns run, floored to 10 ns::

    1 ns run      edge at 1_234_567 ns
    10 ns run     edge at   123_456 ticks  (= 1_234_560 ns: the same instant, floored to a tick)

(floor(floor(x) / 10) = floor(x / 10): pulse rules that floor at 1 ns floor the same way at 10 ns).
Where every instant is a multiple of 10 ns the two runs agree exactly.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np

from cosim import rigs
from cosim.controllers.pmac import LinearMove
from cosim.controllers.trio import TrioController
from cosim.controllers.trio.basic import example
from cosim.kernel import Simulation
from cosim.plants.analytic import IdealConveyor
from cosim.timebase import TimeBase
from cosim.trace import Trace

TEN_NS = TimeBase(Fraction(1, 10**8))


def _same_edges_floored(fine: Trace, coarse: Trace, factor: int) -> int:
    """Assert every signal of ``coarse`` is ``fine`` floored to ``factor`` ticks; return the edges compared."""
    assert fine.names() == coarse.names()
    compared = 0
    for name in fine.names():
        if fine.info[name].kind == "pulse":
            (t1, d1), (t10, d10) = fine.pulses(name), coarse.pulses(name)
            assert t10.tolist() == (t1 // factor).tolist(), name
            assert d10.tolist() == d1.tolist(), name
            compared += t1.size
        else:
            (t1, v1), (t10, v10) = fine.edges(name), coarse.edges(name)
            assert t10.tolist() == (t1 // factor).tolist(), name
            np.testing.assert_array_equal(v10, v1, err_msg=name)
            compared += t1.size
    return compared


def _trio_run(timebase: TimeBase) -> Trace:
    sim = Simulation(timebase=timebase, seed=7)
    trio = TrioController(sim)
    example("tn20_81").start(trio)
    sim.run(until=sim.ticks("2200 ms"))
    return sim.trace


def test_trio_tn20_81_at_10_ns_has_the_1_ns_gate_edges_and_pulses_floored_to_10_ns() -> None:
    fine, coarse = _trio_run(TimeBase()), _trio_run(TEN_NS)
    assert _same_edges_floored(fine, coarse, 10) > 8_000  # 0 -> 300 -> 0 units at UNITS = 16, gate edges, ...
    gate_t, gate_v = fine.edges("trio.axis3.gate")
    assert gate_v.tolist()[:5] == [0, 1, 0, 1, 0] and gate_t.size >= 9  # the note's ON/OFF pairs, forward and back


def _pmac_run(timebase: TimeBase) -> Trace:
    """External time base: a 50 counts/ms master (an edge every 20 us) and a 0.5 ms servo period
    (I10 = 4,194,304): every instant is a multiple of 10 ns."""
    sim = Simulation(timebase=timebase)
    belt = IdealConveyor(sim, speed_counts_per_ms=50, marks=[1000])
    rig = rigs.triggered_time_base(sim, belt, belt.mark, scale_factor=256, i10=4_194_304)
    rig.cs.run_program([LinearMove(2000, 64_000, 20)])
    rig.pmac.set_ivar(8000, 0xB78008)  # armed from the start: the mark at 20 ms starts the move
    rig.pmac.start()
    sim.run(until=sim.ticks("80 ms"))
    return sim.trace


def test_pmac_triggered_time_base_at_10_ns_gives_exactly_the_1_ns_run() -> None:
    fine, coarse = _pmac_run(TimeBase()), _pmac_run(TEN_NS)
    assert _same_edges_floored(fine, coarse, 10) > 400
    assert all((fine.edges(name)[0] % 10 == 0).all() for name in fine.names())  # so floored = exact here
    t_mark, v_mark = fine.edges("conveyor.mark")
    assert t_mark.tolist()[:2] == [0, 20_000_000] and v_mark.tolist()[:2] == [0, 1]  # 1000 counts at 50 counts/ms
    assert fine.values_at("pmac.ect.time_zero_pos", [fine.end_t]).tolist() == [1000.0]
    assert fine.values_at("pmac.motor1.cmd_pos", [fine.end_t])[0] > 0  # the triggered move ran
