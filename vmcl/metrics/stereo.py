"""Stereo: Middlebury "bad pixels", output density, and mean absolute and RMS disparity error.

Bad-pixel rates at 0.5, 1, 2 and 4 px, pixels without an output counted as bad and the output density
reported beside, plus mean absolute and RMS error on the pixels that have an output (Scharstein and
Szeliski 2002), over a Middlebury nonocc, all or disc mask or every pixel with known ground truth.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from vmcl.cm.core import check_real
from vmcl.errors import InputValueError
from vmcl.metrics._inputs import as_float_field, check_sequence, evaluated_pixels

__all__ = ["BAD_PIXEL_THRESHOLDS", "DisparityScores", "evaluate_disparity"]

BAD_PIXEL_THRESHOLDS: tuple[float, ...] = (0.5, 1.0, 2.0, 4.0)
"""The Middlebury thresholds, in pixels, at which a disparity counts as bad."""


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
    disparity = as_float_field(disparity, "disparity", ndim=2)
    truth = as_float_field(ground_truth, "ground_truth", ndim=2)
    if disparity.shape != truth.shape:
        raise InputValueError(f"disparity has shape {disparity.shape}, ground_truth has shape {truth.shape}")
    thresholds = tuple(check_real(t, "thresholds[]", minimum=0) for t in check_sequence(thresholds, "thresholds"))
    if not thresholds:
        raise InputValueError("thresholds must be a non-empty sequence of non-negative numbers, got ()")
    evaluated = evaluated_pixels(truth, mask, np.isfinite(truth))
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
