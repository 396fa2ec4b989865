"""The report opens: its HTML parses, every inline image decodes, and the pictures mean what they say."""

import base64
import re
from html.parser import HTMLParser

import cv2
import numpy as np
import pytest

from vmcl import scenes
from vmcl.errors import InputError
from vmcl.labels import Cue
from vmcl.pictures import disparity_image, flow_image
from vmcl.pipeline import Config, VisionMachine
from vmcl.report import CUE_COLOURS, LABEL_COLOURS, REGISTERED_CUES, labels_image, support_image, write_report


class _Images(HTMLParser):
    def __init__(self):
        super().__init__()
        self.sources, self.tags = [], []

    def handle_starttag(self, tag, attrs):
        self.tags.append(tag)
        if tag == "img":
            self.sources.append(dict(attrs)["src"])


@pytest.fixture(scope="module")
def run():
    s = scenes.render(scenes.preset("blocks", shape=(64, 64)), seed=0, noise=0.01)
    return VisionMachine(Config.from_dict({"mrf": {"method": "icm"}})).run(s.left, s.right, s.left_next)


def test_report_parses_and_every_inline_image_decodes(run, tmp_path):
    written = write_report(run, tmp_path, evaluation={"scores": [("name", "value"), ("bad 1", "0.01")]})
    page = written["report"].read_text(encoding="utf-8")
    parser = _Images()
    parser.feed(page)
    parser.close()
    assert {"html", "body", "table", "img"} <= set(parser.tags)
    assert len(parser.sources) == len(written) - 1 == 11  # every PNG is inline too
    for source in parser.sources:
        prefix, data = source.split(",", 1)
        assert prefix == "data:image/png;base64"
        picture = cv2.imdecode(np.frombuffer(base64.b64decode(data), np.uint8), cv2.IMREAD_COLOR)
        assert picture is not None and picture.shape[1] == 64
    for stem, path in written.items():
        if stem != "report":
            assert cv2.imread(str(path)) is not None
    assert "stereo.d_max" in page and "mrf colour" in page and "bad 1" in page


def test_flow_wheel_directions_and_speed():
    flow = np.zeros((64, 64, 2), np.float32)
    flow[:, :32, 0] = 2.0  # right
    flow[:, 32:, 1] = -2.0  # up
    flow[60:, :] = 0.0  # still
    flow[0, 0] = np.nan
    picture = flow_image(flow, max_flow=2.0)
    np.testing.assert_array_equal(picture[50, 20], [255, 0, 0])  # right is red, as in Baker et al.
    assert picture[50, 50, 2] > 200 and picture[50, 50, 0] < 120  # up is blue-violet
    np.testing.assert_array_equal(picture[62, 10], [255, 255, 255])  # no motion is white


def test_an_infinite_disparity_is_drawn_black_and_leaves_the_scale_to_the_finite_ones():
    # One inf stretched the colour map to it: two colours in all, a scale reading "inf".
    disparity = np.linspace(0, 10, 64 * 64, dtype=np.float32).reshape(64, 64)
    spoiled, unknown = disparity.copy(), disparity.copy()
    spoiled[0, 0], unknown[0, 0] = np.inf, np.nan
    drawn = disparity_image(spoiled)
    assert (drawn[0, 0] == 0).all()
    np.testing.assert_array_equal(drawn, disparity_image(unknown))  # as an unknown pixel is


def test_the_flow_pictures_caption_gives_the_speed_of_full_colour(run):
    from vmcl.report import images_with_captions

    caption = images_with_captions(run)["flow"][1]
    fastest = float(np.nanmax(np.hypot(run.flow[..., 0], run.flow[..., 1])))
    assert f"full colour is its largest speed, {fastest:.2f} px per frame" in caption


