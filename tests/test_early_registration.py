"""Memory-based registration: dots found, matched and interpolated into warp tables."""

import numpy as np
import pytest
from scipy import ndimage

from vmcl.early.registration import TableStore, WarpTable, find_dots, match_dots, warp

SHAPE = (240, 320)
CENTRE = np.array([160.0, 120.0])


def transform(points, *, shift=(6.0, 1.5), angle_deg=0.8, radial=2e-7):
    """Left-view positions to right-view positions: a shift (horizontal disparity of the calibration
    plane plus a vertical offset), a small rotation about the centre and lens-like radial distortion."""
    a = np.deg2rad(angle_deg)
    rotation = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    q = (points - CENTRE) @ rotation.T + CENTRE + np.asarray(shift)
    r2 = np.sum((q - CENTRE) ** 2, axis=-1, keepdims=True)
    return CENTRE + (q - CENTRE) * (1 + radial * r2)


def dot_image(centres, sigma=1.6):
    """Dark Gaussian dots on white, rendered analytically at sub-pixel centres."""
    ys, xs = np.indices(SHAPE, dtype=np.float64)
    image = np.ones(SHAPE)
    for x, y in centres:
        image -= 0.8 * np.exp(-((xs - x) ** 2 + (ys - y) ** 2) / (2 * sigma**2))
    return image.astype(np.float32)


def grid_dots(rng, spacing=24):
    ys, xs = np.mgrid[20:SHAPE[0] - 19:spacing, 20:SHAPE[1] - 19:spacing]
    return np.stack([xs.ravel(), ys.ravel()], axis=1) + rng.uniform(-2, 2, (xs.size, 2))


def inner_pixels(dots, margin=24):
    ys, xs = np.indices(SHAPE)
    inside = ((xs >= dots[:, 0].min() + margin) & (xs <= dots[:, 0].max() - margin)
              & (ys >= dots[:, 1].min() + margin) & (ys <= dots[:, 1].max() - margin))
    return np.stack([xs[inside], ys[inside]], axis=1).astype(np.float64), inside


def test_find_dots_locates_centroids(machine):
    rng = np.random.default_rng(0)
    truth = grid_dots(rng)
    found = find_dots(dot_image(truth), machine=machine)
    assert len(found) == len(truth)
    nearest = np.min(np.linalg.norm(found[:, None] - truth[None], axis=2), axis=1)
    assert nearest.max() < 0.1


def test_registration_removes_vertical_disparity(machine):
    rng = np.random.default_rng(1)
    left = grid_dots(rng)
    table = WarpTable.calibrate(dot_image(left), dot_image(transform(left)), max_shift=10, machine=machine)
    assert table.dots == len(left)
    points, inside = inner_pixels(left)
    error = table.source[inside] - transform(points)
    vertical = np.abs(error[:, 1])
    assert vertical.mean() < 0.1 and np.percentile(vertical, 95) < 0.25
    assert np.percentile(np.abs(error[:, 0]), 95) < 0.25


def test_interpolated_vergence_table_matches_direct_one(machine, tmp_path):
    rng = np.random.default_rng(2)
    left = grid_dots(rng)

    def at(vergence_deg):
        # Symmetric convergence: the calibration plane's disparity and the cyclo-rotation grow with it.
        shift = (200 * np.tan(np.deg2rad(vergence_deg) / 2), 1.0)
        return transform(left, shift=shift, angle_deg=0.2 * vergence_deg)

    store = TableStore()
    for vergence in (0.0, 4.0):
        store.add(WarpTable.calibrate(dot_image(left), dot_image(at(vergence)), max_shift=10,
                                      vergence=vergence, machine=machine))
    direct = WarpTable.calibrate(dot_image(left), dot_image(at(2.0)), max_shift=10, vergence=2.0, machine=machine)
    _, inside = inner_pixels(left)
    difference = np.abs(store.table_for(2.0).source - direct.source)[inside]
    assert difference.max() < 0.25
    store.save(tmp_path / "tables.npz")
    loaded = TableStore.load(tmp_path / "tables.npz")
    np.testing.assert_array_equal(loaded.table_for(2.0).source, store.table_for(2.0).source)
    with pytest.raises(ValueError, match="outside the stored range"):
        store.table_for(5.0)


