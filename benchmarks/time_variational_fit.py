"""Fit the variational refinement's pull towards the previous flow ([time] flow_prior) on rendered sequences,
the training data, never on the real sequences.

Run: python benchmarks/time_variational_fit.py [--out benchmarks/results/time_variational_fit.md]

The sequences and the score are benchmarks/time_fit.py's: presets blocks, corridor and cues, speeds that
change from frame to frame; stereo and motion streamed; the mean over the sequences of the mean of the
restored flow's EPE ratio and the restored disparity's error ratio to the same machine with time off. The
machine here runs the motion cue's variational refinement ([motion] variational_iterations at
vmcl.early.variational.ITERATIONS; off in the default machine for its cost), every other setting its
default. With the refinement on, the motion MRF's temporal terms (fitted by time_fit.py with it off) may
carry less; the refinement's own temporal term, a robust pull of each pixel's flow towards the previous
frame's flow carried to it (none where time is broken), is the seed's "continuity in time" inside that
continuous MRF. Each weight of BETAS is scored, 0 (none) included, and the lowest score is the default of
[time] flow_prior, which acts only when the refinement is on. The time-off row is reported beside it, and
the MRF's temporal terms' worth with the refinement on (the default time section against time off).
benchmarks/motion.py scores the real sequences and chooses nothing.
"""

from __future__ import annotations

import argparse
import datetime
import platform
from pathlib import Path

from time_fit import PRESETS, RESULTS, score, stream_errors, training_sequences

import vmcl
from vmcl.early import variational
from vmcl.pipeline import Config, MotionConfig, TimeConfig

BETAS = (0.0, 0.25, 1.0, 4.0, 16.0, 64.0)
"""The pull's weight (grey levels of 255 squared per pixel of flow, as the refinement's alpha): none, then
from far below the smoothness weight (vmcl.early.variational.ALPHA, 160) to below it, in steps of 4. A pull
of 10^4 holds a textured pixel's flow at the prior's (tests/test_early_variational.py)."""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=RESULTS / "time_variational_fit.md")
    args = parser.parse_args()
    machine = vmcl.Machine()
    sequences = training_sequences()
    refined = MotionConfig(variational_iterations=variational.ITERATIONS)

    def stream(time: TimeConfig) -> dict[str, tuple[float, float]]:
        return stream_errors(machine, sequences, Config(motion=refined, time=time))

    off = stream(TimeConfig(enabled=False))
    rows = {}
    for beta in BETAS:
        found = stream(TimeConfig(flow_prior=beta))
        rows[beta] = (score(found, off), found)
        print(beta, f"{rows[beta][0]:.3f}", flush=True)
    best = min(BETAS, key=lambda beta: (rows[beta][0], beta))
    header = " | ".join(f"{n} flow EPE / disparity error" for n in PRESETS)
    lines = [
        "# The variational refinement's pull towards the previous flow, chosen on rendered sequences",
        "",
        (f"Measured {datetime.datetime.now():%Y-%m-%d %H:%M} on {machine.device.name.strip()}, Python "
         f"{platform.python_version()}. Produced by `python benchmarks/time_variational_fit.py`."),
        "",
        ("Training sequences and score: benchmarks/time_fit.py's (the mean over the sequences of the mean of the "
         "restored flow's EPE ratio and the restored disparity's error ratio to time off). The machine runs the "
         f"motion cue's variational refinement ({variational.ITERATIONS} iterations, alpha "
         f"{variational.ALPHA:g}), every other setting its default (the MRF's temporal terms as time_fit.py "
         "chose them with the refinement off); 'flow_prior' is the weight of the refinement's pull towards the "
         "previous frame's flow carried to the frame (0: none, the MRF's temporal terms alone)."),
        "",
        f"| flow_prior | score | {header} |",
        "|---|---|" + "---|" * len(PRESETS),
        "| time off | 1.000 | " + " | ".join(f"{off[n][0]:.3f} / {off[n][1]:.3f}" for n in PRESETS) + " |",
    ]
    for beta, (found_score, found) in sorted(rows.items(), key=lambda item: (item[1][0], item[0])):
        lines.append(f"| {beta:g} | {found_score:.3f} | "
                     + " | ".join(f"{found[n][0]:.3f} / {found[n][1]:.3f}" for n in PRESETS) + " |")
    lines += ["", (f"Chosen (lowest score, then the smaller weight): flow_prior {best:g} (score "
                   f"{rows[best][0]:.3f}; the MRF's temporal terms alone {rows[0.0][0]:.3f})."), ""]
    args.out.write_text("\n".join(lines), encoding="utf-8")
    print(lines[-2])


if __name__ == "__main__":
    main()
