"""Middlebury v2: the stereo matcher's dense intensity matches restored by the MRF, beside cv2.StereoBM.

vmcl's matcher searches the range it finds from the images (vmcl.early.disparity_range); StereoBM (block
15) gets numDisparities from the range the dataset publishes, as OpenCV asks, with its missing pixels
counted bad. vmcl's dense disparity has the lower bad-1 rate on the nonocc and all masks of venus and
teddy. On tsukuba StereoBM, searching only the 16 disparities the dataset publishes, is ahead on every
mask, and on disc it is ahead on tsukuba and venus (the matcher's 11 x 11 correlation patches fatten
foreground edges, and the MRF keeps what they say): benchmarks/results/mrf.md holds all of them, and
tsukuba is tested against its measured rate only. The input is
vmcl.early.stereo.match(features="intensity") (the sparse Canny matches, 2 to 4% of the pixels, restore
to a worse map than StereoBM's on tsukuba: benchmarks/results/mrf.md), restored by mean field with the
STEREO preset and vmcl's Canny edges of the left image. Skipped when ../shared/datasets is absent.
"""

import cv2
import numpy as np
import pytest

from vmcl import datasets, mrf
from vmcl.early.disparity_range import estimate_range
from vmcl.early.edges import canny
from vmcl.early.stereo import match
from vmcl.metrics import evaluate_disparity

MASKS = ("nonocc", "all")


def bad_1(field, pair) -> np.ndarray:
    truth = pair.disparity
    return np.array([evaluate_disparity(field, truth, mask=pair.masks[m] & np.isfinite(truth)).bad[1.0]
                     for m in MASKS])


# nonocc bad-1 measured with this pipeline (benchmarks/results/mrf.md); the slack is for the matcher's and
# the solver's float changes, the bar itself is the comparison with StereoBM.
@pytest.mark.parametrize(("name", "measured", "beats_bm"),
                         [("tsukuba", 0.143, False), ("venus", 0.0776, True), ("teddy", 0.194, True)])
def test_restored_intensity_matches_beside_stereo_bm(datasets_root, machine, name, measured, beats_bm):
    pair = datasets.load_stereo(name, datasets_root)
    found_range = estimate_range(pair.left, pair.right, machine=machine)
    found = match(pair.left, pair.right, d_min=found_range.d_min, d_max=found_range.d_max, features="intensity",
                  machine=machine)
    matched = np.isfinite(found.disparity)
    field = mrf.restore(found.disparity, confidence=matched.astype(np.float32),
                        edges=canny(pair.left, sigma=2.0, machine=machine), method="meanfield",
                        model=mrf.preset("stereo").model, schedule=mrf.preset("stereo").schedule("meanfield"),
                        machine=machine).field
    assert np.isfinite(field).all()
    ours = bad_1(field, pair)

    grey = [cv2.cvtColor(image, cv2.COLOR_RGB2GRAY) for image in (pair.left, pair.right)]
    published = int((pair.folder / "info.txt").read_text().split()[1])
    bm = cv2.StereoBM_create(16 * -(-(published + 1) // 16), 15).compute(*grey).astype(np.float32) / 16
    theirs = bad_1(np.where(bm >= 0, bm, np.nan), pair)
    assert (ours < theirs).all() == beats_bm, (MASKS, ours, theirs)
    assert ours[0] < measured + 0.01, ours
    # The MRF must do better than the gaps it starts from on the slanted scenes (venus, teddy): there its
    # smoothing and lines, not the fill, make the map.
    if name != "tsukuba":
        start = mrf.restore(found.disparity, confidence=matched.astype(np.float32), method="icm",
                            schedule=mrf.IcmSchedule(icm_sweeps=0), machine=machine).field
        assert ours[0] < bad_1(start, pair)[0], (ours, bad_1(start, pair))
