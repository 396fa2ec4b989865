"""Rows that are not epipolar lines: what a vertical offset does to the depth machine, and how well
vmcl.early.rectification measures it; chooses its notes' thresholds on the training pairs.

Run: python benchmarks/rectification.py [--out benchmarks/results/rectification.md]

Training pairs only (benchmarks/stereo_training.py: the rendered scenes, sawtooth and map with their
exposure variants). Each pair's right view is moved down by each of SHIFTS pixels, and turned about its
centre by each of TURNS degrees (bilinearly, the border reflected), and the depth machine (its defaults,
depth only) runs on it, the range found from the images. row_alignment measures each moved pair as the
machine's note does, each track started at the semi-global matcher's disparity.

The rules (the offset's was set before its first run; the spread's, first a turn's counterpart of the
offset's, was set again after a run: the turned pairs' error also counts the slant a turn gives every
surface's disparity, so it could not choose):
- the offset that matters is the smallest shift whose mean bad-1 over the pairs reaches RISE times the
  aligned pairs' mean; ROW_OFFSET_NOTE is the smallest ``typical`` row_alignment measures on a training
  pair at that shift, rounded down to STEP: every training pair moved that far is noted. (The threshold
  is compared with what is measured, and the real pairs' own rows are a little off, so a shift does not
  measure as itself: map's rows sit about 0.2 px up.)
- ROW_SPREAD_NOTE, from which the note adds that the offset varies across the image (the views turned
  or scaled), is the step of STEP above the largest ``spread`` measured on a training pair that is only
  shifted: no pair whose rows are merely offset is said to be turned.
The note itself follows ``typical`` alone, whether the rows are offset as a whole or turned: what harms a
match is its own row's offset, and half the tracks off by the threshold is half the image.
The turned pairs are reported, never used to choose. A turn moves the right view's columns too (by
(y - centre) sin(angle)), so their bad-1 is taken against the true disparity after the turn; that also
slants every surface's disparity from row to row, which the untextured scenes' restoration follows
poorly, so their bad-1 does not measure the rows' offset alone.
"""

from __future__ import annotations

import argparse
import datetime
import math
import platform
from pathlib import Path

import cv2
import numpy as np
from stereo_training import training_pairs

import vmcl
from vmcl import metrics
from vmcl.early.rectification import ROW_OFFSET_NOTE, ROW_SPREAD_NOTE, row_alignment
from vmcl.early.semiglobal import match_semiglobal
from vmcl.pipeline import Config, VisionMachine
from vmcl.stereo_evaluation import DEPTH_ONLY

RESULTS = Path(__file__).resolve().parent / "results"
SHIFTS = (0.0, 0.25, 0.5, 1.0, 2.0, 3.0)
TURNS = (0.25, 0.5, 1.0)
RISE = 1.5
STEP = 0.05


def warp(shape: tuple[int, ...], shift: float = 0.0, degrees: float = 0.0) -> np.ndarray:
    """The 2 x 3 map of a right view's pixels moved down by ``shift`` pixels and turned by ``degrees`` about
    its centre."""
    height, width = shape[:2]
    matrix = cv2.getRotationMatrix2D((width / 2, height / 2), degrees, 1.0)
    matrix[1, 2] += shift
    return matrix


def moved(view: np.ndarray, shift: float = 0.0, degrees: float = 0.0) -> np.ndarray:
    """``view`` moved and turned by :func:`warp`, bilinearly, the border reflected."""
    height, width = view.shape[:2]
    return cv2.warpAffine(view, warp(view.shape, shift, degrees), (width, height), flags=cv2.INTER_LINEAR,
                          borderMode=cv2.BORDER_REFLECT)


