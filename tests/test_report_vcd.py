"""Waveform exports of a long run: one gzip-compressed VCD by default, read to its end by GTKWave's converter.

A run of more than ``COMPRESS_ABOVE_CHANGES`` value changes (the 1-hour 3-axis job has 387 million:
5 GB of VCD text) gets ``trace.vcd.gz`` and a ``trace.gtkw`` that opens it; the plain VCDs stay an
option. The traces here are small and the threshold is lowered, so that each expected number can be
written out: 3 segments of 4 pulses are 24 edges.
"""

from __future__ import annotations

import gzip
import shutil
import subprocess
from pathlib import Path

import pytest

from cosim import export_vcd
from cosim.export import write_trace
from cosim.export_vcd import changes, write_waveforms
from cosim.trace import Trace

VCD2FST = shutil.which("vcd2fst")
FST2VCD = shutil.which("fst2vcd")


def _trace() -> Trace:
    trace = Trace()
    trace.declare("dev.x.step", "pulse", pulse_width=100)
    trace.declare("dev.x.dir", "bit")
    trace.declare("dev.x.pos", "real", unit="mm")
    for k in range(3):
        trace.record_segment("dev.x.step", k * 10_000, 8_000, 4, 1)  # pulses at 0, 2, 4, 6 us of each 10 us
    trace.record("dev.x.dir", 0, 1)
    trace.record("dev.x.pos", 25_000, 0.5)
    trace.end_t = 40_000
    return trace


def test_a_trace_counts_two_changes_a_pulse_and_one_a_record() -> None:
    assert changes(_trace()) == 2 * 12 + 1 + 1


def test_a_short_run_writes_the_plain_vcds(tmp_path: Path) -> None:
    written = write_waveforms(_trace(), tmp_path)
    assert sorted(p.name for p in written) == ["trace.gtkw", "trace.vcd", "trace_digital.vcd"]
    assert '[dumpfile] "trace.vcd"' in (tmp_path / "trace.gtkw").read_text()


def test_a_long_run_writes_one_compressed_vcd_the_same_as_the_plain_one(tmp_path: Path,
                                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(export_vcd, "COMPRESS_ABOVE_CHANGES", 20)  # this trace has 26 changes: a long run here
    write_trace(_trace(), tmp_path / "long", formats=("vcd",))
    write_trace(_trace(), tmp_path / "plain", formats=("vcd-plain",))
    assert sorted(p.name for p in (tmp_path / "long").iterdir()) == ["trace.gtkw", "trace.vcd.gz", "trace_meta.json"]
    assert '[dumpfile] "trace.vcd.gz"' in (tmp_path / "long" / "trace.gtkw").read_text()
    text = gzip.decompress((tmp_path / "long" / "trace.vcd.gz").read_bytes())
    assert text == (tmp_path / "plain" / "trace.vcd").read_bytes()
    again = tmp_path / "again"
    write_trace(_trace(), again, formats=("vcd",))
    assert (again / "trace.vcd.gz").read_bytes() == (tmp_path / "long" / "trace.vcd.gz").read_bytes()  # no time stamp


@pytest.mark.skipif(VCD2FST is None or FST2VCD is None,
                    reason="GTKWave's converters are not installed (tasks.py test installs the Debian package gtkwave)")
def test_gtkwaves_converter_reads_the_compressed_vcd_to_its_end(tmp_path: Path) -> None:
    vcd = write_waveforms(_trace(), tmp_path, compress=True)[0]
    assert vcd.name == "trace.vcd.gz"
    with vcd.open("rb") as packed:
        unpacked = subprocess.run(["gzip", "-dc"], stdin=packed, capture_output=True, check=True).stdout
    fst = tmp_path / "trace.fst"
    subprocess.run([str(VCD2FST), "-v", "-", "-f", str(fst)], input=unpacked, capture_output=True, check=True)
    back = subprocess.run([str(FST2VCD), str(fst)], capture_output=True, text=True, check=True).stdout
    stamps = [line for line in back.splitlines() if line.startswith("#")]
    assert stamps[-1] == "#40000"  # the run's end: every change was read
    # the last pulse of the last segment rises at 26 us and falls at 26.1 us
    assert "#26000" in stamps and "#26100" in stamps
