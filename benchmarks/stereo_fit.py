"""Fit the stereo cue's defaults on the training pairs: the semi-global matcher's census margin and
smoothness prices, whether the feature matcher still earns its place beside it, the weight of the pixels'
brightness difference beside the census, the weighted median at depth jumps, the stereo MRF's weights on
those matches, the matcher's occlusion geometry, then the messages' directions and prices again.

Run: python benchmarks/stereo_fit.py

Every combination of the grid below runs the Vision Machine (stereo only, every other setting its
default) on every training pair of benchmarks/stereo_training.py: the rendered scenes and Middlebury
sawtooth and map, never a pair a benchmark reports. A combination's score is the mean of two means of
the restored disparity's bad-1 rate (on the evaluated pixels), over the rendered pairs and over the real
ones, which weigh equally so that the many rendered pairs do not decide alone. Six stages, each a grid:
the matcher's (GRID: the census alone, the weighted median at jumps off, messages along EARLY_PATHS = 8
directions, as stages 2 to 5 pass them), whose best combination gives vmcl.early.semiglobal's
CENSUS_THRESHOLD and StereoConfig's feature_matches (and the P1, P2 and EDGE_GAIN the later stages run
with); then the brightness difference's weight, taken with or without the cameras' difference matched, of the grey
levels or of a colour pair's channels (AD_GRID; the best gives AD_WEIGHT, AD_COLOUR and StereoConfig's
match_exposure); then, with those, the weighted
median's (REFINE_GRID: off, or its radius, colour scale and stride; the cheapest within
REFINE_TOLERANCE of the best), which gives StereoConfig's refine and vmcl.early.semiglobal's
REFINE_RADIUS, REFINE_COLOUR and REFINE_STRIDE; then the MRF's (MRF_GRID): the weight of the matches in
the MRF's data (StereoConfig.backfill_weight) and the stereo MRF's alpha and beta (vmcl.cues.stereo's
DENSE_ALPHA and DENSE_BETA), the best depth lines within MRF_TOLERANCE of the best score; then, with all
of those, the matcher's occlusion geometry on or off (GEOMETRY_GRID; vmcl.early.semiglobal's
occlusion_geometry, StereoConfig's), chosen by the MRF stage's rule. Stages 1 and 2 run with it off, as
with the weighted median off the pixels it calls mismatched would keep no value; stages 3 and 4 with it on
(the default); then, with all of those, the number of scanline directions the messages are passed along
and their prices together (PATHS_GRID, combinations with P2 below P1 left out; vmcl.early.semiglobal's
PATHS, P1, P2 and EDGE_GAIN): stage 1 runs the census alone, whose untextured pixels have no data but
what the messages carry in, and the brightness difference and the weighted median change what the
messages must carry; the fewest directions within REFINE_TOLERANCE of the best score, then the best
score among them. Writes benchmarks/results/stereo_fit.md, every combination of each stage, best first.
"""

from __future__ import annotations

import datetime
import itertools
import sys
from pathlib import Path

import numpy as np
from stereo_training import middlebury_pairs, rendered_pairs

import vmcl
from vmcl import metrics
from vmcl.mrf import boundary_map
from vmcl.pipeline import Config, VisionMachine
from vmcl.stereo_evaluation import DEPTH_ONLY

GRID = {"feature_matches": (True, False), "census_threshold": (2.0, 3.0, 4.0), "p1": (32, 48, 64),
        "p2": (64.0, 96.0, 128.0), "edge_gain": (0.0, 0.1)}
AD_GRID = {"match_exposure": (True, False), "ad_colour": (False, True), "ad_weight": (0.0, 1.0, 2.0, 4.0, 8.0, 16.0)}
REFINE_GRID = [{"refine": False}] + [{"refine": True, "refine_radius": radius, "refine_colour": colour,
                                      "refine_stride": stride}
                                     for radius in (5, 9, 13) for colour in (0.05, 0.1, 0.2) for stride in (1, 2)]
REFINE_TOLERANCE = 0.0005
"""The weighted median's setting is the cheapest (fewest voters visited) of those whose score is within this
of the best, and stage 6's the fewest directions: the scores of neighbouring settings differ by about this
much from run to run of the grid (the matcher's rows alternated within 0.0003), so a closer score does not
pay for more work."""
MRF_GRID = {"backfill_weight": (0.2, 1.0), "alpha": (0.25, 1.0, 4.0, 16.0), "beta": (0.25, 0.5, 2.0, 8.0)}
GEOMETRY_GRID = {"occlusion_geometry": (True, False)}
PATHS_GRID = [{"paths": paths, "p1": p1, "p2": p2, "edge_gain": gain}
              for paths in (8, 4) for p1 in (48, 64, 96, 128, 192) for p2 in (64.0, 96.0, 128.0, 192.0, 256.0)
              for gain in (0.0, 0.1) if p2 >= p1]
