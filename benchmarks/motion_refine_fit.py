"""Fit the motion cue's weighted median of the flow on rendered scenes (the training data), never on the
real sequences.

Run: python benchmarks/motion_refine_fit.py [--out benchmarks/results/motion_refine_fit.md]

The training scenes are benchmarks/motion_fit.py's (every moving preset of vmcl.scenes at 256 x 256 and
384 x 384, motions scaled by 1, 2 and 4), the pipeline with motion only and every other setting its
default (the matcher's features, patch and levels as motion_fit.py chose them). Each setting of GRID (the
refinement off, or its radius, colour scale and stride) is scored by the mean EPE of the restored flow
over the scenes. The default is the setting with the fewest voters per pixel among those within
TOLERANCE of the best mean EPE: the refinement visits every voter of every pixel, so a larger window must
pay for itself. benchmarks/motion.py scores the real sequences with the defaults and chooses nothing.
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import platform
from pathlib import Path

import numpy as np
from motion_fit import RESULTS, epe, motion_only, training_scenes
from stereo_fit import voters_visited

import vmcl
from vmcl.pipeline import MotionConfig, VisionMachine

GRID = [{"refine": False}] + [{"refine": True, "refine_radius": radius, "refine_colour": colour, "refine_stride": stride}
                              for radius, stride in ((5, 1), (9, 2), (9, 3), (13, 2), (13, 3), (17, 3), (17, 4),
                                                     (17, 6), (25, 4), (25, 6), (25, 8), (33, 4), (33, 8))
                              for colour in (0.05, 0.1, 0.2)]
TOLERANCE = 0.01
"""The chosen setting's mean EPE is within this share of the best one's (stated before the first run)."""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=RESULTS / "motion_refine_fit.md")
    args = parser.parse_args()
    machine = vmcl.Machine()
    data = training_scenes()
    rows = []
    for values in GRID:
        section = dataclasses.replace(MotionConfig(), **values)
        vm = VisionMachine(motion_only(section), machine=machine)
        scores = [epe(vm.run(scene.left, next=scene.left_next), scene) for _, scene in data]
        rows.append((float(np.mean(scores)), values, scores))
        print(values, f"{np.mean(scores):.4f}", flush=True)
    rows.sort(key=lambda row: row[0])
    best = rows[0][0]
    chosen = min((row for row in rows if row[0] <= best * (1 + TOLERANCE)), key=lambda row: voters_visited(row[1]))[1]
    names = [name for name, _ in data]
    keys = ["refine", "refine_radius", "refine_colour", "refine_stride"]
    lines = [
        "# The motion cue's weighted median, fitted on rendered scenes",
        "",
        (f"Measured {datetime.datetime.now():%Y-%m-%d %H:%M} on {machine.device.name.strip()}, Python "
         f"{platform.python_version()}. Produced by `python benchmarks/motion_refine_fit.py`."),
        "",
        ("Training scenes: benchmarks/motion_fit.py's (vmcl.scenes presets at 256 x 256 and 384 x 384, noise "
         "0.01, motions scaled by 1, 2, 4); the pipeline with motion only, every other setting its default. "
         "EPE (px) of the restored flow over the visible pixels. Best mean EPE first."),
        "",
        (f"Chosen: the fewest voters per pixel among the settings within {TOLERANCE:.0%} of the best mean EPE "
         f"({best:.4f}): {chosen}."),
        "",
        "| mean EPE | voters | " + " | ".join(keys) + " | " + " | ".join(names) + " |",
        "|---|---|" + "---|" * (len(keys) + len(names)),
    ]
    for mean, values, scores in rows:
        lines.append(f"| {mean:.4f} | {voters_visited(values)} | " + " | ".join(str(values.get(k, "-")) for k in keys)
                     + " | " + " | ".join(f"{s:.3f}" for s in scores) + " |")
    args.out.write_text("\n".join(lines) + "\n")
    print("\n".join(lines[:8]))


if __name__ == "__main__":
    main()
