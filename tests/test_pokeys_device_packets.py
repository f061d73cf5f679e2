"""Packet framing, checksum, large-fill parts, field layouts and identity decoding (pure functions)."""

from __future__ import annotations

import pytest
from pokeys_fake_engine import FakeEngine

from cosim.errors import ConfigurationError
from cosim.pokeys_device import Device, DeviceIdentity
from cosim.pokeys_device.identity import decode_device_data, decode_discovery, discovery_reply, identity_reply
from cosim.pokeys_device.layouts import (
    AxisRecord,
    ParamsV1,
    StatusV1,
    StatusV2,
    get_status_v1,
    get_status_v2,
    put_status_v1,
    put_status_v2,
)
from cosim.pokeys_device.packets import (
    BadChecksum,
    BadHeader,
    BadLength,
    BadMultipart,
    PartCollector,
    build_large_fill,
    build_request,
    check_frame,
    check_reply,
    checksum,
    encode_entries,
    new_reply,
    parse_large_fill,
    seal,
    signed_entries,
)


def test_checksum_is_the_sum_of_bytes_0_to_6_mod_256_and_protects_only_the_header() -> None:
    request = build_request(0x85, 0xFF, 0x12, 0x03, request_id=0x0D, payload=b"\xff" * 56)
    assert request[7] == (0xBB + 0x85 + 0xFF + 0x12 + 0x03 + 0x0D) % 256 == 0x61
    assert checksum(request[:7] + b"\0") == request[7]


@pytest.mark.parametrize("data, error", [
    (b"", BadLength),
    (bytes(63), BadLength),
    (bytes(65), BadLength),
    (b"\xaa" + bytes(63), BadHeader),
    (bytes.fromhex("bb00000000000100") + bytes(56), BadChecksum),
])
def test_frames_that_cannot_be_framed_raise_a_specific_error(data: bytes, error: type[Exception]) -> None:
    with pytest.raises(error):
        check_frame(data)


def test_a_reply_echoes_command_and_id_and_is_accepted_only_with_that_id() -> None:
    request = build_request(0x40, 12, 1, request_id=0x21)
    reply = seal(new_reply(request))
    assert reply[:8] == bytes.fromhex("AA 40 00 00 00 00 21 0B") and len(reply) == 64
    assert check_reply(reply, 0x21) == reply
    with pytest.raises(BadHeader):
        check_reply(reply, 0x22)


def test_large_fill_parts_carry_consecutive_ids_start_and_stop_bits_and_reassemble() -> None:
    data = bytes(range(200)) * 2 + bytes(48)
    request = build_large_fill(0xFE, 74, 3, data, first_id=0xFE)
    assert len(request) == 512
    assert [request[64 * i + 2] for i in range(8)] == [0x08, 1, 2, 3, 4, 5, 6, 0x17]
    assert [request[64 * i + 6] for i in range(8)] == [0xFE, 0xFF, 0, 1, 2, 3, 4, 5]  # IDs wrap 255 -> 0
    fill = parse_large_fill(request)
    assert (fill.entry_format, fill.offered_slots, fill.axes_per_slot, fill.last_id) == (0xFE, 74, 3, 5)
    assert fill.data == data


def test_large_fill_with_parts_out_of_order_is_refused() -> None:
    request = bytearray(build_large_fill(0xFF, 10, 3, b"", first_id=1))
    request[64:128], request[128:192] = request[128:192], request[64:128]
    with pytest.raises(BadMultipart):
        parse_large_fill(bytes(request))


def test_tcp_part_collector_returns_the_request_after_the_stop_part_and_restarts_on_a_new_start() -> None:
    request = build_large_fill(0xFF, 1, 3, b"\x01\x00\x00", first_id=0x20)
    parts = [request[64 * i:64 * (i + 1)] for i in range(8)]
    collector = PartCollector()
    assert [collector.add(p) for p in parts[:7]] == [None] * 7
    assert collector.add(parts[7]) == request
    collector.add(parts[0])
    with pytest.raises(BadMultipart):
        collector.add(parts[0])  # a new start before the stop: restart from it
    assert [collector.add(p) for p in parts[1:7]] == [None] * 6
    assert collector.add(parts[7]) == request


@pytest.mark.parametrize("width, slots, raw", [
    (1, [(10, -5, 127)], "0a857f"),
    (2, [(1000, -500, 0)], "e803f4810000"),
])
def test_entries_are_slot_major_with_the_direction_in_the_msb(width: int, slots: list[tuple[int, ...]],
                                                              raw: str) -> None:
    assert encode_entries(slots, width=width).hex() == raw
    assert signed_entries(bytes.fromhex(raw), 1, 3, width=width) == slots


