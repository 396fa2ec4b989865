"""UNET framing: the CRC, encoding, and the frame parser (hardware.protocol, hardware.commands).

The hypothesis properties of the framing (corruptions never accepted, streams recovered) are in
test_hardware_fuzz.py; these are the worked cases.
"""

import doctest
import importlib
import random

import pytest

from hardware.commands import Cmd, LayoutError, pack, unpack
from hardware.physics import COUNTS_PER_DEGREE
from hardware.protocol import (
    ESCAPE,
    FLAG,
    MAX_PAYLOAD,
    Frame,
    Parser,
    crc16,
    encode_reply,
    encode_request,
)


def feed_bytewise(data: bytes) -> list[Frame]:
    """What a micro's UART sees: the bytes one at a time."""
    parser = Parser()
    frames = []
    for byte in data:
        frames += parser.feed(bytes((byte,)))
    return frames


def test_crc_is_crc16_modbus_with_its_catalogue_check_value():
    assert crc16(b"123456789") == 0x4B37
    assert crc16(b"") == 0xFFFF


def test_crc_can_be_continued_over_pieces():
    assert crc16(b"6789", crc16(b"12345")) == crc16(b"123456789")


def test_request_layout_between_flags_and_crc_low_byte_first():
    frame = encode_request(5, 0x42, Cmd.MOVE_TO, pack(Cmd.MOVE_TO, 1, 2))
    assert frame[0] == frame[-1] == FLAG
    assert frame[1:5] == bytes((5, 0x42, 6, Cmd.MOVE_TO))
    assert frame[5:-3] == bytes((1,)) + (2).to_bytes(4, "little", signed=True)
    assert int.from_bytes(frame[-3:-1], "little") == crc16(frame[1:-3])  # ADDR to the end of the payload


def test_reply_sets_the_reply_bit_and_carries_status_then_command():
    frame = encode_reply(3, 9, 0x85, Cmd.STATUS, b"\x01\x00")
    assert frame[1] == 3 | 0x80
    assert frame[3] == 4
    assert frame[4:6] == bytes((0x85, Cmd.STATUS))


def test_flag_and_escape_bytes_inside_a_frame_are_stuffed_and_restored():
    payload = bytes((FLAG, ESCAPE, 0x85, 0xFB, FLAG, FLAG, ESCAPE))
    frame = encode_request(1, FLAG, Cmd.SET_PROFILE, payload)
    assert frame.count(FLAG) == 2 and frame[0] == frame[-1] == FLAG
    assert frame[2:4] == bytes((ESCAPE, FLAG ^ 0x20))  # SEQ A5 goes out as DB 85
    assert feed_bytewise(frame) == [Frame(1, FLAG, Cmd.SET_PROFILE, payload)]


def test_the_documented_examples_are_what_goes_on_the_wire():
    assert encode_request(1, 7, Cmd.PING).hex(" ") == "a5 01 07 01 01 70 49 a5"
    assert encode_reply(1, 7, 0, Cmd.PING, bytes((1, 2))).hex(" ") == "a5 81 07 04 00 01 01 02 ab ee a5"
    move = encode_request(1, 8, Cmd.MOVE_TO, pack(Cmd.MOVE_TO, 0, 34133))
    assert move.hex(" ") == "a5 01 08 06 11 00 55 85 00 00 63 a2 a5"
    assert encode_reply(1, 8, 5, Cmd.MOVE_TO).hex(" ") == "a5 81 08 02 05 11 78 e2 a5"
    assert encode_request(0, 3, Cmd.ESTOP).hex(" ") == "a5 00 03 01 05 31 b7 a5"


def test_a_move_whose_sequence_number_is_the_flag_byte_is_read_as_itself():
    # head.move(tilt=-30.52) with SEQ A5: protocol version 1 read a frame starting at that SEQ byte.
    payload = pack(Cmd.MOVE_TO, 1, round(-30.52 * COUNTS_PER_DEGREE))
    assert feed_bytewise(encode_request(1, 0xA5, Cmd.MOVE_TO, payload)) == [
        Frame(1, 0xA5, Cmd.MOVE_TO, payload)
    ]


@pytest.mark.parametrize(
    "inner",
    [
        bytes.fromhex("a5 00 03 01 05 59 8a"),  # ESTOP by broadcast, as protocol version 1 framed it
        encode_request(0, 3, Cmd.ESTOP),  # and as it is framed now
        encode_reply(1, 4, 0, Cmd.PING, bytes((1, 2))),
    ],
)
def test_a_frame_inside_a_payload_is_never_taken_for_a_frame(inner):
    payload = bytes((0,)) + inner + bytes(max(0, 9 - 1 - len(inner)))
    outer = encode_request(1, 9, Cmd.SET_PROFILE, payload)
    assert feed_bytewise(outer) == [Frame(1, 9, Cmd.SET_PROFILE, payload)]
    assert Parser().feed(outer) == [Frame(1, 9, Cmd.SET_PROFILE, payload)]


