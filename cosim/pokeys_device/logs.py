"""The device server's own log: rate-limited, and written by a thread so that serving never blocks on it.

A server that runs for hours meets the same trouble many times (a client that keeps sending
garbage, the file-descriptor limit): :class:`RateLimit` lets the first report of a kind through
and then one summary line per interval (``... 312 more in the last 10 s``). :func:`background_stderr`
sends records to stderr from a listener thread through a bounded queue; when stderr is a pipe
that nobody reads and the queue is full, records are dropped and counted instead of stalling the
event loop.
"""

from __future__ import annotations

import logging
import logging.handlers
import queue
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager

#: Records the queue holds before it drops new ones.
QUEUE_RECORDS = 1000


class RateLimit:
    """Allow the first event of a kind, then at most one per ``interval_s``, counting the rest.

    Parameters
    ----------
    interval_s : float
        Wall-clock seconds between two reports of the same kind.
    clock : callable
        Monotonic seconds (injectable for tests).
    """

    def __init__(self, interval_s: float = 10.0, *, clock: Callable[[], float] = time.monotonic) -> None:
        self.interval_s = interval_s
        self.clock = clock
        self._last: dict[str, float] = {}
        self._held: dict[str, int] = {}

    def allow(self, kind: str) -> tuple[bool, int]:
        """``(report it now, events held back since the last report)`` for one event of ``kind``."""
        now = self.clock()
        last = self._last.get(kind)
        if last is not None and now - last < self.interval_s:
            self._held[kind] = self._held.get(kind, 0) + 1
            return False, 0
        self._last[kind] = now
        return True, self._held.pop(kind, 0)


class _DroppingQueueHandler(logging.handlers.QueueHandler):
    """A queue handler that never blocks: a full queue drops the record and counts it."""

    def __init__(self, records: queue.Queue[logging.LogRecord]) -> None:
        super().__init__(records)
        self.dropped = 0

    def enqueue(self, record: logging.LogRecord) -> None:
        try:
            self.queue.put_nowait(record)
        except queue.Full:
            self.dropped += 1


@contextmanager
def background_stderr(logger_names: tuple[str, ...] = ("cosim.pokeys_device", "asyncio"),
                      level: int = logging.WARNING) -> Iterator[_DroppingQueueHandler]:
    """Route the given loggers to stderr through a bounded queue and a listener thread while inside."""
    records: queue.Queue[logging.LogRecord] = queue.Queue(QUEUE_RECORDS)
    handler = _DroppingQueueHandler(records)
    stream = logging.StreamHandler(sys.stderr)
    stream.setFormatter(logging.Formatter("cosim pokeys-device: %(levelname)s: %(message)s"))
    listener = logging.handlers.QueueListener(records, stream)
    loggers = [logging.getLogger(name) for name in logger_names]
    saved = [(lg.handlers[:], lg.level, lg.propagate) for lg in loggers]
    for lg in loggers:
        lg.handlers = [handler]
        lg.setLevel(level)
        lg.propagate = False
    listener.start()
    try:
        yield handler
    finally:
        listener.stop()
        for lg, (handlers, lvl, propagate) in zip(loggers, saved, strict=True):
            lg.handlers, lg.level, lg.propagate = handlers, lvl, propagate