def test_a_disparity_of_one_value_is_drawn_and_reported(run, tmp_path):
    # Its own range (vmin == vmax) was refused, so a run whose restored disparity came out constant failed
    # in its report after the run itself had succeeded.
    import dataclasses

    picture = disparity_image(np.full((16, 16), 8.0, np.float32), vmin=8.0, vmax=8.0)
    assert picture.shape == (16 + 28, 16, 3) and (picture[:16] == picture[0, 0]).all() and picture[0, 0].any()
    flat = dataclasses.replace(run, disparity=np.full_like(run.disparity, 8.0))
    write_report(flat, tmp_path / "flat")
    assert (tmp_path / "flat" / "disparity.png").exists()


def test_disparity_scale_runs_from_far_to_near():
    disparity = np.tile(np.linspace(2.0, 10.0, 64, dtype=np.float32), (32, 1))
    disparity[0, 0] = np.nan
    picture = disparity_image(disparity)
    assert picture.shape == (32 + 28, 64, 3)
    assert picture[16, 63, 0] > picture[16, 63, 2] and picture[16, 0, 2] > picture[16, 0, 0]  # near red, far blue
    np.testing.assert_array_equal(picture[0, 0], [0, 0, 0])


def test_support_picture_colours_each_cue_over_the_faded_image():
    image = np.zeros((8, 8), np.float32)
    support = np.zeros((8, 8), np.uint8)
    support[1, 1] = Cue.COLOUR
    support[2, 2] = Cue.STEREO | Cue.COLOUR
    support[3, 3] = Cue.BRIGHTNESS
    # A cue registered at run time holds a bit above BRIGHTNESS: its lines were drawn as brightness edges.
    support[4, 4] = Cue.BRIGHTNESS | 32
    support[5, 5] = Cue.TEXTURE | 64
    picture = support_image(image, support)
    assert tuple(picture[1, 1]) == CUE_COLOURS[Cue.COLOUR]
    assert tuple(picture[2, 2]) == CUE_COLOURS[Cue.STEREO]
    assert tuple(picture[4, 4]) == REGISTERED_CUES and tuple(picture[5, 5]) == CUE_COLOURS[Cue.TEXTURE]
    assert picture[0, 0, 0] == picture[0, 0, 1] > 100  # faded, grey


def test_labelled_cartoon_colours_each_label():
    image = np.zeros((6, 6), np.float32)
    labels = np.zeros((6, 6), np.uint8)
    for k, label in enumerate(LABEL_COLOURS):
        labels[k, k] = label
    picture = labels_image(image, labels)
    for k, (label, colour) in enumerate(LABEL_COLOURS.items()):
        assert tuple(picture[k, k]) == colour, label
    assert picture[0, 1, 0] == picture[0, 1, 1] > 100  # faded, grey


def test_the_report_never_overwrites_a_file_it_did_not_write(run, tmp_path):
    mine = tmp_path / "cartoon.png"
    mine.write_bytes(b"the user's own picture")
    with pytest.raises(ValueError, match="already holds cartoon.png"):
        write_report(run, tmp_path)
    assert mine.read_bytes() == b"the user's own picture"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cartoon.png"]
    # A link to nothing is a name taken too: writing through it made a file wherever it pointed.
    elsewhere = tmp_path.parent / f"{tmp_path.name}-elsewhere.png"
    linked = tmp_path / "links"
    linked.mkdir()
    (linked / "cartoon.png").symlink_to(elsewhere)
    with pytest.raises(ValueError, match="already holds cartoon.png"):
        write_report(run, linked)
    assert not elsewhere.exists()
    # A folder that is a file, or lies below one, is refused by name; the file is left as it was.
    for folder in (mine, mine / "sub"):
        with pytest.raises(InputError, match=re.escape(f"folder {folder} is not a folder")):
            write_report(run, folder)
    assert mine.read_bytes() == b"the user's own picture"


@pytest.mark.parametrize(("kwargs", "match"), [({"title": "bad \ud800"}, "title holds characters"),
                                               ({"evaluation": {"t": []}}, r"evaluation\['t'\] must be a table"),
                                               ({"evaluation": {"t": None}}, r"evaluation\['t'\] must be a table")])
