"""PoKeys slot buffer: 3-byte entries (7-bit count + direction bit per axis), 128 slots, fill/clear.

    entry   byte x     byte y     byte z
            D ccccccc  D ccccccc  D ccccccc      D = 1: direction output activated (negative)
"""

from __future__ import annotations

import pytest

from cosim.controllers.pokeys import (
    BUFFER_SLOTS,
    PINS,
    EngineState,
    PulseEngine,
    SlotBuffer,
    decode_axis,
    decode_entry,
    encode_axis,
    encode_entry,
)
from cosim.controllers.pokeys.buffer import split_packet
from cosim.errors import ConfigurationError
from cosim.kernel import Simulation


@pytest.mark.parametrize(
    ("count", "negative", "byte"),
    [(0, None, 0x00), (1, None, 0x01), (25, None, 0x19), (127, None, 0x7F), (-5, None, 0x85),
     (-127, None, 0xFF), (0, True, 0x80), (0, False, 0x00)],
)
def test_axis_byte_is_7_bit_count_and_direction_msb(count: int, negative: bool | None, byte: int) -> None:
    assert encode_axis(count, negative=negative) == byte
    assert decode_axis(byte) == (abs(count), byte >= 0x80)


def test_entry_is_three_bytes_x_y_z() -> None:
    entry = encode_entry((10, -5, 127))
    assert entry == bytes([0x0A, 0x85, 0x7F])
    assert decode_entry(entry) == (10, -5, 127)
    assert [decode_entry(e) for e in split_packet(entry * 2 + b"\x00", 2)] == [(10, -5, 127)] * 2


@pytest.mark.parametrize("count", [128, -128, 1000])
def test_count_that_does_not_fit_7_bits_is_refused(count: int) -> None:
    with pytest.raises(ConfigurationError, match=rf"axis y: pulse count = {count} is not allowed \(allowed: -127..127"):
        encode_entry((0, count, 0))


def test_buffer_holds_128_slots_and_fill_accepts_as_many_as_fit() -> None:
    buf = SlotBuffer()
    assert buf.depth_slots == BUFFER_SLOTS == 128
    assert buf.fill([encode_entry((1, 0, 0))] * 100) == 100
    assert buf.fill([encode_entry((2, 0, 0))] * 40) == 28  # only 28 free
    assert (buf.level, buf.free) == (128, 0)
    assert buf.fill([encode_entry((3, 0, 0))]) == 0
    assert [decode_entry(buf.pop() or b"")[0] for _ in range(2)] == [1, 1]  # FIFO order
    assert buf.clear() == 126 and buf.pop() is None


def test_fill_reply_returns_accepted_count_and_status(sim: Simulation) -> None:
    engine = PulseEngine(sim)
    engine.set_position(1, -90)
    first = engine.fill_buffer([encode_entry((10, -5, 25))] * 120)
    second = engine.fill_buffer([encode_entry((10, -5, 25))] * 18)
    assert (first.accepted, second.accepted) == (120, 8)
    status = second.status
    assert status.positions == (0, -90, 0)
    assert status.engine_state == EngineState.STOPPED
    assert (status.limit_pos, status.limit_neg, status.home, status.emergency) == (0, 0, 0, False)
    assert status.axis_states == (0, 0, 0) and status.free_slots == 0
    assert engine.free_slots == 0


def test_fill_reply_reports_switch_states_read_at_the_last_slot_start(sim: Simulation) -> None:
    engine = PulseEngine(sim)
    engine.switches.limit_neg[2].set(1)
    engine.switches.home[0].set(1)
    assert engine.fill_buffer([]).status.limit_neg == 0  # not read yet
    sim.run(until=1)
    status = engine.fill_buffer([]).status
    assert (status.limit_pos, status.limit_neg, status.home) == (0b000, 0b100, 0b001)


def test_clear_buffer_drops_every_queued_slot(sim: Simulation) -> None:
    engine = PulseEngine(sim)
    engine.fill_buffer([encode_entry((5, 0, 0))] * 30)
    assert engine.clear_buffer() == 30
    engine.set_state(EngineState.BUFFER)
    sim.run(until=5_000_000)
    assert sim.trace.pulses("pokeys.x.step")[0].size == 0
    assert sim.trace.edges("pokeys.buffer_level")[1].tolist() == [0, 30, 0]


@pytest.mark.parametrize("count", [26, -26, 127])
def test_fill_refuses_more_than_25_pulses_per_slot(sim: Simulation, count: int) -> None:
    engine = PulseEngine(sim)
    message = rf"fill_buffer slot 2 axis z: pulses per slot = {count} is not allowed \(allowed: -25..25"
    with pytest.raises(ConfigurationError, match=message):
        engine.fill_buffer([encode_entry((1, 1, 1))] * 2 + [encode_entry((0, 0, count))])
    assert engine.buffer.level == 0  # nothing of a refused command is queued


def test_fill_refuses_entries_of_the_wrong_length(sim: Simulation) -> None:
    engine = PulseEngine(sim)
    with pytest.raises(ConfigurationError, match=r"fill_buffer slot 0: slot entry length = 2 is not allowed"):
        engine.fill_buffer([b"\x01\x02"])


def test_pin_map_has_home_x_on_pin_47_and_steps_on_46_48_49() -> None:
    assert PINS[47] == "x.home"
    assert (PINS[46], PINS[48], PINS[49]) == ("x.step", "y.step", "z.step")
    assert (PINS[32], PINS[35], PINS[38], PINS[52]) == ("x.limit_pos", "x.limit_neg", "x.dir", "emergency")
    assert len(PINS) == 16
