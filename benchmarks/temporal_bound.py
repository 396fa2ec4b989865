"""How much the past can tell about the present motion: the previous pair's flow as a prediction of this one.

Run: python benchmarks/temporal_bound.py [--data ../shared/datasets] [--out benchmarks/results/temporal_bound.md]

The sequence mode (vmcl.temporal) carries the previous frame's restored flow to the new frame and fuses it
with the new measurement, a prediction of constant velocity. What such a prediction can add depends on
whether the motion holds from one frame pair to the next, which this script measures on every real
sequence with a past: for the pair (t, t + 1) whose ground truth is known, the machine's two-frame flow
u_t; the two-frame flow of the pair before it, u_{t-1}, carried to frame t as the sequence mode carries it
(vmcl.temporal.Memory with the machine's [time] settings: along itself, pixel x reading u_{t-1} at
x - u_{t-1}(x), and none where time is broken: that position outside the frame, or its brightness unlike
frame t's there); their mean, the fusion of two equally trusted estimates; and the best blend of the two
(per pixel, the point between them nearest the truth: an oracle, the bound of any fusion of these two
fields). The sequence mode also searches around the prediction and restores the fused data with its MRF,
so it is not held to the bound; but where the bound itself is close to u_t's error, what the past adds
must come from elsewhere. Nothing here is fitted or chosen; the machine runs its defaults, motion only
(vmcl.flow_evaluation.motion_only).
"""

from __future__ import annotations

import argparse
import datetime
import platform
from pathlib import Path

import numpy as np

import vmcl
from vmcl.datasets import find_flow_folders, read_flow_folder, read_image
from vmcl.flow_evaluation import motion_only
from vmcl.metrics import evaluate_flow
from vmcl.pipeline import Config, TimeConfig, VisionMachine, as_image

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
SHARED = ROOT.parent / "shared" / "datasets"


def carried(machine: vmcl.Machine, time: TimeConfig, frames: list[np.ndarray], previous: np.ndarray) -> np.ndarray:
    """``previous``, the flow from ``frames[0]`` to ``frames[1]``, carried to ``frames[1]`` by the sequence mode's
    own step (:meth:`vmcl.temporal.Memory.carry`, with ``time``'s settings): along itself, each pixel x reading
    ``previous`` at x - previous(x); NaN where time is broken there (that position outside the frame, or the
    brightness there unlike the new frame's) and everywhere when the frame starts cold (a scene cut)."""
    memory = time.memory_of(machine)
    # The images as the machine reads them (float32 in [0, 1]): the brightness test's tolerance is on that scale.
    before, now = (machine.to_device(as_image(frame, "frame")) for frame in frames)
    flow = machine.to_device(np.ascontiguousarray(previous, np.float32))
    memory.begin(before)
    # The information only weighs the carried flow in the fusion; the prediction does not depend on it.
    memory.remember("motion", flow, machine.to_device(np.ones(previous.shape[:2], np.float32)), False)
    memory.end(flow)
    memory.begin(now)
    prediction = memory.carry("motion")
    return np.full_like(previous, np.nan) if prediction is None else prediction.prediction.get()


def closest_blend(first: np.ndarray, second: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """Per pixel, the point of the segment from ``first`` to ``second`` nearest ``truth``: the best that any
    blend of the two estimates with weights of its own at each pixel can do (``first`` where they agree)."""
    step = second - first
    length = (step**2).sum(axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        share = np.clip(((truth - first) * step).sum(axis=-1) / length, 0, 1)
    share = np.where(np.isfinite(share), share, 0)[..., None]
    return first + share * step


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=SHARED)
    parser.add_argument("--out", type=Path, default=RESULTS / "temporal_bound.md")
    args = parser.parse_args()
    machine = vmcl.Machine()
    vm = VisionMachine(motion_only(Config()), machine=machine)
    rows = []
    for folder in find_flow_folders(args.data):
        sequence = read_flow_folder(folder)
        t = sequence.index
        if t == 0:
            continue  # no past
        frames = [read_image(path) for path in sequence.frames[t - 1:t + 2]]
        now = vm.run(frames[1], next=frames[2]).flow
        # Where the carried flow has none (time broken), the two-frame flow stands in for it, as the machine's
        # measurement stands alone there, in every column alike: the columns then score the same pixels, none
        # of them counted as no motion.
        before = carried(machine, vm.config.time, frames[:2], vm.run(frames[0], next=frames[1]).flow)
        before = np.where(np.isfinite(before), before, now)
        mean = (now + before) / 2
        fields = (now, before, mean, closest_blend(now, before, sequence.flow))
        rows.append((sequence.name, *(evaluate_flow(np.nan_to_num(flow), sequence.flow, mask=sequence.mask).epe
                                      for flow in fields)))
        print(rows[-1], flush=True)
    lines = [
        "# The past as a prediction of the present motion",
        "",
        (f"Measured {datetime.datetime.now():%Y-%m-%d %H:%M} on {machine.device.name.strip()}, Python "
         f"{platform.python_version()}. Produced by `python benchmarks/temporal_bound.py`."),
        "",
        ("Every sequence of the data sets with a frame before the ground truth's pair (t, t + 1). EPE (px) over "
         "the ground truth's pixels of: the machine's two-frame flow of the pair (its defaults, motion only); "
         "the two-frame flow of the pair before, (t - 1, t), carried to frame t as the sequence mode carries it "
         "(vmcl.temporal.Memory, the [time] defaults: along itself, pixel x reading u_{t-1} at x - u_{t-1}(x); the "
         "two-frame flow where time is broken, that position outside the frame or its brightness unlike frame "
         "t's): a prediction of constant velocity; "
         "and the mean of the two, the fusion of two equally "
         "trusted estimates (the two-frame flow alone where the carried one has none); and the best blend, at each "
         "pixel the point between the two nearest the truth, which no fusion of these two estimates (weights of "
         "its own at each pixel) can beat. A carried flow far worse than the two-frame one says the motion "
         "changed between the pairs."),
        "",
        "| sequence | two frames (t, t + 1) | previous pair carried | mean of the two | best blend | best blend / two frames |",
        "|---|---|---|---|---|---|",
    ]
    for name, now, before, mean, best in rows:
        lines.append(f"| {name} | {now:.3f} | {before:.3f} | {mean:.3f} | {best:.3f} | {best / now:.2f} |")
    args.out.write_text("\n".join(lines) + "\n", encoding="utf-8")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
