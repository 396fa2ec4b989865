"""Lucas-Kanade steps that refine a dense flow to sub-pixel accuracy.

Seed section "Motion": the matcher assumes "the optical flow is locally constant in a small region
surrounding a point" and finds the best discrete displacement there. The same assumption in its
differential form (Lucas and Kanade) refines a flow that is already close: at each pixel, brightness
constancy linearised about the current flow, f1(x + u + du) = f0(x), gives one equation in the step du;
its least-squares solution over a Gaussian window is the step. A few such steps, each reading frame 1
where the current flow points, carry the matcher's and the MRF's flow below the precision of a discrete
search and its parabola fit. Each step is a fixed number of local operations per pixel (a Gaussian is
two passes), as on the Connection Machine.

Each pixel's products are taken at its own flow and summed over the window, so a step corrects the
window's mean error: the steps refine a flow that is smooth over the window (as the weighted median
leaves it), not one that scatters from pixel to pixel. The window straddles motion boundaries as the
matcher's does; the motion cue takes the steps after the weighted median and before the motion MRF,
whose line process keeps the boundaries. A pixel whose window holds no texture (the normal equations'
ridge dominates) barely moves.

Reference: B. D. Lucas and T. Kanade, "An iterative image registration technique with an application to
stereo vision", IJCAI 1981.
"""

from __future__ import annotations

import numpy as np

from vmcl.cm.core import (
    ArrayLike,
    check_int,
    check_real,
    check_widths,
    machine_for,
    result,
)
from vmcl.early.filters import separable_gaussian
from vmcl.early.flow_frames import check_flow_frames, smoothed_frames
from vmcl.errors import InputValueError
from vmcl.machine import Machine

__all__ = ["HIGHPASS", "ITERATIONS", "LIMIT", "PRESMOOTH", "RIDGE", "WINDOW", "lucas_kanade"]

# WINDOW, ITERATIONS and HIGHPASS are the motion cue's defaults, fitted on rendered scenes by
# benchmarks/motion_lucas_kanade_fit.py (its results file gives every setting tried), never on a sequence a
# benchmark reports.
WINDOW = 4.5
"""Default scale (pixels) of the Gaussian window over which each step's equations are summed."""
ITERATIONS = 2
"""Default number of steps."""
HIGHPASS = 4.0
"""Default scale (pixels) of the Gaussian whose smoothing is taken from the frames before the steps (0: none,
the brightness itself)."""
PRESMOOTH = 1.0
"""The frames' Gaussian smoothing (pixels) before the gradients are taken: differentiation is ill-posed
(the seed's "Edge detection"), and a step's linearisation holds over the smoothed image's scale."""
RIDGE = 1e-4
"""Added to the normal equations' diagonal, in squared brightness per pixel (brightness in [0, 1]): about
the squared gradient of a 1% step over 1 px summed over a window, so that windows with less texture than
that (flat, or an edge's one direction along it) move little."""
LIMIT = 1.0
"""The most a step moves either flow component, in pixels: the linearisation holds near the current flow."""

_FOOTPRINT = 4 * (2 + 2 + 5 + 5 + 1 + 2)
"""Device bytes per pixel at most: the flow, two smoothed frames, five products and their five sums, a
Gaussian's plane between its passes, frames uploaded as float32 grey."""


def lucas_kanade(flow: ArrayLike, frame0: ArrayLike, frame1: ArrayLike, *, window: float = WINDOW,
                 iterations: int = ITERATIONS, highpass: float = HIGHPASS, machine: Machine | None = None) -> ArrayLike:
    """Refine a dense flow by Lucas-Kanade steps.

    Parameters
    ----------
    flow : float32 (H, W, 2) array or device array
        (u, v) per pixel: frame0's pixel x is seen at x + (u, v) in frame1. A pixel whose flow is NaN (or
        infinite) keeps it and adds nothing to its neighbours' steps, as does one whose flow leaves frame1.
    frame0, frame1 : (H, W) or (H, W, 3) arrays or device arrays; uint8, uint16 or float in [0, 1]
        The two frames (RGB is taken as its grey), of one shape and type; NumPy arrays with a NumPy flow,
        device arrays with a device flow.
    window : float
        > 0: the scale (pixels) of the Gaussian window each step's equations are summed over.
    iterations : int
        >= 0: the number of steps (0 returns the flow as it came).
    highpass : float
        0, or the scale (pixels, > 1, the frames' own smoothing) of a Gaussian whose smoothing is taken from
        each frame before the steps, leaving a difference of Gaussians (the seed's approximation of the
        Laplacian of a Gaussian): brightness changes slower than it, such as a camera's exposure or the
        light changing between the frames, then break brightness constancy less. 0: the smoothed
        brightness itself.
    machine : vmcl.Machine, optional

    Returns
    -------
    float32 (H, W, 2), as the flow came (NumPy or device array): a new array.

    Raises
    ------
    InputTypeError, InputValueError
        Naming the argument.
    """
    machine = machine_for(machine)
    data, host = check_flow_frames(flow, frame0, frame1, machine)
    window = check_real(window, "window", above=0)
    iterations = check_int(iterations, "iterations", minimum=0, maximum=1000)
    highpass = check_real(highpass, "highpass", minimum=0)
    if 0 < highpass <= PRESMOOTH:
        raise InputValueError(f"highpass must be 0 or exceed the frames' smoothing ({PRESMOOTH:g} px), got {highpass}")
    height, width = data.shape[:2]
    check_widths({"window": window, "highpass": highpass}, height, width)
    pixels = height * width
    machine.require_memory(f"Lucas-Kanade steps of a {height} x {width} flow", _FOOTPRINT * pixels, 8 * pixels)
    f0, f1, gain = smoothed_frames(frame0, frame1, (PRESMOOTH, highpass) if highpass else (PRESMOOTH,), machine)
    out = data if host else data.copy()  # the steps work in place on a flow of their own
    dims = (np.int64(width), np.int64(height))
    products = [machine.empty((height, width), np.float32) for _ in range(5)]
    terms = machine.kernel("lucas_kanade", "lk_terms")
    step = machine.kernel("lucas_kanade", "lk_step")
    for _ in range(iterations):
        machine.launch(terms, (width, height), f0, f1, out, np.float32(gain), *products, *dims)
        summed = [separable_gaussian(machine, plane, (window,)) for plane in products]
        machine.launch(step, (width, height), *summed, np.float32(RIDGE), np.float32(LIMIT), out, *dims)
    return result(out, host)

