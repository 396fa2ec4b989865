"""vmcl.datasets: format round trips, and the documented values of the shared data sets."""

import struct
import zlib

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from vmcl import datasets
from vmcl.errors import InputError

# --------------------------------------------------------------------------------------------- formats


def test_flo_round_trip_is_bit_exact(tmp_path):
    rng = np.random.default_rng(3)
    flow = rng.normal(scale=20, size=(7, 5, 2)).astype(np.float32)
    flow[2, 3] = np.nan
    path = tmp_path / "a.flo"
    datasets.write_flo(path, flow)
    data = path.read_bytes()
    assert struct.unpack("<fii", data[:12]) == (202021.25, 5, 7)
    # u, v interleaved row by row: the second float of the payload is v at (0, 0).
    assert struct.unpack("<ff", data[12:20]) == (flow[0, 0, 0], flow[0, 0, 1])
    back = datasets.read_flo(path)
    assert back.dtype == np.float32
    assert np.array_equal(back, flow, equal_nan=True)
    assert np.isnan(back[2, 3]).all() and np.isfinite(np.delete(back.reshape(-1, 2), 13, axis=0)).all()


@settings(max_examples=30, deadline=None)
@given(arrays(np.float32, st.tuples(st.integers(1, 9), st.integers(1, 9), st.just(2)),
              elements=st.floats(-1e6, 1e6, width=32) | st.just(np.nan)))
def test_flo_round_trip_any_shape(tmp_path_factory, flow):
    path = tmp_path_factory.mktemp("flo") / "f.flo"
    datasets.write_flo(path, flow)
    back = datasets.read_flo(path)
    # A vector with one NaN component is unknown as a whole.
    expected = flow.copy()
    expected[np.isnan(flow).any(axis=-1)] = np.nan
    assert back.shape == flow.shape and np.array_equal(back, expected, equal_nan=True)


def test_flo_real_file_round_trips_byte_for_byte(datasets_root, tmp_path):
    source = datasets_root / "middlebury_flow" / "RubberWhale" / "flow10.flo"
    copy = tmp_path / "copy.flo"
    datasets.write_flo(copy, datasets.read_flo(source, raw=True))
    assert copy.read_bytes() == source.read_bytes()


def test_flo_bad_input(tmp_path):
    with pytest.raises(FileNotFoundError, match="nope.flo"):
        datasets.read_flo(tmp_path / "nope.flo")
    bad = tmp_path / "bad.flo"
    bad.write_bytes(struct.pack("<fii", 1.0, 2, 2) + bytes(32))
    with pytest.raises(ValueError, match="bad tag"):
        datasets.read_flo(bad)
    bad.write_bytes(struct.pack("<fii", 202021.25, 3, 2) + bytes(32))
    with pytest.raises(ValueError, match="60 bytes, file has 44"):
        datasets.read_flo(bad)
    with pytest.raises(ValueError, match=r"\(H, W, 2\)"):
        datasets.write_flo(tmp_path / "x.flo", np.zeros((2, 2)))


def test_pfm_hand_made_file(tmp_path):
    # 3 wide, 2 high, little endian; rows stored bottom first; inf means unknown.
    path = tmp_path / "d.pfm"
    path.write_bytes(b"Pf\n3 2\n-1.0\n" + struct.pack("<6f", 4, 5, float("inf"), 1, 2, 3))
    disparity = datasets.read_disparity(path)
    assert np.array_equal(disparity, np.array([[1, 2, 3], [4, 5, np.nan]], np.float32), equal_nan=True)
    big_endian = tmp_path / "b.pfm"
    big_endian.write_bytes(b"Pf\n1 1\n1.0\n" + struct.pack(">f", 2.5))
    assert datasets.read_pfm(big_endian)[0, 0] == 2.5
    copy = tmp_path / "c.pfm"
    datasets.write_pfm(copy, disparity)
    assert copy.read_bytes() == path.read_bytes()
    with pytest.raises(ValueError, match="scale"):
        datasets.read_disparity(path, scale=8)
    # Malformed files are refused by name (a raw NumPy error, an empty array, or garbage from a NaN scale).
    for name, content, match in (("odd.pfm", b"Pf\n1 1\n-1.0\n" + bytes(5), "expected 1 floats"),
                                 ("negative.pfm", b"Pf\n-3 -2\n-1.0\n" + bytes(24), "size -3 x -2"),
                                 ("empty.pfm", b"Pf\n0 5\n-1.0\n", "size 0 x 5"),
                                 ("nan.pfm", b"Pf\n1 1\nnan\n" + bytes(4), "scale nan")):
        (tmp_path / name).write_bytes(content)
        with pytest.raises(InputError, match=match):
            datasets.read_pfm(tmp_path / name)


