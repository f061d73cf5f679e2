"""A UDP host keeping a 3-axis job at up to 25 kHz running on the virtual PoKeys for N seconds.

The server runs in its own process (``python -m cosim.pokeys_device.cli``), as it would beside a
real host program; this script is the host: it plans out-and-back 3-axis moves at up to 25 kHz
with the project's planner, prefills the 128-slot buffer, switches to running and then keeps the
buffer topped up with fill-buffer requests (18 slots per 64-byte packet, the device accepts as
many as fit), sleeping ``--period-ms`` between top-ups. At the end it waits for the buffer to run
empty and compares the device's positions with the pulses it sent.

Printed: host-side figures (fills, buffer-empty observations, request round trips), the process
CPU time of the host and of the server (counted once it has ended) beside the wall time, the
server's lag report, its underruns and the PoKeys checks over every recorded pulse (from
``device.json``). Run::

    .venv/bin/python bench/bench_pokeys_device.py [--seconds 60] [--model 57E|56E] [--port 20056]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from clock import cpu_s, machine_load

from cosim.controllers.pokeys import SLOT_NS, uniform_axes
from cosim.controllers.pokeys.planner import Move, plan
from cosim.pokeys_device.layouts import CFG_ENABLED, AxisRecord
from cosim.testing.pokeys_client import PoKeysClient, discover

FAR = (60_000, -45_000, 30_000)  # x at 25 kHz, y and z proportionally slower


def job(seconds: float) -> list[tuple[int, ...]]:
    """Out-and-back moves until the job lasts at least ``seconds``."""
    axes = uniform_axes(max_speed_hz=25_000, accel=500_000, decel=500_000)
    counts: list[tuple[int, ...]] = []
    k = 0
    while len(counts) * SLOT_NS < seconds * 1e9:
        counts.extend(tuple(c) for c in plan([Move(FAR if k % 2 == 0 else (0, 0, 0))], axes,
                                             start=(0, 0, 0) if k % 2 == 0 else FAR))
        k += 1
    return counts


class Host:
    """The refill loop of a host program, v1 (0x80) or v2 (0x85) commands."""

    def __init__(self, client: PoKeysClient, model: str) -> None:
        self.client = client
        self.v1 = model == "56E"
        self.fills = 0
        self.round_trips: list[float] = []

    def start(self) -> None:
        c = self.client
        info = c.identify()
        print(f"connected: {info.type_name} serial {info.serial} FW {info.firmware}")
        if self.v1:
            c.pe_enable(True)
            return
        c.v2_setup(3)
        for axis in range(3):
            c.v2_set_axis(axis, AxisRecord(config=CFG_ENABLED, max_speed=25.0, accel=0.5, decel=0.5))

    def run_state(self) -> None:
        if self.v1:
            self.client.pe_set_state(2)
        else:
            self.client.v2_set_state(3)

    def fill(self, slots: list[tuple[int, ...]]) -> int:
        """Offer up to 18 slots; return how many the device accepted."""
        started = time.perf_counter()
        accepted = self.client.pe_fill(slots)[0] if self.v1 else self.client.v2_fill(slots)[0]
        self.round_trips.append(time.perf_counter() - started)
        self.fills += 1
        return accepted

    def queued(self) -> int:
        return 128 - self.client.pe_free() if self.v1 else int(self.client.v2_status().axis_states[0] == 2)

    def positions(self) -> tuple[int, ...]:
        return self.client.pe_status().positions if self.v1 else self.client.v2_status().positions[:3]


def stream(host: Host, slots: list[tuple[int, ...]], period_s: float) -> None:
    sent = 0
    running = False
    while sent < len(slots):
        while sent < len(slots):  # top up: as many packets as the device accepts
            accepted = host.fill(slots[sent:sent + 18])
            sent += accepted
            if accepted < min(18, len(slots) - sent + accepted):
                break
        if not running:
            host.run_state()
            running = True
        time.sleep(period_s)
    deadline = time.monotonic() + 5
    while host.queued() and time.monotonic() < deadline:
        time.sleep(0.01)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=60, help="job length [s] (default 60)")
    parser.add_argument("--model", choices=("57E", "56E"), default="57E", help="device model (default 57E, PEv2)")
    parser.add_argument("--port", type=int, default=20056, help="UDP/TCP port of the server (default 20056)")
    parser.add_argument("--period-ms", type=float, default=5.0, help="host loop period [ms] (default 5)")
    parser.add_argument("--out", type=Path, default=None, help="server results folder (default: a temporary one)")
    args = parser.parse_args()

    print(f"machine: {machine_load()}")
    slots = job(args.seconds)
    expected = tuple(sum(s[a] for s in slots) for a in range(3))
    pulses = sum(abs(c) for s in slots for c in s)
    print(f"job: {len(slots)} slots ({len(slots) / 1000:.1f} s), {pulses} pulses on 3 axes, "
          f"at most {max(max(abs(c) for c in s) for s in slots)} per slot")
    out = args.out or Path(tempfile.mkdtemp(prefix="pokeys-device-"))
    server = subprocess.Popen(
        [sys.executable, "-m", "cosim.pokeys_device.cli", "--model", args.model, "--port", str(args.port),
         "--duration", str(len(slots) / 1000 + 8), "--out", str(out), "--no-vcd"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        deadline = time.monotonic() + 20
        while not discover(args.port, timeout_s=0.2):
            if server.poll() is not None or time.monotonic() > deadline:
                print(server.stdout.read() if server.stdout else "", file=sys.stderr)
                raise SystemExit("the server did not start")
        with PoKeysClient("127.0.0.1", args.port, transport="udp", timeout_s=0.2) as client:
            host = Host(client, args.model)
            host.start()
            started, host_cpu = time.perf_counter(), cpu_s()
            stream(host, slots, args.period_ms / 1000)
            wall, host_cpu = time.perf_counter() - started, cpu_s() - host_cpu
            positions = host.positions()
            trips = sorted(host.round_trips)
            print(f"host: {host.fills} fills in {wall:.1f} s, round trip median {trips[len(trips) // 2] * 1e3:.2f} ms, "
                  f"max {trips[-1] * 1e3:.2f} ms; stale replies {client.stale_replies}, re-sends {client.resends}")
            print(f"final positions {positions} (pulses sent {expected}): "
                  f"{'EQUAL' if tuple(positions) == expected else 'DIFFERENT'}")
        server.send_signal(2)
        children_cpu = cpu_s(children=True) - cpu_s()
        log, _ = server.communicate(timeout=120)
        server_cpu = cpu_s(children=True) - cpu_s() - children_cpu
    finally:
        if server.poll() is None:
            server.kill()
    print(f"process CPU: host {host_cpu:.2f} s while streaming ({wall:.1f} s wall), server {server_cpu:.2f} s "
          "over its whole run")
    print("server:\n  " + "\n  ".join(log.strip().splitlines()))
    summary = json.loads((out / "device.json").read_text())
    lag = summary["lag"]
    print(f"lag report: max {lag['max_lag_slots']:.3f} slots, mean {lag['mean_lag_slots']:.3f} slots, "
          f"{lag['late_slots']} slots late; underruns {len(summary['underruns'])}; checks "
          f"{'PASS' if summary['passed'] else 'FAIL'}")
    ok = summary["passed"] and not summary["underruns"] and tuple(positions) == expected
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
