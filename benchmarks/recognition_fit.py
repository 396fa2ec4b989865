"""Fit recognition's support tolerance, vote cutoff, pairing, alignment stretch and decision threshold on
training scenes.

Training data only: the rendered recognition scenes of seeds 0..119 (vmcl.scenes.recognition_scene, every
object of vmcl.scenes.OBJECTS, 30 to 50 % of each hidden, clutter), the library learned from
vmcl.scenes.example_views (one view of each flat object, five of each solid one). For each tolerance (the
distance within which an image edge supports a model point), the threshold is the least significance whose
false detections per image stay at most 0.1 (the bar of the recognition issue); the setting chosen is the
one whose recognition rate at its threshold is highest (a tie goes to the smaller tolerance). The vote's
cutoff (``candidates``: how many of the best (model view, pose) bins go on to alignment, shared between
the views) is chosen with it, over the same grid (a further tie goes to the fewer candidates): an
object seen by one corner correspondence gets two votes, which a cutoff set by busier bins leaves out.
How many nearest features each corner or arc is paired with for indexing (``neighbours``) is chosen with
them too (a further tie goes to the fewer): two corners of one object can be farther apart than many of
the clutter's corners. Then, at the grid's
choice, the most a solid's view alignment may stretch (``stretch``; the grid runs at 1.3) is chosen the same
way (a tie goes to the smaller stretch, the less freedom), each with its own threshold. Then, at that choice,
the least share of a view's inner markings (a solid's edges between its faces) that must be supported
(``min_inner``; the stages before run without it, GRID_MIN_INNER) the same way: a tie goes to the fewer false
detections per image at its threshold, then to the smaller share. A solid's outline alone is what clutter
polygons match; its inner edges are what tells it from them.
benchmarks/recognition.py reports the test scenes (seeds 1000 on) at the chosen setting, the defaults of
vmcl.recognize.recognize. Writes benchmarks/results/recognition_fit.md.

Run: python benchmarks/recognition_fit.py
"""

from __future__ import annotations

import platform
import sys
import time
from pathlib import Path

import numpy as np

from vmcl.metrics import recognition_scores
from vmcl.recognize import recognize
from vmcl.scenes import OBJECTS, example_library, recognition_scene

RESULTS = Path(__file__).parent / "results" / "recognition_fit.md"
SEEDS = range(120)
TOLERANCES = (2.5, 3.0, 3.5)  # 2 and 4 px were never chosen (the file's earlier runs)
CANDIDATES = (1024, 4096)  # 16384 was never chosen (the file's earlier runs)
NEIGHBOURS = (12, 24, 36)
GRID_STRETCH = 1.3  # the solids' alignment stretch the grid runs at (recognize's default before it was fitted)
STRETCHES = (1.05, 1.1, 1.15, 1.3, 1.5)
GRID_MIN_INNER = 0.0  # the stages before the inner markings' run without their test, whatever recognize's default
MIN_INNERS = (0.0, 0.1, 0.2, 0.3, 0.4)
THRESHOLDS = tuple(np.arange(0.0, 60.5, 0.5))
SHOWN = (0.0, 10.0, 15.0, 20.0, 25.0, 30.0, 35.0, 40.0, 50.0)  # the thresholds the chosen tolerance's table lists
MAX_FALSE = 0.1


def tally(library, learned, scenes, solid, depths=None, **kwargs) -> np.ndarray:
    """Per threshold: flat objects found, solid objects found, flat objects, solid objects, false detections;
    ``depths``, one disparity map per scene (or None), explain occlusion."""
    rows = np.zeros((len(THRESHOLDS), 5))
    for scene, depth in zip(scenes, depths if depths is not None else [None] * len(scenes)):
        # Detections at a threshold are those at the lowest one whose significance reaches it: the greedy
        # explanation takes candidates most significant first, so lower ones never change higher ones.
        found = recognize(scene.image, library, min_significance=min(THRESHOLDS), depth=depth, **kwargs)
        for t, threshold in enumerate(THRESHOLDS):
            scores = recognition_scores([d for d in found if d.significance >= threshold], scene.placements, learned)
            for placement, hit in zip(scene.placements, scores.found):
                kind = int(solid[placement.name])
                rows[t, kind] += hit
                rows[t, 2 + kind] += 1
            rows[t, 4] += scores.false
    return rows


def chosen_threshold(rows: np.ndarray, scenes: int) -> int:
    """The least threshold whose false detections per image are at most MAX_FALSE (the highest if none)."""
    allowed = np.flatnonzero(rows[:, 4] / scenes <= MAX_FALSE)
    return int(allowed[0]) if len(allowed) else len(THRESHOLDS) - 1


def rate(row: np.ndarray) -> float:
    return float((row[0] + row[1]) / (row[2] + row[3]))


def _choice_rows(fits: dict, chosen: float, scenes: int) -> list[str]:
    """Table rows of a one-setting stage: each value, its threshold, its rates there and its false detections."""
    lines = []
    for value, (r, t) in fits.items():
        row = r[t]
        mark = " (chosen)" if value == chosen else ""
        lines.append(f"| {value:g}{mark} | {THRESHOLDS[t]:g} | {rate(row):.3f} | {row[0] / row[2]:.3f} | "
                     f"{row[1] / row[3]:.3f} | {row[4] / scenes:.3f} |")
    return lines