def moved_truth(disparity: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """The left view's disparity against a right view moved by ``matrix``: the left pixel (x, y) saw the right
    one at (x - d, y), which now lies at matrix (x - d, y, 1); its column gives the disparity."""
    rows, columns = np.indices(disparity.shape, dtype=np.float64)
    seen = matrix[0, 0] * (columns - disparity) + matrix[0, 1] * rows + matrix[0, 2]
    return (columns - seen).astype(np.float32)


def measure(vm: VisionMachine, machine: vmcl.Machine, pair, shift: float = 0.0, degrees: float = 0.0
            ) -> dict[str, float]:
    """The depth machine's bad-1, the matcher's unconfirmed share, and row_alignment's figures on one pair
    whose right view is moved by ``shift`` and ``degrees``."""
    right = moved(pair.right, shift, degrees)
    truth = moved_truth(pair.disparity, warp(pair.right.shape, shift, degrees))
    result = vm.run(pair.left, right)
    found = match_semiglobal(pair.left, right, machine=machine)
    alignment = row_alignment(pair.left, right, disparity=found.filled)
    none = alignment is None
    return {"bad": metrics.evaluate_disparity(result.disparity, truth, mask=pair.mask).bad[1.0],
            "unconfirmed": float((found.occluded | found.mismatched).mean()),
            "offset": np.nan if none else alignment.offset, "typical": np.nan if none else alignment.typical,
            "spread": np.nan if none else alignment.spread}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=RESULTS / "rectification.md")
    args = parser.parse_args()
    machine = vmcl.Machine()
    vm = VisionMachine(Config.from_dict(DEPTH_ONLY), machine=machine)
    pairs = training_pairs()
    cases = [("shift", s) for s in SHIFTS] + [("turn", t) for t in TURNS]
    got: dict[tuple[str, float], list[dict[str, float]]] = {case: [] for case in cases}
    for pair in pairs:
        for kind, amount in cases:
            move = {"shift": amount} if kind == "shift" else {"degrees": amount}
            got[(kind, amount)].append(measure(vm, machine, pair, **move))
        print(pair.name, [f"{got[c][-1]['bad']:.3f}/{got[c][-1]['typical']:.2f}" for c in cases], flush=True)

    def mean(case, key):
        return float(np.nanmean([m[key] for m in got[case]]))

    aligned = mean(("shift", 0.0), "bad")
    chosen = next((s for s in SHIFTS[1:] if mean(("shift", s), "bad") >= RISE * aligned), None)
    offset_note = (None if chosen is None else
                   math.floor(np.nanmin([m["typical"] for m in got[("shift", chosen)]]) / STEP) * STEP)
    shifted_spread = float(np.nanmax([m["spread"] for s in SHIFTS for m in got[("shift", s)]]))
    # The next step above the largest: the note's test is >=, which a shifted pair at a whole step would meet.
    spread_note = (math.floor(shifted_spread / STEP) + 1) * STEP
    names = [pair.name for pair in pairs]
    lines = [
        "# Rows that are not epipolar lines",
        "",
        (f"Measured {datetime.datetime.now():%Y-%m-%d %H:%M} on {machine.device.name.strip()}, Python "
         f"{platform.python_version()}. Produced by `python benchmarks/rectification.py`."),
        "",
        ("Training pairs (benchmarks/stereo_training.py), each with its right view moved down by a shift (px), or "
         "turned about its centre (degrees). Bad-1: the depth machine's restored disparity (its defaults, depth "
         "only, the range found from the images), share of the known pixels more than 1 px off (a turned pair's "
         "against its disparity after the turn, which moves the right view's columns as well as its rows). Unconfirmed: the "
         "semi-global matcher's pixels the left-right check leaves half-occluded or mismatched. Measured: "
         "vmcl.early.rectification.row_alignment, as the machine's note measures it (each track started at the "
         "semi-global matcher's disparity): typical, the median of the tracks' absolute "
         "vertical displacements (px), which the note compares with ROW_OFFSET_NOTE; spread, their median "
         "distance from their median, compared with ROW_SPREAD_NOTE. The real pairs are themselves a little off "
         "at shift 0."),
        "",
        "| moved | mean bad-1 | mean unconfirmed | smallest typical | largest spread | "
        + " | ".join(f"{name} bad-1 / typical / spread" for name in names) + " |",
        "|---|---|---|---|---|" + "---|" * len(names),
    ]
    for kind, amount in cases:
        case = (kind, amount)
        cells = [f"{m['bad']:.3f} / {m['typical']:.2f} / {m['spread']:.2f}" for m in got[case]]
        label = f"{amount:g} px" if kind == "shift" else f"turned {amount:g} deg"
        lines.append(f"| {label} | {mean(case, 'bad'):.3f} | {mean(case, 'unconfirmed'):.3f} | "
                     f"{np.nanmin([m['typical'] for m in got[case]]):.2f} | "
                     f"{np.nanmax([m['spread'] for m in got[case]]):.2f} | " + " | ".join(cells) + " |")
    lines += ["",
              (f"Rules (the script's docstring states them): the offset that matters is the smallest shift whose mean bad-1 reaches "
               f"{RISE} times the aligned pairs' ({aligned:.3f}): "
               + (f"{chosen:g} px; the smallest typical measured at it, rounded down to {STEP:g} px, is "
                  f"{offset_note:.2f} px." if chosen is not None else "none of the shifts reaches it.")
               + f" vmcl.early.rectification.ROW_OFFSET_NOTE is {ROW_OFFSET_NOTE:g} px. The largest spread measured "
               f"on a pair only shifted is {shifted_spread:.3f} px, the next step of {STEP:g} px above it "
               f"{spread_note:.2f} px; "
               f"vmcl.early.rectification.ROW_SPREAD_NOTE is {ROW_SPREAD_NOTE:g} px. The turned pairs are "
               "reported, not used to choose; their bad-1 also counts the slant a turn gives every surface's "
               "disparity.")]
    args.out.write_text("\n".join(lines) + "\n", encoding="utf-8")
    print(f"wrote {args.out}; offset note {offset_note}, spread note {spread_note} (shifted {shifted_spread:.3f})")


if __name__ == "__main__":
    main()
