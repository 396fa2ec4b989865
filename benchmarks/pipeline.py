"""Frames per second of the whole Vision Machine (stereo + motion + colour + texture + MRF + integration).

Seed sections "The Vision Machine System" and "Fast vision". First the steady state of a stream, the video
rate bars' measure: VisionMachine.stream over STREAM_FRAMES frames of the rendered 'blocks' sequence,
every cue and the temporal terms on, the per-frame wall time of every frame but the first (no past) and
the last (no next frame), each Result read and dropped as it comes (benchmarks/stream_timing.py); bars: at
most 100 ms per frame at 256 x 256, 350 ms at 512 x 512. Then independent frames: each size runs the
"blocks" scene once to build the kernels, then REPEATS timed runs; the table gives the median wall time per
frame and each stage's median, for the default solver (mean field) and for ICM. Every run takes the pipeline's defaults: no disparity range is
given, so the machine searches the range it finds from the images. The quality of the dense disparity, and
of each stereo stage on and off, is benchmarks/stereo.py's. Writes benchmarks/results/pipeline.md (or --out;
the device: VMCL_DEVICE, as for every vmcl run).
"""

from __future__ import annotations

import argparse
import datetime
import os
import statistics
import sys
from pathlib import Path

from stream_timing import SteadyState, blocks_sequence, steady_state

import vmcl
from vmcl import scenes
from vmcl.pipeline import Config, VisionMachine

REPEATS = 3
SIZES = (256, 512)
STREAM_FRAMES = 10
STREAM_BARS_MS = {256: 100.0, 512: 350.0}
METHODS = ("meanfield", "icm")
DATA = Path(__file__).resolve().parents[1].parent / "shared" / "datasets"
PHOTO_BAR_MS = 1000.0


def measure_stream(size: int, machine: vmcl.Machine) -> SteadyState:
    lefts, rights = blocks_sequence(size, STREAM_FRAMES)
    return steady_state(VisionMachine(machine=machine), lefts[:STREAM_FRAMES], rights)


def stream_lines(machine: vmcl.Machine) -> list[str]:
    streams = {size: measure_stream(size, machine) for size in SIZES}
    lines = ["## A stream's steady state (the video rate bars)", "",
             (f"VisionMachine.stream over {STREAM_FRAMES} frames of the rendered 'blocks' sequence (seed 1, noise "
              "0.01), every cue, the temporal terms on (the defaults); the median wall time of the frames but the "
              f"first and the last ({STREAM_FRAMES - 2} frames), every transfer included."), "",
             "| size | stream ms per frame | frames per second | bar ms | bar met |", "|---|---|---|---|---|"]
    for size, steady in streams.items():
        bar = STREAM_BARS_MS[size]
        lines.append(f"| {size} x {size} | {steady.median:.0f} | {1000 / steady.median:.2f} | {bar:.0f} | "
                     f"{'yes' if steady.median <= bar else 'no'} |")
        print(f"stream {size}: {steady.median:.0f} ms", file=sys.stderr)
    names = list(next(iter(streams.values())).stages[0])
    lines += ["", "Stage breakdown of the stream (median wall ms; each stage ends with the queue drained):", "",
              "| stream stage | " + " | ".join(f"{size}" for size in streams) + " |",
              "|---" * (len(streams) + 1) + "|"]
    lines += [f"| {name} | " + " | ".join(f"{steady.stage_median(name):.0f}" for steady in streams.values()) + " |"
              for name in names]
    return lines + ["", "## Independent frames", ""]


def measure(size: int, method: str, machine: vmcl.Machine) -> tuple[float, dict[str, float]]:
    s = scenes.render(scenes.preset("blocks", shape=(size, size)), seed=0, noise=0.01)
    vm = VisionMachine(Config.from_dict({"mrf": {"method": method}}), machine=machine)
    vm.run(s.left, s.right, s.left_next)
    runs = [vm.run(s.left, s.right, s.left_next) for _ in range(REPEATS)]
    stages = {name: statistics.median(r.stages[name] for r in runs) for name in runs[0].stages}
    return statistics.median(r.total_ms for r in runs), stages


def measure_photograph(machine: vmcl.Machine) -> tuple[str, float, dict[str, float]] | None:
    """The monocular machine's defaults (all its cues) on the first BSDS500 test image (481 x 321), or None
    without the data."""
    from vmcl.datasets import load_bsds

    try:
        item = load_bsds(DATA).images[0]
    except FileNotFoundError:
        return None
    vm = VisionMachine(Config(), machine=machine)
    vm.run(item.image)
    runs = [vm.run(item.image) for _ in range(REPEATS)]
    stages = {name: statistics.median(r.stages[name] for r in runs) for name in runs[0].stages}
    shape = item.image.shape
    return f"BSDS500 {item.name} ({shape[1]} x {shape[0]})", statistics.median(r.total_ms for r in runs), stages


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path(__file__).resolve().parent / "results" / "pipeline.md")
    out = parser.parse_args().out
    machine = vmcl.Machine()
    lines = ["# The whole Vision Machine per frame", "",
             (f"Measured {datetime.datetime.now():%Y-%m-%d %H:%M}. Device: {machine.device.platform.name} / {machine.device.name}; load average before: "
             f"{os.getloadavg()[0]:.1f}."), ""]
    lines += stream_lines(machine)
    lines += [(f"Median of {REPEATS} runs of the 'blocks' scene (all cues: stereo, motion, colour, texture, four "
               "MRFs, integration), each frame on its own (VisionMachine.run), wall time including every transfer."),
              ""]
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
    photo = measure_photograph(machine)
    if photo is not None:
        name, total, stages = photo
        lines += ["", f"## One photograph, one image: {name}", "",
                  (f"The monocular machine with all its cues (brightness edges, the probability of boundary, colour "
                  f"and texture with their MRFs, the labels), median of {REPEATS} runs: {total:.0f} ms (bar: at "
                  f"most {PHOTO_BAR_MS:.0f} ms: {'met' if total <= PHOTO_BAR_MS else 'not met'})."), "",
                  "| stage | ms |", "|---|---|"]
        lines += [f"| {stage} | {ms:.0f} |" for stage, ms in stages.items()] + [f"| total (median) | {total:.0f} |"]
    out.write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
