"""Boundaries: the BSDS benchmark's precision, recall and F-measure at ODS and OIS, and average precision.

At the optimal dataset scale (ODS) and the optimal image scale (OIS), with the benchmark's one-to-one
pixel matching (``correspondPixels``, taken from the maintained ``pyEdgeEval`` port of the official C++
code) and its thinning (Martin, Fowlkes and Malik 2004; Arbelaez et al. 2011).
"""

from __future__ import annotations

import multiprocessing
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass

import numpy as np

from vmcl.cm.core import check_bool, check_int, check_real, to_host
from vmcl.errors import InputTypeError, InputValueError
from vmcl.metrics._inputs import as_float_field, check_sequence
from vmcl.metrics._rates import f_measure, ratio

__all__ = ["BoundaryCounts", "BoundaryScores", "boundary_counts", "evaluate_boundaries"]

# More boundary thresholds than a 16-bit edge map has levels only repeat matchings, each a costly one.
_MAX_BOUNDARY_THRESHOLDS = 2**16


@dataclass(frozen=True)
class BoundaryCounts:
    """The BSDS benchmark's per-threshold counts for one image.

    Attributes
    ----------
    thresholds : (T,) array
        The thresholds applied to the edge map (``edge_map >= threshold``).
    matched_truth, total_truth : (T,) int arrays
        Ground-truth boundary pixels matched, and in all (summed over the annotators): recall counts.
    matched_predicted, total_predicted : (T,) int arrays
        Predicted (thinned) boundary pixels matched to some annotator, and in all: precision counts.
    """

    thresholds: np.ndarray
    matched_truth: np.ndarray
    total_truth: np.ndarray
    matched_predicted: np.ndarray
    total_predicted: np.ndarray

    @property
    def recall(self) -> np.ndarray:
        return ratio(self.matched_truth, self.total_truth)

    @property
    def precision(self) -> np.ndarray:
        return ratio(self.matched_predicted, self.total_predicted)

    @property
    def f(self) -> np.ndarray:
        return f_measure(self.precision, self.recall)


def _thresholds(thresholds) -> np.ndarray:
    if isinstance(thresholds, (int, np.integer)) and not isinstance(thresholds, (bool, np.bool_)):
        if not 1 <= thresholds <= _MAX_BOUNDARY_THRESHOLDS:
            raise InputValueError(f"thresholds must be a count in 1..{_MAX_BOUNDARY_THRESHOLDS} or a sequence, "
                                  f"got {thresholds}")
        n = int(thresholds)
        # The benchmark's own choice: n thresholds evenly inside (0, 1), ends excluded.
        return np.linspace(1.0 / (n + 1), 1.0 - 1.0 / (n + 1), n)
    values = np.asarray(thresholds) if isinstance(thresholds, (list, tuple, np.ndarray)) else None
    if values is None or values.dtype.kind not in "iuf":
        raise InputTypeError(f"thresholds must be a positive count or a sequence of numbers, got {thresholds!r}")
    if values.ndim != 1 or values.size == 0 or not np.isfinite(values).all():
        raise InputValueError("thresholds must be a positive count or a non-empty 1-D sequence of finite numbers")
    if np.any(np.diff(values) <= 0):
        raise InputValueError("thresholds must be strictly increasing")
    return values.astype(np.float64)


def _edge_map(edge_map) -> np.ndarray:
    edge_map = np.asarray(to_host(edge_map, "edge_map"))
    # A bool map is a map of 0s and 1s, checked for its shape like any other.
    edge_map = as_float_field(edge_map.astype(np.uint8) if edge_map.dtype == bool else edge_map, "edge_map", ndim=2)
    if np.isnan(edge_map).any():
        raise InputValueError("edge_map has NaN pixels; it must hold boundary strengths in [0, 1]")
    if edge_map.min() < 0 or edge_map.max() > 1:
        raise InputValueError("edge_map must hold boundary strengths in [0, 1] (an 8-bit map: divide by 255)")
    return edge_map


