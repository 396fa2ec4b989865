"""Junctions of the edge curves: found, classified (T, Y, arrow, L, X), broken T-junctions repaired, and
curves grouped across pairs of T-junctions.

Seed section "Saliency, grouping, and segmentation" (after Beymer, "Junctions: their detection and use
for grouping in images", MIT AI TR 1989). A junction is where curves meet:

- at branch pixels of the edge map (:attr:`vmcl.group.curves.Curves.branches`): the curves whose ends
  touch a cluster of branch pixels are its arms;
- across a gap: Canny's non-maximum suppression breaks the stem of a T short of the bar (near the bar the
  stem's gradient is not a maximum across the bar's), so a curve end whose tangent, followed for up to
  ``gap`` pixels, reaches another curve makes a T-junction there, with the bar's two directions as its
  other arms (a side of the bar shorter than three pixels is no arm: met by its end, the two curves
  make a corner, which Canny breaks as it breaks T's); the pixels along the way are its repair;
- at corners: where a curve's tangent turns sharply within a few pixels, an L.

Arms are classified by the angles between neighbouring arms: three arms with one angle near 180 degrees
(the bar, within ``straight``) make a T, with one angle wider than that an arrow, otherwise a Y; two arms
an L; four an X. A T's stem is the arm opposite its straight angle; the surface on the bar's far side
from the stem is in front (it occludes the stem's). Two T-junctions whose stems point at each other
along one line (each within ``alignment`` of the line joining them) are taken as the same occluded edge
seen on both sides of an occluder, and their stems' curves are grouped.

Coordinates are (x, y), x the column and y the row; directions are angles atan2(dy, dx) in radians.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from vmcl.cm.core import (
    ArrayLike,
    check_choice,
    check_int,
    check_real,
    finite_float32,
    real_host_array,
    to_host,
)
from vmcl.errors import InputTypeError, InputValueError
from vmcl.group.curves import BRANCH, Curves

__all__ = ["KINDS", "Junctions", "find_junctions", "group_curves", "repair_edges"]

KINDS = ("T", "Y", "arrow", "L", "X")
"""The junction types :func:`find_junctions` tells apart."""

_ARM_WINDOWS = ((2, 12), (4, 14), (2, 8), (1, 5))  # pixels along an arm from the junction its direction is fitted to
_CORNER_SPAN = 5  # a corner's turn: between the chords this many pixels back and ahead along its curve
_SAME_ARM = math.radians(30)  # arms of merged candidates closer than this are one arm
_SAME_CURVE_ARM = math.radians(60)  # the same, for two arms on one curve
_MIN_ARM = 3  # the fewest pixels a curve at a branch cluster, or a bar's side past a gap's end, needs to be an arm
_STEM_REACH, _SIDE = 6.0, 2.5  # where a T's stem sides and bar front are sampled (group_curves' image test)
_REACH = 3.0  # how far the arms' meeting point may move a junction from where its pixels put it
_CONE = math.radians(35)  # how far off a free end's tangent the curve it meets may lie
_NEIGHBOURS = np.array([(dx, dy) for dy in (-1, 0, 1) for dx in (-1, 0, 1) if dx or dy])


@dataclass(frozen=True)
class Junctions:
    """What :func:`find_junctions` returns: J junctions as arrays.

    Attributes
    ----------
    points : float64 (J, 2)
        Positions (x, y).
    kinds : (J,) str array
        One of :data:`KINDS`.
    arms : float64 (J, 4)
        The arms' directions from the junction, ascending, NaN past the junction's arm count.
    arm_curves : int32 (J, 4)
        The curve of each arm (-1 past the count).
    stem : int32 (J,)
        For a T, the column of ``arms`` that is its stem; -1 otherwise.
    occluder : float64 (J, 2)
        For a T, the unit normal of the bar pointing away from the stem, into the surface in front; NaN
        otherwise.
    gap : float64 (J,)
        For a T found across a gap, the gap's length in pixels (0 where the curves touch).
    fills : list of int32 (k, 2) arrays
        Per junction, the pixels (x, y) that close its gap (empty where there is none).
    shape : (int, int) or None
        (H, W) of the edge map the junctions were found in (None where unknown), against which
        :func:`group_curves` checks its ``image``.
    """

    points: np.ndarray
    kinds: np.ndarray
    arms: np.ndarray
    arm_curves: np.ndarray
    stem: np.ndarray
    occluder: np.ndarray
    gap: np.ndarray
    fills: list[np.ndarray]
    shape: tuple[int, int] | None = None

    def __len__(self) -> int:
        return len(self.points)

    def of_kind(self, kind: str) -> np.ndarray:
        """The indices of the junctions of one kind (one of :data:`KINDS`)."""
        return np.flatnonzero(self.kinds == check_choice(kind, "kind", KINDS))

    def counts(self) -> dict[str, int]:
        """The number of junctions of each kind."""
        return {kind: int(np.count_nonzero(self.kinds == kind)) for kind in KINDS}


class _Found:
    """Junction candidates gathered one by one, then merged where they lie together and classified.

    A T that Canny broke shows up as several candidates a pixel or two apart (a corner where the bar
    turns into the stem, a branch cluster with two arms, the gap from the other half of the bar), each
    seeing some of the arms; merged, they see them all."""

    def __init__(self, straight: float, merge: float) -> None:
        self.straight, self.merge = straight, merge
        self.candidates: list[tuple[np.ndarray, list[float], list[int], float, np.ndarray]] = []

    def add(self, point, arms, curves, gap: float = 0.0, fill: np.ndarray | None = None) -> None:
        self.candidates.append((np.asarray(point, float), [float(a) for a in arms], [int(c) for c in curves],
                                float(gap), np.zeros((0, 2), np.int32) if fill is None else fill))

    def _merged(self) -> list[tuple[np.ndarray, list[float], list[int], float, np.ndarray]]:
        # Candidates with more arms first: their point is the better estimate of the junction's.
        order = sorted(range(len(self.candidates)), key=lambda i: (-len(self.candidates[i][1]), i))
        merged: list[tuple[np.ndarray, list[float], list[int], float, np.ndarray]] = []
        points = np.array([c[0] for c in self.candidates]).reshape(-1, 2)
        taken_points: list[int] = []  # the candidate each merged junction's point came from
        for i in order:
            point, arms, curves, gap, fill = self.candidates[i]
            near = (np.flatnonzero(np.hypot(*(points[taken_points] - point).T) <= self.merge)
                    if taken_points else np.zeros(0, int))
            if not len(near):
                merged.append((point, list(arms), list(curves), gap, fill))
                taken_points.append(i)
                continue
            k = int(near[0])
            target = merged[k]
            for arm, curve in zip(arms, curves):
                # One curve's arms measured from two candidates differ more than two curves' do.
                if all(_turn(arm, other) > (_SAME_CURVE_ARM if curve == other_curve else _SAME_ARM)
                       for other, other_curve in zip(target[1], target[2])):
                    target[1].append(arm)
                    target[2].append(curve)
            if len(fill) > len(target[4]):
                merged[k] = (target[0], target[1], target[2], gap, fill)
        return merged

    def junctions(self, shape: tuple[int, int]) -> Junctions:
        rows = []
        for point, arms, curves, gap, fill in self._merged():
            order = np.argsort(arms)
            sorted_arms, sorted_curves = np.asarray(arms)[order], np.asarray(curves, np.int32)[order]
            kind, stem = _classify(sorted_arms, self.straight)
            if kind is None:
                continue
            occluder = _occluder_side(sorted_arms, stem) if stem >= 0 else np.full(2, np.nan)
            rows.append((point, kind, sorted_arms[:4], sorted_curves[:4], stem, occluder, gap, fill))
        count = len(rows)
        arms_out, curves_out = np.full((count, 4), np.nan), np.full((count, 4), -1, np.int32)
        for i, row in enumerate(rows):
            arms_out[i, :len(row[2])], curves_out[i, :len(row[3])] = row[2], row[3]
        column = list(zip(*rows)) if rows else [[] for _ in range(8)]
        return Junctions(np.array(column[0], float).reshape(count, 2), np.array(column[1], dtype="<U5"), arms_out,
                         curves_out, np.array(column[4], np.int32), np.array(column[5], float).reshape(count, 2),
                         np.array(column[6], float), list(column[7]), shape)


def _turn(a: float, b: float) -> float:
    """The angle between two directions, in [0, pi]."""
    return abs(math.remainder(a - b, 2 * math.pi))


def _gaps(arms: np.ndarray) -> np.ndarray:
    """The angles between each arm and the next counter-clockwise (ascending angle), summing to 2 pi."""
    return np.diff(np.r_[arms, arms[0] + 2 * math.pi])


def _classify(arms: np.ndarray, straight: float) -> tuple[str | None, int]:
    """(kind, stem column) from the arms' sorted directions; (None, -1) where they make no junction."""
    count = len(arms)
    if count == 2:
        return ("L", -1) if abs(_gaps(arms)[0] - math.pi) > straight else (None, -1)
    if count == 3:
        gaps = _gaps(arms)
        widest = int(np.argmax(gaps))
        if abs(gaps[widest] - math.pi) <= straight:
            # The straight angle lies between arms widest and widest + 1: the third arm is the stem.
            return "T", (widest + 2) % 3
        return ("arrow", -1) if gaps[widest] > math.pi else ("Y", -1)
    if count >= 4:
        return "X", -1
    return None, -1


