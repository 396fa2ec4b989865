"""Philox4x32-10 in kernels/philox.h against Random123's known-answer vectors."""

import numpy as np
from pyopencl import cltypes

# Random123 tests/kat_vectors, rows "philox4x32 10": counter[4], key[2], expected[4].
KAT = [
    ((0x00000000, 0x00000000, 0x00000000, 0x00000000), (0x00000000, 0x00000000),
     (0x6627E8D5, 0xE169C58D, 0xBC57AC4C, 0x9B00DBD8)),
    ((0xFFFFFFFF, 0xFFFFFFFF, 0xFFFFFFFF, 0xFFFFFFFF), (0xFFFFFFFF, 0xFFFFFFFF),
     (0x408F276D, 0x41C83B0E, 0xA20BC7C6, 0x6D5451FD)),
    ((0x243F6A88, 0x85A308D3, 0x13198A2E, 0x03707344), (0xA4093822, 0x299F31D0),
     (0xD16CFE09, 0x94FDCCEB, 0x5001E420, 0x24126EA1)),
]


def _blocks(machine, counters, keys):
    n = len(counters)
    out = machine.empty((n, 4), np.uint32)
    kernel = machine.kernel("mrf", "philox_blocks", NCOMP=1, KIND=0, NLEVELS=1, MODE=0)
    machine.launch(kernel, (n,), machine.to_device(np.asarray(counters, np.uint32)),
                   machine.to_device(np.asarray(keys, np.uint32)), out, np.int64(n))
    return out.get()


def test_known_answer_vectors(machine):
    got = _blocks(machine, [c for c, _, _ in KAT], [k for _, k, _ in KAT])
    np.testing.assert_array_equal(got, np.asarray([e for _, _, e in KAT], np.uint32))


def test_words_are_uniform(machine):
    """Counters 0..n-1 under one key: each of the 32 bits is set in half the words (within 5 sigma)."""
    n = 1 << 16
    counters = np.zeros((n, 4), np.uint32)
    counters[:, 0] = np.arange(n)
    words = _blocks(machine, counters, np.tile(np.uint32([7, 0]), (n, 1))).ravel()
    bits = (words[:, None] >> np.arange(32, dtype=np.uint32)) & 1
    share = bits.mean(axis=0)
    assert np.all(np.abs(share - 0.5) < 5 * 0.5 / np.sqrt(words.size))


def test_four_lane_rounds_match_scalar_blocks(machine):
    """philox4x32_10_x4 (four blocks on uint4 lanes, as the samplers draw them) gives the scalar blocks."""
    n = 1 << 12
    counters = np.random.default_rng(3).integers(0, 1 << 32, (n, 4), dtype=np.uint64).astype(np.uint32)
    counters[:len(KAT)] = [c for c, _, _ in KAT]
    key = np.uint32([0xA4093822, 0x299F31D0])
    expected = _blocks(machine, counters, np.tile(key, (n, 1)))
    out = machine.empty((n, 4), np.uint32)
    kernel = machine.kernel("mrf", "philox_blocks4", NCOMP=1, KIND=0, NLEVELS=1, MODE=0)
    machine.launch(kernel, (n // 4,), machine.to_device(counters), cltypes.make_uint2(*key), out, np.int64(n))
    np.testing.assert_array_equal(out.get(), expected)
    assert tuple(expected[2]) == KAT[2][2]  # the third counter's block under the third vector's key
