"""Stereo benchmark: the edge matcher against OpenCV's block matchers, speed and quality, in one run.

Run: python benchmarks/stereo.py [--data ../shared/datasets] [--repeat 15] [--out benchmarks/results/stereo.md]

Speed: at teddy's size (450 x 375) with 64 disparities, the whole matcher (Canny on both images
included, NumPy in and out) in its running-maximum and full-table variants, against cv2.StereoBM
(block 15) and cv2.StereoSGBM (block 5, in its default MODE_SGBM and in MODE_SGBM_3WAY), timed in interleaved rounds (one call of each per round, medians
over the rounds) so that a change in the machine's load falls on every method alike; then the device
time of each kernel of the running variant. Quality: on the Middlebury v2 evaluation scenes, the
bad-pixel rate at 1 px on the nonocc mask at the pixels vmcl matched, the share of left edge pixels
matched, and StereoBM's bad-pixel rate at the same pixels (a pixel StereoBM leaves without a value
counts as bad). Dense intensity matches (normalised cross-correlation, patch 11, brightness smoothed
with sigma 1 as the pipeline's backfill does): centred against shiftable windows, bad-1 on the nonocc
and disc masks (an unmatched pixel counts as bad), beside StereoSGBM in both modes. Last, the pipeline's
dense disparity beside OpenCV's matchers on every Middlebury scene folder under --data, as `vmcl eval
stereo` prints it. The machine is shared and noisy: compare ratios within one run.

Every quality figure comes from vmcl.stereo_evaluation, the one harness `vmcl eval stereo` uses too: its
reading of the folders (vmcl.datasets.read_stereo_folder), its OpenCV baselines and its scores
(vmcl.metrics.evaluate_disparity). The Middlebury v2 tables cover the scenes found with nonocc and disc
masks. OpenCV is configured as its documentation says: grey 8-bit input; StereoBM with numDisparities a
multiple of 16 and block 15 (OpenCV's Python stereo tutorial), its other parameters OpenCV's defaults;
StereoSGBM with block 5, P1 = 8 * cn * blockSize^2 = 200 and P2 = 32 * cn * blockSize^2 = 800 (cn = 1),
and uniquenessRatio 10 (OpenCV's default is 0; its documentation suggests 5 to 15), the rest OpenCV's
defaults. Disparity ranges: no method takes one from the ground truth. vmcl's
matcher searches the range vmcl.early.disparity_range.estimate_range finds from the images (the range the
pipeline uses when its Config gives none); OpenCV's matchers get numDisparities from the range the dataset
publishes (info.txt's maximum disparity, 15 / 19 / 59, plus one, rounded up to 16: 16 / 32 / 64), as
their documentation asks for a multiple of 16; where a folder publishes none (2001, 2003), the largest
disparity estimate_range finds, plus one, rounded up to 16.
"""

from __future__ import annotations

import argparse
import datetime
import statistics
import sys
import time
from dataclasses import replace
from pathlib import Path

import vmcl
from vmcl.datasets import find_stereo_folders, load_stereo, read_stereo_folder
from vmcl.early.disparity_range import estimate_range
from vmcl.early.edges import canny
from vmcl.early.stereo import match
from vmcl.stereo_evaluation import (
    SGBM_MODES,
    StereoMethod,
    baseline_disparities,
    evaluate_pair,
    grey,
    markdown_tables,
    opencv_baselines,
    stereo_bm,
    stereo_sgbm,
    vmcl_method,
)

ROOT = Path(__file__).resolve().parents[1]


def interleaved_ms(runs: dict, repeat: int) -> list[tuple[str, float]]:
    """Median ms of each named call over ``repeat`` rounds that call each once, after one warm-up round."""
    times = {name: [] for name in runs}
    for round_ in range(repeat + 1):
        for name, run in runs.items():
            start = time.perf_counter()
            run()
            if round_:
                times[name].append(time.perf_counter() - start)
    return [(name, statistics.median(t) * 1e3) for name, t in times.items()]


