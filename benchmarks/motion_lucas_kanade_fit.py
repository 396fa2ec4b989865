"""Fit the motion cue's Lucas-Kanade steps on rendered scenes (the training data), never on the real
sequences.

Run: python benchmarks/motion_lucas_kanade_fit.py [--out benchmarks/results/motion_lucas_kanade_fit.md]

The training scenes are benchmarks/motion_fit.py's (every moving preset of vmcl.scenes at 256 x 256 and
384 x 384, motions scaled by 1, 2 and 4), each also with its next frame's response changed as
benchmarks/stereo_training.py changes a right view's (levels raised to EXPOSURE_GAMMA): a video camera's
automatic exposure, or the light, changes between frames, and the rendered frames alone would never show
the steps' brightness constancy failing. The pipeline runs with motion only and every other setting its
default. Each setting of GRID (the number of steps, none included, the window's scale, and the scale of
the Gaussian taken from the frames first, none included) is scored by the geometric mean of the restored
flow's EPE over the scenes. The rule: the default is the setting with the fewest steps, then the smallest
window, then no high-pass before one, among those within TOLERANCE of the best score (each step costs a
pass over the frames and five Gaussians), so the steps ship only if they pay.

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
import itertools
import platform
from pathlib import Path
from typing import Any

import numpy as np
from motion_fit import RESULTS, epe, motion_only, training_scenes
from stereo_training import EXPOSURE_GAMMA

import vmcl
from vmcl.pipeline import MotionConfig, VisionMachine

GRID = [(0, 3.0, 0.0)] + list(itertools.product((1, 2, 3), (3.0, 4.5, 6.0), (0.0, 2.0, 4.0, 8.0)))
"""(steps, window scale in px, high-pass scale in px: 0 none)."""
TOLERANCE = 0.01
"""The chosen setting's score is within this share of the best one's."""


def exposure_variant(frame: np.ndarray) -> np.ndarray:
    """A rendered frame (float in [0, 1]) with its response changed by EXPOSURE_GAMMA."""
    return np.clip(frame, 0, 1) ** EXPOSURE_GAMMA


def exposure_data(scenes: list) -> list[tuple[str, Any, np.ndarray]]:
    """(name, scene, next frame) of every training scene with its own next frame, then of every one with its
    next frame's exposure changed (exposure_variant)."""
    return ([(name, scene, scene.left_next) for name, scene in scenes]
            + [(f"{name} (exposure)", scene, exposure_variant(scene.left_next)) for name, scene in scenes])


def score_sections(machine: vmcl.Machine, data: list, sections: list[tuple[tuple, MotionConfig]]) -> np.ndarray:
    """The restored flow's EPE of the motion-only machine with each (setting, section), on each of ``data``
    (exposure_data), a row per section; each row printed after its setting as it comes."""
    scores = np.zeros((len(sections), len(data)))
    for row, (setting, section) in enumerate(sections):
        vm = VisionMachine(motion_only(section), machine=machine)
        for column, (_, scene, following) in enumerate(data):
            scores[row, column] = epe(vm.run(scene.left, next=following), scene)
        print(*setting, " ".join(f"{s:.3f}" for s in scores[row]), flush=True)
    return scores


def geometric_means(scores: np.ndarray) -> np.ndarray:
    """Each row's geometric mean over the scenes (the fits' score; the fit's docstring says why)."""
    return np.exp(np.log(scores).mean(axis=1))


def ranked_rows(scores: np.ndarray, plain: int, cells: list[str]) -> list[str]:
    """Table rows, best score first: the score, its parts over the first ``plain`` scenes and the rest (the
    exposure scenes), the mean EPE, each setting's ``cells`` (already joined) and every scene's EPE."""
    means = geometric_means(scores)
    rows = []
    for k in np.argsort(means, kind="stable"):
        plain_score, exposure_score = (float(np.exp(np.log(part).mean())) for part in (scores[k, :plain],
                                                                                       scores[k, plain:]))
        rows.append(f"| {means[k]:.4f} | {plain_score:.4f} | {exposure_score:.4f} | {scores[k].mean():.4f} | "
                    f"{cells[k]} | " + " | ".join(f"{s:.3f}" for s in scores[k]) + " |")
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=RESULTS / "motion_lucas_kanade_fit.md")
    args = parser.parse_args()
    machine = vmcl.Machine()
    scenes = training_scenes()
    data = exposure_data(scenes)
    scores = score_sections(machine, data, [
        (setting, dataclasses.replace(MotionConfig(), lucas_kanade_iterations=setting[0],
                                      lucas_kanade_window=setting[1], lucas_kanade_highpass=setting[2]))
        for setting in GRID])
    means = geometric_means(scores)
    plain = len(scenes)
    best = float(means.min())
    chosen = min((k for k in range(len(GRID)) if means[k] <= best * (1 + TOLERANCE)), key=lambda k: GRID[k])
    steps, window, highpass = GRID[chosen]
    names = [name for name, _, _ in data]
    lines = [
        "# The motion cue's Lucas-Kanade steps, fitted on rendered scenes",
        "",
        (f"Measured {datetime.datetime.now():%Y-%m-%d %H:%M} on {machine.device.name.strip()}, Python "
         f"{platform.python_version()}. Produced by `python benchmarks/motion_lucas_kanade_fit.py`."),
        "",
        ("Training scenes: benchmarks/motion_fit.py's (vmcl.scenes presets at 256 x 256 and 384 x 384, noise "
         "0.01, motions scaled by 1, 2, 4), each also with its next frame's levels raised to "
         f"{EXPOSURE_GAMMA:g} (exposure); the pipeline with motion only, every other setting its default. EPE "
         "(px) of the restored flow over the visible pixels; the score is its geometric mean over the scenes "
         "(see the script's docstring), also given over the plain and the exposure scenes apart. Best score "
         "first."),
        "",
        (f"Chosen: the fewest steps, then the smallest window, then no high-pass, among the settings within "
         f"{TOLERANCE:.0%} of the best score ({best:.4f}): {steps} steps, window {window:g} px, high-pass "
         f"{highpass:g} px (score {means[chosen]:.4f}, mean EPE {scores[chosen].mean():.4f}; without steps "
         f"{means[0]:.4f} and {scores[0].mean():.4f})."),
        "",
        ("| score (geometric mean EPE) | plain scenes | exposure scenes | mean EPE | steps | window px | high-pass px | "
         + " | ".join(names) + " |"),
        "|---|---|---|---|---|---|---|" + "---|" * len(names),
    ]
    lines += ranked_rows(scores, plain, [f"{iterations} | {size:g} | {cut:g}" for iterations, size, cut in GRID])
    args.out.write_text("\n".join(lines) + "\n")
    print("\n".join(lines[:8]))


if __name__ == "__main__":
    main()
