"""Benchmark of Canny's detector and its hysteresis variants against OpenCV and scikit-image, in one run.

Run: python benchmarks/edges.py [--repeat 15] [--corridor 32] [--out benchmarks/results/edges.md]

Full Canny, smoothing included, sigma 1.4, thresholds 20 / 40 for every detector (Sobel magnitudes of the
8-bit image, the units all three share), on the camera image of scikit-image resized to 512^2 and
1024^2: vmcl.canny (NumPy in, NumPy out, like the baselines; and device in, device out) against
cv2.GaussianBlur + cv2.Canny (L2 gradient) and skimage.feature.canny. The calls are timed in
alternation, one of each per round, so drift in the machine's load hits all alike; figures are medians.
Then the two hysteresis variants on a 1024^2 spiral (one chain of weak pixels with a strong pixel at its
outer end): labelling by distance doubling against the paper's O(m) spreading activation. The machine
is shared with other engineers: compare ratios within one run.
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import statistics
import time
from pathlib import Path

import cv2
import numpy as np
import skimage
from skimage import data, feature

import vmcl
from vmcl.early.edges import canny, hysteresis_threshold
from vmcl.patterns import spiral

RESULTS = Path(__file__).resolve().parent / "results"
SIGMA, LOW, HIGH = 1.4, 20.0, 40.0


def interleaved(runs: dict, repeat: int) -> dict:
    """Median wall ms of each run, taken in alternation after one warm-up call each."""
    for run in runs.values():
        run()
    times = {key: [] for key in runs}
    for _ in range(repeat):
        for key, run in runs.items():
            start = time.perf_counter()
            run()
            times[key].append(time.perf_counter() - start)
    return {key: statistics.median(values) * 1e3 for key, values in times.items()}


def canny_table(machine: vmcl.Machine, side: int, repeat: int) -> tuple[list[str], dict[str, float]]:
    image = cv2.resize(data.camera(), (side, side), interpolation=cv2.INTER_LINEAR)
    device = machine.to_device(image)

    def on_device(**options):
        def run():
            canny(device, sigma=SIGMA, machine=machine, **options)
            machine.finish()
        return run

    fixed = {"low_threshold": LOW, "high_threshold": HIGH}
    runs = {
        "vmcl.canny (NumPy in/out)": lambda: canny(image, sigma=SIGMA, machine=machine, **fixed),
        "vmcl.canny (device in/out)": on_device(**fixed),
        "vmcl.canny, iterative hysteresis": on_device(method="iterative", **fixed),
        "vmcl.canny, no interpolation": on_device(interpolate=False, **fixed),
        "vmcl.canny, noise thresholds (global)": on_device(noise="global"),
        "vmcl.canny, noise thresholds (local)": on_device(noise="local"),
        "cv2.GaussianBlur + cv2.Canny": lambda: cv2.Canny(cv2.GaussianBlur(image, (0, 0), SIGMA), LOW, HIGH,
                                                          L2gradient=True),
        "skimage.feature.canny": lambda: feature.canny(image, sigma=SIGMA, low_threshold=LOW,
                                                       high_threshold=HIGH, mode="nearest"),
    }
    ms = interleaved(runs, repeat)
    cv, sk = ms["cv2.GaussianBlur + cv2.Canny"], ms["skimage.feature.canny"]
    rows = [f"| {side}^2 | {name} | {t:.2f} | {t / cv:.2f}x | {sk / t:.1f}x |" for name, t in ms.items()]
    return rows, ms


def kernel_breakdown(machine: vmcl.Machine, repeat: int) -> list[str]:
    image = machine.to_device(cv2.resize(data.camera(), (1024, 1024), interpolation=cv2.INTER_LINEAR))
    canny(image, sigma=SIGMA, low_threshold=LOW, high_threshold=HIGH, machine=machine)
    machine.timings()
    for _ in range(repeat):
        canny(image, sigma=SIGMA, low_threshold=LOW, high_threshold=HIGH, machine=machine)
    times = machine.timings()
    return [f"| {name} | {t['total_ms'] / repeat:.3f} |" for name, t in times.items()]


def spiral_table(machine: vmcl.Machine, corridor: int, repeat: int) -> list[str]:
    wall = spiral(1024, corridor=corridor)
    field = np.where(wall, np.float32(0.5), np.float32(0.0))
    field[0, 0] = 1.0
    device = machine.to_device(field)
    results, ms = {}, {}
    # The iterative variant's kernels were built by the Canny table; it runs once, the doubling median of
    # `repeat` (each after a warm-up).
    for method, rounds in (("doubling", repeat), ("iterative", 1)):
        times = []
        for _ in range(rounds):
            start = time.perf_counter()
            results[method] = hysteresis_threshold(device, low_threshold=0.4, high_threshold=0.9, method=method,
                                                   machine=machine)
            machine.finish()
            times.append(time.perf_counter() - start)
        ms[method] = statistics.median(times) * 1e3
    same = bool((results["doubling"].get() == results["iterative"].get()).all())
    whole = bool((results["doubling"].get().astype(bool) == wall).all())
    length = int(wall.sum())
    return [
        f"| doubling (label + mark + read marks) | {ms['doubling']:.2f} | 1.00x |",
        (f"| iterative (spreading activation, flag read every 16 steps) | {ms['iterative']:.1f} | "
        f"{ms['iterative'] / ms['doubling']:.0f}x |"),
        "",
        (f"Spiral of {length} weak pixels, corridor {corridor} (the chain runs about 1024^2 / (2 * {corridor}) "
        f"= {1024 * 1024 // (2 * corridor)} pixels from the strong pixel to the centre). Both variants "
        f"{'gave identical edges' if same else 'DISAGREED'}, "
        f"{'the whole spiral' if whole else 'NOT the whole spiral'}."),
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=15)
    parser.add_argument("--corridor", type=int, default=32)
    parser.add_argument("--out", type=Path, default=RESULTS / "edges.md")
    args = parser.parse_args()
    machine = vmcl.Machine(profile=True)
    load = os.getloadavg()[0]
    rows, figures = [], {}
    for side in (512, 1024):
        table, figures[side] = canny_table(machine, side, args.repeat)
        rows += table
        print("\n".join(table), flush=True)
    breakdown = kernel_breakdown(machine, args.repeat)
    spiral_rows = spiral_table(machine, args.corridor, 5)
    print("\n".join(spiral_rows))
    big = figures[1024]
    ours = big["vmcl.canny (NumPy in/out)"]
    verdict = (f"At 1024^2 vmcl.canny (NumPy in/out) took {ours / big['cv2.GaussianBlur + cv2.Canny']:.2f}x the "
               f"cv2 pair's time (bar: at most 3x) and was {big['skimage.feature.canny'] / ours:.1f}x faster than "
               f"skimage's canny (bar: at least 5x).")
    print(verdict)
    now = datetime.datetime.now().strftime("%Y-%m-%d %H:%M")
    text = "\n".join([
        "# Edge detection: vmcl.canny against OpenCV and scikit-image",
        "",
        (f"Measured {now} on {machine.device.platform.name} / {machine.device.name} ({machine.compute_units} "
        f"compute units), host {platform.machine()}, Python {platform.python_version()}, NumPy {np.__version__}, "
        f"OpenCV {cv2.__version__}, scikit-image {skimage.__version__}."),
        (f"Full Canny, smoothing included: sigma {SIGMA}, thresholds {LOW:g} / {HIGH:g} on Sobel magnitudes of the "
        "8-bit camera image resized to the size (the noise-threshold rows estimate their own). Wall-clock "
        f"medians of {args.repeat} rounds, the calls of a size taken in alternation. The machine is shared with "
        f"other engineers running tests (1-minute load average {load:.1f} on {os.cpu_count()} cores at the start): compare "
        "ratios within this run."),
        "",
        verdict,
        "",
        "| size | detector | ms | / cv2 pair | skimage / this |",
        "|---|---|---|---|---|",
        *rows,
        "",
        (f"## Where vmcl's time goes at 1024^2 (device in/out, thresholds given; device ms per call, mean of "
        f"{args.repeat})"),
        "",
        "| kernel | ms |",
        "|---|---|",
        *breakdown,
        "",
        "## Hysteresis variants on a 1024^2 spiral (device in/out, ms)",
        "",
        "| variant | ms | / doubling |",
        "|---|---|---|",
        *spiral_rows,
        "",
    ])
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(text)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
