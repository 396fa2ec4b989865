"""Rows that are not epipolar lines: what a vertical offset does to the depth machine, and how well
vmcl.early.rectification measures it; chooses its note's threshold on the training pairs.

Run: python benchmarks/rectification.py [--out benchmarks/results/rectification.md]

Training pairs only (benchmarks/stereo_training.py: the rendered scenes, sawtooth and map with their
exposure variants). Each pair's right view is moved down by each of SHIFTS pixels (bilinearly, the border
reflected), and the depth machine (its defaults, depth only) runs on it, the range found from the images.
The rule, set before the first run: ROW_OFFSET_NOTE is the smallest shift whose mean bad-1 over the pairs
reaches RISE times the aligned pairs' mean. The table also gives what row_alignment measures at each shift
(the median of the tracks' vertical displacement; the real pairs are themselves a little off), and the
share of the pixels the left-right check leaves unconfirmed, the machine's earlier sign of a pair not
rectified.
"""

from __future__ import annotations

import argparse
import datetime
import platform
from pathlib import Path

import cv2
import numpy as np
from stereo_training import training_pairs

import vmcl
from vmcl import metrics
from vmcl.early.rectification import ROW_OFFSET_NOTE, row_alignment
from vmcl.early.semiglobal import match_semiglobal
from vmcl.pipeline import Config, VisionMachine
from vmcl.stereo_evaluation import DEPTH_ONLY

RESULTS = Path(__file__).resolve().parent / "results"
SHIFTS = (0.0, 0.25, 0.5, 1.0, 2.0, 3.0)
RISE = 1.5


def shifted(view: np.ndarray, shift: float) -> np.ndarray:
    """``view`` moved down by ``shift`` pixels, bilinearly, the border reflected."""
    height, width = view.shape[:2]
    return cv2.warpAffine(view, np.float32([[1, 0, 0], [0, 1, shift]]), (width, height), flags=cv2.INTER_LINEAR,
                          borderMode=cv2.BORDER_REFLECT)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=RESULTS / "rectification.md")
    args = parser.parse_args()
    machine = vmcl.Machine()
    vm = VisionMachine(Config.from_dict(DEPTH_ONLY), machine=machine)
    pairs = training_pairs()
    bad: dict[float, list[float]] = {s: [] for s in SHIFTS}
    measured: dict[float, list[float]] = {s: [] for s in SHIFTS}
    unconfirmed: dict[float, list[float]] = {s: [] for s in SHIFTS}
    for pair in pairs:
        for shift in SHIFTS:
            right = shifted(pair.right, shift)
            result = vm.run(pair.left, right)
            bad[shift].append(metrics.evaluate_disparity(result.disparity, pair.disparity, mask=pair.mask).bad[1.0])
            found = match_semiglobal(pair.left, right, machine=machine)
            unconfirmed[shift].append(float((found.occluded | found.mismatched).mean()))
            alignment = row_alignment(pair.left, right, disparity=found.filled)
            measured[shift].append(np.nan if alignment is None else alignment.offset)
        print(pair.name, [f"{bad[s][-1]:.3f}" for s in SHIFTS], [f"{measured[s][-1]:+.2f}" for s in SHIFTS], flush=True)
    aligned = float(np.mean(bad[0.0]))
    chosen = next((s for s in SHIFTS[1:] if np.mean(bad[s]) >= RISE * aligned), None)
    names = [pair.name for pair in pairs]
    lines = [
        "# Rows that are not epipolar lines",
        "",
        (f"Measured {datetime.datetime.now():%Y-%m-%d %H:%M} on {machine.device.name.strip()}, Python "
         f"{platform.python_version()}. Produced by `python benchmarks/rectification.py`."),
        "",
        ("Training pairs (benchmarks/stereo_training.py), each with its right view moved down by a shift (px). "
         "Bad-1: the depth machine's restored disparity (its defaults, depth only, the range found from the "
         "images), share of the known pixels more than 1 px off. Unconfirmed: the semi-global matcher's pixels "
         "the left-right check leaves half-occluded or mismatched. Measured: vmcl.early.rectification."
         "row_alignment's offset (the median vertical displacement of the tracked corners, px), each started at "
         "the semi-global matcher's disparity; the real pairs are themselves a little off at shift 0."),
        "",
        "| shift | mean bad-1 | mean unconfirmed | " + " | ".join(f"{name} bad-1 / measured" for name in names) + " |",
        "|---|---|---|" + "---|" * len(names),
    ]
    for shift in SHIFTS:
        cells = [f"{b:.3f} / {m:+.2f}" for b, m in zip(bad[shift], measured[shift])]
        lines.append(f"| {shift:g} | {np.mean(bad[shift]):.3f} | {np.mean(unconfirmed[shift]):.3f} | "
                     + " | ".join(cells) + " |")
    lines += ["", (f"Rule (set before the run): the note's threshold is the smallest shift whose mean bad-1 reaches "
                   f"{RISE} times the aligned pairs' ({aligned:.3f}): "
                   + (f"{chosen:g} px." if chosen is not None else "none of the shifts reaches it.")
                   + f" vmcl.early.rectification.ROW_OFFSET_NOTE is {ROW_OFFSET_NOTE:g} px.")]
    args.out.write_text("\n".join(lines) + "\n", encoding="utf-8")
    print(f"wrote {args.out}; chosen {chosen}")


if __name__ == "__main__":
    main()
