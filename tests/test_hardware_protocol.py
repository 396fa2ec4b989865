"""UNET framing: the CRC, encoding, and the resynchronising parser (hardware.protocol, hardware.commands)."""

import doctest
import importlib
import random

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from hardware.commands import Cmd, LayoutError, pack, unpack
from hardware.protocol import (
    MAX_PAYLOAD,
    SYNC,
    Frame,
    Parser,
    crc16,
    encode_reply,
    encode_request,
)


def test_crc_is_crc16_modbus_with_its_catalogue_check_value():
    assert crc16(b"123456789") == 0x4B37
    assert crc16(b"") == 0xFFFF


def test_crc_can_be_continued_over_pieces():
    assert crc16(b"6789", crc16(b"12345")) == crc16(b"123456789")


def test_request_layout_and_crc_low_byte_first():
    frame = encode_request(5, 0x42, Cmd.MOVE_TO, pack(Cmd.MOVE_TO, 1, -2))
    assert frame[:5] == bytes((SYNC, 5, 0x42, 6, Cmd.MOVE_TO))
    assert frame[5:-2] == bytes((1,)) + (-2).to_bytes(4, "little", signed=True)
    assert int.from_bytes(frame[-2:], "little") == crc16(frame[:-2])


def test_reply_sets_the_reply_bit_and_carries_status_then_command():
    frame = encode_reply(3, 9, 0x85, Cmd.STATUS, b"\x01\x00")
    assert frame[1] == 3 | 0x80
    assert frame[3] == 4
    assert frame[4:6] == bytes((0x85, Cmd.STATUS))


@pytest.mark.parametrize(
    ("kwargs", "error", "name"),
    [
        ({"addr": 32}, ValueError, "addr"),
        ({"addr": -1}, ValueError, "addr"),
        ({"seq": 256}, ValueError, "seq"),
        ({"cmd": "1"}, TypeError, "cmd"),
        ({"payload": bytes(MAX_PAYLOAD + 1)}, ValueError, "payload"),
        ({"payload": "text"}, TypeError, "payload"),
    ],
)
def test_encode_rejects_bad_arguments_by_name(kwargs, error, name):
    args = {"addr": 1, "seq": 0, "cmd": 1, "payload": b""} | kwargs
    with pytest.raises(error, match=name):
        encode_request(**args)


def test_reply_to_broadcast_address_is_refused():
    with pytest.raises(ValueError, match="addr"):
        encode_reply(0, 0, 0, 1)


def test_round_trip_of_requests_and_replies():
    parser = Parser()
    req = encode_request(7, 200, Cmd.GALVO_SET, pack(Cmd.GALVO_SET, 1, -10000, 10000))
    rep = encode_reply(7, 200, 0, Cmd.GALVO_SET)
    assert parser.feed(req + rep) == [
        Frame(7, 200, Cmd.GALVO_SET, pack(Cmd.GALVO_SET, 1, -10000, 10000)),
        Frame(7, 200, Cmd.GALVO_SET, b"", 0),
    ]
    assert parser.dropped == 0


def test_garbage_before_a_frame_is_skipped_even_with_false_sync_bytes():
    frame = encode_reply(1, 1, 0, Cmd.PING, b"\x01\x01")
    # A false sync byte whose "header" announces a long body swallows the real frame at first.
    garbage = bytes((0x00, SYNC, 0x81, 0x00, 0x20, SYNC, SYNC, 0xFF))
    parser = Parser()
    assert parser.feed(garbage + frame) == [Frame(1, 1, Cmd.PING, b"\x01\x01", 0)]
    assert parser.dropped == len(garbage)


def test_frame_split_across_feeds_and_bytes_needed():
    frame = encode_reply(2, 3, 0, Cmd.GALVO_GET, bytes(10))
    parser = Parser()
    assert parser.bytes_needed() == 7
    assert parser.feed(frame[:4]) == []
    assert parser.bytes_needed() == len(frame) - 4
    assert parser.feed(frame[4:-1]) == []
    assert parser.bytes_needed() == 1
    assert len(parser.feed(frame[-1:])) == 1