def speed(pair, repeat: int) -> list[tuple[str, float]]:
    left, right = grey(pair.left), grey(pair.right)
    bm = stereo_bm(64)
    runs = {f"vmcl.match canny, {variant}": (lambda v=variant: match(left, right, d_min=0, d_max=63, method=v))
            for variant in ("running", "table")}
    for shiftable in (False, True):
        name = f"vmcl.match intensity (NCC){', shiftable' if shiftable else ''}, table"
        runs[name] = lambda s=shiftable: match(left, right, d_min=0, d_max=63, features="intensity", method="table",
                                               shiftable=s)
    runs["cv2.StereoBM block 15"] = lambda: bm.compute(left, right)
    for mode in SGBM_MODES:
        sgbm = stereo_sgbm(64, mode)
        runs[f"cv2.StereoSGBM {mode}"] = lambda m=sgbm: m.compute(left, right)
    return interleaved_ms(runs, repeat)


def kernel_times(pair, repeat: int) -> list[tuple[str, int, float]]:
    """(kernel, launches per call, median device ms per call) of the running edge matcher."""
    left, right = grey(pair.left), grey(pair.right)
    machine = vmcl.Machine(profile=True)
    match(left, right, d_min=0, d_max=63, machine=machine)
    machine.timings()
    per_call = {}
    for _ in range(repeat):
        match(left, right, d_min=0, d_max=63, machine=machine)
        for name, entry in machine.timings().items():
            per_call.setdefault(name, []).append((entry["calls"], entry["total_ms"]))
    rows = [(name, calls[0][0], statistics.median(ms for _, ms in calls)) for name, calls in per_call.items()]
    return sorted(rows, key=lambda row: -row[2])


def _baseline(pair, name: str) -> StereoMethod:
    """One of the harness's OpenCV baselines for the pair, by its name."""
    return next(m for m in opencv_baselines(pair) if m.name == name)


def _method(name: str, compute) -> StereoMethod:
    return StereoMethod(name, lambda left, right: compute(left, right).disparity)


def quality(pair) -> dict:
    """vmcl's edge matches, bad-1 on the nonocc pixels they matched, beside StereoBM's there.

    The harness compares methods on the pixels a reference method matched: here the edge matcher is the
    reference and StereoBM the method compared with it.
    """
    found_range = estimate_range(pair.left, pair.right)
    edges = _method("vmcl.match canny", lambda left, right: match(left, right, d_min=found_range.d_min,
                                                                   d_max=found_range.d_max))
    bm = replace(_baseline(pair, "OpenCV StereoBM"), baseline=False)
    evaluation = evaluate_pair(replace(pair, masks={"nonocc": pair.masks["nonocc"]}),
                               [replace(edges, baseline=True), bm], warm=False)
    (compared,) = evaluation.matched
    left_edges = canny(pair.left, sigma=2.0) & pair.masks["nonocc"]
    return {
        "scene": pair.name,
        "vmcl range (estimated)": f"{found_range.d_min}..{found_range.d_max}",
        "OpenCV numDisparities": baseline_disparities(pair)[0],
        "matched": compared.matched,
        "share of left edges matched": compared.matched / left_edges.sum(),
        "vmcl bad-1": compared.baseline_bad,
        "StereoBM bad-1 at the same pixels": compared.method_bad,
    }


def dense_quality(pair) -> dict:
    """Bad-1 rates of the dense intensity matches, centred and shiftable, and of StereoSGBM in both modes."""
    found_range = estimate_range(pair.left, pair.right)
    methods = [_baseline(pair, f"OpenCV StereoSGBM {mode}") for mode in SGBM_MODES]
    for shiftable in (False, True):
        methods.append(_method("shiftable" if shiftable else "centred", lambda left, right, s=shiftable: match(
            left, right, d_min=found_range.d_min, d_max=found_range.d_max, features="intensity", sigma=1.0,
            shiftable=s)))
    masks = {mask: pair.masks[mask] for mask in ("nonocc", "disc")}
    evaluation = evaluate_pair(replace(pair, masks=masks), methods, warm=False)
    label = {f"OpenCV StereoSGBM {mode}": f"SGBM {mode}" for mode in SGBM_MODES}
    row = {"scene": pair.name}
    for mask in masks:
        for scores in evaluation.scores:
            if scores.region == mask:
                row[f"{label.get(scores.method, scores.method)} {mask}"] = scores.bad[1.0]
    return row