def test_a_bad_title_or_evaluation_is_refused_before_anything_is_written(run, tmp_path, kwargs, match):
    # They failed after the pictures were written, leaving a folder the next call refused.
    with pytest.raises(InputError, match=match):
        write_report(run, tmp_path / "out", **kwargs)
    assert not (tmp_path / "out").exists()
    write_report(run, tmp_path / "out")


@pytest.mark.parametrize("stem, match", [("../escaped", "names a picture '../escaped'"),
                                         ('a" onerror="x', "names a picture"),
                                         ("cartoon", "which another picture of the report has")])
def test_a_cues_picture_names_are_plain_and_its_own(run, tmp_path, stem, match):
    # A cue's picture names were file stems unchecked: one wrote outside the folder, one put markup into the
    # page, one replaced the cartoon.
    from vmcl import cues
    from vmcl.cues import CueModule
    from vmcl.labels import Label

    class Drawing(CueModule):
        name = "drawing_cue"
        label = Label.SHADOW

        def measure(self, run):
            raise AssertionError("not run")

        def pictures(self, result):
            return {stem: (np.zeros((4, 4, 3), np.uint8), "its picture")}

    cues.register(Drawing())
    try:
        with pytest.raises(InputError, match=re.escape(match)):
            write_report(run, tmp_path / "out")
    finally:
        cues.unregister("drawing_cue")
    assert not (tmp_path / "out").exists() and not (tmp_path / "escaped.png").exists()


@pytest.mark.parametrize(("call", "error", "named"), [
    (lambda: disparity_image(np.zeros((0, 16), np.float32)), ValueError, "disparity"),
    (lambda: disparity_image(np.zeros((8, 8), complex)), TypeError, "disparity"),
    (lambda: disparity_image(np.zeros((8, 8), np.float32), vmin="0"), TypeError, "vmin"),
    (lambda: disparity_image(np.zeros((8, 8), np.float32), vmin=8.0, vmax=2.0), ValueError, "vmin must not exceed vmax"),
    (lambda: flow_image(np.zeros((0, 16, 2), np.float32)), ValueError, "flow"),
    (lambda: flow_image(np.zeros((8, 8, 3), np.float32)), ValueError, "flow"),
    (lambda: flow_image(np.zeros((8, 8, 2), np.float32), max_flow=np.nan), ValueError, "max_flow"),
    (lambda: labels_image(np.zeros((0, 16, 3), np.float32), np.zeros((0, 16), np.uint8)), ValueError, "image"),
    (lambda: labels_image(np.zeros((8, 8), np.float32), np.zeros((8, 9), np.uint8)), ValueError, "labels"),
    (lambda: support_image(np.zeros((8, 8), np.float32), np.zeros((8, 8), np.float32)), TypeError, "support"),
    (lambda: write_report(None, "unused"), TypeError, "result"),
])
def test_bad_pictures_are_refused_by_name(call, error, named):
    with pytest.raises(error, match=named):
        call()


def test_eight_bits_takes_a_16_bit_picture_to_8_bits_rounded():
    from vmcl.pictures import eight_bits

    levels = np.array([[0, 128, 129, 257 * 100 + 128, 65535]], np.uint16)
    np.testing.assert_array_equal(eight_bits(levels), np.round(levels / 257).astype(np.uint8))
    eight = np.array([[3, 200]], np.uint8)
    assert eight_bits(eight) is eight
    with pytest.raises(InputError, match="image must be uint8 or uint16"):
        eight_bits(np.zeros((2, 2), np.float32))


def test_eight_bits_keeps_a_single_channel_axis():
    from vmcl.pictures import eight_bits

    assert eight_bits(np.full((4, 5, 1), 257 * 9, np.uint16)).shape == (4, 5, 1)
