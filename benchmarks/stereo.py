"""Stereo benchmark: the Vision Machine's depth against OpenCV's matchers: quality, each stage on and off,
and speed, in one run.

Run: python benchmarks/stereo.py [--data ../shared/datasets] [--repeat 11] [--out benchmarks/results/stereo.md]

Every quality figure comes from vmcl.stereo_evaluation, the harness `vmcl eval stereo` uses: its reading
of Middlebury-layout folders (vmcl.datasets.find_stereo_folders and read_stereo_folder), its OpenCV
baselines and its scores (vmcl.metrics.evaluate_disparity: bad 0.5 / 1 / 2 with a pixel without a value
counted bad, density, MAE).

1. Quality: vmcl's depth-only machine (its defaults; the disparity range found from the images) beside
   StereoBM and StereoSGBM (MODE_SGBM and 3WAY) on every Middlebury folder under --data, and on
   scikit-image's Middlebury 2014 Motorcycle (quarter size) when it loads offline. OpenCV is configured as
   its documentation says (the harness's docstrings give the values: StereoBM block 15; StereoSGBM block
   5, P1 = 8 * cn * 5^2, P2 = 32 * cn * 5^2, cn = 1, uniquenessRatio 10), with numDisparities from the
   range the data set publishes (v2 info.txt; Motorcycle's calib.txt ndisp 270 at full size, 68 at the
   quarter size), else from vmcl's estimate; never from the ground truth.
2. Stages on and off, on the test pairs (Middlebury v2 tsukuba, venus, teddy, and Motorcycle): the
   defaults were chosen on the training pairs by benchmarks/stereo_fit.py; this table only reports.
3. Speed at teddy's and Motorcycle's sizes: the depth machine against StereoSGBM 3WAY and the others, in
   interleaved rounds (one call of each per round, medians over rounds: a change in the shared machine's
   load falls on every method alike); the semi-global matcher over the range found from the images
   (coarse to fine) against the same matcher over the full fallback range 0..W/3.
4. Device time per kernel of the depth machine on teddy (profiled Machine).
"""

from __future__ import annotations

import argparse
import datetime
import statistics
import sys
import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

import vmcl
from vmcl.datasets import StereoPair, find_stereo_folders, read_stereo_folder
from vmcl.early.disparity_range import estimate_range, fallback_range
from vmcl.early.semiglobal import match_semiglobal
from vmcl.metrics import evaluate_disparity
from vmcl.pipeline import Config, VisionMachine
from vmcl.stereo_evaluation import DEPTH_ONLY, evaluate_pair, markdown_tables, opencv_baselines, vmcl_method

ROOT = Path(__file__).resolve().parents[1]
TEST_SCENES = ("tsukuba", "venus", "teddy", "motorcycle")
MOTORCYCLE_DISPARITIES = 68  # calib.txt's ndisp = 270 for the full-size pair, divided by 4, rounded up

# name -> stereo section of the Config; the first is the machine's default.
STAGES: dict[str, dict] = {
    "default: semi-global matches alone": {},
    "semi-global matches alone, no weighted median at depth jumps": {"refine": False},
    "semi-global matches alone, no occlusion geometry": {"occlusion_geometry": False},
    "semi-global matches alone, the colour channels' brightness difference": {"ad_colour": True},
    "edge matches + semi-global backfill": {"feature_matches": True},
    "edge matches + semi-global backfill, no feedback": {"feature_matches": True, "feedback": False},
    "edge matches + intensity backfill, shiftable (previous default)": {"feature_matches": True,
                                                                         "dense": "intensity",
                                                                         "backfill_weight": 0.2},
    "edge matches + intensity backfill, centred": {"feature_matches": True, "dense": "intensity",
                                                   "backfill_weight": 0.2, "shiftable": False},
    "edge matches alone": {"feature_matches": True, "backfill": False},
}
# The semi-global matcher's own output (half-occluded pixels filled, no MRF), with and without its 3 x 3
# median, its weighted median at depth jumps and its measurement of the cameras' exposure difference
# (match_semiglobal's keywords).
MATCHER_ROWS = {"semi-global matcher alone (filled, no MRF)": {},
                "semi-global matcher alone (filled, no MRF), no weighted median at depth jumps": {"refine": False},
                "semi-global matcher alone (filled, no MRF), no median": {"median": False},
                "semi-global matcher alone (filled, no MRF), no exposure difference taken out": {"match_exposure": False}}


