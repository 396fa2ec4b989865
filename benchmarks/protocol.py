"""How often the eye-head protocol's parser accepts a damaged frame, written to benchmarks/results/protocol.md.

hardware/PROTOCOL.md argues why no single damage can pass the framing (flags at both ends, byte stuffing,
LEN checked against the bytes between the flags, CRC-16 over the content); this script measures it.
Each row: random frames (requests and replies, random addresses, SEQ, codes and payloads of 0 to
MAX_PAYLOAD random bytes), each damaged once between its flags as the row says and followed by an intact
frame. A stream counts as wrong if anything but the intact frame comes out of it (a false frame accepted,
or the intact one lost). Then random bytes on the line: how many frames the parser finds in them.

Run: ``python benchmarks/protocol.py [FRAMES_PER_ROW]`` (default 500,000).
"""

from __future__ import annotations

import platform
import random
import sys
import time
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from hardware.protocol import ESCAPE, FLAG, MAX_PAYLOAD, Parser, encode_reply, encode_request

RESULTS = ROOT / "benchmarks" / "results" / "protocol.md"


def random_frame(rng: random.Random) -> bytes:
    payload = rng.randbytes(rng.randint(0, MAX_PAYLOAD))
    if rng.random() < 0.5:
        return encode_reply(rng.randint(1, 31), rng.randrange(256), rng.randrange(256), rng.randrange(256), payload)
    return encode_request(rng.randint(0, 31), rng.randrange(256), rng.randrange(256), payload)


# Each damage acts between the frame's flags: wire bytes 1 .. len - 2.
def bits_flipped(count: int) -> Callable[[bytes, random.Random], bytes]:
    def damage(wire: bytes, rng: random.Random) -> bytes:
        out = bytearray(wire)
        for i, bit in rng.sample([(i, b) for i in range(1, len(wire) - 1) for b in range(8)], count):
            out[i] ^= 1 << bit
        return bytes(out)
    return damage


def burst(wire: bytes, rng: random.Random) -> bytes:
    out = bytearray(wire)
    i, pattern = rng.randrange(1, len(wire) - 2), rng.randrange(1, 1 << 16)
    out[i] ^= pattern & 0xFF
    out[i + 1] ^= pattern >> 8
    return bytes(out)


def replaced(wire: bytes, rng: random.Random) -> bytes:
    out = bytearray(wire)
    i = rng.randrange(1, len(wire) - 1)
    out[i] = (out[i] + rng.randrange(1, 256)) & 0xFF
    return bytes(out)


def inserted(wire: bytes, rng: random.Random) -> bytes:
    i = rng.randint(2, len(wire) - 2)
    return wire[:i] + bytes((rng.randrange(256),)) + wire[i:]


def deleted(wire: bytes, rng: random.Random) -> bytes:
    i = rng.randrange(1, len(wire) - 1)
    return wire[:i] + wire[i + 1:]


def cut_short(wire: bytes, rng: random.Random) -> bytes:
    return wire[:rng.randint(1, len(wire) - 2)]


def len_bit_flipped(wire: bytes, rng: random.Random) -> bytes:
    out = bytearray(wire)
    out[3] ^= 1 << rng.randrange(8)  # LEN is wire byte 3 when ADDR and SEQ needed no escape
    return bytes(out)


def flag_inside(wire: bytes, rng: random.Random) -> bytes:
    out = bytearray(wire)
    out[rng.randrange(1, len(wire) - 1)] = FLAG  # the one damage that splits a frame
    return bytes(out)


DAMAGES: dict[str, Callable[[bytes, random.Random], bytes]] = {
    "1 bit flipped": bits_flipped(1), "2 bits flipped": bits_flipped(2), "3 bits flipped": bits_flipped(3),
    "a burst of up to 16 bits": burst, "one byte replaced by another": replaced, "one byte inserted": inserted,
    "one byte deleted": deleted, "cut short": cut_short, "1 bit of LEN flipped": len_bit_flipped,
    "a byte turned into the flag (A5)": flag_inside,
}


def wrong_streams(name: str, frames: int, rng: random.Random) -> tuple[int, int]:
    """(streams with anything but the intact frame out, streams tried) for one damage."""
    after = encode_request(2, 2, 1)
    expected = Parser().feed(after)
    wrong = tried = 0
    for _ in range(frames):
        wire = random_frame(rng)
        if name == "1 bit of LEN flipped" and (wire[1] in (FLAG, ESCAPE) or wire[2] in (FLAG, ESCAPE)):
            continue  # an escaped ADDR or SEQ moves LEN off byte 3
        tried += 1
        wrong += Parser().feed(DAMAGES[name](wire, rng) + after) != expected
    return wrong, tried


def main(argv: list[str]) -> int:
    frames = int(argv[0]) if argv else 500_000
    rng = random.Random(2024)
    start = time.perf_counter()
    rows = [(name, *wrong_streams(name, frames, rng)) for name in DAMAGES]
    noise = rng.randbytes(100 * frames)
    false_frames = len(Parser().feed(noise))
    seconds = time.perf_counter() - start
    lines = ["# Eye-head protocol: damaged frames the parser accepts", "",
             (f"Measured by `python benchmarks/protocol.py {frames}` on {platform.node() or 'this machine'} "
             f"({platform.machine()}, Python {platform.python_version()}, {time.strftime('%Y-%m-%d')}), "
             f"{seconds:.0f} s."), "",
             ("Each row: random frames, each damaged once between its flags, then an intact frame; wrong: anything "
             "but the intact frame came out (a false frame, or the intact one lost). With none wrong in n, the "
             "rate is below 3 / n at 95% confidence."), "",
             "| damage (one per frame) | wrong | of |", "|---|---:|---:|"]
    lines += [f"| {name} | {wrong} | {tried:,} |" for name, wrong, tried in rows]
    lines += ["", f"Random bytes on the line: {false_frames} false frames in {len(noise):,} bytes."]
    RESULTS.write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
