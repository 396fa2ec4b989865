"""vmcl.recognize's inputs (the second review of recognition): a damaged or hand-edited model file is refused
when it is read, naming the file and the array, not later in recognize; masks are read by one rule, NumPy or
device, whatever their type's scale; messages name what the user gave."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from vmcl.errors import InputError
from vmcl.recognize import Library, learn, load_model, model_path, recognize, save_model
from vmcl.scenes import object_view


@pytest.fixture(scope="module")
def ell():
    image, _ = object_view("ell", shape=(160, 160))
    return learn("ell", [image]), image


def _edited(folder, path, change):
    """A copy of the model file at ``path`` with ``change(arrays, meta)`` applied, as a hand edit makes one."""
    with np.load(path) as data:
        arrays = dict(data)
    meta = json.loads(str(arrays["meta"]))
    change(arrays, meta)
    arrays["meta"] = np.array(json.dumps(meta))
    folder.mkdir(exist_ok=True)
    edited = folder / path.name
    np.savez(edited, **arrays)
    return edited


def _set(key, value):
    return lambda arrays, meta: arrays.__setitem__(key, value(arrays[key]))


@pytest.mark.parametrize("change, match", [
    # Each loaded, then failed in recognize naming an argument the user never gave ("opening must lie within
    # [0, 3.142]"), or (tangents all NaN) was matched at a wrong pose; the rest matched nothing, silently.
    pytest.param(_set("v0_opening", lambda a: a + 100), r"v0_\*\): a view's opening must lie within \[0, 3.142\]",
                 id="opening+100"),
    pytest.param(_set("v0_tangent", lambda a: np.full_like(a, np.inf)),
                 r"v0_\*\): a view's tangent must be finite or NaN", id="tangent-inf"),
    pytest.param(_set("v0_points", lambda a: a * 1e8), r"v0_\*\): a view's points must be finite coordinates within 1e9",
                 id="points*1e8"),
    pytest.param(_set("v0_tangent", lambda a: np.full_like(a, np.nan)), r"v0_\*\): a view's tangent must be known",
                 id="tangent-all-nan"),
    pytest.param(_set("v0_bisector", lambda a: a + 1e20), r"v0_\*\): a view's bisector must lie within",
                 id="bisector+1e20"),
    pytest.param(_set("v0_centre", lambda a: np.array([1e9, 1e9])),
                 r"v0_\*\): a view's centre must be its boundary's centroid", id="centre-far"),
    pytest.param(_set("v0_frame", lambda a: np.array([1e-300, *a[1:]])),
                 r"v0_\*\): a view's radius must be its boundary's rms", id="radius-tiny"),
    # The points' dimensions were blamed on the outline ("outline is not one bool per boundary point").
    pytest.param(_set("v0_points", lambda a: a[None]), r"v0_\*\): a view's points must be an \(N, 2\) array",
                 id="points-3d"),
    # A header's count of views read with int(): "1", 1.7 and true were one view.
    pytest.param(lambda arrays, meta: meta.__setitem__("views", "1"), "views must be a whole number >= 1, got '1'",
                 id="views-str"),
    pytest.param(lambda arrays, meta: meta.__setitem__("views", 1.7), "views must be a whole number >= 1, got 1.7",
                 id="views-float"),
    pytest.param(lambda arrays, meta: meta.__setitem__("views", True), "views must be a whole number >= 1, got True",
                 id="views-bool"),
    pytest.param(lambda arrays, meta: meta.__setitem__("sources", "ab"), "sources must be a list of str",
                 id="sources-str"),
    # An infinite size ended in a traceback (OverflowError) and "vmcl: internal error".
    pytest.param(_set("v0_frame", lambda a: np.array([a[0], np.inf, *a[2:]])),
                 r"v0_frame is not the 4 finite numbers", id="frame-inf"),
])
def test_a_damaged_model_file_is_refused_when_read_naming_the_file(tmp_path, ell, change, match):
    model, _ = ell
    path = save_model(model, tmp_path / "library")
    edited = _edited(tmp_path / "edited", path, change)
    with pytest.raises(InputError, match=f"^{edited}.*{match}"):
        load_model(edited)
    with pytest.raises(InputError, match=match):
        Library.load(edited.parent)
    # The file it was made from reads back as it was written.
    again = load_model(path)
    assert again.name == "ell" and np.array_equal(again.views[0].points, model.views[0].points)
    assert np.array_equal(again.views[0].tangent, model.views[0].tangent, equal_nan=True)


def test_a_view_made_by_hand_is_checked_as_a_file_is(ell):
    model, _ = ell
    view = model.views[0]
    for changes, match in (({"opening": view.opening + 100}, "opening must lie within"),
                           ({"tangent": np.full_like(view.tangent, np.nan)}, "tangent must be known"),
                           ({"points": view.points * 1e8}, "points must be finite coordinates"),
                           ({"radius": view.radius * 3}, "radius must be its boundary's rms")):
        with pytest.raises(InputError, match=match):
            dataclasses.replace(view, **changes)
    # NaN is an unknown tangent (an edge in any direction supports it): a view with some known is taken.
    some = view.tangent.copy()
    some[::2] = np.nan
    assert np.isnan(dataclasses.replace(view, tangent=some).tangent).sum() == np.isnan(some).sum()


def test_a_mask_is_read_by_one_rule_whatever_its_type_or_where_it_lies(ell, machine):
    _, image = ell
    inside = np.zeros(image.shape[:2], bool)
    inside[20:140, 20:140] = True
    expected = learn("ell", [image], masks=[inside]).views[0]
    # 0 off the object, and 1 or the type's full scale on it; on the host or the device (as images are).
    for mask in (inside.astype(np.uint8), inside.astype(np.uint8) * 255, inside.astype(np.uint16),
                 inside.astype(np.uint16) * 65535, inside.astype(np.float32), machine.to_device(inside.astype(np.uint8)),
                 machine.to_device(inside.astype(np.uint16) * 65535)):
        view = learn("ell", [image], masks=[mask]).views[0]
        assert np.array_equal(view.points, expected.points) and np.array_equal(view.outline, expected.outline)
    grey = inside.astype(np.uint8) * 200
    grey[20] = 100  # an edge of another grey: no one cut is right for it
    for mask, match in ((grey, (r"masks\[0\] must hold only 0 .off the object. and one other value .on it.: 1 or "
                                r"255, its type's full scale; it holds 100, 200 where it is not 0")),
                        (inside * np.float32(0.5), r"masks\[0\] must hold only 0 .* 1; it holds 0.5"),
                        (np.zeros(image.shape[:2], np.uint8), r"masks\[0\] marks no pixel as the object")):
        with pytest.raises(InputError, match=match):
            learn("ell", [image], masks=[mask])
    # A mask that leaves too few of the example's edges is said to, not the example.
    corner = np.zeros(image.shape[:2], bool)
    corner[:4, :4] = True
    with pytest.raises(InputError, match=r"images\[0\]: the mask leaves 0 of the example's \d+ edge pixels"):
        learn("ell", [image], masks=[corner])


def test_learns_messages_say_what_is_wrong():
    image, _ = object_view("ell", shape=(96, 96))
    # Only ASCII letters are allowed, and the message said "letters".
    with pytest.raises(InputError, match="name must be 1 to 64 ASCII letters"):
        learn("bøx", [image])
    # A blank picture was told "texture raises" the thresholds; it has no texture.
    with pytest.raises(InputError, match=r"\(0 edge pixels at the Canny thresholds its noise estimate gives\): a "
                                         "blank, faint or tiny picture shows too few edges"):
        learn("blank", [np.full((64, 64), 128, np.uint8)])


def test_a_library_folder_that_is_a_file_is_refused_before_the_path_is_used(tmp_path):
    (tmp_path / "afile").write_bytes(b"")
    for folder in (tmp_path / "afile", tmp_path / "afile" / "sub"):
        with pytest.raises(InputError, match=f"folder must be a directory .a library of model files., but "
                                             f"{tmp_path / 'afile'} is a file"):
            model_path(folder, "box")
    assert model_path(tmp_path / "new", "box") == tmp_path / "new" / "box.vmodel.npz"


def test_a_valid_models_detections_are_unchanged_by_the_checks(tmp_path, ell):
    # The checks only refuse: a model read back from its file finds what the model learned finds.
    model, image = ell
    path = save_model(model, tmp_path / "library")
    found = recognize(image, Library([model]))
    again = recognize(image, Library([load_model(path)]))
    assert [d.name for d in found] == ["ell"]
    assert [(d.name, d.score, d.significance) for d in again] == [(d.name, d.score, d.significance) for d in found]
    assert np.array_equal(again[0].transform, found[0].transform)


def test_a_model_file_damaged_inside_its_compression_or_header_is_refused_naming_it(tmp_path, ell):
    # A flipped byte inside a compressed member fails in zlib, and a header nested past JSON's reader in
    # RecursionError: both escaped as tracebacks.
    model, _ = ell
    path = save_model(model, tmp_path / "library")
    data = path.read_bytes()
    refused = 0
    for offset in range(200, len(data) - 200, 97):
        damaged = tmp_path / "damaged" / path.name
        damaged.parent.mkdir(exist_ok=True)
        flipped = bytearray(data)
        flipped[offset] ^= 0xFF
        damaged.write_bytes(bytes(flipped))
        try:
            load_model(damaged)
        except InputError as error:
            assert str(damaged) in str(error)
            refused += 1
    assert refused > 0
    nested = tmp_path / "nested" / path.name
    nested.parent.mkdir()
    with np.load(path) as archive:
        arrays = dict(archive)
    arrays["meta"] = np.array("[" * 100000)
    np.savez(nested, **arrays)
    with pytest.raises(InputError, match=f"^{nested} is not a vmcl model file .its header is nested too deeply"):
        load_model(nested)
