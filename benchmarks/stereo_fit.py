"""Fit the stereo cue's defaults on the training pairs: the semi-global matcher's census margin and
smoothness prices, and whether the feature matcher still earns its place beside it.

Run: python benchmarks/stereo_fit.py

Every combination of the grid below runs the Vision Machine (stereo only, every other setting its
default) on every training pair of benchmarks/stereo_training.py: the rendered scenes and Middlebury
sawtooth and map, never a pair a benchmark reports. A combination's score is the mean of two means of
the restored disparity's bad-1 rate (on the evaluated pixels), over the rendered pairs and over the real
ones, which weigh equally so that the many rendered pairs do not decide alone. The best combination
gives the defaults (vmcl.early.semiglobal's CENSUS_THRESHOLD, P1, P2, EDGE_GAIN and StereoConfig's
feature_matches). Writes benchmarks/results/stereo_fit.md, every combination, best first.
"""

from __future__ import annotations

import datetime
import itertools
import sys
from pathlib import Path

import numpy as np
from stereo_training import middlebury_pairs, rendered_pairs

import vmcl
from vmcl import metrics
from vmcl.pipeline import Config, VisionMachine

GRID = {"feature_matches": (True, False), "census_threshold": (2.0, 3.0, 4.0), "p1": (32, 48, 64),
        "p2": (64.0, 96.0, 128.0), "edge_gain": (0.0, 0.1)}
ONLY_STEREO = {"motion": {"enabled": False}, "colour": {"enabled": False}, "texture": {"enabled": False}}


def main() -> int:
    machine = vmcl.Machine()
    rendered, real = rendered_pairs(), middlebury_pairs()
    pairs = rendered + real
    rows = []
    for values in itertools.product(*GRID.values()):
        stereo = dict(zip(GRID, values))
        vm = VisionMachine(Config.from_dict({"stereo": stereo, **ONLY_STEREO}), machine=machine)
        rates = [metrics.evaluate_disparity(vm.run(p.left, p.right).disparity, p.disparity, mask=p.mask).bad[1.0]
                 for p in pairs]
        score = (float(np.mean(rates[:len(rendered)])) + float(np.mean(rates[len(rendered):]))) / 2
        rows.append((score, values, rates))
        print(f"{stereo}: {score:.4f}", file=sys.stderr)
    rows.sort(key=lambda row: row[0])
    names = [p.name for p in pairs]
    lines = ["# The stereo cue's defaults, fitted on the training pairs", "",
             (f"Measured {datetime.datetime.now():%Y-%m-%d %H:%M}. The Vision Machine, stereo only, each pair's "
              "range found from the images. Score: the mean of the rendered pairs' mean and the real pairs' "
              "mean of the restored disparity's bad-1. Best first; the first row gives the defaults."), "",
             "| score | " + " | ".join(GRID) + " | " + " | ".join(names) + " |",
             "|---" * (1 + len(GRID) + len(names)) + "|"]
    lines += [f"| {score:.4f} | " + " | ".join(str(v) for v in values) + " | "
              + " | ".join(f"{r:.3f}" for r in rates) + " |" for score, values, rates in rows]
    out = Path(__file__).resolve().parent / "results" / "stereo_fit.md"
    out.write_text("\n".join(lines) + "\n")
    print("\n".join(lines[:8]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
