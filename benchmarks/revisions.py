"""The whole machine's time per frame at two git revisions, measured in one run: how much a change sped it up.

Run: python benchmarks/revisions.py --base REV [--head REV] [--rounds 3] [--frames 3] [--cold | --stream]
[--out FILE]

This machine is shared and its speed drifts by tens of percent within an hour, so times measured in
different runs cannot be compared; this script measures both revisions in alternation, in the same run.
Each revision's tree is exported (git archive) into a temporary folder, and every measurement is a new
process that imports that tree's vmcl (PYTHONPATH first, checked), renders the 'blocks' scene, runs the
machine with its default Config once to build and warm up, then ``--frames`` times; the process reports the
median total and each stage's median. Rounds alternate base and head; the table gives the medians over the
rounds and head's time over base's. The first frame's time is reported as well: with ``--cold`` every process
starts with empty kernel caches of its own (PoCL's and pyopencl's), so it includes building every kernel the
frame uses, what a fresh install's first frame pays. With ``--stream`` each process measures the video rate
bars' measure instead: VisionMachine.stream over the rendered 'blocks' sequence (seed 1, noise 0.01), a
warm-up stream of 3 frames, then ``--frames`` + 2 frames of which all but the first (no past) and the last
(no next frame) count, each Result read and dropped as it comes (as benchmarks/stream_timing.py does; inline
here, since the base revision's tree need not have that file). Writes benchmarks/results/revisions.md by
default (revisions_cold.md with ``--cold``, revisions_stream.md with ``--stream``).
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
SIZES = (256, 512)

_CHILD = """
import json, statistics, sys
import vmcl
from pathlib import Path
assert Path(vmcl.__file__).resolve().is_relative_to(Path(sys.argv[1]).resolve()), vmcl.__file__
from vmcl import scenes
from vmcl.pipeline import Config, VisionMachine
size, frames = int(sys.argv[2]), int(sys.argv[3])
s = scenes.render(scenes.preset("blocks", shape=(size, size)), seed=0, noise=0.01)
machine = vmcl.Machine()
vm = VisionMachine(Config(), machine=machine)
first = vm.run(s.left, s.right, s.left_next)
runs = [vm.run(s.left, s.right, s.left_next) for _ in range(frames)]
stages = {name: statistics.median(r.stages[name] for r in runs) for name in runs[0].stages}
print(json.dumps({"total": statistics.median(r.total_ms for r in runs), "stages": stages,
                  "first": first.total_ms, "device": machine.device.name.strip()}))
"""

_CHILD_STREAM = """
import json, statistics, sys
import vmcl
from pathlib import Path
assert Path(vmcl.__file__).resolve().is_relative_to(Path(sys.argv[1]).resolve()), vmcl.__file__
from vmcl import scenes
from vmcl.pipeline import Config, VisionMachine
size, frames = int(sys.argv[2]), int(sys.argv[3])
sequence = scenes.render_sequence(scenes.preset("blocks", shape=(size, size)), frames + 2, seed=1, noise=0.01)
lefts, rights = [s.left for s in sequence], [s.right for s in sequence]
machine = vmcl.Machine()
vm = VisionMachine(Config(), machine=machine)
first = None
for result in vm.stream(lefts[:3], rights[:3]):
    first = result.total_ms if first is None else first
totals, stages = [], []
for k, result in enumerate(vm.stream(lefts, rights)):
    if 0 < k < len(lefts) - 1:
        totals.append(result.total_ms)
        stages.append(dict(result.stages))
print(json.dumps({"total": statistics.median(totals),
                  "stages": {name: statistics.median(s[name] for s in stages) for name in stages[0]},
                  "first": first, "device": machine.device.name.strip()}))
"""


def export(revision: str, into: Path) -> tuple[Path, str]:
    """The tree of ``revision`` exported into a new folder under ``into``, and the commit's short name."""
    commit = subprocess.run(["git", "rev-parse", "--short", revision], cwd=ROOT, check=True, capture_output=True,
                            text=True).stdout.strip()
    target = into / commit
    target.mkdir()
    archive = subprocess.run(["git", "archive", commit], cwd=ROOT, check=True, capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(target)], input=archive, check=True)
    return target, commit