def test_pgm_disparity_scale_and_unknown(tmp_path):
    path = tmp_path / "d.pgm"
    path.write_bytes(b"P5\n2 2\n255\n" + bytes([0, 16, 40, 255]))
    disparity = datasets.read_disparity(path, scale=16)
    assert np.array_equal(disparity, np.array([[np.nan, 1.0], [2.5, 255 / 16]], np.float32), equal_nan=True)
    with pytest.raises(ValueError, match="scale must be a positive number"):
        datasets.read_disparity(path)
    with pytest.raises(FileNotFoundError, match="missing.pgm"):
        datasets.read_disparity(tmp_path / "missing.pgm", scale=8)
    not_image = tmp_path / "x.png"
    not_image.write_bytes(b"not an image")
    with pytest.raises(ValueError, match="cannot decode"):
        datasets.read_image(not_image)


def test_images_over_opencvs_limits_or_that_opencv_fails_on_are_refused(tmp_path, monkeypatch):
    # A whole, tiny PNG whose header declares 100000 x 100000 pixels: OpenCV asserts rather than decode it.
    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))

    huge = tmp_path / "huge.png"
    huge.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 100000, 100000, 8, 2, 0, 0, 0))
                     + chunk(b"IDAT", zlib.compress(bytes(10))) + chunk(b"IEND", b""))
    with pytest.raises(InputError, match="huge.png is larger than OpenCV decodes.*CV_IO_MAX_IMAGE_PIXELS"):
        datasets.read_image(huge)
    # Any other failure of OpenCV's decoders is the file's too.
    fine = tmp_path / "fine.png"
    assert cv2.imwrite(str(fine), np.zeros((2, 3), np.uint8))

    def fails(*args):
        raise cv2.error("OpenCV: error: (-2:Unspecified error)\n> in function 'imdecode_'")

    monkeypatch.setattr(cv2, "imdecode", fails)
    with pytest.raises(InputError, match=r"cannot decode an image from .*fine.png \(OpenCV: error: .* in function"):
        datasets.read_image(fine)

# --------------------------------------------------------------------------------------------- stereo


def test_tsukuba_documented_values(datasets_root):
    pair = datasets.load_stereo("tsukuba", datasets_root)
    assert pair.left.shape == pair.right.shape == (288, 384, 3)
    assert pair.left.dtype == np.uint8
    assert pair.disparity.shape == (288, 384)
    assert np.count_nonzero(np.isnan(pair.disparity)) == 22_896
    assert pair.disparity_range == (5.0, 14.0)
    counts = {name: int(mask.sum()) for name, mask in pair.masks.items()}
    assert counts == {"nonocc": 85_438, "all": 87_696, "disc": 15_790}
    # The 'all' mask excludes exactly the unknown pixels.
    assert np.array_equal(pair.masks["all"], np.isfinite(pair.disparity))
    # The 2001 copy of the ground truth says the same thing.
    pgm = datasets.read_disparity(
        datasets_root / "middlebury_stereo_2001/tsukuba/truedisp.row3.col3.pgm", scale=16
    )
    assert np.array_equal(pgm, pair.disparity, equal_nan=True)


