"""The field's own error measures: stereo bad pixels, flow endpoint and angular error, BSDS boundaries.

Every module of the Vision Machine is measured against ground truth (seed paper, "Learning and parameter
estimation": parameters are estimated "from a set of examples in which data and desired solution are
given"). The figures computed here are the ones the literature reports, computed the way it computes
them, so that vmcl's numbers can be set beside published ones (device arrays are accepted and copied
to the host):

- stereo: Middlebury "bad pixels" at 0.5, 1, 2 and 4 px, pixels without an output counted as bad and the
  output density reported beside, plus mean absolute and RMS error on the pixels that have an output
  (Scharstein and Szeliski 2002);
- optical flow: average endpoint error and Barron's average angular error (Barron, Fleet and Beauchemin
  1994; Baker et al. 2011);
- boundaries: the BSDS benchmark's precision, recall and F-measure at the optimal dataset scale (ODS) and
  the optimal image scale (OIS), with the benchmark's one-to-one pixel matching (``correspondPixels``,
  taken from the maintained ``pyEdgeEval`` port of the official C++ code) and its thinning;
- labelled discontinuities: per physical label (depth, orientation, albedo, shadow, specular, texture),
  precision and recall of predicted discontinuity pixels within a tolerance of t pixels, the measure the
  seed paper's labelling stage needs.
"""

from __future__ import annotations

import multiprocessing
from collections.abc import Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass

import numpy as np
import pyopencl.array as cl_array
from scipy import ndimage

from vmcl.cm._arrays import check_bool, check_int, check_real
from vmcl.errors import InputTypeError, InputValueError

__all__ = [
    "BAD_PIXEL_THRESHOLDS",
    "BoundaryCounts",
    "BoundaryScores",
    "DetectionScores",
    "DisparityScores",
    "FlowScores",
    "angular_error",
    "boundary_counts",
    "detection_scores",
    "endpoint_error",
    "evaluate_boundaries",
    "evaluate_disparity",
    "evaluate_flow",
    "label_scores",
]

BAD_PIXEL_THRESHOLDS: tuple[float, ...] = (0.5, 1.0, 2.0, 4.0)
"""The Middlebury thresholds, in pixels, at which a disparity counts as bad."""

# More boundary thresholds than a 16-bit edge map has levels only repeat matchings, at 0.1 s each.
_MAX_BOUNDARY_THRESHOLDS = 2**16


# --------------------------------------------------------------------------------------------- validation


def _host(array) -> np.ndarray:
    """A NumPy view of the input; a device array (pyopencl) is copied to the host first."""
    return np.asarray(array.get() if isinstance(array, cl_array.Array) else array)


def _as_float_field(array, name: str, *, ndim: int) -> np.ndarray:
    array = _host(array)
    if array.dtype.kind not in "iuf":
        raise InputTypeError(f"{name} must be a numeric array of real numbers, got dtype {array.dtype}")
    if array.ndim != ndim:
        raise InputValueError(f"{name} must have {ndim} dimensions, got shape {array.shape}")
    if array.size == 0:
        raise InputValueError(f"{name} is empty")
    array = array.astype(np.float64, copy=False)
    if np.isinf(array).any():
        raise InputValueError(f"{name} contains infinite values; use NaN for 'no value'")
    return array


def _as_mask(mask, name: str, shape: tuple[int, ...], against: str) -> np.ndarray:
    """``mask`` as a boolean array of ``against``'s shape."""
    mask = _host(mask)
    if mask.dtype != bool:
        raise InputTypeError(f"{name} must be a boolean array, got dtype {mask.dtype}")
    if mask.shape != shape:
        raise InputValueError(f"{name} has shape {mask.shape}, {against} has shape {shape}")
    return mask


