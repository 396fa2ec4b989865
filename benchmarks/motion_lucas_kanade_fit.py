"""Fit the motion cue's Lucas-Kanade steps on rendered scenes (the training data), never on the real
sequences.

Run: python benchmarks/motion_lucas_kanade_fit.py [--out benchmarks/results/motion_lucas_kanade_fit.md]

The training scenes are benchmarks/motion_fit.py's (every moving preset of vmcl.scenes at 256 x 256 and
384 x 384, motions scaled by 1, 2 and 4), the pipeline with motion only and every other setting its
default. Each setting of GRID (the number of steps, none included, and the window's scale) is scored by
the geometric mean of the restored flow's EPE over the scenes. The rule: the default is the setting with
the fewest steps, then the smallest window, among those within TOLERANCE of the best score (each step
costs a pass over the frames and five Gaussians), so the steps ship only if they pay.
benchmarks/motion.py scores the real sequences with the defaults and chooses nothing.

Why the geometric mean: the scenes' EPE spans 0.04 px to 12 px, and the arithmetic mean (the first run's
score, when the steps refined the MRF's restored flow) is decided by the three scenes whose motion lies
beyond the matcher's search, where a few more steps over a wider window drag a wrong flow a little
nearer; it chose 8 steps over a 6-px window, which worsened the piecewise-constant blocks scenes by a
third. Steps are for sub-pixel precision, so every scene's relative change weighs the same. The
arithmetic mean is reported beside it.
benchmarks/motion.py scores the real sequences with the defaults and chooses nothing.
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import platform
from pathlib import Path

import numpy as np
from motion_fit import RESULTS, epe, motion_only, training_scenes

import vmcl
from vmcl.pipeline import MotionConfig, VisionMachine

GRID = [(0, 3.0)] + [(iterations, window) for iterations in (1, 2, 3, 5, 8)
                     for window in (1.5, 2.0, 3.0, 4.5, 6.0, 9.0, 12.0)]
"""(steps, window scale in px)."""
TOLERANCE = 0.01
"""The chosen setting's score is within this share of the best one's."""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=RESULTS / "motion_lucas_kanade_fit.md")
    args = parser.parse_args()
    machine = vmcl.Machine()
    data = training_scenes()
    scores = np.zeros((len(GRID), len(data)))
    for row, (iterations, window) in enumerate(GRID):
        section = dataclasses.replace(MotionConfig(), lucas_kanade_iterations=iterations, lucas_kanade_window=window)
        vm = VisionMachine(motion_only(section), machine=machine)
        for column, (_, scene) in enumerate(data):
            scores[row, column] = epe(vm.run(scene.left, next=scene.left_next), scene)
        print(iterations, window, " ".join(f"{s:.3f}" for s in scores[row]), flush=True)
    means = np.exp(np.log(scores).mean(axis=1))
    best = float(means.min())
    chosen = min((k for k in range(len(GRID)) if means[k] <= best * (1 + TOLERANCE)), key=lambda k: GRID[k])
    names = [name for name, _ in data]
    lines = [
        "# The motion cue's Lucas-Kanade steps, fitted on rendered scenes",
        "",
        (f"Measured {datetime.datetime.now():%Y-%m-%d %H:%M} on {machine.device.name.strip()}, Python "
         f"{platform.python_version()}. Produced by `python benchmarks/motion_lucas_kanade_fit.py`."),
        "",
        ("Training scenes: benchmarks/motion_fit.py's (vmcl.scenes presets at 256 x 256 and 384 x 384, noise "
         "0.01, motions scaled by 1, 2, 4); the pipeline with motion only, every other setting its default. EPE (px) "
         "of the restored flow over the visible pixels; the score is its geometric "
         "mean over the scenes (see the script's docstring). Best score first."),
        "",
        (f"Chosen: the fewest steps, then the smallest window, among the settings within {TOLERANCE:.0%} of the "
         f"best score ({best:.4f}): {GRID[chosen][0]} steps, window {GRID[chosen][1]:g} px (score "
         f"{means[chosen]:.4f}, mean EPE {scores[chosen].mean():.4f}; without steps {means[0]:.4f} and "
         f"{scores[0].mean():.4f})."),
        "",
        "| score (geometric mean EPE) | mean EPE | steps | window px | " + " | ".join(names) + " |",
        "|---|---|---|---|" + "---|" * len(names),
    ]
    for k in np.argsort(means, kind="stable"):
        iterations, window = GRID[k]
        lines.append(f"| {means[k]:.4f} | {scores[k].mean():.4f} | {iterations} | {window:g} | "
                     + " | ".join(f"{s:.3f}" for s in scores[k]) + " |")
    args.out.write_text("\n".join(lines) + "\n")
    print("\n".join(lines[:8]))


if __name__ == "__main__":
    main()
