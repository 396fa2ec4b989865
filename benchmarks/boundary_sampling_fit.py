"""Choose how sparsely the probability of boundary computes its wide smoothings, on BSDS500 training images.

Run: python benchmarks/boundary_sampling_fit.py [--data ../shared/datasets] [--thresholds 20]
     [--out benchmarks/results/boundary_sampling_fit.md]

The map's wide smoothings (the textons' histograms and tensors at every texture scale of two pixels or more,
and the surround) are computed at every ``floor(sigma / SAMPLES_PER_SIGMA)``-th pixel
(vmcl.early.boundary_probability.sample_step). This script sets that constant to each candidate of SAMPLINGS
in turn (inf: every smoothing exact at every pixel, as the shipped model was fitted) and scores the map on
the training images the shipped model was not fitted to (the last ones in sorted order, past the count its
record names; boundary_fit.py checked the fit on the same images), with the BSDS matching at 0.0075 of the
diagonal. The default is the fewest samples per sigma among the candidates whose ODS and OIS F are within
TOLERANCE of the exact map's. Only the training split is read. The speed is measured by revisions.py and
roofline.py, not here.
"""

from __future__ import annotations

import argparse
import datetime
import math
import platform
from pathlib import Path

import numpy as np

import vmcl
from vmcl.boundary_evaluation import sweep_thresholds
from vmcl.datasets import load_bsds
from vmcl.early import boundary_probability as bp
from vmcl.metrics import evaluate_boundaries

RESULTS = Path(__file__).resolve().parent / "results"
DEFAULT_DATA = Path(__file__).resolve().parents[1].parent / "shared" / "datasets"
SAMPLINGS = (math.inf, 3.0, 2.0, 1.5, 1.0)
TOLERANCE = 0.002


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, default=DEFAULT_DATA)
    parser.add_argument("--thresholds", type=int, default=20)
    parser.add_argument("--out", type=Path, default=RESULTS / "boundary_sampling_fit.md")
    args = parser.parse_args()
    images = load_bsds(args.data, split="train").images
    fitted = bp.BoundaryModel.load().record
    if not fitted or not isinstance(fitted.get("images"), int):
        raise SystemExit("the shipped model's record does not say how many training images it was fitted to")
    held_out = images[fitted["images"]:]  # boundary_fit.py fits to the first ones in sorted order
    if not held_out:
        raise SystemExit("the shipped model was fitted to every training image: none is left to choose on")
    truths = [item.boundaries for item in held_out]
    machine = vmcl.Machine()
    shipped = bp.SAMPLES_PER_SIGMA
    rows = {}
    try:
        for sampling in SAMPLINGS:
            bp.SAMPLES_PER_SIGMA = sampling
            maps = [bp.boundary_probability(item.image, machine=machine).probability for item in held_out]
            s = evaluate_boundaries(maps, truths, thresholds=sweep_thresholds(args.thresholds), workers=2)
            rows[sampling] = (s.ods_f, s.ois_f, s.average_precision)
            print(sampling, rows[sampling], flush=True)
    finally:
        bp.SAMPLES_PER_SIGMA = shipped
    exact = rows[math.inf]
    near = [sampling for sampling, row in rows.items()
            if row[0] >= exact[0] - TOLERANCE and row[1] >= exact[1] - TOLERANCE and math.isfinite(sampling)]
    chosen = min(near) if near else math.inf
    lines = [
        "# The probability of boundary's wide smoothings: how sparsely to compute them",
        "",
        (f"Measured {datetime.datetime.now():%Y-%m-%d %H:%M} on {machine.device.platform.name} / "
         f"{machine.device.name.strip()}, Python {platform.python_version()}, NumPy {np.__version__}. Produced by "
         "`python benchmarks/boundary_sampling_fit.py`."),
        "",
        (f"The {len(held_out)} BSDS500 training images the shipped model was not fitted to "
         f"({', '.join(item.name for item in held_out)}; boundary_fit.py checked its fit on them), BSDS matching "
         f"at 0.0075 of the diagonal, {args.thresholds} thresholds; the shipped model (fitted with every "
         "smoothing exact). SAMPLES_PER_SIGMA s: the wide smoothings are computed at every floor(sigma / s)-th "
         "pixel (inf: exact at every pixel). The time these save is measured by revisions.py and roofline.py."),
        "",
        "| SAMPLES_PER_SIGMA | ODS F | OIS F | AP |",
        "|---|---|---|---|",
    ]
    for sampling, (ods, ois, ap) in rows.items():
        lines.append(f"| {sampling:g} | {ods:.4f} | {ois:.4f} | {ap:.4f} |")
    candidates = ", ".join(f"{sampling:g}" for sampling in SAMPLINGS if math.isfinite(sampling))
    lines += ["", (f"Chosen: SAMPLES_PER_SIGMA = {chosen:g} (among {candidates}: the fewest samples per sigma whose "
                   f"ODS and OIS F are within {TOLERANCE} of the exact map's)."), ""]
    args.out.write_text("\n".join(lines), encoding="utf-8")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
