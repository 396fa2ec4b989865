"""Arithmetic on points and directions held as (3, N) float32 arrays (structure of arrays).

NumPy's (N, 3) @ (3,) products ran many times slower than three scaled rows added, so the ray
caster, the shading and the renderer all keep points as three rows and use :func:`dot` and
:func:`transform`.
"""

from __future__ import annotations

import numpy as np

__all__ = ["F32", "dot", "transform"]

F32 = np.float32
"""The renderer's working precision (images, depths and points are float32)."""


def dot(v, points: np.ndarray):
    """v . p for a 3-vector v and (3, N) points, or a float for one (3,) point."""
    if points.ndim == 1:
        return float(np.dot(v, points))
    return points[0] * F32(v[0]) + points[1] * F32(v[1]) + points[2] * F32(v[2])


def transform(rot: np.ndarray, trans: np.ndarray, points: np.ndarray) -> np.ndarray:
    """rot @ p + trans for (3, N) points."""
    return np.stack([dot(rot[k], points) + F32(trans[k]) for k in range(3)])
