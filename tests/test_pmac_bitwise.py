"""The bit-by-bit operators ``&``, ``|``, ``^`` of Turbo PMAC expressions, and ``&n`` beside them.

The Turbo PMAC/PMAC2 Software Reference (Mathematical Features) lists ``&`` (and), ``|`` (or) and
``^`` (exclusive or) as operators; ``&`` has the priority of ``*`` and ``/``, ``|`` and ``^`` that of
``+`` and ``-``; they act on the integer and the fraction bits. Its examples are written below as
it writes them. ``&n`` also selects a coordinate system: at the start of a command it does; after
an operand it is the operator (spaces do not matter in PMAC syntax), as the expression reads on.
"""

from __future__ import annotations

from fractions import Fraction

import pytest

from cosim.controllers.pmac import Pmac
from cosim.controllers.pmac.program import parse_text
from cosim.controllers.pmac.syntax import parse_line
from cosim.kernel import Simulation


@pytest.mark.parametrize(
    ("expression", "result"),
    [
        # the reference's table for & (bit-by-bit and)
        ("3&1", 1), ("3&2", 2), ("3&3", 3), ("3&4", 0), ("3&-3", 1),
        ("0.875&1.75", Fraction("0.75")), ("0.875&-1.75", Fraction("0.25")),
        # the reference's table for | (bit-by-bit or)
        ("4|3", 7), ("3|2", 3), ("3|3", 3), ("$F0|$4", 0xF4), ("3|-3", -1), ("0.5|0.375", Fraction("0.875")),
        # ^ (exclusive or): bits set in one operand only
        ("$F0^$FF", 0x0F), ("5^5", 0), ("0.5^0.75", Fraction("0.25")),
        # & binds like * and /, | and ^ like + and -, left to right
        ("1+3&1", 2), ("2*3&2", 2), ("4|3&1", 5), ("6&3*2", 4), ("1|2^3", 0),
    ],
)
def test_the_reference_examples_of_the_bit_operators(sim: Simulation, expression: str, result: object) -> None:
    pmac = Pmac(sim)
    pmac.load(f"P1={expression}\n", source="b.pmc")
    assert pmac.programs.memory.p[1] == result


def test_after_an_operand_an_ampersand_is_the_operator_at_a_command_start_it_selects(sim: Simulation) -> None:
    """``&2 P1=3 &1 Q1=5``: P1 = 3&1 = 1 (the expression reads on), and Q1 is &2's (no selection happened)."""
    pmac = Pmac(sim)
    pmac.load("&2 P1=3 &1 Q1=5\n&1 Q1=7\n", source="s.pmc")
    memory = pmac.programs.memory
    assert memory.p[1] == 1
    assert memory.read("Q", 1, 2, None) == 5  # type: ignore[arg-type]
    assert memory.read("Q", 1, 1, None) == 7  # type: ignore[arg-type]


def test_ampersand_in_program_expressions_and_conditions() -> None:
    text = ("OPEN PLC 1 CLEAR\nP1=P2&3\nIF(M1&4>0)\nP3=M1&$F0|P4^1\nENDIF\nCLOSE\n"
            "OPEN PROG 1 CLEAR\nADDRESS&2#1\nQ1=Q1&$FF\nCLOSE\n")
    parsed = parse_text(text, source="p.pmc")
    assert [type(item).__name__ for item in parsed.items] == ["Buffer", "Buffer"]
    (assign,) = parse_line("P1=P2&3", context="program", source="p.pmc", line=1)
    assert str(assign.expr.rest) == "(('&', Num(value=3)),)"  # type: ignore[attr-defined]


def test_a_plc_tests_a_bit_with_ampersand(sim: Simulation) -> None:
    """``IF(M1&4>0)``: bit 2 of M1 (value 4 = bit 2 set, 3 = not)."""
    pmac = Pmac(sim)
    pmac.load("I5=2\nM1->*\nM1=5 P9=3\nOPEN PLC 1 CLEAR\nIF(M1&4>0)\nP2=1\nELSE\nP2=2\nENDIF\nIF(P9&4>0)\nP3=1\n"
              "ELSE\nP3=2\nENDIF\nDISABLE PLC 1\nCLOSE\nENABLE PLC 1\n", source="t.pmc")
    pmac.start()
    sim.run(until=sim.ticks("1 ms"))
    assert (pmac.programs.memory.p[2], pmac.programs.memory.p[3]) == (1, 2)


def test_xor_after_a_variable_in_a_program_is_the_operator_and_a_trigger_word_stays_one() -> None:
    (xor,) = parse_line("P1=P2^$FF", context="program", source="x.pmc", line=1)
    assert type(xor).__name__ == "Assign"
    (move,) = parse_line("X10^5", context="program", source="x.pmc", line=1)
    assert move.axes[0].trigger is not None  # type: ignore[attr-defined]


@pytest.mark.parametrize(("p2", "approx"), [(10, 1), (10.5, 1), (12, 0), (8, 0)])
def test_approximately_equal_is_within_one(sim: Simulation, p2: float, approx: int) -> None:
    """The comparators ``~`` (approximately equal: within one) and ``!~`` of the reference's summary."""
    pmac = Pmac(sim)
    pmac.load(f"I5=2 P1=10 P2={p2}\nOPEN PLC 1 CLEAR\nIF (P1~P2)\nP3=1\nENDIF\nIF (P1!~P2)\nP4=1\nENDIF\n"
              "DISABLE PLC 1\nCLOSE\nENABLE PLC 1\n", source="a.pmc")
    pmac.start()
    sim.run(until=sim.ticks("1 ms"))
    assert (pmac.programs.memory.p[3], pmac.programs.memory.p[4]) == (approx, 1 - approx)
