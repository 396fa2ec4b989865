"""Fit the integration stage's linear classifier (vmcl.labelling) and measure it on unseen scenes.

Writes vmcl/labelling.json (the shipped weights, fitted as `vmcl fit labelling` fits them:
vmcl.learn.labelling_fit) and benchmarks/results/labelling.md. Run from the repository root:

    python benchmarks/labelling.py

The machine runs on every vmcl.scenes preset at 256 x 256, with and without highlights, for noise seeds
0, 1 and 2 (seeds change the textures' random elements and the noise, not the geometry), with the rule
labels (labels.method = "rule") so that the classifier's inputs do not depend on earlier weights.
- The shipped weights are fitted to seeds 0 and 1 of every preset; seed 2 measures them on images they
  were not fitted to (same geometry), also as one grey image (no stereo, motion or colour).
- Leave one preset out: weights fitted to the other four presets (seeds 0 and 1) label the fifth (seed
  2), a scene of a kind they never saw.
Scores are the ground truth's: discontinuities within the scene's tolerance (Scene.tolerance: 1 px,
texture-only boundaries half their texel spacing; vmcl.metrics.detection_scores) and per label
(vmcl.metrics.label_scores), beside the rule labelling of the same run. The fit's targets reach as far
(vmcl.labelling.fit_targets).
"""

from __future__ import annotations

import platform
import statistics
import time
from pathlib import Path

import numpy as np

from vmcl import labelling, metrics, scenes
from vmcl.integrate import integrate
from vmcl.labels import Label
from vmcl.learn.labelling_fit import fit_labeller, labeller_provenance, labelling_fields, rendered_runs
from vmcl.pipeline import Config, VisionMachine

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results" / "labelling.md"
SHAPE = (256, 256)
FIT_SEEDS, TEST_SEED = (0, 1), 2


def runs(vm: VisionMachine) -> dict[tuple[str, bool | str, int], tuple]:
    """(preset, specular or "grey", seed) -> (Result with rule labels, ground-truth labels, their tolerance) of
    every scene: vmcl.learn.labelling_fit's renderings of every seed, and each preset's seed-TEST_SEED view as
    one grey image."""
    out: dict = dict(rendered_runs(vm, seeds=FIT_SEEDS + (TEST_SEED,), shape=SHAPE))
    for name in scenes.PRESETS:
        scene = scenes.render(scenes.preset(name, shape=SHAPE), seed=TEST_SEED, noise=0.01)
        grey = np.ascontiguousarray(scene.left @ np.array([0.2125, 0.7154, 0.0721], np.float32))
        out[name, "grey", TEST_SEED] = (vm.run(grey), scene.labels, scene.tolerance)
    return out


def scores(predicted: np.ndarray, truth: np.ndarray, tolerance: np.ndarray
           ) -> tuple[float, dict[int, metrics.DetectionScores]]:
    overall = metrics.detection_scores(predicted != 0, truth != 0, tolerance=tolerance)
    kinds = [int(c) for c in labelling.CLASSES[1:]]
    return overall.f, metrics.label_scores(predicted, truth, tolerance=tolerance, labels=kinds)


def _pr(score: metrics.DetectionScores) -> str:
    if score.n_true == 0 and score.n_predicted == 0:
        return "-"
    p = "-" if score.n_predicted == 0 else f"{score.precision:.2f}"
    r = "-" if score.n_true == 0 else f"{score.recall:.2f}"
    return f"{p} / {r}"


def header() -> list[str]:
    head = ["scene", "F (linear)", "F (rule)"] + [Label(int(c)).name.lower() for c in labelling.CLASSES[1:]]
    return ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]


def table(rows_in, labeller, machine) -> list[str]:
    lines = header()
    for key, (r, truth, tolerance) in rows_in:
        predicted = labelling.label(r.support, r.image, labeller=labeller, machine=machine, **labelling_fields(r))
        f, per = scores(predicted, truth, tolerance)
        f_rule, _ = scores(r.labels, truth, tolerance)
        name = key[0] + {True: " (specular)", False: "", "grey": " (grey, one image)"}[key[1]]
        f_text = [f"{v:.2f}" if np.isfinite(v) else "none" for v in (f, f_rule)]
        lines.append("| " + " | ".join([name, *f_text] + [_pr(per[int(c)]) for c in
                                                                               labelling.CLASSES[1:]]) + " |")
    return lines


