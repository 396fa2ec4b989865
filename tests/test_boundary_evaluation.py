"""The boundary evaluation harness: Canny sweeps nest the detectors' edge sets, the scores follow the
benchmark on maps whose answer is known, and `vmcl eval edges` reads a BSDS-layout folder."""

import numpy as np
import pytest
import scipy.io

from vmcl.boundary_evaluation import (
    MapSet,
    boundary_maps,
    canny_sweep,
    opencv_canny_sweep,
    score_maps,
    sweep_thresholds,
)
from vmcl.cli import main
from vmcl.datasets import BSDSImage, find_bsds_folders, read_bsds_folder
from vmcl.early.edges import canny


def _disc_image(size=96):
    """A bright disc on a dark ground, its one annotator's boundary the disc's outline."""
    yy, xx = np.mgrid[:size, :size]
    inside = (yy - size / 2) ** 2 + (xx - size / 2) ** 2 < (size / 4) ** 2
    image = np.where(inside[..., None], 200, 40).astype(np.uint8).repeat(3, axis=2)
    outline = inside & ~np.roll(inside, 1, 0) | inside & ~np.roll(inside, -1, 0) | inside & ~np.roll(inside, 1, 1) \
        | inside & ~np.roll(inside, -1, 1)
    segmentation = np.where(inside, 2, 1).astype(np.uint16)
    return BSDSImage("disc", image, outline[None], segmentation[None])


def test_canny_sweep_nests_the_detectors_edges(machine):
    item = _disc_image()
    image = item.image.astype(np.float32) / 255
    image += np.random.default_rng(0).normal(0, 0.05, image.shape).astype(np.float32)
    image = np.clip(image, 0, 1)
    swept = canny_sweep(image, 5, machine=machine)
    levels = np.geomspace(0.004, 0.4, 5)
    for k, t in enumerate(sweep_thresholds(5)):
        expected = canny(image, sigma=2.0, low_threshold=0.4 * levels[k], high_threshold=levels[k], machine=machine)
        np.testing.assert_array_equal(swept >= t, expected)
    assert opencv_canny_sweep(item.image, 5).max() > 0


def test_scores_of_known_maps():
    item = _disc_image()
    perfect = MapSet("perfect", [item.boundaries[0].astype(np.float32)], 1, 0.0)
    # Not exactly 1: the benchmark thins the outline's corners, and its matching draws random outlier edges
    # (unseeded, as in the official code): 0.977 to 1 over repeated runs, so the bound leaves that room.
    assert score_maps(perfect, [item]).ods_f > 0.95
    # The same outline 2 px off (beyond the match distance on this small image) scores far lower.
    shifted = MapSet("shifted", [np.roll(item.boundaries[0], 2, axis=1).astype(np.float32)], 1, 0.0)
    assert score_maps(shifted, [item]).ods_f < 0.6
    empty = MapSet("empty", [np.zeros(item.boundaries[0].shape, np.float32)], 5, 0.0)
    assert score_maps(empty, [item]).ods_f == 0.0
    with pytest.raises(ValueError, match="1 maps for 2 images"):
        score_maps(perfect, [item, item])


def test_the_soft_map_of_a_disc_finds_its_outline(machine):
    item = _disc_image()
    sets = boundary_maps([item], thresholds=9, machine=machine)
    assert sets[0].name.startswith("vmcl cartoon, soft map")
    scores = {s.name: score_maps(s, [item]) for s in sets}
    assert scores[sets[0].name].ods_f > 0.9
    assert all(0 <= m.min() and m.max() <= 1 for s in sets for m in s.maps)


def test_eval_edges_reads_a_bsds_folder(tmp_path, capsys):
    item = _disc_image(64)
    folder = tmp_path / "bsds" / "disc"
    folder.mkdir(parents=True)
    import cv2

    cv2.imwrite(str(folder / "disc.jpg"), item.image[..., ::-1], [cv2.IMWRITE_JPEG_QUALITY, 100])
    cell = np.empty((1, 1), dtype=object)
    cell[0, 0] = {"Boundaries": item.boundaries[0].astype(np.uint8), "Segmentation": item.segmentations[0]}
    scipy.io.savemat(folder / "disc.mat", {"groundTruth": cell})
    assert [i.name for i in read_bsds_folder(tmp_path / "bsds")] == ["disc"]
    assert main(["eval", "edges", "--data", str(tmp_path / "bsds"), "--thresholds", "5", "-q"]) == 0
    out = capsys.readouterr().out
    assert "soft map" in out and "OpenCV Canny" in out and "ODS F" in out
    assert main(["eval", "edges", "--data", str(tmp_path / "missing"), "-q"]) == 2