def _truth_boundaries(ground_truths, shape: tuple[int, int]) -> list[np.ndarray]:
    if isinstance(ground_truths, np.ndarray) and ground_truths.ndim == 2:
        # Its rows would be read as annotators' maps and refused for their shape, with no word of why.
        raise InputValueError(f"ground_truths must be a list of (H, W) boundary maps, one per annotator, or a "
                              f"(K, H, W) stack; got one (H, W) map {ground_truths.shape}: give [it]")
    truths = [np.asarray(to_host(g, "ground_truths")) for g in check_sequence(ground_truths, "ground_truths")]
    if not truths:
        raise InputValueError("ground_truths must hold at least one annotator's boundary map")
    for k, g in enumerate(truths):
        if g.dtype.kind not in "biuf":
            raise InputTypeError(f"ground_truths[{k}] must be a 0/1 or boolean boundary map, got dtype {g.dtype}")
        if g.shape != shape:
            raise InputValueError(f"ground_truths[{k}] has shape {g.shape}, edge_map has shape {shape}")
        if g.dtype != bool and not np.isin(g, (0, 1)).all():
            raise InputValueError(f"ground_truths[{k}] must be a 0/1 boundary map")
    return [g.astype(bool) for g in truths]


def boundary_counts(
    edge_map,
    ground_truths: Sequence,
    *,
    thresholds=99,
    max_dist: float = 0.0075,
    thin: bool = True,
) -> BoundaryCounts:
    """The BSDS benchmark's match counts for one image at every threshold.

    Parameters
    ----------
    edge_map : (H, W) array
        Boundary strength in [0, 1] (a boolean map is a single level).
    ground_truths : sequence of (H, W) arrays
        One 0/1 boundary map per human annotator (``groundTruth{k}.Boundaries``).
    thresholds : int or sequence of float
        A count n gives the benchmark's ``linspace(1/(n+1), 1 - 1/(n+1), n)``; or the thresholds.
    max_dist : float
        Match distance as a fraction of the image diagonal (the benchmark's 0.0075).
    thin : bool
        Thin each thresholded map to one-pixel lines first, as the benchmark does.

    Returns
    -------
    BoundaryCounts

    Notes
    -----
    For each threshold the map ``edge_map >= t`` is thinned (MATLAB's ``bwmorph(., 'thin', inf)``) and
    matched one-to-one to each annotator's boundaries by a minimum-cost assignment within ``max_dist``
    (``correspondPixels``); a predicted pixel counts as correct when it matches any annotator, and recall
    sums the matched pixels over all annotators. Thresholds that give the same binary map share one
    matching.

    The matcher, like the official C++ code it ports, adds randomly chosen outlier edges to its
    assignment graph (seeded from the clock), so the counts can differ by a pixel or so from run to
    run and the figures in the fourth decimal.

    References
    ----------
    D. Martin, C. Fowlkes and J. Malik, "Learning to detect natural image boundaries using local
    brightness, color, and texture cues", IEEE TPAMI 26(5):530-549, 2004.
    P. Arbelaez, M. Maire, C. Fowlkes and J. Malik, "Contour detection and hierarchical image
    segmentation", IEEE TPAMI 33(5):898-916, 2011.
    """
    try:
        from pyEdgeEval import correspond_pixels
        from pyEdgeEval.preprocess.thin import binary_thin
    except ImportError as error:
        raise ImportError("BSDS boundary matching needs pyEdgeEval: pip install pyEdgeEval") from error

    pb = _edge_map(edge_map)
    truths = _truth_boundaries(ground_truths, pb.shape)
    levels = _thresholds(thresholds)
    check_real(max_dist, "max_dist (a fraction of the diagonal)", above=0, below=1)
    thin = check_bool(thin, "thin")
    total_truth = sum(int(g.sum()) for g in truths)
    counts = np.zeros((4, levels.size), dtype=np.int64)
    previous_key, previous = None, None
    for i, level in enumerate(levels):
        binary = pb >= level
        if thin:
            binary = binary_thin(binary)
        key = binary.tobytes()
        if key != previous_key:
            matched_predicted = np.zeros(pb.shape, dtype=bool)
            matched_truth = 0
            if binary.any():
                for g in truths:
                    match_pred, match_truth, _, _ = correspond_pixels(binary, g, max_dist=max_dist)
                    matched_predicted |= match_pred > 0
                    matched_truth += int(np.count_nonzero(match_truth > 0))
            previous_key = key
            previous = (matched_truth, total_truth, int(matched_predicted.sum()), int(binary.sum()))
        # The first level's key differs from None, so it has always set `previous` by now.
        assert previous is not None
        counts[:, i] = previous
    return BoundaryCounts(levels, *counts)