def table(rows: list[dict]) -> list[str]:
    header = list(rows[0])
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    return lines + ["| " + " | ".join(f"{v:.3f}" if isinstance(v, float) else str(v) for v in row.values()) + " |"
                    for row in rows]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=ROOT.parent / "shared" / "datasets")
    parser.add_argument("--repeat", type=int, default=15)
    parser.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results" / "stereo.md")
    args = parser.parse_args(argv)
    folders = find_stereo_folders(args.data) if args.data.is_dir() else []
    pairs = [replace(read_stereo_folder(f), name=f.relative_to(args.data).as_posix() if f != args.data else f.name)
             for f in folders]
    # The quality tables need the v2 masks (nonocc, disc); they name the scenes by their folders.
    masked = [replace(pair, name=folder.name) for folder, pair in zip(folders, pairs)
              if {"nonocc", "disc"} <= pair.masks.keys()]
    if not masked or not (args.data / "middlebury_stereo_v2eval" / "teddy").is_dir():
        print(f"no Middlebury v2 scenes (with nonocc and disc masks, teddy among them) under {args.data}: pass "
              "--data", file=sys.stderr)
        return 2
    machine = vmcl.default_machine()
    teddy = load_stereo("teddy", args.data)
    timings = speed(teddy, args.repeat)
    reference = dict(timings)["cv2.StereoBM block 15"]
    lines = ["# Stereo: vmcl's edge matcher against OpenCV", "",
             (f"Measured {datetime.datetime.now():%Y-%m-%d %H:%M} on {machine.device.platform.name} / "
             f"{machine.device.name}. NumPy images in and out; medians of {args.repeat} interleaved rounds."), "",
             ("OpenCV as documented, on grey images: StereoBM block 15; StereoSGBM block 5, P1 = 8 * cn * "
              "blockSize^2 = 200, P2 = 32 * cn * blockSize^2 = 800 (cn = 1), uniquenessRatio 10 (as "
              "vmcl.stereo_evaluation, the harness of `vmcl eval stereo`, sets it; OpenCV's default is 0), in "
              "OpenCV's default mode (MODE_SGBM) and in MODE_SGBM_3WAY; their other parameters OpenCV's "
              "defaults. No method takes a range from the ground truth: the speed runs search 64 disparities "
              "(0..63) with every method; on Middlebury, vmcl's matcher searches the range "
              "vmcl.early.disparity_range.estimate_range finds from the images, and OpenCV gets numDisparities "
              "from the range the dataset publishes (info.txt's maximum disparity 15 / 19 / 59, plus one, "
              "rounded up to 16: 16 / 32 / 64), or where a folder publishes none (2001, 2003) from the largest "
              "disparity estimate_range finds, plus one, rounded up to 16."), "",
             "## Speed at teddy's size (450 x 375), 64 disparities, Canny included", "",
             "| method | ms | x StereoBM |", "|---|---|---|"]
    lines += [f"| {name} | {ms:.1f} | {ms / reference:.1f} |" for name, ms in timings]
    kernels = kernel_times(teddy, args.repeat)
    lines += ["", "## Device time per kernel, vmcl.match canny, running (profiled machine, medians)", "",
              (f"Sum {sum(ms for *_, ms in kernels):.2f} ms (the wall time above adds the host's share: "
               "Python, the two uploads and the copies back)."), "",
              "| kernel | launches | ms |", "|---|---|---|"]
    lines += [f"| {name} | {calls} | {ms:.3f} |" for name, calls, ms in kernels]
    lines += ["", "## Quality on Middlebury v2 (nonocc mask, at the pixels vmcl matched)", ""]
    lines += table([quality(pair) for pair in masked])
    lines += ["", "## Dense intensity matches on Middlebury v2: bad-1, centred and shiftable windows, and SGBM", "",
              "Every pixel of the mask counts; one without a value is bad.", ""]
    lines += table([dense_quality(pair) for pair in masked])
    ours = vmcl_method()
    evaluations = [evaluate_pair(pair, [ours, *opencv_baselines(pair)]) for pair in pairs]
    lines += ["", "## The pipeline's dense disparity on every Middlebury scene found (`vmcl eval stereo`)", "",
              ("vmcl.stereo_evaluation, the harness of `vmcl eval stereo`: vmcl's pipeline with only stereo "
               "enabled (its disparity range found from the images) beside OpenCV's matchers configured as "
               "above; scenes named by their folder under --data."), "",
              *markdown_tables(evaluations)]
    text = "\n".join(lines) + "\n"
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
