"""Choose the temporal terms' defaults ([time] gain, memory, jump) on rendered sequences, the training data.

Run: python benchmarks/time_fit.py [--out benchmarks/results/time_fit.md]

Training sequences: vmcl.scenes presets blocks, corridor and cues at 192 x 192, 6 frames, noise 0.02,
with wobble 0.3 (every body's and the rig's speed changes from frame to frame by about 30%, as real
motions do; with constant velocities the carried flow would be exact and any weight on it would win).
The machine streams each with stereo and motion (colour and texture off) under every configuration of
the grid and with the temporal terms off. Scored on the frames that have a past and a next frame:
the restored flow's EPE and the restored disparity's mean absolute error over the visible pixels, each
divided by the same with time off; the configuration with the lowest mean of the two ratios over the
sequences is the default. Then, at that configuration, the previous flow predicting the motion search
([time] predict_search) is scored on and off the same way: on is the default if it scores lower. The real
sequences are scored by benchmarks/motion.py, which chooses nothing.
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import itertools
import platform
from pathlib import Path

import numpy as np

import vmcl
from vmcl import scenes
from vmcl.metrics import evaluate_flow
from vmcl.pipeline import ColourConfig, Config, TextureConfig, TimeConfig, VisionMachine

RESULTS = Path(__file__).resolve().parent / "results"
PRESETS = ("blocks", "corridor", "cues")
SIZE, FRAMES, NOISE, WOBBLE = 192, 6, 0.02, 0.3
GAINS = (0.0625, 0.125, 0.25, 0.5, 1.0, 2.0)
MEMORIES = (1.0, 2.0, 4.0)
JUMPS = (0.125, 0.25, 0.5, 1.0, 2.0)


def errors(results, frames) -> tuple[float, float]:
    """Mean flow EPE and mean |disparity error| over the frames with a past and a next frame."""
    flow, disparity = [], []
    for result, frame in zip(results[1:-1], frames[1:-1]):
        moving = ~frame.occluded_motion & np.isfinite(frame.flow).all(axis=-1)
        visible = ~frame.occluded_stereo & np.isfinite(frame.disparity)
        flow.append(evaluate_flow(result.flow, frame.flow, mask=moving).epe)
        disparity.append(float(np.mean(np.abs(result.disparity - frame.disparity)[visible])))
    return float(np.mean(flow)), float(np.mean(disparity))


def training_sequences() -> dict[str, list]:
    """The rendered training sequences, by preset."""
    return {name: scenes.render_sequence(scenes.preset(name, shape=(SIZE, SIZE)), FRAMES, seed=1, noise=NOISE,
                                         wobble=WOBBLE) for name in PRESETS}


def stream_errors(machine: vmcl.Machine, sequences: dict[str, list], config: Config) -> dict[str, tuple[float, float]]:
    """errors() of each sequence streamed by the machine with ``config`` (colour and texture off)."""
    vm = VisionMachine(dataclasses.replace(config, colour=ColourConfig(enabled=False),
                                           texture=TextureConfig(enabled=False)), machine=machine)
    out = {}
    for name, frames in sequences.items():
        lefts, rights = [f.left for f in frames], [f.right for f in frames]
        out[name] = errors(list(vm.stream(lefts, rights)), frames)
    return out


def score(found: dict[str, tuple[float, float]], off: dict[str, tuple[float, float]]) -> float:
    """The mean over the sequences of the mean of the flow's and the disparity's error ratios to ``off``'s."""
    return float(np.mean([(found[n][0] / off[n][0] + found[n][1] / off[n][1]) / 2 for n in PRESETS]))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=RESULTS / "time_fit.md")
    args = parser.parse_args()
    machine = vmcl.Machine()
    sequences = training_sequences()

    def stream(time: TimeConfig) -> dict[str, tuple[float, float]]:
        return stream_errors(machine, sequences, Config(time=time))

    off = stream(TimeConfig(enabled=False))
    print("off", off, flush=True)
    rows = {}
    for gain, memory, jump in itertools.product(GAINS, MEMORIES, JUMPS):
        # The grid is scored with the search unpredicted, as it was before that switch was fitted (below):
        # its default must not decide the grid it is then fitted on.
        found = stream(TimeConfig(gain=gain, memory=memory, jump=jump, predict_search=False))
        rows[(gain, memory, jump)] = (score(found, off), found)
        print(gain, memory, jump, f"{rows[(gain, memory, jump)][0]:.3f}", flush=True)
    best = min(rows, key=lambda key: rows[key][0])
    header = " | ".join(f"{n} flow EPE / disparity error" for n in PRESETS)
    lines = [
        "# Temporal terms chosen on rendered sequences",
        "",
        (f"Measured {datetime.datetime.now():%Y-%m-%d %H:%M} on {machine.device.name.strip()}, Python "
         f"{platform.python_version()}. Produced by `python benchmarks/time_fit.py`."),
        "",
        (f"Training sequences: vmcl.scenes presets {', '.join(PRESETS)} at {SIZE} x {SIZE}, {FRAMES} frames, noise "
         f"{NOISE}, wobble {WOBBLE} (speeds that change from frame to frame); stereo and motion streamed; scored on "
         "the frames with a past and a next frame. Score: the mean over the sequences of the mean of two ratios to "
         "time off, restored flow EPE and restored disparity mean absolute error (px), over visible pixels."),
        "",
        f"| gain | memory | jump | score | {header} |",
        "|---|---|---|---|" + "---|" * len(PRESETS),
        "| time off | | | 1.000 | " + " | ".join(f"{off[n][0]:.3f} / {off[n][1]:.3f}" for n in PRESETS) + " |",
    ]
    for (gain, memory, jump), (found_score, found) in sorted(rows.items(), key=lambda item: item[1][0]):
        lines.append(f"| {gain} | {memory} | {jump} | {found_score:.3f} | "
                     + " | ".join(f"{found[n][0]:.3f} / {found[n][1]:.3f}" for n in PRESETS) + " |")
    gain, memory, jump = best
    lines += ["", f"Chosen (lowest score): gain {gain}, memory {memory}, jump {jump}.", ""]
    # The search predicted by the previous flow, at the chosen configuration.
    searched = {}
    for predict in (False, True):
        found = stream(TimeConfig(gain=gain, memory=memory, jump=jump, predict_search=predict))
        searched[predict] = (score(found, off), found)
        print("predict_search", predict, f"{searched[predict][0]:.3f}", flush=True)
    lines += ["## The motion search predicted by the previous flow", "",
              ("At the chosen configuration, [time] predict_search off and on (the finest level searched around "
               "the previous flow, carried to the frame, as well as around the coarse-to-fine prediction; each "
               "pixel keeps the better match), scored as above."), "",
              f"| predict_search | score | {header} |", "|---|---|" + "---|" * len(PRESETS)]
    for predict, (found_score, found) in searched.items():
        lines.append(f"| {'on' if predict else 'off'} | {found_score:.3f} | "
                     + " | ".join(f"{found[n][0]:.3f} / {found[n][1]:.3f}" for n in PRESETS) + " |")
    chosen = searched[True][0] < searched[False][0]
    lines += ["", f"Chosen: predict_search {'on' if chosen else 'off'} (on only if it scores lower).", ""]
    args.out.write_text("\n".join(lines), encoding="utf-8")
    print(lines[-2])


if __name__ == "__main__":
    main()