def _sequence(value, name: str) -> Sequence:
    """``value`` checked as a list, tuple or NumPy array of at least one dimension (a stack of maps)."""
    if not isinstance(value, (list, tuple, np.ndarray)) or (isinstance(value, np.ndarray) and value.ndim == 0):
        raise InputTypeError(f"{name} must be a list, tuple or array, got {type(value).__name__}")
    return value


def _evaluated(truth: np.ndarray, mask, truth_known: np.ndarray) -> np.ndarray:
    """Pixels to score: the mask where one is given (the truth must be known there), else the known truth."""
    if mask is None:
        evaluated = truth_known
    else:
        evaluated = _as_mask(mask, "mask", truth_known.shape, "ground_truth")
        unknown = int(np.count_nonzero(evaluated & ~truth_known))
        if unknown:
            raise InputValueError(f"ground_truth has no value (NaN) at {unknown} pixels inside mask")
    if not evaluated.any():
        raise InputValueError("no pixel to evaluate: the mask is empty, or the ground_truth has no value (NaN) "
                              "anywhere")
    return evaluated


# --------------------------------------------------------------------------------------------- stereo


@dataclass(frozen=True)
class DisparityScores:
    """Disparity errors over the evaluated pixels.

    Attributes
    ----------
    bad : dict of float to float
        Share (0..1) of evaluated pixels whose error exceeds each threshold, missing outputs counted bad.
    density : float
        Share of evaluated pixels that have an output (a finite disparity).
    mae, rms : float
        Mean absolute and root-mean-square error over evaluated pixels that have an output
        (NaN if none has).
    n_evaluated : int
        Number of evaluated pixels.
    """

    bad: dict[float, float]
    density: float
    mae: float
    rms: float
    n_evaluated: int


def evaluate_disparity(
    disparity,
    ground_truth,
    *,
    mask=None,
    thresholds: Sequence[float] = BAD_PIXEL_THRESHOLDS,
) -> DisparityScores:
    """Middlebury bad-pixel rates, density, MAE and RMS of a disparity map.

    Parameters
    ----------
    disparity : (H, W) array
        Estimated left-view disparity; NaN where the method gives no value.
    ground_truth : (H, W) array
        True disparity; NaN where unknown.
    mask : (H, W) bool array, optional
        Pixels to evaluate (for example a Middlebury nonocc, all or disc mask). The ground truth must
        be known everywhere inside it. Default: every pixel with known ground truth.
    thresholds : sequence of float
        Error thresholds in pixels; a pixel is bad when ``|d - d_gt| > t``.

    Returns
    -------
    DisparityScores

    Notes
    -----
    A pixel without an output is bad at every threshold, so a sparse method cannot look better by
    abstaining; the density is reported beside the rates, as Middlebury does.

    Examples
    --------
    >>> import numpy as np
    >>> truth = np.array([[1.0, 2.0], [3.0, np.nan]])
    >>> scores = evaluate_disparity(np.array([[1.2, 4.0], [np.nan, 0.0]]), truth)
    >>> scores.bad[1.0], scores.density, scores.mae
    (0.6666666666666666, 0.6666666666666666, 1.1)

    References
    ----------
    D. Scharstein and R. Szeliski, "A taxonomy and evaluation of dense two-frame stereo correspondence
    algorithms", IJCV 47(1/2/3):7-42, 2002.
    """
    disparity = _as_float_field(disparity, "disparity", ndim=2)
    truth = _as_float_field(ground_truth, "ground_truth", ndim=2)
    if disparity.shape != truth.shape:
        raise InputValueError(f"disparity has shape {disparity.shape}, ground_truth has shape {truth.shape}")
    thresholds = tuple(check_real(t, "thresholds[]", minimum=0) for t in _sequence(thresholds, "thresholds"))
    if not thresholds:
        raise InputValueError("thresholds must be a non-empty sequence of non-negative numbers, got ()")
    evaluated = _evaluated(truth, mask, np.isfinite(truth))
    error = np.abs(disparity[evaluated] - truth[evaluated])
    has_output = np.isfinite(error)
    n = error.size
    # NaN > t is False, so missing outputs are added to the bad count explicitly.
    missing = n - int(np.count_nonzero(has_output))
    bad = {t: (int(np.count_nonzero(error[has_output] > t)) + missing) / n for t in thresholds}
    valid = error[has_output]
    mae = float(valid.mean()) if valid.size else float("nan")
    rms = float(np.sqrt(np.mean(valid**2))) if valid.size else float("nan")
    return DisparityScores(bad=bad, density=valid.size / n, mae=mae, rms=rms, n_evaluated=n)


