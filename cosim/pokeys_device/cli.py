"""``cosim pokeys-device``: serve a virtual PoKeys on 127.0.0.1:20055 until Ctrl-C (or ``--duration``).

When it stops it prints the lag report, the packet counters, underruns and the PoKeys checks over
every recorded pulse, and writes the trace (VCD and tables) and ``device.json`` to ``--out``.
Wired into the ``cosim`` command by :func:`add_parser` and :func:`cmd_pokeys_device`.
"""

from __future__ import annotations

import argparse
import contextlib
import re
import signal
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from cosim.errors import ConfigurationError

if TYPE_CHECKING:
    from cosim.controllers.pokeys import PulseEngine
    from cosim.kernel import Simulation
    from cosim.pokeys_device.server import DeviceServer

EXIT_PASS, EXIT_FAIL, EXIT_UNCHECKED = 0, 1, 4
_SWITCH = re.compile(r"^\s*([a-z])\s*([+-]?)\s*=\s*([+-]?\d+)\s*$")


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add the ``pokeys-device`` sub-command to the ``cosim`` parser."""
    parser = subparsers.add_parser(
        "pokeys-device", help="serve a virtual PoKeys (the pulse engine model) on UDP/TCP port 20055",
        description="Serve the simulated PoKeys pulse engine with the device's network protocol, in real time "
                    "(one 1 ms slot per millisecond). Host software connects to it as to the real device. "
                    "Stops on Ctrl-C or after --duration; then prints the lag report and the checks and writes "
                    "the trace to --out.",
        epilog="example: cosim pokeys-device --model 56E --limit x+=20000 --home x=-500 --duration 60")
    parser.add_argument("--model", choices=("56E", "57E", "57CNC"), default="57E",
                        help="PoKeys56E (pulse engine v1) or PoKeys57E / PoKeys57CNC (pulse engine v2); default 57E")
    parser.add_argument("--serial", type=int, default=None,
                        help="serial number (default 20123 for the 56E, 32123 for the 57 series; never 0)")
    parser.add_argument("--host", default="127.0.0.1", help="address to bind (default 127.0.0.1)")
    parser.add_argument("--port", type=int, default=20055, help="UDP and TCP port (default 20055)")
    parser.add_argument("--allow-remote", action="store_true",
                        help="allow a non-loopback --host: anyone who reaches it can drive the device")
    parser.add_argument("--advertise-ip", default=None,
                        help="device address put in discovery replies (default: --host, or 127.0.0.1)")
    parser.add_argument("--duration", type=float, default=None, help="stop after this many seconds")
    parser.add_argument("--limit", action="append", default=[], metavar="AXIS(+|-)=POS",
                        help="wire a limit switch that trips at that position, e.g. x+=20000 or y-=-500 "
                             "(repeatable); the host enables it over the protocol")
    parser.add_argument("--home", action="append", default=[], metavar="AXIS=POS",
                        help="wire a home switch active at or beyond POS (towards its sign), e.g. x=-500")
    parser.add_argument("--rt-priority", type=int, default=10,
                        help="SCHED_FIFO priority of the pacing threads while serving (default 10; 0: normal "
                             "scheduling). Needs the privilege; without it the server runs at normal priority")
    parser.add_argument("--seed", type=int, default=0, help="random seed of the simulation (default 0)")
    parser.add_argument("--out", type=Path, default=Path("results/pokeys-device"),
                        help="results folder (default results/pokeys-device)")
    parser.add_argument("--allow-unchecked", action="store_true",
                        help="exit 0, not 4, when no pulse was emitted (verdict UNCHECKED: nothing was checked)")
    parser.add_argument("--format", choices=("parquet", "csv"), default="parquet",
                        help="format of the trace tables (default parquet)")
    parser.add_argument("--no-vcd", action="store_true", help="do not write trace.vcd")
    return parser


def parse_switch(text: str, *, kind: str) -> tuple[int, str, int]:
    """``(axis index, side, position)`` from ``x+=5000`` (limit) or ``x=-500`` (home)."""
    match = _SWITCH.match(text)
    if match is None or (kind == "limit") != bool(match.group(2)):
        example = "x+=20000 or y-=-500" if kind == "limit" else "x=-500"
        raise ConfigurationError.out_of_range(f"--{kind}", text, f"AXIS{'(+|-)' if kind == 'limit' else ''}=POS, "
                                                                 f"e.g. {example}")
    from cosim.controllers.pokeys import AXIS_NAMES

    if match.group(1) not in AXIS_NAMES:
        raise ConfigurationError.out_of_range(f"--{kind} axis", match.group(1), ", ".join(AXIS_NAMES))
    return AXIS_NAMES.index(match.group(1)), match.group(2), int(match.group(3))


def switch_wiring(limits: list[str], homes: list[str]) -> Callable[[Simulation, PulseEngine], None]:
    """A ``wire(sim, engine)`` that adds a position-driven switch double per ``--limit`` / ``--home``."""
    specs = [("limit", *parse_switch(t, kind="limit")) for t in limits]
    specs += [("home", *parse_switch(t, kind="home")) for t in homes]

    def wire(sim: Simulation, engine: PulseEngine) -> None:
        from cosim.couplings.ideal_axis import PositionSwitch

        for kind, axis, side, at in specs:
            engine.axis(axis, where=f"--{kind}")  # an axis this model drives
            if kind == "limit":
                signal_ = (engine.switches.limit_pos if side == "+" else engine.switches.limit_neg)[axis]
            else:
                signal_ = engine.switches.home[axis]
            upward = side == "+" or (kind == "home" and at > 0)
            PositionSwitch(sim, engine.steps[axis], signal_, _region(at, upward=upward))

    return wire


def _region(at: int, *, upward: bool) -> Callable[[int], bool]:
    """``tripped(position)``: at or beyond ``at`` in the switch's direction."""
    if upward:
        return lambda p: p >= at
    return lambda p: p <= at


