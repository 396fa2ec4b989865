"""Colour and texture modules against NumPy/SciPy implementations of the same computations.

Run: python benchmarks/early.py. Writes benchmarks/results/early.md. Timings are medians of repeated
runs in one process, interleaved, so the ratios compare like with like on a shared, noisy machine.
"""

from __future__ import annotations

import datetime
import math
import platform
import time
from pathlib import Path

import numpy as np
from scipy import ndimage

from vmcl import Machine
from vmcl.early import color, noise, texture

REPEATS = 7
TEXTURE = {"fine_sigma": 1.0, "coarse_sigma": 4.0, "threshold": 0.08, "radius": 24}


def albedo_edges_numpy(rgb: np.ndarray) -> np.ndarray:
    r, g = rgb[..., 0], rgb[..., 1]
    s = r + g
    valid = s >= color.MIN_INTENSITY
    with np.errstate(divide="ignore", invalid="ignore"):
        h = r / s
        gain = np.sqrt(r * r + g * g) / (s * s)
    zx = np.zeros_like(h)
    zy = np.zeros_like(h)
    zx[:, :-1] = (h[:, 1:] - h[:, :-1]) / np.hypot(gain[:, 1:], gain[:, :-1])
    zy[:-1] = (h[1:] - h[:-1]) / np.hypot(gain[1:], gain[:-1])
    z = np.hypot(zx, zy)
    ok = valid.copy()
    ok[:, :-1] &= valid[:, 1:]
    ok[:-1] &= valid[1:]
    s_hat = np.median(z[ok]) / math.sqrt(2 * math.log(2))
    return ok & (z > noise.NOISE_HIGH * max(s_hat, color.NOISE_FLOOR))


def density_scipy(image: np.ndarray) -> np.ndarray:
    fine, coarse, t, r = (TEXTURE[k] for k in ("fine_sigma", "coarse_sigma", "threshold", "radius"))
    f = fine**2 * ndimage.gaussian_laplace(image, fine, mode="nearest")
    c = coarse**2 * ndimage.gaussian_laplace(image, coarse, mode="nearest")
    near_bright = ndimage.maximum_filter(c > t, 3)
    near_dark = ndimage.maximum_filter(c < -t, 3)
    blobs = ((f > t) & ~near_bright) | ((f < -t) & ~near_dark)
    return ndimage.uniform_filter(blobs.astype(np.float32), 2 * r + 1, mode="constant")


def median_ms(runs: dict[str, list[float]], key: str) -> float:
    return 1e3 * float(np.median(runs[key]))


def main() -> None:
    machine = Machine()
    rng = np.random.default_rng(0)
    rows = []
    for n in (512, 1024):
        rgb = (rng.random((n, n, 3), dtype=np.float32) * 0.8 + 0.1).astype(np.float32)
        grey = rgb.mean(axis=2)
        rgb_d, grey_d = machine.to_device(rgb), machine.to_device(grey)
        cases = {
            "colour vmcl (device)": lambda a=rgb_d: (color.albedo_edges(a, machine=machine), machine.finish()),
            "colour vmcl (host in/out)": lambda a=rgb: color.albedo_edges(a, machine=machine),
            "colour NumPy": lambda a=rgb: albedo_edges_numpy(a),
            "texture vmcl (device)": lambda a=grey_d: (texture.density(a, machine=machine, **TEXTURE),
                                                       machine.finish()),
            "texture vmcl (host in/out)": lambda a=grey: texture.density(a, machine=machine, **TEXTURE),
            "texture SciPy": lambda a=grey: density_scipy(a),
        }
        for run in cases.values():
            run()  # build kernels, warm the buffer pool
        runs: dict[str, list[float]] = {k: [] for k in cases}
        for _ in range(REPEATS):
            for key, run in cases.items():
                start = time.perf_counter()
                run()
                runs[key].append(time.perf_counter() - start)
        for module, baseline in (("colour", "colour NumPy"), ("texture", "texture SciPy")):
            base = median_ms(runs, baseline)
            for key in cases:
                if key.startswith(module):
                    ms = median_ms(runs, key)
                    rows.append(f"| {n}^2 | {key} | {ms:.2f} | {base / ms:.1f}x |")
    device = f"{machine.device.platform.name} / {machine.device.name}"
    text = "\n".join([
        "# Colour and texture: vmcl against NumPy/SciPy",
        "",
        (f"Measured {datetime.date.today().isoformat()} on {device} ({platform.machine()}, "
         f"{machine.compute_units} compute units), by `python benchmarks/early.py`: medians of {REPEATS} "
         "interleaved runs in one process. The machine is shared and noisy (medians move by about 30% "
         "between runs): read the ratios within one table, not across runs."),
        "",
        ("Colour: `albedo_edges` (hue, validity, noise-normalised gradient, median-rule threshold, "
         "candidates) against the same steps in NumPy. Texture: `density` (fine and coarse Laplacians of "
         f"Gaussians, blob removal, window sum) with {TEXTURE} against scipy.ndimage.gaussian_laplace, "
         "maximum_filter and uniform_filter."),
        "",
        "| size | implementation | ms | speed-up over NumPy/SciPy |",
        "|---|---|---|---|",
        *rows,
        "",
    ])
    out = Path(__file__).resolve().parent / "results" / "early.md"
    out.write_text(text)
    print(text)


if __name__ == "__main__":
    main()