def test_an_entry_count_that_does_not_fit_is_refused_by_the_client_encoder() -> None:
    with pytest.raises(ConfigurationError, match=r"-127\.\.127"):
        encode_entries([(128, 0, 0)], width=1)


def test_status_blocks_and_records_round_trip() -> None:
    v1 = StatusV1((180, -90, 2286), 1, 2, 4, 2, (1, 2, 30), 1, 0)
    frame = bytearray(64)
    put_status_v1(frame, v1)
    assert get_status_v1(frame) == v1
    v2 = StatusV2(0, 1, 2, 3, 1, 3, 0, 1, 2, 4, 1, (2, 2, 2, 0, 0, 0, 0, 0), (1, -2, 3, 0, 0, 0, 0, -4))
    put_status_v2(frame, v2)
    assert get_status_v2(frame) == v2
    record = AxisRecord(config=0x0D, switches=0x07, max_speed=25.0, accel=0.5, soft_min=-5, home_backoff=7)
    assert AxisRecord.from_bytes(record.to_bytes()) == record and len(record.to_bytes()) == 45
    params = ParamsV1((25.0, 20.0, 10.0), (0.5,) * 3, (0.25,) * 3, 10, 50, 1)
    assert ParamsV1.from_bytes(params.to_bytes()) == params and len(params.to_bytes()) == 39


@pytest.mark.parametrize("model, type_id, name, pe", [
    ("56E", 11, "PoKeys56E", (True, False)),
    ("57E", 31, "PoKeys57E", (False, True)),
    ("57CNC", 32, "PoKeys57CNC", (False, True)),
])
def test_device_data_decodes_to_type_serial_and_pulse_engine_as_the_library_does(
        model: str, type_id: int, name: str, pe: tuple[bool, bool]) -> None:
    identity = DeviceIdentity.preset(model, serial=20456 if model == "56E" else 1_000_001)
    data = decode_device_data(seal(identity_reply(identity, build_request(0x00, request_id=1))))
    assert (data.type_id, data.type_name, data.serial, (data.pe_v1, data.pe_v2)) == (type_id, name,
                                                                                   identity.serial, pe)
    assert data.firmware == ("3.0.60" if model == "56E" else "4.7.15")
    found = decode_discovery(discovery_reply(identity))
    assert found is not None and found.serial == identity.serial and found.device_ip == "127.0.0.1"


def test_handshake_commands_answer_user_id_network_name_and_date() -> None:
    identity = DeviceIdentity.preset("56E")
    reply = identity_reply(identity, build_request(0xE0, request_id=1))
    assert reply[9:17] == bytes((127, 0, 0, 1)) * 2 and reply[17:19] == b"\x1e\x00"
    name = identity_reply(identity, build_request(0x06, request_id=1))
    assert name[8:18] == name[35:45] == b"SimPoKeys\0"
    date = b"".join(identity_reply(identity, build_request(0x04, part, request_id=1))[2:6] for part in range(3))
    assert date.rstrip(b"\0") == b"Mar 14 2025"


@pytest.mark.parametrize("fields, message", [
    ({"model": "58E"}, "model"),
    ({"model": "56E", "serial": 19999, "fw_major": 0x20, "fw_minor": 60}, "20000..65534"),
    ({"model": "57E", "serial": 0}, "1..4294967295"),
    ({"model": "56E", "serial": 20123, "fw_major": 0x21, "fw_minor": 5}, "FW 3.0.59-3.0.65"),
    ({"name": "a name that is too long"}, "at most 10"),
])
def test_bad_identities_are_refused_naming_the_field(fields: dict[str, object], message: str) -> None:
    with pytest.raises(ConfigurationError, match=message):
        DeviceIdentity(**fields)  # type: ignore[arg-type]


def test_device_answers_malformed_requests_with_silence_and_counts_them() -> None:
    device = Device(DeviceIdentity.preset("57E"), FakeEngine())
    good = build_request(0x00, request_id=5)
    bad_checksum = good[:7] + bytes((good[7] ^ 1,)) + good[8:]
    lone_part = build_large_fill(0xFF, 0, 3, b"", first_id=1)[:64]
    for data in (b"\x00" * 10, b"\xaa" + good[1:], bad_checksum, lone_part, bytes(600)):
        assert device.handle(data) is None
    assert device.log.counts == {"bad_length": 2, "bad_header": 1, "bad_checksum": 1, "bad_multipart": 1}
    assert device.handle(good) is not None and device.log.counts["request"] == 1
