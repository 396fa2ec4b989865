"""Verification: each candidate pose tested against the image's edges, and refined.

Seed section "Recognition": the third stage verifies each candidate by "its pose tested against the
image". A posed model point is supported where an image edge lies within ``tolerance`` pixels of it
running the same way (within ``angle``): an oriented chamfer test, read from the image's exact distance
transform (kernels/verification.cl: Felzenszwalb and Huttenlocher's two passes, one work-item per column,
then per row), one work-item per (candidate, point). The pose is refined between tests by least squares
on the point-to-edge distances of the supported points (each edge pixel's normal from its tangent), the
tolerance narrowing from ``start`` to ``tolerance``: a similarity, an affine map or a homography, each
linear in its parameters. A candidate's score is the fraction of its points (those that land in the
image) that are supported.

:func:`support_numpy` and :func:`distance_transform_numpy` are the same steps in NumPy and SciPy, the
references the kernels are tested and timed against.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal, NamedTuple

import numpy as np

from vmcl.cm.core import check_choice, check_int, check_real, check_unmasked, machine_for
from vmcl.errors import InputTypeError, InputValueError
from vmcl.machine import Machine
from vmcl.recognize.arguments import angles, edge_map, real_map
from vmcl.recognize.arguments import points as point_array

__all__ = ["TRANSFORMS", "NearestEdge", "Support", "Verified", "carry", "distance_transform",
           "distance_transform_numpy", "refine", "support", "support_numpy"]

Transform = Literal["similarity", "affine", "homography"]
TRANSFORMS: tuple[Transform, ...] = ("similarity", "affine", "homography")
"""The pose models :func:`refine` fits."""

_PARAMETERS = {"similarity": 4, "affine": 6, "homography": 8}


class NearestEdge(NamedTuple):
    """Every pixel's nearest edge pixel: its flat address (-1 where there is none) and the distance."""

    nearest: np.ndarray
    distance: np.ndarray


