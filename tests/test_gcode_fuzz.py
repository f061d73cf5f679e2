"""The G-code reader never crashes: generated, mutated and random programs only ever get cosim's own errors.

A few hundred inputs per run (the same every run); ``bench/fuzz_gcode.py`` runs a million
(docs/reliability.md).
"""

from __future__ import annotations

import random

from gcode_fuzz_programs import draw, exercise, seeds


def test_four_hundred_fuzzed_programs_are_read_or_refused_without_a_crash() -> None:
    rng = random.Random(26)
    texts = seeds()
    ran = sum(exercise(draw(rng, texts)) for _ in range(400))
    assert ran > 0  # some run through to a tool path: the inputs reach the interpreter's depths


def test_four_hundred_fuzzed_programs_run_live_as_a_machine_runs_them_without_a_crash() -> None:
    """Live: each M66 stops the interpreter and it goes on with a value; waits, cycle start and an A axis."""
    rng = random.Random(66)
    texts = seeds()
    ran = sum(exercise(draw(rng, texts), live=True) for _ in range(400))
    assert ran > 0
    assert exercise("G21\nG1 X1 A2 F10\nM66 P0 L3 Q1\no1 if [#5399 GT 0]\nM0\no1 endif\nM66 E3 L0\nM2\n",
                    live=True) == 1


def test_pathological_inputs_are_refused_with_cosims_error() -> None:
    for text in ["G0 X" + "[" * 3000 + "1" + "]" * 3000, "G0 X" + "#" * 3000 + "1", "G0 X" + "9" * 400,
                 "#1=[" + "9" * 200 + "*" + "9" * 200 + "]\nG0 X#1", "G0 X[sin[" + "9" * 400 + "]]",
                 "o1 while [1]\no1 endwhile\nM2", "o<a> sub\no<a> call\no<a> endsub\no<a> call\nM2",
                 "\x00", "G0 X1 " * 5000,
                 "G1 X[[17 ** atan[13.8787]/[-21.58]]] F2644\nM2",  # 1e181: squared, it overflowed a double
                 "G4 P100000\nM2"]:
        assert exercise(text) == 0
    assert exercise("\ufeffG0 X1\nM2") == 1  # a byte order mark (Windows editors) is not G-code: it is skipped