def _occluder_side(arms: np.ndarray, stem: int) -> np.ndarray:
    """A T's bar normal pointing away from its stem."""
    bar = [a for i, a in enumerate(arms) if i != stem]
    along = np.array([math.cos(bar[0]) - math.cos(bar[1]), math.sin(bar[0]) - math.sin(bar[1])])
    along /= np.linalg.norm(along)
    stem_direction = np.array([math.cos(arms[stem]), math.sin(arms[stem])])
    across = stem_direction - along * (stem_direction @ along)
    return -across / np.linalg.norm(across)


def find_junctions(curves: Curves, *, gap: float = 6.0, min_length: int = 5, corner: float = 60.0,
                   straight: float = 25.0, merge: float = 3.0) -> Junctions:
    """The junctions of linked edge curves (:func:`vmcl.group.curves.link_edges`).

    Parameters
    ----------
    curves : Curves
    gap : float
        The longest gap, in pixels, a curve's end may be followed across to the curve it meets (a broken
        T-junction), passing over fragments (curves shorter than 3 pixels); >= 0 (0: only curves that
        touch).
    min_length : int
        Curves shorter than this (in pixels) are not arms: their ends' tangents are too short to
        measure, and Canny leaves such stubs at many junctions; >= 2.
    corner : float
        The turn, in degrees, within a few pixels of a curve that makes an L-junction; in (0, 180].
    straight : float
        How far from 180 degrees, in degrees, an angle between two arms may be and still make a bar (a T
        rather than a Y or an arrow; no L); in [0, 90).
    merge : float
        Candidates closer than this, in pixels, are one junction (their arms pooled); >= 0.

    Returns
    -------
    Junctions
    """
    if not isinstance(curves, Curves):
        raise InputTypeError(f"curves must be a vmcl.group.Curves (from link_edges), got {type(curves).__name__}")
    gap = check_real(gap, "gap", minimum=0)
    min_length = check_int(min_length, "min_length", minimum=2)
    corner = math.radians(check_real(corner, "corner", above=0, maximum=180))
    straight = math.radians(check_real(straight, "straight", minimum=0, below=90))
    merge = check_real(merge, "merge", minimum=0)
    labels = np.asarray(to_host(curves.labels))
    found = _Found(straight, merge)
    long_enough = curves.sizes >= min_length
    touching, passable = _branch_junctions(curves, labels, found)
    corners = _corners(curves, long_enough, corner, found)
    if gap > 0:
        _gap_junctions(curves, labels, passable, long_enough, touching, corners, gap, min_length, found)
    return found.junctions((int(labels.shape[0]), int(labels.shape[1])))