@pytest.mark.parametrize(
    ("name", "shape", "unknown", "masks", "low", "high"),
    [
        ("venus", (383, 434), 0, (147_513, 150_282, 10_540), 3.0, 19.75),
        ("teddy", (375, 450), 3_406, (147_651, 165_344, 40_517), 12.5, 52.75),
    ],
)
def test_v2_scenes_documented_values(datasets_root, name, shape, unknown, masks, low, high):
    pair = datasets.load_stereo(name, datasets_root)
    assert pair.disparity.shape == shape and pair.left.shape == (*shape, 3)
    assert np.count_nonzero(np.isnan(pair.disparity)) == unknown
    assert tuple(int(pair.masks[m].sum()) for m in ("nonocc", "all", "disc")) == masks
    assert pair.disparity_range == (low, high)


def test_2001_scenes_without_masks(datasets_root):
    sawtooth = datasets.load_stereo("Sawtooth", datasets_root)
    assert sawtooth.disparity.shape == (380, 434) and sawtooth.masks == {}
    assert sawtooth.disparity_range == (3.875, 17.875)
    scene_map = datasets.load_stereo("map", datasets_root)
    assert scene_map.left.shape == (216, 284) and scene_map.left.ndim == 2
    assert scene_map.disparity_range == (4.375, 28.125)
    with pytest.raises(ValueError, match="unknown stereo scene 'cones'.*tsukuba"):
        datasets.load_stereo("cones", datasets_root)


def test_stereo_convention_by_warping(datasets_root):
    """I_left(x, y) = I_right(x - d, y) on the venus ground truth."""
    pair = datasets.load_stereo("venus", datasets_root)
    left = pair.left.astype(np.float64).mean(axis=-1)
    right = pair.right.astype(np.float64).mean(axis=-1)
    ys, xs = np.nonzero(pair.masks["nonocc"])
    source = np.rint(xs - pair.disparity[ys, xs]).astype(int)
    keep = (source >= 0) & (source < left.shape[1])
    right_sign = np.abs(left[ys, xs] - right[ys, np.clip(source, 0, left.shape[1] - 1)])[keep].mean()
    wrong = np.rint(xs + pair.disparity[ys, xs]).astype(int)
    keep_w = wrong < left.shape[1]
    wrong_sign = np.abs(left[ys, xs] - right[ys, np.minimum(wrong, left.shape[1] - 1)])[keep_w].mean()
    assert right_sign < 6 < 3 * right_sign < wrong_sign


# --------------------------------------------------------------------------------------------- flow


@pytest.mark.parametrize(
    ("name", "shape", "unknown"),
    [
        ("Dimetrodon", (388, 584), 10_772),
        ("Grove2", (480, 640), 0),
        ("Hydrangea", (388, 584), 14_880),
        ("RubberWhale", (388, 584), 3_622),
        ("Venus", (380, 420), 0),
    ],
)
def test_middlebury_flow_documented_values(datasets_root, name, shape, unknown):
    pair = datasets.load_flow(name, datasets_root)
    assert pair.flow.shape == (*shape, 2) and pair.flow.dtype == np.float32
    assert pair.frame0.shape == pair.frame1.shape == shape
    assert np.count_nonzero(~pair.mask) == unknown
    assert np.array_equal(pair.mask, np.isfinite(pair.flow).all(axis=-1))


def test_flow_ranges_and_colour(datasets_root):
    venus = datasets.load_flow("venus", datasets_root)
    assert np.all(venus.flow[..., 1] == 0)
    assert float(venus.flow[..., 0].min()) == pytest.approx(-9.38, abs=0.01)
    colour = datasets.load_flow("RubberWhale", datasets_root, colour=True)
    assert colour.frame0.shape == (388, 584, 3)
    with pytest.raises(ValueError, match="only for RubberWhale"):
        datasets.load_flow("Grove2", datasets_root, colour=True)


def test_yosemite_sky_excluded(datasets_root):
    pair = datasets.load_flow("yosemite", datasets_root)
    assert pair.flow.shape == (252, 316, 2)
    assert np.isfinite(pair.flow).all()
    assert np.count_nonzero(~pair.mask) == 20_721
    assert float(np.abs(pair.flow).max()) == pytest.approx(3.887, abs=0.001)