"""Stage 6's grid, wider than stage 1's: on this stage's first two runs the chosen P1 (64, then 96) was its
grid's largest, so the grid was widened until the choice lay inside it."""
EARLY_PATHS = 8
"""The scanline directions of stages 1 to 5 (whatever the shipped default, which stage 6 chooses)."""
MRF_TOLERANCE = 0.001
"""The MRF's setting is, among those whose score is within this of the best (about twice the grid's
run-to-run noise; the MRF's rows all lay within 0.003 of each other), the one whose lines find the rendered
scenes' depth discontinuities best: the MRF is where the machine draws them (seed, "Detection of Depth
Discontinuities"), and the disparity's error alone hardly tells its settings apart."""
LINES_LEFT_OUT = "cues"
"""The preset whose depth lines do not enter the MRF's choice: its depth-only outline is a test of the cartoon
(tests/test_pipeline.py)."""


def score(machine: vmcl.Machine, rendered: list, real: list, config: dict) -> tuple[float, list[float], float]:
    """The mean of the rendered pairs' and the real pairs' mean bad-1 of the restored disparity, the rates,
    and the mean F (within 1 px) of the stereo MRF's lines against the rendered pairs' depth discontinuities
    (but those of LINES_LEFT_OUT)."""
    vm = VisionMachine(Config.from_dict({**DEPTH_ONLY, **config}), machine=machine)
    rates, lines_f = [], []
    for p in rendered + real:
        result = vm.run(p.left, p.right)
        rates.append(metrics.evaluate_disparity(result.disparity, p.disparity, mask=p.mask).bad[1.0])
        if p.depth_edges is not None and not p.name.startswith(LINES_LEFT_OUT):
            found = boundary_map(*result.lines["stereo"])
            lines_f.append(np.nan_to_num(metrics.detection_scores(found, p.depth_edges, tolerance=1).f))
    found_score = (float(np.mean(rates[:len(rendered)])) + float(np.mean(rates[len(rendered):]))) / 2
    return found_score, rates, float(np.mean(lines_f))


def stage(machine: vmcl.Machine, rendered: list, real: list, grid: dict | list[dict], config) -> list[tuple]:
    """(score, values, rates, depth lines F) of every combination of ``grid`` (a dictionary of each key's
    values, or a list of the combinations), best score first; ``config(values)`` makes its Config dictionary."""
    combinations = grid if isinstance(grid, list) else [dict(zip(grid, values))
                                                         for values in itertools.product(*grid.values())]
    rows = []
    for values in combinations:
        found, rates, lines_f = score(machine, rendered, real, config(values))
        rows.append((found, values, rates, lines_f))
        print(f"{values}: {found:.4f}, depth lines F {lines_f:.3f}", file=sys.stderr)
    return sorted(rows, key=lambda row: row[0])


def best_lines(rows: list[tuple]) -> dict:
    """The MRF stage's choice (MRF_TOLERANCE): the best depth lines within the tolerance of the best score."""
    best = rows[0][0]
    return max((row for row in rows if row[0] <= best + MRF_TOLERANCE), key=lambda row: row[3])[1]