def _ends(curves: Curves) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every open curve's two ends: (curve, end 0 or 1, pixel (x, y))."""
    open_curves = np.flatnonzero(~curves.closed)
    curve = np.repeat(open_curves, 2)
    end = np.tile([0, 1], len(open_curves))
    index = np.where(end == 0, curves.offsets[curve], curves.offsets[curve + 1] - 1)
    return curve, end, curves.points[index]


def _arm(curves: Curves, c: int, at: int, step: int, origin: np.ndarray) -> tuple[float, np.ndarray] | None:
    """The direction away from ``origin`` of curve ``c`` from its pixel ``at`` on (in the sense of
    ``step``, +1 or -1; held at an open curve's end, wrapped round a loop), and a point on its line: the
    principal axis of the curve's pixels in the first of the windows :data:`_ARM_WINDOWS` (pixels along
    from ``at``) whose pixels stay within a pixel of their line (an arm may turn a corner further on),
    oriented away from ``origin``; the chord to the farthest where fewer than three pixels are left.
    None where no pixel lies apart from the origin. The first pixels are skipped where the curve allows
    because Canny rounds curves where they meet."""
    start, size, closed = int(curves.offsets[c]), int(curves.sizes[c]), bool(curves.closed[c])
    fallback = None
    for first, last in _ARM_WINDOWS:
        steps = at + step * np.arange(first, last + 1)
        if closed:
            steps = np.unique(steps % size) if last - first >= size else steps % size
        else:
            inside = steps[(steps >= 0) & (steps < size)]
            # Past an open curve's end the window holds at its last pixel.
            steps = inside if len(inside) else np.array([min(max(at + step * first, 0), size - 1)])
        pixels = curves.points[start + steps].astype(float)
        centre = pixels.mean(axis=0)
        away = centre - origin
        if not away.any():
            continue
        if len(pixels) < 3:
            fallback = fallback or (math.atan2(away[1], away[0]), centre)
            continue
        centred = pixels - centre
        # The principal axis of the 2 x 2 scatter matrix in closed form.
        sxx, syy, sxy = (centred[:, 0] ** 2).sum(), (centred[:, 1] ** 2).sum(), (centred[:, 0] * centred[:, 1]).sum()
        theta = 0.5 * math.atan2(2 * sxy, sxx - syy)
        axis = np.array([math.cos(theta), math.sin(theta)])
        if axis @ away < 0:
            axis = -axis
        across = np.abs(centred[:, 1] * axis[0] - centred[:, 0] * axis[1]).max()
        if across <= 1.0:
            return math.atan2(axis[1], axis[0]), centre
        fallback = fallback or (math.atan2(axis[1], axis[0]), centre)
    return fallback