def test_flow_convention_by_warping(datasets_root):
    """frame0(x, y) = frame1(x + u, y + v) on RubberWhale."""
    pair = datasets.load_flow("RubberWhale", datasets_root)
    f0, f1 = pair.frame0.astype(np.float64), pair.frame1.astype(np.float64)
    ys, xs = np.nonzero(pair.mask)
    h, w = f0.shape

    def error(sign):
        xt = np.clip(np.rint(xs + sign * pair.flow[ys, xs, 0]).astype(int), 0, w - 1)
        yt = np.clip(np.rint(ys + sign * pair.flow[ys, xs, 1]).astype(int), 0, h - 1)
        return np.abs(f0[ys, xs] - f1[yt, xt]).mean()

    assert error(+1) < 2.0 < 2 * error(+1) < error(-1)


# --------------------------------------------------------------------------------------------- BSDS


def test_bsds_test_split(datasets_root):
    bsds = datasets.load_bsds(datasets_root)
    assert [image.name for image in bsds.images] == [
        "100007", "100039", "100099", "10081", "101027", "101084", "102062", "103006", "103029", "103078",
    ]
    for image in bsds.images:
        assert image.image.shape in ((321, 481, 3), (481, 321, 3))
        k = image.boundaries.shape[0]
        assert 5 <= k <= 8
        assert image.boundaries.shape == (k, *image.image.shape[:2]) == image.segmentations.shape
        assert image.boundaries.dtype == bool and image.segmentations.min() >= 1
    assert bsds.expected == {}


def test_bsds_golden_split(datasets_root):
    golden = datasets.load_bsds(datasets_root, split="golden")
    assert [image.name for image in golden.images] == ["2018", "3063", "5096", "6046", "8068"]
    assert golden.expected["ods_f"] == 0.704628 and golden.expected["ois_f"] == 0.708698
    assert all(0 <= image.edge_map.min() and image.edge_map.max() <= 1 for image in golden.images)
    with pytest.raises(ValueError, match="split"):
        datasets.load_bsds(datasets_root, split="validation")


def test_bsds_train_split_and_any_bsds_folder(datasets_root, tmp_path):
    train = datasets.load_bsds(datasets_root, split="train")
    assert len(train.images) == 200 and train.split == "train"
    assert not {image.name for image in train.images} & {image.name for image in datasets.load_bsds(datasets_root).images}
    # The distribution's layout: images/ and groundTruth/ side by side, here with a test split.
    source = datasets_root / "bsds500" / "test" / "100007"
    for kind, suffix in (("images", "jpg"), ("groundTruth", "mat")):
        (tmp_path / "data" / kind / "test").mkdir(parents=True)
        (tmp_path / "data" / kind / "test" / f"100007.{suffix}").write_bytes((source / f"100007.{suffix}").read_bytes())
    found = datasets.read_bsds_folder(tmp_path / "data")
    assert [image.name for image in found] == ["100007"]
    np.testing.assert_array_equal(found[0].boundaries, datasets.load_bsds(datasets_root).images[0].boundaries)
    (tmp_path / "data" / "groundTruth" / "test" / "100007.mat").unlink()
    with pytest.raises(ValueError, match="without their ground truth"):
        datasets.read_bsds_folder(tmp_path / "data")
    with pytest.raises(FileNotFoundError, match="no BSDS images"):
        datasets.read_bsds_folder(tmp_path / "data" / "images")
    with pytest.raises(FileNotFoundError, match="no such folder"):
        datasets.read_bsds_folder(tmp_path / "missing")


def test_missing_root_names_the_path(tmp_path):
    with pytest.raises(FileNotFoundError, match=str(tmp_path)):
        datasets.load_stereo("tsukuba", tmp_path)
    with pytest.raises(FileNotFoundError, match="bsds500"):
        datasets.load_bsds(tmp_path)


