"""Procedural textures: the achromatic modulation a :class:`~vmcl.scenes.world.Texture` applies to the
albedo of a region, evaluated at surface coordinates (s, t) and fixed to the surface by a hash key.
"""

from __future__ import annotations

import math

import numpy as np

from vmcl.scenes.points import F32
from vmcl.scenes.world import Texture

__all__ = ["texture_modulation"]


def _hash01(i: np.ndarray, j: np.ndarray, key: int) -> np.ndarray:
    """Uniform [0, 1) from integer lattice coordinates and a key (splitmix64 finaliser)."""
    with np.errstate(over="ignore"):
        x = (i.astype(np.int64).view(np.uint64) * np.uint64(0x9E3779B97F4A7C15)
             ^ j.astype(np.int64).view(np.uint64) * np.uint64(0xC2B2AE3D27D4EB4F)
             ^ np.uint64(key & 0xFFFFFFFFFFFFFFFF))
        x ^= x >> np.uint64(30)
        x *= np.uint64(0xBF58476D1CE4E5B9)
        x ^= x >> np.uint64(27)
        x *= np.uint64(0x94D049BB133111EB)
        x ^= x >> np.uint64(31)
    return ((x >> np.uint64(40)).astype(np.float32)) * F32(2.0**-24)


class _Lattice:
    """Random values of the lattice cells a set of pixels touches, hashed once per cell, not per pixel."""

    def __init__(self, i: np.ndarray, j: np.ndarray, key: int):
        self.i0, self.j0 = int(i.min()), int(j.min())
        shape = (int(i.max()) - self.i0 + 2, int(j.max()) - self.j0 + 2)
        self.key = key
        # A grazing plane can span more cells than there are pixels: then hash per pixel.
        self.table = None
        if shape[0] * shape[1] <= i.size:
            ii, jj = np.meshgrid(np.arange(shape[0]) + self.i0, np.arange(shape[1]) + self.j0, indexing="ij")
            self.table = ii, jj

    def __call__(self, i: np.ndarray, j: np.ndarray, offset: int = 0) -> np.ndarray:
        if self.table is None:
            return _hash01(i, j, self.key + offset)
        values = _hash01(*self.table, self.key + offset)
        return values[i - self.i0, j - self.j0]


def texture_modulation(texture: Texture, s: np.ndarray, t: np.ndarray, key: int) -> np.ndarray:
    """The factor ``texture`` multiplies the albedo by at surface coordinates (s, t), mean 1; ``key``
    seeds its random elements (one key, one pattern)."""
    c = F32(texture.contrast)
    if texture.kind == "flat" or c == 0:
        return np.ones_like(s)
    if texture.kind in ("stripes", "gradient"):
        a = s * F32(math.cos(texture.angle)) + t * F32(math.sin(texture.angle))
        if texture.kind == "stripes":
            return 1 + c * np.sin(a * F32(2 * math.pi / texture.scale))
        return 1 + c * np.tanh(a / F32(texture.scale))
    fs, ft = s / F32(texture.scale), t / F32(texture.scale)
    i, j = np.floor(fs), np.floor(ft)
    fx, fy = fs - i, ft - j
    i, j = i.astype(np.int64), j.astype(np.int64)
    cell = _Lattice(i, j, key)
    if texture.kind == "noise":
        wx, wy = fx * fx * (3 - 2 * fx), fy * fy * (3 - 2 * fy)
        top = cell(i, j) * (1 - wx) + cell(i + 1, j) * wx
        bottom = cell(i, j + 1) * (1 - wx) + cell(i + 1, j + 1) * wx
        return 1 + c * (2 * (top * (1 - wy) + bottom * wy) - 1)
    # Blobs: one per cell at most, kept 3 sigma inside it, so a pixel needs only its own cell.
    sigma = texture.size / texture.scale
    margin, span = 3 * sigma, 1 - 6 * sigma
    bx = margin + span * cell(i, j, 1)
    by = margin + span * cell(i, j, 2)
    present = cell(i, j) < texture.fill
    blob = np.exp(((fx - bx) ** 2 + (fy - by) ** 2) * F32(-0.5 / sigma**2)) * present
    mean = 1 - texture.contrast * texture.fill * 2 * math.pi * sigma**2
    return (1 - c * blob) / F32(mean)
