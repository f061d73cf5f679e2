"""The console (issue 28, item 5): every PRINT line is kept with its time, in the results' ``console.txt``;
a machine file feeds a channel for INPUT ([[channel]]); a background process stays out of the job."""

from __future__ import annotations

import json
from pathlib import Path

from cosim.catalog import load
from cosim.runner import run_scenario

MACHINE = """
[machine]
description = "console test"
until = "20 ms"

[controller]
family = "trio"

[[program]]
file = "ask.bas"
[[program]]
file = "beat.bas"
process = 5
job = false

[[channel]]
channel = 0
at = ["3 ms", "7 ms"]
text = ["2", "5\\r"]
"""


def test_print_lines_are_kept_with_their_time_in_console_txt(tmp_path: Path) -> None:
    """ask.bas prints a prompt at 0, reads "25" (its line ends at 7 ms) and prints the doubled value then;
    beat.bas (process 5, a high-priority task: it runs first at 0) prints every 5 ms for ever and is not part
    of the job."""
    (tmp_path / "m.toml").write_text(MACHINE)
    (tmp_path / "ask.bas").write_text('PRINT "count?"\nINPUT #0, n\nPRINT "twice: "; n * 2[0]\n')
    (tmp_path / "beat.bas").write_text('WHILE TRUE\n  PRINT #5, "beat"\n  WA(5)\nWEND\n')
    result = run_scenario(load(tmp_path / "m.toml"), out=tmp_path / "out", formats=())
    lines = (tmp_path / "out" / "console.txt").read_text().splitlines()
    assert lines == [
        "      0.000000 ms  [trio.proc5]  beat.bas:2  [#5] beat",
        "      0.000000 ms  [trio.proc1]  ask.bas:1  count?",
        "      5.000000 ms  [trio.proc5]  beat.bas:2  [#5] beat",
        "      7.000000 ms  [trio.proc1]  ask.bas:3  twice: 50",
        "     10.000000 ms  [trio.proc5]  beat.bas:2  [#5] beat",
        "     15.000000 ms  [trio.proc5]  beat.bas:2  [#5] beat",
    ]
    assert json.loads((tmp_path / "out" / "result.json").read_text())["console_lines"] == 6
    assert result.error is None