def measure(tree: Path, size: int, frames: int, cold: bool, stream: bool = False) -> dict:
    """One new process's first frame time, median frame time and stage times with the vmcl of ``tree`` (with
    empty kernel caches of its own when ``cold``; of a stream's steady frames with ``stream``)."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(tree), os.environ.get("PYTHONPATH", "")])}
    if cold:
        caches = Path(tempfile.mkdtemp(prefix="caches-", dir=tree.parent))
        env.update(POCL_CACHE_DIR=str(caches / "pocl"), XDG_CACHE_HOME=str(caches / "xdg"))
    # Run in the tree: `python -c` puts the working folder first on the path, which must not be a checkout's.
    run = subprocess.run([sys.executable, "-c", _CHILD_STREAM if stream else _CHILD, str(tree), str(size), str(frames)],
                         env=env, cwd=tree, check=False, capture_output=True, text=True)
    if run.returncode:
        raise RuntimeError(f"measuring {tree.name} at {size} failed:\n{run.stderr[-2000:]}")
    return json.loads(run.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--base", required=True, help="the earlier revision (a commit, tag or branch)")
    parser.add_argument("--head", default="HEAD", help="the later revision (default HEAD)")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--frames", type=int, default=3)
    modes = parser.add_mutually_exclusive_group()
    modes.add_argument("--cold", action="store_true", help="empty kernel caches for every process")
    modes.add_argument("--stream", action="store_true", help="a stream's steady state instead of single frames")
    parser.add_argument("--out", type=Path)
    args = parser.parse_args()
    name = "revisions_cold.md" if args.cold else "revisions_stream.md" if args.stream else "revisions.md"
    out = args.out or RESULTS / name
    with tempfile.TemporaryDirectory(prefix="vmcl-revisions-") as folder:
        trees = [export(revision, Path(folder)) for revision in (args.base, args.head)]
        found: dict[tuple[str, int], list[dict]] = {}
        for _ in range(args.rounds):
            for size in SIZES:
                for tree, commit in trees:
                    found.setdefault((commit, size), []).append(measure(tree, size, args.frames, args.cold,
                                                                        args.stream))
                    print(commit, size, round(found[(commit, size)][-1]["total"]), flush=True)
    (_, base), (_, head) = trees
    lines = ["# The machine's time per frame at two revisions, in one run", "",
             (f"Measured {datetime.datetime.now():%Y-%m-%d %H:%M} on {found[(head, SIZES[0])][0]['device']}, "
              f"{os.cpu_count()} cores, 1-minute load "
              f"{os.getloadavg()[0]:.1f} at the end. Produced by `python benchmarks/revisions.py --base {args.base} "
              f"--head {args.head}{' --cold' if args.cold else ' --stream' if args.stream else ''}`: base {base}, "
              f"head {head}; "
              + (f"the 'blocks' sequence streamed with every cue and the default Config (temporal terms on); "
                 f"{args.rounds} rounds alternating the revisions, each a new process streaming 3 frames to build "
                 f"and warm up ('first frame': the first of them), then {args.frames + 2} frames, of which the "
                 f"{args.frames} but the first and the last count; "
                 if args.stream else
                 f"the 'blocks' scene with every cue and the default Config; {args.rounds} rounds alternating the "
                 f"revisions, each a new process running a first frame, then {args.frames} frames; ")
              + "medians over the rounds of each process's medians (ms). "
              + ("Every process started with empty kernel caches: its first frame built every kernel it used."
                 if args.cold else "The kernel caches were those of this machine: built already.")), ""]
    for size in SIZES:
        rows = {commit: found[(commit, size)] for commit in (base, head)}
        names = list(rows[head][0]["stages"])
        lines += [f"## {size} x {size}", "", f"| stage | base {base} | head {head} | head / base |", "|---|---|---|---|"]
        for name in ["first", "total", *names]:
            per = [[r[name] if name in ("first", "total") else r["stages"].get(name) for r in rows[commit]]
                   for commit in (base, head)]
            if any(None in values for values in per):  # a stage one of the revisions does not have
                continue
            before, after = (statistics.median(values) for values in per)
            ratio = f"{after / before:.2f}" if before > 0 else ""
            label = {"first": "first frame", "total": "whole frame"}.get(name, name)
            lines.append(f"| {label} | {before:.0f} | {after:.0f} | {ratio} |")
        lines.append("")
    out.write_text("\n".join(lines), encoding="utf-8")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
