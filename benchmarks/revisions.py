"""The whole machine's time per frame at two git revisions, measured in one run: how much a change sped it up.

Run: python benchmarks/revisions.py --base REV [--head REV] [--rounds 3] [--frames 3] [--out FILE]

This machine is shared and its speed drifts by tens of percent within an hour, so times measured in
different runs cannot be compared; this script measures both revisions in alternation, in the same run.
Each revision's tree is exported (git archive) into a temporary folder, and every measurement is a new
process that imports that tree's vmcl (PYTHONPATH first, checked), renders the 'blocks' scene, runs the
machine with its default Config once to build and warm up, then ``--frames`` times; the process reports the
median total and each stage's median. Rounds alternate base and head; the table gives the medians over the
rounds and head's time over base's. Writes benchmarks/results/revisions.md by default.
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
vm.run(s.left, s.right, s.left_next)
runs = [vm.run(s.left, s.right, s.left_next) for _ in range(frames)]
stages = {name: statistics.median(r.stages[name] for r in runs) for name in runs[0].stages}
print(json.dumps({"total": statistics.median(r.total_ms for r in runs), "stages": stages,
                  "device": machine.device.name.strip()}))
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


def measure(tree: Path, size: int, frames: int) -> dict:
    """One new process's median frame time and stage times with the vmcl of ``tree``."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(tree), os.environ.get("PYTHONPATH", "")])}
    # Run in the tree: `python -c` puts the working folder first on the path, which must not be a checkout's.
    run = subprocess.run([sys.executable, "-c", _CHILD, str(tree), str(size), str(frames)], env=env, cwd=tree, check=False,
                         capture_output=True, text=True)
    if run.returncode:
        raise RuntimeError(f"measuring {tree.name} at {size} failed:\n{run.stderr[-2000:]}")
    return json.loads(run.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--base", required=True, help="the earlier revision (a commit, tag or branch)")
    parser.add_argument("--head", default="HEAD", help="the later revision (default HEAD)")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--frames", type=int, default=3)
    parser.add_argument("--out", type=Path, default=RESULTS / "revisions.md")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="vmcl-revisions-") as folder:
        trees = [export(revision, Path(folder)) for revision in (args.base, args.head)]
        found: dict[tuple[str, int], list[dict]] = {}
        for _ in range(args.rounds):
            for size in SIZES:
                for tree, commit in trees:
                    found.setdefault((commit, size), []).append(measure(tree, size, args.frames))
                    print(commit, size, round(found[(commit, size)][-1]["total"]), flush=True)
    (_, base), (_, head) = trees
    lines = ["# The machine's time per frame at two revisions, in one run", "",
             (f"Measured {datetime.datetime.now():%Y-%m-%d %H:%M} on {found[(head, SIZES[0])][0]['device']}, "
              f"{os.cpu_count()} cores, 1-minute load "
              f"{os.getloadavg()[0]:.1f} at the end. Produced by `python benchmarks/revisions.py --base {args.base} "
              f"--head {args.head}`: base {base}, head {head}; the 'blocks' scene with every cue and the default "
              f"Config; {args.rounds} rounds alternating the revisions, each a new process running "
              f"{args.frames} frames after a warm-up; medians over the rounds of each process's medians (ms)."), ""]
    for size in SIZES:
        rows = {commit: found[(commit, size)] for commit in (base, head)}
        names = list(rows[head][0]["stages"])
        lines += [f"## {size} x {size}", "", f"| stage | base {base} | head {head} | head / base |", "|---|---|---|---|"]
        for name in ["total", *names]:
            values = []
            for commit in (base, head):
                per = [r["total"] if name == "total" else r["stages"].get(name) for r in rows[commit]]
                values.append(statistics.median(per) if None not in per else None)
            if None in values:
                continue
            ratio = f"{values[1] / values[0]:.2f}" if values[0] > 0 else ""
            label = "whole frame" if name == "total" else name
            lines.append(f"| {label} | {values[0]:.0f} | {values[1]:.0f} | {ratio} |")
        lines.append("")
    args.out.write_text("\n".join(lines), encoding="utf-8")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