def _meeting_point(arms: list[tuple[float, np.ndarray]], near: np.ndarray, reach: float) -> np.ndarray:
    """The point nearest (least squares) to every arm's line, where the lines are not near parallel and
    it lies within ``reach`` of ``near``; ``near`` otherwise."""
    normals = np.array([(-math.sin(a), math.cos(a)) for a, _ in arms])
    offsets = np.array([n @ anchor for n, (_, anchor) in zip(normals, arms)])
    system = normals.T @ normals
    if np.linalg.cond(system) > 50:
        return near
    point = np.linalg.solve(system, normals.T @ offsets)
    return point if np.linalg.norm(point - near) <= reach else near


def _branch_junctions(curves: Curves, labels: np.ndarray, found: _Found) -> tuple[np.ndarray, np.ndarray]:
    """Junctions at clusters of branch pixels; returns which curve ends touch one ((C, 2) bool), and the
    pixels a free end's search passes over ((H, W) bool): the fragments (curves shorter than an arm) and
    the clusters that make no junction (a spur and a stub where Canny broke an edge): a stem that met
    them was taken as joined to a junction that was not there."""
    from scipy import ndimage

    height, width = labels.shape
    touching = np.zeros((len(curves), 2), bool)
    passable = np.isin(labels, np.flatnonzero(curves.sizes < _MIN_ARM))
    if not len(curves.branches):
        return touching, passable
    clusters, count = ndimage.label(labels == BRANCH, structure=np.ones((3, 3)))
    curve, end, pixel = _ends(curves)
    around = pixel[:, None, :] + _NEIGHBOURS[None]
    inside = (around[..., 0] >= 0) & (around[..., 1] >= 0) & (around[..., 0] < width) & (around[..., 1] < height)
    clipped = np.clip(around, 0, [width - 1, height - 1])
    cluster_of = np.where(inside, clusters[clipped[..., 1], clipped[..., 0]], 0).max(axis=1)
    # Each cluster's centre: the mean of its branch pixels.
    members = clusters[curves.branches[:, 1], curves.branches[:, 0]]
    weight = np.bincount(members, minlength=count + 1)[1:]
    centres = np.stack([np.bincount(members, curves.branches[:, k], count + 1)[1:] / weight for k in (0, 1)], axis=1)
    idle: list[int] = []  # the clusters that make no junction
    for c in range(1, count + 1):
        here = np.flatnonzero((cluster_of == c) & (curves.sizes[curve] >= _MIN_ARM))
        centre = centres[c - 1]
        fitted = [(_arm(curves, curve[i], 0 if end[i] == 0 else curves.sizes[curve[i]] - 1, 1 - 2 * end[i], centre),
                   curve[i]) for i in here]
        arms = [(arm, k) for arm, k in fitted if arm is not None]
        if len(arms) >= 2:
            point = _meeting_point([arm for arm, _ in arms], centre, _REACH)
            found.add(point, [arm[0] for arm, _ in arms], [k for _, k in arms])
        else:
            idle.append(c)
    passable |= np.isin(clusters, idle)  # once: a comparison of the whole map per cluster cost O(clusters H W)
    # An end at any cluster is not searched from: one at a cluster with no junction may be a T's stem that
    # Canny broke into a spur and a stub, but searching from those on a textured photograph (OpenCV's
    # box_in_scene) added 50 corners to its 827, and recognition lost the box among them.
    touching[curve, end] = cluster_of > 0
    return touching, passable


