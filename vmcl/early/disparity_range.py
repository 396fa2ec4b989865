"""The disparity range of a stereo pair, found from the images by a coarse-to-fine search.

The matcher (:func:`vmcl.early.stereo.match`) compares the two views over a given range of disparities;
what that range is, is a property of the scene, which only the images tell. Both views are smoothed with
the binomial mask (:func:`vmcl.cm.filters.binomial`, the seed's Gaussian on the mesh) and halved, ``k``
times, until the smaller side would drop below ``coarse_side``; at that level a disparity of half the
width is a few dozen planes, so a wide range is searched cheaply. Dense intensity matches are made
there in both directions, and a match counts when its correlation is high and the other view's match
points back to it (left-right consistency, which rejects the chance winners of occluded and untextured
pixels). The low and high quantiles of the confident matches are the range at that level; each finer
level, down to half resolution, searches the coarser one's range doubled and widened by a margin, and
narrows it to its own quantiles. The last range, times the last level's scale and widened by a margin of
its pixels for its error, is the range at full resolution.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pyopencl as cl
import pyopencl.array as cl_array

from vmcl.cm.core import ArrayLike, check_int, check_real, finite_float32, machine_for
from vmcl.cm.filters import binomial
from vmcl.early.filters import gaussian
from vmcl.early.stereo import StereoMatch, check_pair, check_range, match
from vmcl.errors import InputValueError
from vmcl.machine import Machine, on_device

__all__ = ["MAX_DISPARITY", "DisparityRange", "estimate_range", "fallback_range", "range_to_search", "with_given_ends"]

MAX_DISPARITY = 0.5
"""The widest disparity searched by default, either sign, as a share of the image width: near objects of
a wide-baseline rig reach 40% of the width."""

_PATCH = 11
"""The correlation patch of :func:`estimate_range` by default (the matcher's default patch)."""

_PYRAMID_PASSES = 2
"""Binomial passes before each halving: two passes of [1 2 1] / 4 are Burt and Adelson's 5-tap
[1 4 6 4 1] / 16 reduction filter (a Gaussian of sigma 1), which suppresses what halving would alias."""


@dataclass(frozen=True)
class DisparityRange:
    """What :func:`estimate_range` found, and what it was based on.

    Attributes
    ----------
    d_min, d_max : int
        The range at full resolution (``I_left(x, y) = I_right(x - d, y)``), margin included; when not
        ``decided``, the wide fallback of :func:`fallback_range`.
    decided : bool
        Whether enough confident matches were found to decide the range; False: too few, and
        ``d_min, d_max`` are the fallback.
    level : int
        How many times the images were halved (the coarse level; its scale is ``1 / 2**level``).
    confident : float
        The confident matches' share of the coarse level's pixels.
    searched : (int, int)
        The range searched at the coarse level, in full-resolution pixels.
    found : (int, int) or None
        The quantiles of the confident matches at the finest level searched, in full-resolution pixels,
        before the margin; None when not decided.
    """

    d_min: int
    d_max: int
    decided: bool
    level: int
    confident: float
    searched: tuple[int, int]
    found: tuple[int, int] | None


def fallback_range(width: int, max_disparity: float = MAX_DISPARITY) -> tuple[int, int]:
    """The wide range a caller matches over when the images do not decide it: 0 to
    ``floor(max_disparity * width)``, no more than the matcher takes (``width - 1``).

    Non-negative only: a parallel rig's rectified pair has d >= 0 (the points in front of both
    cameras); negative disparities come from a shifted rectification, which the estimate sees when it
    decides.
    """
    width = check_int(width, "width", minimum=1)
    max_disparity = check_real(max_disparity, "max_disparity", above=0, maximum=1)
    return 0, min(width - 1, math.floor(max_disparity * width))


def estimate_range(left: ArrayLike, right: ArrayLike, *, max_disparity: float = MAX_DISPARITY, coarse_side: int = 48,
                   patch: int = _PATCH, min_score: float = 0.8, quantile: float = 0.005, margin: int = 1,
                   widen: float = 0.25, min_share: float = 0.05, machine: Machine | None = None) -> DisparityRange:
    """Estimate the disparity range of a rectified pair from the images (coarse to fine).

    Parameters
    ----------
    left, right : (H, W) or (H, W, 3) arrays or device arrays; uint8, uint16 or float
        The pair, as :func:`vmcl.early.stereo.match` takes it (rows are epipolar lines).
    max_disparity : float
        In (0, 1]: the widest disparity searched, either sign, as a share of the image width.
    coarse_side : int
        The images are halved while their smaller side stays at least this (k = 0 for smaller images).
    patch : int
        Odd side of the correlation patch at every level searched (the matcher's default; smaller
        patches let periodic texture, such as the "blocks" scene's stripes, match a period off).
    min_score : float
        A match is confident when its normalised cross-correlation is at least this and the right
        view's match at the pixel it points to is within one pixel of it.
    quantile : float
        In [0, 0.5): the range found runs from this quantile of the confident matches to ``1 -
        quantile`` (a few stray matches do not widen it).
    margin : int
        >= 0: pixels of a level added on each side of its range, for that level's error (a disparity
        found there is known to one of its pixels): when the next finer level searches it, and at full
        resolution (``margin * 2`` pixels when the search ended at half resolution).
    widen : float
        >= 0: the full-resolution range is widened on each side by this share of its width (besides the
        margin). Near objects small in the image shrink to a few pixels at the coarse levels, where too
        few of their matches are confident to reach the quantiles, and a disparity missing from the
        range is lost to every pixel that has it, while one too many only costs matching time. The
        value is that asymmetry's allowance, not a fit.
    min_share : float
        In (0, 1]: the range is decided only when the confident matches are at least this share of the
        coarse pixels (and at least ``patch**2`` of them); else ``decided`` is False and the range is
        :func:`fallback_range`.
    machine : vmcl.Machine, optional

    Returns
    -------
    DisparityRange

    Notes
    -----
    The level k is the most halvings (sides rounded up) that keep the smaller side at least
    ``coarse_side``. At level k, each view is smoothed by ``_PYRAMID_PASSES`` binomial passes (a grey
    image first for RGB) and every other pixel kept. The left view is matched over
    [-S, S], S = floor(max_disparity * W_k), by dense intensity correlation (centred windows); the right
    view over the same range by matching it against the left one with the disparities negated, which
    gives the right view's disparities without mirroring the images. A left match d at x is kept when
    its score is at least ``min_score`` and the right view's match at ``x - d`` is within 1 of d; the
    kept matches' quantiles, floor(q_lo) .. ceil(q_hi), are the level's range. Level j - 1 then searches
    [2 lo - 2 margin, 2 hi + 2 margin] the same way, down to level 1 (a finer level that keeps too few
    matches leaves the coarser range). With the last level j, the range is
    ``2^j (lo - margin) - s .. 2^j (hi + margin) + s`` with ``s = ceil(widen * 2^j (hi - lo))``, clipped to
    what the matcher accepts at full resolution.

    Raises
    ------
    InputTypeError, InputValueError
        Not a pair of images of one shape and type, or images smaller than the patch.
    """
    machine = machine_for(machine)
    check_pair(left, right, machine)
    images = tuple(finite_float32(image, name) if isinstance(image, np.ndarray) else image
                   for name, image in (("left", left), ("right", right)))
    max_disparity = check_real(max_disparity, "max_disparity", above=0, maximum=1)
    coarse_side = check_int(coarse_side, "coarse_side", minimum=1)
    patch = check_int(patch, "patch", minimum=1)
    if patch % 2 == 0:
        raise InputValueError(f"patch must be odd (a window centred on the pixel), got {patch}")
    min_score = check_real(min_score, "min_score", minimum=-1, maximum=1)
    quantile = check_real(quantile, "quantile", minimum=0, below=0.5)
    margin = check_int(margin, "margin", minimum=0)
    widen = check_real(widen, "widen", minimum=0)
    min_share = check_real(min_share, "min_share", above=0, maximum=1)
    height, width = images[0].shape[:2]
    if min(height, width) < patch:
        raise InputValueError(f"left and right must be at least the patch ({patch} pixels) on each side to find "
                              f"their disparity range, got {height} x {width} (or give the range: d_min and d_max)")
    level = _level(height, width, max(coarse_side, patch))
    pyramid = [_reduce(image, level, machine) for image in images]
    coarse_width = pyramid[0][-1].shape[1]
    reach = max(0, min(coarse_width // 2 - 1, math.floor(max_disparity * coarse_width)))
    searched = (-reach * 2**level, reach * 2**level)
    search = _Search(patch, min_score, quantile, machine)
    found, share = search.range(pyramid[0][-1], pyramid[1][-1], -reach, reach)
    if found is None or share < min_share:
        return DisparityRange(*fallback_range(width, max_disparity), decided=False, level=level, confident=share,
                              searched=searched, found=None)
    # Down the pyramid to level 1: each level searches the coarser one's range, doubled and widened by
    # the margin, and narrows it to its own quantiles. Level 0 would be the full match itself.
    finest = level
    while finest > 1:
        low, high = 2 * found[0] - 2 * margin, 2 * found[1] + 2 * margin
        finer, _ = search.range(pyramid[0][finest - 1], pyramid[1][finest - 1], low, high,
                                keep=(2 * found[0], 2 * found[1]))
        if finer is None:
            break
        found, finest = finer, finest - 1
    scale = 2**finest
    spread = math.ceil(widen * scale * (found[1] - found[0]))
    # The matcher takes |d| < W and at most W planes: the margins are cut where they would pass those
    # limits, never what the images showed.
    d_min = max(scale * (found[0] - margin) - spread, -(width - 1), scale * found[1] - (width - 1))
    d_max = min(scale * (found[1] + margin) + spread, width - 1, d_min + width - 1)
    return DisparityRange(d_min, d_max, decided=True, level=level, confident=share, searched=searched,
                          found=(scale * found[0], scale * found[1]))


@dataclass(frozen=True)
class _Search:
    """The matching and the statistics of one pyramid level, as :func:`estimate_range` was told them."""

    patch: int
    min_score: float
    quantile: float
    machine: Machine

    def range(self, left: cl_array.Array, right: cl_array.Array, d_min: int, d_max: int,
              keep: tuple[int, int] | None = None) -> tuple[tuple[int, int] | None, float]:
        """The quantiles (floor, ceil) of one level's confident matches over [d_min, d_max] (None when
        fewer than ``patch**2``), and their share of the level's pixels. A range the matcher cannot search
        at this level (|d| >= W, or more than W planes) is cut at its ends, the part ``keep`` (the coarser
        level's range, in this level's pixels) kept whole."""
        width = left.shape[1]
        d_min, d_max = max(d_min, -(width - 1)), min(d_max, width - 1)
        if keep is not None:
            # As at full resolution: the margins are cut, never what the images showed (cutting the top
            # alone lost it: tsukuba with margin 100 searched -191..0 at half size, and found -222..0).
            d_min = max(d_min, keep[1] - (width - 1))
        d_max = min(d_max, d_min + width - 1)
        forward = self._match(left, right, d_min, d_max)
        # The right view's disparities, without mirroring the images: matched against the left one over
        # the negated range, they come out negated.
        backward = self._match(right, left, -d_max, -d_min)
        # The level's three fields come back in one wait: the statistics are the host's, and the range
        # they give is the one scalar pair the matcher's launches need. (pyopencl's concatenate would
        # build a copy program of its own, on a first run's clock.)
        fields = [on_device(a) for a in (forward.disparity, forward.score, backward.disparity)]
        host = np.empty((len(fields), *fields[0].shape), fields[0].dtype)
        reads = [self.machine.read_into(host[k], field) for k, field in enumerate(fields)]
        events = [event for event in reads if event is not None]  # None: an empty field, nothing to read
        if events:  # OpenCL refuses an empty wait list
            cl.wait_for_events(events)
        disparity, score, back = host
        values = disparity[_consistent(disparity, score, -back, self.min_score)]
        share = values.size / disparity.size
        if values.size < self.patch * self.patch:
            return None, share
        low, high = np.quantile(values, (self.quantile, 1 - self.quantile))
        return (math.floor(low), math.ceil(high)), share

    def _match(self, left: cl_array.Array, right: cl_array.Array, d_min: int, d_max: int) -> StereoMatch:
        # Light smoothing: the pyramid has smoothed already. Whole-pixel matches: the range's bounds are
        # the quantiles rounded outwards, which sub-pixel disparities moved out by a pixel a level (blocks:
        # 2..12 became -6..14, and its dense bad-1 rose from 2.9% to 8.4%).
        return match(left, right, d_min=d_min, d_max=d_max, features="intensity", patch=self.patch,
                            sigma=0.5, subpixel=False, machine=self.machine)


def _level(height: int, width: int, side: int) -> int:
    """The most halvings (rounding up) that keep the smaller side at least ``side``."""
    level, smaller = 0, min(height, width)
    while -(-smaller // 2) >= side:
        smaller, level = -(-smaller // 2), level + 1
    return level


def _reduce(image, level: int, machine: Machine) -> list[cl_array.Array]:
    """Levels 0..``level`` of the grey image's binomial pyramid on the device: each level smoothed by
    ``_PYRAMID_PASSES`` binomial passes and halved (every other pixel)."""
    data = gaussian(machine.to_device(image) if isinstance(image, np.ndarray) else image,
                    sigma=math.sqrt(_PYRAMID_PASSES / 2), method="binomial", machine=machine)
    levels = [data]
    for k in range(level):
        if k:
            data = binomial(data, _PYRAMID_PASSES, machine=machine)
        height, width = data.shape
        half = machine.empty((-(-height // 2), -(-width // 2)), np.float32)
        machine.launch(machine.kernel("motion", "decimate"), (half.shape[1], half.shape[0]), data, half,
                       np.int64(width), np.int64(height), np.int64(half.shape[1]), np.int64(half.shape[0]))
        levels.append(half)
        data = half
    return levels


def _consistent(disparity: np.ndarray, score: np.ndarray, back: np.ndarray, min_score: float) -> np.ndarray:
    """Left matches of score >= min_score whose right view's match (``back``, right-view disparities)
    at x - d is within one pixel of d."""
    width = disparity.shape[1]
    known = np.isfinite(disparity) & (score >= min_score)
    ys, xs = np.nonzero(known)
    d = disparity[ys, xs]
    target = np.rint(xs - d).astype(np.int64)
    inside = (target >= 0) & (target < width)
    agree = np.zeros(d.shape, bool)
    other = back[ys[inside], target[inside]]
    agree[inside] = np.abs(other - d[inside]) <= 1
    kept = np.zeros_like(known)
    kept[ys[agree], xs[agree]] = True
    return kept


def range_to_search(left: ArrayLike, right: ArrayLike, d_min: int | None = None, d_max: int | None = None, *,
                    machine: Machine | None = None) -> tuple[int, int]:
    """The disparity range a matcher searches: the given ends, the others found from the images by
    :func:`estimate_range` (an end given overrides that end, and the found one moves to it if it would
    cross it), checked against the image's width.

    Parameters
    ----------
    left, right : arrays
        The pair, as :func:`estimate_range` takes it (matched only when an end is missing).
    d_min, d_max : int, optional

    Returns
    -------
    (d_min, d_max) : tuple of int
    """
    machine = machine_for(machine)
    check_pair(left, right, machine)  # checked even when both ends are given: one call, one contract
    low = None if d_min is None else check_int(d_min, "d_min")
    high = None if d_max is None else check_int(d_max, "d_max")
    if low is None or high is None:
        height, width = left.shape[:2]
        if min(height, width) < _PATCH:
            # estimate_range would say so in terms of its own patch, which the caller of a matcher never gave.
            raise InputValueError(f"left and right ({height} x {width}) are too small to find their disparity range "
                                  f"from the images (at least {_PATCH} pixels on each side): give d_min and d_max")
        low, high = with_given_ends(estimate_range(left, right, machine=machine), low, high)
    check_range(low, high, left.shape[1])
    return low, high


def with_given_ends(found: DisparityRange, d_min: int | None, d_max: int | None) -> tuple[int, int]:
    """The range ``found`` from the images with the ends a user gave in its place: a given end overrides that
    end, and the found one moves to it if it would cross it.

    Parameters
    ----------
    found : DisparityRange
    d_min, d_max : int or None
        The given ends (None: the found one's).

    Returns
    -------
    (d_min, d_max) : tuple of int
    """
    if d_min is None and d_max is None:
        return found.d_min, found.d_max
    if d_min is None:
        assert d_max is not None
        return min(found.d_min, d_max), d_max
    return d_min, max(found.d_max, d_min) if d_max is None else d_max
