"""The disparity range found from the images (vmcl.early.disparity_range.estimate_range), and what it does
to the restored disparity.

For each pair: the true range of the evaluated pixels (for the table only: nothing here gives it to the
estimator), the range estimate_range finds with its defaults, and the Vision Machine's dense bad-1 rate
(the stereo MRF's restoration, default Config) in three runs: the range left to the machine (found from
the images), the old default 0..ceil(0.05 W), and the true range rounded outwards. Training data (where
the defaults were chosen): the rendered scenes of vmcl.scenes at 256 x 256 (visible pixels), and one
world with near objects whose disparities reach about 0.3 W. Test data (reported only): the Middlebury
pairs of ../shared/datasets (nonocc mask where there is one, else every pixel of known disparity) and
scikit-image's Motorcycle when it loads offline. Writes benchmarks/results/disparity_range.md.
"""

from __future__ import annotations

import datetime
import math
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np
from stereo_training import near_world

import vmcl
from vmcl import datasets, metrics, scenes
from vmcl.early.disparity_range import estimate_range
from vmcl.pipeline import Config, VisionMachine

OLD_SHARE = 0.05  # the default range before the estimate: 0 .. ceil(0.05 W)


def cases(root: Path) -> list[tuple[str, str, np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
    """(set, name, left, right, true disparity, evaluated pixels) for every pair."""
    found = []
    for name in scenes.PRESETS:
        s = scenes.render(scenes.preset(name, shape=(256, 256)), seed=0, noise=0.01)
        found.append(("training", name, s.left, s.right, s.disparity, ~s.occluded_stereo & np.isfinite(s.disparity)))
    s = scenes.render(near_world(), seed=0, noise=0.01)
    found.append(("training", "near objects", s.left, s.right, s.disparity,
                  ~s.occluded_stereo & np.isfinite(s.disparity)))
    for name in ("tsukuba", "venus", "teddy", "sawtooth", "map") if root.is_dir() else ():
        pair = datasets.load_stereo(name, root)
        mask = pair.masks.get("nonocc", np.isfinite(pair.disparity))
        found.append(("test", name, pair.left, pair.right, pair.disparity, mask))
    try:
        from skimage import data
        left, right, disparity = data.stereo_motorcycle()
    except (ImportError, OSError, ValueError) as error:  # not installed, or not in its cache offline
        print(f"Motorcycle skipped: {error}", file=sys.stderr)
    else:
        disparity = np.where(np.isfinite(disparity), disparity, np.nan).astype(np.float32)
        found.append(("test", "motorcycle", left, right, disparity, np.isfinite(disparity)))
    return found


def bad1(machine: vmcl.Machine, left, right, truth, mask, stereo: dict) -> tuple[float, list[str]]:
    result = VisionMachine(Config.from_dict({"stereo": stereo}), machine=machine).run(left, right)
    return metrics.evaluate_disparity(result.disparity, truth, mask=mask).bad[1.0], result.notes


def main() -> int:
    machine = vmcl.Machine()
    root = Path(__file__).resolve().parents[2] / "shared" / "datasets"
    rows = []
    for group, name, left, right, truth, mask in cases(root):
        known = truth[mask & np.isfinite(truth)]
        low, high = float(known.min()), float(known.max())
        width = left.shape[1]
        start = time.perf_counter()
        estimate = estimate_range(left, right, machine=machine)
        took = (time.perf_counter() - start) * 1e3
        estimated, notes = bad1(machine, left, right, truth, mask, {})
        old, _ = bad1(machine, left, right, truth, mask, {"d_min": 0, "d_max": math.ceil(OLD_SHARE * width)})
        true, _ = bad1(machine, left, right, truth, mask, {"d_min": math.floor(low), "d_max": math.ceil(high)})
        contains = estimate.d_min <= math.floor(low) and estimate.d_max >= math.ceil(high)
        rows.append((group, name, f"{left.shape[1]} x {left.shape[0]}", f"{low:.1f}..{high:.1f}",
                     f"{estimate.d_min}..{estimate.d_max}" + ("" if estimate.decided else " (fallback)"),
                     "yes" if contains else "no", f"1/{2**estimate.level}", f"{100 * estimate.confident:.0f}%",
                     f"{took:.0f}", f"{100 * estimated:.1f}%", f"{100 * old:.1f}%", f"{100 * true:.1f}%"))
        print(" | ".join(rows[-1]), "|", "; ".join(notes), file=sys.stderr)
    now = datetime.datetime.now().strftime("%Y-%m-%d %H:%M")
    machine_line = (f"Measured {now} on {machine.device.platform.name} / {machine.device.name} "
                    f"({platform.machine()}, {os.cpu_count()} logical CPUs); load average before: "
                    f"{os.getloadavg()[0]:.1f}.")
    legend = ("True range: of the evaluated pixels (for this table only). Estimated: `estimate_range` with its "
              "defaults, margin included (the machine's range when the Config gives none). Contains: the "
              "estimate holds the true range rounded outwards. Level: the coarse level it matched at first; "
              "confident: the share of that level's pixels whose match was kept. ms: the estimate alone "
              "(kernel builds included on a new size). Bad-1: the Vision Machine's dense disparity (the stereo "
              "MRF's restoration, default Config), share of evaluated pixels off by more than 1 px; "
              f"'5% default': the old range 0..ceil({OLD_SHARE} W); 'true range': the true range rounded "
              "outwards, given as d_min/d_max.")
    evaluated = ("Evaluated pixels: rendered scenes, the visible ones; Middlebury tsukuba, venus and teddy, the "
                 "nonocc mask; sawtooth, map and Motorcycle (scikit-image), every pixel of known disparity.")
    header = ("| set | pair | size | true range | estimated | contains | level | confident | ms | bad-1 estimated "
              "| bad-1 5% default | bad-1 true range |")
    lines = ["# The disparity range found from the images", "", machine_line, "", legend, "", evaluated, "",
             header, "|---" * 12 + "|"]
    lines += ["| " + " | ".join(row) + " |" for row in rows]
    out = Path(__file__).resolve().parent / "results" / "disparity_range.md"
    out.write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
