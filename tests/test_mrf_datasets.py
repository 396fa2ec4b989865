"""Middlebury v2 tsukuba: the MRF densifies 10% of the ground-truth disparities (noise sigma 0.3 px).

Stands in for the stereo module's sparse matches until that module exists (issue 5); brightness edges
are OpenCV's Canny of the left image. Skipped when ../shared/datasets is absent.
"""

import cv2
import numpy as np

from vmcl import datasets, mrf
from vmcl.metrics import evaluate_disparity


def test_tsukuba_densified_and_edges_help_at_discontinuities(datasets_root, machine):
    pair = datasets.load_stereo("tsukuba", datasets_root)
    truth = pair.disparity
    rng = np.random.default_rng(0)
    keep = (rng.random(truth.shape) < 0.1) & np.isfinite(truth)
    sparse = np.where(keep, truth + rng.normal(0, 0.3, truth.shape), np.nan).astype(np.float32)
    edges = cv2.Canny(cv2.cvtColor(pair.left, cv2.COLOR_RGB2GRAY), 50, 150) > 0
    params = mrf.preset("depth")
    bad = {}
    for label, e in (("alone", None), ("coupled", edges)):
        field = mrf.restore(sparse, edges=e, method="meanfield", params=params, machine=machine).field
        bad[label] = {m: evaluate_disparity(field, truth, mask=pair.masks[m] & np.isfinite(truth)).bad[1.0]
                      for m in ("nonocc", "disc")}
    assert bad["coupled"]["nonocc"] < 0.04, bad  # measured 0.029
    assert bad["coupled"]["disc"] < bad["alone"]["disc"] - 0.05, bad  # measured 0.155 against 0.274