def _distance(nearest: np.ndarray, width: int) -> np.ndarray:
    h, w = nearest.shape
    ys, xs = np.mgrid[0:h, 0:w]
    d = np.hypot(xs - nearest % width, ys - nearest // width).astype(np.float32)
    return np.where(nearest >= 0, d, np.float32(np.inf))


def distance_transform(edges: Any, *, machine: Machine | None = None) -> NearestEdge:
    """The exact Euclidean distance transform of an edge map, with each pixel's nearest edge pixel.

    Parameters
    ----------
    edges : bool or uint8 (H, W) array
    machine : vmcl.Machine, optional

    Returns
    -------
    NearestEdge
        ``nearest``: int32 (H, W) flat address y * W + x of the nearest edge pixel (ties to either);
        ``distance``: float32 (H, W), inf where the image has no edge pixel.
    """
    machine = machine_for(machine)
    edges = edge_map(edges, "edges")
    h, w = edges.shape
    mask = machine.to_device(np.ascontiguousarray(edges.astype(np.uint8)))
    rows, nearest = machine.empty((h, w), np.int32), machine.empty((h, w), np.int32)
    hull, bounds = machine.empty((h, w), np.int32), machine.empty((h, w + 1), np.float32)
    machine.launch(machine.kernel("verification", "column_nearest"), (w,), mask, rows, np.int32(w), np.int32(h))
    machine.launch(machine.kernel("verification", "row_envelope"), (h,), rows, nearest, hull, bounds, np.int32(w),
                   np.int32(h))
    found = nearest.get()
    return NearestEdge(found, _distance(found, w))


def distance_transform_numpy(edges: Any) -> NearestEdge:
    """:func:`distance_transform` by SciPy (``scipy.ndimage.distance_transform_edt``)."""
    from scipy import ndimage

    edges = edge_map(edges, "edges")
    h, w = edges.shape
    if not edges.any():
        return NearestEdge(np.full((h, w), -1, np.int32), np.full((h, w), np.inf, np.float32))
    _, (ys, xs) = ndimage.distance_transform_edt(~edges.astype(bool), return_indices=True)
    nearest = (ys * w + xs).astype(np.int32)
    return NearestEdge(nearest, _distance(nearest, w))


class Support(NamedTuple):
    """Per (candidate, point): the nearest edge pixel (x, y), the distance to it, the angle between the
    tangents (radians, in [0, pi/2]), and whether the point landed in the image."""

    edge: np.ndarray
    distance: np.ndarray
    angle: np.ndarray
    inside: np.ndarray


def _homographies(transforms: Any) -> np.ndarray:
    if not isinstance(transforms, np.ndarray) or transforms.dtype.kind not in "iuf":
        raise InputTypeError("transforms must be a real NumPy array")
    check_unmasked(transforms, "transforms")
    t = transforms.astype(np.float64)
    if t.ndim != 3 or t.shape[1:] not in ((2, 3), (3, 3)):
        raise InputValueError(f"transforms must be (C, 2, 3) affine or (C, 3, 3) homography arrays, got {t.shape}")
    if t.shape[1] == 2:
        t = np.concatenate([t, np.broadcast_to(np.array([0.0, 0.0, 1.0]), (len(t), 1, 3))], axis=1)
    if not np.isfinite(t).all() or np.abs(t).max(initial=0) > 1e9:
        raise InputValueError("transforms must be finite, within 1e9")
    return t


def _items(point_ranges: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    counts = point_ranges[:, 1] - point_ranges[:, 0]
    candidate = np.repeat(np.arange(len(point_ranges)), counts)
    first = np.repeat(point_ranges[:, 0] - np.concatenate([[0], np.cumsum(counts)[:-1]]), counts)
    return first + np.arange(counts.sum()), candidate


def _check_support(nearest: Any, tangent_map: Any, points_: Any, tangents: Any, point_ranges: Any,
                   transforms: Any) -> tuple[np.ndarray, ...]:
    if not isinstance(nearest, np.ndarray) or nearest.dtype != np.int32 or nearest.ndim != 2 or nearest.size == 0:
        raise InputValueError("nearest must be an int32 (H, W) array (distance_transform's nearest)")
    for name, value in (("nearest", nearest), ("point_ranges", point_ranges)):
        check_unmasked(value, name)
    if nearest.min() < -1 or nearest.max() >= nearest.size:
        raise InputValueError(f"nearest must hold flat addresses of its pixels (0 to {nearest.size - 1}) or -1")
    tangent_map = real_map(tangent_map, "tangent_map", nearest.shape, "nearest", unknown=True).astype(np.float32)
    points_ = point_array(points_, "points")
    tangents = angles(tangents, "tangents", len(points_), "points", unknown=True)
    homographies = _homographies(transforms)
    if not isinstance(point_ranges, np.ndarray) or point_ranges.dtype.kind not in "iu":
        raise InputTypeError("point_ranges must be an integer NumPy array")
    ranges = point_ranges.astype(np.int64)
    if ranges.shape != (len(homographies), 2):
        raise InputValueError(f"point_ranges must hold one (start, stop) per transform, shape ({len(homographies)}, 2), "
                              f"got {ranges.shape}")
    if len(ranges) and (ranges.min() < 0 or ranges.max() > len(points_) or np.any(ranges[:, 1] < ranges[:, 0])):
        raise InputValueError(f"point_ranges must be (start, stop) slices of the {len(points_)} points")
    if int((ranges[:, 1] - ranges[:, 0]).sum()) >= 2**31:
        raise InputValueError("point_ranges must cover fewer than 2**31 points in all")
    return np.ascontiguousarray(nearest), tangent_map, points_, tangents, ranges, homographies


def support(nearest: Any, tangent_map: Any, points: Any, tangents: Any, point_ranges: Any, transforms: Any, *,
            machine: Machine | None = None) -> Support:
    """Each posed model point's nearest edge, distance and tangent angle, on the device.

    Parameters
    ----------
    nearest : int32 (H, W)
        :func:`distance_transform`'s ``nearest``.
    tangent_map : float (H, W)
        The edges' tangents (radians, NaN where unknown).
    points : float (N, 2)
        Model points, every candidate's (its view's) one after another.
    tangents : float (N,)
        Their tangents (radians; NaN where unknown).
    point_ranges : int (C, 2)
        Candidate c's points are ``points[start:stop]``.
    transforms : float (C, 2, 3) or (C, 3, 3)
        Each candidate's pose (model to image).
    machine : vmcl.Machine, optional

    Returns
    -------
    Support
        Arrays over the candidates' points, candidate after candidate.
    """
    machine = machine_for(machine)
    nearest, tangent_map, points, tangents, ranges, homographies = _check_support(
        nearest, tangent_map, points, tangents, point_ranges, transforms)
    return _SupportTest(machine, nearest, tangent_map, points, tangents, ranges)(homographies)


class _SupportTest:
    """The support kernel's inputs on the device, uploaded once for the poses a refinement tries."""

    def __init__(self, machine: Machine, nearest: np.ndarray, tangent_map: np.ndarray, points: np.ndarray,
                 tangents: np.ndarray, ranges: np.ndarray) -> None:
        self.machine = machine
        point_of_item, candidate_of_item = _items(ranges)
        self.items = len(point_of_item)
        self.height, self.width = nearest.shape
        if self.items:
            self.inputs = tuple(machine.to_device(a) for a in (
                nearest, tangent_map, points.astype(np.float32), tangents.astype(np.float32),
                point_of_item.astype(np.int32), candidate_of_item.astype(np.int32)))

    def __call__(self, homographies: np.ndarray) -> Support:
        if self.items == 0:
            return Support(np.zeros((0, 2)), np.zeros(0), np.zeros(0), np.zeros(0, bool))
        m = self.machine
        found, status = m.empty((self.items, 4), np.float32), m.empty(self.items, np.uint8)
        m.launch(m.kernel("verification", "support"), (self.items,), *self.inputs,
                 m.to_device(homographies.reshape(-1, 9).astype(np.float32)), found, status, np.int32(self.items),
                 np.int32(self.width), np.int32(self.height))
        f = found.get().astype(np.float64)
        return Support(f[:, :2], f[:, 2], f[:, 3], status.get() == 0)


def support_numpy(nearest: Any, tangent_map: Any, points: Any, tangents: Any, point_ranges: Any,
                  transforms: Any) -> Support:
    """:func:`support` in NumPy on the host: the reference the kernel is tested and timed against."""
    nearest, tangent_map, points, tangents, ranges, homographies = _check_support(
        nearest, tangent_map, points, tangents, point_ranges, transforms)
    point_of_item, candidate_of_item = _items(ranges)
    h, w = nearest.shape
    m = homographies[candidate_of_item]
    p = points[point_of_item]
    denominator = m[:, 2, 0] * p[:, 0] + m[:, 2, 1] * p[:, 1] + m[:, 2, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        x = (m[:, 0, 0] * p[:, 0] + m[:, 0, 1] * p[:, 1] + m[:, 0, 2]) / denominator
        y = (m[:, 1, 0] * p[:, 0] + m[:, 1, 1] * p[:, 1] + m[:, 1, 2]) / denominator
    cx, cy = np.floor(x + 0.5), np.floor(y + 0.5)
    inside = (denominator > 0) & (cx >= 0) & (cy >= 0) & (cx < w) & (cy < h)
    q = np.full(len(p), -1, np.int64)
    q[inside] = nearest[cy[inside].astype(np.int64), cx[inside].astype(np.int64)]
    inside &= q >= 0
    qx, qy = (q % w).astype(np.float64), (q // w).astype(np.float64)
    distance = np.where(inside, np.hypot(x - qx, y - qy), np.inf)
    t = tangents[point_of_item]
    e = tangent_map.ravel()[np.maximum(q, 0)].astype(np.float64)
    dx, dy = np.cos(t), np.sin(t)
    with np.errstate(divide="ignore", invalid="ignore"):
        jx = ((m[:, 0, 0] - x * m[:, 2, 0]) * dx + (m[:, 0, 1] - x * m[:, 2, 1]) * dy) / denominator
        jy = ((m[:, 1, 0] - y * m[:, 2, 0]) * dx + (m[:, 1, 1] - y * m[:, 2, 1]) * dy) / denominator
    a = np.mod(np.arctan2(jy, jx) - e, math.pi)
    angle = np.where(np.isfinite(t) & np.isfinite(e) & inside, np.minimum(a, math.pi - a), 0.0)
    edge = np.where(inside[:, None], np.stack([qx, qy], axis=1), 0.0)
    return Support(edge, distance, angle, inside)


@dataclass(frozen=True)
class Verified:
    """What :func:`refine` returns, per candidate.

    Attributes
    ----------
    transforms : float64 (C, 3, 3)
        The refined poses (homographies; the last row (0, 0, 1) for similarities and affine maps).
    score : float64 (C,)
        The fraction of the candidate's points inside the image that are supported.
    supported : int64 (C,)
        How many points are supported.
    inside : int64 (C,)
        How many points land in the image.
    support : Support
        The final test, point by point.
    """

    transforms: np.ndarray
    score: np.ndarray
    supported: np.ndarray
    inside: np.ndarray
    support: Support


def _solve(kind: str, p: np.ndarray, q: np.ndarray, normal: np.ndarray, previous: np.ndarray) -> np.ndarray:
    """The pose minimising the squared point-to-line distances n . (T p - q), damped towards ``previous``."""
    x, y = p[:, 0], p[:, 1]
    nx, ny = normal[:, 0], normal[:, 1]
    target = nx * q[:, 0] + ny * q[:, 1]
    if kind == "similarity":
        rows = np.stack([nx * x + ny * y, ny * x - nx * y, nx, ny], axis=1)
        old = np.array([previous[0, 0], previous[1, 0], previous[0, 2], previous[1, 2]])
    elif kind == "affine":
        rows = np.stack([nx * x, nx * y, nx, ny * x, ny * y, ny], axis=1)
        old = previous[:2].ravel()
    else:
        rows = np.stack([nx * x, nx * y, nx, ny * x, ny * y, ny, -target * x, -target * y], axis=1)
        old = (previous / previous[2, 2]).ravel()[:8]
    # Columns scaled to unit size, a little damping: parameters the points do not pin down stay put.
    scale = np.sqrt((rows ** 2).mean(axis=0)) + 1e-12
    a = rows / scale
    damping = 1e-3 * len(rows)
    lhs = a.T @ a + damping * np.eye(a.shape[1])
    rhs = a.T @ target + damping * old * scale
    try:
        params = np.linalg.solve(lhs, rhs) / scale
    except np.linalg.LinAlgError:
        return previous
    if kind == "similarity":
        a_, b_, tx, ty = params
        return np.array([[a_, -b_, tx], [b_, a_, ty], [0.0, 0.0, 1.0]])
    if kind == "affine":
        return np.vstack([params.reshape(2, 3), [0.0, 0.0, 1.0]])
    return np.append(params, 1.0).reshape(3, 3)


def refine(nearest: Any, tangent_map: Any, points: Any, tangents: Any, point_ranges: Any, transforms: Any, *,
           transform: Transform = "similarity", tolerance: float = 2.0, angle: float = 25.0, start: float = 8.0,
           iterations: int = 6, machine: Machine | None = None) -> Verified:
    """Refine and score candidate poses against an image's edges.

    Parameters
    ----------
    nearest, tangent_map, points, tangents, point_ranges, transforms
        As :func:`support` takes them.
    transform : {"similarity", "affine", "homography"}
        The pose model fitted.
    tolerance : float
        The distance (pixels) within which an edge supports a point in the final test, > 0.
    angle : float
        The largest angle (degrees) between the point's tangent and the edge's for support, in (0, 90].
    start : float
        The first refinement's tolerance (pixels), >= tolerance; it narrows to ``tolerance`` geometrically.
    iterations : int
        Refinement steps, >= 0 (0: only the test).
    machine : vmcl.Machine, optional

    Returns
    -------
    Verified
    """
    machine = machine_for(machine)
    transform = check_choice(transform, "transform", TRANSFORMS)
    tolerance = check_real(tolerance, "tolerance", above=0, maximum=1e6)
    angle_limit = math.radians(check_real(angle, "angle", above=0, maximum=90))
    start = check_real(start, "start", minimum=tolerance, maximum=1e6)
    iterations = check_int(iterations, "iterations", minimum=0, maximum=1000)
    nearest, tangent_map, points, tangents, ranges, current = _check_support(
        nearest, tangent_map, points, tangents, point_ranges, transforms)
    current = current.copy()
    counts = ranges[:, 1] - ranges[:, 0]
    bounds = np.concatenate([[0], np.cumsum(counts)])
    point_of_item, _ = _items(ranges)
    tol_schedule = start * (tolerance / start) ** (np.arange(iterations) / max(iterations - 1, 1))
    test = _SupportTest(machine, nearest, tangent_map, points, tangents, ranges)
    for tol in tol_schedule:
        found = test(current)
        ok = found.inside & (found.distance <= tol) & (found.angle <= angle_limit)
        for c in range(len(ranges)):
            s = slice(bounds[c], bounds[c + 1])
            use = np.flatnonzero(ok[s])
            if len(use) < _PARAMETERS[transform] + 2:
                continue
            p = points[point_of_item[s][use]]
            q = found.edge[s][use]
            e = tangent_map[q[:, 1].astype(np.int64), q[:, 0].astype(np.int64)].astype(np.float64)
            posed = _carried(current[c], p)
            away = posed - q
            length = np.hypot(away[:, 0], away[:, 1])
            normal = np.where(np.isfinite(e)[:, None], np.stack([-np.sin(e), np.cos(e)], axis=1),
                              away / np.maximum(length, 1e-9)[:, None])
            current[c] = _solve(transform, p, q, normal, current[c])
    found = test(current)
    ok = found.inside & (found.distance <= tolerance) & (found.angle <= angle_limit)
    candidate = np.repeat(np.arange(len(ranges)), counts)
    supported = np.bincount(candidate, weights=ok, minlength=len(ranges))
    inside = np.bincount(candidate, weights=found.inside, minlength=len(ranges))
    score = np.where(inside > 0, supported / np.maximum(inside, 1), 0.0)
    return Verified(current, score, supported.astype(np.int64), inside.astype(np.int64), found)


def carry(transform: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Points (x, y), (N, 2), carried by a 2 x 3 affine map or a 3 x 3 homography; float64 (N, 2)."""
    check_unmasked(transform, "transform")
    if isinstance(transform, np.ndarray) and transform.ndim == 2:
        transform = _homographies(transform[None])[0]
    else:
        _homographies(transform)  # refuses it by name
    return _carried(transform, point_array(points, "points"))


def _carried(transform: np.ndarray, p: np.ndarray) -> np.ndarray:
    h = p @ transform[:, :2].T + transform[:, 2]
    return h[:, :2] / h[:, 2:3]
