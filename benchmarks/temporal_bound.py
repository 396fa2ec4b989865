"""How much the past can tell about the present motion: the previous pair's flow as a prediction of this one.

Run: python benchmarks/temporal_bound.py [--data ../shared/datasets] [--out benchmarks/results/temporal_bound.md]

The sequence mode (vmcl.temporal) carries the previous frame's restored flow to the new frame and fuses it
with the new measurement, a prediction of constant velocity. What such a prediction can add depends on
whether the motion holds from one frame pair to the next, which this script measures on every real
sequence with a past: for the pair (t, t + 1) whose ground truth is known, the machine's two-frame flow
u_t; the two-frame flow of the pair before it, u_{t-1}, carried to frame t (sampled at x - u_t(x), where
the pixel was); their mean, the fusion of two equally trusted estimates; and the best blend of the two
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

import cv2
import numpy as np

import vmcl
from vmcl.datasets import find_flow_folders, read_flow_folder, read_image
from vmcl.flow_evaluation import motion_only
from vmcl.metrics import evaluate_flow
from vmcl.pipeline import Config, VisionMachine

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
SHARED = ROOT.parent / "shared" / "datasets"


def carried(previous: np.ndarray, current: np.ndarray) -> np.ndarray:
    """``previous`` sampled where each pixel of the current frame was one frame before (x - current(x)),
    bilinearly; NaN outside the frame or where either flow has none."""
    height, width = current.shape[:2]
    rows, columns = np.mgrid[:height, :width].astype(np.float32)
    where = np.nan_to_num(current, nan=np.float32(1e6))  # a pixel without flow samples outside: NaN
    return cv2.remap(previous.astype(np.float32), columns - where[..., 0], rows - where[..., 1], cv2.INTER_LINEAR,
                     borderMode=cv2.BORDER_CONSTANT, borderValue=(np.nan, np.nan))


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
        # Where the carried flow has none (sampled outside the frame), the two-frame flow stands in for it, in
        # every column alike: the columns then score the same pixels, none of them counted as no motion.
        before = carried(vm.run(frames[0], next=frames[1]).flow, now)
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
         "the two-frame flow of the pair before, (t - 1, t), carried to frame t (sampled where each pixel was, "
         "x - u_t(x); the two-frame flow where that lies outside the frame): a prediction of constant velocity; "
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