def test_every_single_bit_flip_is_rejected():
    frame = encode_request(1, 2, Cmd.MOVE_TO, pack(Cmd.MOVE_TO, 0, 123456))
    for i in range(len(frame) * 8):
        corrupted = bytearray(frame)
        corrupted[i // 8] ^= 1 << (i % 8)
        parser = Parser()
        assert parser.feed(bytes(corrupted)) == [], f"bit {i} flipped was accepted"


def test_layouts_check_lengths_and_commands():
    assert unpack(Cmd.AXIS_STATUS, pack(Cmd.AXIS_STATUS, -5, 7, 3, reply=True), reply=True) == (-5, 7, 3)
    with pytest.raises(LayoutError, match="MOVE_TO expects 5"):
        unpack(Cmd.MOVE_TO, b"\x00")
    with pytest.raises(LayoutError, match="unknown command 0x7f"):
        pack(0x7F)
    with pytest.raises(LayoutError, match="GALVO_SET"):
        pack(Cmd.GALVO_SET, 0, 40000, 0)


# --- property tests: the parser never crashes and never accepts a corrupted frame ------------------


def _random_frames(rng: random.Random) -> list[bytes]:
    frames = []
    for _ in range(rng.randint(1, 4)):
        addr, seq, cmd = rng.randrange(32), rng.randrange(256), rng.randrange(256)
        payload = rng.randbytes(rng.randint(0, MAX_PAYLOAD))
        if rng.random() < 0.5:
            frames.append(encode_reply(max(addr, 1), seq, rng.randrange(256), cmd, payload))
        else:
            frames.append(encode_request(addr, seq, cmd, payload))
    return frames


def _chunks(data: bytes, cuts: list[int]) -> list[bytes]:
    """`data` cut at `cuts` (taken modulo its length): len(cuts) + 1 pieces, some perhaps empty."""
    points = sorted(c % (len(data) + 1) for c in cuts)
    return [data[a:b] for a, b in zip([0, *points], [*points, len(data)])]


# Hypothesis's own cost is about 0.4 ms a draw here, so each example is two draws: the garbage, and 16
# bytes of knobs (frame seed, where the garbage splits, the error burst, where the stream is cut).
@settings(max_examples=10_000, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck))
@given(junk=st.binary(max_size=40), knobs=st.binary(min_size=16, max_size=16))
def test_parser_recovers_every_intact_frame_and_no_corrupted_one(junk, knobs):
    """Frames separated by garbage, one of them perhaps hit by an error burst of up to 16 bits (a 1- or
    2-byte XOR; CRC-16 detects every such burst), fed in pieces: the parser returns every intact frame,
    in order, and nothing else."""
    sent = _random_frames(random.Random(knobs[:4]))
    garbage = _chunks(junk, list(knobs[4:8]))
    burst = knobs[8:13] if knobs[8] & 1 else None
    cuts = list(knobs[13:16])
    stream = bytearray()
    spans = []
    for junk_piece, frame in zip(garbage, sent):
        stream += junk_piece
        spans.append((len(stream), len(stream) + len(frame)))
        stream += frame
    stream += garbage[-1]
    hit = None
    if burst is not None:
        where, pattern, two = burst[1], int.from_bytes(burst[2:4], "little") or 1, burst[4] & 1
        hit = where % len(sent)
        start, end = spans[hit]
        at = start + where % (end - start)
        width = 2 if two and at + 1 < end else 1
        if width == 1 and pattern & 0xFF == 0:
            pattern |= 1
        for k in range(width):
            stream[at + k] ^= (pattern >> (8 * k)) & 0xFF
    parser = Parser()
    got = []
    for piece in _chunks(bytes(stream), [c * len(stream) // 255 for c in cuts]):
        got += parser.feed(piece)
    decoded = [Parser().feed(f)[0] for f in sent]
    assert all(f in decoded for f in got), "accepted a frame that was never sent"
    intact = [f for i, f in enumerate(decoded) if i != hit]
    remaining = iter(got)
    assert all(any(f == g for g in remaining) for f in intact), "lost an intact frame"
    if hit is not None and decoded.count(decoded[hit]) == 1:
        assert decoded[hit] not in got, "accepted the corrupted frame"


@settings(max_examples=2_000, deadline=None, derandomize=True)
@given(data=st.binary(max_size=200), cuts=st.binary(max_size=8))
def test_parser_never_crashes_on_random_bytes(data, cuts):
    parser = Parser()
    total = 0
    for piece in _chunks(data, list(cuts)):
        for frame in parser.feed(piece):
            assert isinstance(frame, Frame)
            encoded = (
                encode_reply(frame.addr, frame.seq, frame.status, frame.cmd, frame.payload)
                if frame.is_reply
                else encode_request(frame.addr, frame.seq, frame.cmd, frame.payload)
            )
            assert encoded in data
            total += len(encoded)
        assert parser.bytes_needed() >= 1
    assert parser.dropped + total <= len(data)


def test_seeded_random_streams_with_many_faults_yield_only_sent_frames():
    rng = random.Random(0)
    sent = [
        encode_request(rng.randrange(32), rng.randrange(256), rng.randrange(256), rng.randbytes(8))
        for _ in range(2000)
    ]
    stream = bytearray(b"".join(sent))
    for _ in range(400):
        stream[rng.randrange(len(stream))] ^= 1 << rng.randrange(8)
    got = Parser().feed(bytes(stream))
    decoded = {Parser().feed(f)[0] for f in sent}
    assert got and all(f in decoded for f in got)
    assert len(got) > 2000 - 400 - 50


@pytest.mark.parametrize("module", ["hardware", "hardware.protocol", "hardware.head"])
def test_docstring_examples_run(module):
    failures, tried = doctest.testmod(importlib.import_module(module))
    assert tried > 0
    assert failures == 0
