"""Shapes in clutter: a closed smooth contour hidden among random short segments, the display that
structural saliency is tested on (Sha'ashua and Ullman's, after the perceptual demonstrations of a
smooth closed figure that pops out of a field of oriented fragments).

:func:`clutter_display` draws an ellipse of random centre, radii and orientation, optionally broken by
evenly spaced gaps, among random straight segments of random orientation, as a one-pixel-thin line
drawing (the edge map a detector would give), and says which pixels are the contour's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from vmcl.cm.core import check_int, check_real
from vmcl.errors import InputTypeError, InputValueError

__all__ = ["LARGEST", "ClutterDisplay", "clutter_display"]

LARGEST = 16384
"""The largest side :func:`clutter_display` draws, in pixels."""


@dataclass(frozen=True, eq=False)
class ClutterDisplay:
    """What :func:`clutter_display` returns.

    Attributes
    ----------
    edges : bool (H, W)
        The line drawing: the contour's pixels and the segments' (lines one pixel wide, 8-connected).
    contour : bool (H, W)
        The contour's pixels among ``edges``.
    centre, radii : tuple of float
        The ellipse's centre (x, y) and semi-axes in pixels; ``angle`` its rotation in degrees.
    angle : float
    """

    edges: np.ndarray
    contour: np.ndarray
    centre: tuple[float, float]
    radii: tuple[float, float]
    angle: float


def clutter_display(shape: tuple[int, int] = (256, 256), *, segments: int = 200, length: tuple[float, float] = (5, 10),
                    gaps: int = 0, gap_length: int = 3, seed: int = 0) -> ClutterDisplay:
    """A closed smooth contour among random short segments.

    Parameters
    ----------
    shape : (int, int)
        (H, W), each from 64 to :data:`LARGEST`.
    segments : int
        The number of clutter segments, from 0 to one per pixel.
    length : (float, float)
        The segments' lengths are drawn uniformly from this range, in pixels (0 < low <= high).
    gaps : int
        Gaps cut into the contour, evenly spaced round it from a random start, >= 0.
    gap_length : int
        Pixels removed at each gap (the contour pixels nearest its place), >= 1.
    seed : int
        >= 0.

    Returns
    -------
    ClutterDisplay
    """
    if not (isinstance(shape, tuple) and len(shape) == 2):
        raise InputTypeError(f"shape must be a pair (H, W), got {shape!r}")
    height, width = (check_int(n, "shape", minimum=64, maximum=LARGEST) for n in shape)
    segments = check_int(segments, "segments", minimum=0, maximum=height * width)
    gaps = check_int(gaps, "gaps", minimum=0, maximum=height * width)
    gap_length = check_int(gap_length, "gap_length", minimum=1, maximum=height * width)
    seed = check_int(seed, "seed", minimum=0)
    if not (isinstance(length, tuple) and len(length) == 2):
        raise InputTypeError(f"length must be a pair (low, high), got {length!r}")
    low, high = (check_real(v, "length", above=0) for v in length)
    if low > high:
        raise InputValueError(f"length must be (low, high) with low <= high, got {length!r}")
    rng = np.random.default_rng(seed)
    clutter = np.zeros((height, width), np.uint8)
    for _ in range(segments):
        x, y = rng.uniform(0, width), rng.uniform(0, height)
        a, size = rng.uniform(0, math.pi), rng.uniform(low, high)
        cv2.line(clutter, (int(x), int(y)), (round(x + size * math.cos(a)), round(y + size * math.sin(a))),
                 1, 1)
    small = min(height, width)
    centre = (float(rng.uniform(0.35, 0.65) * width), float(rng.uniform(0.35, 0.65) * height))
    radii = (float(rng.uniform(0.12, 0.23) * small), float(rng.uniform(0.12, 0.23) * small))
    angle = float(rng.uniform(0, 180))
    figure = np.zeros((height, width), np.uint8)
    cv2.ellipse(figure, (round(centre[0]), round(centre[1])), (round(radii[0]), round(radii[1])),
                angle, 0, 360, 1, 1)
    if gaps:
        ys, xs = np.nonzero(figure)
        around = np.arctan2(ys - centre[1], xs - centre[0])
        start = rng.uniform(0, 2 * math.pi)
        for g in range(gaps):
            place = start + 2 * math.pi * g / gaps
            nearest = np.argsort(np.abs(np.angle(np.exp(1j * (around - place)))))[:gap_length]
            figure[ys[nearest], xs[nearest]] = 0
    edges = (clutter | figure).astype(bool)
    return ClutterDisplay(edges, edges & figure.astype(bool), centre, radii, angle)
