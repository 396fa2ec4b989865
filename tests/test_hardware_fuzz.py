"""A fuzzer of the UNET framing (hardware.protocol): hypothesis throws encoded frames, corrupted frames,
frames hidden in payloads and garbage at the parser, and checks that it takes exactly the frames that
were sent, intact, in order, and never anything else.

13,500 cases in all, derandomized so that a run repeats; each case builds its whole stream from
one or two draws, since hypothesis's own cost per draw is what bounds the time.
"""

import random

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from hardware.protocol import (
    ESCAPE,
    FLAG,
    MAX_ADDRESS,
    MAX_PAYLOAD,
    REPLY_BIT,
    Frame,
    Parser,
    crc16,
    encode_reply,
    encode_request,
)


def fuzz(examples: int):
    return settings(
        max_examples=examples, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck)
    )


def random_frame(rng: random.Random) -> tuple[Frame, bytes]:
    """A frame and its encoding; payloads are rich in flag and escape bytes, the ones stuffing must hide."""
    seq, cmd = rng.choice((FLAG, ESCAPE, rng.randrange(256))), rng.randrange(256)
    size = rng.randint(0, MAX_PAYLOAD)
    payload = bytes(rng.choice((FLAG, ESCAPE, 0x85, 0xFB, rng.randrange(256))) for _ in range(size))
    if rng.random() < 0.5:
        addr, status = rng.randint(1, MAX_ADDRESS), rng.choice((FLAG, ESCAPE, rng.randrange(256)))
        return Frame(addr, seq, cmd, payload, status), encode_reply(addr, seq, status, cmd, payload)
    addr = rng.randint(0, MAX_ADDRESS)
    return Frame(addr, seq, cmd, payload), encode_request(addr, seq, cmd, payload)


# The oracle of the stuffing, written out independently of hardware.protocol.
def stuff(content: bytes) -> bytes:
    return (
        bytes((FLAG,)) + content.replace(b"\xdb", b"\xdb\xfb").replace(b"\xa5", b"\xdb\x85") + bytes((FLAG,))
    )


def unstuff(wire: bytes) -> bytes:
    return wire[1:-1].replace(b"\xdb\x85", b"\xa5").replace(b"\xdb\xfb", b"\xdb")


def legacy(frame: Frame) -> bytes:
    """`frame` as protocol version 1 sent it: a sync byte, no stuffing, the CRC over the sync byte too."""
    if frame.is_reply:
        head, body = (frame.addr | REPLY_BIT, frame.seq), bytes((frame.status, frame.cmd)) + frame.payload
    else:
        head, body = (frame.addr, frame.seq), bytes((frame.cmd,)) + frame.payload
    data = bytes((FLAG, *head, len(body))) + body
    return data + crc16(data).to_bytes(2, "little")


def pieces(data: bytes, rng: random.Random) -> list[bytes]:
    """`data` cut at a few random places (a UART hands bytes over in chunks of any size)."""
    cuts = sorted(rng.randrange(len(data) + 1) for _ in range(rng.randint(0, 4)))
    return [data[a:b] for a, b in zip([0, *cuts], [*cuts, len(data)])]


def parse(data: bytes, rng: random.Random) -> list[Frame]:
    parser = Parser()
    frames = []
    for piece in pieces(data, rng):
        frames += parser.feed(piece)
        assert parser.bytes_needed() >= 1
    return frames


# --- every frame round-trips -----------------------------------------------------------------------


@fuzz(2_000)
@given(
    addr=st.integers(0, MAX_ADDRESS),
    seq=st.integers(0, 255),
    cmd=st.integers(0, 255),
    status=st.none() | st.integers(0, 255),
    payload=st.binary(max_size=MAX_PAYLOAD),
)
def test_every_encoded_frame_round_trips(addr, seq, cmd, status, payload):
    if status is None:
        sent, wire = Frame(addr, seq, cmd, payload), encode_request(addr, seq, cmd, payload)
    else:
        addr = max(addr, 1)
        sent, wire = Frame(addr, seq, cmd, payload, status), encode_reply(addr, seq, status, cmd, payload)
    # The flag opens and closes the frame and appears nowhere else; no escape is left dangling.
    assert wire[0] == wire[-1] == FLAG and FLAG not in wire[1:-1]
    assert wire[-2] != ESCAPE
    assert Parser().feed(wire) == [sent]
    assert parse(wire + wire, random.Random(seq)) == [sent, sent]


# --- no corrupted frame is ever accepted -----------------------------------------------------------


def corrupt(wire: bytes, kind: int, rng: random.Random) -> bytes:
    """`wire` (one encoded frame) with one kind of damage to what lies between its flags."""
    frame = bytearray(wire)
    inside = range(1, len(frame) - 1)
    if kind == 0:  # one to three bits flipped
        for at in rng.sample([(i, b) for i in inside for b in range(8)], rng.randint(1, 3)):
            frame[at[0]] ^= 1 << at[1]
    elif kind == 1:  # cut short: the rest of the frame, its closing flag and at least one byte, is lost
        del frame[rng.randint(1, len(frame) - 2) :]
    elif kind == 2:  # a byte inserted strictly inside (any byte: a flag, an escape...)
        frame.insert(rng.randint(2, len(frame) - 2), rng.choice((FLAG, ESCAPE, rng.randrange(256))))
    elif kind == 3:  # a byte lost from inside
        del frame[rng.choice(inside)]
    else:  # LEN wrong by any amount, with the CRC left alone or (kind 5) recomputed to match
        length = unstuff(wire)[2]
        frame = bytearray(relength(wire, length ^ rng.randint(1, 255), recompute_crc=kind == 5))
    return bytes(frame)


