"""Detected points (junctions, corners) against true ones: one-to-one matching within a tolerance, and the
junctions of human segmentations.

A detection is right when it is matched, one to one, to a true point within the tolerance (the matching
that matches the most, nearest first among equals: a linear assignment on the distances); true points a
method is not asked for can be set aside (``ignore``), and detections near them count neither way.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from vmcl.cm.core import check_real, real_host_array, to_host
from vmcl.errors import InputValueError
from vmcl.metrics._rates import f_measure
from vmcl.metrics.detections import DetectionScores

__all__ = ["match_points", "point_scores", "segmentation_junctions"]


def _points(x, name: str) -> np.ndarray:
    if isinstance(x, (list, tuple)):
        try:
            x = np.asarray(x, dtype=float)
        except (TypeError, ValueError):
            raise InputValueError(f"{name} must be (N, 2) points (x, y): a list of pairs of numbers") from None
    points = real_host_array(to_host(x, name), name, ndims=(2,), empty=True).astype(float)
    if points.shape[1:] != (2,) and points.shape != (0, 0):
        raise InputValueError(f"{name} must be (N, 2) points (x, y), got shape {points.shape}")
    if not np.isfinite(points).all():
        raise InputValueError(f"{name} holds NaN or infinite coordinates")
    return points.reshape(-1, 2)


def one_to_one(cost: np.ndarray, feasible: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """As many one-to-one (row, column) pairs among the ``feasible`` as can be made, of least total
    ``cost`` among those (a greedy pass, row after row, can take the column a later row needed)."""
    top = float(cost[feasible].max()) if feasible.any() else 1.0
    scaled = cost / top if np.isfinite(top) and top > 0 else np.where(cost > 0, 1.0, 0.0)
    # An infeasible pair costs more than any set of feasible ones (each at most 1 once scaled), so the
    # assignment takes as many feasible pairs as there can be and, among those, the cheapest.
    rows, cols = linear_sum_assignment(np.where(feasible, scaled, 1.0 + min(cost.shape)))
    keep = feasible[rows, cols]
    return rows[keep], cols[keep]


def match_points(truth, found, *, tolerance: float) -> np.ndarray:
    """One-to-one matches of ``found`` to ``truth`` within ``tolerance``: int (M, 2) rows (truth index,
    found index), as many as can be made, nearest first among equally many.

    Parameters
    ----------
    truth, found : (N, 2) arrays of points (x, y)
    tolerance : float
        The farthest a match may be, >= 0.
    """
    truth, found = _points(truth, "truth"), _points(found, "found")
    tolerance = check_real(tolerance, "tolerance", minimum=0)
    if not len(truth) or not len(found):
        return np.zeros((0, 2), int)
    distance = np.linalg.norm(truth[:, None] - found[None], axis=2)
    rows, cols = one_to_one(distance, distance <= tolerance)
    return np.stack([rows, cols], axis=1)


def point_scores(truth, found, *, tolerance: float, ignore=None, exclude=None) -> DetectionScores:
    """Precision and recall of detected points within ``tolerance`` (:func:`match_points`).

    Parameters
    ----------
    truth, found : (N, 2) arrays of points (x, y)
    tolerance : float
    ignore : (K, 2) array of points, optional
        True points set aside: detections within ``tolerance`` of one, and not matched, count neither
        as right nor as wrong.
    exclude : (N,) bool array, optional
        Detections set aside (e.g. where the truth is not known): unless matched, they count neither as
        right nor as wrong.

    Returns
    -------
    DetectionScores
        With counts of points; precision over the detections that count.
    """
    truth, found = _points(truth, "truth"), _points(found, "found")
    matches = match_points(truth, found, tolerance=tolerance)
    counted = np.ones(len(found), bool)
    if ignore is not None and len(found):
        aside = _points(ignore, "ignore")
        if len(aside):
            near = np.linalg.norm(found[:, None] - aside[None], axis=2).min(axis=1) <= tolerance
            counted &= ~near
    if exclude is not None:
        excluded = np.asarray(exclude)
        if excluded.dtype != bool or excluded.shape != (len(found),):
            raise InputValueError(f"exclude must be a bool array of one value per found point ({len(found)}), "
                                  f"got {excluded.dtype} of shape {excluded.shape}")
        counted &= ~excluded
    counted[matches[:, 1]] = True
    hits = len(matches)
    predicted = int(counted.sum())
    precision = hits / predicted if predicted else float("nan")
    recall = hits / len(truth) if len(truth) else float("nan")
    return DetectionScores(precision, recall, float(f_measure(precision, recall)), predicted, len(truth))


def segmentation_junctions(segmentation, *, merge: float = 2.0) -> np.ndarray:
    """Where three or more segments of a label map meet: float (N, 2) points (x, y).

    Every 2 x 2 block of pixels holding three or more labels marks its centre (a pixel corner); marks
    chained by steps of at most ``merge`` pixels are one junction, at their mean.

    Parameters
    ----------
    segmentation : (H, W) integer array
        A segmentation (e.g. one BSDS annotator's).
    merge : float
        >= 0.
    """
    labels = real_host_array(to_host(segmentation, "segmentation"), "segmentation", ndims=(2,))
    if labels.dtype.kind not in "biu":
        raise InputValueError(f"segmentation must hold integer labels, got dtype {labels.dtype}")
    merge = check_real(merge, "merge", minimum=0)
    if min(labels.shape) < 2:
        return np.zeros((0, 2))
    blocks = np.sort(np.stack([labels[:-1, :-1], labels[:-1, 1:], labels[1:, :-1], labels[1:, 1:]]), axis=0)
    distinct = 1 + np.count_nonzero(np.diff(blocks, axis=0), axis=0)
    marks = distinct >= 3
    if not marks.any():
        return np.zeros((0, 2))
    # Marks chained by steps of at most `merge` are one junction (single linkage). A dilation by merge / 2
    # with 8-connected labelling merged marks farther apart, and merged neighbours at merge = 0.
    rows, cols = np.nonzero(marks)
    points = np.stack([cols, rows], axis=1).astype(float)
    if merge >= math.hypot(*labels.shape):  # every two marks are within it: one junction (no pairs listed)
        return points.mean(axis=0, keepdims=True) + 0.5
    pairs = cKDTree(points).query_pairs(merge, output_type="ndarray")
    links = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(points),) * 2)
    count, group = connected_components(links, directed=False)
    sizes = np.bincount(group, minlength=count)
    centres = np.stack([np.bincount(group, points[:, k], minlength=count) / sizes for k in range(2)], axis=1)
    return centres + 0.5
