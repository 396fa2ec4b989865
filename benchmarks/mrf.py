"""Speed of the line-process MRF solvers (vmcl.mrf), written to benchmarks/results/mrf.md.

Run as ``python benchmarks/mrf.py``. In one run, on a piecewise-planar disparity map with noise:

- sweeps per second of each solver's sweep (heat bath, heat bath plus MPM accumulation, mean field, ICM)
  at 256^2 and 512^2, every site (f and l) once per sweep;
- time to the final energy: wall time of ``restore`` with each method, and the energy it reaches;
- mean field restoring a 512^2 disparity map (bar: under 0.5 s);
- a Gibbs sweep against a vectorised NumPy checkerboard sweep of the same model (bar: >= 20x faster);
- where ../shared/datasets is present, Middlebury v2 (tsukuba, venus, teddy): vmcl.early.stereo's matches
  (Canny edges, sparse; and the dense intensity variant) restored by the MRF with Canny edges of the left
  image, bad-1 on nonocc, all and disc, beside cv2.StereoBM (block 15) and StereoSGBM (block 5, P1 = 8 *
  cn * blockSize^2, P2 = 32 * cn * blockSize^2 as OpenCV documents them, uniquenessRatio 10 as `vmcl eval
  stereo` uses; default MODE_SGBM and MODE_SGBM_3WAY), built by vmcl.stereo_evaluation (the one stereo
  evaluation harness) and computed in the same run (bar: vmcl below StereoBM on every scene). vmcl's matcher searches the range vmcl.early.disparity_range.estimate_range finds from the
  images; OpenCV's matchers get numDisparities from the range the dataset publishes (info.txt), rounded up
  to 16. Nothing takes a range from the ground truth.

The machine is shared and noisy: compare ratios within one run.
"""

from __future__ import annotations

import datetime
import platform
import time
from pathlib import Path

import numpy as np

from vmcl import datasets, default_machine, mrf
from vmcl.early.disparity_range import estimate_range
from vmcl.early.edges import canny
from vmcl.early.stereo import match
from vmcl.metrics import evaluate_disparity
from vmcl.mrf import EnergyModel, Settings
from vmcl.mrf.lattice import Lattice, philox_key
from vmcl.stereo_evaluation import (
    BM_BLOCK,
    SGBM_BLOCK,
    baseline_disparities,
    grey,
    opencv_disparity,
    stereo_bm,
    stereo_sgbm,
)

DENSE = Settings().override({"alpha": 0.5, "beta": 4.0, "t0": 4.0, "t_factor": 0.98, "sweeps": 300, "mf_t0": 2.0,
                              "mf_factor": 0.8, "mf_steps": 20, "mf_iterations": 5})
# Mean field in 14 sweeps: 6 temperatures 2, 1.2, ... 0.16, two sweeps each, then 2 ICM sweeps. Measured on
# the 512^2 map: final energy within 0.02% of the 110-sweep schedule's, the same RMS error.
FAST_MEANFIELD = Settings().override({"alpha": 0.5, "beta": 4.0, "mf_t0": 2.0, "mf_factor": 0.6, "mf_steps": 6,
                                       "mf_iterations": 2, "quench": 2})


def restore_with(data, settings: Settings, method: str, **kwargs):
    """mrf.restore with ``settings``' model and its schedule for ``method``."""
    return mrf.restore(data, method=method, model=settings.model, schedule=settings.schedule(method), **kwargs)


