"""PoKeys internal-to-buffer hazard fixed: clear the buffer (or wait 10 ms) before using buffer mode.

The run of ``pokeys_stale_slots`` with ``fix=clear`` (default) or ``fix=wait``: the host's move
ends exactly at the position it planned::

    clear:  [host move +100]                      x ends at P + 100
    wait:   [10 stale slots] 10 ms, read P', [move +100]   x ends at P' + 100

Check: the final position equals the planned one.
"""

from __future__ import annotations

from cosim.scenario import Param, Run
from cosim.scenarios.pokeys_stale_slots import stale_slots_run

PARAMETERS = (
    Param("fix", "clear", "", ("clear", "wait"), "clear the buffer at the switch, or wait 10 ms"),
    Param("speed_hz", 10_000, "Hz", (1_000, 25_000), "internal speed-control speed (multiple of 1 kHz)"),
)
UNTIL = "200 ms"


def scenario(run: Run) -> None:
    run.check(stale_slots_run(run))
