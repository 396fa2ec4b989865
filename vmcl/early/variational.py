"""The variational refinement of a dense flow: brightness and gradient constancy against a robust smoothness.

Seed section "Motion" measures the flow by patchwise correlation, assuming it "locally constant in a small
region surrounding a point"; the Lucas-Kanade steps (:mod:`vmcl.early.lucas_kanade`) refine it window by
window. This refinement instead lets every pixel's flow answer to its own brightness and to its
neighbours' flow at once: it minimises

    E(w) = sum_p delta psi(|f1(p + w) - f0(p)|^2) + gamma psi(|grad f1(p + w) - grad f0(p)|^2)
           + alpha psi(|grad u|^2 + |grad v|^2),        psi(s) = sqrt(s + eps^2),

brightness constancy, gradient constancy (which an exposure change between the frames does not break)
and a smoothness that, being robust, lets the flow jump at motion boundaries (Brox, Bruhn, Papenberg and
Weickert, ECCV 2004; the refinement DIS ends each level with, Kroeger et al., ECCV 2016). The constancy
terms are linearised about the incoming flow (frame 1 read once where it points); each fixed-point
iteration lags the robust weights, which leaves a linear system, relaxed by red-black successive
over-relaxation: an MRF over continuous values, each pixel a processor updating from its four neighbours,
as the seed's MRFs are on the Connection Machine. Relaxation alone carries a correction about a pixel per
sweep, so a flow that must spread across a wide region of weak texture needs hundreds of sweeps; a
multigrid V-cycle relaxes the same system on a pyramid of 2 x 2 blocks (each level's correction solved on
the next coarser one), which carries it twice as far per sweep at each coarser level (the solver Bruhn,
Weickert et al. use to compute this functional in real time, IEEE TIP 2005). Brightness is counted in
grey levels of 255 (the units alpha, delta and gamma are given in), the flow in pixels.

The motion cue can run it after the Lucas-Kanade steps and before the motion MRF, whose line process keeps
the boundaries (``[motion] variational_iterations``). It is off there by default for its cost:
benchmarks/results/motion.md gives the motion-only machine's time and a stream's with and without it, and
its gain on the real sequences.

References: T. Brox, A. Bruhn, N. Papenberg and J. Weickert, "High accuracy optical flow estimation based on
a theory for warping", ECCV 2004. A. Bruhn, J. Weickert, C. Feddern, T. Kohlberger and C. Schnoerr,
"Variational optical flow computation in real time", IEEE Trans. Image Processing 14(5), 2005.
"""

from __future__ import annotations

import numpy as np
import pyopencl.array as cl_array

from vmcl.cm.core import ArrayLike, check_int, check_real, check_same_kind, field, machine_for, result
from vmcl.early.flow_frames import check_flow_frames, smoothed_frames
from vmcl.errors import InputValueError
from vmcl.machine import Machine

__all__ = ["ALPHA", "COARSEST", "COARSEST_SWEEPS", "DELTA", "EPSILON", "GAMMA", "ITERATIONS", "LINK_SCALE",
           "PRESMOOTH", "RELAXATION", "SWEEPS", "variational_refine"]

# ALPHA and ITERATIONS were fitted on rendered scenes by benchmarks/motion_variational_fit.py (its results
# file gives every setting tried), never on a sequence a benchmark reports.
ALPHA = 160.0
"""Default weight of the smoothness term (grey levels of 255 squared per pixel of flow squared)."""
# DELTA and GAMMA are not fitted: the numbers OpenCV's VariationalRefinement (DIS's refinement) documents for
# a functional of this form (which also normalises its data terms; this one does not), brightness in grey
# levels of 255; only their ratios to ALPHA and to each other matter, and ALPHA was fitted with them.
DELTA = 5.0
"""Default weight of brightness constancy."""
GAMMA = 10.0
"""Default weight of gradient constancy."""
ITERATIONS = 10
"""Default number of fixed-point iterations (each re-weighs the robust terms and runs one V-cycle)."""
# Not fitted: two sweeps before a level's coarse correction and two after it, a common multigrid cycle.
SWEEPS = 2
"""Default number of over-relaxation sweeps (each a red and a black half-sweep) on each level of the
V-cycle before its coarser level's correction and again after it; on a single level, the sweeps per
iteration."""
# Not fitted: the value OpenCV's VariationalRefinement documents.
RELAXATION = 1.6
"""The over-relaxation factor (1: Gauss-Seidel)."""
# COARSEST and COARSEST_SWEEPS are not fitted: a level of a few dozen pixels costs its launches more than its
# work, and each iteration's V-cycle goes on from where the last one's coarsest sweeps stopped.
COARSEST = 8
"""The multigrid coarsens until the smaller side would fall below this many pixels."""
COARSEST_SWEEPS = 10
"""Over-relaxation sweeps on the coarsest level, whose few pixels take them cheaply."""
# Not fitted: derived (kernels/variational.cl's vr_restrict says how).
LINK_SCALE = 0.5
"""A coarse link's weight per fine link crossing between its blocks: a piecewise-constant correction over
2 x 2 blocks doubles a smoothness term's stiffness, which this halves."""
EPSILON = 0.001
"""psi's smoothing (its square is added under the root): keeps the weights finite where a term vanishes."""
PRESMOOTH = 1.0
"""The frames' Gaussian smoothing (pixels) before the derivatives are taken (the Lucas-Kanade steps' own)."""

