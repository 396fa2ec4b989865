"""The steady state of a stream, timed as a video consumer sees it: a helper of benchmarks/pipeline.py and
benchmarks/motion.py (benchmarks/ is a folder of scripts, not a package: they import it by name).

A stream's first frame has no past (its MRFs start cold) and its last has no next frame (no flow), so
neither is steady. Each Result is read as it comes and dropped, as a consumer of a video would: a list of
every frame's Result would hold tens of fresh host arrays per frame, and the first touch of their pages
would be timed as the frame's download.
"""

from __future__ import annotations

import statistics
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from vmcl import scenes
from vmcl.pipeline import VisionMachine


@dataclass(frozen=True)
class SteadyState:
    """Per steady frame of a stream: its wall time and each stage's (ms)."""

    totals: tuple[float, ...]
    stages: tuple[dict[str, float], ...]

    @property
    def median(self) -> float:
        return statistics.median(self.totals)

    def stage_median(self, name: str) -> float:
        return statistics.median(s.get(name, 0.0) for s in self.stages)


def blocks_sequence(size: int, frames: int) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """The rendered 'blocks' sequence at size x size (seed 1, noise 0.01): ``frames`` left frames and the one
    after them (for the independent runs' flow), and the right frames."""
    sequence = scenes.render_sequence(scenes.preset("blocks", shape=(size, size)), frames, seed=1, noise=0.01)
    return [s.left for s in sequence] + [sequence[-1].left_next], [s.right for s in sequence]


WARM_UP = 3
"""Frames of a first, untimed stream: every kernel a stream runs is built, and the buffers its frames use
are allocated and touched, before anything is timed."""


def steady_state(vm: VisionMachine, lefts: Sequence[np.ndarray], rights: Sequence[np.ndarray]) -> SteadyState:
    """``vm.stream`` over the frames (as many lefts as rights, more than WARM_UP), each Result read and dropped
    as it comes, after a stream of their first WARM_UP frames; the frames but the first and the last."""
    for _ in vm.stream(lefts[:WARM_UP], rights[:WARM_UP]):
        pass
    totals, stages = [], []
    for k, result in enumerate(vm.stream(lefts, rights)):
        if 0 < k < len(rights) - 1:
            totals.append(result.total_ms)
            stages.append(dict(result.stages))
    return SteadyState(tuple(totals), tuple(stages))