# --------------------------------------------------------------------------------------------- flow


def _flow_pair(flow, ground_truth) -> tuple[np.ndarray, np.ndarray]:
    flow = _as_float_field(flow, "flow", ndim=3)
    truth = _as_float_field(ground_truth, "ground_truth", ndim=3)
    if flow.shape[-1] != 2:
        raise InputValueError(f"flow must have shape (H, W, 2), got {flow.shape}")
    if flow.shape != truth.shape:
        raise InputValueError(f"flow has shape {flow.shape}, ground_truth has shape {truth.shape}")
    return flow, truth


def endpoint_error(flow, ground_truth) -> np.ndarray:
    """Per-pixel endpoint error ``|w - w_gt|`` in pixels (NaN where either has no value).

    Parameters
    ----------
    flow, ground_truth : (H, W, 2) arrays
        Flow fields (u, v); NaN where there is no value.

    Returns
    -------
    (H, W) float64 array
    """
    flow, truth = _flow_pair(flow, ground_truth)
    return np.hypot(flow[..., 0] - truth[..., 0], flow[..., 1] - truth[..., 1])


def angular_error(flow, ground_truth) -> np.ndarray:
    """Per-pixel Barron angular error in degrees (NaN where either has no value).

    The angle between the space-time direction vectors (u, v, 1) and (u_gt, v_gt, 1).

    Parameters
    ----------
    flow, ground_truth : (H, W, 2) arrays
        Flow fields (u, v); NaN where there is no value.

    Returns
    -------
    (H, W) float64 array

    References
    ----------
    J. L. Barron, D. J. Fleet and S. S. Beauchemin, "Performance of optical flow techniques",
    IJCV 12(1):43-77, 1994.
    """
    flow, truth = _flow_pair(flow, ground_truth)
    u, v = flow[..., 0], flow[..., 1]
    ug, vg = truth[..., 0], truth[..., 1]
    cosine = (u * ug + v * vg + 1.0) / np.sqrt((u * u + v * v + 1.0) * (ug * ug + vg * vg + 1.0))
    # Rounding can push the cosine of two equal vectors a few ulps above 1; arccos would give NaN.
    return np.degrees(np.arccos(np.minimum(cosine, 1.0)))


@dataclass(frozen=True)
class FlowScores:
    """Flow errors over the evaluated pixels that have an output.

    Attributes
    ----------
    epe, aae : float
        Average endpoint error (pixels) and average Barron angular error (degrees).
    epe_std, aae_std : float
        Their standard deviations.
    density : float
        Share of evaluated pixels with an output.
    n_evaluated : int
        Number of evaluated pixels.
    """

    epe: float
    aae: float
    epe_std: float
    aae_std: float
    density: float
    n_evaluated: int


