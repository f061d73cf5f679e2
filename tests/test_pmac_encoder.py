"""Encoder channel: 1/T extension (1/32 and 1/256 count) and the level-triggered capture."""

from __future__ import annotations

from collections.abc import Generator
from fractions import Fraction
from typing import Any

import pytest

from cosim.controllers.pmac.encoder import EncoderChannel
from cosim.encoders import EncoderSample, SignalEncoder, extend_one_over_t
from cosim.errors import ConfigurationError
from cosim.kernel import Simulation
from cosim.plants.analytic import IdealConveyor
from cosim.signals import Signal
from cosim.timebase import Priority


def test_one_over_t_extends_between_edges() -> None:
    """Edges every 16,000 ns; a quarter of the interval after the last edge is 1/4 count.

        count   9          10
        edges   |----------|----- t = last + 4000
                0        16000
    """
    sample = EncoderSample(count=10, last_edge_t=16_000, prev_edge_t=0)
    assert extend_one_over_t(sample, 16_000, 5) == 320
    assert extend_one_over_t(sample, 20_000, 5) == 328  # 10 + 8/32
    assert extend_one_over_t(sample, 20_000, 8) == 2624  # 10 + 64/256
    assert extend_one_over_t(sample, 20_001, 8) == 2624  # truncated, not rounded


def test_one_over_t_clamps_below_the_next_count_and_handles_down_edges() -> None:
    sample = EncoderSample(count=10, last_edge_t=16_000, prev_edge_t=0)
    assert extend_one_over_t(sample, 10**9, 5) == 10 * 32 + 31
    down = EncoderSample(count=10, last_edge_t=16_000, prev_edge_t=0, direction=-1)
    assert extend_one_over_t(down, 20_000, 5) == 11 * 32 - 8  # boundary 11 crossed downwards
    assert extend_one_over_t(EncoderSample(count=3), 5, 5) == 96  # no edges yet: whole counts
    assert extend_one_over_t(EncoderSample(count=3, last_edge_t=4), 5, 5) == 96


def test_signal_encoder_takes_edge_times_from_signal_changes(sim: Simulation) -> None:
    count = Signal(sim, "belt.count", kind="int")
    encoder = SignalEncoder(count)

    def edges() -> Generator[Any, Any, None]:
        for k in (1, 2, 3):
            yield sim.at(k * 10_000)
            count.set(k)

    sim.process(edges())
    sim.run(until=35_000)
    assert encoder.sample(35_000) == EncoderSample(3, 30_000, 20_000, 1)
    assert extend_one_over_t(encoder.sample(35_000), 35_000, 5) == 3 * 32 + 16


def test_signal_encoder_needs_an_int_signal(sim: Simulation) -> None:
    with pytest.raises(ConfigurationError, match=r"kind of encoder count signal belt\.count = 'bit'"):
        SignalEncoder(Signal(sim, "belt.count", kind="bit"))


def test_capture_latches_first_trigger_until_read(sim: Simulation) -> None:
    """Capture flag: set by the first mark, kept (second mark ignored) until the register is read.

        mark    _|‾|_____|‾|_________|‾|___
        flag    _|‾‾‾‾‾‾‾‾‾‾‾‾‾|_____|‾‾‾‾
        read                   ^ (returns mark 1's position, re-arms)
    """
    belt = IdealConveyor(sim, speed_counts_per_ms=64, marks=[100, 200, 300], mark_width_counts=2)
    channel = EncoderChannel(sim, 0x078008, belt, trigger=belt.mark)
    reads: list[int] = []

    def host() -> Generator[Any, Any, None]:
        yield sim.at(4_000_000, Priority.HOST)  # position 256: between marks 2 and 3
        reads.append(channel.read_capture())

    sim.process(host())
    sim.run(until=5_000_000)
    assert [t for t, _ in channel.captures] == [1_562_500, 4_687_500]  # marks 1 and 3 (mark 2 ignored)
    assert reads == [100 * 256]
    t, v = sim.trace.edges("pmac.ch78008.capture_flag")
    assert t.tolist() == [0, 1_562_500, 4_000_000, 4_687_500]
    assert v.tolist() == [0, 1, 0, 1]


def test_capture_is_level_triggered_on_re_arm(sim: Simulation) -> None:
    """A read while the mark is still under the sensor latches again at once (position of the read)."""
    belt = IdealConveyor(sim, speed_counts_per_ms=64, marks=[100], mark_width_counts=10)
    channel = EncoderChannel(sim, 0x078008, belt, trigger=belt.mark)

    def host() -> Generator[Any, Any, None]:
        yield sim.at(1_600_000, Priority.HOST)  # position 102.4: mark (100..110) still active
        channel.read_capture()

    sim.process(host())
    sim.run(until=2_000_000)
    assert channel.captures == [(1_562_500, 100 * 256), (1_600_000, int(Fraction(1_600_000, 15_625) * 256))]
    assert channel.capture_flag


def test_capture_sub_count_position_matches_master_within_1_256(sim: Simulation) -> None:
    belt = IdealConveyor(sim, speed_counts_per_ms=Fraction(577, 9), marks=[Fraction(12345, 7)])
    channel = EncoderChannel(sim, 0x078008, belt, trigger=belt.mark)
    sim.run(until=40_000_000)
    (t, pos256), = channel.captures
    assert 0 <= belt.position(t) - Fraction(pos256, 256) <= Fraction(1, 256)
    assert belt.position(t - 1) < Fraction(12345, 7) <= belt.position(t)


def test_channel_registers_and_bad_offsets(sim: Simulation) -> None:
    belt = IdealConveyor(sim, speed_counts_per_ms=64)
    channel = EncoderChannel(sim, 0x078008, belt)
    assert channel.read_register(0) == 0
    assert channel.read_register(3) == 0
    with pytest.raises(ConfigurationError, match=r"register offset of encoder channel \$078008 = 1"):
        channel.read_register(1)
    with pytest.raises(ConfigurationError, match="trigger_level = 2"):
        EncoderChannel(sim, 0x078010, belt, trigger_level=2)
