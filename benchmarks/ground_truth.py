"""Speed of the ground-truth tools: scene rendering, and the BSDS boundary benchmark.

Writes benchmarks/results/ground_truth.md. Run from the repository root:

    python benchmarks/ground_truth.py

- Rendering: each preset at 512 x 512, the stereo pair plus the next frame with all ground truth
  (depth, disparity, flow, albedo, illumination, occlusions, labels), median of several runs.
- BSDS: the benchmark's own golden set (figures beside the official ones), and the 10 BSDS500 test
  images under ../shared/datasets with a baseline edge map (Gaussian gradient magnitude, sigma 2) at
  5 and 10 thresholds, in one process and in two.
"""

from __future__ import annotations

import os
import platform
import statistics
import time
from pathlib import Path

import cv2
import numpy as np

from vmcl import datasets, metrics, scenes

ROOT = Path(__file__).resolve().parents[1]
DATA = (ROOT / ".." / "shared" / "datasets").resolve()
RESULTS = ROOT / "benchmarks" / "results" / "ground_truth.md"


def _machine() -> str:
    model = platform.processor() or platform.machine()
    cpuinfo = Path("/proc/cpuinfo")
    if cpuinfo.exists():
        names = [line.split(":", 1)[1].strip() for line in cpuinfo.read_text().splitlines()
                 if line.startswith("model name")]
        model = names[0] if names else model
    load = f", load average {os.getloadavg()[0]:.1f} at the start (the machine is shared)"
    return (f"{model}, {os.cpu_count()} logical CPUs, Python {platform.python_version()}, "
            f"NumPy {np.__version__}{load}")


def _timed(call, repeats: int) -> tuple[float, float]:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return statistics.median(times), min(times)


def render_table(repeats: int = 7) -> list[str]:
    rows = ["| preset | faces | median (ms) | best (ms) |", "|---|---|---|---|"]
    for name in scenes.PRESETS:
        world = scenes.preset(name, shape=(512, 512))
        scenes.render(world)
        median, best = _timed(lambda world=world: scenes.render(world, seed=1, noise=0.01), repeats)
        faces = sum(len(body.faces) for body in world.bodies)
        rows.append(f"| {name} | {faces} | {median * 1e3:.0f} | {best * 1e3:.0f} |")
    return rows


def _gradient_edges(image: np.ndarray) -> np.ndarray:
    grey = cv2.GaussianBlur(cv2.cvtColor(image, cv2.COLOR_RGB2GRAY).astype(np.float64), (0, 0), 2.0)
    magnitude = np.hypot(cv2.Sobel(grey, cv2.CV_64F, 1, 0), cv2.Sobel(grey, cv2.CV_64F, 0, 1))
    return magnitude / magnitude.max()


def bsds_tables() -> list[str]:
    golden = datasets.load_bsds(DATA, split="golden")
    start = time.perf_counter()
    scores = metrics.evaluate_boundaries([i.edge_map for i in golden.images], [i.boundaries for i in golden.images],
                                         thresholds=5)
    seconds = time.perf_counter() - start
    expected = golden.expected
    lines = [
        f"Golden set (bench/data, 5 images, 5 thresholds, {seconds:.1f} s):",
        "",
        "| figure | vmcl.metrics | official (expected_test_2) | difference |",
        "|---|---|---|---|",
    ]
    for label, ours, key in (("ODS F", scores.ods_f, "ods_f"), ("ODS recall", scores.ods_recall, "ods_recall"),
                             ("ODS precision", scores.ods_precision, "ods_precision"),
                             ("OIS F", scores.ois_f, "ois_f"), ("AP (Area_PR)", scores.average_precision,
                                                                 "average_precision")):
        lines.append(f"| {label} | {ours:.4f} | {expected[key]:.4f} | {ours - expected[key]:+.4f} |")
    test = datasets.load_bsds(DATA)
    maps = [_gradient_edges(i.image) for i in test.images]
    truths = [i.boundaries for i in test.images]
    lines += [
        "",
        f"{len(maps)} BSDS500 test images, baseline edge map (gradient magnitude, sigma 2):",
        "",
        "| thresholds | processes | time (s) | ODS F | OIS F | AP |",
        "|---|---|---|---|---|---|",
    ]
    for thresholds, workers in ((5, 1), (5, 2), (10, 2)):
        start = time.perf_counter()
        s = metrics.evaluate_boundaries(maps, truths, thresholds=thresholds, workers=workers)
        seconds = time.perf_counter() - start
        lines.append(f"| {thresholds} | {workers} | {seconds:.1f} | {s.ods_f:.4f} | {s.ois_f:.4f} | "
                     f"{s.average_precision:.4f} |")
    return lines


def main() -> None:
    lines = [
        "# Ground truth: rendering and boundary-benchmark speed",
        "",
        f"Machine: {_machine()}. Written by `python benchmarks/ground_truth.py`.",
        "",
        "## Rendering a 512 x 512 stereo pair plus the next frame, with all ground truth",
        "",
        *render_table(),
        "",
        "## BSDS boundary benchmark (matching by pyEdgeEval's port of the official correspondPixels)",
        "",
    ]
    if DATA.is_dir():
        lines += bsds_tables()
    else:
        lines.append(f"Skipped: no data at {DATA}.")
    lines += [
        "",
        "The matcher adds random outlier edges to its assignment graph (as the official code does), so the",
        "figures move in the fourth decimal from run to run.",
        "",
    ]
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text("\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