def disparity_map(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Slanted planes with jumps of 3 to 8 px at any size, and the same with noise sigma 1 px."""
    y, x = np.mgrid[:n, :n].astype(float) * (96.0 / n)
    depth = 6 + 0.04 * x + 0.02 * y
    box = (x >= 20) & (x < 60) & (y >= 15) & (y < 50)
    depth[box] = 14 + 0.05 * (y[box] - 15) - 0.03 * (x[box] - 20)
    disc = (x - 62) ** 2 + (y - 65) ** 2 < 20 ** 2
    depth[disc] = 20 - 0.04 * (x[disc] - 62)
    noisy = depth + np.random.default_rng(seed).normal(0, 1.0, depth.shape)
    return depth.astype(np.float32), noisy.astype(np.float32)


def best_of(repeats: int, run) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        times.append(time.perf_counter() - start)
    return min(times)


def sweeps_per_second(machine, noisy: np.ndarray, mode: str, count: int = 20) -> float:
    lattice = Lattice(machine, machine.to_device(noisy), None, None, "smooth", DENSE.model)
    key = philox_key(1)
    if mode == "mpm":
        sums = [machine.empty(lattice.n, np.float32) for _ in range(3)]
        accumulate = lattice.kernel("accumulate")

    def run() -> None:
        for k in range(count):
            lattice.sweep("sample" if mode == "mpm" else mode, 1.0, k, key)
            if mode == "mpm":
                machine.launch(accumulate, (lattice.n,), lattice.f, lattice.lh, lattice.lv, *sums, lattice.levels,
                               np.int64(lattice.n))
        machine.finish()

    run()
    return count / best_of(3, run)


class NumpyGibbs:
    """The same model's heat-bath checkerboard sweep, vectorised in NumPy (smooth kind, scalar, padded lines)."""

    def __init__(self, noisy: np.ndarray, model: EnergyModel, seed: int) -> None:
        self.g = noisy.astype(np.float64)
        self.height, self.width = noisy.shape
        self.w = np.full(noisy.shape, model.alpha)
        self.f = self.g.copy()
        self.lh = np.zeros(noisy.shape)
        self.lv = np.zeros(noisy.shape)
        self.table = model.vertex_table()
        self.parallel = model.beta * model.prior.parallel
        self.cost = model.beta * model.prior.line
        self.rng = np.random.default_rng(seed)
        y, x = np.mgrid[:self.height, :self.width]
        self.parity = (x + y) & 1
        self.valid_h = x < self.width - 1
        self.valid_v = y < self.height - 1

    def _line_delta(self, type_: int) -> np.ndarray:
        lh, lv, f = self.lh, self.lv, self.f
        t = self.table

        def shifted(a, dy, dx):
            """a[y + dy, x + dx], zero outside."""
            out = np.zeros_like(a)
            ys = slice(max(dy, 0), self.height + min(dy, 0))
            yd = slice(max(-dy, 0), self.height + min(-dy, 0))
            xs = slice(max(dx, 0), self.width + min(dx, 0))
            xd = slice(max(-dx, 0), self.width + min(-dx, 0))
            out[yd, xd] = a[ys, xs]
            return out

        def vertex(bit, arms, exists):
            rest = sum(a.astype(int) << b for b, a in arms)
            return np.where(exists, t[rest | (1 << bit)] - t[rest], 0.0)

        y = np.arange(self.height)[:, None]
        x = np.arange(self.width)[None, :]
        if type_ == 0:
            bond = (shifted(f, 0, 1) - f) ** 2
            delta = self.cost - bond
            delta += vertex(1, [(0, shifted(lh, -1, 0)), (2, shifted(lv, -1, 0)), (3, shifted(lv, -1, 1))], y > 0)
            delta += vertex(0, [(1, shifted(lh, 1, 0)), (2, lv), (3, shifted(lv, 0, 1))], y < self.height - 1)
            delta += self.parallel * (shifted(lh, 0, -1) + np.where(x + 1 < self.width - 1, shifted(lh, 0, 1), 0))
        else:
            bond = (shifted(f, 1, 0) - f) ** 2
            delta = self.cost - bond
            delta += vertex(3, [(0, shifted(lh, 0, -1)), (1, shifted(lh, 1, -1)), (2, shifted(lv, 0, -1))], x > 0)
            delta += vertex(2, [(0, lh), (1, shifted(lh, 1, 0)), (3, shifted(lv, 0, 1))], x < self.width - 1)
            delta += self.parallel * (shifted(lv, -1, 0) + np.where(y + 1 < self.height - 1, shifted(lv, 1, 0), 0))
        return delta

    def sweep(self, temperature: float) -> None:
        for type_, line, valid in ((0, self.lh, self.valid_h), (1, self.lv, self.valid_v)):
            for parity in (0, 1):
                delta = self._line_delta(type_)
                on = self.rng.random(delta.shape) * (1 + np.exp(np.minimum(delta / temperature, 80))) < 1
                update = valid & (self.parity == parity)
                line[update] = on[update]
        for parity in (0, 1):
            f, keep_h, keep_v = self.f, 1 - self.lh, 1 - self.lv
            a = self.w.copy()
            b = self.w * self.g
            a[:, 1:] += keep_h[:, :-1]
            b[:, 1:] += keep_h[:, :-1] * f[:, :-1]
            a[:, :-1] += keep_h[:, :-1]
            b[:, :-1] += keep_h[:, :-1] * f[:, 1:]
            a[1:, :] += keep_v[:-1, :]
            b[1:, :] += keep_v[:-1, :] * f[:-1, :]
            a[:-1, :] += keep_v[:-1, :]
            b[:-1, :] += keep_v[:-1, :] * f[1:, :]
            sample = b / a + np.sqrt(temperature / (2 * a)) * self.rng.standard_normal(a.shape)
            update = self.parity == parity
            f[update] = sample[update]


DATASETS = Path(__file__).resolve().parents[1] / ".." / "shared" / "datasets"


def real_data(machine) -> list[str]:
    """bad-1 rates on Middlebury v2: vmcl's matches restored by the MRF, beside OpenCV's matchers."""
    lines = ["## Middlebury v2: dense disparity, vmcl.early.stereo matches restored by the MRF (mean field)\n",
             ("No method takes a disparity range from the ground truth. vmcl's matcher searches the range "
              "vmcl.early.disparity_range.estimate_range finds from the images (stated per scene below); "
              "OpenCV's matchers get numDisparities from the range the dataset publishes (info.txt's maximum "
              "disparity 15 / 19 / 59, plus one, rounded up to 16: 16 / 32 / 64), as their documentation asks "
              "for a multiple of 16 (vmcl.stereo_evaluation.baseline_disparities). OpenCV as documented, built by "
              "vmcl.stereo_evaluation (the harness `vmcl eval stereo` uses), on grey images: StereoBM block 15, its other "
              "parameters OpenCV's defaults; StereoSGBM block 5, P1 = 8 * cn * blockSize^2 = 200, P2 = 32 * cn "
              "* blockSize^2 = 800 (cn = 1), uniquenessRatio 10 (as `vmcl eval stereo` sets it; OpenCV's "
              "default is 0), the rest OpenCV's defaults, in its default mode (MODE_SGBM) and in "
              "MODE_SGBM_3WAY. MRF inputs: the matcher's "
              "disparities (NaN where no match) with confidence 1 where matched, 0 elsewhere, and "
              "vmcl.early.edges.canny(left, sigma=2) as brightness edges. \"gaps filled\" is the MRF's start "
              "(restore with ICM and 0 sweeps: the jump fill of neighbour means). StereoBM and SGBM leave "
              "pixels without a value: counted bad, as Middlebury does.\n"),
             "| scene | method | density of the input | bad-1 nonocc | bad-1 all | bad-1 disc | seconds |",
             "|---|---|---|---|---|---|---|"]
    verdicts, ranges = [], []
    for name in ("tsukuba", "venus", "teddy"):
        pair = datasets.load_stereo(name, DATASETS)
        truth = pair.disparity
        start = time.perf_counter()
        found_range = estimate_range(pair.left, pair.right, machine=machine)
        estimate_seconds = time.perf_counter() - start
        levels, levels_note = baseline_disparities(pair)
        ranges.append(f"{name} {found_range.d_min}..{found_range.d_max} (found in {estimate_seconds:.3f} s, not "
                      f"in the seconds column; OpenCV {levels_note})")
        edges = canny(pair.left, sigma=2.0, machine=machine)
        rows = []
        for features in ("canny", "intensity"):
            start = time.perf_counter()
            found = match(pair.left, pair.right, d_min=found_range.d_min, d_max=found_range.d_max,
                          features=features, machine=machine)
            match_seconds = time.perf_counter() - start
            matched = np.isfinite(found.disparity)
            confidence = matched.astype(np.float32)
            runs = [("DEPTH preset", "meanfield", mrf.preset("stereo"))]
            if features == "intensity":
                runs.append(("gaps filled, no MRF", "icm", mrf.preset("stereo").override({"icm_sweeps": 0})))
            for label, method, settings in runs:
                start = time.perf_counter()
                field = restore_with(found.disparity, settings, method, confidence=confidence, edges=edges,
                                     machine=machine).field
                seconds = match_seconds + time.perf_counter() - start
                rows.append((f"vmcl {features} matches + {label}", matched.mean(), field, seconds))
        left, right = grey(pair.left), grey(pair.right)
        for label, matcher in ((f"cv2.StereoBM (block {BM_BLOCK})", stereo_bm(levels)),
                               *((f"cv2.StereoSGBM {mode} (block {SGBM_BLOCK})", stereo_sgbm(levels, mode))
                                 for mode in ("MODE_SGBM", "3WAY"))):
            start = time.perf_counter()
            disparity = opencv_disparity(matcher, left, right)
            seconds = time.perf_counter() - start
            rows.append((label, 1.0, disparity, seconds))
        bad = {}
        for label, density, field, seconds in rows:
            bad[label] = [evaluate_disparity(field, truth, mask=pair.masks[m] & np.isfinite(truth)).bad[1.0]
                          for m in ("nonocc", "all", "disc")]
            lines.append(f"| {name} | {label} | {density:.3f} | {bad[label][0]:.4f} | {bad[label][1]:.4f} | "
                         f"{bad[label][2]:.4f} | {seconds:.3f} |")
        ours, bm = bad["vmcl intensity matches + DEPTH preset"], bad[f"cv2.StereoBM (block {BM_BLOCK})"]
        verdicts.append(f"{name}: " + ", ".join(f"{m} {'holds' if o < b else 'missed'} ({o:.4f} against {b:.4f})"
                                                for m, o, b in zip(("nonocc", "all", "disc"), ours, bm)))
    return lines + ["", ("Ranges searched, vmcl's estimated from the images (the first estimate's time includes "
                         "building its kernels): " + "; ".join(ranges) + "."),
                    "", ("Bar (vmcl's dense disparity below StereoBM's bad-1 on every scene; intensity matches, "
                         "DEPTH preset, against StereoBM): " + "; ".join(verdicts) + "."), ""]


def main() -> None:
    machine = default_machine()
    rows = []
    lines = ["# vmcl.mrf benchmark\n", f"Date: {datetime.datetime.now():%Y-%m-%d %H:%M}  ",
             (f"Device: {machine.device.name} ({machine.device.platform.name}, {machine.compute_units} compute units); "
             f"host {platform.processor() or platform.machine()}, NumPy {np.__version__}\n"),
             ("Model: smooth kind, scalar disparity (slanted planes, jumps of 3 to 8 px, noise sigma 1 px), "
             "alpha 0.5, beta 4, default LinePrior. One sweep updates every line site (4 colours) and every "
             "pixel (2 colours). Timings: best of 3 after a warm-up.\n"),
             "## Sweeps per second\n", "| solver's sweep | 256^2 | 512^2 |", "|---|---|---|"]
    maps = {n: disparity_map(n) for n in (256, 512)}
    for mode, name in (("sample", "Gibbs heat bath (anneal)"), ("mpm", "heat bath + MPM accumulation"),
                       ("mean", "mean field"), ("icm", "ICM")):
        rates = [sweeps_per_second(machine, maps[n][1], mode) for n in (256, 512)]
        rows.append((name, rates))
        lines.append(f"| {name} | {rates[0]:.0f} | {rates[1]:.0f} |")
    lines += ["", "## Time to the final energy (restore, 256^2 and 512^2)\n",
              "| method | sweeps | 256^2 time (s) | 256^2 energy | 512^2 time (s) | 512^2 energy | 512^2 RMS error (px) |",
              "|---|---|---|---|---|---|---|"]
    for method in ("anneal", "mpm", "meanfield", "icm"):
        cells = []
        for n in (256, 512):
            depth, noisy = maps[n]
            restore_with(noisy, DENSE, method, machine=machine)
            result = None

            def run(noisy=noisy, method=method):
                nonlocal result
                result = restore_with(noisy, DENSE, method, machine=machine)

            seconds = best_of(1 if method in ("anneal", "mpm") else 3, run)
            cells.append((seconds, result.energy, float(np.sqrt(np.mean((result.field - depth) ** 2))), result.sweeps))
        lines.append(f"| {method} | {cells[0][3]} | {cells[0][0]:.3f} | {cells[0][1]:.0f} | {cells[1][0]:.3f} | "
                     f"{cells[1][1]:.0f} | {cells[1][2]:.3f} |")
    depth, noisy = maps[512]
    restore_with(noisy, FAST_MEANFIELD, "meanfield", machine=machine)
    fast = None

    def run_fast():
        nonlocal fast
        fast = restore_with(noisy, FAST_MEANFIELD, "meanfield", machine=machine)

    seconds = best_of(3, run_fast)
    rms = float(np.sqrt(np.mean((fast.field - depth) ** 2)))
    lines += ["", (f"Mean field on the 512^2 disparity map with the 14-sweep schedule (6 temperatures from 2 by "
                   f"0.6, 2 sweeps each, 2 ICM sweeps): {seconds:.3f} s, energy {fast.energy:.0f}, RMS error "
                   f"{rms:.3f} px (noise 1.0 px in); {'meets' if seconds < 0.5 else 'misses'} the 0.5 s bar."), ""]
    noisy = maps[512][1]
    numpy_gibbs = NumpyGibbs(noisy, DENSE.model, seed=1)
    numpy_gibbs.sweep(1.0)
    numpy_seconds = best_of(3, lambda: numpy_gibbs.sweep(1.0))
    kernel_seconds = 1.0 / rows[0][1][1]
    lines += ["## Gibbs sweep against NumPy (512^2, the same model and the same colouring)\n",
              "| implementation | seconds per sweep |", "|---|---|",
              f"| vmcl kernels (mrf.cl) | {kernel_seconds * 1e3:.2f} ms |",
              f"| vectorised NumPy checkerboard | {numpy_seconds * 1e3:.1f} ms |", "",
              (f"Ratio: {numpy_seconds / kernel_seconds:.1f}x ({'meets' if numpy_seconds / kernel_seconds >= 20 else 'misses'}"
              " the 20x bar)."),
              (f"For scale: an ICM sweep of the same kernels (no random numbers, no exponentials) takes "
               f"{1e3 / rows[3][1][1]:.2f} ms; the heat bath adds Philox blocks (one per four sites), exp per "
               "line site and Box-Muller per pixel pair, as float16 lanes of 16 sites per work-item (four Philox "
               "blocks computed together on uint4 lanes)."), ""]
    if DATASETS.is_dir():
        lines += real_data(machine)
    text = "\n".join(lines)
    out = Path(__file__).resolve().parent / "results" / "mrf.md"
    out.write_text(text)
    print(text)


if __name__ == "__main__":
    main()
