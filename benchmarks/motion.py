"""Benchmark of the motion module (patch-correlation optical flow) against OpenCV, in one run.

Run: python benchmarks/motion.py [--repeat 21] [--out benchmarks/results/motion.md]

Speed: at RubberWhale's size (584 x 388, its two grey frames), vmcl's flow (delta 4, patch 7: the
running-maximum variant with and without sub-pixel refinement and with a 2-level pyramid, the full-table
variant; delta 6, patch 15; and the sign of the LoG at delta 4, patch 21, 2 levels, the configuration of
the quality test) against
cv2.calcOpticalFlowFarneback (pyr 0.5, levels 3, win 15, iters 3, poly 5 / 1.2) and cv2.DISOpticalFlow
(MEDIUM). vmcl figures are device arrays in and out, the Python call
and a final queue.finish() included; OpenCV's are NumPy in and out. All are taken in alternation, one of
each per round, and the medians of --repeat rounds are compared: the machine is shared and its load
drifts, so only ratios within one run mean anything. A profiled run gives the device time per kernel.

Quality: EPE and AAE per sequence (Middlebury flow, Yosemite without the sky) for vmcl's configurations
beside Farneback and DIS computed in the same run, and EPE on vmcl.scenes presets (non-occluded pixels).
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import statistics
import sys
import time
from pathlib import Path

import cv2
import numpy as np

import vmcl
from vmcl import scenes
from vmcl.datasets import FLOW_SCENES, load_flow
from vmcl.early import motion
from vmcl.metrics import evaluate_flow

RESULTS = Path(__file__).resolve().parent / "results"
DATA = Path(__file__).resolve().parents[1] / ".." / "shared" / "datasets"

SPEED = {"delta": 4, "patch": 7}
FLAT = {"delta": 6, "patch": 15}
BEST = {"delta": 4, "patch": 21, "levels": 2, "features": "sign_log"}
CONFIGS = {
    "vmcl delta 4 patch 7": SPEED,
    "vmcl delta 6 patch 15": FLAT,
    "vmcl delta 6 patch 15, no sub-pixel": dict(FLAT, subpixel=False),
    "vmcl delta 4 patch 15, 2 levels": {"delta": 4, "patch": 15, "levels": 2},
    "vmcl delta 4 patch 21, 2 levels, log": dict(BEST, features="log"),
    "vmcl delta 4 patch 21, 1 level, sign_log": dict(BEST, levels=1),
    "vmcl delta 4 patch 21, 2 levels, sign_log": BEST,
}


def farneback(frame0: np.ndarray, frame1: np.ndarray) -> np.ndarray:
    return cv2.calcOpticalFlowFarneback(frame0, frame1, None, 0.5, 3, 15, 3, 5, 1.2, 0)


def dis(frame0: np.ndarray, frame1: np.ndarray) -> np.ndarray:
    return cv2.DISOpticalFlow_create(cv2.DISOPTICAL_FLOW_PRESET_MEDIUM).calc(frame0, frame1, None)


def interleaved(runs: dict, repeat: int, finish) -> dict:
    """Median wall-clock ms of each run, taken in alternation so drift in the load hits all alike."""
    for run in runs.values():
        run()
    finish()
    times = {key: [] for key in runs}
    for _ in range(repeat):
        for key, run in runs.items():
            start = time.perf_counter()
            run()
            finish()
            times[key].append(time.perf_counter() - start)
    return {key: statistics.median(t) * 1e3 for key, t in times.items()}


def speed(machine: vmcl.Machine, pair, repeat: int) -> tuple[list[str], dict]:
    f0, f1 = machine.to_device(pair.frame0), machine.to_device(pair.frame1)
    runs = {
        "vmcl running maximum, delta 4, patch 7": lambda: motion.flow(f0, f1, **SPEED, machine=machine),
        "vmcl full table, delta 4, patch 7": lambda: motion.flow(f0, f1, **SPEED, method="table",
                                                                 machine=machine),
        "vmcl running maximum, delta 4, patch 7, 2 levels": lambda: motion.flow(f0, f1, **SPEED, levels=2,
                                                                                machine=machine),
        "vmcl running maximum, delta 4, patch 7, no sub-pixel": lambda: motion.flow(f0, f1, **SPEED,
                                                                                    subpixel=False,
                                                                                    machine=machine),
        "vmcl delta 6, patch 15": lambda: motion.flow(f0, f1, **FLAT, machine=machine),
        "vmcl sign_log, delta 4, patch 21, 2 levels": lambda: motion.flow(f0, f1, **BEST, machine=machine),
        "cv2 Farneback": lambda: farneback(pair.frame0, pair.frame1),
        "cv2 DIS MEDIUM": lambda: dis(pair.frame0, pair.frame1),
    }
    medians = interleaved(runs, repeat, machine.finish)
    reference = medians["cv2 Farneback"]
    lines = ["| method | median ms | time / Farneback's |", "|---|---|---|"]
    for key, ms in medians.items():
        lines.append(f"| {key} | {ms:.1f} | {ms / reference:.2f} |")
        print(lines[-1], flush=True)
    return lines, medians


def kernel_breakdown(pair, repeat: int) -> list[str]:
    machine = vmcl.Machine(profile=True)
    f0, f1 = machine.to_device(pair.frame0), machine.to_device(pair.frame1)
    motion.flow(f0, f1, **SPEED, machine=machine)
    machine.timings()
    for _ in range(repeat):
        motion.flow(f0, f1, **SPEED, machine=machine)
    timings = machine.timings()
    total = sum(t["total_ms"] for t in timings.values()) / repeat
    lines = [(f"Device time per call, running maximum, delta 4, patch 7 (profiled, mean of {repeat}): "
             f"{total:.1f} ms in all."), "", "| kernel | calls per flow | ms per flow | share |", "|---|---|---|---|"]
    for name, t in sorted(timings.items(), key=lambda item: -item[1]["total_ms"]):
        ms = t["total_ms"] / repeat
        lines.append(f"| {name} | {t['calls'] // repeat} | {ms:.2f} | {100 * ms / total:.0f}% |")
    return lines


def quality(root: Path) -> tuple[list[str], dict]:
    names = ["Farneback", "DIS MEDIUM", *CONFIGS]
    lines = ["| sequence | " + " | ".join(f"{n} EPE / AAE" for n in names) + " |",
             "|---|" + "---|" * len(names)]
    epe = {n: [] for n in names}
    for scene in FLOW_SCENES:
        pair = load_flow(scene, root)
        flows = [farneback(pair.frame0, pair.frame1), dis(pair.frame0, pair.frame1)]
        flows += [motion.flow(pair.frame0, pair.frame1, **config).flow for config in CONFIGS.values()]
        cells = []
        for name, flow in zip(names, flows):
            scores = evaluate_flow(flow, pair.flow, mask=pair.mask)
            epe[name].append(scores.epe)
            dense = "" if scores.density > 0.999 else f" ({100 * scores.density:.0f}% dense)"
            cells.append(f"{scores.epe:.3f} / {scores.aae:.2f}{dense}")
        lines.append(f"| {scene} | " + " | ".join(cells) + " |")
        print(lines[-1], flush=True)
    lines.append("| mean EPE | " + " | ".join(f"{np.mean(epe[n]):.3f}" for n in names) + " |")
    return lines, {n: float(np.mean(v)) for n, v in epe.items()}


def synthetic() -> list[str]:
    lines = ["| preset (128 x 192) | vmcl delta 4 patch 11 EPE | Farneback EPE | DIS EPE |", "|---|---|---|---|"]
    for name in ("blocks", "cues", "textures", "corridor"):
        scene = scenes.render(scenes.preset(name, shape=(128, 192)), seed=1)
        grey = [np.clip(cv2.cvtColor(im, cv2.COLOR_RGB2GRAY) * 255, 0, 255).astype(np.uint8)
                for im in (scene.left, scene.left_next)]
        mask = ~scene.occluded_motion & np.isfinite(scene.flow).all(axis=-1)
        mask[:6], mask[-6:], mask[:, :6], mask[:, -6:] = False, False, False, False
        ours = motion.flow(scene.left, scene.left_next, delta=4, patch=11).flow
        row = [evaluate_flow(f, scene.flow, mask=mask).epe for f in (ours, farneback(*grey), dis(*grey))]
        lines.append(f"| {name} | " + " | ".join(f"{e:.3f}" for e in row) + " |")
        print(lines[-1], flush=True)
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=21)
    parser.add_argument("--out", type=Path, default=RESULTS / "motion.md")
    args = parser.parse_args()
    if not DATA.is_dir():
        sys.exit(f"evaluation data not found at {DATA.resolve()}")
    machine = vmcl.default_machine()
    load = os.getloadavg()[0]
    pair = load_flow("RubberWhale", DATA)
    speed_lines, medians = speed(machine, pair, args.repeat)
    breakdown = kernel_breakdown(pair, args.repeat)
    quality_lines, mean_epe = quality(DATA)
    synthetic_lines = synthetic()
    stamp = datetime.datetime.now().strftime("%Y-%m-%d %H:%M")
    device = f"{machine.device.platform.name} / {machine.device.name} ({machine.compute_units} compute units)"
    running = medians["vmcl running maximum, delta 4, patch 7"] / medians["cv2 Farneback"]
    best_name = min((name for name in CONFIGS), key=mean_epe.get)
    best = mean_epe[best_name]
    text = [
        "# Motion: patch-correlation optical flow against OpenCV",
        "",
        (f"Measured {stamp} on {device}, host {platform.machine()}, Python {platform.python_version()}, "
        f"NumPy {np.__version__}, OpenCV {cv2.__version__}. Produced by `python benchmarks/motion.py`."),
        "",
        "## Speed at RubberWhale's size (584 x 388, grey uint8)",
        "",
        ("vmcl: device arrays in and out, Python call and queue.finish() included; OpenCV: NumPy in and out, "
        "two threads. Farneback: pyr 0.5, levels 3, win 15, iters 3, poly 5 / 1.2. The methods ran in "
        f"alternation, one of each per round, medians of {args.repeat} rounds. The machine is shared with "
        f"other jobs and its load drifts (1-minute load average {load:.1f} on {os.cpu_count()} cores when "
        "this run began): compare within this table only."),
        "",
        *speed_lines,
        "",
        (f"Bar (running maximum at delta 4 within 1x Farneback's time): {running:.2f}x, "
        f"{'met' if running <= 1 else 'NOT met'}."),
        "",
        *breakdown,
        "",
        "## Quality on real sequences",
        "",
        ("Middlebury flow (Baker et al., IJCV 2011) and Yosemite (Barron, Fleet and Beauchemin, IJCV 1994; sky "
        "excluded), grey frames. EPE in pixels / AAE in degrees over the known pixels; vmcl's output is dense "
        "except where noted (flat patches have no estimate). All methods computed in this run."),
        "",
        *quality_lines,
        "",
        (f"Bar (vmcl's best configuration has a lower mean EPE than Farneback): {best_name}, {best:.3f} "
         f"against {mean_epe['Farneback']:.3f}, {'met' if best < mean_epe['Farneback'] else 'NOT met'}. "
         f"DIS MEDIUM: {mean_epe['DIS MEDIUM']:.3f}."),
        "",
        "## Synthetic scenes (vmcl.scenes, seed 1, non-occluded pixels 6 or more from the border)",
        "",
        *synthetic_lines,
        "",
    ]
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text("\n".join(text))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
