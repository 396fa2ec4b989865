"""Whether a stereo pair's rows are epipolar lines: how far the right view's rows lie from the left's.

Every matcher of the machine searches along rows (seed section "Stereo": the images are registered first,
so that epipolar lines are rows). A pair whose views are offset vertically by a pixel or two, or turned
against each other, still gives a disparity map, but a wrong one, and the left-right check flags only
part of it (benchmarks/results/rectification.md). So the offset is measured, not inferred: corners of the
left view (Shi and Tomasi's) are tracked into the right view by pyramidal Lucas-Kanade (OpenCV's), from a
given typical disparity, and back again; the tracks that return to where they started give the vertical
offset of the rows (their median) and how much it varies across the image (a rotation or a difference of
scale between the views spreads it). The tracking is the host's (OpenCV does it in a few milliseconds);
the matching itself stays on the device.

References
----------
J. Shi and C. Tomasi, "Good features to track", CVPR 1994.
J.-Y. Bouguet, "Pyramidal implementation of the Lucas Kanade feature tracker", Intel, 2000.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from vmcl.cm.core import check_real, check_unit_image, real_host_array
from vmcl.early.filters import GREY_WEIGHTS
from vmcl.errors import InputValueError
from vmcl.pictures import eight_bits

__all__ = ["ROW_OFFSET_NOTE", "ROW_SPREAD_NOTE", "RowAlignment", "row_alignment"]

ROW_OFFSET_NOTE = 0.8
"""Half the tracks' rows off by at least this many pixels (:attr:`RowAlignment.typical`), the machine's run
notes that the pair is not rectified. Chosen on the training pairs (benchmarks/results/rectification.md, by
a rule set before the run): the smallest ``typical`` measured on a training pair moved by the smallest
vertical shift at which the depth machine's mean bad-1 reached 1.5 times the aligned pairs'. It is compared
with what is measured, not with a shift: real pairs come a little off themselves, so a shift does not
measure as itself."""

ROW_SPREAD_NOTE = 0.1
"""Where the note is made, it adds that the views are turned or scaled against each other when the tracks'
offsets spread at least this far (:attr:`RowAlignment.spread`): more than on any training pair that was
only shifted (benchmarks/results/rectification.md: the step of 0.05 px above their largest spread). The note itself
follows :attr:`RowAlignment.typical` alone: a match is harmed by its own row's offset, whether the rows are
offset as a whole or turned."""


CORNERS = 150
"""The most corners tracked."""
HALVE_FROM = 256
"""Views of at least this many pixels on their smaller side find their corners at half size."""
WINDOW = 21
"""Lucas-Kanade's window, in pixels."""
RETURN = 0.5
"""A track is kept when tracking it back from the right view lands within this many pixels of its start."""
LEAST_TRACKS = 20
"""Fewer kept tracks than this say nothing (an untextured pair)."""
COARSEST_SIDE = 32
"""The tracker's pyramid halves the images while the smaller side stays at least this long."""


@dataclass(frozen=True)
class RowAlignment:
    """How the right view's rows lie against the left's, from corners tracked between them.

    Attributes
    ----------
    offset : float
        The median vertical displacement of the tracks, in pixels (y_right - y_left): 0 for a rectified pair.
    spread : float
        The median distance of the tracks' vertical displacements from ``offset``: near 0 for a pair offset
        as a whole; larger where the views are turned or scaled against each other.
    typical : float
        The median of the tracks' absolute vertical displacements: half the tracks are off by more.
    tracks : int
        The tracks kept (those that came back to their start).
    """

    offset: float
    spread: float
    typical: float
    tracks: int


def _eight_bit_grey(image: np.ndarray, name: str) -> np.ndarray:
    """A view as the tracker takes it: 8-bit grey (uint16 levels / 257, float brightness in [0, 1] x 255), an
    RGB view weighed by the machine's :data:`vmcl.early.filters.GREY_WEIGHTS`, as its matchers see it."""
    real_host_array(image, name, ndims=(2, 3))
    if image.ndim == 3 and image.shape[2] != 3:
        raise InputValueError(f"{name} must be grey (H, W) or RGB (H, W, 3), got shape {image.shape}")
    if image.dtype == np.uint8:
        eight = image
    elif image.dtype == np.uint16:
        eight = eight_bits(image)
    elif image.dtype.kind == "f":
        if not np.isfinite(image).all():
            raise InputValueError(f"{name} must not contain NaN or infinite values")
        check_unit_image(image, name)
        # Clipped first: convertScaleAbs would fold the margin below 0 that check_unit_image allows upwards.
        eight = cv2.convertScaleAbs(np.clip(image, 0, 1, dtype=np.float32), alpha=255)
    else:
        raise InputValueError(f"{name} must be uint8, uint16 or float brightness in [0, 1], got {image.dtype}")
    if eight.ndim == 2:
        return eight
    return np.rint(eight @ np.array(GREY_WEIGHTS, np.float32)).astype(np.uint8)