async def _serve(server: DeviceServer, duration_s: float | None) -> None:
    import asyncio

    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    for sig in (signal.SIGINT, signal.SIGTERM):
        with contextlib.suppress(NotImplementedError, RuntimeError):
            loop.add_signal_handler(sig, stop.set)
    if duration_s is not None:
        loop.call_later(duration_s, stop.set)
    await server.serve(stop)


def check_options(args: argparse.Namespace) -> None:
    """Refuse option values the server cannot honour, before anything starts (ConfigurationError)."""
    import ipaddress

    from cosim import validate

    if args.duration is not None:
        validate.in_range(args.duration, "--duration", low=0, low_open=True, high=10**9, unit="s")
    if args.advertise_ip is not None:
        try:
            ipaddress.IPv4Address(args.advertise_ip)
        except ValueError:
            raise ConfigurationError.out_of_range("--advertise-ip", args.advertise_ip,
                                                  "an IPv4 address, e.g. 127.0.0.1") from None
    validate.integer(args.port, "--port", low=0, high=65535)
    validate.integer(args.rt_priority, "--rt-priority", low=0, high=99)
    validate.integer(args.seed, "--seed", low=0, high=2**63 - 1)
    if args.serial is not None:
        validate.integer(args.serial, "--serial", low=1, high=2**32 - 1)


def cmd_pokeys_device(args: argparse.Namespace) -> int:
    """Run the server until stopped; print the report; exit by the verdict: 0 PASS, 1 FAIL, 4 UNCHECKED (no
    pulse was emitted, so the checks examined nothing; 0 with ``--allow-unchecked``)."""
    from cosim.pokeys_device.identity import DeviceIdentity
    from cosim.pokeys_device.logs import background_stderr
    from cosim.pokeys_device.rig import VirtualPoKeys
    from cosim.pokeys_device.server import DeviceServer, check_address

    check_options(args)
    check_address(args.host, allow_remote=args.allow_remote)
    identity = DeviceIdentity.preset(args.model, serial=args.serial)
    rig = VirtualPoKeys.create(identity, seed=args.seed, wire=switch_wiring(args.limit, args.home),
                               rt_priority=args.rt_priority or None)
    server = DeviceServer(rig.device, pacer=rig.pacer, host=args.host, port=args.port,
                          allow_remote=args.allow_remote, advertise_ip=args.advertise_ip)
    engine = "pulse engine v1 (0x80)" if identity.pulse_engine == 1 else "pulse engine v2 (0x85, 0xB0)"
    print(f"virtual PoKeys{identity.model} serial {identity.serial}, {engine}, on UDP and TCP "
          f"{args.host}:{args.port}" + (f" for {args.duration} s" if args.duration else "; Ctrl-C stops"), flush=True)
    import asyncio  # here, not at the top: `cosim --help` and `cosim run` build this command's parser

    with background_stderr() as log_queue, contextlib.suppress(KeyboardInterrupt):
        try:
            asyncio.run(_serve(server, args.duration))
        except OSError as exc:  # binding: the port is taken, or the address is not this machine's
            raise ConfigurationError(f"cannot serve on {args.host}:{args.port}: {exc.strerror or exc} "
                                     "(another virtual or real device may be using the port: stop it, or "
                                     "choose another with --port)") from None
    if log_queue.dropped:
        print(f"({log_queue.dropped} log messages were dropped: stderr was not read fast enough)")
    formats = (() if args.no_vcd else ("vcd",)) + (args.format,)
    summary = rig.finish(args.out, formats=formats)
    print(rig.pacer.report().summary())
    print(f"packets: {rig.device.log.summary()}")
    underruns = summary["underruns"]
    print(f"underruns: {len(underruns)}" + "".join(f"\n  at {u['t_start_ns'] / 1e6:.3f} ms, {u['slots']} slots"
                                                   for u in underruns[:10]))
    print(f"positions {summary['positions']}, pulses {summary['pulses']}")
    for line in summary["checks"]:
        print(f"  {line}")
    verdict = summary["verdict"]
    print(f"verdict: {verdict}" + (" (no axis emitted a pulse: nothing was checked)" if verdict == "UNCHECKED" else ""))
    print(f"results in {args.out}/ (device.json, {'trace.vcd, ' if not args.no_vcd else ''}{args.format} tables)")
    if verdict == "UNCHECKED":
        return EXIT_PASS if args.allow_unchecked else EXIT_UNCHECKED
    return EXIT_PASS if verdict == "PASS" else EXIT_FAIL


def main(argv: list[str] | None = None) -> int:
    """``python -m cosim.pokeys_device.cli [options]``: the same as ``cosim pokeys-device``."""
    import sys

    parser = argparse.ArgumentParser(prog="cosim")
    add_parser(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(["pokeys-device", *(sys.argv[1:] if argv is None else argv)])
    try:
        return cmd_pokeys_device(args)
    except ConfigurationError as exc:
        print(f"cosim pokeys-device: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    raise SystemExit(main())