@pytest.mark.parametrize("call, error, match", [
    (lambda tmp: datasets.read_mask(3), TypeError, "path must be a str or an os.PathLike"),
    (lambda tmp: datasets.read_flo(None), TypeError, "path must be a str or an os.PathLike"),
    (lambda tmp: datasets.read_disparity(3, scale=8.0), TypeError, "path must be a str"),
    (lambda tmp: datasets.read_disparity(tmp / "d.png", scale="8"), TypeError, "scale .* must be a real number"),
    (lambda tmp: datasets.read_disparity(tmp / "d.png", scale=8.0, unknown=0.5), TypeError,
     "unknown must be an integer"),
    (lambda tmp: datasets.read_flo(tmp / "f.flo", raw="yes"), TypeError, "raw must be a bool"),
    (lambda tmp: datasets.write_pfm(tmp / "x.pfm", np.zeros((4, 4), complex)), TypeError, "image must hold real"),
    (lambda tmp: datasets.write_pfm(tmp / "x.pfm", [[0.0]]), TypeError, "image must be a NumPy array"),
    (lambda tmp: datasets.write_pfm(3, np.zeros((4, 4))), TypeError, "path must be a str"),
    (lambda tmp: datasets.write_flo(tmp / "x.flo", np.zeros((4, 4, 2), object)), TypeError, "flow must hold real"),
    (lambda tmp: datasets.load_stereo("cones", tmp), ValueError, "name must be one of"),
    (lambda tmp: datasets.load_stereo(["tsukuba"], tmp), TypeError, "name must be the name of a stereo scene"),
    (lambda tmp: datasets.load_stereo("tsukuba", 3), TypeError, "root must be a str"),
    (lambda tmp: datasets.load_flow("Venus", tmp, colour=None), TypeError, "colour must be a bool"),
    (lambda tmp: datasets.load_bsds(None), TypeError, "root must be a str"),
    (lambda tmp: datasets.load_bsds(tmp, split=None), TypeError, "split must be one of"),
])
def test_bad_arguments_are_refused_by_name(tmp_path, call, error, match):
    datasets.write_flo(tmp_path / "f.flo", np.zeros((2, 2, 2), np.float32))
    with pytest.raises(error, match=match) as raised:
        call(tmp_path)
    assert isinstance(raised.value, InputError)


@pytest.mark.parametrize("orientation", range(1, 9))
@pytest.mark.parametrize("grey", [False, True])
def test_a_jpeg_is_read_upright_as_its_exif_orientation_says(tmp_path, orientation, grey):
    # Read as stored, a portrait photograph (orientation 6) was matched along its columns. OpenCV's own
    # reader, which turns a picture upright unless told not to, is the oracle.
    from PIL import Image

    rng = np.random.default_rng(orientation)
    picture = cv2.GaussianBlur((rng.random((40, 64, 3)) * 255).astype(np.uint8), (0, 0), 2)
    picture[:8, :16] = 255  # a corner that tells every turn apart
    stored = Image.fromarray(picture[..., 0] if grey else picture)
    exif = Image.Exif()
    exif[0x0112] = orientation
    path = tmp_path / "photo.jpg"
    stored.save(path, exif=exif, quality=95)
    upright = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE if grey else cv2.IMREAD_COLOR)
    expected = upright if grey else upright[..., ::-1]
    read = datasets.read_image(path)
    assert read.shape == expected.shape and np.array_equal(read, expected)
    assert read.shape[:2] == ((40, 64) if orientation < 5 else (64, 40))


@pytest.mark.parametrize("maxval, dtype", [(1023, ">u2"), (100, "u1"), (255, "u1"), (65535, ">u2")])
def test_a_pictures_pnm_maximum_is_its_white(tmp_path, maxval, dtype):
    # A 10-bit PGM (maxval 1023) was read as 1/64 of full brightness, and one of maxval 100 at 39%, in silence;
    # maps of data (a disparity, a mask) are still read as stored.
    values = np.linspace(0, maxval, 24 * 32).round().astype(dtype).reshape(24, 32)
    path = tmp_path / "grey.pgm"
    path.write_bytes(f"P5\n# a comment\n32 24\n{maxval}\n".encode() + values.tobytes())
    stored = datasets.read_image(path)
    assert np.array_equal(stored, values.astype(stored.dtype))
    shown = datasets.read_image(path, picture=True)
    full = np.iinfo(stored.dtype).max
    assert shown.dtype == stored.dtype and int(shown.max()) == full
    np.testing.assert_allclose(shown.astype(float) / full, values.astype(float) / maxval, atol=0.5 / full)