def _gap_junctions(curves: Curves, labels: np.ndarray, passable: np.ndarray, long_enough: np.ndarray,
                   touching: np.ndarray, corners: dict[int, np.ndarray], gap: float, min_length: int,
                   found: _Found) -> None:
    """T-junctions where a free curve end, followed along its tangent, meets another curve within ``gap``
    (passing over the ``passable`` pixels)."""
    position = np.asarray(to_host(curves.position))
    curve, end, pixel = _ends(curves)
    free = long_enough[curve] & ~touching[curve, end]
    searched = np.where(passable, -1, labels)
    for c, e, start in zip(curve[free], end[free], pixel[free]):
        tangent = curves.tangents[c, e]
        if not np.all(np.isfinite(tangent)):
            continue
        hit = _first_hit(searched, start, tangent, gap, _CONE, c)
        if hit is None:
            continue
        bar, point, distance = hit
        stem = _arm(curves, c, 0 if e == 0 else curves.sizes[c] - 1, 1 - 2 * e, point)
        if stem is None:
            continue
        arms, arm_curves = [stem], [c]
        if bar != BRANCH and curves.sizes[bar] >= min_length:
            at = position[point[1], point[0]]
            near = corners.get(bar, np.zeros(0, int))
            near = near[np.abs(near - at) <= _CORNER_SPAN]
            if len(near):
                # The gap reached a corner's side: the junction is the corner, where the bar turns into
                # another edge (Canny broke the bar, not the stem), and its arms are the corner's.
                at = int(near[np.argmin(np.abs(near - at))])
                point = curves.points[curves.offsets[bar] + at]
            for sign in (-1, 1):
                # Pixels of the bar beyond the meeting point on this side (a loop goes on either way).
                beyond = _MIN_ARM if curves.closed[bar] else (at if sign < 0 else curves.sizes[bar] - 1 - at)
                if beyond < _MIN_ARM:
                    continue
                arm = _arm(curves, bar, at, sign, point)
                if arm is not None and all(_turn(arm[0], other[0]) > _SAME_ARM for other in arms):
                    arms.append(arm)
                    arm_curves.append(bar)
        meeting = _meeting_point(arms, point.astype(float), _REACH) if len(arms) >= 2 else point
        # A hit on a branch pixel or a stub adds the stem alone: it joins the junction found there.
        found.add(meeting, [arm[0] for arm in arms], arm_curves, gap=distance, fill=_line_pixels(start, point))


