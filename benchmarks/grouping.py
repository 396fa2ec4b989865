"""Grouping: curves, saliency and junctions on real images and rendered scenes, and their speed.

Run: python benchmarks/grouping.py [--data ../shared/datasets] [--thresholds 30] [--workers 2]
     [--out benchmarks/results/grouping.md]

- BSDS500 test images (the 10 in ../shared): vmcl Canny's threshold sweep against Canny pruned by local
  saliency and by structural saliency (vmcl.boundary_evaluation's sweeps, the [grouping] defaults, which
  benchmarks/grouping_fit.py chose on training images), the benchmark's ODS / OIS / AP.
- Junctions on the same images: the junctions of the machine's own edges (T, Y, arrow and X: where three
  or more regions meet) against each annotator's segmentation junctions (vmcl.metrics.segmentation_junctions),
  matched one to one within 6 px, beside OpenCV's goodFeaturesToTrack (Shi-Tomasi) and Harris corners
  asked for as many points.
- Occlusion scenes (vmcl.scenes.render_occlusion) of seeds 0-39 (the tests'; early versions of the
  junction detector were diagnosed on them), of seeds 2000-2039 (scored once before the last change to
  the detector) and of seeds 3000-3039 (never looked at while developing it): T-junction recall and
  precision within 3 px (the resolvable ones; detections in the scene's border strip, where it knows no
  junctions, count neither way), the occluding side, the repair of
  broken T-junctions within 2 px, and the pairs of T-junctions across occluders; shapes-in-clutter
  displays of seeds 0-19: the contour's rank.
- Speed at 512 x 512: Canny against linking its edges into curves and scoring them (wall time in
  alternating blocks of calls after a warm-up, device time from the profiling Machine), and the structural saliency network per iteration against
  the same network in NumPy (tests/oracles.py), with the iterations its ranking takes to settle.
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
from scipy import ndimage

import vmcl
from vmcl.boundary_evaluation import canny_sweep, local_saliency_sweep, structural_saliency_sweep
from vmcl.datasets import load_bsds
from vmcl.early.edges import canny
from vmcl.group import (
    find_junctions,
    group,
    group_curves,
    link_edges,
    local_saliency,
    repair_edges,
    saliency_strength,
    structural_saliency,
)
from vmcl.metrics import evaluate_boundaries, match_points, point_scores, segmentation_junctions
from vmcl.pipeline import Config, as_image
from vmcl.scenes import OcclusionScene, clutter_display, render_occlusion

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
from oracles import structural_saliency as numpy_network

RESULTS = ROOT / "benchmarks" / "results"
DEFAULT_DATA = ROOT.parent / "shared" / "datasets"
BAR_STRUCTURAL = 0.03
MATCH_JUNCTIONS = 6.0
SCENE_SEEDS = {"seeds 0-39": range(40), "seeds 2000-2039": range(2000, 2040), "seeds 3000-3039": range(3000, 3040)}
CLUTTER_SEEDS = range(20)
SPEED_RUNS = 20
SPEED_ROUNDS = 15  # alternating blocks of SPEED_RUNS calls each


def boundaries(images, thresholds: int, workers: int, machine: vmcl.Machine) -> list[str]:
    truths = [item.boundaries for item in images]
    maps = {"vmcl Canny, threshold sweep": [canny_sweep(item.image, thresholds, machine=machine) for item in images],
            "Canny pruned by local saliency": [local_saliency_sweep(item.image, machine=machine) for item in images],
            "Canny pruned by structural saliency": [structural_saliency_sweep(item.image, machine=machine)
                                                    for item in images]}
    scores = {name: evaluate_boundaries(m, truths, thresholds=thresholds, workers=workers) for name, m in maps.items()}
    rows = [f"| {name} | {s.ods_f:.3f} | {s.ods_precision:.3f} | {s.ods_recall:.3f} | {s.ois_f:.3f} | "
            f"{s.average_precision:.3f} |" for name, s in scores.items()]
    canny_ods = scores["vmcl Canny, threshold sweep"].ods_f
    structural = scores["Canny pruned by structural saliency"].ods_f
    local = scores["Canny pruned by local saliency"].ods_f
    verdict = (f"Structural saliency {structural - canny_ods:+.3f} over Canny's ODS (bar: at least "
               f"+{BAR_STRUCTURAL}: {'met' if structural - canny_ods >= BAR_STRUCTURAL else 'not met'}); local "
               f"saliency {local - canny_ods:+.3f}.")
    return rows + ["", verdict]


def corners(grey: np.ndarray, count: int, harris: bool) -> np.ndarray:
    """OpenCV's corners, as its documentation's examples configure them: quality 0.01, 10 px apart."""
    found = cv2.goodFeaturesToTrack(grey, maxCorners=max(count, 1), qualityLevel=0.01, minDistance=10,
                                    useHarrisDetector=harris)
    return np.zeros((0, 2)) if found is None else found.reshape(-1, 2)


def junctions_on_bsds(images, machine: vmcl.Machine) -> list[str]:
    sigma = Config().edges.sigma
    totals = {name: [0, 0, 0] for name in ("vmcl junctions (T, Y, arrow, X)", "goodFeaturesToTrack (Shi-Tomasi)",
                                          "Harris corners")}
    found_count, grouping_ms = 0, 0.0
    for item in images:
        image = as_image(item.image, "image")
        edges = canny(image, sigma=sigma, return_gradient=True, machine=machine)
        start = time.perf_counter()
        grouping = group(edges.edges, magnitude=edges.magnitude, image=image, machine=machine)
        grouping_ms += 1e3 * (time.perf_counter() - start)
        junctions = grouping.junctions
        ours = junctions.points[np.isin(junctions.kinds, ["T", "Y", "arrow", "X"])]
        found_count += len(ours)
        grey = cv2.cvtColor(np.round(image * 255).astype(np.uint8), cv2.COLOR_RGB2GRAY) if image.ndim == 3 \
            else np.round(image * 255).astype(np.uint8)
        detections = {"vmcl junctions (T, Y, arrow, X)": ours,
                      "goodFeaturesToTrack (Shi-Tomasi)": corners(grey, len(ours), False),
                      "Harris corners": corners(grey, len(ours), True)}
        for segmentation in item.segmentations:
            truth = segmentation_junctions(segmentation)
            for name, points in detections.items():
                totals[name][0] += len(match_points(truth, points, tolerance=MATCH_JUNCTIONS))
                totals[name][1] += len(points)
                totals[name][2] += len(truth)
    rows = [f"| {name} | {hits / max(n, 1):.3f} | {hits / max(t, 1):.3f} | {n} |"
            for name, (hits, n, t) in totals.items()]
    return rows + ["", (f"{found_count} vmcl junctions over {len(images)} images; counts are summed over "
                       "annotators (each annotator's junctions matched separately). The grouping of one image "
                       f"(vmcl.group.group: curves, saliency, junctions, repairs, pairs) took {grouping_ms / len(images):.0f} "
                       "ms of wall time on average.")]


def occlusion_measures(seeds: range, machine: vmcl.Machine) -> dict[str, str]:
    hits = truths = counted = 0
    sides = [0, 0]
    broken = repaired = 0
    pair_hits = pair_truths = pair_found = 0
    for seed in seeds:
        scene = render_occlusion((256, 256), polygons=6, seed=seed, noise=0.01)
        edges = canny(scene.image, sigma=1.0, machine=machine)
        curves = link_edges(edges, machine=machine)
        junctions = find_junctions(curves)
        ts = junctions.of_kind("T")
        truth_ts = scene.t_junctions()
        keep = scene.resolvable()
        points = np.array([[j.x, j.y] for j in truth_ts]).reshape(-1, 2)
        found = junctions.points[ts]
        matches = match_points(points[keep], found, tolerance=3.0)
        hits += len(matches)
        truths += int(keep.sum())
        # Detections in the border strip where the scene knows no junctions count neither way.
        counted += point_scores(points[keep], found, tolerance=3.0, ignore=points[~keep],
                                exclude=scene.outside(found)).n_predicted
        kept = [j for j, k in zip(truth_ts, keep) if k]
        for r, c in matches:
            x, y = np.clip(np.rint(found[c] + 4 * junctions.occluder[ts[c]]).astype(int), 0, 255)
            sides[0] += int(scene.regions[y, x] == kept[r].occluder)
            sides[1] += 1
        fixed = link_edges(repair_edges(edges, junctions), machine=machine)
        for point in points[keep]:
            if len(curves.branches) and np.linalg.norm(curves.branches - point, axis=1).min() <= 2:
                continue
            broken += 1
            repaired += int(len(fixed.branches) > 0 and np.linalg.norm(fixed.branches - point, axis=1).min() <= 2)
        pairs, _ = group_curves(junctions, image=scene.image)
        everything = np.array([[j.x, j.y] for j in scene.junctions])
        t_index = [i for i, j in enumerate(scene.junctions) if j.kind == "T"]
        resolvable = {i for i, k in zip(t_index, keep) if k}
        truth_pairs = {tuple(sorted(p)) for p in scene.t_pairs() if set(p) <= resolvable}
        pair_truths += len(truth_pairs)
        pair_found += len(pairs)
        for a, b in pairs:
            ends = [int(np.argmin(np.linalg.norm(everything - junctions.points[k], axis=1))) for k in (a, b)]
            near = all(np.linalg.norm(everything[e] - junctions.points[k]) <= 3 for e, k in zip(ends, (a, b)))
            pair_hits += int(near and tuple(sorted(ends)) in truth_pairs)
    return {"T-junction recall within 3 px (resolvable)": f"{hits / truths:.3f}",
            "T-junction precision within 3 px": f"{hits / counted:.3f}",
            "occluding side right (matched T-junctions)": f"{sides[0] / max(sides[1], 1):.3f}",
            "broken T-junctions repaired within 2 px": f"{repaired / max(broken, 1):.3f} ({repaired} of {broken})",
            "T-junction pairs: precision": f"{pair_hits / max(pair_found, 1):.3f} ({pair_hits} of {pair_found})",
            "T-junction pairs: recall (both ends resolvable)":
                f"{pair_hits / max(pair_truths, 1):.3f} ({pair_hits} of {pair_truths})"}


OCCLUSION_BARS = {"T-junction recall within 3 px (resolvable)": "at least 0.8",
                  "T-junction precision within 3 px": "at least 0.8",
                  "broken T-junctions repaired within 2 px": "at least 0.7"}


def scenes(machine: vmcl.Machine) -> tuple[list[str], list[str]]:
    """The occlusion scenes' table rows (one column per seed set) and the clutter displays'."""
    measured = {name: occlusion_measures(seeds, machine) for name, seeds in SCENE_SEEDS.items()}
    first = next(iter(measured.values()))
    occlusion = [f"| {measure} | " + " | ".join(m[measure] for m in measured.values())
                 + f" | {OCCLUSION_BARS.get(measure, '')} |" for measure in first]
    clutter = {}
    for gaps in (0, 8):
        shares = []
        for seed in CLUTTER_SEEDS:
            display = clutter_display(gaps=gaps, seed=seed)
            saliency = structural_saliency(display.edges, machine=machine).saliency
            k = int(display.contour.sum())
            top = np.argsort(np.where(display.edges, saliency, -1).ravel(), kind="stable")[::-1][:k]
            shares.append(ndimage.binary_dilation(display.contour, iterations=1).ravel()[top].mean())
        clutter[gaps] = (float(np.mean(shares)), float(np.mean(np.array(shares) >= 0.9)))
    displays = [(f"| no gaps | {clutter[0][1]:.2f} (mean share {clutter[0][0]:.3f}) | at least 0.9 |"),
                f"| 8 gaps of 3 px | {clutter[8][1]:.2f} (mean share {clutter[8][0]:.3f}) | at least 0.9 |"]
    return occlusion, displays


def _timed(call, runs: int) -> float:
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return 1e3 * statistics.median(times)


def _interleaved(first, second, rounds: int, runs: int) -> tuple[float, float, float]:
    """Wall times of two calls measured in alternating blocks of ``runs`` calls, after a warm-up: the median
    ms of each over all rounds, and the median over rounds of the ratio second / first. A shared machine's
    load drifts over seconds; blocks side by side see the same load, the order swaps every round (neither
    always follows the other), and the first block of a run (caches, the pool's first buffers) counts for
    neither."""
    for _ in range(5):
        first()
        second()
    ones, twos, ratios = [], [], []
    for round_ in range(rounds):
        if round_ % 2:
            two, one = _timed(second, runs), _timed(first, runs)
        else:
            one, two = _timed(first, runs), _timed(second, runs)
        ones.append(one)
        twos.append(two)
        ratios.append(two / one)
    return statistics.median(ones), statistics.median(twos), statistics.median(ratios)


def speed(images, machine: vmcl.Machine) -> list[str]:
    image = cv2.resize(as_image(images[0].image, "image"), (512, 512), interpolation=cv2.INTER_AREA)
    sigma = Config().edges.sigma
    # Wall times on a machine without profiling, as a user runs it (profiling costs every launch an
    # event); device times from the profiling machine.
    plain = vmcl.Machine(machine.device)

    def calls(on: vmcl.Machine):
        device = on.to_device(image)
        found = canny(device, sigma=sigma, return_gradient=True, machine=on)
        on.finish()

        def curves_and_saliency():
            local_saliency(link_edges(found.edges, magnitude=found.magnitude, machine=on))
            on.finish()

        def canny_call():
            canny(device, sigma=sigma, return_gradient=True, machine=on)
            on.finish()

        return canny_call, curves_and_saliency, found

    def device_ms(call) -> float:
        call()
        machine.finish()
        machine.timings(reset=True)
        for _ in range(SPEED_RUNS):
            call()
        machine.finish()
        return sum(t["total_ms"] for t in machine.timings(reset=True).values()) / SPEED_RUNS

    canny_wall, curves_wall, ratio = _interleaved(*calls(plain)[:2], SPEED_ROUNDS, SPEED_RUNS)
    canny_call, curves_and_saliency, found = calls(machine)
    canny_device, curves_device = device_ms(canny_call), device_ms(curves_and_saliency)
    # The same on the profiling machine, whose events cost every launch (the curves make more of them).
    profiled = _interleaved(canny_call, curves_and_saliency, SPEED_ROUNDS, SPEED_RUNS)
    edges = found.edges
    strength = saliency_strength(edges, found.magnitude, machine=machine)
    tangent = link_edges(edges, machine=machine).tangent

    def network(iterations: int):
        result = structural_saliency(edges, tangent=tangent, strength=strength, iterations=iterations, machine=machine)
        machine.finish()
        return result

    per_iteration = (_timed(lambda: network(31), 5) - _timed(lambda: network(1), 5)) / 30
    small = (slice(0, 128), slice(0, 128))
    host_edges, host_tangent, host_strength = edges.get()[small].astype(bool), tangent.get()[small], strength.get()[small]
    start = time.perf_counter()
    numpy_network(host_edges, host_tangent, host_strength, 11, 0.85, 1.0)
    numpy_ten = time.perf_counter() - start
    start = time.perf_counter()
    numpy_network(host_edges, host_tangent, host_strength, 1, 0.85, 1.0)
    numpy_per_iteration = 1e3 * (numpy_ten - (time.perf_counter() - start)) / 10 * (512 * 512) / (128 * 128)
    on = edges.get().astype(bool)
    final = network(120).saliency.get()[on]
    top = final >= np.quantile(final, 0.9)
    settle = None
    for iterations in range(5, 121, 5):
        values = network(iterations).saliency.get()[on]
        if np.mean(values[top] >= np.quantile(values, 0.9)) >= 0.95:
            settle = iterations
            break
    return [f"| Canny (sigma {sigma:g}, with its gradient) | {canny_wall:.2f} | {canny_device:.2f} | 1.00 |",
            (f"| curves and local saliency | {curves_wall:.2f} | {curves_device:.2f} | "
            f"{ratio:.2f} (device {curves_device / canny_device:.2f}) |"),
            "",
            (f"On the profiling machine (an event per launch): Canny {profiled[0]:.2f} ms, curves and local saliency "
             f"{profiled[1]:.2f} ms, {profiled[2]:.2f} Canny's time. The wall times are steady state: kernels built, "
             "the machine's scalar arguments and the curves' filter weights already set up."),
            "",
            (f"Structural saliency at 512 x 512: {per_iteration:.2f} ms per iteration on the device, "
            f"{numpy_per_iteration:.0f} ms in NumPy (tests/oracles.py's network, timed at 128 x 128 and scaled by "
            f"the pixel count): {numpy_per_iteration / per_iteration:.0f}x. The ranking settles (95% of the top "
            f"tenth of the edge pixels after 120 iterations already in the top tenth) after "
            f"{settle if settle else 'more than 120'} iterations; the default is {Config().grouping.iterations}.")]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, default=DEFAULT_DATA)
    parser.add_argument("--thresholds", type=int, default=30)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", type=Path, default=RESULTS / "grouping.md")
    args = parser.parse_args()
    machine = vmcl.Machine(profile=True)
    load = os.getloadavg()[0]
    images = load_bsds(args.data, split="test").images
    speed_rows = speed(images, machine)
    scene_rows, clutter_rows = scenes(machine)
    junction_rows = junctions_on_bsds(images, machine)
    boundary_rows = boundaries(images, args.thresholds, args.workers, machine)
    nl = "\n"
    args.out.write_text(f"""# Grouping: curves, saliency and junctions

Measured {datetime.datetime.now():%Y-%m-%d %H:%M} on {machine.device.platform.name} / {machine.device.name}, \
{platform.machine()}, load {load:.1f}: `python benchmarks/grouping.py`. Settings: the [grouping] defaults,
chosen on training data by benchmarks/grouping_fit.py (results/grouping_fit.md).

## Boundaries on the BSDS500 test images in ../shared ({len(images)} images)

The benchmark's protocol ({args.thresholds} thresholds, match distance 0.0075 of the diagonal). Each pruned map
keeps every edge of vmcl Canny at the sweep's lowest threshold, each pixel given its curve's local saliency
or its structural saliency times its strength; sweeping that value prunes the edges.

| map | ODS F | ODS precision | ODS recall | OIS F | AP |
|---|---|---|---|---|---|
{nl.join(boundary_rows)}

## Junctions on the same images

The machine's junctions (its own Canny edges, sigma {Config().edges.sigma:g}) where three or more regions meet, against
each annotator's segmentation junctions (a pixel corner where three or more segments meet), matched one to
one within {MATCH_JUNCTIONS:g} px; OpenCV's corner detectors asked for as many points per image.

| detector | precision | recall | points |
|---|---|---|---|
{nl.join(junction_rows)}

## Occlusion scenes

6 polygons, 256 x 256, noise 0.01, Canny sigma 1; resolvable T-junctions (OcclusionScene.resolvable: no
other junction within 6 px, arms at least 30 degrees apart); detections near the others, and detections
in the {OcclusionScene.margin:g} px border strip where the scene knows no junctions, count neither way.
Seeds 0-39 are the tests' (early versions of the junction detector were diagnosed on them, before its
tuning moved to seeds 1000-1039); seeds 2000-2039 were scored once before the detector's last change (the
bar's sides need three pixels each), which was made on seeds 1000-1039; seeds 3000-3039 were never looked
at while developing it.

| measure | {' | '.join(SCENE_SEEDS)} | bar |
|---|{'---|' * len(SCENE_SEEDS)}---|
{nl.join(scene_rows)}

## Shapes in clutter

An ellipse among 200 segments of 5-10 px, seeds 0-19 (the defaults were chosen on seeds 100-119); a display
counts when at least 90% of its K most salient edge pixels (K the contour's size) lie within 1 px of the
contour.

| contour | displays whose contour ranks highest | bar |
|---|---|---|
{nl.join(clutter_rows)}

## Speed at 512 x 512

Wall time: after a warm-up, {SPEED_ROUNDS} rounds of {SPEED_RUNS} calls of each, side by side, on a machine without
profiling, the order swapped every round; each call waits for its results (the curves' maps on the device
included). The milliseconds are medians over all rounds, the ratio the median of the rounds' ratios. Device
time: the profiling machine's kernel time per call (on 2 cores a call's device time can exceed its wall time:
kernels run on both). Until 2026-12-03 06:00 this section timed one block of each, Canny first, on the
profiling machine, with no warm-up.

| stage | wall ms | device ms | over Canny (wall) |
|---|---|---|---|
{nl.join(speed_rows)}
""")
    print(args.out.read_text())


if __name__ == "__main__":
    main()
