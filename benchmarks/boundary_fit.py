"""Fit the probability-of-boundary model (vmcl/early/boundary_probability.json) to BSDS500's training images.

Run: python benchmarks/boundary_fit.py [--data ../shared/datasets] [--split train] [--held-out 10]
     [--thresholds 20] [--out benchmarks/results/boundary_fit.md]

Only the training split is read; any other split (the test images the figures are reported on) is
refused. The training images, in sorted order, are split into the fitting images and the last
``--held-out`` ones, on which the fitted model is checked against vmcl's Canny (fit quality, with the
BSDS benchmark's matching at 0.0075 of the diagonal):

1. Textons: k-means (OpenCV, seeded) of the compressed filter-bank responses
   (:func:`vmcl.early.boundary_probability.bank_responses`) of 4000 pixels of every 4th fitting image.
2. Samples: on every fitting image, the pixels on some annotator's boundary (positives) and pixels more
   than 3 px from every annotator's boundary (negatives), 1500 and 3000 at random; their features at all
   orientations.
3. Logistic regression (Newton's method, weight decay 1e-3 on the non-bias weights), the two classes
   weighed equally, at each sample's orientation: first the orientation where the features' sum (each
   divided by its mean) is largest, then, once, the orientation the fitted model prefers.
"""

from __future__ import annotations

import argparse
import datetime
import platform
from pathlib import Path

import cv2
import numpy as np

import vmcl
from vmcl.boundary_evaluation import canny_sweep, sweep_thresholds
from vmcl.datasets import load_bsds
from vmcl.early import boundary_probability as bp
from vmcl.fitted import code_sha256, files_sha256
from vmcl.metrics import evaluate_boundaries

RESULTS = Path(__file__).resolve().parent / "results"
DEFAULT_DATA = Path(__file__).resolve().parents[1].parent / "shared" / "datasets"
SCALES = (1.5, 3.0, 6.0)
TEXTONS = 32
POSITIVES, NEGATIVES, FAR = 1500, 3000, 3
L2 = 1e-3
SEED = 0


def training_images(root: Path, split: str):
    """The training images; any other split is refused (the test split is where figures are reported)."""
    if split != "train":
        raise SystemExit(f"boundary_fit.py fits on BSDS500's train split only, not {split!r}: the test images are "
                         "kept for reporting")
    return load_bsds(root, split="train").images


def provenance(root: Path, fitting) -> dict:
    """What the model's "fitted" record says it was fitted on: the fitting images' files (their images and
    annotations, hashed) and this script's hash."""
    folder = Path(root) / "bsds500" / "train"
    files = [folder / item.name / f"{item.name}{suffix}" for item in fitting for suffix in (".jpg", ".mat")]
    return {"data_sha256": files_sha256(files), "images": len(fitting),
            "code": "benchmarks/boundary_fit.py", "code_sha256": code_sha256(Path(__file__))}


def fit_textons(images, machine: vmcl.Machine, rng: np.random.Generator) -> np.ndarray:
    samples = []
    for item in images[::4]:
        responses = bp.bank_responses(item.image, machine=machine).reshape(-1, bp.BANK_SIZE)
        samples.append(responses[rng.choice(len(responses), 4000, replace=False)])
    cv2.setRNGSeed(SEED)
    criteria = (cv2.TERM_CRITERIA_MAX_ITER + cv2.TERM_CRITERIA_EPS, 100, 1e-5)
    _, _, centres = cv2.kmeans(np.concatenate(samples).astype(np.float32), TEXTONS, None, criteria, 3,
                               cv2.KMEANS_PP_CENTERS)
    return centres.astype(np.float32)


def sample(images, model: bp.BoundaryModel, machine: vmcl.Machine, rng: np.random.Generator):
    """Features at every orientation, (ORIENTATIONS, n, features), and targets (n,) of every image's samples."""
    features, targets = [], []
    for item in images:
        oriented = bp.oriented_gradients(item.image, model=model, machine=machine)
        on = item.boundaries.any(axis=0)
        near = cv2.dilate(on.astype(np.uint8), np.ones((2 * FAR + 1, 2 * FAR + 1), np.uint8)) > 0
        pos, neg = np.flatnonzero(on), np.flatnonzero(~near)
        pos = rng.choice(pos, min(POSITIVES, len(pos)), replace=False)
        neg = rng.choice(neg, min(NEGATIVES, len(neg)), replace=False)
        flat = oriented.reshape(bp.ORIENTATIONS, -1, oriented.shape[-1])
        features.append(flat[:, np.r_[pos, neg]])
        targets.append(np.r_[np.ones(len(pos)), np.zeros(len(neg))])
    return np.concatenate(features, axis=1), np.concatenate(targets)


