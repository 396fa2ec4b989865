"""The MRF stage's data and confidence from the early modules' measurements.

Seed section "Organization of integration": the results of stereo and motion "are typically noisy and
sparse", and the MRF restores them. :func:`vmcl.mrf.restore` weighs each datum by a confidence gamma_i;
this module derives it from what the modules report. :func:`score_confidence` turns a matching score into
a weight, so that patches which barely match (no texture, an occlusion) pull the restoration nowhere.
:func:`backfill` keeps a sparse, precise measurement (edge matches) where it exists and fills its gaps with
a dense, weaker one (intensity matches) at that one's own confidence.

NumPy in gives NumPy out; device arrays in give device arrays out.
"""

from __future__ import annotations

import math

import numpy as np

from vmcl.cm import reduce as cm_reduce
from vmcl.cm.core import ArrayLike, field, machine_for
from vmcl.errors import InputTypeError, InputValueError
from vmcl.machine import Machine

__all__ = ["backfill", "check_unit_interval", "mask_confidence", "score_confidence"]


def check_unit_interval(value, name: str, *, closed_above: bool) -> float:
    """``value`` as a float in [0, 1] (``closed_above``) or [0, 1); TypeError or ValueError naming ``name``
    otherwise (NaN included). The pipeline checks its configuration of these weights with it too."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise InputTypeError(f"{name} must be a number, got {type(value).__name__}")
    value = float(value)
    inside = 0 <= value <= 1 if closed_above else 0 <= value < 1
    if not math.isfinite(value) or not inside:
        raise InputValueError(f"{name} must be in [0, {'1]' if closed_above else '1)'}, got {value}")
    return value


def score_confidence(score: ArrayLike, *, floor: float, weight: float = 1.0,
                     machine: Machine | None = None) -> ArrayLike:
    """Weights from matching scores: ``weight * clamp((score - floor) / (1 - floor), 0, 1)``.

    Parameters
    ----------
    score : float32 (H, W) array or device array
        A normalised matching score, 1 for a perfect match (:attr:`vmcl.early.motion.FlowResult.score`,
        :attr:`vmcl.early.stereo.StereoMatch.score`); NaN where there is no measurement.
    floor : float
        In [0, 1): scores at or below it weigh 0, rising linearly to ``weight`` at score 1.
    weight : float
        In [0, 1]: the weight of a perfect match.
    machine : vmcl.Machine, optional

    Returns
    -------
    float32 (H, W), 0 where there is no score.

    Notes
    -----
    Why the pipeline weighs the flow by its score (brightness features, mean field, floor 0.7): on the
    "cues" scene it removed most of the motion line sites, made those left more precise at the same
    recall of the moving plate's outline, and lowered the restored flow's endpoint error there and on
    the "corridor" and "blocks" scenes.

    Examples
    --------
    >>> import numpy as np
    >>> score_confidence(np.array([[np.nan, 0.5, 0.85, 1.0]], np.float32), floor=0.7).round(2).tolist()
    [[0.0, 0.0, 0.5, 1.0]]
    """
    machine = machine_for(machine)
    scores, host = field(score, "score", machine, ndims=(2,), dtypes=(np.float32,))
    floor = check_unit_interval(floor, "floor", closed_above=False)
    weight = check_unit_interval(weight, "weight", closed_above=True)
    gamma = machine.empty(scores.shape, np.float32)
    # score_confidence reads no NCOMP: taken at 1, it shares the build of the scalar fields' kernels.
    machine.launch(machine.kernel("mrf_data", "score_confidence", NCOMP=1), (scores.size,), scores, gamma,
                   np.float32(floor), np.float32(weight), np.int64(scores.size))
    return gamma.get() if host else gamma


def backfill(primary: ArrayLike, secondary: ArrayLike, secondary_confidence: ArrayLike, *,
             machine: Machine | None = None) -> tuple[ArrayLike, ArrayLike]:
    """Data and confidence for :func:`vmcl.mrf.restore`: the primary measurement, its gaps filled.

    Parameters
    ----------
    primary, secondary : float32 (H, W) or (H, W, C) arrays or device arrays, the same shape
        Two measurements of one cue, NaN where there is none (a pixel has one when all its components
        are finite).
    secondary_confidence : float32 (H, W)
        The secondary's weights, e.g. from :func:`score_confidence`: >= 0, or NaN or +inf for none (a
        weight of 0). Negative values are refused, on the host and on the device.
    machine : vmcl.Machine, optional

    Returns
    -------
    (data, confidence)
        The primary (confidence 1) where it has a measurement, elsewhere the secondary with its
        confidence (0 where neither has one, or the secondary's confidence is not finite). NumPy for
        NumPy input, device arrays when any input is one.

    Notes
    -----
    The pipeline fills the stereo edge matches (a small share of the pixels; benchmarks/results/mrf.md
    gives their density on Middlebury) with the dense intensity matches whose normalised
    cross-correlation exceeds 0.9, at weight up to 0.2. With the pipeline's depth restoration (mean
    field) and its default intensity matches (shiftable windows, ``stereo.shiftable`` and
    ``stereo.intensity_sigma``, sub-pixel disparities), this lowers the dense bad-1 rate on Middlebury
    (nonocc) and on the "blocks" scene, and a little on the sparsely textured "cues" scene, where the
    edge matches alone do well (benchmarks/results/pipeline.md holds both; with whole-pixel intensity
    matches the rate on "cues" was the edge matches' own). Centred windows on brightness smoothed with
    sigma 2, an earlier default, lowered it less on Middlebury and on "blocks".
    """
    machine = machine_for(machine)
    host = all(isinstance(a, np.ndarray) for a in (primary, secondary, secondary_confidence))
    first, _ = field(primary, "primary", machine, ndims=(2, 3), dtypes=(np.float32,))
    second, _ = field(secondary, "secondary", machine, ndims=(2, 3), dtypes=(np.float32,))
    gamma2, _ = field(secondary_confidence, "secondary_confidence", machine, ndims=(2,), dtypes=(np.float32,))
    if second.shape != first.shape:
        raise InputValueError(f"secondary has shape {second.shape}, primary has {first.shape}")
    if gamma2.shape != first.shape[:2]:
        raise InputValueError(f"secondary_confidence must have shape {first.shape[:2]}, got {gamma2.shape}")
    # A negative weight would reach the restoration as one (host or device alike); "min" skips NaN, which
    # stands for no confidence.
    lowest = cm_reduce.extremes(gamma2, machine=machine)[0]
    if lowest < 0:
        raise InputValueError(f"secondary_confidence must be >= 0 (NaN or +inf: no confidence), got a value of "
                              f"{lowest:g}")
    ncomp = first.shape[2] if first.ndim == 3 else 1
    if not 1 <= ncomp <= 4:
        raise InputValueError(f"primary must have 1 to 4 components per pixel, got {ncomp}")
    data = machine.empty(first.shape, np.float32)
    gamma = machine.empty(first.shape[:2], np.float32)
    machine.launch(machine.kernel("mrf_data", "backfill", NCOMP=ncomp), (gamma.size,), first, second, gamma2,
                   data, gamma, np.int64(gamma.size))
    if host:
        return data.get(), gamma.get()
    return data, gamma


def mask_confidence(data: ArrayLike, mask: ArrayLike, *, weight: float, masked_weight: float,
                    machine: Machine | None = None) -> ArrayLike:
    """Weights of a measurement some of whose values were filled in rather than measured.

    Parameters
    ----------
    data : float32 (H, W) or (H, W, C) array or device array
        The measurement, NaN where there is none (a pixel has one when all its components are finite).
    mask : bool or uint8 (H, W)
        Set where the value was filled in (e.g. :attr:`vmcl.early.semiglobal.SemiGlobalMatch.occluded`,
        whose disparities come from the background beside them).
    weight, masked_weight : float
        In [0, 1]: the weight of a measured value and of a filled one.
    machine : vmcl.Machine, optional

    Returns
    -------
    float32 (H, W): ``weight``, ``masked_weight``, or 0 where there is no value. NumPy for NumPy input.
    """
    machine = machine_for(machine)
    host = isinstance(data, np.ndarray) and isinstance(mask, np.ndarray)
    values, _ = field(data, "data", machine, ndims=(2, 3), dtypes=(np.float32,))
    if isinstance(mask, np.ndarray) and mask.dtype == np.bool_:
        mask = mask.view(np.uint8)
    flags, _ = field(mask, "mask", machine, ndims=(2,), dtypes=(np.uint8,))
    if flags.shape != values.shape[:2]:
        raise InputValueError(f"mask must have data's shape (H, W): data has {values.shape}, mask {flags.shape}")
    weight = check_unit_interval(weight, "weight", closed_above=True)
    masked_weight = check_unit_interval(masked_weight, "masked_weight", closed_above=True)
    ncomp = values.shape[2] if values.ndim == 3 else 1
    gamma = machine.empty(values.shape[:2], np.float32)
    machine.launch(machine.kernel("mrf_data", "mask_confidence", NCOMP=ncomp), (gamma.size,), values, flags, gamma,
                   np.float32(weight), np.float32(masked_weight), np.int64(gamma.size))
    return gamma.get() if host else gamma
