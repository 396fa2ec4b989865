"""Benchmark of the motion stage against OpenCV and scikit-image, in one run: speed, quality, streaming.

Run: python benchmarks/motion.py [--repeat 21] [--frames 8] [--out benchmarks/results/motion.md]

Speed: at RubberWhale's size (584 x 388, its two grey frames), the motion module's variants (delta 4,
patch 7: the running-maximum variant with and without sub-pixel refinement and with a 2-level pyramid,
the full-table variant; delta 6, patch 15; the sign of the LoG at delta 4, patch 21, 2 levels) against
cv2.calcOpticalFlowFarneback (pyr 0.5, levels 3, win 15, iters 3, poly 5 / 1.2) and cv2.DISOpticalFlow
(MEDIUM), and the whole machine with motion only (NumPy in, Result out), with its defaults and with the
variational refinement on. The module's figures are device arrays in and out, the Python call and a final
queue.finish() included; OpenCV's are NumPy in and out. All are taken in alternation, one of each per round, and the
medians of --repeat rounds are compared: the machine is shared and its load drifts, so only ratios
within one run mean anything. A profiled run gives the device time per kernel.

Quality: the machine's defaults (nothing chosen here; benchmarks/motion_fit.py chose them on rendered
scenes) on every flow folder of the data sets, in two-frame and sequence modes, and the same with the
variational refinement on at the setting benchmarks/motion_variational_fit.py chose (off by default for
its cost), beside DIS, Farneback and TV-L1 (vmcl.flow_evaluation). Streaming: the per-frame time of
VisionMachine.stream against independent runs, all cues, at 256^2 and 512^2, and its flow stages against DIS
medium; with the defaults and with the variational refinement on.
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import os
import platform
import statistics
import sys
import time
from pathlib import Path

import cv2
import numpy as np
from stream_timing import blocks_sequence, steady_state

import vmcl
from vmcl.datasets import find_flow_folders, load_flow, read_flow_folder
from vmcl.early import motion, variational
from vmcl.flow_evaluation import FlowRow, evaluate_sequence, motion_only
from vmcl.pipeline import Config, MotionConfig, VisionMachine

RESULTS = Path(__file__).resolve().parent / "results"
DATA = Path(__file__).resolve().parents[1] / ".." / "shared" / "datasets"

SPEED = {"delta": 4, "patch": 7}
FLAT = {"delta": 6, "patch": 15}
SIGNS = {"delta": 4, "patch": 21, "levels": 2, "features": "sign_log"}
REFINED = Config(motion=dataclasses.replace(MotionConfig(), variational_iterations=variational.ITERATIONS))
"""The machine with the variational refinement on, at its fitted setting (off by default: its cost)."""
WITH_REFINEMENT = ", variational refinement"


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
    default, refined = (VisionMachine(motion_only(config), machine=machine) for config in (Config(), REFINED))
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
        "vmcl sign_log, delta 4, patch 21, 2 levels": lambda: motion.flow(f0, f1, **SIGNS, machine=machine),
        "cv2 Farneback": lambda: farneback(pair.frame0, pair.frame1),
        "cv2 DIS MEDIUM": lambda: dis(pair.frame0, pair.frame1),
        "vmcl machine, motion only (NumPy in, Result out), defaults": lambda: default.run(pair.frame0,
                                                                                         next=pair.frame1),
        f"vmcl machine, motion only (NumPy in, Result out){WITH_REFINEMENT}": lambda: refined.run(
            pair.frame0, next=pair.frame1),
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


MIDDLEBURY = ("Dimetrodon", "Grove2", "Hydrangea", "RubberWhale", "Venus")
METHODS = ("vmcl two frames", "vmcl sequence", f"vmcl two frames{WITH_REFINEMENT}", f"vmcl sequence{WITH_REFINEMENT}",
           "OpenCV DIS medium", "OpenCV DIS fast", "OpenCV Farneback", "scikit-image TV-L1")


def quality(root: Path, machine: vmcl.Machine) -> tuple[list[str], dict]:
    """Every flow folder of the data sets: the machine's defaults and the other methods, in this run."""
    scores: dict[str, dict[str, FlowRow]] = {}
    for folder in find_flow_folders(root):
        sequence = read_flow_folder(folder)
        scores[sequence.name] = {row.method: row for row in evaluate_sequence(sequence, machine=machine)}
        scores[sequence.name].update({row.method + WITH_REFINEMENT: row for row in evaluate_sequence(
            sequence, config=REFINED, machine=machine, others=False)})
        print(sequence.name, {m: round(r.epe, 3) for m, r in scores[sequence.name].items()}, flush=True)
    methods = [m for m in METHODS if any(m in rows for rows in scores.values())]
    lines = ["| sequence | " + " | ".join(f"{m} EPE" for m in methods) + " |", "|---|" + "---|" * len(methods)]
    for name, rows in scores.items():
        cells = []
        for method in methods:
            row = rows.get(method)
            if row is None:
                cells.append("-")
                continue
            split = (f" ({row.epe_matched:.3f} / {row.epe_unmatched:.3f})"
                     if row.epe_matched is not None and row.epe_unmatched is not None else "")
            cells.append(f"{row.epe:.3f}{split}")
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    means = {m: float(np.mean([scores[n][m].epe for n in MIDDLEBURY])) for m in methods
             if not m.startswith("vmcl sequence")}
    lines.append("| mean of the 5 Middlebury pairs | "
                 + " | ".join(f"{means[m]:.3f}" if m in means else "-" for m in methods) + " |")
    return lines, scores