def logistic(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Bias and weights of the logistic regression, classes weighed equally, by Newton's method."""
    design = np.hstack([np.ones((len(x), 1)), x.astype(np.float64)])
    weight = np.where(y > 0, 0.5 / y.sum(), 0.5 / (1 - y).sum()) * len(y)
    decay = L2 * np.eye(design.shape[1])
    decay[0, 0] = 0.0
    w = np.zeros(design.shape[1])
    for _ in range(50):
        p = 1.0 / (1.0 + np.exp(-design @ w))
        gradient = design.T @ (weight * (p - y)) / len(y) + decay @ w
        hessian = (design * (weight * p * (1 - p))[:, None]).T @ design / len(y) + decay
        step = np.linalg.solve(hessian, gradient)
        w -= step
        if np.abs(step).max() < 1e-7:
            break
    return w


def at(features: np.ndarray, orientation: np.ndarray) -> np.ndarray:
    return np.take_along_axis(features, orientation[None, :, None], axis=0)[0]


def fit(images, machine: vmcl.Machine) -> bp.BoundaryModel:
    rng = np.random.default_rng(SEED)
    centres = fit_textons(images, machine, rng)
    unfitted = bp.BoundaryModel(SCALES, centres, np.zeros(1 + len(bp.feature_names(SCALES)), np.float32))
    features, targets = sample(images, unfitted, machine, rng)
    plain = 4 * len(SCALES)
    means = features[..., :plain].reshape(-1, plain).mean(axis=0)
    orientation = (features[..., :plain] / means).sum(axis=-1).argmax(axis=0)
    w = logistic(at(features, orientation), targets)
    orientation = (features @ w[1:] + w[0]).argmax(axis=0)
    w = logistic(at(features, orientation), targets)
    return bp.BoundaryModel(SCALES, centres, w.astype(np.float32))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, default=DEFAULT_DATA)
    parser.add_argument("--split", default="train")
    parser.add_argument("--held-out", type=int, default=10)
    parser.add_argument("--thresholds", type=int, default=20)
    parser.add_argument("--model", type=Path, default=bp.MODEL_FILE)
    parser.add_argument("--out", type=Path, default=RESULTS / "boundary_fit.md")
    args = parser.parse_args()
    images = training_images(args.data, args.split)
    fitting, held_out = images[:-args.held_out], images[-args.held_out:]
    machine = vmcl.Machine()
    model = fit(fitting, machine)
    model = bp.BoundaryModel(model.scales, model.centres, model.weights,
                             f"BSDS500 train, the first {len(fitting)} of {len(images)} images in sorted order, "
                             f"{TEXTONS} textons: benchmarks/boundary_fit.py")
    model.save(args.model, provenance(args.data, fitting))
    truths = [item.boundaries for item in held_out]
    maps = {"vmcl probability of boundary": [bp.boundary_probability(item.image, model=model, machine=machine)
                                             .probability for item in held_out],
            "vmcl Canny, threshold sweep": [canny_sweep(item.image, args.thresholds, machine=machine)
                                            for item in held_out]}
    rows = []
    for name, edge_maps in maps.items():
        s = evaluate_boundaries(edge_maps, truths, thresholds=sweep_thresholds(args.thresholds), workers=2)
        rows.append(f"| {name} | {s.ods_f:.3f} | {s.ois_f:.3f} | {s.average_precision:.3f} |")
    weights = "\n".join(f"| {name} | {w:+.3f} |" for name, w in zip(("bias",) + model.features, model.weights))
    args.out.write_text(f"""# Probability of boundary: the fit to BSDS500's training images

Measured {datetime.datetime.now():%Y-%m-%d %H:%M} on {machine.device.platform.name} / {machine.device.name}, \
Python {platform.python_version()}, NumPy {np.__version__}, OpenCV {cv2.__version__}.
Fitted on {len(fitting)} training images ({TEXTONS} textons; {POSITIVES} boundary and {NEGATIVES} other \
pixels per image); checked on the {len(held_out)} training images held out of the fit (the last in sorted \
order), BSDS matching at 0.0075 of the diagonal, {args.thresholds} thresholds. The test images are not read.

| map | ODS F | OIS F | AP |
|---|---|---|---|
{chr(10).join(rows)}

## Weights

| feature | weight |
|---|---|
{weights}
""")
    print(args.out.read_text())


if __name__ == "__main__":
    main()
