"""Fuzzing the PMAC text readers: generated and mutated text may only raise the project's own errors.

Hypothesis draws token soups (every kind of line end among the separators) and edits of real setup,
motion and PLC files (:mod:`cosim.testing.pmac_text`); each goes to ``parse_setup``, ``parse_text``
and the online command parser, and is loaded and run for 3 ms. A longer run is
``bench/bench_pmac_fuzz.py`` (see docs/pmac.md for its count).
"""

from __future__ import annotations

import random

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cosim.testing.pmac_text import CORPUS, SEPARATORS, TOKENS, feed, mutate

soup = st.lists(st.tuples(st.sampled_from(TOKENS) | st.text(max_size=3), st.sampled_from(SEPARATORS)),
                max_size=30).map(lambda parts: "".join(token + sep for token, sep in parts))
edited = st.tuples(st.sampled_from(CORPUS), st.integers(0, 2**32)).map(
    lambda pair: mutate(pair[0], random.Random(pair[1])))
FUZZ = settings(max_examples=150, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])


@FUZZ
@given(soup)
def test_token_soups_raise_only_our_errors(text: str) -> None:
    assert feed(text) is None


@FUZZ
@given(edited)
def test_edited_pmac_files_raise_only_our_errors(text: str) -> None:
    assert feed(text) is None


@settings(max_examples=60, deadline=None, derandomize=True)
@given(st.text(max_size=200))
def test_any_text_at_all(text: str) -> None:
    assert feed(text, readers=("preprocess", "parse_setup", "parse_text", "command")) is None