def _interpolated_best(thresholds, recall, precision) -> tuple[float, float, float, float]:
    """The benchmark's maxF: the best F along straight lines between neighbouring thresholds."""
    best = (thresholds[0], recall[0], precision[0], float(f_measure(precision[0], recall[0])))
    # MATLAB's linspace(0, 1) has 100 points; the benchmark's figures depend on that grid.
    d = np.linspace(0.0, 1.0, 100)
    for i in range(1, len(thresholds)):
        t = thresholds[i] * d + thresholds[i - 1] * (1 - d)
        r = recall[i] * d + recall[i - 1] * (1 - d)
        p = precision[i] * d + precision[i - 1] * (1 - d)
        f = f_measure(p, r)
        j = int(np.argmax(f))
        if f[j] > best[3]:
            best = (t[j], r[j], p[j], float(f[j]))
    return float(best[0]), float(best[1]), float(best[2]), float(best[3])


@dataclass(frozen=True)
class BoundaryScores:
    """BSDS boundary scores of a set of images.

    Attributes
    ----------
    ods_threshold, ods_recall, ods_precision, ods_f : float
        At the optimal dataset scale: one threshold for all images (interpolated between thresholds).
    ois_recall, ois_precision, ois_f : float
        At the optimal image scale: each image at its own best threshold.
    average_precision : float
        Area under the dataset's precision-recall curve (the benchmark's ``Area_PR``).
    recall, precision, f : (T,) arrays
        The dataset's curve at each threshold.
    per_image : list of BoundaryCounts
        The counts of each image, in input order.
    """

    ods_threshold: float
    ods_recall: float
    ods_precision: float
    ods_f: float
    ois_recall: float
    ois_precision: float
    ois_f: float
    average_precision: float
    recall: np.ndarray
    precision: np.ndarray
    f: np.ndarray
    per_image: list[BoundaryCounts]

    def best_per_image(self) -> list[tuple[float, float, float, float]]:
        """Each image's (threshold, recall, precision, F) at its interpolated best F."""
        return [_interpolated_best(c.thresholds, c.recall, c.precision) for c in self.per_image]


def _average_precision(recall: np.ndarray, precision: np.ndarray) -> float:
    # MATLAB: [Ru, i] = unique(R); interp1(Ru, P(i), 0:0.01:1) with NaN outside set to 0.
    # MATLAB's unique keeps the last occurrence of a repeated value.
    order = np.argsort(recall, kind="stable")
    r_sorted = recall[order]
    last = np.append(r_sorted[1:] != r_sorted[:-1], True)
    r_unique, p_unique = r_sorted[last], precision[order][last]
    if r_unique.size < 2:
        return 0.0
    grid = np.linspace(0.0, 1.0, 101)
    inside = (grid >= r_unique[0]) & (grid <= r_unique[-1])
    return float(np.interp(grid[inside], r_unique, p_unique).sum() * 0.01)


def _counts_of(args) -> BoundaryCounts:
    edge_map, truths, kwargs = args
    return boundary_counts(edge_map, truths, **kwargs)