def evaluate_flow(flow, ground_truth, *, mask=None) -> FlowScores:
    """Average endpoint error and Barron angular error of a flow field.

    Parameters
    ----------
    flow : (H, W, 2) array
        Estimated flow (u, v) with ``I_t(x, y) = I_t+1(x + u, y + v)``; NaN where there is no output.
    ground_truth : (H, W, 2) array
        True flow; NaN where unknown.
    mask : (H, W) bool array, optional
        Pixels to evaluate (for example Yosemite without the sky); the ground truth must be known
        inside it. Default: every pixel with known ground truth.

    Returns
    -------
    FlowScores

    Notes
    -----
    The averages are over evaluated pixels that have an output; the density says how many had one.

    References
    ----------
    S. Baker, D. Scharstein, J. P. Lewis, S. Roth, M. J. Black and R. Szeliski, "A database and
    evaluation methodology for optical flow", IJCV 92(1):1-31, 2011.
    """
    epe = endpoint_error(flow, ground_truth)
    aae = angular_error(flow, ground_truth)
    truth = _host(ground_truth).astype(np.float64)
    evaluated = _evaluated(truth, mask, np.isfinite(truth).all(axis=-1))
    has_output = evaluated & np.isfinite(epe)
    n = int(np.count_nonzero(evaluated))
    if not has_output.any():
        nan = float("nan")
        return FlowScores(epe=nan, aae=nan, epe_std=nan, aae_std=nan, density=0.0, n_evaluated=n)
    e, a = epe[has_output], aae[has_output]
    return FlowScores(
        epe=float(e.mean()),
        aae=float(a.mean()),
        epe_std=float(e.std()),
        aae_std=float(a.std()),
        density=e.size / n,
        n_evaluated=n,
    )


# --------------------------------------------------------------------------------------------- BSDS


def _f_measure(precision, recall):
    precision = np.asarray(precision, dtype=np.float64)
    recall = np.asarray(recall, dtype=np.float64)
    total = precision + recall
    return 2.0 * precision * recall / (total + (total == 0))


def _ratio(count, total):
    count = np.asarray(count, dtype=np.float64)
    total = np.asarray(total, dtype=np.float64)
    return count / (total + (total == 0))


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
        return _ratio(self.matched_truth, self.total_truth)

    @property
    def precision(self) -> np.ndarray:
        return _ratio(self.matched_predicted, self.total_predicted)

    @property
    def f(self) -> np.ndarray:
        return _f_measure(self.precision, self.recall)


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
    edge_map = _host(edge_map)
    if edge_map.dtype == bool:
        return edge_map.astype(np.float64)
    edge_map = _as_float_field(edge_map, "edge_map", ndim=2)
    if np.isnan(edge_map).any() or edge_map.min() < 0 or edge_map.max() > 1:
        raise InputValueError("edge_map must hold boundary strengths in [0, 1] (an 8-bit map: divide by 255)")
    return edge_map


def _truth_boundaries(ground_truths, shape: tuple[int, int]) -> list[np.ndarray]:
    truths = [_host(g) for g in _sequence(ground_truths, "ground_truths")]
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
        counts[:, i] = previous
    return BoundaryCounts(levels, *counts)