_GREY_LEVELS = 255.0
_FOOTPRINT = 4 * (2 + 2 + 2 + 8 + 1 + 2 + 1)
"""Device bytes per pixel of the pixel grid besides the multigrid's levels: the flow, its step, two smoothed
frames, eight derivative planes, the smoothness weight, the two frames uploaded as float32 grey, a
Gaussian's plane between its passes."""
_LEVEL_FOOTPRINT = 4 * (8 + 2 + 2)
"""Device bytes per pixel of each multigrid level: its system, its unknown (the pixel grid's is the step) and
its residual (none on the coarsest)."""


def variational_refine(flow: ArrayLike, frame0: ArrayLike, frame1: ArrayLike, *, alpha: float = ALPHA,
                       delta: float = DELTA, gamma: float = GAMMA, iterations: int = ITERATIONS,
                       sweeps: int = SWEEPS, levels: int | None = None, prior: ArrayLike | None = None,
                       beta: float = 0.0, machine: Machine | None = None) -> ArrayLike:
    """Refine a dense flow by minimising brightness and gradient constancy against a robust smoothness.

    Parameters
    ----------
    flow : float32 (H, W, 2) array or device array
        (u, v) per pixel: frame0's pixel x is seen at x + (u, v) in frame1. A pixel whose flow is NaN (or
        infinite) keeps it and links to no neighbour; one whose flow leaves frame1 has no data term and
        takes its neighbours' flow.
    frame0, frame1 : (H, W) or (H, W, 3) arrays or device arrays; uint8, uint16 or float in [0, 1]
        The two frames (RGB is taken as its grey), of one shape and type; NumPy arrays with a NumPy flow,
        device arrays with a device flow.
    alpha : float
        >= 0: the smoothness term's weight (0: each pixel alone, as far as its data allows).
    delta, gamma : float
        >= 0, not both 0: the weights of brightness constancy and of gradient constancy.
    iterations : int
        >= 0: fixed-point iterations (0 returns the flow as it came).
    sweeps : int
        >= 1: red-black over-relaxation sweeps on each level before its coarser level's correction and
        after it.
    levels : int, optional
        >= 1: the multigrid's levels, the pixel grid included (1: plain over-relaxation, ``sweeps`` per
        iteration). By default as many as halve the smaller side down to COARSEST pixels.
    prior : float32 (H, W, 2) array or device array, optional
        A flow the result is pulled towards, with weight ``beta`` (the energy gains beta psi(|w - prior|^2)):
        in a stream, the previous frame's flow carried to this one. NaN where it has no value (no pull
        there). NumPy or device array as the flow is.
    beta : float
        >= 0: the prior's weight (0: none; ignored without a prior).
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
    alpha = check_real(alpha, "alpha", minimum=0, maximum=1e6)
    delta = check_real(delta, "delta", minimum=0, maximum=1e6)
    gamma = check_real(gamma, "gamma", minimum=0, maximum=1e6)
    if delta == 0 and gamma == 0:
        raise InputValueError("delta and gamma must not both be 0: the refinement needs a data term")
    iterations = check_int(iterations, "iterations", minimum=0, maximum=1000)
    sweeps = check_int(sweeps, "sweeps", minimum=1, maximum=1000)
    if levels is not None:
        levels = check_int(levels, "levels", minimum=1, maximum=64)
    beta = check_real(beta, "beta", minimum=0, maximum=1e6)
    pulled_to, pull = data, 0.0  # no prior: the kernel reads no buffer of it (beta 0); the flow stands in
    if prior is not None:
        check_same_kind("flow", host, "prior", not isinstance(prior, cl_array.Array))
        pulled_to, _ = field(prior, "prior", machine, ndims=(3,), dtypes=(np.float32,))
        if pulled_to.shape != data.shape:
            raise InputValueError(f"prior must have the flow's shape {data.shape}, got {pulled_to.shape}")
        pull = beta
    height, width = data.shape[:2]
    pixels = height * width
    shapes = _level_shapes(height, width, levels)
    machine.require_memory(f"the variational refinement of a {height} x {width} flow",
                           _FOOTPRINT * pixels + sum(_LEVEL_FOOTPRINT * h * w for h, w in shapes),
                           32 * pixels)  # the largest buffers: the derivative planes, the pixel grid's system
    # The frames are checked (and smoothed) even for no iterations: bad frames are refused whatever the count.
    f0, f1, gain = smoothed_frames(frame0, frame1, (PRESMOOTH,), machine)
    out = data if host else data.copy()  # refined in place on a flow of its own
    if not iterations:
        return result(out, host)
    dims = (np.int64(width), np.int64(height))
    terms = machine.empty((8, height, width), np.float32)
    smooth = machine.empty((height, width), np.float32)
    step = machine.empty((height, width, 2), np.float32)
    step.fill(0)
    grid = _Multigrid(machine, step, shapes, sweeps)
    machine.launch(machine.kernel("variational", "vr_terms"), (width, height), f0, f1, out,
                   np.float32(gain * _GREY_LEVELS), terms, *dims)
    weights = machine.kernel("variational", "vr_weights")
    links = machine.kernel("variational", "vr_links")
    for _ in range(iterations):
        machine.launch(weights, (width, height), terms, out, step, pulled_to, np.float32(pull),
                       np.float32(delta), np.float32(gamma), np.float32(alpha), np.float32(EPSILON ** 2),
                       grid.systems[0], smooth, *dims)
        machine.launch(links, (width, height), smooth, out, grid.systems[0], *dims)
        grid.cycle()
    machine.launch(machine.kernel("variational", "vr_apply"), (width, height), out, step, *dims)
    return result(out, host)


def _level_shapes(height: int, width: int, levels: int | None) -> list[tuple[int, int]]:
    """The multigrid's (height, width) per level, the pixel grid first, each the last's 2 x 2 blocks: as many
    as ``levels`` asks, or (None) until the smaller side would fall below COARSEST."""
    shapes = [(height, width)]
    while len(shapes) < (levels or 1000):
        h, w = shapes[-1]
        if (levels is None and (min(h, w) + 1) // 2 < COARSEST) or h == w == 1:
            break
        shapes.append(((h + 1) // 2, (w + 1) // 2))
    return shapes


class _Multigrid:
    """The linear system of each fixed-point iteration, solved by one multigrid V-cycle: ``sweeps``
    red-black over-relaxation sweeps on each level before its coarser level's correction and after it, and
    COARSEST_SWEEPS on the coarsest (a single level is plain over-relaxation)."""

    def __init__(self, machine: Machine, unknown, shapes: list[tuple[int, int]], sweeps: int):
        self.machine = machine
        self.shapes = shapes
        self.sweeps = sweeps
        self.unknowns = [unknown] + [machine.empty((h, w, 2), np.float32) for h, w in shapes[1:]]
        self.systems = [machine.empty((h, w, 8), np.float32) for h, w in shapes]
        self.residuals = [machine.empty((h, w, 2), np.float32) for h, w in shapes[:-1]]
        self.relax = machine.kernel("variational", "vr_relax")
        self.residual = machine.kernel("variational", "vr_residual")
        self.restrict = machine.kernel("variational", "vr_restrict")
        self.prolong = machine.kernel("variational", "vr_prolong")

    def cycle(self, level: int = 0) -> None:
        coarsest = level == len(self.shapes) - 1
        self._relax(level, COARSEST_SWEEPS if coarsest and level else self.sweeps)
        if coarsest:
            return
        (h, w), (ch, cw) = self.shapes[level], self.shapes[level + 1]
        dims = (np.int64(w), np.int64(h))
        self.machine.launch(self.residual, (w, h), self.unknowns[level], self.systems[level],
                            self.residuals[level], *dims)
        self.machine.launch(self.restrict, (cw, ch), self.systems[level], self.residuals[level],
                            self.systems[level + 1], self.unknowns[level + 1], np.float32(LINK_SCALE), *dims,
                            np.int64(cw), np.int64(ch))
        self.cycle(level + 1)
        self.machine.launch(self.prolong, (w, h), self.unknowns[level], self.unknowns[level + 1], *dims,
                            np.int64(cw))
        self._relax(level, self.sweeps)

    def _relax(self, level: int, sweeps: int) -> None:
        h, w = self.shapes[level]
        for _ in range(sweeps):
            for parity in (0, 1):
                self.machine.launch(self.relax, ((w + 1) // 2, h), self.unknowns[level], self.systems[level],
                                    np.float32(RELAXATION), np.int32(parity), np.int64(w), np.int64(h))
