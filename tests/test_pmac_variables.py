"""The Turbo I-variable space and the P, Q, M variables in every form (issue 27, items 2 and 3).

Numbers are the Turbo PMAC Software Reference's: Ixx92 (jog move calculation time) 1..8,388,607 ms,
default 10; Isx11 (countdown timer) -8,388,608..8,388,607 servo cycles; I59 0..3; Ixx66 0..32,767,
default 6527; Ixx08 default 96; the timer example ``I5111=2259`` is one second at the default I10.
"""

from __future__ import annotations

from fractions import Fraction

import pytest

from cosim.controllers.pmac import Pmac, ivartable
from cosim.controllers.pmac.mvars import q_offset
from cosim.errors import ConfigurationError
from cosim.kernel import Simulation


def test_every_i_variable_takes_its_default_and_has_a_name() -> None:
    for number in range(8192):
        item = ivartable.spec(number)
        assert ivartable.check(number, item.default) == item.default, number
        assert ivartable.name(number).startswith(f"I{number} (")


@pytest.mark.parametrize(("number", "value", "allowed"), [
    (192, 0, r"integers 1..8388607 \(ms\)"),  # Ixx92 jog move calculation time: 0 is not allowed
    (5111, 1 << 23, r"integers -8388608..8388607 \(servo cycles\)"),  # Isx11
    (59, 4, r"integers 0..3"),  # I59 motor/C.S. group select
    (166, 32768, r"integers 0..32767 \(PWM_CLK cycles\)"),  # Ixx66 PWM scale factor
    (108, -1, r"integers 0..8388607"),  # Ixx08 position scale factor
    (8010, 1 << 24, r"integers 0..16777215"),  # a conversion-table line
])
def test_a_value_out_of_the_documented_range_is_refused_with_the_range(number: int, value: int, allowed: str) -> None:
    with pytest.raises(ConfigurationError, match=rf"I{number} \(.*\) = {value} is not allowed \(allowed: {allowed}\)"):
        ivartable.check(number, value)


def test_defaults_from_the_reference() -> None:
    assert ivartable.default(192) == 10 and ivartable.default(166) == 6527 and ivartable.default(108) == 96
    assert ivartable.default(5194) == 1644 and ivartable.default(5189) == 1000 and ivartable.default(10) == 3713707


def test_every_assignment_is_stored_readable_back_and_listed_as_not_modelled(sim: Simulation) -> None:
    pmac = Pmac(sim)
    pmac.load("I130=2500 I7003=1746\nI5213,15,100=10\nI100..131=0\nP1=I130+1 P2=I(100+30) P3=I6613\n",
              source="setup.pmc")
    memory = pmac.programs.memory
    assert pmac.get_ivar(130) == 0  # I100..131=0 came after I130=2500
    assert pmac.get_ivar(5213) == pmac.get_ivar(6613) == 10 and pmac.get_ivar(6713 - 100) == 10  # 15 systems
    assert (memory.p[1], memory.p[2], memory.p[3]) == (1, 0, 10)
    listed = {item.name: item for item in sim.notes.unmodelled()}
    assert listed["I7003"].value == 1746 and listed["I7003"].where == "setup.pmc:1:11"
    assert listed["I130"].value == 0 and "I123" in listed
    assert "I122" not in listed and "I5213" not in listed  # Ixx22 (RAPID speed), Isx13 (segmentation) act
    pmac.command("I130=*")  # the reference's default
    assert pmac.get_ivar(130) == 2000


def test_modelled_i_variables_act() -> None:
    sim = Simulation()
    pmac = Pmac(sim)
    pmac.load("I5194=5000 I5187=7\n&1 #1->1X\n", source="s.pmc")
    assert pmac.coordinate_system(1).ix94 == 5000 and pmac.coordinate_system(1).ix87 == 7
    assert not any(item.name in ("I5194", "I5187") for item in sim.notes.unmodelled())


def test_the_countdown_timer_counts_servo_cycles(sim: Simulation) -> None:
    """The reference's example: I5111=2259 is one second (2259 servo cycles of 442.7 us); it does not roll over."""
    pmac = Pmac(sim)
    pmac.load("I5111=2259 I5112=-8388607\n", source="t.pmc")
    pmac.start()
    sim.run(until=pmac.clock.t(2258) + 1)  # cycles 0..2258 have run: 2259 of them
    assert pmac.get_ivar(5111) == 0 and pmac.get_ivar(5112) == -(1 << 23)
    sim.run(until=pmac.clock.t(2259) + 1)
    assert pmac.get_ivar(5111) == -1 and pmac.get_ivar(5112) == -(1 << 23)


def test_q_variables_belong_to_the_coordinate_system(sim: Simulation) -> None:
    """&2's Q0 is &1's Q4096 (the bits of s - 1 reversed, times 512); online commands use the host's &n."""
    assert [q_offset(s) for s in (1, 2, 3, 4, 5, 16)] == [0, 4096, 2048, 6144, 1024, 7680]
    pmac = Pmac(sim)
    pmac.load("&1 Q10=1\n&2 Q10=2\n&1 P1=Q10 P2=Q4106\n&2 P3=Q10\n", source="q.pmc")
    assert pmac.programs.memory.p[1:4] == [1, 2, 2]


def test_indirect_variables_of_every_kind(sim: Simulation) -> None:
    pmac = Pmac(sim)
    pmac.load("P1=10\nP(P1+1)=5\nQ(P1)=P11*2\nM20->*\nM(P1+10)=7\nI(P1*10+30)=1234\nP2=Q10+M20+I130\n",
              source="i.pmc")
    memory = pmac.programs.memory
    assert memory.p[11] == 5 and memory.p[2] == 10 + 7 + 1234
    with pytest.raises(ConfigurationError, match=r"^cmd:1:1: P\(8192\) is not allowed \(allowed: P0..P8191\)$"):
        pmac.command("P(8191+1)=1", source="cmd")


def test_m_variable_definitions_of_every_form(sim: Simulation) -> None:
    """X:/Y: bit fields, D:/DP:/L:/F: words, TWS: thumbwheels, ->*, and the range M0..8191->* (undefine them all)."""
    pmac = Pmac(sim)
    pmac.load("M1->X:$078000,0,24,S M2->Y:$078005,14 M3->D:$00008B M4->DP:$060000 M5->L:$006000 M6->F:$060001\n"
              "M7->TWS:1 M8->*\nM2=1 M3=123456789 M5=0.5 M8=3\nP1=M2 P2=M3 P3=M5 P4=M8\n", source="m.pmc")
    memory = pmac.programs.memory
    assert memory.p[1:5] == [1, 123456789, Fraction(1, 2), 3]
    pmac.start()  # definitions are listed once the registers the model has are known
    listed = {item.name for item in sim.notes.unmodelled()}
    assert {"M2->", "M3->", "M4->", "M5->", "M6->", "M7->"} <= listed  # registers the model does not have
    pmac.command("M0..8191->*")
    assert memory.definitions[2].target is None and memory.definitions[8191].target is None
