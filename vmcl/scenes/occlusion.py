"""Occlusion scenes: opaque polygons of distinct greys stacked in depth, with every junction known exactly.

A scene is a background grey and a list of polygons, far to near, each filled with one grey and painted
over the ones behind (the painter's algorithm). Its ground truth is analytic: the visible polygon at any
point of the plane (exact even-odd point-in-polygon tests in float64) and every junction, the points
where three or more boundary arms meet or where one boundary turns a corner, at its exact sub-pixel
position and with its type:

- ``"T"``: one polygon's edge (the stem) disappears behind a nearer polygon's straight edge (the bar);
  the ground truth of a T-junction detector, of T-junction repair, and of the grouping of the two
  visible ends of one edge across the occluder (:meth:`OcclusionScene.t_pairs`);
- ``"L"``: a visible polygon corner (two arms whose angle is not within 10 degrees of 180);
- ``"Y"``, ``"arrow"``, ``"X"``: three arms none straight (``"arrow"`` when one angle exceeds 190
  degrees) and four or more arms; opaque polygons in general position give only T and L, these come
  from polygons that share vertices.

Conventions: pixel-centre coordinates, x right (the column), y down (the row), pixel (row r, column c)
centred at (x, y) = (c, r); directions are ``atan2(dy, dx)`` in those coordinates. A point exactly on a
polygon's edge follows the usual half-open rule of the crossing test (the left and top edges of an
axis-aligned rectangle are inside, the right and bottom ones outside).

Junction classification: the visible region is sampled at 720 points on a circle of radius 1e-3 px
around every candidate point (every polygon vertex and every crossing of two edges of different
polygons); the arms are the directions where the region changes, snapped to the exact direction of the
polygon edge along them. A candidate with one region all around is hidden; one with two arms 180 +- 10
degrees apart lies on a straight boundary; one with an arm between two greys less than
:data:`MIN_CONTRAST` apart has an invisible boundary; none of these is a junction. The small radius
gives the structure of the point itself: a boundary passing a fraction of a pixel away does not add arms
to it, it makes junctions of its own, so junctions can lie closer than a pixel to each other.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from vmcl.cm.core import check_bool, check_int, check_real, real_host_array
from vmcl.errors import InputTypeError, InputValueError

__all__ = [
    "KINDS",
    "MAX_POLYGONS",
    "MIN_CONTRAST",
    "Junction",
    "OcclusionScene",
    "occlusion_scene",
    "render_occlusion",
]

KINDS = ("T", "L", "Y", "arrow", "X")
"""The junction types, :attr:`Junction.kind`."""

MAX_POLYGONS = 8
"""The most polygons :func:`render_occlusion` draws: with the background, 9 greys 0.1 apart in [0.1, 0.9]."""

MIN_CONTRAST = 0.1
"""Grey difference below which a boundary counts as invisible (its junctions are dropped)."""

_SUPERSAMPLE = 4
# Far below a pixel, so that the arms found are those of the point itself, not of a boundary passing a
# fraction of a pixel away (which makes junctions of its own); far above float64 rounding at image scales.
_PROBE_RADIUS = 1e-3
_PROBE_SAMPLES = 720
_PROBE_STEP = 2.0 * math.pi / _PROBE_SAMPLES
_STRAIGHT = math.radians(10.0)
# Intersections of float64 segments are off by ~1e-13 px at image scales; 1e-7 px is far above that and
# far below any real separation between distinct geometric features.
_ON_EDGE = 1e-7
_SAME_DIRECTION = 1e-6
_GREY_LEVELS = 7  # linspace(0.1, 0.9, 7): 0.133 apart, the most levels that keep the 0.12 spacing


@dataclass(frozen=True)
class Junction:
    """A point where region boundaries meet, with its exact position and type.

    Attributes
    ----------
    x, y : float
        Exact position in pixel-centre coordinates (x = column, y = row, y down).
    kind : str
        ``"T"``, ``"L"``, ``"Y"``, ``"arrow"`` or ``"X"`` (see :mod:`vmcl.scenes.occlusion`).
    arms : tuple of float
        Directions (radians, ``atan2(dy, dx)`` in image coordinates) of the boundary arms leaving the
        junction, ascending in [-pi, pi).
    occluder : int
        For a T: the polygon owning the region on the bar's straight side (the nearer polygon, whose
        edge is the bar); -1 for other kinds, or where that region is the background (polygons that
        merely abut).
    occluded : int
        For a T: the polygon whose edge continues as the stem and is cut off by the occluder; -1
        otherwise.
    edge : int
        For a T: the index of the occluded polygon's edge along the stem (edge k joins vertices k and
        k + 1 modulo the vertex count); -1 otherwise.
    """

    x: float
    y: float
    kind: str
    arms: tuple[float, ...]
    occluder: int = -1
    occluded: int = -1
    edge: int = -1


@dataclass(frozen=True, eq=False)
class OcclusionScene:
    """A rendered occlusion scene and its ground truth.

    Attributes
    ----------
    image : (H, W) float32
        The greys, supersampled at the polygon edges when rendered with ``antialias``, plus Gaussian
        noise (not clipped) when rendered with ``noise > 0``.
    regions : (H, W) int32
        The visible polygon at each pixel centre, -1 for the background.
    polygons : tuple of (K, 2) float64 arrays
        Vertices (x, y) of each polygon; index = depth order, 0 farthest.
    greys : tuple of float
        The grey of each polygon.
    background : float
        The background's grey.
    junctions : tuple of Junction
        Every visible junction at least ``margin`` px inside the image, sorted by (y, x). Junctions
        closer than a pixel to each other are all kept: each is exact, but an image cannot separate
        them.
    margin : float
        How far inside the image (from the first and last pixel centres) the junctions are known.
    """

    image: np.ndarray
    regions: np.ndarray
    polygons: tuple[np.ndarray, ...]
    greys: tuple[float, ...]
    background: float
    junctions: tuple[Junction, ...]
    margin: float = 8.0

    @property
    def shape(self) -> tuple[int, int]:
        """(H, W)."""
        return (int(self.image.shape[0]), int(self.image.shape[1]))

    def outside(self, points) -> np.ndarray:
        """Which points (x, y) lie in the border strip where :attr:`junctions` are not known (closer than
        :attr:`margin` to the image's first or last pixel centre): detections there can be neither right
        nor wrong.

        Returns
        -------
        bool (N,)
        """
        points = real_host_array(points, "points", ndims=(2,), empty=True)
        if points.shape[1] != 2:
            raise InputValueError(f"points must be (N, 2) positions (x, y), got shape {points.shape}")
        height, width = self.shape
        x, y = points[:, 0], points[:, 1]
        return (x < self.margin) | (y < self.margin) | (x > width - 1 - self.margin) | (y > height - 1 - self.margin)

    def t_junctions(self) -> tuple[Junction, ...]:
        """The T-junctions among :attr:`junctions`, in their order.

        Returns
        -------
        tuple of Junction
        """
        return tuple(j for j in self.junctions if j.kind == "T")

    def resolvable(self, *, separation: float = 6.0, widest_merge: float = 30.0) -> np.ndarray:
        """Which T-junctions (of :meth:`t_junctions`, in order) a detector working at a few pixels' scale can
        resolve: no other junction of the scene within ``separation`` pixels, and every angle between
        its arms at least ``widest_merge`` degrees. Closer junctions blur into one compound junction at
        that scale, and arms at a narrower angle into one edge.

        Returns
        -------
        bool (T,)
        """
        separation = check_real(separation, "separation", minimum=0)
        widest_merge = check_real(widest_merge, "widest_merge", minimum=0, maximum=120)
        everything = np.array([[j.x, j.y] for j in self.junctions]).reshape(-1, 2)
        keep = []
        for j in self.t_junctions():
            others = np.sort(np.linalg.norm(everything - [j.x, j.y], axis=1))[1:]
            arms = np.array(j.arms)
            angles = np.degrees(np.diff(np.r_[arms, arms[0] + 2 * math.pi]))
            keep.append((not len(others) or others[0] >= separation) and angles.min() >= widest_merge)
        return np.array(keep, bool)

    def t_pairs(self) -> list[tuple[int, int]]:
        """Pairs of T-junctions at both ends of one hidden stretch of one straight edge.

        Where an occluder crosses an edge of a polygon behind it, the edge disappears at one T-junction
        and reappears at another: both have the same occluder, occluded polygon and edge. The stretches
        are found from the geometry (the occluder's boundary crossings along the edge, consecutive ones
        enclosing a part inside the occluder), so a pair is never formed across two occluded stretches.

        Returns
        -------
        list of (int, int)
            Indices into :attr:`junctions`, smaller first, sorted; only pairs with both ends in
            :attr:`junctions` (neither hidden by a third polygon nor outside the margin).
        """
        groups: dict[tuple[int, int, int], list[int]] = {}
        for i, j in enumerate(self.junctions):
            if j.kind == "T" and j.occluder >= 0 and j.occluded >= 0:
                groups.setdefault((j.occluder, j.occluded, j.edge), []).append(i)
        pairs: list[tuple[int, int]] = []
        for (front, back, edge), members in groups.items():
            if len(members) < 2:
                continue
            polygon = self.polygons[back]
            a, b = polygon[edge], polygon[(edge + 1) % len(polygon)]
            cuts = _crossings_along(a, b, self.polygons[front])
            for t0, t1 in itertools.pairwise(cuts):
                middle = a + 0.5 * (t0 + t1) * (b - a)
                if not _inside(self.polygons[front], middle[None, 0], middle[None, 1])[0]:
                    continue
                ends = [self._junction_at(members, a + t * (b - a)) for t in (t0, t1)]
                if ends[0] is not None and ends[1] is not None:
                    pairs.append((min(ends[0], ends[1]), max(ends[0], ends[1])))
        return sorted(pairs)

    def _junction_at(self, members: list[int], point: np.ndarray) -> int | None:
        for i in members:
            j = self.junctions[i]
            if math.hypot(j.x - point[0], j.y - point[1]) <= 1e-6:
                return i
        return None


def render_occlusion(shape: tuple[int, int] = (256, 256), *, polygons: int = 6, seed: int = 0,
                     noise: float = 0.0, antialias: bool = True, margin: float = 8) -> OcclusionScene:
    """Render random convex polygons of distinct greys stacked over a background.

    Parameters
    ----------
    shape : (int, int)
        (H, W), each >= 16.
    polygons : int
        How many polygons, 1 to 8.
    seed : int
        Seeds ``np.random.default_rng`` for the polygons, greys and noise (>= 0); the same seed gives the
        same scene.
    noise : float
        Standard deviation of the Gaussian noise added to every pixel (>= 0).
    antialias : bool
        Supersample every pixel 4 x 4 so edge pixels carry their coverage; otherwise each pixel takes
        the grey at its centre.
    margin : float
        Junctions closer than this to the image border (the first and last pixel centres) are dropped
        (>= 0).

    Returns
    -------
    OcclusionScene

    Notes
    -----
    Each polygon has 3 to 6 vertices on a jittered circle (radius 8 % to 30 % of min(H, W), centre
    uniform in the image, radii jittered by +-20 %), redrawn until strictly convex with edges at least
    2 px long. The background and polygon greys are distinct levels of a shuffled grid in [0.1, 0.9]:
    0.133 apart for up to 6 polygons, 0.8 / polygons apart for 7 and 8.

    Examples
    --------
    >>> from vmcl.scenes import render_occlusion
    >>> scene = render_occlusion((128, 128), polygons=4, seed=3)
    >>> scene.image.shape, scene.regions.dtype
    ((128, 128), dtype('int32'))
    """
    h, w = _check_shape(shape)
    count = check_int(polygons, "polygons", minimum=1)
    if count > MAX_POLYGONS:
        raise InputValueError(f"polygons must be <= {MAX_POLYGONS}: the greys of the background and "
                              f"{MAX_POLYGONS} polygons already sit only {MIN_CONTRAST} apart in [0.1, 0.9], "
                              f"got {count}")
    seed = check_int(seed, "seed", minimum=0)
    noise = check_real(noise, "noise", minimum=0.0)
    antialias = check_bool(antialias, "antialias")
    margin = check_real(margin, "margin", minimum=0.0)
    rng = np.random.default_rng(seed)
    shapes = [_random_polygon(rng, h, w) for _ in range(count)]
    levels = rng.permutation(np.linspace(0.1, 0.9, max(_GREY_LEVELS, count + 1)))
    return occlusion_scene(shapes, [float(g) for g in levels[1:count + 1]], shape=(h, w),
                           background=float(levels[0]), noise=noise, seed=seed, antialias=antialias,
                           margin=margin)


def occlusion_scene(polygons: Sequence[Any], greys: Sequence[float], *, shape: tuple[int, int],
                    background: float = 0.5, noise: float = 0.0, seed: int = 0, antialias: bool = True,
                    margin: float = 8) -> OcclusionScene:
    """Render given polygons, far to near, over a background, with the scene's exact junctions.

    Parameters
    ----------
    polygons : sequence of (K, 2) arrays
        Vertices (x, y) of each simple polygon (K >= 3, finite, non-zero area, either orientation);
        index 0 is the farthest.
    greys : sequence of float
        The grey of each polygon, in [0, 1]; one per polygon.
    shape : (int, int)
        (H, W), each >= 16.
    background : float
        The background's grey, in [0, 1].
    noise : float
        Standard deviation of the Gaussian noise added to every pixel (>= 0).
    seed : int
        Seeds the noise (>= 0).
    antialias : bool
        Supersample every pixel 4 x 4; otherwise each pixel takes the grey at its centre.
    margin : float
        Junctions closer than this to the image border (the first and last pixel centres) are dropped
        (>= 0).

    Returns
    -------
    OcclusionScene

    Examples
    --------
    >>> import numpy as np
    >>> from vmcl.scenes import occlusion_scene
    >>> back = np.array([[40, 40], [120, 40], [120, 120], [40, 120]], float)
    >>> scene = occlusion_scene([back, back + 40], [0.2, 0.8], shape=(200, 200))
    >>> [(j.x, j.y) for j in scene.t_junctions()]
    [(120.0, 80.0), (80.0, 120.0)]
    """
    h, w = _check_shape(shape)
    shapes = _check_polygons(polygons)
    greys_ = _check_greys(greys, len(shapes))
    background = check_real(background, "background", minimum=0.0, maximum=1.0)
    noise = check_real(noise, "noise", minimum=0.0)
    seed = check_int(seed, "seed", minimum=0)
    antialias = check_bool(antialias, "antialias")
    margin = check_real(margin, "margin", minimum=0.0)

    regions = _paint(shapes, np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
    lookup = np.array([*greys_, background], dtype=np.float64)  # index -1 is the background
    if antialias:
        offsets = (np.arange(_SUPERSAMPLE) + 0.5) / _SUPERSAMPLE - 0.5
        xs = (np.arange(w)[:, None] + offsets).ravel()
        ys = (np.arange(h)[:, None] + offsets).ravel()
        fine = lookup[_paint(shapes, xs, ys)]
        image = fine.reshape(h, _SUPERSAMPLE, w, _SUPERSAMPLE).mean(axis=(1, 3)).astype(np.float32)
    else:
        image = lookup[regions].astype(np.float32)
    if noise > 0:
        image += np.random.default_rng(seed).normal(0.0, noise, image.shape).astype(np.float32)

    junctions = _junctions(shapes, lookup, h, w, margin)
    for array in (image, regions, *shapes):
        array.setflags(write=False)
    return OcclusionScene(image=image, regions=regions.astype(np.int32, copy=False), polygons=tuple(shapes),
                          greys=tuple(greys_), background=background, junctions=tuple(junctions), margin=margin)


# ---------------------------------------------------------------------------------------------- checks


def _check_shape(shape: Any) -> tuple[int, int]:
    if not isinstance(shape, (tuple, list)) or len(shape) != 2:
        raise InputTypeError(f"shape must be a pair (height, width) of ints, got {shape!r}")
    return (check_int(shape[0], "shape[0] (height)", minimum=16),
            check_int(shape[1], "shape[1] (width)", minimum=16))


def _check_polygons(polygons: Any) -> list[np.ndarray]:
    if isinstance(polygons, (str, bytes)) or not isinstance(polygons, (Sequence, np.ndarray)):
        raise InputTypeError(f"polygons must be a sequence of (K, 2) vertex arrays, "
                             f"got {type(polygons).__name__}")
    out = []
    for i, polygon in enumerate(polygons):
        name = f"polygons[{i}]"
        try:
            vertices = np.asarray(polygon)
        except ValueError as error:  # ragged nested lists
            raise InputValueError(f"{name} must be a (K, 2) array of vertices: {error}") from None
        if vertices.dtype.kind not in "iuf":
            raise InputTypeError(f"{name} must hold real numbers (integer or float), "
                                 f"got dtype {vertices.dtype}")
        if vertices.ndim != 2 or vertices.shape[1] != 2 or vertices.shape[0] < 3:
            raise InputValueError(f"{name} must be a (K, 2) array of vertices with K >= 3, got shape "
                                  f"{vertices.shape}")
        vertices = vertices.astype(np.float64)
        if not np.isfinite(vertices).all():
            raise InputValueError(f"{name} must have finite vertices")
        if abs(_area(vertices)) <= 1e-9:
            raise InputValueError(f"{name} has zero area")
        out.append(vertices)
    return out


def _check_greys(greys: Any, count: int) -> list[float]:
    if isinstance(greys, (str, bytes)) or not isinstance(greys, (Sequence, np.ndarray)):
        raise InputTypeError(f"greys must be a sequence of floats, got {type(greys).__name__}")
    if len(greys) != count:
        raise InputValueError(f"greys must hold one grey per polygon ({count}), got {len(greys)}")
    return [check_real(g, f"greys[{i}]", minimum=0.0, maximum=1.0) for i, g in enumerate(greys)]


# -------------------------------------------------------------------------------------------- geometry


def _area(vertices: np.ndarray) -> float:
    x, y = vertices[:, 0], vertices[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def _random_polygon(rng: np.random.Generator, h: int, w: int) -> np.ndarray:
    while True:
        k = int(rng.integers(3, 7))
        radius = rng.uniform(0.08, 0.30) * min(h, w)
        centre = rng.uniform((0.0, 0.0), (w - 1.0, h - 1.0))
        # Jitter within +-0.35 of the angular step keeps the angles ascending, hence the vertices in
        # order around the centre; only the radial jitter can make the polygon non-convex.
        steps = np.arange(k) + rng.uniform(-0.35, 0.35, k)
        angles = rng.uniform(0.0, 2.0 * math.pi) + 2.0 * math.pi * steps / k
        radii = radius * rng.uniform(0.8, 1.2, k)
        vertices = centre + radii[:, None] * np.stack([np.cos(angles), np.sin(angles)], axis=1)
        edges = np.roll(vertices, -1, axis=0) - vertices
        turns = edges[:, 0] * np.roll(edges[:, 1], -1) - edges[:, 1] * np.roll(edges[:, 0], -1)
        if (turns > 0).all() and (np.hypot(edges[:, 0], edges[:, 1]) >= 2.0).all():
            return vertices


def _edge_arrays(vertices: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Start and end coordinates of the edges that are not horizontal (the only ones a ray along x can
    cross)."""
    xi, yi = vertices[:, 0], vertices[:, 1]
    xj, yj = np.roll(xi, -1), np.roll(yi, -1)
    keep = yi != yj
    return xi[keep], yi[keep], xj[keep], yj[keep]


def _inside(vertices: np.ndarray, px: np.ndarray, py: np.ndarray) -> np.ndarray:
    """Even-odd test of points (px, py); the same arithmetic as :func:`_inside_grid`, so both agree to the
    bit."""
    xi, yi, xj, yj = _edge_arrays(vertices)
    slope = (xj - xi) / (yj - yi)
    inside = np.zeros(np.shape(px), dtype=bool)
    for k in range(len(xi)):
        crosses = (yi[k] > py) != (yj[k] > py)
        inside ^= crosses & (px < xi[k] + (py - yi[k]) * slope[k])
    return inside


def _inside_grid(vertices: np.ndarray, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
    """Even-odd test of the grid ``ys x xs`` (both ascending), (len(ys), len(xs)) bool.

    Per row, a point is inside when an odd number of edge crossings lie strictly to its right. The
    crossings are counted per column with searchsorted and a reversed cumulative sum, so the cost is one
    pass over the grid rather than one per edge.
    """
    inside = np.zeros((len(ys), len(xs)), dtype=bool)
    xi, yi, xj, yj = _edge_arrays(vertices)
    if len(xi) == 0:
        return inside
    r0, r1 = np.searchsorted(ys, yi.min(), "left"), np.searchsorted(ys, yi.max(), "right")
    rows_y = ys[r0:r1]
    if len(rows_y) == 0:
        return inside
    slope = (xj - xi) / (yj - yi)
    crosses = (yi[None, :] > rows_y[:, None]) != (yj[None, :] > rows_y[:, None])
    rows, edges = np.nonzero(crosses)
    xint = xi[edges] + (rows_y[rows] - yi[edges]) * slope[edges]
    first_right = np.searchsorted(xs, xint, "left")  # columns before it have the crossing to their right
    width = len(xs) + 1
    counts = np.bincount(rows * width + first_right, minlength=len(rows_y) * width)
    counts = counts.reshape(len(rows_y), width)
    right = np.cumsum(counts[:, ::-1], axis=1)[:, ::-1]
    inside[r0:r1] = (right[:, 1:] & 1).astype(bool)
    return inside


def _paint(shapes: list[np.ndarray], xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
    labels = np.full((len(ys), len(xs)), -1, dtype=np.int32)
    for index, vertices in enumerate(shapes):
        labels[_inside_grid(vertices, xs, ys)] = index
    return labels


def _visible(shapes: list[np.ndarray], px: np.ndarray, py: np.ndarray) -> np.ndarray:
    labels = np.full(np.shape(px), -1, dtype=np.int32)
    for index, vertices in enumerate(shapes):
        labels[_inside(vertices, px, py)] = index
    return labels


def _crossings_along(a: np.ndarray, b: np.ndarray, vertices: np.ndarray) -> list[float]:
    """Parameters t in [0, 1] where segment a-b meets the boundary of ``vertices``, ascending, merged."""
    d = b - a
    starts = vertices
    ends = np.roll(vertices, -1, axis=0)
    e = ends - starts
    denom = d[0] * e[:, 1] - d[1] * e[:, 0]
    r = starts - a
    scale = np.hypot(*d) * np.hypot(e[:, 0], e[:, 1])
    ok = np.abs(denom) > 1e-12 * scale
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (r[:, 0] * e[:, 1] - r[:, 1] * e[:, 0]) / denom
        u = (r[:, 0] * d[1] - r[:, 1] * d[0]) / denom
    tol_t = _ON_EDGE / max(float(np.hypot(*d)), 1e-300)
    tol_u = _ON_EDGE / np.maximum(np.hypot(e[:, 0], e[:, 1]), 1e-300)
    ok &= (t >= -tol_t) & (t <= 1 + tol_t) & (u >= -tol_u) & (u <= 1 + tol_u)
    merged: list[float] = []
    for value in np.sort(t[ok]):
        if not merged or value - merged[-1] > tol_t:
            merged.append(float(value))
    return merged


def _candidates(shapes: list[np.ndarray]) -> np.ndarray:
    """Every vertex and every meeting point of two edges of different polygons, (N, 2), duplicates merged."""
    if not shapes:
        return np.zeros((0, 2))
    starts = np.concatenate(shapes)
    ends = np.concatenate([np.roll(v, -1, axis=0) for v in shapes])
    owner = np.concatenate([np.full(len(v), i) for i, v in enumerate(shapes)])
    d = ends - starts
    i, j = np.nonzero(owner[:, None] < owner[None, :])
    denom = d[i, 0] * d[j, 1] - d[i, 1] * d[j, 0]
    length_i, length_j = np.hypot(d[i, 0], d[i, 1]), np.hypot(d[j, 0], d[j, 1])
    r = starts[j] - starts[i]
    # Parallel edges meet, if at all, along a stretch whose ends are vertices: already candidates.
    ok = np.abs(denom) > 1e-12 * length_i * length_j
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (r[:, 0] * d[j, 1] - r[:, 1] * d[j, 0]) / denom
        u = (r[:, 0] * d[i, 1] - r[:, 1] * d[i, 0]) / denom
    tol_t, tol_u = _ON_EDGE / length_i, _ON_EDGE / length_j
    ok &= (t >= -tol_t) & (t <= 1 + tol_t) & (u >= -tol_u) & (u <= 1 + tol_u)
    crossings = starts[i[ok]] + t[ok, None] * d[i[ok]]
    points = np.concatenate([starts, crossings])
    # Vertices come first, so a crossing at a vertex keeps the vertex's exact coordinates.
    keep: list[np.ndarray] = []
    for p in points:
        if not keep or np.min(np.hypot(*(np.array(keep) - p).T)) > _ON_EDGE:
            keep.append(p)
    return np.array(keep)


def _directions_at(shapes: list[np.ndarray], point: np.ndarray) -> list[tuple[float, int, int]]:
    """(direction, polygon, edge) of every edge passing through ``point``, towards each of its ends."""
    out = []
    for index, vertices in enumerate(shapes):
        a, b = vertices, np.roll(vertices, -1, axis=0)
        d = b - a
        length2 = np.einsum("ij,ij->i", d, d)
        t = np.clip(np.einsum("ij,ij->i", point - a, d) / length2, 0.0, 1.0)
        near = np.hypot(*(a + t[:, None] * d - point).T) <= _ON_EDGE
        for k in np.nonzero(near)[0]:
            for end in (a[k], b[k]):
                away = end - point
                if math.hypot(*away) > _ON_EDGE:
                    out.append((_wrap(math.atan2(away[1], away[0])), index, int(k)))
    return out


def _wrap(angle: float) -> float:
    """``angle`` in [-pi, pi)."""
    wrapped = (angle + math.pi) % (2.0 * math.pi) - math.pi
    return -math.pi if wrapped >= math.pi else wrapped


def _angle_between(a: float, b: float) -> float:
    return abs(_wrap(a - b))


def _classify(arms: list[float]) -> str | None:
    """The junction type of ascending arm directions, None when they make no junction."""
    if len(arms) < 2:
        return None
    gaps = np.diff(np.append(arms, arms[0] + 2.0 * math.pi))
    if len(arms) == 2:
        return "L" if abs(gaps[0] - math.pi) > _STRAIGHT else None
    if len(arms) == 3:
        if (np.abs(gaps - math.pi) <= _STRAIGHT).any():
            return "T"
        return "arrow" if (gaps > math.pi + _STRAIGHT).any() else "Y"
    return "X"


def _arcs(shapes: list[np.ndarray], point: np.ndarray, arms: list[float]) -> list[int]:
    """The visible region in the middle of each arc, arc k running from arms[k] to arms[k + 1]."""
    ends = np.append(arms[1:], arms[0] + 2.0 * math.pi)
    middle = 0.5 * (np.asarray(arms) + ends)
    px = point[0] + _PROBE_RADIUS * np.cos(middle)
    py = point[1] + _PROBE_RADIUS * np.sin(middle)
    return [int(v) for v in _visible(shapes, px, py)]


def _junctions(shapes: list[np.ndarray], lookup: np.ndarray, h: int, w: int, margin: float) -> list[Junction]:
    points = _candidates(shapes)
    if len(points) == 0:
        return []
    inside = ((points[:, 0] >= margin) & (points[:, 0] <= w - 1 - margin)
              & (points[:, 1] >= margin) & (points[:, 1] <= h - 1 - margin))
    points = points[inside]
    # Half-step offsets keep the samples off the axis directions, along which hand-built scenes put edges.
    theta = -math.pi + (np.arange(_PROBE_SAMPLES) + 0.5) * _PROBE_STEP
    px = points[:, 0, None] + _PROBE_RADIUS * np.cos(theta)
    py = points[:, 1, None] + _PROBE_RADIUS * np.sin(theta)
    rings = _visible(shapes, px, py)
    out = []
    for point, ring in zip(points, rings):
        changes = np.nonzero(ring != np.roll(ring, -1))[0]
        if len(changes) == 0:
            continue  # hidden: one region all around
        directions = _directions_at(shapes, point)
        arms = [_snap(-math.pi + (k + 1) * _PROBE_STEP, directions) for k in changes]
        arms, arcs = _merge(shapes, point, arms)
        kind = _classify(arms)
        if kind is None:
            continue
        grey = lookup[arcs]
        if (np.abs(grey - np.roll(grey, 1)) < MIN_CONTRAST - 1e-9).any():
            continue  # an arm between two equal greys is no visible boundary
        occluder = occluded = edge = -1
        if kind == "T":
            occluder, occluded, edge = _t_roles(arms, arcs, directions)
        out.append(Junction(float(point[0]), float(point[1]), kind, tuple(arms), occluder, occluded, edge))
    out.sort(key=lambda j: (j.y, j.x))
    return out


def _snap(angle: float, directions: list[tuple[float, int, int]]) -> float:
    """The exact direction of the edge nearest ``angle``, when one is within a few probe steps."""
    best = min(directions, key=lambda d: _angle_between(d[0], angle), default=None)
    if best is not None and _angle_between(best[0], angle) <= 3.0 * _PROBE_STEP:
        return best[0]
    return _wrap(float(angle))


def _merge(shapes: list[np.ndarray], point: np.ndarray, arms: list[float]) -> tuple[list[float], list[int]]:
    """Sorted, distinct arms and the region of each arc, dropping arms with the same region either side.

    Snapping can make two sampled arms one, or (for arms a probe step apart) reorder them: the regions
    are sampled again between the final arms rather than carried over from the ring.
    """
    arms = sorted(set(arms))
    while True:
        if not arms:
            return arms, []
        arcs = _arcs(shapes, point, arms)
        keep = [k for k in range(len(arms)) if arcs[k - 1] != arcs[k]]
        if len(keep) == len(arms):
            return arms, arcs
        arms = [arms[k] for k in keep]


def _t_roles(arms: list[float], arcs: list[int],
             directions: list[tuple[float, int, int]]) -> tuple[int, int, int]:
    """(occluder, occluded, edge) of a T: the region across the straight bar, and the edge along the stem."""
    gaps = np.diff(np.append(arms, arms[0] + 2.0 * math.pi))
    bar = int(np.argmin(np.abs(gaps - math.pi)))  # arc `bar` spans the straight side
    occluder = arcs[bar]
    stem = arms[(bar + 2) % 3]
    beside = {arcs[(bar + 1) % 3], arcs[(bar + 2) % 3]}
    along = [(index, k) for angle, index, k in directions
             if _angle_between(angle, stem) <= _SAME_DIRECTION and index in beside and index != occluder]
    behind = [(index, k) for index, k in along if occluder < 0 or index < occluder]
    if not behind:
        return (max(occluder, -1), -1, -1)
    occluded, edge = max(behind)
    return occluder, occluded, edge
