"""The device server under hostile conditions: bad options, a taken port, floods of trouble, a deaf stderr."""

from __future__ import annotations

import argparse
import json
import logging
import queue
import socket
from pathlib import Path

import pytest

from cosim.cli import main
from cosim.errors import ConfigurationError
from cosim.pokeys_device.cli import check_options
from cosim.pokeys_device.logs import RateLimit, _DroppingQueueHandler
from cosim.pokeys_device.rig import VirtualPoKeys
from cosim.pokeys_device.server import DeviceServer


def _options(**changes: object) -> argparse.Namespace:
    base = {"duration": 1.0, "advertise_ip": None, "port": 20055, "rt_priority": 10, "seed": 0, "serial": None}
    return argparse.Namespace(**{**base, **changes})


@pytest.mark.parametrize(("changes", "message"), [
    ({"duration": -1.0}, r"--duration = -1.0 is not allowed \(allowed: > 0 and <= 1000000000 s\)"),
    ({"duration": float("nan")}, r"--duration = nan is not allowed \(allowed: a finite number\)"),
    ({"duration": float("inf")}, r"--duration = inf is not allowed"),
    ({"advertise_ip": "not-an-ip"}, r"--advertise-ip = 'not-an-ip' is not allowed \(allowed: an IPv4 address"),
    ({"seed": -1}, r"--seed = -1 is not allowed"),
    ({"port": 70000}, r"--port = 70000 is not allowed \(allowed: 0\.\.65535\)"),
    ({"rt_priority": 100}, r"--rt-priority = 100 is not allowed"),
])
def test_bad_options_are_refused_before_anything_starts(changes: dict[str, object], message: str) -> None:
    with pytest.raises(ConfigurationError, match=message):
        check_options(_options(**changes))


def test_bad_duration_exits_2_through_the_command_line(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["pokeys-device", "--duration", "-1"]) == 2
    assert "--duration = -1.0 is not allowed" in capsys.readouterr().err


def test_a_port_in_use_is_a_clear_error_not_a_traceback(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        status = main(["pokeys-device", "--port", str(port), "--duration", "0.2", "--rt-priority", "0",
                       "--out", str(tmp_path / "out")])
    assert status == 2
    assert f"cannot serve on 127.0.0.1:{port}" in capsys.readouterr().err


def test_a_device_no_client_drove_is_unchecked_not_passed(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """No client: no axis emits a pulse, the nine pulse checks examine nothing: UNCHECKED, exit 4 (0 if allowed)."""
    args = ["pokeys-device", "--port", "0", "--duration", "0.1", "--rt-priority", "0", "--no-vcd"]
    assert main([*args, "--out", str(tmp_path / "a")]) == 4
    assert "verdict: UNCHECKED (no axis emitted a pulse: nothing was checked)" in capsys.readouterr().out
    assert json.loads((tmp_path / "a" / "device.json").read_text())["verdict"] == "UNCHECKED"
    assert main([*args, "--out", str(tmp_path / "b"), "--allow-unchecked"]) == 0


def test_repeated_trouble_is_counted_and_reported_once_per_interval(caplog: pytest.LogCaptureFixture) -> None:
    rig = VirtualPoKeys.create()
    server = DeviceServer(rig.device, port=0)
    trouble = {"message": "socket.accept() out of system resource", "exception": OSError(24, "Too many open files")}
    with caplog.at_level(logging.WARNING, logger="cosim.pokeys_device"):
        for _ in range(300):
            server.loop_trouble(None, trouble)  # type: ignore[arg-type]
    assert rig.device.log.counts["socket_error"] == 300
    reports = [r for r in caplog.records if "out of system resource" in r.getMessage()]
    assert len(reports) == 1 and reports[0].exc_info is None  # one line, no traceback


def test_rate_limit_reports_the_first_then_one_per_interval_with_the_count_held_back() -> None:
    now = [0.0]
    limit = RateLimit(10.0, clock=lambda: now[0])
    assert limit.allow("x") == (True, 0)
    assert [limit.allow("x") for _ in range(3)] == [(False, 0)] * 3
    now[0] = 10.0
    assert limit.allow("x") == (True, 3)
    assert limit.allow("y") == (True, 0)  # kinds are separate


def test_a_full_log_queue_drops_records_instead_of_blocking() -> None:
    records: queue.Queue[logging.LogRecord] = queue.Queue(2)
    handler = _DroppingQueueHandler(records)
    logger = logging.getLogger("cosim.test.dropping")
    logger.addHandler(handler)
    logger.propagate = False
    try:
        for k in range(5):
            logger.warning("message %d", k)  # nobody reads the queue: a blocking handler would hang here
    finally:
        logger.removeHandler(handler)
    assert records.qsize() == 2 and handler.dropped == 3
