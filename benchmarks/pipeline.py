"""Frames per second of the whole Vision Machine (stereo + motion + colour + texture + MRF + integration).

Seed section "The Vision Machine System"; the bar of issue 9: a 256 x 256 frame with all cues in under
1 s on this project's 2-core machine. Each size runs the "blocks" scene once to build the kernels, then
REPEATS timed runs; the table gives the median wall time per frame and each stage's median, for the
default solver (mean field) and for ICM. Then the quality of the dense disparity, with the depth MRF's
data backfilled by intensity matches (the default) and from the edge matches alone: bad-1 on Middlebury
v2 (nonocc mask; when ../shared/datasets is present) and on the "blocks" and "cues" scenes (visible
pixels). Every run takes the pipeline's defaults: no disparity range is given, so the machine searches the
range it finds from the images (vmcl.early.disparity_range.estimate_range), never one from the ground
truth. Writes benchmarks/results/pipeline.md.
"""

from __future__ import annotations

import os
import statistics
import sys
from pathlib import Path

import numpy as np

import vmcl
from vmcl import datasets, metrics, scenes
from vmcl.pipeline import Config, VisionMachine

REPEATS = 3
SIZES = (256, 512)
METHODS = ("meanfield", "icm")


def measure(size: int, method: str, machine: vmcl.Machine) -> tuple[float, dict[str, float]]:
    s = scenes.render(scenes.preset("blocks", shape=(size, size)), seed=0, noise=0.01)
    vm = VisionMachine(Config.from_dict({"mrf": {"method": method}}), machine=machine)
    vm.run(s.left, s.right, s.left_next)
    runs = [vm.run(s.left, s.right, s.left_next) for _ in range(REPEATS)]
    stages = {name: statistics.median(r.stages[name] for r in runs) for name in runs[0].stages}
    return statistics.median(r.total_ms for r in runs), stages


def dense_quality(machine: vmcl.Machine) -> list[str]:
    """Dense bad-1 with and without the backfill, and bad-0.5 with it, as table lines."""
    cases = []
    for name in ("blocks", "cues"):
        s = scenes.render(scenes.preset(name, shape=(256, 256)), seed=0, noise=0.01)
        cases.append((name, s.left, s.right, s.disparity, ~s.occluded_stereo & np.isfinite(s.disparity)))
    root = Path(__file__).resolve().parents[2] / "shared" / "datasets"
    for name in ("tsukuba", "venus", "teddy") if root.is_dir() else ():
        pair = datasets.load_stereo(name, root)
        cases.append((name, pair.left, pair.right, pair.disparity, pair.masks["nonocc"]))
    caption = ("Dense disparity bad-1 and bad-0.5 (the stereo MRF's restoration; Middlebury: nonocc mask, scenes: visible "
               "pixels; the pipeline's defaults, the disparity range found from the images, none from the "
               "ground truth):")
    lines = ["", caption, "", ("| data | edge matches backfilled by intensity matches | edge matches alone "
             "| bad 0.5, backfilled |"), "|---|---|---|---|"]
    notes = []
    for name, left, right, truth, mask in cases:
        scores = []
        for backfill in (True, False):
            config = Config.from_dict({"stereo": {"backfill": backfill}})
            result = VisionMachine(config, machine=machine).run(left, right)
            scores.append(metrics.evaluate_disparity(result.disparity, truth, mask=mask).bad)
            if backfill:
                notes += [f"{name}: {note}" for note in result.notes if "disparity range" in note]
        lines.append(f"| {name} | {100 * scores[0][1.0]:.1f}% | {100 * scores[1][1.0]:.1f}% "
                     f"| {100 * scores[0][0.5]:.1f}% |")
        print(lines[-1], file=sys.stderr)
    return lines + ["", "The range each run searched, as its notes state it:", ""] + [f"- {note}" for note in notes]


def main() -> int:
    machine = vmcl.Machine()
    lines = ["# The whole Vision Machine per frame", "",
             (f"Device: {machine.device.platform.name} / {machine.device.name}; load average before: "
             f"{os.getloadavg()[0]:.1f}; median of {REPEATS} runs of the 'blocks' scene (all cues: stereo with "
             "feedback, motion, colour, texture, four MRFs, integration), wall time including every transfer."), ""]
    rows = {}
    for size in SIZES:
        for method in METHODS:
            total, stages = measure(size, method, machine)
            rows[(size, method)] = (total, stages)
            print(f"{size} {method}: {total:.0f} ms", file=sys.stderr)
    lines += ["| size | MRF solver | ms per frame | frames per second | under 1 s |", "|---|---|---|---|---|"]
    for (size, method), (total, _) in rows.items():
        lines.append(f"| {size} x {size} | {method} | {total:.0f} | {1000 / total:.2f} | "
                     f"{'yes' if total < 1000 else 'no'} |")
    names = list(next(iter(rows.values()))[1])
    lines += ["", "Stage breakdown (median wall ms; each stage ends with the queue drained):", "",
              "| stage | " + " | ".join(f"{s} {m}" for s, m in rows) + " |", "|---" * (len(rows) + 1) + "|"]
    for name in names:
        lines.append(f"| {name} | " + " | ".join(f"{stages.get(name, 0):.0f}" for _, stages in rows.values()) + " |")
    lines += dense_quality(machine)
    out = Path(__file__).resolve().parent / "results" / "pipeline.md"
    out.write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
