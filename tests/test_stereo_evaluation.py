"""vmcl.stereo_evaluation and the folder reader under it: any Middlebury-layout folder, OpenCV as documented."""

import shutil

import cv2
import numpy as np
import pytest

from vmcl import datasets
from vmcl import stereo_evaluation as se
from vmcl.cli import main
from vmcl.early.disparity_range import estimate_range
from vmcl.errors import InputTypeError, InputValueError

V2_TEDDY = "middlebury_stereo_v2eval/teddy"


def _oracle_bad(disparity, truth, mask, threshold):
    """Middlebury's bad-pixel share computed here directly: |d - d_gt| > t, or no value."""
    d, g = disparity[mask], truth[mask]
    return float(np.mean(np.isnan(d) | (np.abs(d - g) > threshold)))


def _opencv(raw):
    """OpenCV's fixed-point output in pixels, its "no value" (below minDisparity 0) as NaN."""
    return np.where(raw < 0, np.nan, raw.astype(np.float32) / 16).astype(np.float32)


# --------------------------------------------------------------------------------------------- baselines


def test_sgbm_3way_is_opencv_bit_for_bit(datasets_root):
    pair = datasets.load_stereo("teddy", datasets_root)
    # teddy's info.txt publishes a maximum disparity of 59: 60 disparities, 64 for OpenCV.
    assert pair.published_disparities == 60
    assert se.baseline_disparities(pair)[0] == 64
    left, right = (cv2.cvtColor(image, cv2.COLOR_RGB2GRAY) for image in (pair.left, pair.right))
    direct = {
        "OpenCV StereoSGBM 3WAY": cv2.StereoSGBM_create(
            minDisparity=0, numDisparities=64, blockSize=5, P1=8 * 1 * 5**2, P2=32 * 1 * 5**2, uniquenessRatio=10,
            mode=cv2.STEREO_SGBM_MODE_SGBM_3WAY).compute(left, right),
        "OpenCV StereoSGBM MODE_SGBM": cv2.StereoSGBM_create(
            minDisparity=0, numDisparities=64, blockSize=5, P1=200, P2=800, uniquenessRatio=10,
            mode=cv2.STEREO_SGBM_MODE_SGBM).compute(left, right),
        "OpenCV StereoBM": cv2.StereoBM_create(numDisparities=64, blockSize=15).compute(left, right),
    }
    evaluation = se.evaluate_pair(pair, se.opencv_baselines(pair), warm=False)
    assert set(evaluation.disparities) == set(direct)
    for name, raw in direct.items():
        expected = _opencv(raw)
        got = evaluation.disparities[name]
        assert got.dtype == np.float32
        assert np.array_equal(got, expected, equal_nan=True), name
        assert np.isnan(got).any()  # OpenCV leaves some pixels without a value: they must count as bad
        for scores in (s for s in evaluation.scores if s.method == name):
            mask = pair.masks[scores.region]
            assert scores.pixels == int(mask.sum())
            assert scores.density == float(np.mean(np.isfinite(expected[mask])))
            for threshold in se.THRESHOLDS:
                assert scores.bad[threshold] == pytest.approx(_oracle_bad(expected, pair.disparity, mask, threshold),
                                                              abs=1e-12)
    assert sorted({s.region for s in evaluation.scores}) == ["all", "disc", "nonocc"]


