"""NumPy oracles for the Connection Machine primitives, written for clarity, not speed."""

import itertools

import numpy as np

UFUNCS = {"plus": np.add, "max": np.maximum, "min": np.minimum}
IDENTITIES = {
    "plus": lambda dtype: dtype.type(0),
    "max": lambda dtype: dtype.type(-np.inf) if dtype.kind == "f" else np.iinfo(dtype).min,
    "min": lambda dtype: dtype.type(np.inf) if dtype.kind == "f" else np.iinfo(dtype).max,
    "copy": lambda dtype: dtype.type(0),
}


def scan_line(line, op, exclusive, starts):
    """Segmented scan of one 1-D line; starts marks segment starts (the line start is one anyway)."""
    out = np.empty_like(line)
    bounds = list(np.flatnonzero(starts)) + [len(line)]
    if bounds[0] != 0:
        bounds.insert(0, 0)
    for a, b in itertools.pairwise(bounds):
        seg = line[a:b]
        inclusive = np.full_like(seg, seg[0]) if op == "copy" else UFUNCS[op].accumulate(seg)
        if exclusive:
            out[a] = IDENTITIES[op](line.dtype)
            out[a + 1:b] = inclusive[:-1]
        else:
            out[a:b] = inclusive
    return out


def scan(x, op="plus", axis=-1, exclusive=False, segments=None):
    moved = np.moveaxis(x, axis, -1)
    starts = np.zeros(moved.shape, bool) if segments is None else np.moveaxis(segments != 0, axis, -1)
    out = np.empty_like(moved)
    for index in np.ndindex(moved.shape[:-1]):
        out[index] = scan_line(moved[index], op, exclusive, starts[index])
    return np.moveaxis(out, -1, axis)


def box_sum(x, r, axes=(-2, -1)):
    """Window sums with zeros outside, from float64 (or int64) prefix sums."""
    acc = x.astype(np.float64 if x.dtype.kind == "f" else np.int64)
    for axis in axes:
        n = acc.shape[axis]
        prefix = np.cumsum(acc, axis=axis)
        prefix = np.concatenate([np.zeros_like(np.take(prefix, [0], axis=axis)), prefix], axis=axis)
        index = np.arange(n)
        acc = np.take(prefix, np.minimum(index + r + 1, n), axis=axis) - np.take(prefix, np.maximum(index - r, 0), axis=axis)
    return acc