def version_1_len_trap(rng: random.Random, bit: int) -> bytes | None:
    """A request on the wire with bit `bit` of its LEN flipped, where the bytes at which protocol
    version 1 would look for the CRC of the frame LEN now announces hold exactly that CRC: in the
    payload when LEN shrinks, in the bytes after the frame when it grows. None where no such trap fits
    (LEN out of bounds, or the CRC would have to lie on the frame's own CRC)."""
    for _ in range(1000):
        addr, seq, cmd = rng.randrange(32), rng.randrange(FLAG), rng.randrange(256)
        payload = bytearray(rng.randbytes(rng.randint(0, MAX_PAYLOAD)))
        length = 1 + len(payload)
        wrong = length ^ (1 << bit)
        if not 1 <= wrong <= MAX_PAYLOAD + 1 or length - 2 < wrong < length + 3:
            continue
        tail = b""
        if wrong < length:
            shorter = bytes((FLAG, addr, seq, wrong, cmd)) + payload[: wrong - 1]
            payload[wrong - 1 : wrong + 1] = crc16(shorter).to_bytes(2, "little")
        wire = encode_request(addr, seq, cmd, bytes(payload))
        if FLAG in wire[1:-1] or ESCAPE in wire[1:-1]:
            continue  # keep wire positions equal to version 1's, so the trap lies where it aims
        corrupted = wire[:3] + bytes((wrong,)) + wire[4:]
        if wrong > length:
            filler = rng.randbytes(4 + wrong - len(corrupted))
            tail = filler + crc16(corrupted + filler).to_bytes(2, "little")
        return corrupted + tail
    return None


def test_every_single_bit_len_error_is_refused_even_where_a_matching_crc_waits():
    """Version 1 accepted a 1-bit LEN error whenever the bytes where the wrong LEN put the CRC happened
    to hold a matching one (about 1 frame in 100,000 at random); here they always do."""
    rng = random.Random(5)
    traps = 0
    for _ in range(500):
        for bit in range(8):
            trap = version_1_len_trap(rng, bit)
            if trap is not None:
                traps += 1
                assert feed_bytewise(trap) == [], trap.hex(" ")
            frame = encode_request(rng.randrange(32), rng.randrange(FLAG), 1, rng.randbytes(10))
            if ESCAPE not in frame:
                corrupted = bytearray(frame)
                corrupted[3] ^= 1 << bit  # ADDR < 32 and SEQ < A5 are never escaped: LEN is wire byte 3
                assert Parser().feed(bytes(corrupted) + rng.randbytes(40)) == []
    assert traps >= 1500  # bits 1..4; bit 0 puts the CRC on the frame's own, bits 5..7 LEN out of bounds


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


def test_garbage_before_a_frame_is_skipped_even_with_false_flags():
    frame = encode_reply(1, 1, 0, Cmd.PING, b"\x01\x01")
    # A false flag whose "header" announces a long body is closed by the real frame's opening flag.
    garbage = bytes((0x00, FLAG, 0x81, 0x00, 0x20, FLAG, FLAG, 0xFF, ESCAPE))
    parser = Parser()
    assert parser.feed(garbage + frame) == [Frame(1, 1, Cmd.PING, b"\x01\x01", 0)]
    assert parser.dropped == len(garbage) - garbage.count(FLAG)


def test_a_frame_cut_short_is_dropped_and_the_next_one_read():
    first, second = (
        encode_reply(1, 1, 0, Cmd.STATUS, b"\x02\x00"),
        encode_reply(1, 2, 0, Cmd.PING, b"\x01\x02"),
    )
    parser = Parser()
    assert parser.feed(first[:6] + second) == [Frame(1, 2, Cmd.PING, b"\x01\x02", 0)]
    assert parser.dropped == 5


def test_frame_split_across_feeds_and_bytes_needed():
    frame = encode_reply(2, 3, 0, Cmd.GALVO_GET, bytes(10))
    assert FLAG not in frame[1:-1] and ESCAPE not in frame[1:-1]
    parser = Parser()
    assert parser.bytes_needed() == 8  # a flag, the shortest request, a flag
    assert parser.feed(frame[:4]) == []
    # 15 more bytes would finish this frame; but a flag now and the shortest frame would take 8.
    assert parser.bytes_needed() == 8
    assert parser.feed(frame[4:-8]) == []
    assert parser.bytes_needed() == 8
    assert parser.feed(frame[-8:-3]) == []
    assert parser.bytes_needed() == 3
    assert parser.feed(frame[-3:-1]) == []
    assert parser.bytes_needed() == 1
    assert len(parser.feed(frame[-1:])) == 1
    assert parser.bytes_needed() == 7  # the closing flag may open the next frame


def test_every_single_bit_flip_is_rejected():
    frame = encode_request(1, 2, Cmd.MOVE_TO, pack(Cmd.MOVE_TO, 0, 123456))
    for i in range(8, (len(frame) - 1) * 8):  # the flags are not the frame's: flipping one loses it
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


def test_seeded_random_streams_with_many_faults_yield_only_sent_frames():
    rng = random.Random(0)
    sent = [
        encode_request(rng.randrange(32), rng.randrange(256), rng.randrange(256), rng.randbytes(8))
        for _ in range(2000)
    ]
    stream = bytearray(b"".join(sent))
    hit = set()
    for _ in range(400):
        at = rng.randrange(len(stream))
        stream[at] ^= 1 << rng.randrange(8)
        hit.add(at)
    got = Parser().feed(bytes(stream))
    decoded = [Parser().feed(f)[0] for f in sent]
    # Every frame no flip touched comes through, in order, and nothing else: a flipped flag byte
    # costs only the frame it belonged to, since each frame has flags of its own.
    starts = [0]
    for frame in sent:
        starts.append(starts[-1] + len(frame))
    intact = [f for f, a, b in zip(decoded, starts, starts[1:]) if not hit & set(range(a, b))]
    assert got == intact
    assert len(intact) > 2000 - 400


@pytest.mark.parametrize("module", ["hardware", "hardware.protocol", "hardware.head"])
def test_docstring_examples_run(module):
    failures, tried = doctest.testmod(importlib.import_module(module))
    assert tried > 0
    assert failures == 0