def cost(vm: VisionMachine, size: int) -> str:
    m = vm.machine
    scene = scenes.render(scenes.preset("blocks", shape=(size, size)), seed=0, noise=0.01)
    r = vm.run(scene.left, scene.right, scene.left_next)
    device = {k: m.to_device(np.ascontiguousarray(v)) for k, v in labelling_fields(r).items()}
    support, image = m.to_device(r.support), m.to_device(r.image)
    lines = {cue: (m.to_device(h.astype(np.uint8)), m.to_device(v.astype(np.uint8))) for cue, (h, v) in r.lines.items()}
    edges = m.to_device(r.edges.astype(np.uint8))
    calls = {"linear": lambda: labelling.label(support, image, machine=m, **device),
             "rule": lambda: integrate(lines, edges=edges, machine=m)}
    times = {name: [] for name in calls}
    for _ in range(30):
        for name, call in calls.items():
            start = time.perf_counter()
            call()
            m.finish()
            times[name].append((time.perf_counter() - start) * 1e3)
    linear, rule = statistics.median(times["linear"]), statistics.median(times["rule"])
    return f"| {size} x {size} | {linear:.2f} | {rule:.2f} | {linear / rule:.1f} |"


def main() -> None:
    vm = VisionMachine(Config.from_dict({"labels": {"method": "rule"}}))
    start = time.perf_counter()
    data = runs(vm)
    took = time.perf_counter() - start
    fitted_on, provenance = labeller_provenance(seeds=FIT_SEEDS, shape=SHAPE, config=vm.config)
    start = time.perf_counter()
    colour_runs = {k: v for k, v in data.items() if k[1] != "grey"}
    shipped = fit_labeller([v for k, v in colour_runs.items() if k[2] in FIT_SEEDS], fitted_on=fitted_on,
                           machine=vm.machine)
    fit_s = time.perf_counter() - start
    shipped.save(labelling.WEIGHTS_FILE, provenance)
    out = ["# Labelling: the linear classifier of the integration stage", "",
           (f"{platform.node()}, {time.strftime('%Y-%m-%d')}, device: {vm.machine.device.name}. "
           "Written by benchmarks/labelling.py, which also fits vmcl/labelling.json."), "",
           (f"{len(data)} runs of the machine in {took:.0f} s; fitting the weights for the "
           f"{2 ** len(labelling.INPUTS)} sets of inputs took {fit_s:.0f} s."), "",
           ("Cells are precision / recall per label within the scene's tolerance (1 px; texture-only "
           "boundaries half the coarser texel spacing of their two sides, Scene.tolerance) ('-': no such pixel "
           "predicted or in the truth); F is the discontinuity F within the same tolerance whatever the label "
           "('none': nothing labelled). "
           "'rule' is labels.method = \"rule\" on the same run."), "",
           f"## Shipped weights (fitted to seeds {FIT_SEEDS}) on seed {TEST_SEED}", ""]
    out += table([(k, v) for k, v in colour_runs.items() if k[2] == TEST_SEED], shipped, vm.machine)
    out += ["", f"## Shipped weights on one grey image (seed {TEST_SEED}): no stereo, motion or colour", "",
            "The weights fitted without those inputs label brightness edges and texture lines only.", ""]
    out += table([(k, v) for k, v in data.items() if k[1] == "grey"], shipped, vm.machine)
    out += ["", f"## Leave one preset out: fitted to the other presets (seeds {FIT_SEEDS}), on seed {TEST_SEED}", ""]
    held_rows = []
    for name in scenes.PRESETS:
        others = fit_labeller([v for k, v in colour_runs.items() if k[0] != name and k[2] in FIT_SEEDS],
                              input_sets=[labelling.INPUTS], machine=vm.machine)
        held_rows += table([(k, v) for k, v in colour_runs.items() if k[0] == name and k[2] == TEST_SEED], others,
                           vm.machine)[2:]
    out += header() + held_rows
    out += ["", "## Cost", "", ("Wall time of one labelling (the one kernel; fields already on the device), "
                                "median of 30, beside the rule labelling (vmcl.integrate.integrate), on the "
                                "blocks scene:"), ""]
    out += ["| size | linear (ms) | rule (ms) | ratio |", "|---|---|---|---|"]
    for size in (256, 512):
        out.append(cost(vm, size))
    RESULTS.write_text("\n".join(out) + "\n")
    print("\n".join(out))


if __name__ == "__main__":
    main()