def motorcycle() -> StereoPair | None:
    """scikit-image's quarter-size Middlebury 2014 Motorcycle, or None when it does not load offline."""
    try:
        from skimage import data
        left, right, disparity = data.stereo_motorcycle()
    except (ImportError, OSError, ValueError) as error:
        print(f"Motorcycle skipped: {error}", file=sys.stderr)
        return None
    disparity = np.where(np.isfinite(disparity), disparity, np.nan).astype(np.float32)
    return StereoPair(name="motorcycle", left=left, right=right, disparity=disparity, masks={},
                      disparity_range=(float(np.nanmin(disparity)), float(np.nanmax(disparity))), scale=1.0,
                      folder=Path("skimage.data.stereo_motorcycle"), published_disparities=MOTORCYCLE_DISPARITIES)


def pairs(root: Path) -> list[StereoPair]:
    found = [read_stereo_folder(folder) for folder in find_stereo_folders(root)] if root.is_dir() else []
    # Folder names repeat across the groups (2001 venus, v2 venus): each pair is named by group/scene.
    named = [replace(pair, name=f"{pair.folder.parent.name}/{pair.folder.name}") for pair in found]
    extra = motorcycle()
    return named + ([extra] if extra is not None else [])


def scene_pair(all_pairs: list[StereoPair], scene: str) -> StereoPair | None:
    """The test pair of a scene: the v2 evaluation folder's (with masks), or Motorcycle."""
    for pair in all_pairs:
        if pair.name in (f"middlebury_stereo_v2eval/{scene}", scene):
            return pair
    return None


def region(pair: StereoPair) -> tuple[str, np.ndarray]:
    return ("nonocc", pair.masks["nonocc"]) if "nonocc" in pair.masks else ("known", np.isfinite(pair.disparity))


@dataclass(frozen=True)
class StageRow:
    stage: str
    rates: dict[str, tuple[float, float]]  # scene -> (bad 1, bad 0.5)


def stages(test: list[StereoPair], machine: vmcl.Machine) -> list[StageRow]:
    """Bad-1 and bad-0.5 of each stage variant's restored disparity on the test pairs."""
    variants: dict[str, dict] = {**STAGES, **MATCHER_ROWS}
    rows = []
    for stage, variant in variants.items():
        rates = {}
        for pair in test:
            _, mask = region(pair)
            if stage in MATCHER_ROWS:
                disparity = match_semiglobal(pair.left, pair.right, **variant, machine=machine).filled
            else:
                method = vmcl_method(Config.from_dict({**DEPTH_ONLY, "stereo": variant}), machine=machine)
                disparity = method.compute(pair.left, pair.right)
            scores = evaluate_disparity(disparity, pair.disparity, mask=mask)
            rates[pair.name] = (scores.bad[1.0], scores.bad[0.5])
        rows.append(StageRow(stage, rates))
        print(stage, {k: round(v[0], 4) for k, v in rates.items()}, file=sys.stderr)
    return rows


def interleaved_ms(runs: dict, repeat: int) -> dict[str, float]:
    """Median ms of each named call over ``repeat`` rounds that call each once, after one warm-up round."""
    times: dict[str, list[float]] = {name: [] for name in runs}
    for round_ in range(repeat + 1):
        for name, run in runs.items():
            start = time.perf_counter()
            run()
            if round_:
                times[name].append(time.perf_counter() - start)
    return {name: statistics.median(t) * 1e3 for name, t in times.items()}


def speed(pair: StereoPair, repeat: int, machine: vmcl.Machine) -> dict[str, float]:
    found = estimate_range(pair.left, pair.right, machine=machine)
    full = fallback_range(pair.left.shape[1])
    machine_method = vmcl_method(machine=machine)
    runs = {"vmcl depth machine (range found, semi-global, MRF)": lambda: machine_method.compute(pair.left, pair.right),
            f"vmcl semi-global matcher, range found {found.d_min}..{found.d_max}":
                lambda: match_semiglobal(pair.left, pair.right, d_min=found.d_min, d_max=found.d_max, machine=machine),
            f"vmcl semi-global matcher, full range {full[0]}..{full[1]}":
                lambda: match_semiglobal(pair.left, pair.right, d_min=full[0], d_max=full[1], machine=machine),
            "vmcl range estimate alone": lambda: estimate_range(pair.left, pair.right, machine=machine)}
    for method in opencv_baselines(pair):
        runs[method.name] = lambda m=method: m.compute(pair.left, pair.right)
    return interleaved_ms(runs, repeat)


