"""A flow field's weighted median, whose support stops at brightness edges.

Seed section "Motion": the patchwise matcher's windows straddle motion boundaries and carry one surface's
motion over the other's, and on weak texture its estimates scatter. Both are mended by giving each pixel
the weighted median of the flow around it among the pixels of its own colour
(:func:`vmcl.early.weighted_median.weighted_median`, each component on its own): the median ignores the
scattered estimates, and the colour weights stop it at the brightness edge where the motion changes.
Median filtering of the flow is what Sun, Roth and Black found the classical flow methods owe most of
their accuracy to, and the weighted form is theirs.

Reference: D. Sun, S. Roth and M. J. Black, "Secrets of optical flow estimation and their principles",
CVPR 2010.
"""

from __future__ import annotations

import numpy as np
import pyopencl.array as cl_array

from vmcl.cm.core import ArrayLike, check_int, check_real, check_same_kind, field, machine_for, result
from vmcl.cm.reduce import extremes
from vmcl.early.weighted_median import weighted_median
from vmcl.errors import InputTypeError, InputValueError
from vmcl.machine import Machine

__all__ = ["FLOW_BIN", "FLOW_LIMIT", "REFINE", "REFINE_COLOUR", "REFINE_RADIUS", "REFINE_STRIDE", "refine_flow"]

# The defaults, fitted on rendered scenes by benchmarks/motion_refine_fit.py (its results file gives every
# setting tried), never on a sequence a benchmark reports.
REFINE = True
"""Default: the motion cue refines its flow (:class:`vmcl.pipeline.MotionConfig`'s ``refine``)."""
REFINE_RADIUS = 17
"""Default radius of the window, in pixels (its spatial scale too)."""
REFINE_COLOUR = 0.2
"""Default colour distance (in [0, 1] levels) at which a voter weighs 1/e."""
REFINE_STRIDE = 6
"""Default step between voters, in pixels."""

FLOW_BIN = 0.125
"""The median's bins are at most this wide, in pixels of flow: finer than the matcher's sub-pixel error."""
FLOW_LIMIT = 1e30
"""The largest flow component (pixels, either sign) refine_flow takes: far beyond any image, and within the
quarter of float32's range the weighted median's bins need."""
_SPAN_BINS = 62
"""The bins the flow's span may take: the weighted median's private histogram then has its smallest size
(64 bins; the stereo cue's refinement builds the same program), so a wide span widens the bins instead."""
_ROUNDING = 1 + 1e-6
"""A wide span's bins are this much wider than span / _SPAN_BINS, so that the weighted median's count of
them, span / width rounded up, does not come out one over through rounding (and need the next size)."""


def refine_flow(flow: ArrayLike, image: ArrayLike, *, radius: int = REFINE_RADIUS,
                sigma_colour: float = REFINE_COLOUR, stride: int = REFINE_STRIDE,
                machine: Machine | None = None) -> ArrayLike:
    """Replace each pixel's flow by the weighted median, component by component, of the flow around it.

    Parameters
    ----------
    flow : float32 (H, W, 2) array or device array
        (u, v) per pixel, NaN where there is none: such a pixel does not vote, and takes the median of the
        voters around it (NaN if it has none).
    image : (H, W) or (H, W, 3) array or device array; uint8, uint16 or float in [0, 1]
        The frame the flow belongs to, whose colours weigh the voters; a NumPy array with a NumPy flow, a
        device array with a device flow.
    radius : int
        >= 1: the window's radius, and the voters' spatial scale, in pixels.
    sigma_colour : float
        > 0: the colour distance (in [0, 1] levels) at which a voter's weight falls by e.
    stride : int
        >= 1: the step between voters.
    machine : vmcl.Machine, optional

    Returns
    -------
    float32 (H, W, 2), as the flow came (NumPy or device array). The median is taken over bins at most
    :data:`FLOW_BIN` px wide across the flow's span (wider where the span exceeds 62 such bins); each pixel
    takes the weighted mean of its median bin's voters.

    Raises
    ------
    InputTypeError, InputValueError
        Naming the argument (through :func:`vmcl.early.weighted_median.weighted_median` for the image).
    """
    machine = machine_for(machine)
    data, host = field(flow, "flow", machine, ndims=(3,), dtypes=(np.float32,))
    if data.shape[2] != 2:
        raise InputValueError(f"flow must have two components (H, W, 2), got shape {data.shape}")
    if not isinstance(image, (np.ndarray, cl_array.Array)):
        raise InputTypeError(f"image must be a NumPy array or a device array, got {type(image).__name__}")
    check_same_kind("flow", host, "image", not isinstance(image, cl_array.Array))
    if image.shape[:2] != data.shape[:2]:
        raise InputValueError(f"flow and image must have the same height and width, got flow {data.shape} and "
                              f"image {image.shape}")
    radius = check_int(radius, "radius", minimum=1, maximum=2**31 - 1)
    sigma_colour = check_real(sigma_colour, "sigma_colour", above=0)
    stride = check_int(stride, "stride", minimum=1, maximum=2**31 - 1)
    # The span is read back (one wait): the bins must cover the flow actually found, which is far narrower
    # than the search's reach.
    low, high = extremes(data, machine=machine)
    if np.isnan(low):  # no pixel has a flow: nothing to refine
        return result(data, host)
    if np.isinf(low) or np.isinf(high):
        raise InputValueError("flow must not contain infinite values (NaN marks a pixel without flow)")
    if max(-low, high) > FLOW_LIMIT:
        raise InputValueError(f"flow must lie within +-{FLOW_LIMIT:.1e} pixels (its bins' edges must stay finite in "
                              f"float32), got values from {low:.3g} to {high:.3g}")
    return weighted_median(data.get() if host else data, image, low=low, high=high, radius=radius,
                           sigma_colour=sigma_colour, sigma_space=float(radius), stride=stride,
                           bin_width=max(FLOW_BIN, (high - low) / _SPAN_BINS * _ROUNDING), machine=machine)