def _first_hit(labels: np.ndarray, start: np.ndarray, tangent: np.ndarray, gap: float, cone: float,
               own: int) -> tuple[int, np.ndarray, float] | None:
    """The nearest pixel of another curve (or a branch pixel) within ``gap`` of a curve's end and within
    ``cone`` of its tangent, with its distance. A cone rather than a ray: Canny bends a stem towards the
    bar in the last pixels before it breaks, so the end's tangent points a little off."""
    height, width = labels.shape
    # No gap reaches farther than the image's diagonal, however long it is allowed to be.
    reach = math.ceil(min(gap, math.hypot(height, width)))
    x0, y0 = max(0, start[0] - reach), max(0, start[1] - reach)
    window = labels[y0:min(height, start[1] + reach + 1), x0:min(width, start[0] + reach + 1)]
    ys, xs = np.nonzero((window != -1) & (window != own))
    if not len(xs):
        return None
    offsets = np.stack([xs + x0 - start[0], ys + y0 - start[1]], axis=1).astype(float)
    distance = np.linalg.norm(offsets, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        ahead = (offsets @ tangent) / distance
    inside = (distance <= gap) & (ahead >= math.cos(cone))
    if not inside.any():
        return None
    # The nearest curve is the one met; on it, the pixel nearest the end's line is where the line meets it.
    nearest = np.flatnonzero(inside)[np.argmin(distance[inside])]
    met = inside & (window[ys, xs] == window[ys[nearest], xs[nearest]])
    across = np.abs(offsets @ np.array([-tangent[1], tangent[0]]))
    best = np.flatnonzero(met)[np.argmin(across[met] + 1e-3 * distance[met])]
    point = np.array([xs[best] + x0, ys[best] + y0])
    return int(window[ys[best], xs[best]]), point, float(distance[best])


def _line_pixels(start: np.ndarray, stop: np.ndarray) -> np.ndarray:
    """The pixels strictly between two pixels along the straight line joining them."""
    count = int(max(abs(stop[0] - start[0]), abs(stop[1] - start[1])))
    if count <= 1:
        return np.zeros((0, 2), np.int32)
    t = np.arange(1, count) / count
    line = np.rint(start[None] + t[:, None] * (stop - start)[None]).astype(np.int32)
    return line


def _corners(curves: Curves, long_enough: np.ndarray, corner: float, found: _Found) -> dict[int, np.ndarray]:
    """L-junctions where a curve's direction (the chords _CORNER_SPAN pixels back and ahead) turns by at least
    ``corner``, at the sharpest pixel of each such turn; returns each curve's corners (arc positions)."""
    span = _CORNER_SPAN
    corners: dict[int, np.ndarray] = {}
    for c in np.flatnonzero(long_enough & (curves.sizes > 2 * span)):
        points = curves.points[curves.offsets[c]:curves.offsets[c + 1]].astype(float)
        if curves.closed[c]:
            back, ahead = np.roll(points, span, axis=0), np.roll(points, -span, axis=0)
            middle = points
        else:
            back, ahead, middle = points[:-2 * span], points[2 * span:], points[span:-span]
        into_back, into_ahead = back - middle, ahead - middle
        angle_back = np.arctan2(into_back[:, 1], into_back[:, 0])
        angle_ahead = np.arctan2(into_ahead[:, 1], into_ahead[:, 0])
        # The turn is pi minus the angle between the two chords.
        between = np.abs(np.angle(np.exp(1j * (angle_ahead - angle_back))))
        turn = math.pi - between
        sharp = turn >= corner
        if not sharp.any():
            continue
        # One L per run of sharp pixels, at its sharpest.
        runs = np.split(np.flatnonzero(sharp), np.flatnonzero(np.diff(np.flatnonzero(sharp)) > 1) + 1)
        at = np.array([run[np.argmax(turn[run])] for run in runs]) + (0 if curves.closed[c] else span)
        corners[int(c)] = at
        for j in at:
            point = curves.points[curves.offsets[c] + j].astype(float)
            arms = [_arm(curves, int(c), int(j), sign, point) for sign in (-1, 1)]
            if all(arm is not None for arm in arms):
                found.add(point, [arm[0] for arm in arms if arm is not None], [c, c])
    return corners


def repair_edges(edges: ArrayLike, junctions: Junctions) -> np.ndarray:
    """``edges`` (a host bool (H, W) map, of the junctions' edge map's shape where known:
    :attr:`Junctions.shape`; finite) with every junction's gap filled (:attr:`Junctions.fills`)."""
    if not isinstance(junctions, Junctions):
        raise InputTypeError(f"junctions must be a vmcl.group.Junctions, got {type(junctions).__name__}")
    # NaN is non-zero, so cast to bool it would become an edge: refused, as the other grouping functions
    # refuse float edge maps (finite_float32 refuses what overflows its cast, with a message).
    with np.errstate(over="ignore"):
        mask = finite_float32(real_host_array(to_host(edges), "edges", ndims=(2,)), "edges").astype(bool)
    if junctions.shape is not None and mask.shape != tuple(junctions.shape):
        # Fills inside a larger or differently shaped map would land at pixels of another meaning.
        raise InputValueError(f"edges must have the shape of the edge map the junctions were found in "
                              f"{tuple(junctions.shape)}, got shape {mask.shape}")
    for fill in junctions.fills:
        if len(fill) and (fill.max(axis=0) >= mask.shape[::-1]).any():
            raise InputValueError(f"edges ({mask.shape}) is smaller than the map the junctions were found in")
    for fill in junctions.fills:
        if len(fill):
            mask[fill[:, 1], fill[:, 0]] = True
    return mask


def group_curves(junctions: Junctions, *, image: ArrayLike | None = None, alignment: float = 20.0,
                 max_distance: float = math.inf, contrast: float = 0.1) -> tuple[np.ndarray, list[np.ndarray]]:
    """Pairs of T-junctions whose stems point at each other along one line, and the groups of curves they join.

    Parameters
    ----------
    junctions : Junctions
    image : (H, W) or (H, W, 3) array, NumPy or device, optional
        The image the junctions came from, of the edge map's (H, W) (``junctions.shape``) and at least
        16 x 16 pixels; uint8, uint16 or float (brightness in [0, 1]), as :func:`vmcl.pipeline.as_image`
        reads it, and checked so before anything else, however many T-junctions there are. With it, two
        T-junctions pair only where they look like one edge behind one occluder: the brightness on each
        side of one stem matches the other stem's (sides swapped, since the stems point at each other),
        and the brightness in front of both bars matches, each within ``contrast``.
    alignment : float
        The most each stem's continuation (the direction opposite the stem) may differ from the line to
        the other junction, in degrees; in (0, 90).
    max_distance : float
        The farthest apart two paired junctions may be, in pixels; > 0.
    contrast : float
        The brightness tolerance of the ``image`` test, in [0, 1].

    Returns
    -------
    pairs : int32 (P, 2)
        Junction indices, each T in at most one pair (the best-aligned first), smaller index first.
    groups : list of int32 arrays
        The stems' curves joined by the pairs (connected through shared curves), each sorted.
    """
    if not isinstance(junctions, Junctions):
        raise InputTypeError(f"junctions must be a vmcl.group.Junctions, got {type(junctions).__name__}")
    limit = math.radians(check_real(alignment, "alignment", above=0, below=90))
    contrast = check_real(contrast, "contrast", minimum=0, maximum=1)
    max_distance = check_real(max_distance, "max_distance", above=0) if max_distance != math.inf else math.inf
    grey = None if image is None else pairing_image(image, junctions.shape)
    ts = junctions.of_kind("T")
    if len(ts) < 2:
        return np.zeros((0, 2), np.int32), []
    stems = junctions.arms[ts, junctions.stem[ts]]
    onward = np.stack([-np.cos(stems), -np.sin(stems)], axis=1)
    points = junctions.points[ts]
    joining = points[None, :, :] - points[:, None, :]
    distance = np.linalg.norm(joining, axis=2)
    with np.errstate(invalid="ignore", divide="ignore"):
        unit = joining / distance[..., None]
        off_i = np.arccos(np.clip(np.einsum("ijk,ik->ij", unit, onward), -1, 1))
        off_j = np.arccos(np.clip(np.einsum("ijk,jk->ij", -unit, onward), -1, 1))
    cost = np.maximum(off_i, off_j)
    usable = (cost < limit) & (distance <= max_distance) & (distance > 0)
    if grey is not None:
        usable &= _alike(_appearance(grey, junctions, ts), contrast)
    pairs = []
    taken = np.zeros(len(ts), bool)
    for flat in np.argsort(np.where(usable, cost, np.inf), axis=None):
        i, j = np.unravel_index(flat, cost.shape)
        if not usable[i, j]:
            break
        if i < j and not taken[i] and not taken[j]:
            taken[i] = taken[j] = True
            pairs.append((ts[i], ts[j]))
    pairs_array = np.array(sorted(pairs), np.int32).reshape(-1, 2)
    stem_curve = {int(t): int(junctions.arm_curves[t, junctions.stem[t]]) for t in ts}
    groups = _connected([(stem_curve[int(a)], stem_curve[int(b)]) for a, b in pairs_array])
    return pairs_array, groups


def pairing_image(image: Any, shape: tuple[int, int] | None) -> np.ndarray:
    """``image`` (NumPy or device) checked as :func:`vmcl.pipeline.as_image` checks it (16 x 16 pixels at
    least, masked values refused), of the edge map's ``shape`` where known, as float32 grey in [0, 1] on
    the host, where the pairing samples it. Samples off a smaller or larger image would be clamped to its
    border or read from the wrong place, silently."""
    from vmcl.pipeline import as_image

    grey = as_image(to_host(image, "image"), "image")
    if shape is not None and grey.shape[:2] != tuple(shape):
        raise InputValueError(f"image must have the edge map's height and width {tuple(shape)}, got shape "
                              f"{image.shape}")
    if grey.ndim == 3:
        grey = grey @ np.array([0.299, 0.587, 0.114], np.float32)
    return grey


def _appearance(grey: np.ndarray, junctions: Junctions, ts: np.ndarray) -> np.ndarray:
    """Per T: the brightness left and right of its stem (seen looking along the stem away from the
    junction) and in front of its bar, from the grey image (:func:`pairing_image`) smoothed a little ((T, 3))."""
    from scipy import ndimage

    grey = ndimage.gaussian_filter(grey, 1.0)
    stems = junctions.arms[ts, junctions.stem[ts]]
    along = np.stack([np.cos(stems), np.sin(stems)], axis=1)
    left = np.stack([along[:, 1], -along[:, 0]], axis=1)
    points = junctions.points[ts]
    samples = [points + _STEM_REACH * along + _SIDE * left, points + _STEM_REACH * along - _SIDE * left,
               points + _SIDE * junctions.occluder[ts]]
    return np.stack([ndimage.map_coordinates(grey, [p[:, 1], p[:, 0]], order=1, mode="nearest") for p in samples],
                    axis=1)


def _alike(looks: np.ndarray, contrast: float) -> np.ndarray:
    """(T, T): whether two T-junctions' stems could be one edge behind one occluder: the sides swapped
    (the stems point at each other) and the fronts alike."""
    left, right, front = looks[:, 0], looks[:, 1], looks[:, 2]
    return ((np.abs(left[:, None] - right[None, :]) <= contrast) & (np.abs(right[:, None] - left[None, :]) <= contrast)
            & (np.abs(front[:, None] - front[None, :]) <= contrast))


def _connected(links: list[tuple[int, int]]) -> list[np.ndarray]:
    """Connected components of an undirected graph given by its edges, as sorted arrays, by smallest member."""
    parent: dict[int, int] = {}

    def root(a: int) -> int:
        while parent.setdefault(a, a) != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    for a, b in links:
        ra, rb = root(a), root(b)
        if ra != rb:
            parent[max(ra, rb)] = min(ra, rb)
    members: dict[int, list[int]] = {}
    for node in parent:
        members.setdefault(root(node), []).append(node)
    return sorted((np.array(sorted(group), np.int32) for group in members.values()), key=lambda g: int(g[0]))