def kernel_times(pair: StereoPair, repeat: int) -> list[tuple[str, int, float]]:
    """(kernel, launches per run, median device ms per run) of the depth machine (a profiled Machine, whose
    runs each report their own kernels)."""
    vm = VisionMachine(Config.from_dict(DEPTH_ONLY), machine=vmcl.Machine(profile=True))
    vm.run(pair.left, pair.right)
    per_run: dict[str, list[tuple[int, float]]] = {}
    for _ in range(repeat):
        for name, entry in vm.run(pair.left, pair.right).kernels.items():
            per_run.setdefault(name, []).append((int(entry["calls"]), entry["total_ms"]))
    rows = [(name, calls[0][0], statistics.median(ms for _, ms in calls)) for name, calls in per_run.items()]
    return sorted(rows, key=lambda row: -row[2])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=ROOT.parent / "shared" / "datasets")
    parser.add_argument("--repeat", type=int, default=11)
    parser.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results" / "stereo.md")
    args = parser.parse_args(argv)
    machine = vmcl.default_machine()
    every = pairs(args.data)
    if not every:
        print(f"no stereo pair under {args.data} and no Motorcycle: pass --data", file=sys.stderr)
        return 2
    lines = ["# Stereo: the Vision Machine's depth against OpenCV", "",
             (f"Measured {datetime.datetime.now():%Y-%m-%d %H:%M} on {machine.device.platform.name} / "
              f"{machine.device.name}. Rates in %; a pixel without a value counts as bad. vmcl: the depth-only "
              "machine with its defaults, the disparity range found from the images. OpenCV as its "
              "documentation configures it (vmcl.stereo_evaluation), numDisparities from the range the data "
              "set publishes, else from vmcl's estimate; never from the ground truth."), "",
             "## Quality on every pair", ""]
    vmcl_machine = vmcl_method(machine=machine)
    evaluations = []
    for pair in every:
        evaluations.append(evaluate_pair(pair, [vmcl_machine, *opencv_baselines(pair)]))
        print(f"evaluated {pair.name}", file=sys.stderr)
    lines += markdown_tables(evaluations)
    test = [p for p in (scene_pair(every, scene) for scene in TEST_SCENES) if p is not None]
    rows = stages(test, machine)
    names = [p.name for p in test]
    lines += ["", "## Stages on and off (test pairs; the defaults were fitted on training pairs)", "",
              ("Bad 1 and bad 0.5 (%) of the restored disparity (Middlebury v2: nonocc mask; Motorcycle: every "
               "pixel of known disparity). The rows 'semi-global matcher alone' are the matcher's output with its "
               "half-occluded pixels filled, restored by no MRF, with and without its median filter, its weighted "
               "median at depth jumps and its measurement of the cameras' exposure difference; every other "
               "row is the whole depth machine with the Config's stereo section changed as named."), "",
              "| stage | " + " | ".join(f"{n} bad 1 | {n} bad 0.5" for n in names) + " |",
              "|---" * (1 + 2 * len(names)) + "|"]
    lines += [f"| {row.stage} | " + " | ".join(f"{100 * row.rates[n][0]:.1f} | {100 * row.rates[n][1]:.1f}"
                                               for n in names) + " |" for row in rows]
    lines += ["", "## Speed (medians of interleaved rounds, ms)", ""]
    for scene in ("teddy", "motorcycle"):
        pair = scene_pair(every, scene)
        if pair is None:
            continue
        timings = speed(pair, args.repeat, machine)
        reference = timings["OpenCV StereoSGBM 3WAY"]
        height, width = pair.left.shape[:2]
        lines += [f"### {pair.name}, {width} x {height}", "", "| method | ms | x SGBM 3WAY |", "|---|---|---|"]
        lines += [f"| {name} | {ms:.1f} | {ms / reference:.1f} |" for name, ms in timings.items()]
        lines.append("")
    teddy = scene_pair(every, "teddy")
    if teddy is not None:
        kernels = kernel_times(teddy, args.repeat)
        lines += ["## Device time per kernel, the depth machine on teddy (profiled, medians)", "",
                  f"Sum {sum(ms for *_, ms in kernels):.1f} ms.", "", "| kernel | launches | ms |", "|---|---|---|"]
        lines += [f"| {name} | {calls} | {ms:.2f} |" for name, calls, ms in kernels]
    text = "\n".join(lines) + "\n"
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
