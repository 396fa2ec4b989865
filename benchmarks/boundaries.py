"""Boundaries on BSDS500: the cartoon's soft map beside the cartoon, vmcl's Canny and OpenCV's Canny.

Run: python benchmarks/boundaries.py [--data ../shared/datasets] [--split test] [--thresholds 30] [--workers 2]
     [--cartoon-only] [--out benchmarks/results/boundaries.md]

On the BSDS500 test images in the data folder (10 in ../shared; any BSDS-layout folder with --folder;
``--split train --cartoon-only --out benchmarks/results/boundaries_train.md``: the 200 training images the
soft map's model was fitted to, its fit quality, not a test; about an hour of scoring on a 2-core machine
with ``--cartoon-only``, which scores the cartoon's two maps only: the Canny sweeps, made all the same, would
take two thirds of the scoring),
every map comes from vmcl.boundary_evaluation, the harness ``vmcl eval edges`` uses: the monocular
machine's defaults, and the two Canny detectors swept over the same number of
thresholds. The figures are the BSDS benchmark's (match distance 0.0075 of the diagonal, thinning,
one-to-one matching by pyEdgeEval's port of the official code). The model behind the soft map was fitted
to the training images only (benchmarks/boundary_fit.py).
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
from pathlib import Path

import numpy as np

import vmcl
from vmcl.boundary_evaluation import boundary_maps, score_maps
from vmcl.datasets import load_bsds, read_bsds_folder

RESULTS = Path(__file__).resolve().parent / "results"
DEFAULT_DATA = Path(__file__).resolve().parents[1].parent / "shared" / "datasets"
BAR_ODS, BAR_OVER_CANNY = 0.66, 0.06


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, default=DEFAULT_DATA)
    parser.add_argument("--split", choices=("test", "train"), default="test",
                        help="the data's BSDS500 split (train: the images the soft map was fitted to)")
    parser.add_argument("--folder", type=Path, help="a BSDS-layout folder to read instead of the data's split")
    parser.add_argument("--thresholds", type=int, default=30)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--cartoon-only", action="store_true",
                        help="score the cartoon's soft map and binary map only, not the Canny sweeps")
    parser.add_argument("--out", type=Path, default=RESULTS / "boundaries.md")
    args = parser.parse_args()
    images = read_bsds_folder(args.folder) if args.folder else load_bsds(args.data, split=args.split).images
    machine = vmcl.Machine(profile=True)
    load = os.getloadavg()[0]
    sets = boundary_maps(images, thresholds=args.thresholds, machine=machine)
    if args.cartoon_only:
        sets = [maps for maps in sets if maps.name.startswith("vmcl cartoon")]
        assert len(sets) == 2, "boundary_maps' cartoon maps are named 'vmcl cartoon, ...'"
    scores = {maps.name: score_maps(maps, images, workers=args.workers) for maps in sets}
    rows = []
    for maps in sets:
        s = scores[maps.name]
        swept = maps.thresholds > 1
        rows.append(f"| {maps.name} | {s.ods_f:.3f} | {s.ods_precision:.3f} | {s.ods_recall:.3f} | "
                    f"{f'{s.ois_f:.3f}' if swept else '-'} | {f'{s.average_precision:.3f}' if swept else '-'} | "
                    f"{maps.ms_per_image:.0f} |")
    soft = scores[sets[0].name].ods_f
    canny = scores["vmcl Canny, threshold sweep"].ods_f if not args.cartoon_only else None
    beside = f", {soft - canny:+.3f} over vmcl Canny's sweep" if canny is not None else " (Canny not scored)"
    verdict = f"The soft map's ODS F is {soft:.3f} (bar: at least {BAR_ODS}: {'met' if soft >= BAR_ODS else 'not met'})"
    verdict += (f"{beside} (bar: at least +{BAR_OVER_CANNY}: {'met' if soft - canny >= BAR_OVER_CANNY else 'not met'})."
                if canny is not None else f"{beside}.")
    source = f"the folder {args.folder}" if args.folder else f"the BSDS500 {args.split} images in ../shared"
    if args.split == "train" and not args.folder:
        verdict = (f"The soft map's ODS F on the images its model was fitted to is {soft:.3f}{beside}: its fit "
                   "quality (the bars are for the test images, results/boundaries.md).")
    args.out.write_text(f"""# Boundaries on BSDS500: the cartoon's soft map, the cartoon and Canny

Measured {datetime.datetime.now():%Y-%m-%d %H:%M} on {machine.device.platform.name} / {machine.device.name}, \
Python {platform.python_version()}, NumPy {np.__version__}; load average before: {load:.1f}.
{len(images)} images ({source}: {', '.join(item.name for item in images)}); the BSDS benchmark's matching \
at 0.0075 of the diagonal with thinning; {args.thresholds} thresholds per sweep (the benchmark's own count is \
99). The soft map's model was fitted to the training images only (benchmarks/results/boundary_fit.md). \
ms per image: the whole monocular machine for the two cartoon rows, the sweep's detector runs for Canny's.

| map | ODS F | precision | recall | OIS F | AP | ms per image |
|---|---|---|---|---|---|---|
{chr(10).join(rows)}

{verdict}
""")
    print(args.out.read_text())


if __name__ == "__main__":
    main()
