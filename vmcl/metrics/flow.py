"""Optical flow: average endpoint error and Barron's average angular error.

Per-pixel endpoint and angular errors, and their averages and spreads over the evaluated pixels that have
an output, with the output density beside (Barron, Fleet and Beauchemin 1994; Baker et al. 2011).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import cast

import numpy as np

from vmcl.cm.core import to_host
from vmcl.datasets import FLO_UNKNOWN_ABOVE
from vmcl.errors import InputValueError
from vmcl.metrics._inputs import as_float_field, evaluated_pixels

__all__ = ["FlowScores", "angular_error", "endpoint_error", "evaluate_flow"]


def _flow_pair(flow, ground_truth) -> tuple[np.ndarray, np.ndarray]:
    flow = as_float_field(flow, "flow", ndim=3)
    truth = as_float_field(ground_truth, "ground_truth", ndim=3)
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
    # Each direction scaled to unit length by hypot, which does not square: the squares of flows past
    # 1e154 px overflow to inf, and inf / inf gave NaN for two equal vectors.
    length, truth_length = np.hypot(np.hypot(u, v), 1.0), np.hypot(np.hypot(ug, vg), 1.0)
    a = [u / length, v / length, 1.0 / length]
    b = [ug / truth_length, vg / truth_length, 1.0 / truth_length]
    dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    cross = np.sqrt((a[1] * b[2] - a[2] * b[1]) ** 2 + (a[2] * b[0] - a[0] * b[2]) ** 2
                    + (a[0] * b[1] - a[1] * b[0]) ** 2)
    # atan2 of the sine and cosine: exact 0 for equal vectors, and accurate at small angles, where the
    # arccos of a cosine rounded near 1 is not.
    return np.degrees(np.arctan2(cross, dot))


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
    truth = np.asarray(to_host(ground_truth, "ground_truth")).astype(np.float64)
    if np.nanmax(np.abs(truth), initial=0.0) > FLO_UNKNOWN_ABOVE:
        # The .flo format's marker of an unknown vector (what OpenCV's reader leaves in place): scored as a
        # motion it made the error millions of pixels.
        raise InputValueError(f"ground_truth holds vectors beyond {FLO_UNKNOWN_ABOVE:g} px, the .flo format's marker of an "
                              "unknown one: give those pixels NaN (vmcl.datasets.read_flo does)")
    # endpoint_error has checked that the truth is (H, W, 2), so reducing its last axis leaves an (H, W)
    # array; NumPy's stubs cannot tell that from a scalar.
    truth_known = cast(np.ndarray, np.isfinite(truth).all(axis=-1))
    evaluated = evaluated_pixels(truth, mask, truth_known)
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
