"""Fit the motion cue's variational refinement on rendered scenes (the training data), never on the real
sequences.

Run: python benchmarks/motion_variational_fit.py [--out benchmarks/results/motion_variational_fit.md]

The training scenes are benchmarks/motion_lucas_kanade_fit.py's: benchmarks/motion_fit.py's (every moving
preset of vmcl.scenes at 256 x 256 and 384 x 384, motions scaled by 1, 2 and 4), each also with its next
frame's response changed (a camera's exposure changing between frames, which breaks brightness constancy
and not gradient constancy). The pipeline runs with motion only and every other setting its default (the
Lucas-Kanade steps included). Each setting of GRID (the fixed-point iterations, none included, and the
smoothness weight alpha; vmcl.early.variational's DELTA, GAMMA, SWEEPS and multigrid as they are) is
scored by the geometric mean of the restored flow's EPE over the scenes, as the Lucas-Kanade steps' fit scores (its
docstring says why: a refinement is for sub-pixel precision, and the arithmetic mean is decided by the
few scenes whose motion lies beyond the matcher's search). The rule: the fewest iterations among the
settings within TOLERANCE of the best score (each iteration costs a multigrid V-cycle), then the best
score among them. The choice is vmcl.early.variational's ALPHA and ITERATIONS (the refinement's own
defaults); the machine leaves the refinement off by default for its cost (``[motion]
variational_iterations`` turns it on), which benchmarks/results/motion.md measures. The arithmetic mean is
reported beside it.

benchmarks/motion.py scores the real sequences with the defaults and chooses nothing.
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import itertools
import platform
from pathlib import Path

from motion_fit import RESULTS, training_scenes
from motion_lucas_kanade_fit import exposure_data, geometric_means, ranked_rows, score_sections

import vmcl
from vmcl.early import variational
from vmcl.pipeline import MotionConfig

GRID = [(0, 10.0)] + list(itertools.product((1, 2, 3, 5, 10, 20), (20.0, 40.0, 80.0, 160.0, 320.0, 640.0, 1280.0)))
"""(fixed-point iterations, 0 for none; alpha). The earlier runs of this fit relaxed on the pixel grid alone,
which converges slowly: they chose their grids' largest iterations (40, the cap set for cost). With the
multigrid a few iterations come near the solution; alpha's range is the one those runs found its best
inside (10 to 2560), at finer steps."""
TOLERANCE = 0.01
"""The chosen setting's score is within this share of the best one's."""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=RESULTS / "motion_variational_fit.md")
    args = parser.parse_args()
    machine = vmcl.Machine()
    scenes = training_scenes()
    data = exposure_data(scenes)
    scores = score_sections(machine, data, [
        (setting, dataclasses.replace(MotionConfig(), variational_iterations=setting[0],
                                      variational_alpha=setting[1]))
        for setting in GRID])
    means = geometric_means(scores)
    plain = len(scenes)
    best = float(means.min())
    near = [k for k in range(len(GRID)) if means[k] <= best * (1 + TOLERANCE)]
    fewest = min(GRID[k][0] for k in near)
    chosen = min((k for k in near if GRID[k][0] == fewest), key=lambda k: means[k])
    iterations, alpha = GRID[chosen]
    names = [name for name, _, _ in data]
    lines = [
        "# The motion cue's variational refinement, fitted on rendered scenes",
        "",
        (f"Measured {datetime.datetime.now():%Y-%m-%d %H:%M} on {machine.device.name.strip()}, Python "
         f"{platform.python_version()}. Produced by `python benchmarks/motion_variational_fit.py`."),
        "",
        ("Training scenes: benchmarks/motion_lucas_kanade_fit.py's (vmcl.scenes presets at 256 x 256 and 384 x 384, "
         "noise 0.01, motions scaled by 1, 2, 4, each also with its next frame's exposure changed); the pipeline "
         "with motion only, every other setting its default; the refinement's delta "
         f"{variational.DELTA:g}, gamma {variational.GAMMA:g}, one multigrid V-cycle per iteration with "
         f"{variational.SWEEPS} over-relaxation sweeps before and after each level's coarse correction. EPE "
         "(px) of the restored flow over the visible pixels; the score is its geometric mean over the scenes "
         "(see the script's docstring), also given over the plain and the exposure scenes apart. Best score "
         "first."),
        "",
        (f"Chosen: the fewest iterations among the settings within {TOLERANCE:.0%} of the best score "
         f"({best:.4f}), then the best score among them: {iterations} iterations, alpha {alpha:g} (score "
         f"{means[chosen]:.4f}, mean EPE {scores[chosen].mean():.4f}; without the refinement {means[0]:.4f} and "
         f"{scores[0].mean():.4f})."),
        "",
        ("| score (geometric mean EPE) | plain scenes | exposure scenes | mean EPE | iterations | alpha | "
         + " | ".join(names) + " |"),
        "|---|---|---|---|---|---|" + "---|" * len(names),
    ]
    lines += ranked_rows(scores, plain, [f"{steps} | {weight:g}" for steps, weight in GRID])
    args.out.write_text("\n".join(lines) + "\n")
    print("\n".join(lines[:8]))


if __name__ == "__main__":
    main()