def test_unpublished_range_comes_from_the_images_not_the_truth(datasets_root):
    pair = datasets.read_stereo_folder(datasets_root / "middlebury_stereo_2003/teddy")
    assert pair.published_disparities is None
    count, note = se.baseline_disparities(pair)
    found = estimate_range(pair.left, pair.right)
    assert count == -(-(found.d_max + 1) // 16) * 16 and count % 16 == 0
    assert "publishes no disparity range" in note and f"{found.d_min}..{found.d_max}" in note


def test_matched_pixels_comparison_against_an_oracle(datasets_root):
    pair = datasets.load_stereo("tsukuba", datasets_root)
    truth = pair.disparity.copy()
    half = truth.copy()
    half[:, : truth.shape[1] // 2] = np.nan  # a method that answers on the right half only
    sgbm = next(m for m in se.opencv_baselines(pair) if m.name == "OpenCV StereoSGBM 3WAY")
    methods = [se.StereoMethod("truth", lambda left, right: truth), se.StereoMethod("half", lambda left, right: half), sgbm]
    evaluation = se.evaluate_pair(pair, methods)
    nonocc = pair.masks["nonocc"]
    scores = {(s.method, s.region): s for s in evaluation.scores}
    assert scores["truth", "nonocc"].bad == {0.5: 0.0, 1.0: 0.0, 2.0: 0.0}
    assert scores["half", "all"].density == pytest.approx(np.mean(np.isfinite(half[pair.masks["all"]])))
    assert scores["half", "nonocc"].bad[1.0] == pytest.approx(np.mean(np.isnan(half[nonocc])))
    assert all(s.ms > 0 for s in evaluation.scores)
    matched_at = nonocc & np.isfinite(evaluation.disparities[sgbm.name])
    rows = {c.method: c for c in evaluation.matched}
    assert set(rows) == {"truth", "half"} and all(c.baseline == sgbm.name for c in rows.values())
    assert rows["truth"].matched == int(matched_at.sum()) > 0
    assert rows["truth"].method_bad == 0.0
    assert rows["truth"].baseline_bad == pytest.approx(
        _oracle_bad(evaluation.disparities[sgbm.name], pair.disparity, matched_at, 1.0))
    assert rows["half"].method_bad == pytest.approx(np.mean(np.isnan(half[matched_at])))


# --------------------------------------------------------------------------------------------- folders


def test_a_copied_scene_under_another_name(datasets_root, tmp_path):
    folder = tmp_path / "my_pair"
    shutil.copytree(datasets_root / V2_TEDDY, folder)
    pair = datasets.read_stereo_folder(folder)
    teddy = datasets.load_stereo("teddy", datasets_root)
    assert pair.name == "my_pair" and pair.folder == folder
    assert (pair.scale, pair.published_disparities, pair.disparity_range) == (4.0, 60, (12.5, 52.75))
    assert np.array_equal(pair.disparity, teddy.disparity, equal_nan=True)
    assert np.array_equal(pair.left, teddy.left) and np.array_equal(pair.right, teddy.right)
    assert pair.masks.keys() == teddy.masks.keys() == {"nonocc", "all", "disc"}
    assert all(np.array_equal(pair.masks[m], teddy.masks[m]) for m in pair.masks)
    methods = se.opencv_baselines(pair)
    ours = se.evaluate_pair(pair, methods, warm=False)
    reference = se.evaluate_pair(teddy, se.opencv_baselines(teddy), warm=False)
    assert [(s.method, s.region, s.bad, s.density, s.mae) for s in ours.scores] == \
           [(s.method, s.region, s.bad, s.density, s.mae) for s in reference.scores]
    # Found as a scene folder itself, and below a folder of scene folders, at any depth within reach.
    assert datasets.find_stereo_folders(folder) == [folder]
    nested = tmp_path / "a" / "b"
    shutil.copytree(folder, nested / "other")
    assert datasets.find_stereo_folders(tmp_path) == [nested / "other", folder]
    assert datasets.find_stereo_folders(tmp_path, depth=1) == [folder]


def test_the_shared_scenes_are_all_found(datasets_root):
    found = {f.relative_to(datasets_root).as_posix() for f in datasets.find_stereo_folders(datasets_root)}
    assert found == {"middlebury_stereo_2001/map", "middlebury_stereo_2001/sawtooth", "middlebury_stereo_2001/tsukuba",
                     "middlebury_stereo_2001/venus", "middlebury_stereo_2003/teddy",
                     "middlebury_stereo_v2eval/teddy", "middlebury_stereo_v2eval/tsukuba",
                     "middlebury_stereo_v2eval/venus"}
    # Each copy agrees with its other copy (PROVENANCE: the same pixels), whatever its layout's scale.
    for name, old in (("tsukuba", "middlebury_stereo_2001/tsukuba"), ("venus", "middlebury_stereo_2001/venus"),
                      ("teddy", "middlebury_stereo_2003/teddy")):
        v2 = datasets.load_stereo(name, datasets_root)
        other = datasets.read_stereo_folder(datasets_root / old)
        assert np.array_equal(other.disparity, v2.disparity, equal_nan=True), name
        assert other.scale == v2.scale and other.masks == {} and other.published_disparities is None
    assert [datasets.load_stereo(n, datasets_root).published_disparities for n in ("tsukuba", "venus")] == [16, 20]


def _write_pair(folder, names, shape, rng):
    folder.mkdir(parents=True, exist_ok=True)
    for name in names:
        assert cv2.imwrite(str(folder / name), rng.integers(0, 256, shape, dtype=np.uint8))


@pytest.mark.parametrize(("width", "scale"), [(463, 3), (695, 2), (1390, 1)])
def test_2005_2006_layout_scale_from_the_published_width(tmp_path, width, scale):
    rng = np.random.default_rng(width)
    folder = tmp_path / "Art"
    _write_pair(folder, ("view1.png", "view5.png"), (6, width), rng)
    grey = rng.integers(0, 256, (6, width), dtype=np.uint8)
    grey[0, :5] = 0
    assert cv2.imwrite(str(folder / "disp1.png"), grey)
    pair = datasets.read_stereo_folder(folder)
    expected = np.where(grey == 0, np.nan, grey / scale).astype(np.float32)
    assert pair.scale == scale and pair.published_disparities is None and pair.masks == {}
    assert np.array_equal(pair.disparity, expected, equal_nan=True)
    assert np.isnan(pair.disparity[0, :5]).all()


def test_2005_layout_of_an_unpublished_width_is_refused(tmp_path):
    folder = tmp_path / "cropped"
    _write_pair(folder, ("view1.png", "view5.png", "disp1.png"), (6, 550), np.random.default_rng(0))
    with pytest.raises(InputValueError, match="550 px wide.*scale of disp1.png cannot be decided"):
        datasets.read_stereo_folder(folder)


def _write_pfm_by_hand(path, rows_top_first):
    """A little-endian PFM written here: its rows bottom to top, as the format stores them."""
    height, width = rows_top_first.shape
    path.write_bytes(f"Pf\n{width} {height}\n-1.0\n".encode() + np.flipud(rows_top_first).astype("<f4").tobytes())


@pytest.mark.parametrize("truth_name", ["disp0.pfm", "disp0GT.pfm"])
def test_2014_layout(tmp_path, truth_name):
    rng = np.random.default_rng(7)
    folder = tmp_path / "Adirondack-perfect"
    _write_pair(folder, ("im0.png", "im1.png"), (5, 8, 3), rng)
    truth = (rng.random((5, 8)) * 60).astype(np.float32)
    truth[0, 0] = truth[4, 7] = np.inf
    _write_pfm_by_hand(folder / truth_name, truth)
    (folder / "calib.txt").write_text("cam0=[4000 0 1000; 0 4000 900; 0 0 1]\ncam1=[4000 0 1100; 0 4000 900; 0 0 1]\n"
                                      "doffs=100\nbaseline=170\nwidth=8\nheight=5\nndisp=290\nisint=0\nvmin=10\n"
                                      "vmax=60\n")
    pair = datasets.read_stereo_folder(folder)
    expected = np.where(np.isinf(truth), np.nan, truth)
    assert np.array_equal(pair.disparity, expected, equal_nan=True)  # row 0 on top, inf unknown
    assert pair.scale == 1.0 and pair.published_disparities == 290 and pair.masks == {}
    assert pair.left.shape == (5, 8, 3)
    # MiddEval3's mask: 255 non-occluded, 128 occluded, 0 without ground truth.
    levels = np.full((5, 8), 255, np.uint8)
    levels[1, :3] = 128
    levels[0, 0] = levels[4, 7] = 0
    assert cv2.imwrite(str(folder / "mask0nocc.png"), levels)
    masked = datasets.read_stereo_folder(folder)
    assert np.array_equal(masked.masks["nonocc"], levels == 255)
    assert np.array_equal(masked.masks["all"], levels > 0)
    # The same map through write_pfm reads back the same.
    datasets.write_pfm(folder / truth_name, expected)
    assert np.array_equal(datasets.read_stereo_folder(folder).disparity, expected, equal_nan=True)


def test_a_folder_of_no_layout_is_refused_by_name(tmp_path):
    folder = tmp_path / "holiday_photos"
    _write_pair(folder, ("left.png", "right.png"), (4, 4), np.random.default_rng(1))
    with pytest.raises(InputValueError, match="holiday_photos holds no stereo pair.*imL.png.*calib.txt.*view1.png"):
        datasets.read_stereo_folder(folder)
    assert datasets.find_stereo_folders(tmp_path) == []
    with pytest.raises(FileNotFoundError, match="nowhere"):
        datasets.read_stereo_folder(tmp_path / "nowhere")
    with pytest.raises(InputTypeError, match="folder must be a str"):
        datasets.read_stereo_folder(3)
    # The 2001 / 2003 layout's scale is known only for their published sizes.
    _write_pair(tmp_path / "small", ("im2.png", "im6.png", "disp2.png"), (10, 20), np.random.default_rng(2))
    with pytest.raises(InputValueError, match="20 x 10, not a size"):
        datasets.read_stereo_folder(tmp_path / "small")


def test_harness_arguments_are_refused_by_name(datasets_root):
    from vmcl.pipeline import Config, StereoConfig

    pair = datasets.load_stereo("map", datasets_root)
    with pytest.raises(InputTypeError, match="pair must be a vmcl.datasets.StereoPair"):
        se.evaluate_pair("map", se.opencv_baselines(pair))
    with pytest.raises(InputValueError, match="methods must be a non-empty sequence"):
        se.evaluate_pair(pair, [])
    with pytest.raises(InputValueError, match="num_disparities must be a multiple of 16"):
        se.stereo_bm(40)
    with pytest.raises(InputValueError, match="mode must be one of"):
        se.stereo_sgbm(64, "HH")
    with pytest.raises(InputValueError, match="config must enable stereo"):
        se.vmcl_method(Config(stereo=StereoConfig(enabled=False)))
    with pytest.raises(InputTypeError, match="config must be a vmcl.pipeline.Config"):
        se.vmcl_method({"stereo": {}})
    with pytest.raises(InputValueError, match="image must be uint8"):
        se.grey(pair.left.astype(np.uint16))


# --------------------------------------------------------------------------------------------- the command


def test_eval_stereo_reads_any_folder(datasets_root, tmp_path, capsys):
    shutil.copytree(datasets_root / V2_TEDDY, tmp_path / "my_pair")
    assert main(["eval", "stereo", "--data", str(tmp_path), "-q"]) == 0
    printed = capsys.readouterr().out
    rows = {tuple(c.strip() for c in line.strip("|").split("|")) for line in printed.splitlines()
            if line.startswith("| my_pair |")}
    methods = {row[1] for row in rows if len(row) == 9}
    assert methods == {"vmcl (dense, MRF)", "OpenCV StereoBM", "OpenCV StereoSGBM MODE_SGBM",
                       "OpenCV StereoSGBM 3WAY"}
    pair = datasets.load_stereo("teddy", datasets_root)
    left, right = (cv2.cvtColor(image, cv2.COLOR_RGB2GRAY) for image in (pair.left, pair.right))
    sgbm = _opencv(cv2.StereoSGBM_create(minDisparity=0, numDisparities=64, blockSize=5, P1=200, P2=800,
                                         uniquenessRatio=10, mode=cv2.STEREO_SGBM_MODE_SGBM_3WAY).compute(left, right))
    bad1 = _oracle_bad(sgbm, pair.disparity, pair.masks["nonocc"], 1.0)
    row = next(r for r in rows if r[1:3] == ("OpenCV StereoSGBM 3WAY", "nonocc") and len(r) == 9)
    assert row[4] == f"{100 * bad1:.1f}"
    assert "numDisparities 64: the data set publishes 60 disparities" in printed
    # The scene folder itself is read too.
    assert main(["eval", "stereo", "--data", str(tmp_path / "my_pair"), "-q"]) == 0
    assert "| my_pair | vmcl (dense, MRF) | nonocc |" in capsys.readouterr().out


def test_eval_stereo_without_a_scene_is_exit_2(tmp_path, capsys):
    (tmp_path / "notes.txt").write_text("no pair here")
    assert main(["eval", "stereo", "--data", str(tmp_path), "-q"]) == 2
    assert "no stereo scene in a Middlebury layout" in capsys.readouterr().err


# -- the depth machine on Middlebury v2 -----------------------------------------------------------------

BARS = {"tsukuba": 0.05, "venus": 0.025, "teddy": 0.10}  # the stereo issue's nonocc bad-1 bars


@pytest.fixture(scope="module")
def v2_evaluations(datasets_root):
    from vmcl.datasets import load_stereo
    from vmcl.stereo_evaluation import evaluate_pair, opencv_baselines, vmcl_method

    method = vmcl_method()
    found = {}
    for name in BARS:
        pair = load_stereo(name, datasets_root)
        found[name] = evaluate_pair(pair, [method, *[m for m in opencv_baselines(pair) if "3WAY" in m.name]],
                                    warm=False)
    return found


def _bad1(evaluation, method_prefix, region):
    return next(s.bad[1.0] for s in evaluation.scores if s.method.startswith(method_prefix) and s.region == region)


@pytest.mark.parametrize("name", list(BARS))
def test_depth_machine_beats_sgbm_3way_on_middlebury(name, v2_evaluations):
    """No range given, the restored disparity has fewer bad pixels than StereoSGBM 3WAY configured as
    OpenCV documents it, over the nonocc and the all masks (measured nonocc: 2.5 / 1.9 / 10.5% against
    4.4 / 5.9 / 16.6%; benchmarks/results/stereo.md)."""
    evaluation = v2_evaluations[name]
    for region in ("nonocc", "all"):
        assert _bad1(evaluation, "vmcl", region) < _bad1(evaluation, "OpenCV StereoSGBM 3WAY", region), region


@pytest.mark.xfail(strict=True, reason="measured nonocc bad-1 2.5 / 1.9 / 10.5% (tsukuba / venus / teddy) against "
                   "bars of 5 / 2.5 / 10%: tsukuba and venus meet theirs, teddy does not (benchmarks/results/"
                   "stereo.md, with the matcher's directions and prices that stage 6 of benchmarks/stereo_fit.py "
                   "chose on the training pairs)")
def test_depth_machine_meets_the_issue_s_bars(v2_evaluations):
    assert all(_bad1(v2_evaluations[name], "vmcl", "nonocc") <= bar for name, bar in BARS.items())


def _matched_ratio(evaluation, region="nonocc"):
    """vmcl's bad-1 over SGBM 3WAY's on the pixels SGBM 3WAY gives a value."""
    row = next(c for c in evaluation.matched if c.region == region and "3WAY" in c.baseline)
    return row.method_bad / row.baseline_bad


@pytest.mark.parametrize("name", [
    "tsukuba", "teddy",
    pytest.param("venus", marks=pytest.mark.xfail(strict=True, reason=(
        "measured 1.66 times SGBM 3WAY's bad-1 on the pixels it matched, the bar 1.5 "
        "(benchmarks/results/stereo.md, the matched-pixels table's last column)")))])
def test_depth_machine_within_1_5_times_sgbm_on_the_pixels_sgbm_matched(name, v2_evaluations):
    """The issue's bar on the pixels SGBM 3WAY matched (measured nonocc, benchmarks/results/stereo.md:
    tsukuba 0.67, teddy 1.33 times)."""
    assert _matched_ratio(v2_evaluations[name]) <= 1.5


def test_a_written_stereo_folder_reads_back(tmp_path):
    """write_stereo_folder's 2014 layout: read_stereo_folder gives the images (rounded to 8 bits), the
    disparity (NaN where unknown) and ndisp back; a folder holding files is refused, nothing written."""
    from vmcl import scenes

    s = scenes.render(scenes.preset("blocks", shape=(64, 64)), seed=0, noise=0.01)
    truth = s.disparity.copy()
    truth[:4] = np.nan
    folder = datasets.write_stereo_folder(tmp_path / "new" / "pair", s.left, s.right, truth)
    pair = datasets.read_stereo_folder(folder)
    np.testing.assert_array_equal(pair.left, np.round(s.left * 255).astype(np.uint8))
    np.testing.assert_array_equal(pair.right, np.round(s.right * 255).astype(np.uint8))
    np.testing.assert_array_equal(pair.disparity, truth.astype(np.float32))
    assert pair.published_disparities == int(np.ceil(np.nanmax(truth))) + 1
    (tmp_path / "busy").mkdir()
    (tmp_path / "busy" / "mine.txt").write_text("a user's file")
    with pytest.raises(InputValueError, match="folder must be new or empty"):
        datasets.write_stereo_folder(tmp_path / "busy", s.left, s.right, truth)
    assert sorted(p.name for p in (tmp_path / "busy").iterdir()) == ["mine.txt"]
    with pytest.raises(InputValueError, match="left must be uint8 or floats in"):
        datasets.write_stereo_folder(tmp_path / "other", s.left * 2, s.right, truth)


def test_eval_stereo_scores_the_scenes_it_can_and_names_each_it_leaves_out(tmp_path, capsys):
    """A scene without its ground truth, one whose ground truth has another size and a 16-bit one beside a
    good one: the good and the 16-bit scenes are scored (OpenCV's matchers given the 16-bit pair at 8 bits,
    and saying so), each other folder is named on stderr with what is wrong: the one without ground truth in
    a note (a benchmark's test scenes have none), the one that fails to read as a failure (status 2)."""
    from vmcl import scenes

    s = scenes.render(scenes.preset("blocks", shape=(96, 128)), seed=0, noise=0.01)
    datasets.write_stereo_folder(tmp_path / "good", s.left, s.right, s.disparity)
    folder = datasets.write_stereo_folder(tmp_path / "no truth", s.left, s.right, s.disparity)
    (folder / "disp0.pfm").unlink()
    folder = datasets.write_stereo_folder(tmp_path / "other size", s.left, s.right, s.disparity)
    datasets.write_pfm(folder / "disp0.pfm", s.disparity[:-8])
    deep = datasets.write_stereo_folder(tmp_path / "deep" / "sixteen", s.left, s.right, s.disparity)
    for name in ("im0.png", "im1.png"):  # the same pair at 16 bits
        cv2.imwrite(str(deep / name), cv2.imread(str(deep / name)).astype(np.uint16) * 257)
    assert main(["eval", "stereo", "--data", str(tmp_path), "-q"]) == 2
    captured = capsys.readouterr()
    assert "Stereo on 2 Middlebury scene(s)" in captured.out
    assert "| good | vmcl (dense, MRF) |" in captured.out and "| deep/sixteen | OpenCV StereoSGBM 3WAY |" in captured.out
    assert "the 16-bit left and right views are given to them at 8 bits" in captured.out
    err = captured.err.splitlines()
    assert any(line.startswith(f"vmcl: note: left out {tmp_path / 'no truth'}: it holds the two views of the "
                               "Middlebury 2014/2021 layout, but not disp0.pfm or disp0GT.pfm") for line in err), err
    assert any(line.startswith(f"vmcl: left out {tmp_path / 'other size'}:") and "size" in line for line in err), err
    assert len(err) == 2, err


def test_the_baselines_take_each_view_of_a_mixed_pair_at_8_bits_by_its_own_type(tmp_path):
    # A 16-bit left view beside an 8-bit right one: both were divided by 257, so the right view went black
    # and OpenCV's figures were wrong without a word.
    from vmcl import scenes

    s = scenes.render(scenes.preset("blocks", shape=(96, 128)), seed=0, noise=0.01)
    folder = datasets.write_stereo_folder(tmp_path / "mixed", s.left, s.right, s.disparity)
    pair = datasets.read_stereo_folder(folder)
    wide = datasets.StereoPair(**{**vars(pair), "left": pair.left.astype(np.uint16) * 257})
    for method, same in zip(se.opencv_baselines(wide), se.opencv_baselines(pair)):
        assert "the 16-bit left view is given to them at 8 bits" in method.note
        np.testing.assert_array_equal(method.compute(wide.left, wide.right), same.compute(pair.left, pair.right))


def test_eval_stereo_notes_scenes_without_ground_truth_and_succeeds(tmp_path, capsys):
    """A benchmark's own test scenes come without ground truth (MiddEval3's testF): named in a note, and the
    scored scenes make the run a success."""
    from vmcl import scenes

    s = scenes.render(scenes.preset("blocks", shape=(96, 128)), seed=0, noise=0.01)
    datasets.write_stereo_folder(tmp_path / "trainingQ" / "scene", s.left, s.right, s.disparity)
    test_scene = datasets.write_stereo_folder(tmp_path / "testQ" / "scene", s.left, s.right, s.disparity)
    (test_scene / "disp0.pfm").unlink()
    assert main(["eval", "stereo", "--data", str(tmp_path), "-q"]) == 0
    captured = capsys.readouterr()
    assert "Stereo on 1 Middlebury scene(s)" in captured.out
    assert captured.err.startswith(f"vmcl: note: left out {test_scene}: it holds the two views"), captured.err


@pytest.mark.parametrize("shape, match", [((40, 70), "StereoBM's numDisparities plus its block less one"),
                                          ((15, 100), "larger than the matcher's block")])
def test_stereobm_is_refused_where_opencv_returns_memory_it_never_wrote(shape, match):
    # Between numDisparities and numDisparities + block - 2 columns StereoBM returned unwritten memory
    # (disparities near 2000 px, different each call), which the harness scored; a side equal to the block
    # raised a bare cv2.error.
    rng = np.random.default_rng(0)
    left = (rng.random(shape) * 255).astype(np.uint8)
    with pytest.raises(InputValueError, match=match):
        se.opencv_disparity(se.stereo_bm(64), left, np.roll(left, -3, axis=1))
    wide = (rng.random((40, 200)) * 255).astype(np.uint8)
    found = se.opencv_disparity(se.stereo_bm(64), wide, np.roll(wide, -3, axis=1))
    assert np.nanmax(found) < 64


# --------------------------------------------------------------------------------------------- what cannot be scored


def _blocks(shape=(96, 128)):
    from vmcl import scenes

    return scenes.render(scenes.preset("blocks", shape=shape), seed=0, noise=0.01)


def _v2_folder(folder, left, right, disparity, *, max_disparity=20, disc=None):
    """A Middlebury v2 evaluation folder: imL/imR.png, groundtruth.png at scale 8, info.txt, and the masks
    nonocc.png and all.png (every pixel) and disc.png (``disc``, default every pixel)."""
    folder.mkdir(parents=True)
    for name, image in (("imL.png", left), ("imR.png", right)):
        cv2.imwrite(str(folder / name), np.round(image[..., ::-1] * 255).astype(np.uint8))
    cv2.imwrite(str(folder / "groundtruth.png"), np.round(disparity * 8).astype(np.uint8))
    (folder / "info.txt").write_text(f"8\n{max_disparity}\n")
    every = np.full(disparity.shape, 255, np.uint8)
    for name, mask in (("nonocc", every), ("all", every), ("disc", every if disc is None else disc)):
        cv2.imwrite(str(folder / f"{name}.png"), mask)
    return folder


def test_a_region_whose_mask_marks_no_pixel_is_not_scored_and_the_others_are(tmp_path):
    # An empty disc mask (a scene without depth jumps, or a crop) left the whole pair out, its nonocc and
    # all regions unscored, with a message naming the metric's internal argument "ground_truth".
    s = _blocks()
    truth = s.disparity.astype(np.float32)
    every, none = np.ones(truth.shape, bool), np.zeros(truth.shape, bool)
    pair = datasets.StereoPair("flat", s.left, s.right, truth, {"nonocc": every, "all": every, "disc": none},
                               (float(truth.min()), float(truth.max())), 1.0, tmp_path / "flat")
    off = truth + np.where(np.arange(truth.size).reshape(truth.shape) % 3 == 0, 1.5, 0.25).astype(np.float32)
    evaluation = se.evaluate_pair(pair, [se.StereoMethod("off", lambda left, right: off)], warm=False)
    assert [s.region for s in evaluation.scores] == ["nonocc", "all"]
    for scores in evaluation.scores:
        assert scores.bad == {t: pytest.approx(_oracle_bad(off, truth, every, t), abs=1e-12) for t in se.THRESHOLDS}
    assert evaluation.not_scored == {"disc": f"the disc mask of {tmp_path / 'flat'} marks no pixel"}
    assert f"- flat: region disc not scored: the disc mask of {tmp_path / 'flat'} marks no pixel" in \
        se.markdown_tables([evaluation])
    nothing = datasets.StereoPair(**{**vars(pair), "masks": {"nonocc": none, "disc": none}})
    with pytest.raises(InputValueError, match=r"pair flat: no pixel to evaluate: every mask of .* \(nonocc, disc\)"):
        se.evaluate_pair(nothing, [se.StereoMethod("off", lambda left, right: off)], warm=False)


def test_eval_stereo_keeps_a_scene_whose_disc_mask_is_empty(tmp_path, capsys):
    s = _blocks()
    folder = _v2_folder(tmp_path / "flatdisc", s.left, s.right, s.disparity, disc=np.zeros(s.disparity.shape, np.uint8))
    assert main(["eval", "stereo", "--data", str(folder), "-q"]) == 0
    captured = capsys.readouterr()
    regions = {line.split("|")[3].strip() for line in captured.out.splitlines() if line.startswith("| flatdisc | vmcl")}
    assert regions == {"nonocc", "all"}
    assert f"- flatdisc: region disc not scored: the disc mask of {folder} marks no pixel" in captured.out
    assert captured.err == ""


def test_the_evaluation_keeps_what_vmcl_said_about_each_pair(tmp_path, capsys):
    # Swapped views: vmcl's run says so ("is the left image the left camera's?"), but the evaluation kept
    # only its disparity, and its notes only the configuration.
    from vmcl.pipeline import Config, VisionMachine

    s = _blocks()
    said = VisionMachine(Config.from_dict(se.DEPTH_ONLY)).run(s.right, s.left).notes
    assert any("is the left image the left camera's?" in note for note in said)
    truth = s.disparity.astype(np.float32)
    pair = datasets.StereoPair("swapped", s.right, s.left, truth, {}, (float(truth.min()), float(truth.max())), 1.0,
                               tmp_path)
    evaluation = se.evaluate_pair(pair, [se.vmcl_method()], warm=False)
    assert evaluation.notes == ["vmcl: the disparity range found from the images", *(f"vmcl: {n}" for n in said)]
    folder = datasets.write_stereo_folder(tmp_path / "swapped", s.right, s.left, s.disparity)
    assert main(["eval", "stereo", "--data", str(folder), "-q"]) == 0
    assert f"- swapped: vmcl: {said[0]}" in capsys.readouterr().out.splitlines()


def test_vmcl_without_a_disparity_has_no_value_anywhere_and_says_why(tmp_path):
    # Images of one brightness: the run gives no disparity (None), which the evaluation turned into a 0-d
    # NaN that the metric refused ("disparity must have 2 dimensions"), leaving the whole pair out.
    flat = np.full((32, 48), 128, np.uint8)
    truth = np.full(flat.shape, 2.0, np.float32)
    pair = datasets.StereoPair("flat", flat, flat, truth, {}, (2.0, 2.0), 1.0, tmp_path)
    evaluation = se.evaluate_pair(pair, [se.vmcl_method()], warm=False)
    (scores,) = evaluation.scores
    assert (scores.region, scores.density, scores.bad[1.0], scores.pixels) == ("known", 0.0, 1.0, flat.size)
    assert np.isnan(evaluation.disparities["vmcl (dense, MRF)"]).all()
    assert any("one brightness everywhere" in note for note in evaluation.notes), evaluation.notes


def test_a_baseline_that_cannot_run_on_a_small_pair_is_named_and_vmcl_still_scored(tmp_path):
    # A 20 x 30 crop: too narrow for StereoSGBM's 32 disparities, which left the whole pair out, vmcl too.
    s = _blocks()
    left, right, truth = s.left[40:60, 40:70], s.right[40:60, 40:70], s.disparity[40:60, 40:70]
    pair = datasets.read_stereo_folder(datasets.write_stereo_folder(tmp_path / "crop", left, right, truth, ndisp=20))
    ours = se.vmcl_method()
    evaluation = se.evaluate_pair(pair, [ours, *se.opencv_baselines(pair)], warm=False)
    sgbm = ["OpenCV StereoSGBM MODE_SGBM", "OpenCV StereoSGBM 3WAY"]
    assert list(evaluation.not_run) == sgbm
    assert all("wider than StereoSGBM's numDisparities plus half its block (32 + 2 pixels), got 30" in why
               for why in evaluation.not_run.values())
    expected = se.evaluate_pair(pair, [ours], warm=False).scores
    assert [(s.method, s.region, s.bad, s.density) for s in evaluation.scores if s.method == ours.name] == \
           [(s.method, s.region, s.bad, s.density) for s in expected]
    assert {s.method for s in evaluation.scores} == {ours.name, "OpenCV StereoBM"}
    assert {c.baseline for c in evaluation.matched} == {"OpenCV StereoBM"}
    lines = se.markdown_tables([evaluation])
    assert f"- crop: {', '.join(sgbm)}: not run on this pair: {evaluation.not_run[sgbm[0]]}" in lines
    assert f"| crop | {sgbm[1]} | not run (see the notes) | - | - | - | - | - | - |" in lines


def test_eval_stereo_scores_vmcl_where_info_txt_publishes_more_disparities_than_opencv_searches(tmp_path, capsys):
    s = _blocks()
    folder = _v2_folder(tmp_path / "huge", s.left, s.right, s.disparity, max_disparity=100000)
    assert main(["eval", "stereo", "--data", str(folder), "-q"]) == 0
    captured = capsys.readouterr()
    assert "| huge | vmcl (dense, MRF) | nonocc |" in captured.out
    assert ("- huge: OpenCV StereoBM, OpenCV StereoSGBM MODE_SGBM, OpenCV StereoSGBM 3WAY: not run on this pair: "
            f"numDisparities 100016: the data set publishes 100001 disparities (in {folder / 'info.txt'}), more than "
            "the 2048 OpenCV's matchers can search") in captured.out.splitlines()
    assert captured.err == ""