@pytest.mark.parametrize("channels", [None, 3])
def test_warp_matches_bilinear_oracle(channels, machine, machine_with_local_size):
    rng = np.random.default_rng(3)
    shape = (37, 53) if channels is None else (37, 53, channels)
    image = rng.random(shape).astype(np.float32)
    ys, xs = np.indices(shape[:2], dtype=np.float32)
    source = np.stack([xs + rng.uniform(-3, 3, xs.shape), ys + rng.uniform(-3, 3, ys.shape)], axis=2)
    source = source.astype(np.float32)
    got = warp(image, source, machine=machine)
    planes = [image] if channels is None else [image[..., c] for c in range(channels)]
    expected = [ndimage.map_coordinates(p.astype(np.float64), [source[..., 1], source[..., 0]], order=1,
                                        mode="constant", cval=np.nan) for p in planes]
    expected = expected[0] if channels is None else np.stack(expected, axis=2)
    outside = (source[..., 0] < 0) | (source[..., 1] < 0) | (source[..., 0] > shape[1] - 1) | \
        (source[..., 1] > shape[0] - 1)
    assert np.all(np.isnan(got[outside]))
    np.testing.assert_allclose(got[~outside], expected[~outside], atol=1e-5)
    np.testing.assert_array_equal(warp(image, source, machine=machine_with_local_size), got)


def _table(vergence: float, shape=(6, 8)) -> WarpTable:
    ys, xs = np.indices(shape, dtype=np.float32)
    return WarpTable(np.stack([xs + vergence, ys], axis=-1), vergence=vergence, dots=3)


@pytest.mark.parametrize("name", ["tables", "tables.npz", "tables.bin"])
def test_a_saved_store_loads_from_the_path_it_was_saved_to(name, tmp_path):
    """save wrote tables.npz for "tables" (NumPy's suffix), and load("tables") found no file."""
    store = TableStore()
    for vergence in (2.0, 0.0):
        store.add(_table(vergence))
    store.save(str(tmp_path / name))
    assert [path.name for path in tmp_path.iterdir()] == [name]
    loaded = TableStore.load(str(tmp_path / name))
    assert [t.vergence for t in loaded.tables] == [0.0, 2.0]
    np.testing.assert_array_equal(loaded.table_for(1.0).source, store.table_for(1.0).source)


def _saved(path, vergence, source) -> None:
    np.savez_compressed(path, vergence=np.array(vergence, np.float64), dots=np.full(len(vergence), 3),
                        source=np.asarray(source, np.float32))


def test_load_checks_and_orders_the_tables_as_add_does(tmp_path):
    """load took the file's tables as they came: duplicate vergences, sources that are no (H, W, 2) positions,
    vergences out of order (which table_for's bisection then misread). Now each goes through add."""
    path = tmp_path / "store.npz"
    source = np.stack([_table(v).source for v in (3.0, 1.0, 2.0)])
    _saved(path, [3.0, 1.0, 2.0], source)
    loaded = TableStore.load(path)
    assert [t.vergence for t in loaded.tables] == [1.0, 2.0, 3.0]
    np.testing.assert_array_equal(loaded.table_for(1.5).source, _table(1.5).source)
    for vergence, tables, match in (([1.0, 1.0], source[:2], "already stored"),
                                    ([1.0], np.zeros((1, 3, 3)), r"shape \(H, W, 2\)"),
                                    ([float("nan")], source[:1], "table.vergence")):
        _saved(path, vergence, tables)
        with pytest.raises(ValueError, match=match) as raised:
            TableStore.load(path)
        assert "store.npz" in str(raised.value)
    with pytest.raises(ValueError, match="holds no tables"):
        TableStore().save(path)
    # The constructor's tables go through add too: they were taken unchecked and unordered.
    made = TableStore([_table(3.0), _table(1.0)])
    assert [t.vergence for t in made.tables] == [1.0, 3.0]
    with pytest.raises(ValueError, match="already stored"):
        TableStore([_table(1.0), _table(1.0)])


