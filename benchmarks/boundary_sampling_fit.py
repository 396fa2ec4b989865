"""Choose how sparsely the probability of boundary computes its wide smoothings, on BSDS500 training images.

Run: python benchmarks/boundary_sampling_fit.py [--data ../shared/datasets] [--held-out 10] [--thresholds 20]
     [--out benchmarks/results/boundary_sampling_fit.md]

The map's wide smoothings (the textons' histograms and tensors at the wider texture scales, the surround) are
computed at every ``floor(sigma / SAMPLES_PER_SIGMA)``-th pixel (vmcl.early.boundary_probability.sample_step).
This script sets that constant to each candidate in turn (inf: every smoothing exact at every pixel, as the
shipped model was fitted) and scores the map on the training images boundary_fit.py holds out of its fit
(the last ``--held-out`` in sorted order), with the BSDS matching at 0.0075 of the diagonal. Beside each: the
map's median wall time per image and its device time in kernels (profiled, one pass over the images), both
measured in this run. The default is the fewest samples per sigma whose ODS and OIS F are within TOLERANCE
of the exact map's. Only the training split is read.
"""

from __future__ import annotations

import argparse
import datetime
import math
import platform
import statistics
import time
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
    parser.add_argument("--held-out", type=int, default=10)
    parser.add_argument("--thresholds", type=int, default=20)
    parser.add_argument("--out", type=Path, default=RESULTS / "boundary_sampling_fit.md")
    args = parser.parse_args()
    held_out = load_bsds(args.data, split="train").images[-args.held_out:]
    truths = [item.boundaries for item in held_out]
    machine, profiled = vmcl.Machine(), vmcl.Machine(profile=True)
    shipped = bp.SAMPLES_PER_SIGMA
    rows = {}
    try:
        for sampling in SAMPLINGS:
            bp.SAMPLES_PER_SIGMA = sampling
            bp.boundary_probability(held_out[0].image, machine=machine)  # build and warm up
            maps, seconds = [], []
            for item in held_out:
                start = time.perf_counter()
                maps.append(bp.boundary_probability(item.image, machine=machine).probability)
                seconds.append(time.perf_counter() - start)
            bp.boundary_probability(held_out[0].image, machine=profiled)
            profiled.timings(reset=True)
            for item in held_out:
                bp.boundary_probability(item.image, machine=profiled)
            device = sum(entry["total_ms"] for entry in profiled.timings(reset=True).values()) / len(held_out)
            s = evaluate_boundaries(maps, truths, thresholds=sweep_thresholds(args.thresholds), workers=2)
            rows[sampling] = (s.ods_f, s.ois_f, s.average_precision, 1e3 * statistics.median(seconds), device)
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
        (f"The {len(held_out)} BSDS500 training images boundary_fit.py holds out of its fit "
         f"({', '.join(item.name for item in held_out)}), BSDS matching at 0.0075 of the diagonal, "
         f"{args.thresholds} thresholds; the shipped model (fitted with every smoothing exact). SAMPLES_PER_SIGMA "
         "s: the wide smoothings are computed at every floor(sigma / s)-th pixel (inf: exact at every pixel). "
         "Times from this run only: the map's median wall ms per image, and its device time in kernels per image "
         "(profiled)."),
        "",
        "| SAMPLES_PER_SIGMA | ODS F | OIS F | AP | wall ms per image | device ms per image |",
        "|---|---|---|---|---|---|",
    ]
    for sampling, (ods, ois, ap, wall, device) in rows.items():
        lines.append(f"| {sampling:g} | {ods:.4f} | {ois:.4f} | {ap:.4f} | {wall:.0f} | {device:.1f} |")
    lines += ["", (f"Chosen: SAMPLES_PER_SIGMA = {chosen:g} (the fewest samples per sigma whose ODS and OIS F are "
                   f"within {TOLERANCE} of the exact map's)."), ""]
    args.out.write_text("\n".join(lines), encoding="utf-8")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
