"""Optical flow measured on a sequence with ground truth, beside OpenCV's and scikit-image's methods.

What ``vmcl eval flow`` and benchmarks/motion.py report. For one :class:`vmcl.datasets.FlowSequence`:

- "vmcl two frames": the machine (motion only, its default settings) on the ground truth's frame and the
  next; its restored flow;
- "vmcl sequence": :meth:`vmcl.pipeline.VisionMachine.stream` over the frames from the first up to the
  one after the ground truth's, with the temporal terms; the ground truth's frame's restored flow (only
  where the folder holds frames before it);
- OpenCV's DIS (presets MEDIUM and FAST; OpenCV has no finer preset), Farneback (OpenCV's sample parameters: pyramid scale 0.5, 3
  levels, window 15, 3 iterations, poly_n 5, poly_sigma 1.2) and TV-L1 (scikit-image's
  ``optical_flow_tvl1``, its defaults, when scikit-image is installed), all on the grey frames.

EPE and AAE over the sequence's mask (every pixel with a valid flow, occluded ones included, as Sintel
reports it), and, where the sequence gives occlusions, EPE over the matched (visible) and unmatched pixels.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from vmcl.cm.core import check_bool
from vmcl.datasets import FlowSequence, read_image
from vmcl.errors import InputTypeError, InputValueError
from vmcl.machine import Machine
from vmcl.metrics import evaluate_flow
from vmcl.pictures import eight_bits

__all__ = ["FlowRow", "baselines", "evaluate_sequence", "motion_only"]


@dataclass(frozen=True)
class FlowRow:
    """One method's scores on one sequence.

    Attributes
    ----------
    method : str
    epe, aae : float
        Over the sequence's mask (px, degrees).
    epe_matched, epe_unmatched : float or None
        Over the visible and the occluded pixels of the mask, where the sequence gives occlusions.
    ms : float
        Wall time of the method on the pair (for "vmcl sequence", of the scored frame).
    """

    method: str
    epe: float
    aae: float
    epe_matched: float | None
    epe_unmatched: float | None
    ms: float


def motion_only(config=None):
    """``config`` (default ``Config()``) with every cue but motion switched off."""
    from dataclasses import replace

    from vmcl.pipeline import ColourConfig, Config, StereoConfig, TextureConfig

    if config is None:
        config = Config()
    if not isinstance(config, Config):
        raise InputTypeError(f"config must be a vmcl.pipeline.Config or None, got {type(config).__name__}")
    return replace(config, stereo=StereoConfig(enabled=False), colour=ColourConfig(enabled=False),
                   texture=TextureConfig(enabled=False))


def _grey(frame: np.ndarray) -> np.ndarray:
    import cv2

    grey = cv2.cvtColor(frame, cv2.COLOR_RGB2GRAY) if frame.ndim == 3 else frame
    return eight_bits(grey)  # OpenCV's and scikit-image's methods take 8 bits: a 16-bit frame's levels / 257


def baselines() -> dict[str, Callable[[np.ndarray, np.ndarray], np.ndarray]]:
    """The other methods, by name: each takes two grey uint8 frames and returns (H, W, 2) (u, v)."""
    import cv2

    # OpenCV's type stubs take no None for the output flow, which OpenCV itself then allocates. DIS
    # refuses a frame that is a slice of a larger array (its rows not contiguous): frames are made so.
    def dis(preset: int) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
        return lambda a, b: np.asarray(cv2.DISOpticalFlow.create(preset).calc(  # type: ignore[call-overload]
            np.ascontiguousarray(a), np.ascontiguousarray(b), None))

    def farneback(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return np.asarray(cv2.calcOpticalFlowFarneback(  # type: ignore[call-overload]
            np.ascontiguousarray(a), np.ascontiguousarray(b), None, 0.5, 3, 15, 3, 5, 1.2, 0))

    methods: dict[str, Callable[[np.ndarray, np.ndarray], np.ndarray]] = {
        "OpenCV DIS medium": dis(cv2.DISOPTICAL_FLOW_PRESET_MEDIUM),
        "OpenCV DIS fast": dis(cv2.DISOPTICAL_FLOW_PRESET_FAST),
        "OpenCV Farneback": farneback,
    }
    try:
        from skimage.registration import optical_flow_tvl1
    except ImportError:
        return methods

    def tvl1(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        rows, cols = optical_flow_tvl1(a.astype(np.float32) / 255, b.astype(np.float32) / 255)
        return np.stack([cols, rows], axis=-1).astype(np.float32)  # (v, u) by axis -> (u, v)

    methods["scikit-image TV-L1"] = tvl1
    return methods


def _row(method: str, flow: np.ndarray | None, sequence: FlowSequence, ms: float) -> FlowRow:
    if flow is None:  # the machine found no flow at all: scored as a zero flow
        flow = np.zeros_like(sequence.flow)
    scores = evaluate_flow(flow, sequence.flow, mask=sequence.mask)
    matched = unmatched = None
    if sequence.occluded is not None:
        visible, hidden = sequence.mask & ~sequence.occluded, sequence.mask & sequence.occluded
        matched = evaluate_flow(flow, sequence.flow, mask=visible).epe if visible.any() else None
        unmatched = evaluate_flow(flow, sequence.flow, mask=hidden).epe if hidden.any() else None
    return FlowRow(method, scores.epe, scores.aae, matched, unmatched, ms)


def evaluate_sequence(sequence: FlowSequence, *, config=None, machine: Machine | None = None,
                      others: bool = True) -> list[FlowRow]:
    """Score the machine (two frames and, where there is a past, the sequence) and the other methods.

    Parameters
    ----------
    sequence : vmcl.datasets.FlowSequence
    config : vmcl.pipeline.Config, optional
        The machine's settings (motion only is run); default ``Config()``.
    machine : vmcl.Machine, optional
    others : bool
        Also run :func:`baselines`.

    Returns
    -------
    list of FlowRow

    Notes
    -----
    The frames are read as ``vmcl run`` reads them (:func:`vmcl.datasets.read_image` with ``picture=True``):
    a PGM or PPM whose declared maximum lies below its type's full scale is scaled to it.
    """
    from vmcl.pipeline import VisionMachine

    if not isinstance(sequence, FlowSequence):
        raise InputTypeError(f"sequence must be a vmcl.datasets.FlowSequence (read_flow_folder's), got "
                             f"{type(sequence).__name__}")
    others = check_bool(others, "others")
    vm = VisionMachine(motion_only(config), machine=machine)
    index = sequence.index
    # As `vmcl run` reads a frame (a picture's brightness: a 10-bit PGM's 1023 is white), so that a file is
    # measured here as it is run; read as stored, such frames were dark and the baselines' 8 bits few levels.
    paths = sequence.frames[:index + 2]
    frames = [read_image(path, picture=True) for path in paths]
    for path, frame in zip(paths, frames):
        if frame.shape != frames[index].shape:  # named here: the machine's refusal would name a frame's index
            raise InputValueError(f"{path} has shape {frame.shape}, the scored frame {paths[index].name} "
                                  f"{frames[index].shape}: a sequence's frames have one size and colour kind")
    vm.run(frames[index], next=frames[index + 1])  # the kernels are built before anything is timed
    pair = vm.run(frames[index], next=frames[index + 1])
    rows = [_row("vmcl two frames", pair.flow, sequence, pair.total_ms)]
    if index > 0:
        streamed = list(vm.stream(frames))[index]
        rows.append(_row("vmcl sequence", streamed.flow, sequence, streamed.total_ms))
    if others:
        grey = [_grey(frames[index]), _grey(frames[index + 1])]
        for name, method in baselines().items():
            start = time.perf_counter()
            flow = method(*grey)
            rows.append(_row(name, flow, sequence, (time.perf_counter() - start) * 1e3))
    return rows
