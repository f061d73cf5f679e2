"""Process CPU and wall time of the virtual PoKeys device's fuzz runs (min / median / max of ``--repeat``).

The test suite runs the same fuzzing (tests/test_pokeys_device_fuzz.py: 100,000 packets in process, then
packets through the UDP socket) and asserts what the device answers, never how long it took: on a loaded
machine the in-process run took 204 s and the socket run 104 s where they used to take under 60 s and 20 s.
The durations are measured here instead::

    .venv/bin/python bench/bench_pokeys_device_fuzz.py [--repeat 3]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from clock import Series, machine_load, measure, spread

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

import test_pokeys_device_fuzz as fuzz  # the suite's own fuzzing, from tests/


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3, help="runs of each part (default 3)")
    args = parser.parse_args()
    print(machine_load())
    in_process, socket = Series(), Series()
    for _ in range(args.repeat):
        with measure() as lap:
            handled = fuzz.fuzz_in_process("56E") + fuzz.fuzz_in_process("57E")
        in_process.add(lap)
        with measure() as lap:
            fuzz.test_fuzzed_packets_through_the_udp_socket_then_a_correct_status()
        socket.add(lap)
    print(f"in process, {handled:,} packets: CPU {spread(in_process.cpu())} s, wall {spread(in_process.wall())} s")
    print(f"through the UDP socket ({fuzz.SOCKET_PACKETS} packets): CPU {spread(socket.cpu())} s "
          f"(this process; the server thread included), wall {spread(socket.wall())} s")
    print(machine_load())


if __name__ == "__main__":
    main()