def streaming(machine: vmcl.Machine, frames: int) -> list[str]:
    """Per-frame time of the stream (temporal terms on) and of independent runs, all cues, and the flow
    stages against DIS medium on the same frames: the machine's defaults, and the same with the variational
    refinement on (REFINED's motion section, every other section the default)."""
    from vmcl.pipeline import VisionMachine

    header = ("| size | machine | stream ms per frame | independent runs ms per frame | stream / independent | "
              "flow stages ms (stream) | DIS medium ms | flow stages / DIS |")
    lines = [header, "|---|---|---|---|---|---|---|---|"]
    for size in (256, 512):
        lefts, rights = blocks_sequence(size, frames)
        grey = [np.clip(cv2.cvtColor(im, cv2.COLOR_RGB2GRAY) * 255, 0, 255).astype(np.uint8) for im in lefts]
        for label, config in (("defaults", Config()), (WITH_REFINEMENT[2:], REFINED)):
            vm = VisionMachine(config, machine=machine)
            streamed = steady_state(vm, lefts[:frames], rights)  # its warm-up builds every kernel the runs use
            alone = [vm.run(lefts[k], rights[k], lefts[k + 1]).total_ms for k in range(1, frames - 1)]
            dis_ms = []
            for k in range(1, frames - 1):
                start = time.perf_counter()
                dis(grey[k], grey[k + 1])
                dis_ms.append((time.perf_counter() - start) * 1e3)
            stream_ms = streamed.median
            alone_ms = statistics.median(alone)
            flow_ms = statistics.median(s["motion"] + s["mrf motion"] for s in streamed.stages)
            dis_median = statistics.median(dis_ms)
            lines.append(f"| {size} x {size} | {label} | {stream_ms:.0f} | {alone_ms:.0f} | "
                         f"{stream_ms / alone_ms:.2f} | {flow_ms:.0f} | {dis_median:.1f} | "
                         f"{flow_ms / dis_median:.1f} |")
            print(lines[-1], flush=True)
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=21)
    parser.add_argument("--frames", type=int, default=10, help="frames of the streaming measurement")
    parser.add_argument("--out", type=Path, default=RESULTS / "motion.md")
    args = parser.parse_args()
    if not DATA.is_dir():
        sys.exit(f"evaluation data not found at {DATA.resolve()}")
    machine = vmcl.default_machine()
    load = os.getloadavg()[0]
    pair = load_flow("RubberWhale", DATA)
    speed_lines, medians = speed(machine, pair, args.repeat)
    breakdown = kernel_breakdown(pair, args.repeat)
    quality_lines, scores = quality(DATA, machine)
    stream_lines = streaming(machine, args.frames)
    stamp = datetime.datetime.now().strftime("%Y-%m-%d %H:%M")
    device = f"{machine.device.platform.name} / {machine.device.name} ({machine.compute_units} compute units)"
    running = medians["vmcl running maximum, delta 4, patch 7"] / medians["cv2 Farneback"]
    two = float(np.mean([scores[n]["vmcl two frames"].epe for n in MIDDLEBURY]))
    dis_mean = float(np.mean([scores[n]["OpenCV DIS medium"].epe for n in MIDDLEBURY]))
    tvl1 = "scikit-image TV-L1"
    worse = [n for n in MIDDLEBURY if tvl1 in scores[n] and scores[n]["vmcl two frames"].epe > scores[n][tvl1].epe]
    with_past = [n for n, rows in scores.items() if "vmcl sequence" in rows]
    gains = {n: 1 - scores[n]["vmcl sequence"].epe / scores[n]["vmcl two frames"].epe for n in with_past}
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
        "## Quality on real sequences: the machine's defaults",
        "",
        ("Every folder of flow data in the data sets (vmcl.datasets.find_flow_folders): Middlebury flow (Baker "
         "et al., IJCV 2011), Yosemite (Barron, Fleet and Beauchemin, IJCV 1994; sky excluded) and the "
         "MPI-Sintel excerpts (Butler et al., ECCV 2012; 'easy' is alley_1, 'medium' cave_2; EPE over all "
         "valid pixels, with matched / unmatched in brackets). vmcl runs its defaults (vmcl.pipeline.Config(), "
         "motion only; nothing here was chosen on these sequences, see motion_fit.md): 'two frames' is the "
         "restored flow of the pair; 'sequence' streams the frames before the ground truth's (Middlebury "
         "frames 07-11, Sintel 1-3) with the temporal terms. DIS: OpenCV's presets; Farneback: OpenCV's sample "
         "parameters; TV-L1: scikit-image's defaults; all on the grey frames, in this run "
         "(vmcl.flow_evaluation)."),
        "",
        *quality_lines,
        "",
        (f"The columns '{WITH_REFINEMENT[2:]}' run the machine with its variational refinement on "
         f"(`[motion] variational_iterations = {variational.ITERATIONS}`, alpha {variational.ALPHA:g}: the "
         "setting benchmarks/motion_variational_fit.py chose on rendered scenes); it is off by default for its "
         "cost (the speed table's last two rows). The bars below are the defaults'."),
        "",
        (f"Bar (two frames, mean EPE of the 5 Middlebury pairs at most DIS medium's): {two:.3f} against "
         f"{dis_mean:.3f}, {'met' if two <= dis_mean else 'NOT met'}. Bar (no Middlebury pair worse than "
         f"TV-L1's): {'met' if not worse else 'NOT met (' + ', '.join(worse) + ')'}."),
        "",
        ("Bar (the sequence mode's EPE at least 10% below the two-frame mode's): "
         + "; ".join(f"{n} {100 * g:.0f}% {'met' if g >= 0.1 else 'NOT met'}" for n, g in gains.items()) + "."),
        "",
        f"## Streaming ({args.frames} frames of the rendered blocks sequence, all cues, noise 0.01)",
        "",
        ("Per-frame wall time of VisionMachine.stream (temporal terms on; after an untimed stream of its first "
         "frames, as benchmarks/pipeline.py times it) and of independent runs of the same frames, medians over the "
         "frames but the first and the last (no next frame); the flow stages are the motion module and its MRF "
         "in the stream; DIS medium on the same grey frame pairs. 'machine': the defaults, or the same with "
         f"the{WITH_REFINEMENT[1:]} on (its cost to a stream). Measured in one run on a shared machine: "
         "compare within this table only."),
        "",
        *stream_lines,
        "",
    ]
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text("\n".join(text))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