def evaluate_boundaries(
    edge_maps: Sequence,
    ground_truths: Sequence[Sequence | np.ndarray],
    *,
    thresholds=99,
    max_dist: float = 0.0075,
    thin: bool = True,
    workers: int = 1,
) -> BoundaryScores:
    """BSDS boundary benchmark: ODS, OIS and average precision over a set of images.

    Parameters
    ----------
    edge_maps : sequence of (H, W) arrays
        Boundary strength in [0, 1] per image.
    ground_truths : sequence of sequences of (H, W) arrays, or of (K, H, W) arrays
        Per image, the annotators' 0/1 boundary maps.
    thresholds : int or sequence of float
        As in :func:`boundary_counts`. The default, 99, is the benchmark's; each threshold costs one
        matching per annotator and image, which is most of the time (benchmarks/results/ground_truth.md
        times 10 BSDS images), so a quick check may use fewer.
    max_dist : float
        Match distance as a fraction of the image diagonal.
    thin : bool
        Thin thresholded maps before matching.
    workers : int
        Processes evaluating images in parallel (1: in this process). Workers are spawned, so each
        pays a fresh interpreter's start-up.

    Returns
    -------
    BoundaryScores

    Notes
    -----
    Follows the benchmark's ``collect_eval_bdry``: ODS interpolates the dataset's precision-recall
    curve between thresholds; OIS adds up each image's counts at its best threshold (the highest one
    when several tie); the average precision interpolates precision on a recall grid of step 0.01.
    On the benchmark's own golden set (``bench/data``, 5 thresholds) this reproduces the official
    figures up to the matcher's random outlier edges (benchmarks/results/ground_truth.md compares them).

    References
    ----------
    P. Arbelaez, M. Maire, C. Fowlkes and J. Malik, "Contour detection and hierarchical image
    segmentation", IEEE TPAMI 33(5):898-916, 2011.
    """
    check_sequence(edge_maps, "edge_maps")
    for k, truths in enumerate(check_sequence(ground_truths, "ground_truths")):
        check_sequence(truths, f"ground_truths[{k}]")
    if len(edge_maps) != len(ground_truths):
        raise InputValueError(f"{len(edge_maps)} edge_maps but {len(ground_truths)} ground_truths")
    if len(edge_maps) == 0:  # (a stack's truth value is ambiguous)
        raise InputValueError("edge_maps is empty")
    # Workers beyond one per image would idle (and a count beyond the system's limits would not start).
    workers = min(check_int(workers, "workers", minimum=1), len(edge_maps))
    kwargs = {"thresholds": thresholds, "max_dist": max_dist, "thin": thin}
    # Host copies: a worker process cannot receive device arrays.
    jobs = [(np.asarray(to_host(e, "edge_maps")), [np.asarray(to_host(t, "ground_truths")) for t in g], kwargs)
            for e, g in zip(edge_maps, ground_truths)]
    if workers == 1:
        per_image = [_counts_of(job) for job in jobs]
    else:
        # Spawned, not forked: a forked child of a process holding an OpenCL context can deadlock.
        with ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn")) as pool:
            per_image = list(pool.map(_counts_of, jobs))
    levels = per_image[0].thresholds
    total = np.sum([[c.matched_truth, c.total_truth, c.matched_predicted, c.total_predicted]
                    for c in per_image], axis=0)
    recall, precision = ratio(total[0], total[1]), ratio(total[2], total[3])
    ods = _interpolated_best(levels, recall, precision)
    best = np.zeros(4)
    for c in per_image:
        f = c.f
        # MATLAB's ff(end): the last of the thresholds that reach the maximum.
        i = int(np.flatnonzero(f == f.max())[-1])
        best += (c.matched_truth[i], c.total_truth[i], c.matched_predicted[i], c.total_predicted[i])
    ois_recall, ois_precision = float(ratio(best[0], best[1])), float(ratio(best[2], best[3]))
    return BoundaryScores(
        ods_threshold=ods[0],
        ods_recall=ods[1],
        ods_precision=ods[2],
        ods_f=ods[3],
        ois_recall=ois_recall,
        ois_precision=ois_precision,
        ois_f=float(f_measure(ois_precision, ois_recall)),
        average_precision=_average_precision(recall, precision),
        recall=recall,
        precision=precision,
        f=f_measure(precision, recall),
        per_image=per_image,
    )
