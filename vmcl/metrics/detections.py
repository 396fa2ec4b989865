"""Labelled discontinuities: precision and recall of detected pixels within a tolerance, per physical label.

Per physical label (depth, orientation, albedo, shadow, specular, texture), precision and recall of
predicted discontinuity pixels within a tolerance of t pixels, the measure the seed paper's labelling
stage needs. The tolerance may differ from one true pixel to another (a rendered scene's
``Scene.tolerance``: texture-only boundaries are found only to within their texels).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from vmcl.cm.core import check_int, check_real, to_host
from vmcl.errors import InputTypeError, InputValueError
from vmcl.metrics._inputs import as_mask, check_sequence
from vmcl.metrics._rates import f_measure

__all__ = ["DetectionScores", "detection_scores", "label_scores", "within_tolerance"]


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


def _tolerance(tolerance, shape: tuple[int, ...]) -> float | np.ndarray:
    """A number >= 0, or a map of them of ``shape`` (one per true pixel), on the host or the device."""
    tolerance = to_host(tolerance, "tolerance")
    if isinstance(tolerance, np.ndarray) and tolerance.ndim > 0:
        if not np.issubdtype(tolerance.dtype, np.floating) and not np.issubdtype(tolerance.dtype, np.integer):
            raise InputTypeError(f"tolerance must be a number or an array of real numbers, got dtype {tolerance.dtype}")
        if tolerance.shape != shape:
            raise InputValueError(f"tolerance has shape {tolerance.shape}, the maps have shape {shape}")
        if not np.all(np.isfinite(tolerance)) or (tolerance < 0).any():
            raise InputValueError("tolerance must hold finite distances >= 0")
        return tolerance
    return check_real(tolerance, "tolerance", minimum=0)


def within_tolerance(truth, tolerance) -> np.ndarray:
    """The pixels within the tolerance of a true pixel, each true pixel reaching as far as its own.

    Parameters
    ----------
    truth : (H, W) bool array
    tolerance : float or (H, W) array
        A distance in pixels for every true pixel, or a map of them (e.g. a rendered scene's
        ``Scene.tolerance``); >= 0.

    Returns
    -------
    bool (H, W)

    Notes
    -----
    One Euclidean distance transform per distinct tolerance among the true pixels: a map of a few values
    (a scene's: 1 px and its textures' half spacings, in half-pixel steps) costs a few.
    """
    truth = np.asarray(to_host(truth, "truth"))
    if truth.dtype != bool or truth.ndim != 2:
        raise InputTypeError(f"truth must be a 2-D boolean array, got {truth.dtype} of shape {truth.shape}")
    tolerance = _tolerance(tolerance, truth.shape)
    if not isinstance(tolerance, np.ndarray):
        return _within(truth, tolerance)
    near = np.zeros(truth.shape, bool)
    for value in np.unique(tolerance[truth]):
        near |= _within(truth & (tolerance == value), float(value))
    return near


def detection_scores(predicted, truth, *, tolerance: float | np.ndarray = 1.0) -> DetectionScores:
    """Precision and recall of predicted boundary pixels against true ones, within ``tolerance`` px.

    Parameters
    ----------
    predicted, truth : (H, W) bool arrays
        Predicted and true boundary pixels.
    tolerance : float or (H, W) array
        Largest Euclidean distance, in pixels, at which a pixel counts as found (0: same pixel). A map
        gives each true pixel its own: a true pixel is found by a predicted pixel within its tolerance,
        and a predicted pixel is right when it lies within the tolerance of a true pixel.

    Returns
    -------
    DetectionScores

    Notes
    -----
    Unlike the BSDS matching this is not one-to-one: several predicted pixels may be near one true
    pixel. It is the usual measure for labelled discontinuities on synthetic scenes, where the truth is
    one pixel thick and the question is whether each kind of discontinuity was found at all.
    """
    predicted = np.asarray(to_host(predicted, "predicted"))
    if predicted.dtype != bool:
        raise InputTypeError(f"predicted must be a 2-D boolean array, got dtype {predicted.dtype}")
    if predicted.ndim != 2:
        raise InputValueError(f"predicted must be a 2-D boolean array, got shape {predicted.shape}")
    truth = as_mask(truth, "truth", predicted.shape, "predicted")
    tolerance = _tolerance(tolerance, predicted.shape)
    n_predicted, n_true = int(predicted.sum()), int(truth.sum())
    found_predicted = int(np.count_nonzero(predicted & within_tolerance(truth, tolerance)))
    # A true pixel is found by a prediction within its own tolerance: one distance map serves every tolerance.
    to_predicted = ndimage.distance_transform_edt(~predicted) if predicted.any() else np.full(truth.shape, np.inf)
    found_truth = int(np.count_nonzero(truth & (to_predicted <= tolerance)))
    precision = found_predicted / n_predicted if n_predicted else np.nan
    recall = found_truth / n_true if n_true else np.nan
    f = float(f_measure(precision, recall)) if n_predicted and n_true else float("nan")
    return DetectionScores(float(precision), float(recall), f, n_predicted, n_true)


def label_scores(
    predicted,
    truth,
    *,
    tolerance: float | np.ndarray = 1.0,
    labels: Sequence[int] | None = None,
) -> Mapping[int, DetectionScores]:
    """Per physical label, precision and recall of labelled discontinuity pixels within ``tolerance``.

    Parameters
    ----------
    predicted, truth : (H, W) integer arrays
        Label maps with the codes of :class:`vmcl.labels.Label` (0 = no discontinuity).
    tolerance : float or (H, W) array
        Largest Euclidean distance in pixels at which a pixel counts as found; a map gives each true
        pixel its own (e.g. a rendered scene's ``Scene.tolerance``), as :func:`detection_scores` takes it.
    labels : sequence of int, optional
        Labels to score; default: every non-zero label present in either map.

    Returns
    -------
    dict of int to DetectionScores
        For each label l, :func:`detection_scores` of ``predicted == l`` against ``truth == l``.
    """
    predicted = np.asarray(to_host(predicted, "predicted"))
    truth = np.asarray(to_host(truth, "truth"))
    for name, array in (("predicted", predicted), ("truth", truth)):
        if not np.issubdtype(array.dtype, np.integer):
            raise InputTypeError(f"{name} must be a 2-D integer label map, got dtype {array.dtype}")
        if array.ndim != 2:
            raise InputValueError(f"{name} must be a 2-D integer label map, got shape {array.shape}")
    if predicted.shape != truth.shape:
        raise InputValueError(f"predicted has shape {predicted.shape}, truth has shape {truth.shape}")
    tolerance = _tolerance(tolerance, truth.shape)
    if labels is None:
        labels = sorted((set(np.unique(predicted).tolist()) | set(np.unique(truth).tolist())) - {0})
    labels = [check_int(lab, "labels[]") for lab in check_sequence(labels, "labels")]
    return {int(lab): detection_scores(predicted == lab, truth == lab, tolerance=tolerance) for lab in labels}