def voters_visited(values: dict) -> int:
    """Pixels of the weighted median's window that vote, per refined pixel (0 when it is off)."""
    if not values["refine"]:
        return 0
    return (2 * (values["refine_radius"] // values["refine_stride"]) + 1) ** 2


def cheapest_refinement(rows: list[tuple]) -> dict:
    """The refinement stage's choice (REFINE_TOLERANCE): the fewest voters within the tolerance of the best."""
    best = rows[0][0]
    return min((values for found, values, _, _ in rows if found <= best + REFINE_TOLERANCE), key=voters_visited)


def fewest_paths(rows: list[tuple]) -> dict:
    """The directions stage's choice: the fewest directions within REFINE_TOLERANCE of the best score (each
    direction is a pass over the costs), then the best score among those."""
    best = rows[0][0]
    near = [row for row in rows if row[0] <= best + REFINE_TOLERANCE]
    fewest = min(values["paths"] for _, values, _, _ in near)
    return next(values for _, values, _, _ in near if values["paths"] == fewest)


def table(rows: list[tuple], names: list[str]) -> list[str]:
    keys = list(dict.fromkeys(key for _, values, _, _ in rows for key in values))
    lines = ["| score | depth lines F | " + " | ".join(keys) + " | " + " | ".join(names) + " |",
             "|---" * (2 + len(keys) + len(names)) + "|"]
    return lines + [f"| {found:.4f} | {lines_f:.3f} | " + " | ".join(str(values.get(key, "-")) for key in keys)
                    + " | " + " | ".join(f"{r:.3f}" for r in rates) + " |" for found, values, rates, lines_f in rows]


def main() -> int:
    machine = vmcl.Machine()
    rendered, real = rendered_pairs(), middlebury_pairs()
    names = [p.name for p in rendered + real]
    # The weighted median is what gives the pixels the occlusion geometry calls mismatched a value: off with it.
    unrefined = {"refine": False, "occlusion_geometry": False}
    matcher = stage(machine, rendered, real, GRID, lambda values: {"stereo": {**values, "ad_weight": 0.0,
                                                                             "paths": EARLY_PATHS, **unrefined}})
    census = {**matcher[0][1], "paths": EARLY_PATHS}
    data_term = stage(machine, rendered, real, AD_GRID, lambda values: {"stereo": {**census, **values,
                                                                                  **unrefined}})
    chosen = {**census, **data_term[0][1]}
    refinement = stage(machine, rendered, real, REFINE_GRID, lambda values: {"stereo": {**chosen, **values}})
    chosen = {**chosen, **cheapest_refinement(refinement)}
    weights = stage(machine, rendered, real, MRF_GRID, lambda values: {
        "stereo": {**chosen, "backfill_weight": values["backfill_weight"]},
        "mrf": {"stereo": {"alpha": values["alpha"], "beta": values["beta"]}}})
    mrf_choice = best_lines(weights)
    fitted = {"stereo": {**chosen, "backfill_weight": mrf_choice["backfill_weight"]},
              "mrf": {"stereo": {"alpha": mrf_choice["alpha"], "beta": mrf_choice["beta"]}}}
    geometry = stage(machine, rendered, real, GEOMETRY_GRID, lambda values: {
        **fitted, "stereo": {**fitted["stereo"], **values}})
    geometry_choice = best_lines(geometry)
    settled = {**fitted, "stereo": {**fitted["stereo"], **geometry_choice}}
    directions = stage(machine, rendered, real, PATHS_GRID, lambda values: {
        **settled, "stereo": {**settled["stereo"], **values}})
    lines = ["# The stereo cue's defaults, fitted on the training pairs", "",
             (f"Measured {datetime.datetime.now():%Y-%m-%d %H:%M}. The Vision Machine, stereo only, each pair's "
              "range found from the images. Score: the mean of the rendered pairs' mean and the real pairs' "
              "mean of the restored disparity's bad-1. Depth lines F: the stereo MRF's lines against the "
              f"rendered pairs' depth discontinuities (within 1 px; {LINES_LEFT_OUT} left out), their mean. "
              "Best score first; the first row of stages 1 and 2 gives the defaults (but P1, P2 and EDGE_GAIN, "
              "which stage 6 chooses again), stages 3 to 6 say their choice."),
             "", ("## Stage 1: the matcher (the census alone, the weighted median at depth jumps and the occlusion "
                  f"geometry off, {EARLY_PATHS} directions)"), "", *table(matcher, names), "",
             f"## Stage 2: the brightness difference beside the census, with {census}", "", *table(data_term, names),
             "", f"## Stage 3: the weighted median at depth jumps, with {chosen}", "",
             (f"Chosen: the fewest voters per refined pixel among the settings within {REFINE_TOLERANCE} of the best "
              f"score: {cheapest_refinement(refinement)}."), "", *table(refinement, names),
             "", f"## Stage 4: the MRF's weights, with {chosen}", "",
             (f"Chosen: the best depth lines among the settings within {MRF_TOLERANCE} of the best score: "
              f"{mrf_choice}."), "", *table(weights, names),
             "", f"## Stage 5: the matcher's occlusion geometry, with {fitted}", "",
             (f"Chosen: as in stage 4, the best depth lines among the settings within {MRF_TOLERANCE} of the best "
              f"score: {geometry_choice}."), "", *table(geometry, names),
             "", f"## Stage 6: the scanline directions and the messages' prices, with {settled}", "",
             (f"Chosen: the fewest directions among the settings within {REFINE_TOLERANCE} of the best score, then "
              f"the best score among them: {fewest_paths(directions)}."), "", *table(directions, names)]
    out = Path(__file__).resolve().parent / "results" / "stereo_fit.md"
    out.write_text("\n".join(lines) + "\n")
    print("\n".join(lines[:10]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
