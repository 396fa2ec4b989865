"""Where the Vision Machine's device time goes, kernel by kernel, against this device's copy bandwidth.

Run: python benchmarks/roofline.py

A profiling Machine runs the whole machine (every cue, the 'blocks' scene, after a warm-up run that builds
the kernels) REPEATS times at each size. Per kernel, per frame: its family (kernels/<family>.cl), its
launches, its device time, the bytes of the buffers its launches are given (vmcl.Machine.timings: each
buffer once per launch, the compulsory traffic of a kernel that reads or writes each of its buffers
once), the effective bandwidth (those bytes over its device time) and that bandwidth's share of the copy
kernel's, measured in the same run (news.cl's copy of 64 MiB, benchmarks/primitives.py's yardstick).

How to read it: a kernel near 100% of the copy is at the memory roof, and only moving fewer bytes makes
it faster; one far below it is bound by something else (arithmetic, a serial loop of dependent steps,
too little parallel work for the device, launch overhead), and rethinking its work is what makes it
faster. A kernel that reads a buffer several times from beyond the caches can show more than 100%: its
real traffic is larger than the count. Operations are not counted (PoCL's CPU device has no hardware
counters to read them from), so the arithmetic roof is not drawn. Writes benchmarks/results/roofline.md (or
--out; the device: VMCL_DEVICE, as for every vmcl run).
"""

from __future__ import annotations

import argparse
import datetime
import os
import statistics
import sys
from collections import defaultdict
from pathlib import Path

from primitives import Bench, copy_bandwidth

import vmcl
from vmcl import scenes
from vmcl.pipeline import VisionMachine

REPEATS = 3
SIZES = (256, 512)
COPY_FLOATS = 16 * 1024 * 1024
TOP = 25
"""Kernels listed per size, by device time (the rest are summed in one row)."""


def profile(size: int, machine: vmcl.Machine) -> tuple[dict[str, dict[str, float]], float]:
    """Per-kernel figures per frame at ``size`` (medians over REPEATS frames), and the median frame's wall ms."""
    scene = scenes.render(scenes.preset("blocks", shape=(size, size)), seed=0, noise=0.01)
    vm = VisionMachine(machine=machine)
    vm.run(scene.left, scene.right, scene.left_next)
    machine.timings()
    frames, walls = [], []
    for _ in range(REPEATS):
        result = vm.run(scene.left, scene.right, scene.left_next)
        frames.append(result.kernels or machine.timings())
        walls.append(result.total_ms)
    names = set().union(*frames)
    per_frame = {name: {key: statistics.median(frame.get(name, {}).get(key, 0.0) for frame in frames)
                        for key in ("calls", "total_ms", "bytes")} for name in names}
    return per_frame, statistics.median(walls)


def table(per_frame: dict[str, dict[str, float]], families: dict[str, str], copy_gbs: float) -> list[str]:
    total = sum(entry["total_ms"] for entry in per_frame.values())
    ranked = sorted(per_frame.items(), key=lambda item: -item[1]["total_ms"])
    lines = ["| kernel | family | launches | device ms | share of device time | MB | GB/s | of the copy |",
             "|---|---|---|---|---|---|---|---|"]
    for name, entry in ranked[:TOP]:
        gbs = entry["bytes"] / entry["total_ms"] / 1e6 if entry["total_ms"] > 0 else 0.0
        lines.append(f"| {name} | {families.get(name, '?')} | {entry['calls']:.0f} | {entry['total_ms']:.2f} | "
                     f"{100 * entry['total_ms'] / total:.1f}% | {entry['bytes'] / 1e6:.1f} | {gbs:.2f} | "
                     f"{100 * gbs / copy_gbs:.0f}% |")
    rest = ranked[TOP:]
    if rest:
        ms = sum(entry["total_ms"] for _, entry in rest)
        lines.append(f"| {len(rest)} others | | {sum(e['calls'] for _, e in rest):.0f} | {ms:.2f} | "
                     f"{100 * ms / total:.1f}% | {sum(e['bytes'] for _, e in rest) / 1e6:.1f} | | |")
    return lines


def families_table(per_frame: dict[str, dict[str, float]], families: dict[str, str], copy_gbs: float) -> list[str]:
    grouped: dict[str, list[float]] = defaultdict(lambda: [0.0, 0.0, 0.0])
    for name, entry in per_frame.items():
        group = grouped[families.get(name, "?")]
        group[0] += entry["calls"]
        group[1] += entry["total_ms"]
        group[2] += entry["bytes"]
    total = sum(group[1] for group in grouped.values())
    lines = ["| family | launches | device ms | share of device time | MB | GB/s | of the copy |",
             "|---|---|---|---|---|---|---|"]
    for family, (calls, ms, moved) in sorted(grouped.items(), key=lambda item: -item[1][1]):
        gbs = moved / ms / 1e6 if ms > 0 else 0.0
        lines.append(f"| {family} | {calls:.0f} | {ms:.2f} | {100 * ms / total:.1f}% | {moved / 1e6:.1f} | "
                     f"{gbs:.2f} | {100 * gbs / copy_gbs:.0f}% |")
    return lines


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path(__file__).resolve().parent / "results" / "roofline.md")
    out = parser.parse_args().out
    machine = vmcl.Machine(profile=True)
    bench = Bench(machine, repeat=5)
    copy_bandwidth(bench, "64 MiB", COPY_FLOATS)
    copy_gbs = bench.copy_gbs["64 MiB"]
    lines = ["# Roofline: each kernel's device time against the copy bandwidth", "",
             (f"Measured {datetime.datetime.now():%Y-%m-%d %H:%M}. Device: {machine.device.platform.name} / "
              f"{machine.device.name}; load average before: {os.getloadavg()[0]:.1f}. The whole machine (every cue) "
              f"on the 'blocks' scene, medians of {REPEATS} profiled frames after a warm-up. The yardstick: the copy "
              f"kernel (news.cl, 64 MiB of float32) moves {copy_gbs:.2f} GB/s (read + write). MB: the bytes of "
              "the buffers each kernel's launches are given, each once per launch (vmcl.Machine.timings); GB/s: "
              "those bytes over its device time; 'of the copy': that bandwidth as a share of the copy's (near "
              "100%: at the memory roof; far below: bound by arithmetic, serial steps or too little parallel "
              "work). Operations are not counted (no hardware counters on this device), so no arithmetic roof "
              "is drawn.")]
    for size in SIZES:
        print(f"{size} ...", file=sys.stderr)
        per_frame, wall = profile(size, machine)
        families = machine.kernel_families()
        device = sum(entry["total_ms"] for entry in per_frame.values())
        moved = sum(entry["bytes"] for entry in per_frame.values())
        lines += ["", f"## {size} x {size}", "",
                  (f"Per frame: {wall:.0f} ms wall, {device:.0f} ms of device time in kernels "
                   f"({100 * device / wall:.0f}% of the wall; the rest is transfers, host work and launches), "
                   f"{moved / 1e6:.0f} MB given to kernels: {moved / device / 1e6:.2f} GB/s on average, "
                   f"{100 * moved / device / 1e6 / copy_gbs:.0f}% of the copy."), "",
                  "By family (kernels/<family>.cl):", "", *families_table(per_frame, families, copy_gbs), "",
                  f"The {TOP} kernels with the most device time:", "", *table(per_frame, families, copy_gbs)]
    out.write_text("\n".join(lines) + "\n", encoding="utf-8")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