def test_eval_edges_names_each_image_it_cannot_score_and_scores_the_others(tmp_path, capsys):
    # A .mat cut short, or without groundTruth, ended in a traceback (exit 1); one of another size was
    # refused after the whole run, naming no file; one image without its .mat stopped every other's scoring.
    import cv2

    item = _disc_image(64)
    cell = np.empty((1, 1), dtype=object)
    cell[0, 0] = {"Boundaries": item.boundaries[0].astype(np.uint8), "Segmentation": item.segmentations[0]}
    names = ("good", "cut", "other", "wrong", "missing")
    for name in names:
        folder = tmp_path / "bsds" / name
        folder.mkdir(parents=True)
        cv2.imwrite(str(folder / f"{name}.jpg"), item.image[..., ::-1], [cv2.IMWRITE_JPEG_QUALITY, 100])
        if name != "missing":
            scipy.io.savemat(folder / f"{name}.mat", {"groundTruth": cell} if name != "other" else {"notes": cell})
    whole = (tmp_path / "bsds" / "cut" / "cut.mat").read_bytes()
    (tmp_path / "bsds" / "cut" / "cut.mat").write_bytes(whole[:len(whole) // 3])
    cell[0, 0] = {"Boundaries": item.boundaries[0].T.astype(np.uint8)[:, :40], "Segmentation": item.segmentations[0]}
    scipy.io.savemat(tmp_path / "bsds" / "wrong" / "wrong.mat", {"groundTruth": cell})
    left_out: list = []
    assert [i.name for i in read_bsds_folder(tmp_path / "bsds", left_out=left_out)] == ["good"]
    assert sorted(p.stem for p, _ in left_out) == ["cut", "missing", "other", "wrong"]
    with pytest.raises(ValueError, match="images without their ground truth"):
        read_bsds_folder(tmp_path / "bsds")
    assert main(["eval", "edges", "--data", str(tmp_path / "bsds"), "--thresholds", "3", "-q"]) == 2
    captured = capsys.readouterr()
    assert "ODS F" in captured.out and "1 images" in captured.out
    for name, why in (("cut", "is not a BSDS ground-truth file"), ("other", "is not a BSDS ground-truth file"),
                      ("wrong", "is 40 x 64, its image wrong.jpg 64 x 64"), ("missing", "no ground truth")):
        assert any(line.startswith(f"vmcl: left out {tmp_path / 'bsds' / name / name}.jpg") and why in line
                   for line in captured.err.splitlines()), (name, captured.err)


# On the 10 BSDS500 test images in ../shared: the soft map's ODS F at least 0.66 and at least 0.06 above
# vmcl Canny's sweep (measured 0.665 and +0.109 with 30 thresholds, benchmarks/results/boundaries.md).
# Here 15 thresholds keep the matching to a few minutes.
SOFT_MAP_BAR, OVER_CANNY_BAR = 0.66, 0.06


def test_soft_map_on_bsds_beats_canny_by_the_bars(datasets_root, machine):
    from vmcl.datasets import load_bsds

    images = load_bsds(datasets_root).images
    sets = {s.name: s for s in boundary_maps(images, thresholds=15, machine=machine)}
    soft = score_maps(sets["vmcl cartoon, soft map (boundary_strength), swept"], images, workers=2)
    canny_scores = score_maps(sets["vmcl Canny, threshold sweep"], images, workers=2)
    print(f"BSDS500 test (10 images, 15 thresholds): soft map ODS {soft.ods_f:.4f} OIS {soft.ois_f:.4f}; "
          f"vmcl Canny ODS {canny_scores.ods_f:.4f}")
    assert soft.ods_f >= SOFT_MAP_BAR
    assert soft.ods_f >= canny_scores.ods_f + OVER_CANNY_BAR
    assert soft.ois_f > canny_scores.ois_f


def test_eval_edges_finds_the_distributions_layout_below_the_folder_it_is_given(tmp_path, capsys):
    """BSR/BSDS500/data/{images,groundTruth}/test, as the distribution unpacks, found below --data; a layout
    without a test split is refused naming what it holds."""
    import cv2

    item = _disc_image(64)
    data = tmp_path / "unpacked" / "BSR" / "BSDS500" / "data"
    for kind in ("images", "groundTruth"):
        (data / kind / "test").mkdir(parents=True)
    cv2.imwrite(str(data / "images" / "test" / "disc.jpg"), item.image[..., ::-1], [cv2.IMWRITE_JPEG_QUALITY, 100])
    cell = np.empty((1, 1), dtype=object)
    cell[0, 0] = {"Boundaries": item.boundaries[0].astype(np.uint8), "Segmentation": item.segmentations[0]}
    scipy.io.savemat(data / "groundTruth" / "test" / "disc.mat", {"groundTruth": cell})
    assert find_bsds_folders(tmp_path / "unpacked") == [data]
    assert main(["eval", "edges", "--data", str(tmp_path / "unpacked"), "--thresholds", "3", "-q"]) == 0
    assert "Boundaries (BSDS500 benchmark, 1 images" in capsys.readouterr().out
    val = tmp_path / "val_only"
    for kind in ("images", "groundTruth"):
        (val / kind / "val").mkdir(parents=True)
    assert main(["eval", "edges", "--data", str(val), "-q"]) == 2
    assert "images/ and groundTruth/ hold no test/ split (images/ holds val)" in capsys.readouterr().err
