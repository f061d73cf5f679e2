"""What a fuzz worker keeps of its inputs: counts, crashes and slow inputs (``bench/fuzz_*.py``)."""

from __future__ import annotations

import time
import traceback
from collections.abc import Callable
from pathlib import Path

#: Wall time above which an input counts as slow [s].
SLOW_S = 5.0
#: Crashes and slow inputs kept per worker (the first ones).
KEPT = 20


class Tally:
    """Inputs, crashes (any exception that is not cosim's own: the callee lets only those through) and
    slow inputs of one worker; the first :data:`KEPT` crashes and slow inputs are written to ``crash_dir``
    as ``crash_<seed>_<n>.txt`` (the input and its traceback) and ``slow_<seed>_<n>.txt``."""

    def __init__(self, seed: int, crash_dir: str) -> None:
        self.seed, self.folder = seed, Path(crash_dir)
        self.inputs = self.crashes = self.slow = 0
        self.slowest = 0.0

    def exercise(self, text: str, call: Callable[[], bool]) -> bool:
        """``call()`` on ``text``: its result, or False when it crashed."""
        started = time.monotonic()
        result = False
        try:
            result = call()
        except Exception:
            self.crashes += 1
            if self.crashes <= KEPT:
                self._keep(f"crash_{self.seed}_{self.crashes}.txt", f"{text!r}\n\n{traceback.format_exc()}")
        took = time.monotonic() - started
        if took > SLOW_S:
            self.slow += 1
            if self.slow <= KEPT:
                self._keep(f"slow_{self.seed}_{self.slow}.txt", f"{took:.1f} s\n{text!r}\n")
        self.slowest = max(self.slowest, took)
        self.inputs += 1
        return result

    def _keep(self, name: str, text: str) -> None:
        self.folder.mkdir(parents=True, exist_ok=True)  # only when there is something to keep
        (self.folder / name).write_text(text)