def _corners(grey: np.ndarray) -> np.ndarray | None:
    """Up to :data:`CORNERS` of Shi and Tomasi's corners of an 8-bit view, float32 (N, 1, 2), or None. A view
    of :data:`HALVE_FROM` or more on its smaller side is searched at half size (OpenCV's pyrDown, a quarter
    of the work) and the corners scaled back: the tracker, which starts from them, places them at full size."""
    if min(grey.shape) < HALVE_FROM:
        return cv2.goodFeaturesToTrack(grey, CORNERS, 0.01, WINDOW // 3)
    found = cv2.goodFeaturesToTrack(cv2.pyrDown(grey), CORNERS, 0.01, WINDOW // 6)
    return None if found is None else (2 * found).astype(np.float32)


def row_alignment(left: np.ndarray, right: np.ndarray, *, disparity: float | np.ndarray = 0.0
                  ) -> RowAlignment | None:
    """The vertical offset of the right view's rows from the left's, from corners tracked between the views.

    Parameters
    ----------
    left, right : (H, W) or (H, W, 3) NumPy arrays of one shape
        uint8, uint16, or float brightness in [0, 1].
    disparity : float, or (H, W) float array
        Where each track starts its search in the right view: at x - d for a disparity d (x_right = x_left -
        d). A number for every corner, or a disparity map (a matcher's, NaN where it has none) read at each
        corner's pixel, which leaves the tracker only the matcher's error to find; corners where the map has
        no value start at the median of its values. The tracker reaches about 10 px times 2**levels (its
        pyramid's, down to a side of :data:`COARSEST_SIDE`) from the start.

    Returns
    -------
    RowAlignment, or None where fewer than :data:`LEAST_TRACKS` tracks came back to their start (too
    little texture to tell).
    """
    grey = [_eight_bit_grey(image, name) for name, image in (("left", left), ("right", right))]
    if left.shape != right.shape:
        raise InputValueError(f"left and right must have one shape, got {left.shape} and {right.shape}")
    height, width = grey[0].shape
    if isinstance(disparity, np.ndarray):
        real_host_array(disparity, "disparity", ndims=(2,))
        if disparity.shape != (height, width):
            raise InputValueError(f"disparity must be a number or a map of the views' size {(height, width)}, got "
                                  f"shape {disparity.shape}")
        if np.isinf(disparity).any():
            raise InputValueError("disparity must not hold infinite values (NaN: no value)")
    else:
        disparity = check_real(disparity, "disparity")
    if min(height, width) < WINDOW:
        return None  # the window does not fit: nothing to track
    corners = _corners(grey[0])
    if corners is None or len(corners) < LEAST_TRACKS:
        return None
    levels = 0
    while min(height, width) >> (levels + 1) >= COARSEST_SIDE:
        levels += 1
    if isinstance(disparity, np.ndarray):
        rows, columns = (np.clip(np.rint(corners[:, 0, k]).astype(int), 0, n - 1) for k, n in ((1, height), (0, width)))
        at = disparity[rows, columns].astype(np.float64)
        known = disparity[np.isfinite(disparity)]
        at = np.where(np.isfinite(at), at, np.median(known) if known.size else 0.0)
    else:
        at = np.full(len(corners), disparity)
    start = corners.copy()
    start[:, 0, 0] -= at.astype(np.float32)
    criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 30, 0.01)
    tracked, found, _ = cv2.calcOpticalFlowPyrLK(grey[0], grey[1], corners, start, winSize=(WINDOW, WINDOW),
                                                 maxLevel=levels, criteria=criteria,
                                                 flags=cv2.OPTFLOW_USE_INITIAL_FLOW)
    back, returned, _ = cv2.calcOpticalFlowPyrLK(grey[1], grey[0], tracked, corners.copy(),
                                                 winSize=(WINDOW, WINDOW), maxLevel=levels, criteria=criteria,
                                                 flags=cv2.OPTFLOW_USE_INITIAL_FLOW)
    kept = (found[:, 0] == 1) & (returned[:, 0] == 1) & (np.linalg.norm((back - corners)[:, 0], axis=1) < RETURN)
    if kept.sum() < LEAST_TRACKS:
        return None
    rise = (tracked - corners)[kept, 0, 1].astype(np.float64)
    offset = float(np.median(rise))
    return RowAlignment(offset, float(np.median(np.abs(rise - offset))), float(np.median(np.abs(rise))),
                        int(kept.sum()))
