"""What a fresh install's first runs spend building kernels: `vmcl demo` with empty kernel caches, again with
the caches it filled, then at a second size.

Run: python benchmarks/first_run.py [--out benchmarks/results/first_run.md]

Each run is `vmcl demo --quiet` in a new process whose PoCL cache (POCL_CACHE_DIR) and pyopencl cache
(XDG_CACHE_HOME) are folders of this benchmark's own, empty at the start. The wall time of a run less that
of the same run with every cache filled is what it spent building: OpenCL programs (clang), and PoCL's
work-group functions, which PoCL compiles at a kernel's first launch for each work-group size. The second
size (128 x 128 after 256 x 256) says whether anything is built again for a new image size. Each warm run
is the median of three. After the first run, PoCL's cache is counted: the programs it holds (a program.bc
each: vmcl's builds and any of pyopencl's own) and the work-group functions (a .so each).
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

RESULTS = Path(__file__).resolve().parent / "results"


def demo(caches: Path, size: int, out: Path) -> float:
    """Wall seconds of one `vmcl demo` in a new process with these caches."""
    env = {**os.environ, "POCL_CACHE_DIR": str(caches / "pocl"), "XDG_CACHE_HOME": str(caches / "xdg")}
    start = time.perf_counter()
    subprocess.run([sys.executable, "-m", "vmcl.cli", "demo", "--quiet", "--size", str(size), "--out", str(out)],
                   env=env, check=True, capture_output=True)
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=RESULTS / "first_run.md")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        root = Path(folder)
        out = root / "demo"
        first = demo(root, 256, out)
        programs = sum(1 for _ in (root / "pocl").rglob("program.bc"))
        functions = sum(1 for _ in (root / "pocl").rglob("*.so"))
        warm = statistics.median(demo(root, 256, out) for _ in range(3))
        second_size = demo(root, 128, out)
        warm_second = statistics.median(demo(root, 128, out) for _ in range(3))
    rows = [("first run, empty caches, 256 x 256", first, first - warm),
            ("again, caches filled, 256 x 256 (median of 3)", warm, 0.0),
            ("first run at a second size, 128 x 128", second_size, second_size - warm_second),
            ("again at 128 x 128 (median of 3)", warm_second, 0.0)]
    load = os.getloadavg()[0]
    lines = [
        "# A fresh install's first runs: time spent building kernels",
        "",
        (f"Measured {datetime.datetime.now():%Y-%m-%d %H:%M}, host {platform.machine()}, Python "
         f"{platform.python_version()}, {os.cpu_count()} cores (1-minute load {load:.1f} at the end). Produced by "
         "`python benchmarks/first_run.py`: `vmcl demo --quiet` (the blocks scene, every cue) in a new process "
         "each time, with PoCL's and pyopencl's caches in folders of the benchmark's own, empty at the start."),
        "",
        (f"The first run left {programs} programs and {functions} work-group functions in PoCL's cache: "
         "the builds a first run pays for."),
        "",
        "| run | wall s | spent building (s, against the same run with caches filled) |",
        "|---|---|---|",
        *(f"| {name} | {wall:.1f} | {built:.1f} |" for name, wall, built in rows),
        "",
        (f"Bar (first `vmcl demo` spends at most 15 s building): {first - warm:.1f} s, "
         f"{'met' if first - warm <= 15 else 'NOT met'}. Bar (a second size builds nothing, within 1 s of the "
         f"warm run): {second_size - warm_second:.1f} s, {'met' if second_size - warm_second <= 1 else 'NOT met'}."),
        "",
    ]
    args.out.write_text("\n".join(lines), encoding="utf-8")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
