"""Indexing: candidate (model, pose) pairs from invariant keys of feature pairs, by geometric hashing.

Seed section "Recognition": indexing finds "a small set of candidate models" from "simple
viewpoint-invariant combinations of features". Two corners A and B (each a position, the bisector of its
angle and the angle's opening) give a key that a similarity does not change: the openings of A and B,
and the directions of their bisectors measured from the line A -> B. An arc (a curve piece on a circle,
:func:`vmcl.recognize.features.arcs_of`) takes part by its circle's centre: in a pair, its coordinates
are its radius over the pair's length (in place of a bisector's direction) and a mark saying it is an arc
(in place of an opening), so a curved outline with a single corner in view still has keys. The
library's table maps every key to the model views' feature pairs that have it (built once per library,
with each pair entered in the two nearest bins of every coordinate so a key near a bin's edge still meets
it). For an image, every ordered pair of nearby features looks its key up; each entry it meets fixes
the similarity taking the model pair onto the image pair, and votes for (view, rotation, scale, where
the view's centre lands), binned, on the device (kernels/indexing.cl, one work-item per hit: an image
pair and an entry it met; votes counted in a hashed accumulator with a region per view, sized to the
view's hypotheses, and each hit's bins kept for the pass that lists the kept bins' hypotheses). The bins
with the most votes of each view are the candidates, the budget shared between the views; their votes'
similarities are pooled into each candidate's pose. Candidate generation looks at the entries that share
a key with the image's pairs only, so its work grows with those entries (about as the table does).

:func:`vote_numpy` is the same vote in NumPy, the reference the kernel is tested and timed against.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import pyopencl.array as cl_array
from scipy.spatial import cKDTree

from vmcl.cm.core import check_bool, check_int, check_real, machine_for
from vmcl.errors import InputTypeError, InputValueError
from vmcl.machine import Machine
from vmcl.recognize.arguments import angles, index_pairs, points
from vmcl.recognize.features import Features
from vmcl.recognize.models import Library, View

__all__ = ["ANGLE_BINS", "KEYS", "MAX_CANDIDATES", "OPENING_BINS", "Candidates", "Index", "anchors_of", "corner_pairs",
           "index_for", "pair_keys", "vote", "vote_numpy"]

MAX_CANDIDATES = 1 << 20
"""The most pose bins :func:`vote` keeps (its ``candidates``)."""

ANGLE_BINS = 16
"""Bins of a bisector's direction from the line between the two corners (22.5 degrees each)."""
OPENING_BINS = 9
"""Bins of a corner's opening over (0, 180) degrees (20 degrees each)."""
_ARC_MARK = OPENING_BINS  # the opening coordinate's value for an arc: one bin past the corners' openings
_KINDS = OPENING_BINS + 1
_RATIO_LOW, _RATIO_HIGH = -3.0, 3.0  # the log of an arc's radius over the pair's length, over the angle bins
KEYS = ANGLE_BINS * ANGLE_BINS * _KINDS * _KINDS
"""The number of distinct keys."""

_ROTATION_BINS = 24  # the pose bins: 15 degrees of rotation,
_ROTATION_BIN = 2 * math.pi / _ROTATION_BINS
_SCALE_BIN = 0.2  # 0.2 of log scale (22 %),
_POSITION_BIN = 0.25  # a quarter of the view's radius (at the pose's scale) for where its centre lands
_SLOTS_PER_HYPOTHESIS = 64  # a view's accumulator region: each hypothesis votes 16 bins, so a slot holds
# at most a quarter of a vote of other poses' on average, below the caps (one table of fixed size shared by
# all views let a large model's hypotheses bury a small model's pose under collisions)
_MIN_REGION_BITS, _MAX_REGION_BITS = 6, 24
_MAX_SLOTS = 1 << 27  # the whole accumulator's most slots (512 MB): past it the largest regions shrink
_COUNT_BINS = 1024  # the vote counts the cutoffs are read from; the last holds 1023 votes and more
_MIN_SEPARATION = 4.0  # pixels: closer corners are one junction's, with no direction between them


