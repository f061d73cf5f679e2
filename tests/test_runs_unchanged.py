"""Every bundled run records the same trace as before the hot-path rewrites (issue 29).

The stored table (``tests/data/run_digests.json``, see ``tests/run_digests.py``) was taken with the
code before the rewrite; each run's signals must match it edge for edge and pulse for pulse, and
the run's verdict must be the same.
"""

from __future__ import annotations

import json

import pytest
from run_digests import TABLE, run_names, run_with_trace, signal_digests

pytestmark = pytest.mark.fmu

STORED = json.loads(TABLE.read_text())


def test_the_table_covers_every_bundled_run() -> None:
    assert sorted(STORED) == sorted(run_names())


@pytest.mark.parametrize("name", sorted(STORED))
def test_every_stored_signal_of_the_run_is_unchanged(name: str) -> None:
    result, trace = run_with_trace(name)
    stored = STORED[name]
    assert result.verdict == stored["verdict"], result.table()
    digests = signal_digests(trace)
    missing = sorted(set(stored["signals"]) - set(digests))
    changed = sorted(n for n, d in stored["signals"].items() if n in digests and digests[n] != d)
    assert not missing and not changed, f"{name}: missing {missing}, changed {changed}"