def test_match_dots_is_mutual_and_bounded():
    left = np.array([[10.0, 10.0], [50.0, 10.0], [90.0, 10.0]])
    right = np.array([[12.0, 11.0], [52.0, 9.0], [140.0, 10.0]])
    matched_left, matched_right = match_dots(left, right, max_shift=5)
    np.testing.assert_array_equal(matched_left, left[:2])
    np.testing.assert_array_equal(matched_right, right[:2])


@pytest.mark.parametrize("call, error, match", [
    (lambda: find_dots(np.zeros(5)), ValueError, "image must be a non-empty grey image"),
    (lambda: find_dots(np.ones((5, 5))), ValueError, "constant"),
    (lambda: find_dots(np.eye(5), polarity="grey"), ValueError, "polarity"),
    (lambda: match_dots(np.zeros((3, 3)), np.zeros((3, 2)), max_shift=1), ValueError, "left must be"),
    (lambda: match_dots(np.zeros((3, 2)), np.zeros((3, 2)), max_shift=0), ValueError, "max_shift"),
    (lambda: WarpTable.from_dots(np.zeros((2, 2)), np.zeros((2, 2)), (5, 5)), ValueError, "at least 3"),
    (lambda: warp(np.zeros((4, 4), np.float32), np.zeros((4, 5, 2), np.float32)), ValueError, "table must have"),
    (lambda: warp(np.zeros((4, 4), np.complex64), np.zeros((4, 4, 2), np.float32)), TypeError, "real-valued"),
    # float64 beyond float32's range became infinities (NaN and infinities themselves carry over).
    (lambda: warp(np.full((4, 4), 1e300), np.zeros((4, 4, 2), np.float32)), ValueError,
     "image has values beyond float32's range"),
])
def test_bad_input_is_named(call, error, match):
    with pytest.raises(error, match=match):
        call()


@pytest.mark.parametrize("dtype", [np.complex128, object, str])
def test_find_dots_refuses_images_that_are_not_real(dtype):
    """Complex images lost their imaginary part, and object and string images were parsed as numbers."""
    image = np.eye(8).astype(dtype)
    with pytest.raises(TypeError, match="image must hold real numbers"):
        find_dots(image)


@pytest.mark.parametrize("call, error, match", [
    (lambda: find_dots(np.eye(8), threshold=float("nan")), ValueError, "threshold"),
    (lambda: find_dots(np.eye(8), threshold="0.5"), TypeError, "threshold"),
    (lambda: find_dots(np.eye(8), min_area=2.0), TypeError, "min_area"),
    (lambda: find_dots(np.eye(8), min_area=-1), ValueError, "min_area"),
    (lambda: find_dots(np.eye(8), polarity=["dark"]), TypeError, "polarity"),
    (lambda: match_dots(np.zeros((3, 2)), np.zeros((3, 2)), max_shift="1"), TypeError, "max_shift"),
    (lambda: match_dots(np.zeros((3, 2), complex), np.zeros((3, 2)), max_shift=1), TypeError, "left"),
    (lambda: match_dots(np.full((3, 2), np.nan), np.zeros((3, 2)), max_shift=1), ValueError, "left"),
    (lambda: WarpTable.from_dots(np.eye(3, 2), np.eye(3, 2), (8, 8), vergence="1"), TypeError, "vergence"),
    (lambda: WarpTable.from_dots(np.eye(3, 2), np.eye(3, 2)[:2], (8, 8)), ValueError, "same number"),
    (lambda: WarpTable.from_dots(np.eye(3, 2), np.eye(3, 2), (0, 8)), ValueError, "shape"),
    (lambda: WarpTable.from_dots(np.eye(3, 2), np.eye(3, 2), None), TypeError, "shape"),
    (lambda: WarpTable.calibrate([[1.0]], [[1.0]], max_shift=1.0), TypeError, "left_image"),
    (lambda: TableStore().add("table"), TypeError, "WarpTable"),
    (lambda: TableStore([WarpTable(np.zeros((2, 2, 2), np.float32))]).table_for("0"), TypeError, "vergence"),
])
def test_arguments_are_checked_by_type_and_range(call, error, match):
    from vmcl.errors import InputError

    with pytest.raises(error, match=match) as raised:
        call()
    assert isinstance(raised.value, InputError)