def corner_pairs(corners: np.ndarray, *, neighbours: int = 8, groups: np.ndarray | None = None) -> np.ndarray:
    """Ordered pairs (i, j) of corners: each corner with its ``neighbours`` nearest (at least 4 px away),
    and, given ``groups`` (a label per corner, -1 for none), with its ``neighbours`` nearest of its own
    group (every two corners of a group of at most ``neighbours`` + 1).

    Pairing every two corners of a group, however large, made a textured region of 800 corners 640,000
    pairs, whose chance poses outvoted the object's; the nearest are found on a k-d tree, in O(n log n)
    memory and time rather than the n x n distances.

    Returns
    -------
    int64 (P, 2), each unordered pair in both orders, no pair twice.
    """
    corners = points(corners, "corners")
    n = len(corners)
    neighbours = check_int(neighbours, "neighbours", minimum=0)
    if groups is not None and (not isinstance(groups, np.ndarray) or groups.dtype.kind not in "iu"
                               or groups.shape != (n,)):
        raise InputValueError(f"groups must be an integer ({n},) array, one label per corner")
    if n < 2:
        return np.zeros((0, 2), np.int64)
    found = [_nearest_pairs(corners, np.arange(n), neighbours)]
    if groups is not None:
        labels = np.asarray(groups)
        for label in np.unique(labels[labels >= 0]):
            found.append(_nearest_pairs(corners, np.flatnonzero(labels == label), neighbours))
    pairs = np.concatenate(found)
    pairs = np.concatenate([pairs, pairs[:, ::-1]])
    return np.unique(pairs, axis=0).astype(np.int64)


def _nearest_pairs(corners: np.ndarray, members: np.ndarray, k: int) -> np.ndarray:
    """(i, j) rows: each of ``members`` with its ``k`` nearest other members at least _MIN_SEPARATION away
    (among members equally near at the k-th place, the k-d tree decides which are taken)."""
    k = min(k, len(members) - 1)
    if k < 1:
        return np.zeros((0, 2), np.int64)
    at = corners[members]
    tree = cKDTree(at)
    # Enough candidates that k of them lie beyond the separation: the closest ones may not.
    close = tree.query_ball_point(at, np.nextafter(_MIN_SEPARATION, 0), return_length=True)
    reach = min(len(members), k + int(close.max()))
    distance, index = tree.query(at, k=reach)
    distance, index = distance.reshape(len(members), reach), index.reshape(len(members), reach)
    order = np.lexsort((index, distance), axis=1)  # stable among equal distances: the lower index first
    distance, index = np.take_along_axis(distance, order, 1), np.take_along_axis(index, order, 1)
    far = (distance >= _MIN_SEPARATION) & (index < len(members))
    rank = np.cumsum(far, axis=1)
    take = far & (rank <= k)
    rows = np.repeat(np.arange(len(members)), reach).reshape(len(members), reach)
    return np.stack([members[rows[take]], members[index[take]]], axis=1)


