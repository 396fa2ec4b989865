"""Motion: optical flow by patchwise comparison of two frames over a range of displacements.

Seed section "Motion" (Bulthoff, Little and Poggio). The flow is assumed locally constant, and small,
within (+-delta, +-delta). For every displacement v = (vx, vy) of the range, every processor compares
frame 0 at (x, y) with frame 1 at (x + vx, y + vy) (a squared difference of brightness or of the
Laplacian of a Gaussian, or the "exclusive or" of binary maps: the sign of the LoG, or edges); the
comparisons are summed over the patch around each pixel with scans (:func:`vmcl.cm.scan.box_sum`), a
vote for a patch of surface moving with v; and the winner per pixel is chosen by "non-maximum
suppression across velocities", done as a running extremum during the iteration over displacements so
that "no actual table of summed differences over displacements need be constructed" (the faithful
table variant is kept for comparison). A low normalised score at the chosen displacement marks
occlusions and motion boundaries. Beyond the paper: a sub-pixel parabola fit and a coarse-to-fine
pyramid for motions larger than delta.

The paper's theorem on why edge- and intensity-based variants agree is
:mod:`vmcl.early.sign_correlation`.

References
----------
H. H. Bulthoff, J. J. Little and T. Poggio, "A parallel algorithm for real-time computation of optical
flow", Nature 337:549-553, 1989.
J. J. Little, H. H. Bulthoff and T. Poggio, "Parallel optical flow using local voting", Proc. ICCV,
1988.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
import pyopencl.array as cl_array

from vmcl.cm import scan
from vmcl.cm.core import (
    ArrayLike,
    check_bool,
    check_choice,
    check_int,
    check_real,
    check_same_kind,
    check_same_scale,
    field,
    machine_for,
)
from vmcl.early import edges as _edges
from vmcl.early import filters as _filters
from vmcl.early.sign_correlation import arcsine_law
from vmcl.errors import InputTypeError, InputValueError
from vmcl.machine import Machine

__all__ = [
    "BOUNDARY_SCORE",
    "COARSEST_SIDE",
    "DEFAULT_SIGMA",
    "DELTA",
    "EDGE_QUANTILES",
    "FEATURES",
    "METHODS",
    "PATCH",
    "PYRAMID_SIGMA",
    "SPEED_PENALTY",
    "Features",
    "FlowResult",
    "Method",
    "flow",
    "pyramid_levels",
    "reach",
    "votes",
]

Features = Literal["brightness", "log", "sign_log", "edges"]
Method = Literal["running", "table"]

FEATURES: tuple[Features, ...] = ("brightness", "log", "sign_log", "edges")
METHODS: tuple[Method, ...] = ("running", "table")

DEFAULT_SIGMA = {"brightness": 1.0, "log": 2.0, "sign_log": 1.0, "edges": 1.5}
"""Gaussian width (pixels) of each feature map when ``sigma`` is None (sign_log: of 1.0, 1.5 and 2.0, 1.0
gave the lowest mean EPE on the real sequences of benchmarks/results/motion.md)."""

EDGE_QUANTILES = (0.7, 0.9)
"""Canny's hysteresis thresholds for the "edges" features, as quantiles of the gradient magnitude: a
fixed share of the image is edge whatever its contrast (the noise rule finds none in clean renderings)."""

DELTA = 4
"""Default displacement range of :func:`flow` (the machine's, vmcl.pipeline.MotionConfig.delta): motions up to
4 px at one level, about 4 (2**levels - 1) px with a pyramid (:func:`reach`)."""

PATCH = 21
"""Default patch width of :func:`flow` (the machine's, vmcl.pipeline.MotionConfig.patch, fitted by
benchmarks/motion_fit.py on rendered scenes)."""

SPEED_PENALTY = 1e-3
"""Default slow-motion prior of the squared-difference features (see :func:`flow`)."""

PYRAMID_SIGMA = 1.0
"""Gaussian smoothing before each halving of the pyramid."""

COARSEST_SIDE = 32
"""The smallest side of the coarsest level :func:`pyramid_levels` goes down to, in pixels."""

BOUNDARY_SCORE = {"brightness": 0.9, "log": 0.9, "sign_log": float(arcsine_law(0.9)), "edges": 0.5}
"""Default ``boundary_score`` per feature: the sign correlation's is the arcsine law's image of 0.9."""

_COMPARE = {"brightness": 0, "log": 0, "sign_log": 1, "edges": 2}
_IMAGE_DTYPES = (np.uint8, np.uint16, np.float32)


@dataclass(frozen=True)
class FlowResult:
    """What :func:`flow` returns (NumPy arrays, or device arrays for device input).

    Attributes
    ----------
    flow : float32 (H, W, 2)
        (u, v) with ``frame0(x, y) = frame1(x + u, y + v)``; NaN where there is no estimate.
    score : float32 (H, W)
        The normalised score of the chosen displacement, 1 for a perfect match (see :func:`flow`);
        NaN where there is no estimate.
    boundaries : bool (H, W); uint8 0/1 on the device
        Pixels with an estimate whose score is below ``boundary_score``: the paper's evidence of
        occlusions and motion discontinuities.
    limit_share : float
        In [0, 1]: the share of the coarsest level's pixels whose estimate lies at the edge of its range
        (either component equal to +-delta, or both): motion there may exceed what the search reaches
        (:func:`reach`).
    found_share : float
        The share of the coarsest level's pixels with an estimate: the features and patch found little
        to match where it is small.
    """

    flow: ArrayLike
    score: ArrayLike
    boundaries: ArrayLike
    limit_share: float = 0.0
    found_share: float = 1.0


def _frames(frame0, frame1, machine: Machine) -> tuple[cl_array.Array, cl_array.Array, bool]:
    devices = []
    for name, frame in (("frame0", frame0), ("frame1", frame1)):
        if isinstance(frame, np.ndarray) and frame.dtype.kind == "f":
            if not np.isfinite(frame).all():
                raise InputValueError(f"{name} must not contain NaN or infinite values")
            frame = frame.astype(np.float32)
            if not np.isfinite(frame).all():
                raise InputValueError(f"{name} has values beyond float32's range")
        data, host = field(frame, name, machine, ndims=(2, 3), dtypes=_IMAGE_DTYPES)
        if data.ndim == 3 and data.shape[2] != 3:
            raise InputValueError(f"{name} must be grey (H, W) or RGB (H, W, 3), got shape {data.shape}")
        devices.append((data, host))
    (d0, host0), (d1, host1) = devices
    check_same_kind("frame0", host0, "frame1", host1)
    check_same_scale("frame0", frame0.dtype, "frame1", frame1.dtype)
    if d0.shape != d1.shape:
        raise InputValueError(f"frame0 and frame1 must have the same shape, got {d0.shape} and {d1.shape}")
    return d0, d1, host0


def _most_levels(shape: tuple[int, ...], patch: int, delta: int) -> int:
    """The most pyramid levels this image allows: the coarsest level must still hold the patch and a
    displacement of delta (its sides are halved, rounding up, at each level)."""
    sides, levels = shape[:2], 1
    while min(-(-n // 2) for n in sides) >= max(patch, delta + 1) and max(sides) > 1:
        sides, levels = tuple(-(-n // 2) for n in sides), levels + 1
    return levels


def pyramid_levels(shape: tuple[int, ...], *, patch: int = PATCH, delta: int = DELTA, coarsest: int = COARSEST_SIDE) -> int:
    """The pyramid levels that let :func:`flow` find its own displacement range on an image this size.

    The image is halved (rounding up) while its smaller side stays at least ``coarsest`` pixels and the
    coarsest level still holds the patch and a displacement of delta. The search then
    reaches about ``delta (2**levels - 1)`` pixels (:func:`reach`): a fixed share of the image's size,
    whatever its resolution.

    Parameters
    ----------
    shape : tuple of int
        The image's (H, W[, C]).
    patch, delta : int
        As :func:`flow` takes them (the same defaults).
    coarsest : int
        The smallest side of the coarsest level, >= 1; default :data:`COARSEST_SIDE`.

    Returns
    -------
    int, >= 1
    """
    if not isinstance(shape, tuple) or len(shape) not in (2, 3):
        raise InputTypeError(f"shape must be a tuple (H, W) or (H, W, C), got {shape!r}")
    sides = [check_int(n, "shape", minimum=1) for n in shape[:2]]
    patch = check_int(patch, "patch", minimum=1)
    delta = check_int(delta, "delta", minimum=1)
    coarsest = check_int(coarsest, "coarsest", minimum=1)
    most = _most_levels(tuple(sides), patch, delta)
    levels = 1
    while levels < most and min(-(-n // 2 ** levels) for n in sides) >= coarsest:
        levels += 1
    return levels


def reach(delta: int, levels: int) -> int:
    """The largest displacement, in pixels along each axis, that :func:`flow` can find with these
    settings: delta at the coarsest level, doubled at each finer one, plus delta at each."""
    return check_int(delta, "delta", minimum=1) * (2 ** check_int(levels, "levels", minimum=1, maximum=64) - 1)


def _check(shape: tuple[int, ...], delta, patch, features, sigma, levels=1) -> tuple[int, int, float, int]:
    """(delta, patch radius, sigma, levels) after checking them against the image and the coarsest level."""
    delta = check_int(delta, "delta", minimum=1)
    patch = check_int(patch, "patch", minimum=1)
    levels = check_int(levels, "levels", minimum=1)
    if patch % 2 == 0:
        raise InputValueError(f"patch must be odd (a window centred on the pixel), got {patch}")
    features = check_choice(features, "features", FEATURES)
    sigma = check_real(DEFAULT_SIGMA[features] if sigma is None else sigma, "sigma", above=0)
    side = min(shape[:2])
    if patch > side:
        raise InputValueError(f"patch ({patch}) is larger than the image ({shape[1]} x {shape[0]}, width x height)")
    if delta >= side:
        raise InputValueError(f"delta ({delta}) must be smaller than the image ({shape[1]} x {shape[0]}, width x "
                              "height)")
    if _COMPARE[features] and patch**2 * (2 * delta**2 + 1) >= 2**31:
        raise InputValueError(f"patch ({patch}) and delta ({delta}) are too large for the integer keys of binary "
                              f"votes: patch**2 * (2 delta**2 + 1) must stay below 2**31")
    most = _most_levels(shape, patch, delta)
    if levels > most:
        raise InputValueError(f"levels must be at most {most} for a {shape[0]} x {shape[1]} image with patch "
                              f"{patch} and delta {delta} (each level halves the image, and the coarsest must "
                              f"still hold the patch and delta + 1 pixels), got {levels}")
    return delta, patch // 2, sigma, levels


def _require_memory(machine: Machine, shape: tuple[int, ...], planes: int, largest: int, what: str) -> None:
    """Refuse a search whose vote planes (``planes`` alive at once, ``largest`` in one buffer) the device
    cannot hold."""
    height, width = shape[:2]
    plane = height * width * 4
    per_pixel = 96  # frames, pyramid, feature maps, moments and their sums, winners, outputs
    machine.require_memory(what, planes * plane + per_pixel * height * width, largest * plane)


def _features(machine: Machine, image: cl_array.Array, features: str, sigma: float) -> cl_array.Array:
    """The feature map on the device: float32 brightness or LoG (also for its sign), uint8 edges."""
    if features == "brightness":
        return _filters.gaussian(image, sigma=sigma, method="exact", machine=machine)
    if features == "edges":
        low, high = EDGE_QUANTILES
        return _edges.canny(image, sigma=sigma, low_threshold=low, high_threshold=high, use_quantiles=True,
                            machine=machine)
    return _filters.laplacian_of_gaussian(image, sigma=sigma, machine=machine)


def _defines(feature_map: cl_array.Array, features: str) -> dict:
    compare = _COMPARE[features]
    return {"F_T": "uchar" if feature_map.dtype == np.uint8 else "float",
            "V_T": "float" if compare == 0 else "int", "COMPARE": compare}


def _vote_dtype(defines: dict) -> type:
    return np.float32 if defines["V_T"] == "float" else np.int32


def _launch(machine: Machine, kernel, size: tuple[int, int], *args) -> None:
    """A launch over (work-items along a row, rows), in the Machine's work-groups for row kernels."""
    machine.launch(kernel, size, *args, local_size=machine.row_local_size(size))


def _groups(machine: Machine, width: int) -> list[tuple[int, int, int]]:
    """(VEC, first column, work-items) per launch: on CPUs 16 pixels per work-item (SIMD lanes see
    contiguous loads) and the remainder one by one, as the column scans do; on GPUs one pixel each."""
    return scan.column_groups(width) if machine.is_cpu else [(1, 0, width)]


def _costs(machine: Machine, f0, f1, delta: int, first: int, planes: int, defines: dict) -> cl_array.Array:
    """The comparison planes of displacements first .. first + planes - 1."""
    height, width = f0.shape
    out = machine.empty((planes, height, width), _vote_dtype(defines))
    for vec, col0, count in _groups(machine, width):
        _launch(machine, machine.kernel("motion", "cost", VEC=vec, **defines), (count, height), f0, f1, out,
                np.int64(width), np.int64(height), np.int64(col0), np.int64(count), np.int32(delta),
                np.int32(first), np.int32(planes))
    return out


def _table(machine: Machine, f0, f1, delta: int, radius: int, defines: dict) -> cl_array.Array:
    n = 2 * delta + 1
    return scan.box_sum(_costs(machine, f0, f1, delta, 0, n * n, defines), radius, machine=machine)


def _moments(machine: Machine, f0, f1, radius: int, defines: dict) -> cl_array.Array:
    """Box sums that normalise the votes: of f and f**2 in both frames (squared differences), of the
    edge maps (XOR); the sign comparison needs none and gets a placeholder."""
    if defines["COMPARE"] == _COMPARE["sign_log"]:
        return f0
    height, width = f0.shape
    planes = 4 if defines["COMPARE"] == _COMPARE["brightness"] else 2
    raw = machine.empty((planes, height, width), np.float32)
    _launch(machine, machine.kernel("motion", "moments", **defines), (width, height), f0, f1, raw,
            np.int64(width), np.int64(height))
    return scan.box_sum(raw, radius, machine=machine)


def _rows(delta: int) -> list[int]:
    """Rows of displacements (vy + delta) in the order they are visited: out from vy = 0, as row_of in
    kernels/motion.cl, so a small motion's winner is found first and rarely moves afterwards."""
    return [delta + (s + 1) // 2 * (-1 if s % 2 else 1) for s in range(2 * delta + 1)]


def _winner(machine: Machine, f0, f1, moments, delta: int, radius: int, penalty: float, method: str,
            subpixel: bool, defines: dict):
    """Per pixel: the winning key, its displacement index and the keys of its four neighbours."""
    height, width = f0.shape
    n = 2 * delta + 1
    best = machine.empty((height, width), _vote_dtype(defines))
    index = machine.empty((height, width), np.int32)
    neigh = machine.empty((4, height, width), np.float32)
    state = (best, index, neigh, np.int64(width), np.int64(height))
    params = (np.int32(delta), np.int32(radius), np.float32(penalty), np.int32(bool(subpixel)))
    groups = _groups(machine, width)
    if method == "table":
        table = _table(machine, f0, f1, delta, radius, defines)
        for vec, col0, count in groups:
            _launch(machine, machine.kernel("motion", "winner_table", VEC=vec, **defines), (count, height), table,
                    moments, *state, np.int64(col0), np.int64(count), *params)
        return best, index, neigh
    rows = _rows(delta)
    visited: dict[int, cl_array.Array] = {}
    for step, row in enumerate(rows):
        votes_row = scan.box_sum(_costs(machine, f0, f1, delta, row * n, n, defines), radius, machine=machine)
        inward = visited.get(row + 1 if row < delta else row - 1, votes_row)
        for vec, col0, count in groups:
            _launch(machine, machine.kernel("motion", "vote_running", VEC=vec, **defines), (count, height),
                    votes_row, inward, moments, *state, np.int64(col0), np.int64(count), *params, np.int32(step))
        # A row's inward row was visited one or two steps before it: keep the last two.
        visited = {r: v for r, v in visited.items() if r in rows[max(step - 1, 0):step]}
        visited[row] = votes_row
    return best, index, neigh


def _level(machine: Machine, f0, f1, pred, delta: int, radius: int, features: str, penalty: float,
           method: str, subpixel: bool, threshold: float):
    """Flow, score and boundaries of one pyramid level from its feature maps."""
    height, width = f0.shape
    defines = _defines(f0, features)
    moments = _moments(machine, f0, f1, radius, defines)
    best, index, neigh = _winner(machine, f0, f1, moments, delta, radius, penalty, method, subpixel, defines)
    flow_out = machine.empty((height, width, 2), np.float32)
    score = machine.empty((height, width), np.float32)
    boundaries = machine.empty((height, width), np.uint8)
    _launch(machine, machine.kernel("motion", "finish", **defines),
            (width, height), best, index, neigh, pred if pred is not None else neigh, moments, f0, flow_out, score,
            boundaries, np.int64(width), np.int64(height), np.int32(delta), np.int32(radius), np.float32(penalty),
            np.int32(bool(subpixel)), np.float32(threshold), np.int32(pred is not None))
    return flow_out, score, boundaries


def _pyramid(machine: Machine, frame: cl_array.Array, levels: int) -> list[cl_array.Array]:
    """The frame and its successive halvings (Gaussian of PYRAMID_SIGMA, then every other pixel)."""
    images = [frame]
    for _ in range(levels - 1):
        smooth = _filters.gaussian(images[-1], sigma=PYRAMID_SIGMA, method="exact", machine=machine)
        height, width = smooth.shape
        half = machine.empty((-(-height // 2), -(-width // 2)), np.float32)
        _launch(machine, machine.kernel("motion", "decimate"), (half.shape[1], half.shape[0]), smooth, half,
                np.int64(width), np.int64(height), np.int64(half.shape[1]), np.int64(half.shape[0]))
        images.append(half)
    return images


def _patch_mean(machine: Machine, coarse: cl_array.Array, radius: int) -> cl_array.Array:
    """The coarse flow averaged over each patch: the flow the patch's vote stands for, without the
    pixel-to-pixel jitter of the winners, which the warp would pass on to the finer level's flow."""
    height, width = coarse.shape[:2]
    planes = machine.empty((3, height, width), np.float32)
    _launch(machine, machine.kernel("motion", "flow_planes"), (width, height), coarse, planes, np.int64(width),
            np.int64(height))
    sums = scan.box_sum(planes, radius, machine=machine)
    mean = machine.empty(coarse.shape, np.float32)
    _launch(machine, machine.kernel("motion", "mean_flow"), (width, height), sums, mean, np.int64(width),
            np.int64(height))
    return mean


def _warp(machine: Machine, f1: cl_array.Array, coarse: cl_array.Array, features: str, scale: int = 2):
    """Frame 1's features warped by the flow ``coarse`` interpolated to their size and multiplied by ``scale``
    (2: the level below's; 1: a flow of their own size), and that prediction."""
    height, width = f1.shape
    warped = machine.empty(f1.shape, f1.dtype)
    pred = machine.empty((height, width, 2), np.float32)
    _launch(machine, machine.kernel("motion", "warp", **_defines(f1, features)), (width, height), f1, coarse,
            warped, pred, np.int64(width), np.int64(height), np.int64(coarse.shape[1]), np.int64(coarse.shape[0]),
            np.float32(1 / scale), np.float32(scale))
    return warped, pred


def _prediction(prediction: ArrayLike, shape: tuple[int, ...], machine: Machine) -> cl_array.Array:
    """The given prediction on the device, float32 (H, W, 2), checked against the frames' shape."""
    if isinstance(prediction, np.ndarray) and prediction.dtype.kind == "f":
        prediction = prediction.astype(np.float32)
    data, _ = field(prediction, "prediction", machine, ndims=(3,), dtypes=(np.float32,))
    if data.shape != (*shape[:2], 2):
        raise InputValueError(f"prediction must be a flow of the frames' size, ({shape[0]}, {shape[1]}, 2), "
                              f"got shape {data.shape}")
    return data


def _keep_better(machine: Machine, found: tuple, other: tuple, prediction: cl_array.Array) -> None:
    """Where the prediction holds, ``other``'s estimates replace ``found``'s (flow, score, boundaries) that
    they outscore."""
    size = found[1].size
    machine.launch(machine.kernel("motion", "keep_better"), (size,), *found, *other, prediction, np.int64(size))


def flow(frame0: ArrayLike, frame1: ArrayLike, *, delta: int = DELTA, patch: int = PATCH, features: Features = "brightness",
         subpixel: bool = True, levels: int = 1, sigma: float | None = None,
         speed_penalty: float = SPEED_PENALTY, method: Method = "running", boundary_score: float | None = None,
         prediction: ArrayLike | None = None, machine: Machine | None = None) -> FlowResult:
    """Optical flow by patchwise comparison over the displacements (-delta..delta)^2.

    Parameters
    ----------
    frame0, frame1 : ndarray or pyopencl.array.Array, (H, W) grey or (H, W, 3) RGB
        The frames at t and t + 1, same shape; uint8, uint16 or float (float64 is converted to float32;
        device arrays must be uint8, uint16 or float32). RGB becomes grey with
        :data:`vmcl.early.filters.GREY_WEIGHTS` (ITU-R BT.709: 0.2125 R + 0.7154 G + 0.0721 B).
    delta : int
        The displacement range, >= 1 and smaller than the image: (2 delta + 1)^2 displacements; default
        :data:`DELTA`.
    patch : int
        Width of the square patch over which comparisons are summed; odd, 1 .. min(H, W); default
        :data:`PATCH`.
    features : {"brightness", "log", "sign_log", "edges"}
        What is compared: the Gaussian-smoothed brightness, or its Laplacian (squared differences);
        the sign of the Laplacian of a Gaussian, or Canny's edges (:func:`vmcl.early.edges.canny`, with
        the thresholds :data:`EDGE_QUANTILES`) (exclusive or of binary maps).
    subpixel : bool
        Refine each displacement by the vertex of the parabola through the winning vote and its two
        neighbours, along x and along y (no refinement along an axis where the winner lies on the
        border of the range, or the votes are collinear; at most half a pixel).
    levels : int
        Coarse-to-fine pyramid levels. Level k + 1 is level k smoothed by a Gaussian of
        :data:`PYRAMID_SIGMA` and halved; the flow found at a level, averaged over the patch,
        doubled and interpolated bilinearly (0 where it has no estimate), predicts the flow one level
        finer, where the search covers delta around the prediction, so motions up to about
        delta (2**levels - 1) are found. 1: no pyramid.
    sigma : float, optional
        Gaussian width of the feature maps in pixels; default :data:`DEFAULT_SIGMA` per feature.
    speed_penalty : float
        A prior for slow motion, in [0, 1], for the squared-difference features: every vote gains
        ``speed_penalty * C0 * (vx**2 + vy**2)`` (C0 below). It settles the aperture problem, where a
        patch of one orientation has votes along it that differ only by rounding, on the slowest
        candidate; 0 is the paper's plain minimum. At most 1, so that ``speed_penalty * C0`` stays within
        float32's range wherever C0 does (at 1 a one-pixel motion already costs the patch's whole
        contrast, half the vote of an unrelated patch of like contrast). Binary votes are exact integers and take none.
    method : {"running", "table"}
        "running" (default, the paper's simplification): displacements are visited a row (fixed vy) at
        a time, out from vy = 0, and each pixel keeps its best so far, so at most three rows of votes
        exist at once.
        "table" (faithful): all (2 delta + 1)^2 vote planes are built, then the winner is chosen.
        Identical results.
    boundary_score : float, optional
        Pixels with an estimate and a normalised score below this are marked in ``boundaries``;
        default :data:`BOUNDARY_SCORE` per feature.
    prediction : (H, W, 2) float array, optional
        A flow expected from elsewhere (in a sequence, the previous frame's flow carried along itself;
        NaN where there is none). The finest level is then searched a second time, over delta around the
        prediction, and each pixel where the prediction holds keeps whichever of the two estimates scores
        better: a motion that the coarse levels lost (a small, fast object whose texture they blur away)
        is found where the past points. NumPy or device array.
    machine : vmcl.Machine, optional

    Returns
    -------
    FlowResult
        Its ``flow``, ``score`` and ``boundaries``: NumPy arrays for NumPy input, device arrays for device
        input; and the coarsest level's ``limit_share`` and ``found_share``. Read them by name (a dataclass,
        not a tuple).

    Notes
    -----
    The winner minimises the vote (squared differences: plus the speed penalty). Ties go to the first
    displacement visited: rows of fixed vy in the order 0, -1, +1, -2, +2, ..., vx ascending within a
    row; binary votes, exact integers, first prefer the smaller ``vx**2 + vy**2``. (Squared differences
    tie exactly only in degenerate cases: a flat patch, which has no estimate; equal raw votes differ by
    the penalty.) Results do not depend on the work-group size. Frame 1 is read with clamped coordinates (the edge pixel
    repeats) and patches that reach over the border sum fewer pixels.

    Normalised scores, 1 for a perfect match:

    - squared differences: ``1 - vote / (C0 + C1)``, C the patch's contrast ``sum (f - mean)**2`` in
      frame 0 around (x, y) and in frame 1 around (x + vx, y + vy); about 0 for unrelated patches, and
      below where the brightness differs. No estimate (NaN) where frame 0's patch is flat (C0 below
      1e-5 of ``sum f**2``).
    - sign of the LoG: ``1 - 2 disagreements / n``, the correlation of the signs over the patch's n
      pixels; by the arcsine law, ``sin(pi / 2 * score)`` estimates the correlation of the LoG fields.
    - edges: ``1 - XOR / (n0 + n1)`` = 2 common / (n0 + n1) with n0, n1 the edge pixels of the two
      patches (Dice's coefficient). Estimates only at frame 0's edge pixels (the paper's sparse flow).

    With levels > 1, frame 1's features are warped by the coarse level's prediction (bilinearly; edges:
    nearest pixel) before the search, which is then for the residual around it; a given ``prediction`` is
    used the same way, as it is (not averaged). Averaging the coarse flow over the patch first matters: the winners' pixel-to-pixel jitter would otherwise pass into the warp and
    the finer flow (on Middlebury it raised the error markedly away from motion boundaries). Device
    frames are not checked for NaN (that would need a read back).

    References
    ----------
    H. H. Bulthoff, J. J. Little and T. Poggio, "A parallel algorithm for real-time computation of
    optical flow", Nature 337:549-553, 1989.
    J. J. Little, H. H. Bulthoff and T. Poggio, "Parallel optical flow using local voting", Proc. ICCV,
    1988.

    Examples
    --------
    >>> import numpy as np
    >>> from vmcl.early.motion import flow
    >>> rng = np.random.default_rng(0)
    >>> frame0 = rng.random((48, 64), np.float32)
    >>> frame1 = np.roll(frame0, (1, 2), axis=(0, 1))  # moves 2 right, 1 down
    >>> result = flow(frame0, frame1, delta=3, patch=7, subpixel=False)
    >>> result.flow[24, 32].tolist()
    [2.0, 1.0]
    """
    machine = machine_for(machine)
    d0, d1, host = _frames(frame0, frame1, machine)
    delta, radius, sigma, levels = _check(d0.shape, delta, patch, features, sigma, levels)
    method = check_choice(method, "method", METHODS)
    subpixel = check_bool(subpixel, "subpixel")
    boundary_score = check_real(BOUNDARY_SCORE[features] if boundary_score is None else boundary_score,
                                "boundary_score")
    # The device computes speed_penalty * C0 in float32: above 1 it overflows where C0 is large (an infinity
    # times a zero |v|**2 is NaN, so no displacement won and the flow came out at (-delta - 1, -delta)).
    speed_penalty = check_real(speed_penalty, "speed_penalty", minimum=0, maximum=1)
    predicted = None if prediction is None else _prediction(prediction, d0.shape, machine)
    n = 2 * delta + 1
    # The table and its box sum's two passes; running: three rows of votes kept, one being summed.
    table = method == "table"
    _require_memory(machine, d0.shape, 3 * n * n if table else 6 * n, n * n if table else n,
                    f"motion.flow over {n} x {n} displacements (method {method!r})")
    pyramids = [_pyramid(machine, d, levels) for d in (d0, d1)]
    coarse = None
    for image0, image1 in zip(reversed(pyramids[0]), reversed(pyramids[1])):
        f0 = _features(machine, image0, features, sigma)
        f1 = unwarped = _features(machine, image1, features, sigma)
        pred = None
        if coarse is not None:
            f1, pred = _warp(machine, f1, _patch_mean(machine, coarse, radius), features)
        flow_out, score, boundaries = _level(machine, f0, f1, pred, delta, radius, features, speed_penalty,
                                             method, subpixel, boundary_score)
        if coarse is None:  # the coarsest level: its range bounds the whole search's
            # Counted on the host: the coarsest level is small, and a device count would build
            # pyopencl's own elementwise programs on a first run's clock.
            coarsest = np.empty(flow_out.shape, flow_out.dtype)
            coarsest_read = machine.read_into(coarsest, flow_out)
        coarse = flow_out
    if predicted is not None:  # the finest level again, around the given prediction
        f1, pred = _warp(machine, unwarped, predicted, features, scale=1)
        other = _level(machine, f0, f1, pred, delta, radius, features, speed_penalty, method, subpixel,
                       boundary_score)
        _keep_better(machine, (flow_out, score, boundaries), other, predicted)
    # Read back once the finer levels are enqueued, so the queue does not drain between levels.
    if coarsest_read is not None:
        coarsest_read.wait()
    # Pixels, not components: one with both components at the limit counts once.
    limit_share = float(np.any(np.abs(coarsest) >= delta - 1e-3, axis=-1).mean())
    found_share = float(np.isfinite(coarsest).all(axis=-1).mean())
    if host:
        return FlowResult(flow_out.get(), score.get(), boundaries.get().view(np.bool_), limit_share, found_share)
    return FlowResult(flow_out, score, boundaries, limit_share, found_share)


def votes(frame0: ArrayLike, frame1: ArrayLike, *, delta: int = DELTA, patch: int = PATCH, features: Features = "brightness",
          sigma: float | None = None, machine: Machine | None = None) -> ArrayLike:
    """The full table of votes: the patch sum of the comparisons at every displacement.

    Parameters
    ----------
    frame0, frame1, delta, patch, features, sigma, machine
        As for :func:`flow`.

    Returns
    -------
    ((2 delta + 1)**2, H, W) array: float32 sums of squared differences (brightness, log) or int32
    counts of disagreeing pixels (sign_log, edges). Plane ``(vy + delta) * (2 delta + 1) + vx + delta``
    holds displacement (vx, vy). NumPy for NumPy input, a device array for device input.

    Notes
    -----
    This is the table the faithful variant of :func:`flow` builds; the winner per pixel is the
    smallest vote (ties as in :func:`flow`).

    References
    ----------
    H. H. Bulthoff, J. J. Little and T. Poggio, "A parallel algorithm for real-time computation of
    optical flow", Nature 337:549-553, 1989.
    """
    machine = machine_for(machine)
    d0, d1, host = _frames(frame0, frame1, machine)
    delta, radius, sigma, _ = _check(d0.shape, delta, patch, features, sigma)
    n = 2 * delta + 1
    _require_memory(machine, d0.shape, 3 * n * n, n * n, f"motion.votes over {n} x {n} displacements")
    f0 = _features(machine, d0, features, sigma)
    f1 = _features(machine, d1, features, sigma)
    table = _table(machine, f0, f1, delta, radius, _defines(f0, features))
    return table.get() if host else table
