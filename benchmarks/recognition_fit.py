"""Fit recognition's decision threshold on training scenes: the least significance a detection needs.

Training data only: the rendered recognition scenes of seeds 0..59 (vmcl.scenes.recognition_scene, every
object of vmcl.scenes.OBJECTS, 30 to 50 % of each hidden, clutter), the library learned from
vmcl.scenes.example_views (one view of each flat object, five of each solid one). The threshold chosen is
the least one whose false detections per image stay at most 0.1 (the bar of the recognition issue);
benchmarks/recognition.py reports the test scenes (seeds 1000 on) at that threshold. Writes
benchmarks/results/recognition_fit.md.

Run: python benchmarks/recognition_fit.py
"""

from __future__ import annotations

import platform
import sys
import time
from pathlib import Path

from vmcl.metrics import recognition_scores
from vmcl.recognize import recognize
from vmcl.scenes import example_library, recognition_scene

RESULTS = Path(__file__).parent / "results" / "recognition_fit.md"
SEEDS = range(60)
THRESHOLDS = (0.0, 10.0, 20.0, 25.0, 27.5, 30.0, 32.5, 35.0, 37.5, 40.0, 50.0)
MAX_FALSE = 0.1


def main() -> int:
    library, learned = example_library()
    rows = {t: [0, 0, 0] for t in THRESHOLDS}  # found, objects, false
    start = time.perf_counter()
    for seed in SEEDS:
        scene = recognition_scene(seed=seed)
        # Detections at a threshold are those at the lowest one whose significance reaches it: the greedy
        # explanation takes candidates most significant first, so lower ones never change higher ones.
        found = recognize(scene.image, library, min_significance=min(THRESHOLDS))
        for t in THRESHOLDS:
            kept = [d for d in found if d.significance >= t]
            scores = recognition_scores(kept, scene.placements, learned)
            rows[t][0] += sum(scores.found)
            rows[t][1] += len(scores.found)
            rows[t][2] += scores.false
    chosen = next((t for t in THRESHOLDS if rows[t][2] / len(SEEDS) <= MAX_FALSE), THRESHOLDS[-1])
    # Selection's share: the same scenes with no region's corners paired among themselves.
    alone = [0, 0, 0]
    for seed in SEEDS:
        scene = recognition_scene(seed=seed)
        scores = recognition_scores(recognize(scene.image, library, min_significance=chosen, regions=0),
                                    scene.placements, learned)
        alone[0] += sum(scores.found)
        alone[1] += len(scores.found)
        alone[2] += scores.false
    seconds = time.perf_counter() - start
    lines = ["# Recognition: the significance threshold, fitted on training scenes", "",
             (f"`python benchmarks/recognition_fit.py` on {platform.node() or 'this machine'} "
              f"({time.strftime('%Y-%m-%d')}), {len(SEEDS)} training scenes (seeds {SEEDS.start}..{SEEDS.stop - 1}), "
              f"{len(library)} models, {seconds:.0f} s."), "",
             "| min_significance | recognition rate | false detections per image |", "|---|---|---|"]
    for t in THRESHOLDS:
        found, objects, false = rows[t]
        lines.append(f"| {t:g} | {found / objects:.3f} | {false / len(SEEDS):.3f} |")
    lines += ["", (f"Chosen: min_significance = {chosen:g} (the least whose false detections per image are at most "
                   f"{MAX_FALSE:g})."), "",
              ("Selection at that threshold (the corners of the 8 most salient regions paired among themselves, "
               "beside each corner's 12 nearest):"), "",
              "| selection | recognition rate | false detections per image |", "|---|---|---|",
              f"| on (regions = 8) | {rows[chosen][0] / rows[chosen][1]:.3f} | {rows[chosen][2] / len(SEEDS):.3f} |",
              f"| off (regions = 0) | {alone[0] / alone[1]:.3f} | {alone[2] / len(SEEDS):.3f} |", ""]
    RESULTS.write_text("\n".join(lines))
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
