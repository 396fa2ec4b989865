"""Fit recognition's decision threshold where a disparity map explains occlusion, on training scenes.

Training data only: the rendered recognition scenes of seeds 0..119 (benchmarks/recognition_fit.py's),
rendered as stereo pairs (vmcl.scenes.recognition_scene(stereo=True): each layer flat at its disparity,
nearer as it is painted later; the left view is the plain scene's). The depth machine (vmcl's defaults,
depth only, the disparity range found from the images) measures each pair's disparity, and
vmcl.recognize.recognize, at every default but the threshold, leaves out of an object's coverage the model
points a nearer surface hides (its ``depth``). The threshold is chosen by recognition_fit.py's rule: the
least significance whose false detections per image stay at most MAX_FALSE; it is
vmcl.recognize.recognition.MIN_SIGNIFICANCE_DEPTH, the default where a disparity map is given. The same
scenes without the disparity (the plain threshold's case) are scored beside it.

Run: python benchmarks/recognition_depth_fit.py
"""

from __future__ import annotations

import platform
import sys
import time
from pathlib import Path

from recognition_fit import MAX_FALSE, SEEDS, SHOWN, THRESHOLDS, chosen_threshold, rate, tally

import vmcl
from vmcl.pipeline import Config, VisionMachine
from vmcl.recognize.recognition import MIN_SIGNIFICANCE, MIN_SIGNIFICANCE_DEPTH
from vmcl.scenes import OBJECTS, example_library, recognition_scene
from vmcl.stereo_evaluation import DEPTH_ONLY

RESULTS = Path(__file__).parent / "results" / "recognition_depth_fit.md"


def main() -> int:
    library, learned = example_library()
    solid = {o.name: o.solid for o in OBJECTS}
    start = time.perf_counter()
    scenes = [recognition_scene(seed=seed, stereo=True) for seed in SEEDS]
    machine = vmcl.Machine()
    vm = VisionMachine(Config.from_dict(DEPTH_ONLY), machine=machine)
    depths = [vm.run(scene.image, scene.right).disparity for scene in scenes]
    counted = {"the machine's disparity": tally(library, learned, scenes, solid, depths=depths),
               "none (the image alone)": tally(library, learned, scenes, solid)}
    chosen = {label: chosen_threshold(rows, len(scenes)) for label, rows in counted.items()}
    seconds = time.perf_counter() - start
    n = len(scenes)
    lines = ["# Recognition's threshold where the machine's disparity explains occlusion, fitted on training scenes",
             "",
             (f"`python benchmarks/recognition_depth_fit.py` on {platform.node() or 'this machine'} "
              f"({time.strftime('%Y-%m-%d')}), {n} training scenes rendered as stereo pairs (seeds "
              f"{SEEDS.start}..{SEEDS.stop - 1}), {len(library)} models, {seconds:.0f} s."), "",
             (f"The least threshold (steps of {THRESHOLDS[1] - THRESHOLDS[0]:g}) whose false detections per image "
              f"are at most {MAX_FALSE:g}, and the recognition rate there, with the depth machine's disparity and "
              "without it:"), "",
             "| disparity | min_significance | recognition rate | flat | solid | false detections per image |",
             "|---|---|---|---|---|---|"]
    for label, rows in counted.items():
        row = rows[chosen[label]]
        lines.append(f"| {label} | {THRESHOLDS[chosen[label]]:g} | {rate(row):.3f} | {row[0] / row[2]:.3f} | "
                     f"{row[1] / row[3]:.3f} | {row[4] / n:.3f} |")
    with_depth = counted["the machine's disparity"]
    lines += ["", "With the machine's disparity, by threshold:", "",
              "| min_significance | recognition rate | false detections per image |", "|---|---|---|"]
    for shown in SHOWN:
        row = with_depth[THRESHOLDS.index(shown)]
        lines.append(f"| {shown:g} | {rate(row):.3f} | {row[4] / n:.3f} |")
    lines += ["", (f"Chosen: min_significance = {THRESHOLDS[chosen[next(iter(counted))]]:g} (where a disparity map is "
                   "given)."), "",
              (f"vmcl.recognize.recognition.MIN_SIGNIFICANCE_DEPTH is {MIN_SIGNIFICANCE_DEPTH:g}; MIN_SIGNIFICANCE (the "
               f"image alone, benchmarks/recognition_fit.py) is {MIN_SIGNIFICANCE:g}."), ""]
    RESULTS.write_text("\n".join(lines))
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
