"""Fuzzing the Trio BASIC parser and interpreter: generated, mutated and random programs may only raise the
project's own errors (a few seconds here; ``bench/fuzz_trio_basic.py`` runs for as long as it is given)."""

from __future__ import annotations

import random

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from trio_fuzz_programs import ODD, exercise, generate, mutate

from cosim.controllers.trio.basic import example

FAST = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow], database=None)
NOTE = example("tn20_81").text


@FAST
@given(st.integers(min_value=0, max_value=2**32 - 1))
def test_generated_programs_run_or_stop_with_our_errors(seed: int) -> None:
    exercise(generate(random.Random(seed)), until_ms=20)


@FAST
@given(st.integers(min_value=0, max_value=2**32 - 1), st.booleans())
def test_mutated_programs_run_or_stop_with_our_errors(seed: int, note: bool) -> None:
    rng = random.Random(seed)
    exercise(mutate(rng, NOTE if note else generate(rng)), until_ms=20)


@FAST
@given(st.lists(st.one_of(st.sampled_from(ODD), st.text(max_size=8), st.sampled_from(NOTE.split())), max_size=40))
def test_random_text_parses_or_is_refused_with_our_errors(pieces: list[str]) -> None:
    exercise("".join(pieces), until_ms=5)


def test_the_generator_writes_programs_that_mostly_parse() -> None:
    """The fuzz test is only worth its time if most generated programs get past the parser and run."""
    rng = random.Random(1)
    assert sum(exercise(generate(rng), until_ms=2) for _ in range(40)) >= 20