def len_trap(rng: random.Random) -> bytes:
    """A frame whose LEN has lost some bytes, and whose payload holds, just where that shorter frame
    would end, the CRC of the shorter frame: computed over the sync byte too as version 1 did, or not.
    Only a LEN checked against the bytes actually received refuses it for sure."""
    frame, wire = random_frame(rng)
    head = bytes((frame.addr | REPLY_BIT, frame.seq)) if frame.is_reply else bytes((frame.addr, frame.seq))
    prefix = bytes((frame.status, frame.cmd)) if frame.is_reply else bytes((frame.cmd,))
    body = bytearray(prefix + frame.payload + rng.randbytes(MAX_PAYLOAD - len(frame.payload)))[
        : len(prefix) + 30
    ]
    short = rng.randint(len(prefix), len(body) - 2)
    sync = bytes((FLAG,)) if rng.random() < 0.5 else b""
    body[short : short + 2] = crc16(sync + head + bytes((short,)) + body[:short]).to_bytes(2, "little")
    if frame.is_reply:
        wire = encode_reply(frame.addr, frame.seq, body[0], body[1], bytes(body[2:]))
    else:
        wire = encode_request(frame.addr, frame.seq, body[0], bytes(body[1:]))
    return relength(wire, short, recompute_crc=False)


def relength(wire: bytes, length: int, *, recompute_crc: bool) -> bytes:
    """`wire` with its LEN byte replaced: unstuff, change, restuff (the CRC recomputed or not)."""
    content = bytearray(unstuff(wire))
    content[2] = length
    if recompute_crc:
        content[-2:] = crc16(content[:-2]).to_bytes(2, "little")
    return stuff(bytes(content))


@fuzz(8_000)
@given(seed=st.binary(min_size=8, max_size=8), kind=st.integers(0, 6))
def test_no_corrupted_frame_is_ever_accepted(seed, kind):
    """A corrupted frame between two intact ones: the parser returns the two intact ones, in order, and
    nothing else, whatever the damage (bit errors, truncation, an inserted or lost byte, a wrong LEN
    with or without a CRC that matches it, a short LEN with a matching CRC where it points)."""
    rng = random.Random(seed)
    (before, before_wire), (_, wire), (after, after_wire) = (random_frame(rng) for _ in range(3))
    damaged = len_trap(rng) if kind == 6 else corrupt(wire, kind, rng)
    assert damaged != wire
    assert parse(before_wire + damaged + after_wire, rng) == [before, after]


# --- a frame inside another frame's payload is never found -----------------------------------------


@fuzz(1_500)
@given(seed=st.binary(min_size=8, max_size=8), version_1=st.booleans())
def test_no_frame_inside_a_payload_is_ever_accepted(seed, version_1):
    """Payloads that hold whole frames (framed as now, or as protocol version 1 framed them, with a
    flag byte but no stuffing) at any offset: only the outer frame comes out, fed whole or in pieces."""
    rng = random.Random(seed)
    frame, inner = random_frame(rng)
    if version_1:
        inner = legacy(frame)
    inner = inner[: rng.randint(2, MAX_PAYLOAD)]
    room = MAX_PAYLOAD - len(inner)
    payload = rng.randbytes(rng.randint(0, room)) + inner
    payload += rng.randbytes(rng.randint(0, MAX_PAYLOAD - len(payload)))
    outer = Frame(1, rng.randrange(256), rng.randrange(256), payload)
    wire = encode_request(outer.addr, outer.seq, outer.cmd, payload)
    assert parse(wire, rng) == [outer]
    assert parse(wire * 2, rng) == [outer, outer]


# --- valid frames among garbage are all recovered, in order ---------------------------------------


@fuzz(2_000)
@given(seed=st.binary(min_size=8, max_size=8), junk=st.binary(max_size=64))
def test_frames_among_garbage_are_all_recovered_in_order(seed, junk):
    """Garbage before, between and after the frames (random bytes with flags and escapes among them, and
    now and then a frame as protocol version 1 sent it, which is garbage to version 2), the stream fed
    in pieces of any size: every frame comes out, in order, and nothing else."""
    rng = random.Random(seed)
    junk = bytes(rng.choice((FLAG, ESCAPE, b)) if rng.random() < 0.1 else b for b in junk)
    frames = [random_frame(rng) for _ in range(rng.randint(1, 4))]
    cuts = sorted(rng.randrange(len(junk) + 1) for _ in range(len(frames)))
    garbage = [junk[a:b] for a, b in zip([0, *cuts], [*cuts, len(junk)])]
    garbage = [g + legacy(random_frame(rng)[0]) if rng.random() < 0.25 else g for g in garbage]
    stream = b"".join(g + wire for g, (_, wire) in zip(garbage, frames)) + garbage[-1]
    assert parse(stream, rng) == [frame for frame, _ in frames]