def _coordinates(corners: np.ndarray, bisector: np.ndarray, opening: np.ndarray, radius: np.ndarray,
                 pairs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The four key coordinates of each pair, in bins (continuous), and which are cyclic: for a corner, its
    bisector's direction from the line A -> B and its opening; for an arc, the log of its radius over the
    pair's length and the arc mark."""
    a, b = pairs[:, 0], pairs[:, 1]
    step = corners[b] - corners[a]
    line = np.arctan2(step[:, 1], step[:, 0])
    length = np.hypot(step[:, 0], step[:, 1])
    turn = 2 * math.pi / ANGLE_BINS
    width = math.pi / OPENING_BINS
    ratio_bin = (_RATIO_HIGH - _RATIO_LOW) / ANGLE_BINS
    coords, cyclic = [], []
    for member in (a, b):
        arc = np.isfinite(radius[member])
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = (np.log(radius[member] / length) - _RATIO_LOW) / ratio_bin
        coords.append(np.where(arc, ratio, np.mod(bisector[member] - line, 2 * math.pi) / turn))
        cyclic.append(~arc)
    for member in (a, b):
        arc = np.isfinite(radius[member])
        # An arc's mark sits mid-bin; _bins puts its second-nearest bin back on the mark.
        coords.append(np.where(arc, _ARC_MARK + 0.5, np.minimum(opening[member] / width, OPENING_BINS - 1e-9)))
    return np.stack(coords, axis=1), np.stack(cyclic, axis=1)


def _flatten(bins: np.ndarray) -> np.ndarray:
    return ((bins[..., 0] * ANGLE_BINS + bins[..., 1]) * _KINDS + bins[..., 2]) * _KINDS + bins[..., 3]


def _bins(bins: np.ndarray, cyclic: np.ndarray, marks: np.ndarray) -> np.ndarray:
    """Bins in range: the angle coordinates wrapped where cyclic (a corner's) or clipped (an arc's ratio),
    the openings clipped to the corners' bins, an arc's mark kept."""
    angle = np.where(cyclic, np.mod(bins[..., :2], ANGLE_BINS), np.clip(bins[..., :2], 0, ANGLE_BINS - 1))
    kind = np.where(marks, _ARC_MARK, np.clip(bins[..., 2:], 0, OPENING_BINS - 1))
    return np.concatenate([angle, kind], axis=-1)


def pair_keys(corners: np.ndarray, bisector: np.ndarray, opening: np.ndarray, pairs: np.ndarray, *,
              radius: np.ndarray | None = None, soft: bool = False) -> np.ndarray:
    """The invariant key of each ordered feature pair.

    Parameters
    ----------
    corners, bisector, opening : arrays
        As :class:`vmcl.recognize.features.Features` holds them (or :func:`anchors_of` gives them, arcs
        among them).
    pairs : int (P, 2)
    radius : float (F,) array, optional
        NaN for a corner; for an arc (its row of ``corners`` the circle's centre, its bisector and opening
        unused), its radius in pixels (> 0). Default: every row a corner.
    soft : bool
        Each pair's keys in the two nearest bins of every coordinate (16 keys, (P, 16)), as the library's
        table enters them; otherwise the one bin it falls in, (P,).

    Returns
    -------
    int32 (P,) or (P, 16)
    """
    corners = points(corners, "corners")
    bisector = angles(bisector, "bisector", len(corners), "corners")
    opening = angles(opening, "opening", len(corners), "corners", low=0.0, high=math.pi)
    radius = _radii(radius, len(corners))
    pairs = index_pairs(pairs, "pairs", len(corners))
    soft = check_bool(soft, "soft")
    if len(pairs) and (np.isfinite(radius[pairs]).any(axis=1)
                       & np.all(corners[pairs[:, 0]] == corners[pairs[:, 1]], axis=1)).any():
        raise InputValueError("pairs must join features at distinct points where an arc takes part (its "
                              "radius is measured against the pair's length)")
    coords, cyclic = _coordinates(corners, bisector, opening, radius, pairs)
    marks = np.isfinite(radius[pairs])
    home = np.floor(coords).astype(np.int64)
    if not soft:
        return _flatten(_bins(home, cyclic, marks)).astype(np.int32)
    other = np.where(coords - home >= 0.5, home + 1, home - 1)
    combos = np.array([[(c >> d) & 1 for d in range(4)] for c in range(16)], bool)  # (16, 4)
    bins = np.where(combos[None], other[:, None, :], home[:, None, :])
    return _flatten(_bins(bins, cyclic[:, None, :], marks[:, None, :])).astype(np.int32)


def _radii(radius: Any, count: int) -> np.ndarray:
    if radius is None:
        return np.full(count, np.nan)
    radius = angles(radius, "radius", count, "corners", unknown=True)
    if (radius <= 0).any():
        raise InputValueError("radius must hold NaN (a corner) or an arc's radius > 0")
    return radius


def anchors_of(features: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The features indexing pairs: a :class:`vmcl.recognize.features.Features`' or a model
    :class:`vmcl.recognize.models.View`'s corners, then its arcs' centres.

    Returns
    -------
    points : float64 (F + A, 2)
    bisector, opening : float64 (F + A,)
        The corners'; 0 for the arcs (unused).
    radius : float64 (F + A,)
        NaN for the corners, the arcs' radii.
    """
    if not isinstance(features, (Features, View)):
        raise InputTypeError("features must be vmcl.recognize.Features or a vmcl.recognize.View, got "
                             f"{type(features).__name__}")
    arcs = np.asarray(features.arcs, np.float64).reshape(-1, 2)
    zeros = np.zeros(len(arcs))
    return (np.concatenate([features.corners.reshape(-1, 2), arcs]), np.concatenate([features.bisector, zeros]),
            np.concatenate([features.opening, zeros]),
            np.concatenate([np.full(len(features.corners), np.nan), np.asarray(features.arc_radius, np.float64)]))


@dataclass(frozen=True, eq=False)
class Index:
    """A library's table: for every key, the model views' feature pairs (corners and arcs) that have it.

    Attributes
    ----------
    offsets : int32 (KEYS + 1,)
        Key k's entries are ``offsets[k]:offsets[k + 1]``.
    entry_view : int32 (E,)
        The view (a row of ``views``) of each entry.
    entry_points : float32 (E, 4)
        The entry's features A and B (Ax, Ay, Bx, By: a corner, or an arc's centre) in the view's frame.
    frames : float32 (V, 4)
        Each view's centre (x, y) and radius.
    views : int32 (V, 2)
        Each view's (model, view) in the library.
    """

    offsets: np.ndarray
    entry_view: np.ndarray
    entry_points: np.ndarray
    frames: np.ndarray
    views: np.ndarray

    @classmethod
    def build(cls, library: Library, *, neighbours: int = 8) -> Index:
        """The table of every view of ``library``, each feature (corner or arc) paired with its ``neighbours``
        nearest."""
        if not isinstance(library, Library):
            raise InputTypeError(f"library must be a vmcl.recognize.Library, got {type(library).__name__}")
        neighbours = check_int(neighbours, "neighbours", minimum=1, maximum=1000)
        keys, views, pair_points = [], [], []
        frames, ids = [], []
        for row, (m, v, view) in enumerate(library.views()):
            frames.append([*view.centre, view.radius, 0.0])
            ids.append((m, v))
            at, bisector, opening, radius = anchors_of(view)
            pairs = corner_pairs(at, neighbours=neighbours)
            if not len(pairs):
                continue
            k = pair_keys(at, bisector, opening, pairs, radius=radius, soft=True)
            keys.append(k.ravel())
            views.append(np.full(k.size, row, np.int32))
            p = np.concatenate([at[pairs[:, 0]], at[pairs[:, 1]]], axis=1)
            pair_points.append(np.repeat(p, k.shape[1], axis=0))
        key = np.concatenate(keys) if keys else np.zeros(0, np.int32)
        # A pair entered twice under one key (its soft bins clipped to the same edge bin) votes once.
        entry_view = np.concatenate(views) if views else np.zeros(0, np.int32)
        entry_points = (np.concatenate(pair_points) if pair_points else np.zeros((0, 4))).astype(np.float32)
        unique = np.unique(np.column_stack([key, entry_view, entry_points.view(np.int32)]), axis=0,
                           return_index=True)[1]
        order = unique[np.argsort(key[unique], kind="stable")]
        counts = np.bincount(key[order], minlength=KEYS)
        offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int32)
        return cls(offsets, entry_view[order], entry_points[order], np.array(frames, np.float32).reshape(-1, 4),
                   np.array(ids, np.int32).reshape(-1, 2))

    def __len__(self) -> int:
        return len(self.entry_view)


@dataclass(frozen=True)
class Candidates:
    """What :func:`vote` returns: candidate poses, most votes first.

    Attributes
    ----------
    views : int32 (C,)
        The row of :attr:`Index.views` (the model and view) of each candidate.
    similarity : float64 (C, 4)
        Each candidate's similarity (zr, zi, tx, ty): x' = zr x - zi y + tx, y' = zi x + zr y + ty.
    votes : int32 (C,)
    """

    views: np.ndarray
    similarity: np.ndarray
    votes: np.ndarray

    def __len__(self) -> int:
        return len(self.views)

    def matrices(self) -> np.ndarray:
        """Each candidate's similarity as a 2 x 3 affine matrix, (C, 2, 3)."""
        zr, zi, tx, ty = self.similarity.T
        return np.stack([np.stack([zr, -zi, tx], 1), np.stack([zi, zr, ty], 1)], 1)


def _check_inputs(index: Any, corners: Any, bisector: Any, opening: Any, pairs: Any, scales: Any, candidates: Any,
                  min_votes: Any, radius: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                                                        tuple[float, float], int, int]:
    if not isinstance(index, Index):
        raise InputTypeError(f"index must be a vmcl.recognize.Index, got {type(index).__name__}")
    corners = points(corners, "corners")
    bisector = angles(bisector, "bisector", len(corners), "corners")
    opening = angles(opening, "opening", len(corners), "corners", low=0.0, high=math.pi)
    radius = _radii(radius, len(corners))
    pairs = index_pairs(pairs, "pairs", len(corners))
    if not isinstance(scales, (tuple, list)) or len(scales) != 2:
        raise InputTypeError(f"scales must be a pair (low, high), got {scales!r}")
    low, high = (check_real(v, "scales", above=0, maximum=1e6) for v in scales)
    if low > high:
        raise InputValueError(f"scales must be (low, high) with low <= high, got {scales!r}")
    return (corners, bisector, opening, radius, pairs, (low, high),
            check_int(candidates, "candidates", minimum=1, maximum=MAX_CANDIDATES),
            check_int(min_votes, "min_votes", minimum=1, maximum=2**31 - 1))


def _pair_points(corners: np.ndarray, pairs: np.ndarray) -> np.ndarray:
    return np.concatenate([corners[pairs[:, 0]], corners[pairs[:, 1]]], axis=1).astype(np.float32)


def _looked_up(index: Index, keys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every (image pair, table entry) a lookup meets: the pair's row and the entry's, entry by entry."""
    starts, stops = index.offsets[keys], index.offsets[keys + 1]
    lengths = (stops - starts).astype(np.int64)
    which = np.repeat(np.arange(len(keys)), lengths)
    entries = np.repeat(starts - np.concatenate([[0], np.cumsum(lengths)[:-1]]), lengths) + np.arange(lengths.sum())
    return which, entries


def _regions(index: Index, entries: np.ndarray, most_slots: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each view's region of the accumulator, sized to its hypotheses: the regions' first slots (V + 1,
    the last the accumulator's size), their masks (V,) and each view's hypotheses (V,). A view no lookup
    met gets no slots (its region starts where the next one does)."""
    hypotheses = np.bincount(index.entry_view[entries], minlength=len(index.views))
    live = hypotheses > 0
    slots = np.maximum(hypotheses * float(_SLOTS_PER_HYPOTHESIS), 1.0)
    wanted = np.clip(np.ceil(np.log2(slots)), _MIN_REGION_BITS, _MAX_REGION_BITS).astype(np.int64)
    # The largest cap on a region's size that keeps the whole within `most_slots`: more collisions in the
    # largest regions rather than memory the device lacks.
    for cap in range(_MAX_REGION_BITS, _MIN_REGION_BITS - 1, -1):
        bits = np.minimum(wanted, cap)
        if int((np.left_shift(1, bits) * live).sum()) <= most_slots:
            break
    sizes = np.where(live, np.left_shift(1, bits), 0)
    starts = np.concatenate([[0], np.cumsum(sizes)]).astype(np.uint32)
    return starts, np.maximum(sizes - 1, 0).astype(np.uint32), hypotheses


def _trimmed(view: np.ndarray, votes: np.ndarray, bins: np.ndarray, views: int, min_votes: int) -> np.ndarray:
    """Every view's histogram of its bins by their votes, from its filled entries (each a view, a vote count
    (the last, _COUNT_BINS - 1, holding that many votes and more) and the view's bins with it; a view no
    lookup met has none), cut after the highest vote count any bin has (and past ``min_votes``), so that
    the cutoffs' arithmetic spans what is there: a column of zeros stays last, and a last column that is
    not cut holds the bins with that many votes and more."""
    columns = min(_COUNT_BINS, max(int(votes.max(initial=0)), min_votes) + 2)
    counts = np.zeros((views, columns), np.int64)
    counts[view, votes] = bins
    return counts


def _cutoffs(counts: np.ndarray, candidates: int, min_votes: int) -> tuple[np.ndarray, np.ndarray]:
    """The votes a bin of each view needs to be kept, and each view's share of the kept bins, from the
    views' histograms of their bins' votes (``counts[view, v]``: the view's bins with v votes, v >= 1;
    the last column those with more too).

    The ``candidates`` are shared between the views as water fills vessels: each view keeps its best bins
    (of those with at least ``min_votes``) up to one share, the same for all, and a view with fewer bins
    leaves the rest to the others; the shares add up to ``candidates`` (or to every usable bin, where
    there are fewer). One cutoff for all views let a model with many features, which gathers many votes by
    chance everywhere, crowd the other models' poses out. The cutoff keeps every bin tied with a view's
    last; :func:`_within_shares` cuts those ties after pooling."""
    columns = counts.shape[1]
    at_least = np.cumsum(counts[:, ::-1], axis=1)[:, ::-1]  # [view, v]: the view's bins with >= v votes
    usable = at_least[:, min(min_votes, columns - 1)]
    wanted = min(candidates, int(usable.sum()))
    low, high = 1, max(int(usable.max(initial=0)), 1)
    while low < high:  # the least share that keeps `wanted` bins in all
        middle = (low + high) // 2
        if int(np.minimum(middle, usable).sum()) >= wanted:
            high = middle
        else:
            low = middle + 1
    share = np.minimum(low, usable)
    # The least share can overshoot `wanted` by one bin for each view that takes it whole: those views,
    # the last first, give one back, so that the shares add up to exactly `wanted`.
    full = np.flatnonzero(share == low)
    share[full[::-1][:max(int(share.sum()) - wanted, 0)]] -= 1
    reach = at_least[:, 1:] >= np.maximum(share, 1)[:, None]
    # The highest v (>= 1) at which the view still has its share of bins.
    own = reach.shape[1] - np.argmax(reach[:, ::-1], axis=1)
    return np.maximum(own, min_votes).astype(np.int32), share


def _within_shares(found: Candidates, shares: np.ndarray) -> Candidates:
    """The pooled candidates cut to each view's share: its most voted first, ties in the order of their
    bins (a view keeps every bin tied with its last, so without the cut many views with a few bins of
    equal votes kept several times ``candidates`` between them)."""
    rank = np.lexsort((np.arange(len(found.views)), found.views))  # each view's candidates, in vote order
    sorted_views = found.views[rank]
    first = np.searchsorted(sorted_views, sorted_views, side="left")
    place = np.empty(len(rank), np.int64)
    place[rank] = np.arange(len(rank)) - first
    keep = place < shares[found.views]
    return Candidates(found.views[keep], found.similarity[keep], found.votes[keep])


def _filled(histograms: np.ndarray, rows: np.ndarray, live: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The filled entries of the device's histogram rows (row i ``histograms[rows[i]:rows[i + 1]]``, the
    view ``live[i]``'s) as :func:`_trimmed` takes them. A row shorter than _COUNT_BINS reaches past the most
    votes its view's slots can hold, so its last entry holds exactly that many."""
    filled = np.flatnonzero(histograms)
    row = np.searchsorted(rows, filled, side="right") - 1
    return live[row], filled - rows[row], histograms[filled].astype(np.int64)


def _capacity(counts: np.ndarray, cutoffs: np.ndarray, hypotheses: np.ndarray) -> int:
    """The most hypotheses the emit pass can write: each writes once, to a kept bin of its own view, so
    no more than a view's kept bins' votes (all its hypotheses where its bins' counts saturate the
    histogram, their votes unknown)."""
    v = np.arange(counts.shape[1])
    kept_votes = (counts * v * (v[None, :] >= cutoffs[:, None])).sum(axis=1)
    bound = np.where(counts[:, -1] > 0, hypotheses, np.minimum(kept_votes, hypotheses))
    return max(int(bound.sum()), 1)


def _no_candidates() -> Candidates:
    return _pool(np.zeros((0, 4)), np.zeros((0, 2), np.int32))


def _pool(found: np.ndarray, info: np.ndarray) -> Candidates:
    """Each (bin, view)'s hypotheses pooled into one candidate: the median similarity, the count as votes."""
    if not len(info):
        return Candidates(np.zeros(0, np.int32), np.zeros((0, 4)), np.zeros(0, np.int32))
    info = np.asarray(info, np.int64)
    order = np.argsort((info[:, 0] << 32) | info[:, 1], kind="stable")  # by bin, then view (both >= 0)
    info, found = info[order], np.asarray(found, np.float32)[order]
    starts = np.flatnonzero(np.concatenate([[True], np.any(info[1:] != info[:-1], axis=1)]))
    stops = np.append(starts[1:], len(info))
    views = info[starts, 1].astype(np.int32)
    votes = (stops - starts).astype(np.int32)
    # Each group's median, column by column: its values sorted within the group (one sort of the group's
    # number above each value's order-keeping bits), the middle one (or two).
    group = np.repeat(np.arange(len(starts), dtype=np.uint64), votes)
    ranked = _float32_of(np.sort((group[:, None] << np.uint64(32)) | _ordered_bits(found), axis=0))
    low, high = starts + (votes - 1) // 2, starts + votes // 2
    similarity = 0.5 * (ranked[low].astype(np.float64) + ranked[high])
    rank = np.lexsort((views, -votes))
    return Candidates(views[rank], similarity[rank], votes[rank])


def _ordered_bits(values: np.ndarray) -> np.ndarray:
    """float32 values as uint64 whose order is the values' (the sign bit flipped for positives, every bit
    for negatives), in the low 32 bits."""
    bits = values.view(np.uint32).astype(np.uint64)
    return np.where(bits >> np.uint64(31), bits ^ np.uint64(0xFFFFFFFF), bits | np.uint64(0x80000000))


def _float32_of(ordered: np.ndarray) -> np.ndarray:
    """The float32 values :func:`_ordered_bits` keeps in the low 32 bits of ``ordered``."""
    bits = ordered & np.uint64(0xFFFFFFFF)
    return np.where(bits >> np.uint64(31), bits ^ np.uint64(0x80000000), bits ^ np.uint64(0xFFFFFFFF)).astype(
        np.uint32).view(np.float32)


def vote(index: Index, corners: np.ndarray, bisector: np.ndarray, opening: np.ndarray, pairs: np.ndarray, *,
         radius: np.ndarray | None = None, scales: tuple[float, float] = (0.25, 4.0), candidates: int = 1024,
         min_votes: int = 2, machine: Machine | None = None) -> Candidates:
    """Candidate poses of the library's views in an image, by geometric hashing on the device.

    Parameters
    ----------
    index : Index
    corners, bisector, opening : arrays
        The image's corners (:class:`vmcl.recognize.features.Features`), or its corners and arcs
        (:func:`anchors_of`).
    pairs : int (P, 2)
        The ordered feature pairs to look up (:func:`corner_pairs`).
    radius : float (F,) array, optional
        NaN for a corner, an arc's radius (:func:`pair_keys`). Default: every row a corner.
    scales : (float, float)
        The range of scales (image size over view size) a pose may have.
    candidates : int
        The pose bins kept, >= 1, shared between the model views: each view keeps its own best bins up to
        an equal share, a view with fewer leaving the rest to the others (among bins of equal votes, those
        of the lowest addresses in the view's table; at most ``candidates`` come back in all). A
        model with many features, which gathers many votes by chance everywhere, thus cannot take the
        other views' shares, but each view's share shrinks as the library grows, and an object whose true
        pose ranks low among its own view's bins can then be lost; a view of a solid is a view like any
        other. The default is :func:`vmcl.recognize.recognize`'s, fitted on rendered training scenes.
    min_votes : int
        The fewest votes a kept bin has, >= 1 (each corner correspondence votes twice, once per order).
    machine : vmcl.Machine, optional

    Returns
    -------
    Candidates
    """
    machine = machine_for(machine)
    corners, bisector, opening, radius, pairs, (low, high), candidates, min_votes = _check_inputs(
        index, corners, bisector, opening, pairs, scales, candidates, min_votes, radius)
    if not len(pairs) or not len(index):
        return _no_candidates()
    host_keys = pair_keys(corners, bisector, opening, pairs, radius=radius)
    which, entries = _looked_up(index, host_keys)
    if not len(entries):  # no pair's key is in the library's table
        return _no_candidates()
    most_slots = min(_MAX_SLOTS, machine.device.max_mem_alloc_size // 4)
    starts, masks, hypotheses = _regions(index, entries, most_slots)
    live = np.flatnonzero(hypotheses > 0)
    # Each live view's histogram row: a slot holds at most 16 votes of each of the view's hypotheses.
    lengths = np.minimum(_COUNT_BINS, 16 * hypotheses[live] + 1)
    rows = np.concatenate([[0], np.cumsum(lengths)])
    # The accumulator, the hits (2 words each) and their kept bins, similarities and first votes (16 + 4 + 1/2
    # words), the histograms.
    words = int(starts[-1]) + 23 * len(entries) + int(rows[-1])
    machine.require_memory("the vote's accumulator", 4 * words,
                           4 * max(int(starts[-1]), 16 * len(entries), int(rows[-1])))
    hits = machine.to_device(np.stack([which, entries], axis=1).astype(np.int32))
    votes = machine.full(int(starts[-1]), np.int32, 0)
    hit_bins = machine.empty(16 * len(entries), np.uint32)
    hit_similarity = machine.empty((len(entries), 4), np.float32)
    hit_first = machine.empty(len(entries), np.uint16)
    entry_view, entry_points, frames = _device_table(index, machine)
    machine.launch(machine.kernel("indexing", "vote"), (len(entries),), hits,
                   machine.to_device(_pair_points(corners, pairs)), entry_view, entry_points, frames,
                   machine.to_device(np.ascontiguousarray(np.stack([starts[:-1], masks], axis=1))), votes, hit_bins,
                   hit_similarity, hit_first, np.int32(len(entries)), np.float32(_ROTATION_BIN), np.int32(_ROTATION_BINS),
                   np.float32(_SCALE_BIN), np.float32(_POSITION_BIN), np.float32(low), np.float32(high))
    # The histograms of the views the lookups met, one row each (the others have no slots).
    histograms = machine.full(int(rows[-1]), np.int32, 0)
    view_rows = np.zeros((len(hypotheses), 2), np.int32)
    view_rows[live] = np.stack([rows[:-1], lengths], axis=1)
    machine.launch(machine.kernel("indexing", "vote_counts"), (len(entries),), hits, entry_view, votes, hit_bins,
                   hit_first, machine.to_device(view_rows), histograms, np.int32(len(entries)))
    view, filled_votes, bins_with = _filled(histograms.get(), rows, live)
    counts = _trimmed(view, filled_votes, bins_with, len(hypotheses), min_votes)
    cutoffs, shares = _cutoffs(counts, candidates, min_votes)
    capacity = _capacity(counts, cutoffs, hypotheses)
    device_cutoffs = machine.to_device(cutoffs)
    count = machine.empty(1, np.int32)  # zeroed before each emit pass
    while True:
        found, info = machine.empty((capacity, 4), np.float32), machine.empty((capacity, 2), np.int32)
        machine.fill(count, 0)
        machine.launch(machine.kernel("indexing", "vote_emit"), (len(entries),), hits, entry_view, votes, hit_bins,
                       hit_similarity, device_cutoffs, count, found, info, np.int32(len(entries)),
                       np.int32(capacity))
        n = int(count.get()[0])
        if n <= capacity:
            break
        capacity = n  # the bound above holds; were it ever to fail, the list is made long enough, not cut
    if not n:
        return _no_candidates()
    return _within_shares(_pool(found[:n].get(), info[:n].get()), shares)


def _device_table(index: Index, machine: Machine) -> tuple[cl_array.Array, ...]:
    def upload() -> tuple[cl_array.Array, ...]:
        return tuple(machine.to_device(a) for a in (index.entry_view,
                                                     np.ascontiguousarray(index.entry_points),
                                                     np.ascontiguousarray(index.frames)))
    cache = index.__dict__.setdefault("_device", {})
    if id(machine) not in cache:
        cache[id(machine)] = (machine, upload())
    return cache[id(machine)][1]


def _coordinates_numpy(image: np.ndarray, model: np.ndarray, frames: np.ndarray, views: np.ndarray,
                       low: float, high: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """kernels/indexing.cl's pose_coordinates over arrays (float32, as the kernel computes): (in range,
    similarities (n, 4), pose coordinates in bins (n, 4))."""
    f32 = np.float32
    mx, my = model[:, 2] - model[:, 0], model[:, 3] - model[:, 1]
    ix, iy = image[:, 2] - image[:, 0], image[:, 3] - image[:, 1]
    norm = mx * mx + my * my
    with np.errstate(divide="ignore", invalid="ignore"):
        zr, zi = (ix * mx + iy * my) / norm, (iy * mx - ix * my) / norm
        scale = np.sqrt(zr * zr + zi * zi)
        tx = image[:, 0] - (zr * model[:, 0] - zi * model[:, 1])
        ty = image[:, 1] - (zi * model[:, 0] + zr * model[:, 1])
        frame = frames[views]
        cx = zr * frame[:, 0] - zi * frame[:, 1] + tx
        cy = zi * frame[:, 0] + zr * frame[:, 1] + ty
        cell = f32(_POSITION_BIN) * frame[:, 2] * scale
        coords = np.stack([(np.arctan2(zi, zr) + f32(math.pi)) / f32(_ROTATION_BIN), np.log(scale) / f32(_SCALE_BIN),
                           cx / cell, cy / cell], axis=1)
    ok = (norm > 0) & (scale >= low) & (scale <= high)
    return ok, np.stack([zr, zi, tx, ty], axis=1), coords


def _combo_bins(coords: np.ndarray, views: np.ndarray, starts: np.ndarray, masks: np.ndarray) -> np.ndarray:
    """kernels/indexing.cl's combo_bins: (n, 16) addresses, each in its view's region."""
    home = np.floor(coords)
    other = np.where(coords - home >= 0.5, home + 1, home - 1)
    combos = np.array([[(c >> d) & 1 for d in range(4)] for c in range(16)], bool)
    bins = np.where(combos[None], other[:, None, :], home[:, None, :]).astype(np.int64)
    bins[..., 0] = np.mod(bins[..., 0], _ROTATION_BINS)
    ints = [bins[..., d].astype(np.uint32) for d in range(4)]
    h = np.repeat(views.astype(np.uint32)[:, None] * np.uint32(73856093), 16, axis=1)
    for value, prime in zip(ints, (19349663, 83492791, 2654435761, 40503)):
        h ^= value * np.uint32(prime) + np.uint32(0x9E3779B9) + (h << np.uint32(6)) + (h >> np.uint32(2))
    return starts[views].astype(np.int64)[:, None] + (h & masks[views][:, None]).astype(np.int64)


def vote_numpy(index: Index, corners: np.ndarray, bisector: np.ndarray, opening: np.ndarray, pairs: np.ndarray, *,
               radius: np.ndarray | None = None, scales: tuple[float, float] = (0.25, 4.0), candidates: int = 1024,
               min_votes: int = 2) -> Candidates:
    """:func:`vote` in NumPy on the host: the reference the kernel is tested and timed against."""
    corners, bisector, opening, radius, pairs, (low, high), candidates, min_votes = _check_inputs(
        index, corners, bisector, opening, pairs, scales, candidates, min_votes, radius)
    if not len(pairs) or not len(index):
        return _no_candidates()
    keys = pair_keys(corners, bisector, opening, pairs, radius=radius)
    points = _pair_points(corners, pairs)
    which, entries = _looked_up(index, keys)
    if not len(entries):
        return _no_candidates()
    starts, masks, hypotheses = _regions(index, entries, _MAX_SLOTS)
    views = index.entry_view[entries]
    ok, similarity, coords = _coordinates_numpy(points[which], index.entry_points[entries], index.frames, views,
                                                np.float32(low), np.float32(high))
    bins = _combo_bins(coords[ok], views[ok], starts, masks)
    addresses, totals = np.unique(bins.ravel(), return_counts=True)
    votes = np.zeros(int(starts[-1]), np.int64)
    votes[addresses] = totals
    # Each filled slot's view: the last region starting at or before it (empty regions share a start).
    region = np.searchsorted(starts[:-1], addresses, side="right") - 1
    filled, bins_with = np.unique(region * _COUNT_BINS + np.minimum(totals, _COUNT_BINS - 1), return_counts=True)
    counts = _trimmed(filled // _COUNT_BINS, filled % _COUNT_BINS, bins_with, len(hypotheses), min_votes)
    cutoffs, shares = _cutoffs(counts, candidates, min_votes)
    # Each hypothesis's best bin: the most votes, the lowest address among equals.
    order = np.lexsort((bins, -votes[bins]), axis=1) if len(bins) else np.zeros((0, 16), np.int64)
    best = np.take_along_axis(bins, order[:, :1], axis=1)[:, 0]
    keep = votes[best] >= cutoffs[views[ok]]
    return _within_shares(_pool(similarity[ok][keep], np.stack([best[keep], views[ok][keep]], axis=1)), shares)


def index_for(library: Library, *, neighbours: int = 8) -> Index:
    """The library's :class:`Index`, built once per library and ``neighbours``."""
    if not isinstance(library, Library):
        raise InputTypeError(f"library must be a vmcl.recognize.Library, got {type(library).__name__}")
    neighbours = check_int(neighbours, "neighbours", minimum=1, maximum=1000)
    return library.cached(("index", neighbours), lambda: Index.build(library, neighbours=neighbours))