def _interpolated_best(thresholds, recall, precision) -> tuple[float, float, float, float]:
    """The benchmark's maxF: the best F along straight lines between neighbouring thresholds."""
    best = (thresholds[0], recall[0], precision[0], float(_f_measure(precision[0], recall[0])))
    # MATLAB's linspace(0, 1) has 100 points; the benchmark's figures depend on that grid.
    d = np.linspace(0.0, 1.0, 100)
    for i in range(1, len(thresholds)):
        t = thresholds[i] * d + thresholds[i - 1] * (1 - d)
        r = recall[i] * d + recall[i - 1] * (1 - d)
        p = precision[i] * d + precision[i - 1] * (1 - d)
        f = _f_measure(p, r)
        j = int(np.argmax(f))
        if f[j] > best[3]:
            best = (t[j], r[j], p[j], float(f[j]))
    return tuple(float(x) for x in best)


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
    ground_truths: Sequence[Sequence],
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
    ground_truths : sequence of sequences of (H, W) arrays
        Per image, the annotators' 0/1 boundary maps.
    thresholds : int or sequence of float
        As in :func:`boundary_counts`. The default, 99, is the benchmark's; each threshold costs about
        0.1 s of matching per annotator on a 321 x 481 image (10 BSDS images at 5 thresholds: about
        30 s on 2 cores), so a quick check may use fewer.
    max_dist : float
        Match distance as a fraction of the image diagonal.
    thin : bool
        Thin thresholded maps before matching.
    workers : int
        Processes evaluating images in parallel (1: in this process). Workers are spawned, which
        costs about a second each to start.

    Returns
    -------
    BoundaryScores

    Notes
    -----
    Follows the benchmark's ``collect_eval_bdry``: ODS interpolates the dataset's precision-recall
    curve between thresholds; OIS adds up each image's counts at its best threshold (the highest one
    when several tie); the average precision interpolates precision on a recall grid of step 0.01.
    On the benchmark's own golden set (``bench/data``, 5 thresholds) this gives ODS F and OIS F within
    2e-4 of the official 0.7046 and 0.7087.

    References
    ----------
    P. Arbelaez, M. Maire, C. Fowlkes and J. Malik, "Contour detection and hierarchical image
    segmentation", IEEE TPAMI 33(5):898-916, 2011.
    """
    _sequence(edge_maps, "edge_maps")
    for k, truths in enumerate(_sequence(ground_truths, "ground_truths")):
        _sequence(truths, f"ground_truths[{k}]")
    if len(edge_maps) != len(ground_truths):
        raise InputValueError(f"{len(edge_maps)} edge_maps but {len(ground_truths)} ground_truths")
    if not edge_maps:
        raise InputValueError("edge_maps is empty")
    # Workers beyond one per image would idle (and a count beyond the system's limits would not start).
    workers = min(check_int(workers, "workers", minimum=1), len(edge_maps))
    kwargs = {"thresholds": thresholds, "max_dist": max_dist, "thin": thin}
    # Host copies: a worker process cannot receive device arrays.
    jobs = [(_host(e), [_host(t) for t in g], kwargs) for e, g in zip(edge_maps, ground_truths)]
    if workers == 1:
        per_image = [_counts_of(job) for job in jobs]
    else:
        # Spawned, not forked: a forked child of a process holding an OpenCL context can deadlock.
        with ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn")) as pool:
            per_image = list(pool.map(_counts_of, jobs))
    levels = per_image[0].thresholds
    total = np.sum([[c.matched_truth, c.total_truth, c.matched_predicted, c.total_predicted]
                    for c in per_image], axis=0)
    recall, precision = _ratio(total[0], total[1]), _ratio(total[2], total[3])
    ods = _interpolated_best(levels, recall, precision)
    best = np.zeros(4)
    for c in per_image:
        f = c.f
        # MATLAB's ff(end): the last of the thresholds that reach the maximum.
        i = int(np.flatnonzero(f == f.max())[-1])
        best += (c.matched_truth[i], c.total_truth[i], c.matched_predicted[i], c.total_predicted[i])
    ois_recall, ois_precision = float(_ratio(best[0], best[1])), float(_ratio(best[2], best[3]))
    return BoundaryScores(
        ods_threshold=ods[0],
        ods_recall=ods[1],
        ods_precision=ods[2],
        ods_f=ods[3],
        ois_recall=ois_recall,
        ois_precision=ois_precision,
        ois_f=float(_f_measure(ois_precision, ois_recall)),
        average_precision=_average_precision(recall, precision),
        recall=recall,
        precision=precision,
        f=_f_measure(precision, recall),
        per_image=per_image,
    )


# --------------------------------------------------------------------------------------------- labels


@dataclass(frozen=True)
class DetectionScores:
    """Precision and recall of boundary pixels matched within a tolerance.

    Attributes
    ----------
    precision : float
        Share of predicted pixels within the tolerance of a true pixel (NaN if nothing is predicted).
    recall : float
        Share of true pixels within the tolerance of a predicted pixel (NaN if there is no true pixel).
    f : float
        Harmonic mean of the two (NaN if either is NaN).
    n_predicted, n_true : int
        Pixel counts.
    """

    precision: float
    recall: float
    f: float
    n_predicted: int
    n_true: int


def _within(target: np.ndarray, tolerance: float) -> np.ndarray:
    """Pixels whose Euclidean distance to the nearest pixel of ``target`` is at most ``tolerance``."""
    if not target.any():
        return np.zeros(target.shape, dtype=bool)
    return ndimage.distance_transform_edt(~target) <= tolerance


def detection_scores(predicted, truth, *, tolerance: float = 1.0) -> DetectionScores:
    """Precision and recall of predicted boundary pixels against true ones, within ``tolerance`` px.

    Parameters
    ----------
    predicted, truth : (H, W) bool arrays
        Predicted and true boundary pixels.
    tolerance : float
        Largest Euclidean distance, in pixels, at which a pixel counts as found (0: same pixel).

    Returns
    -------
    DetectionScores

    Notes
    -----
    Unlike the BSDS matching this is not one-to-one: several predicted pixels may be near one true
    pixel. It is the usual measure for labelled discontinuities on synthetic scenes, where the truth is
    one pixel thick and the question is whether each kind of discontinuity was found at all.
    """
    predicted = _host(predicted)
    if predicted.dtype != bool:
        raise InputTypeError(f"predicted must be a 2-D boolean array, got dtype {predicted.dtype}")
    if predicted.ndim != 2:
        raise InputValueError(f"predicted must be a 2-D boolean array, got shape {predicted.shape}")
    truth = _as_mask(truth, "truth", predicted.shape, "predicted")
    tolerance = check_real(tolerance, "tolerance", minimum=0)
    n_predicted, n_true = int(predicted.sum()), int(truth.sum())
    found_predicted = np.count_nonzero(predicted & _within(truth, tolerance))
    found_truth = np.count_nonzero(truth & _within(predicted, tolerance))
    precision = found_predicted / n_predicted if n_predicted else np.nan
    recall = found_truth / n_true if n_true else np.nan
    f = float(_f_measure(precision, recall)) if n_predicted and n_true else float("nan")
    return DetectionScores(float(precision), float(recall), f, n_predicted, n_true)


def label_scores(
    predicted,
    truth,
    *,
    tolerance: float = 1.0,
    labels: Sequence[int] | None = None,
) -> Mapping[int, DetectionScores]:
    """Per physical label, precision and recall of labelled discontinuity pixels within ``tolerance``.

    Parameters
    ----------
    predicted, truth : (H, W) integer arrays
        Label maps with the codes of :class:`vmcl.labels.Label` (0 = no discontinuity).
    tolerance : float
        Largest Euclidean distance in pixels at which a pixel counts as found.
    labels : sequence of int, optional
        Labels to score; default: every non-zero label present in either map.

    Returns
    -------
    dict of int to DetectionScores
        For each label l, :func:`detection_scores` of ``predicted == l`` against ``truth == l``.
    """
    predicted = _host(predicted)
    truth = _host(truth)
    for name, array in (("predicted", predicted), ("truth", truth)):
        if not np.issubdtype(array.dtype, np.integer):
            raise InputTypeError(f"{name} must be a 2-D integer label map, got dtype {array.dtype}")
        if array.ndim != 2:
            raise InputValueError(f"{name} must be a 2-D integer label map, got shape {array.shape}")
    if predicted.shape != truth.shape:
        raise InputValueError(f"predicted has shape {predicted.shape}, truth has shape {truth.shape}")
    check_real(tolerance, "tolerance", minimum=0)
    if labels is None:
        labels = sorted((set(np.unique(predicted).tolist()) | set(np.unique(truth).tolist())) - {0})
    labels = [check_int(lab, "labels[]") for lab in _sequence(labels, "labels")]
    return {int(lab): detection_scores(predicted == lab, truth == lab, tolerance=tolerance) for lab in labels}
