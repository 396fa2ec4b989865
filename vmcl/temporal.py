"""Time: what the streaming machine carries from one frame to the next (kernels/temporal.cl).

Seed section "Fast vision: The role of time smoothness": surfaces and the brightness array change little
from frame to frame, and the MRFs that restore each cue can "enforce continuity in time (if there are no
discontinuities)", or do "a form of Kalman filtering". After each frame the machine keeps every cue's
restored field and the information behind it (the data term's weight: the measurement's confidence plus
what time contributed). At the next frame it

1. carries each field along the previous frame's restored flow (a pixel x came from x - u(x)), and with
   it the information, faded by the memory m: w becomes w m / (m + w), the Kalman prediction of an
   information filter whose process noise is 1 / m, so that a static pixel's information settles at a
   few frames' worth instead of growing without bound;
2. breaks time where the carried brightness disagrees with the new frame's by more than a tolerance, or
   the carried position left the image (the temporal line process: occlusions, objects that appear, a
   scene cut; a broken pixel gets no temporal term);
3. fuses the new measurement and the carried field into one data term, the information-weighted mean
   with the informations summed (the Kalman update), which the cue's MRF then restores with its spatial
   line process, starting from the carried field (a warm start, with a schedule that starts cold
   enough to keep it: :data:`vmcl.pipeline.WARM_SCHEDULE`).

The carried flow also predicts where the next motion search looks, where
:attr:`vmcl.pipeline.TimeConfig.predict_search` asks for it (:func:`vmcl.early.motion.flow`'s
``prediction``). When most of the image is broken (a scene cut), the frame starts cold: no temporal term
and the full schedule.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pyopencl.array as cl_array

from vmcl.cm import reduce as cm_reduce
from vmcl.early import filters
from vmcl.machine import Machine

__all__ = ["COMPARISON_SIGMA", "Carried", "Memory"]

COMPARISON_SIGMA = 1.0
"""Gaussian width (pixels) of the brightness compared across frames: the comparison then reads the
brightness, not its per-pixel noise and sampling phase."""


@dataclass(frozen=True)
class Carried:
    """One cue's field carried to the new frame (device arrays).

    Attributes
    ----------
    prediction : float32 (H, W) or (H, W, C)
        The previous restoration at the carried positions; NaN where time is broken.
    weight : float32 (H, W)
        The information it carries (0 where broken).
    """

    prediction: cl_array.Array
    weight: cl_array.Array


class Memory:
    """The state a stream keeps between frames, and the temporal terms it gives the next frame.

    Parameters
    ----------
    machine : vmcl.Machine
    tolerance : float
        Largest change of smoothed brightness (images in [0, 1]) along the flow that keeps time unbroken.
    memory : float
        m > 0, the most information (in frames' worth of a unit-confidence measurement) carried forward.
    gain : float
        >= 0, the weight of the carried information against the new measurement's.
    scene_cut : float
        In (0, 1]: when more than this share of the pixels is broken, the frame starts cold.
    """

    def __init__(self, machine: Machine, *, tolerance: float, memory: float, gain: float, scene_cut: float) -> None:
        self.machine = machine
        self.tolerance, self.memory, self.gain, self.scene_cut = tolerance, memory, gain, scene_cut
        self.grey: cl_array.Array | None = None
        self.flow: cl_array.Array | None = None
        self.fields: dict[str, tuple[cl_array.Array, cl_array.Array, bool]] = {}
        self.next_fields: dict[str, tuple[cl_array.Array, cl_array.Array, bool]] = {}
        self.broken: cl_array.Array | None = None
        self.broken_share = 0.0
        self.carried: dict[str, Carried] = {}
        self.previous_grey: cl_array.Array | None = None
        self.frame = -1  # the index of the frame begun last in the stream

    def comparison_grey(self, image: cl_array.Array) -> cl_array.Array:
        """The smoothed grey brightness of a device image in [0, 1], as frames are compared."""
        grey = filters.grey_field(self.machine, image)
        return filters.gaussian(grey, sigma=COMPARISON_SIGMA, method="exact", machine=self.machine)

    def begin(self, image: cl_array.Array) -> bool:
        """Start a frame: compare it with the previous one; True when time carries (no cut, a past).

        Sets :attr:`broken` (uint8 (H, W), 1 where time is broken) and :attr:`broken_share`.
        """
        m = self.machine
        self.frame += 1
        grey = self.comparison_grey(image)
        previous, self.grey = self.grey, grey
        self.next_fields, self.carried = {}, {}
        if previous is None or previous.shape != grey.shape:
            self.fields, self.broken, self.broken_share = {}, None, 1.0
            return False
        height, width = grey.shape
        self.broken = m.empty((height, width), np.uint8)
        ones = m.empty((height, width), np.float32)
        ones.fill(1.0, queue=m.queue)
        scratch = m.empty((height, width), np.float32)
        self._predict(ones, ones, previous, grey, 1, False, scratch, m.empty((height, width), np.float32),
                      tested=False)
        share = float(cm_reduce.reduce(self.broken, "sum", machine=m).get()) / (height * width)
        self.broken_share = share
        self.previous_grey = previous
        if share > self.scene_cut:
            self.fields = {}
            return False
        return bool(self.fields)

    def _predict(self, field: cl_array.Array, information: cl_array.Array, before: cl_array.Array,
                 now: cl_array.Array, ncomp: int, nearest: bool, prediction: cl_array.Array,
                 weight: cl_array.Array, *, tested: bool = True) -> None:
        """Carry ``field`` along the flow; ``tested``: :attr:`broken` holds this frame's brightness test
        (:meth:`begin` made it), else the test is made and written there."""
        m = self.machine
        height, width = now.shape
        flow = self.flow
        kernel = m.kernel("temporal", "predict", NCOMP=ncomp, NEAREST=int(nearest))
        m.launch(kernel, (width, height), field, information, flow if flow is not None else information,
                 np.int32(flow is not None), before, now, np.float32(self.tolerance), np.float32(self.memory),
                 prediction, weight, self.broken, np.int32(tested), np.int64(width), np.int64(height))

    def carry(self, cue: str) -> Carried | None:
        """The cue's previous restoration carried to this frame (None when there is none to carry, or no frame
        has begun since the last one ended: the carry rests on the frame's brightness test)."""
        if cue not in self.fields or self.broken is None or self.grey is None or self.previous_grey is None:
            return None
        if cue not in self.carried:
            field, information, nearest = self.fields[cue]
            ncomp = 1 if field.ndim == 2 else field.shape[2]
            prediction = self.machine.empty(field.shape, np.float32)
            weight = self.machine.empty(self.grey.shape, np.float32)
            self._predict(field, information, self.previous_grey, self.grey, ncomp, nearest, prediction, weight)
            self.carried[cue] = Carried(prediction, weight)
        return self.carried[cue]

    def fuse(self, data: cl_array.Array, confidence: cl_array.Array | None, carried: Carried | None,
             jump: float = math.inf) -> tuple[cl_array.Array, cl_array.Array, cl_array.Array]:
        """The measurement and the carried field as one data term, and the MRF's warm start.

        ``jump``: where the measurement and the carried value differ by more than this (the cue's units;
        Euclidean over its components), time is broken for the cue at that pixel.

        Returns (data, confidence, start): the fused data and its information for the MRF, and the carried
        value where it entered the data (NaN elsewhere).
        """
        m = self.machine
        height, width = data.shape[:2]
        ncomp = 1 if data.ndim == 2 else data.shape[2]
        fused = m.empty(data.shape, np.float32)
        start = m.empty(data.shape, np.float32)
        information = m.empty((height, width), np.float32)
        prediction = carried.prediction if carried is not None else data
        weight = carried.weight if carried is not None else information
        m.launch(m.kernel("temporal", "fuse", NCOMP=ncomp), (width, height), data,
                 confidence if confidence is not None else information, np.int32(confidence is not None),
                 prediction, weight, np.int32(carried is not None), np.float32(self.gain),
                 np.float32(min(jump, np.finfo(np.float32).max)), fused, information, start,
                 np.int64(width), np.int64(height))
        return fused, information, start

    def remember(self, cue: str, field: cl_array.Array, information: cl_array.Array, nearest: bool) -> None:
        """Keep a cue's restoration of this frame and its information for the next frame."""
        self.next_fields[cue] = (field, information, nearest)

    def end(self, flow: cl_array.Array | None) -> None:
        """Finish the frame: its restorations and restored flow become the past, and its brightness test
        ends with it."""
        self.fields, self.next_fields = self.next_fields, {}
        self.flow = flow
        self.broken = None