def main() -> int:
    library, learned = example_library()
    solid = {o.name: o.solid for o in OBJECTS}
    scenes = [recognition_scene(seed=seed) for seed in SEEDS]
    start = time.perf_counter()
    fits = {}
    for tolerance in TOLERANCES:
        for count in CANDIDATES:
            for neighbours in NEIGHBOURS:
                counted = tally(library, learned, scenes, solid, tolerance=tolerance, candidates=count,
                                 neighbours=neighbours, stretch=GRID_STRETCH, min_inner=GRID_MIN_INNER)
                fits[tolerance, count, neighbours] = (counted, chosen_threshold(counted, len(scenes)))
    best, candidates, neighbours = max(fits, key=lambda key: (round(rate(fits[key][0][fits[key][1]]), 6), -key[0],
                                                              -key[1], -key[2]))
    chosen = {"tolerance": best, "candidates": candidates, "neighbours": neighbours}
    stretches = {}
    for stretch in STRETCHES:
        counted = fits[best, candidates, neighbours][0] if stretch == GRID_STRETCH else tally(
            library, learned, scenes, solid, stretch=stretch, min_inner=GRID_MIN_INNER, **chosen)
        stretches[stretch] = (counted, chosen_threshold(counted, len(scenes)))
    stretch = max(stretches, key=lambda s: (round(rate(stretches[s][0][stretches[s][1]]), 6), -s))
    inners = {}
    for share in MIN_INNERS:
        counted = stretches[stretch][0] if share == GRID_MIN_INNER else tally(
            library, learned, scenes, solid, stretch=stretch, min_inner=share, **chosen)
        inners[share] = (counted, chosen_threshold(counted, len(scenes)))
    min_inner = max(inners, key=lambda q: (round(rate(inners[q][0][inners[q][1]]), 6),
                                           -inners[q][0][inners[q][1]][4], -q))
    rows, at = inners[min_inner]
    threshold = THRESHOLDS[at]
    # Selection's share: the same scenes with no region's corners paired within their regions.
    alone = tally(library, learned, scenes, solid, stretch=stretch, min_inner=min_inner, regions=0, **chosen)[at]
    seconds = time.perf_counter() - start
    n = len(scenes)
    lines = [("# Recognition: the support tolerance, the vote's cutoff, the pairing, the alignment stretch, the inner "
              "markings' support and the significance threshold, fitted on training scenes"), "",
             (f"`python benchmarks/recognition_fit.py` on {platform.node() or 'this machine'} "
              f"({time.strftime('%Y-%m-%d')}), {n} training scenes (seeds {SEEDS.start}..{SEEDS.stop - 1}), "
              f"{len(library)} models, {seconds:.0f} s."), "",
             (f"Per tolerance, vote cutoff (the best bins kept for alignment, shared between the views) and neighbours (the nearest features each "
              f"corner or arc is paired with), the least threshold (steps of {THRESHOLDS[1] - THRESHOLDS[0]:g}) whose "
              f"false detections per image are at most {MAX_FALSE:g}, and the recognition rate there:"), "",
             ("| tolerance px | candidates | neighbours | min_significance | recognition rate | flat | solid | "
              "false detections per image |"),
             "|---|---|---|---|---|---|---|---|"]
    for (tolerance, count, pairing), (r, t) in fits.items():
        row = r[t]
        mark = " (chosen)" if (tolerance, count, pairing) == (best, candidates, neighbours) else ""
        lines.append(f"| {tolerance:g}{mark} | {count} | {pairing} | {THRESHOLDS[t]:g} | {rate(row):.3f} | "
                     f"{row[0] / row[2]:.3f} | {row[1] / row[3]:.3f} | {row[4] / n:.3f} |")
    lines += ["", (f"At tolerance {best:g} px, {candidates} candidates and {neighbours} neighbours (the highest rate "
                   "above; a tie goes to the smaller tolerance, then to the fewer candidates, then to the fewer "
                   f"neighbours), the solids' alignment stretch (the grid ran at {GRID_STRETCH:g}):"), "",
              "| stretch | min_significance | recognition rate | flat | solid | false detections per image |",
              "|---|---|---|---|---|---|"]
    lines += _choice_rows(stretches, stretch, n)
    lines += ["", (f"At stretch {stretch:g}, the least share of a view's inner markings that must be supported (the "
                   f"stages above ran at {GRID_MIN_INNER:g}, no test):"), "",
              "| min_inner | min_significance | recognition rate | flat | solid | false detections per image |",
              "|---|---|---|---|---|---|"]
    lines += _choice_rows(inners, min_inner, n)
    lines += ["", (f"Chosen: tolerance = {best:g} px, candidates = {candidates}, neighbours = {neighbours}, "
                   f"stretch = {stretch:g}, min_inner = {min_inner:g}, min_significance = {threshold:g} (the highest "
                   "rate; a tie goes to the smaller tolerance, then to the fewer candidates, then to the fewer "
                   "neighbours; then the smaller stretch; then the fewer false detections and the smaller share)."), "",
              (f"The threshold at tolerance {best:g} px, {candidates} candidates, {neighbours} neighbours, "
               f"stretch {stretch:g} and min_inner {min_inner:g}:"), "",
              "| min_significance | recognition rate | false detections per image |", "|---|---|---|"]
    for shown in SHOWN:
        row = rows[THRESHOLDS.index(shown)]
        lines.append(f"| {shown:g} | {rate(row):.3f} | {row[4] / n:.3f} |")
    lines += ["", ("Selection at the chosen setting (each corner of the 8 most salient regions also paired with its "
                   f"{neighbours} nearest of its region, beside each feature's {neighbours} nearest):"), "",
              "| selection | recognition rate | false detections per image |", "|---|---|---|",
              f"| on (regions = 8) | {rate(rows[at]):.3f} | {rows[at][4] / n:.3f} |",
              f"| off (regions = 0) | {rate(alone):.3f} | {alone[4] / n:.3f} |", ""]
    RESULTS.write_text("\n".join(lines))
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