# --------------------------------------------------------------------------------------------- edge cases


def test_write_flo_refuses_what_it_cannot_store_and_read_flo_a_folder(tmp_path):
    # float64 beyond float32's range was written as infinity (read back as unknown) with only NumPy's
    # RuntimeWarning; a bool array was written as 0 and 1 pixel flows; a folder was "no such file".
    path = tmp_path / "x.flo"
    huge = np.zeros((2, 3, 2))
    huge[1, 2, 0] = 1e300
    with pytest.raises(InputError, match=r"flow holds 1e\+300, beyond float32's range"):
        datasets.write_flo(path, huge)
    with pytest.raises(InputError, match="flow must hold numbers .* got dtype bool") as raised:
        datasets.write_flo(path, np.ones((2, 3, 2), bool))
    assert isinstance(raised.value, TypeError) and not path.exists()
    # The largest float32 is stored as it is; a vector with one NaN component is unknown as a whole.
    edge = np.zeros((1, 2, 2))
    edge[0, 0] = (np.finfo(np.float32).max, 1.0)
    edge[0, 1] = (np.nan, 2.0)
    datasets.write_flo(path, edge)
    stored = datasets.read_flo(path, raw=True)
    assert stored[0, 0].tolist() == [np.finfo(np.float32).max, 1.0] and stored[0, 1].tolist() == [1e10, 1e10]
    with pytest.raises(InputError, match=f"{tmp_path} is a folder, not a .flo file") as raised:
        datasets.read_flo(tmp_path)
    assert isinstance(raised.value, ValueError)
    with pytest.raises(InputError, match=f"{tmp_path} is a folder, not a PFM file"):
        datasets.read_pfm(tmp_path)


def test_read_disparity_refuses_maps_that_are_not_8_bit(tmp_path):
    # A 16-bit PNG was read as grey / scale: levels up to 65535 / 4, disparities far wider than the image.
    wide = tmp_path / "disp.png"
    assert cv2.imwrite(str(wide), np.full((4, 5), 40 * 256, np.uint16))
    with pytest.raises(InputError, match="disp.png is a 16-bit map; expected an 8-bit PGM/PNG"):
        datasets.read_disparity(wide, scale=4)
    pgm = tmp_path / "disp.pgm"
    pgm.write_bytes(b"P5\n2 1\n1000\n" + np.array([0, 400], ">u2").tobytes())
    with pytest.raises(InputError, match="disp.pgm is a 16-bit map"):
        datasets.read_disparity(pgm, scale=4)
    narrow = tmp_path / "narrow.png"
    assert cv2.imwrite(str(narrow), np.array([[0, 40]], np.uint8))
    assert np.array_equal(datasets.read_disparity(narrow, scale=4), np.array([[np.nan, 10]], np.float32),
                          equal_nan=True)


def test_write_stereo_folder_refuses_negative_disparities_by_name(tmp_path):
    # A negative disparity was refused as "ndisp must be >= 1, got -2", ndisp being the default the caller
    # never gave (the largest disparity plus one).
    image = np.zeros((4, 6), np.uint8)
    disparity = -np.arange(24, 48, dtype=np.float32).reshape(4, 6) / 8
    disparity[0, 0] = np.nan
    for ndisp in (None, 16):
        with pytest.raises(InputError, match=r"disparity must be >= 0 where known .* down to -5\.875"):
            datasets.write_stereo_folder(tmp_path / f"scene{ndisp}", image, image, disparity, ndisp=ndisp)
        assert not (tmp_path / f"scene{ndisp}").exists()
