"""The stereo pairs defaults are fitted on: never the pairs the benchmarks report.

Training pairs: the rendered scenes of vmcl.scenes (every preset at 256 x 256, two noise seeds; visible
pixels evaluated), one world with near objects whose disparities reach about 0.3 W, and the Middlebury 2001
pairs that no table reports as a test figure (sawtooth and map; every pixel of known disparity), each also
with its right view's brightness response changed (EXPOSURE_GAMMA: two cameras rarely agree on exposure
and response, and these pairs were taken with one camera, so only a variant shows a cost's sensitivity
to it). The
test pairs (Middlebury v2 tsukuba, venus and teddy with their masks, scikit-image's Motorcycle, and any
pair a user evaluates) are never used to choose a default.
"""

from __future__ import annotations

from pathlib import Path
from typing import NamedTuple

import numpy as np

from vmcl import datasets, scenes
from vmcl.labels import Label
from vmcl.scenes import Body, Camera, Face, Light, Texture, World

SHARED = Path(__file__).resolve().parents[2] / "shared" / "datasets"
MIDDLEBURY_TRAINING = ("sawtooth", "map")
EXPOSURE_GAMMA = 1.15
"""The exposure variant's right view: its levels, scaled to [0, 1], raised to this power (mid-tones about 5%
darker, black and white unchanged), rounded back to whole levels."""


class Pair(NamedTuple):
    name: str
    left: np.ndarray
    right: np.ndarray
    disparity: np.ndarray
    mask: np.ndarray
    depth_edges: np.ndarray | None = None
    """A rendered pair's depth discontinuities (the pixels its ground truth labels DEPTH); None for real pairs."""


def near_world(shape: tuple[int, int] = (192, 256)) -> World:
    """A dotted wall at depth 6 (d = 0.025 W), a panel at 1.5 (0.1 W) and a plate at 0.5 (0.3 W)."""
    focal = float(shape[1])

    def dots(depth: float) -> Texture:
        return Texture("noise", 5 * depth / focal, 0.5)  # 5-pixel cells on every face

    wall = Face((0.0, 0.0, 6.0), (1, 0, 0), (0, 1, 0), None, (0.6, 0.55, 0.5), dots(6.0))
    panel = Face((-0.45, -0.2, 1.5), (1, 0, 0), (0, 1, 0), (0.3, 0.45), (0.45, 0.6, 0.5), dots(1.5))
    plate = Face((0.02, -0.06, 0.5), (1, 0, 0), (0, 1, 0), (0.13, 0.16), (0.7, 0.5, 0.4), dots(0.5))
    bodies = (Body((wall,), name="wall"), Body((panel,), name="panel"), Body((plate,), name="plate"))
    return World(Camera(shape, focal, 0.15), Light(ambient=1.0), bodies)


def rendered_pairs(seeds: tuple[int, ...] = (0, 1)) -> list[Pair]:
    """Every preset at 256 x 256 for each seed, and the near objects' world (seed 0); noise 0.01."""
    found = []
    worlds = [(name, scenes.preset(name, shape=(256, 256))) for name in scenes.PRESETS]
    for seed in seeds:
        for name, world in worlds:
            s = scenes.render(world, seed=seed, noise=0.01)
            found.append(Pair(f"{name} (seed {seed})", s.left, s.right, s.disparity,
                              ~s.occluded_stereo & np.isfinite(s.disparity), s.labels == Label.DEPTH))
    s = scenes.render(near_world(), seed=0, noise=0.01)
    found.append(Pair("near objects", s.left, s.right, s.disparity, ~s.occluded_stereo & np.isfinite(s.disparity),
                      s.labels == Label.DEPTH))
    return found


def middlebury_pairs(root: Path = SHARED) -> list[Pair]:
    """The Middlebury training pairs under ``root`` (none when it is absent), each followed by its exposure
    variant."""
    found = []
    for name in MIDDLEBURY_TRAINING if root.is_dir() else ():
        pair = datasets.load_stereo(name, root)
        known = np.isfinite(pair.disparity)
        found.append(Pair(name, pair.left, pair.right, pair.disparity, known))
        found.append(Pair(f"{name} (exposure)", pair.left, exposure_variant(pair.right), pair.disparity, known))
    return found


def exposure_variant(view: np.ndarray) -> np.ndarray:
    """An 8-bit view with its response changed by :data:`EXPOSURE_GAMMA`."""
    if view.dtype != np.uint8:
        raise TypeError(f"the training views are 8-bit, got {view.dtype}")
    return np.rint(255 * (view / 255.0) ** EXPOSURE_GAMMA).astype(np.uint8)


def training_pairs(root: Path = SHARED) -> list[Pair]:
    return rendered_pairs() + middlebury_pairs(root)
