"""Pictures of a Vision Machine run a person reads at a glance, and the single-file HTML report.

Seed section "The Vision Machine System": the machine's output is "a 'cartoon' of the original scene"
(its labelled discontinuities) "along with interpolated depth, motion, texture, and color fields". The
report shows exactly those: the cartoon coloured by label and by the cue that supports each
discontinuity over the faded image, each cue's pictures of its fields (:mod:`vmcl.pictures`: the dense
disparity with a scale bar, the flow in the Middlebury colour wheel, the hue and texture fields), then
the parameters and the timing table. Images are NumPy RGB uint8; files are PNGs, and report.html holds them
inline (base64) so it can be mailed or archived as one file.
"""

from __future__ import annotations

import base64
import html
import re
from collections.abc import Mapping, Sequence
from pathlib import Path

import cv2
import numpy as np

from vmcl.cm.core import real_host_array
from vmcl.cues import registered
from vmcl.early.filters import GREY_WEIGHTS
from vmcl.errors import InputTypeError, InputValueError
from vmcl.group import Grouping
from vmcl.labels import Cue, Label
from vmcl.output_folder import refuse_names_present
from vmcl.pictures import to_uint8
from vmcl.recognize import Detection
from vmcl.result import Result

__all__ = [
    "BRIGHTNESS_ONLY",
    "CUE_COLOURS",
    "JUNCTION_COLOURS",
    "LABEL_COLOURS",
    "REGISTERED_CUES",
    "encode_png",
    "grouping_image",
    "images",
    "images_with_captions",
    "labels_image",
    "recognition_image",
    "strength_image",
    "support_image",
    "write_report",
]

CUE_COLOURS = {Cue.STEREO: (230, 40, 40), Cue.MOTION: (250, 150, 20), Cue.COLOUR: (40, 110, 240),
               Cue.TEXTURE: (30, 180, 60)}
"""RGB of each cue in the cartoon; a pixel several cues support takes the first in this order."""

LABEL_COLOURS = {Label.DEPTH: (230, 40, 40), Label.ORIENTATION: (150, 60, 200), Label.ALBEDO: (40, 110, 240),
                 Label.SHADOW: (60, 60, 60), Label.SPECULAR: (240, 200, 0), Label.TEXTURE: (30, 180, 60)}
"""RGB of each physical label in the labelled cartoon."""

JUNCTION_COLOURS = {"T": (230, 40, 40), "Y": (30, 160, 60), "arrow": (40, 110, 240), "L": (240, 170, 0),
                    "X": (170, 40, 200)}
"""RGB of each junction type in the grouping picture."""

_PAIR_COLOUR = (0, 170, 190)
_OBJECT_COLOURS = ((0, 200, 80), (230, 120, 0), (40, 110, 240), (200, 40, 200), (0, 170, 190), (200, 170, 0))
_UNSUPPORTED = (120, 20, 20)
_CURVE_DARK, _CURVE_LIGHT = np.array([150, 150, 150]), np.array([20, 20, 20])

BRIGHTNESS_ONLY = (200, 200, 200)
"""RGB of brightness edges no cue supports (drawn under the cues)."""

REGISTERED_CUES = (200, 40, 200)
"""RGB of the lines of cues registered at run time (:func:`vmcl.cues.register`), where no built-in cue's are."""

def _grey(image: np.ndarray) -> np.ndarray:
    """float (H, W) in [0, 1] from a grey or RGB float image (BT.709 luma, as vmcl.early.filters)."""
    if image.ndim == 3:
        image = image @ np.array(GREY_WEIGHTS, np.float32)
    return np.clip(image, 0.0, 1.0)


def _image_argument(image: np.ndarray, name: str) -> np.ndarray:
    """A picture's background: a real (H, W) grey or (H, W, 3) RGB NumPy array, not empty."""
    real_host_array(image, name, ndims=(2, 3))
    if image.ndim == 3 and image.shape[2] != 3:
        raise InputValueError(f"{name} must be (H, W) grey or (H, W, 3) RGB, got shape {image.shape}")
    return image


def _overlay_argument(values: np.ndarray, name: str, image: np.ndarray) -> np.ndarray:
    """Codes drawn over ``image``: a real (H, W) array of the image's height and width."""
    real_host_array(values, name, ndims=(2,))
    if values.shape != image.shape[:2]:
        raise InputValueError(f"{name} has shape {values.shape}, the image {image.shape[:2]}: they must match")
    return values


def _faded(image: np.ndarray) -> np.ndarray:
    faded = 255 * (0.55 + 0.4 * _grey(image))  # light grey: the coloured lines carry the picture
    return to_uint8(np.repeat(faded[..., None], 3, axis=2))


def labels_image(image: np.ndarray, labels: np.ndarray) -> np.ndarray:
    """The labelled cartoon: each discontinuity coloured by its physical cause (:data:`LABEL_COLOURS`).

    Parameters
    ----------
    image : float (H, W) or (H, W, 3) in [0, 1]
    labels : uint8 (H, W), :class:`vmcl.labels.Label` codes (:attr:`vmcl.result.Result.labels`)

    Returns
    -------
    uint8 RGB (H, W, 3)
    """
    _overlay_argument(labels, "labels", _image_argument(image, "image"))
    picture = _faded(image)
    for label, colour in LABEL_COLOURS.items():
        picture[labels == label] = colour
    return picture


def support_image(image: np.ndarray, support: np.ndarray) -> np.ndarray:
    """The cues' support: the pixels each cue's line marks, coloured by cue (:data:`CUE_COLOURS`), and the
    brightness edges no cue marks, over the faded image.

    Parameters
    ----------
    image : float (H, W) or (H, W, 3) in [0, 1]
    support : uint8 (H, W), :class:`vmcl.labels.Cue` bits (:attr:`vmcl.result.Result.support`)

    Returns
    -------
    uint8 RGB (H, W, 3)
    """
    _overlay_argument(support, "support", _image_argument(image, "image"))
    if support.dtype.kind not in "biu":
        raise InputTypeError(f"support must hold integer Cue bits, got dtype {support.dtype}")
    picture = _faded(image)
    picture[(support & Cue.BRIGHTNESS) != 0] = BRIGHTNESS_ONLY
    painted = np.zeros(support.shape, bool)
    for cue, colour in CUE_COLOURS.items():
        here = ((support & cue) != 0) & ~painted
        picture[here] = colour
        painted |= here
    # The bits above BRIGHTNESS are the cues registered at run time (vmcl.cues.register): one colour for
    # them all, rather than drawing their lines as brightness edges or not at all.
    picture[((support.astype(np.int64) & ~0x1F) != 0) & ~painted] = REGISTERED_CUES
    return picture


def grouping_image(image: np.ndarray, grouping: Grouping) -> np.ndarray:
    """The grouping over the faded image: each curve in grey, darker the more locally salient it is (its
    rank among the curves), the T-junction pairs joined by a cyan line, and each junction as a small
    square coloured by type (:data:`JUNCTION_COLOURS`), a T's with a tick towards the occluding side.

    Parameters
    ----------
    image : float (H, W) or (H, W, 3) in [0, 1]
    grouping : vmcl.group.Grouping of the same image

    Returns
    -------
    uint8 RGB (H, W, 3)
    """
    if not isinstance(grouping, Grouping):
        raise InputTypeError(f"grouping must be a vmcl.group.Grouping, got {type(grouping).__name__}")
    labels = np.asarray(grouping.curves.labels)
    _overlay_argument(labels, "grouping.curves.labels", _image_argument(image, "image"))
    picture = _faded(image)
    count = len(grouping.saliency)
    if count:
        rank = np.empty(count)
        rank[np.argsort(grouping.saliency, kind="stable")] = np.arange(count) / max(count - 1, 1)
        on = labels >= 0
        picture[on] = to_uint8(_CURVE_DARK + rank[labels[on], None] * (_CURVE_LIGHT - _CURVE_DARK))
    junctions = grouping.junctions
    for a, b in grouping.pairs:
        cv2.line(picture, tuple(int(v) for v in np.rint(junctions.points[a])),
                 tuple(int(v) for v in np.rint(junctions.points[b])), _PAIR_COLOUR, 1)
    for point, kind, occluder in zip(junctions.points, junctions.kinds, junctions.occluder):
        x, y = (int(v) for v in np.rint(point))
        colour = JUNCTION_COLOURS[str(kind)]
        cv2.rectangle(picture, (x - 1, y - 1), (x + 1, y + 1), colour, -1)
        if kind == "T":
            tip = np.rint(point + 4 * occluder).astype(int)
            cv2.line(picture, (x, y), (int(tip[0]), int(tip[1])), colour, 1)
    return picture


def recognition_image(image: np.ndarray, detections: Sequence[Detection]) -> np.ndarray:
    """The recognised objects over the faded image: each model's boundary where the image supports it in
    its colour, unsupported in dark red, its corners as small squares, its name at its first corner.

    Parameters
    ----------
    image : float (H, W) or (H, W, 3) in [0, 1]
    detections : sequence of vmcl.recognize.Detection

    Returns
    -------
    uint8 RGB (H, W, 3)
    """
    picture = _faded(_image_argument(image, "image"))
    h, w = picture.shape[:2]
    if isinstance(detections, (str, Detection)) or not isinstance(detections, Sequence):
        raise InputTypeError(f"detections must be a sequence (a list) of vmcl.recognize.Detection, got "
                             f"{type(detections).__name__}")
    for k, detection in enumerate(detections):
        if not isinstance(detection, Detection):
            raise InputTypeError(f"detections must hold vmcl.recognize.Detection, got {type(detection).__name__}")
        colour = _OBJECT_COLOURS[k % len(_OBJECT_COLOURS)]
        at = np.rint(detection.boundary).astype(np.int64)
        inside = (at[:, 0] >= 0) & (at[:, 1] >= 0) & (at[:, 0] < w) & (at[:, 1] < h)
        picture[at[inside & ~detection.supported, 1], at[inside & ~detection.supported, 0]] = _UNSUPPORTED
        picture[at[inside & detection.supported, 1], at[inside & detection.supported, 0]] = colour
        for x, y in np.rint(detection.corners).astype(np.int64):
            if 0 <= x < w and 0 <= y < h:
                cv2.rectangle(picture, (int(x) - 1, int(y) - 1), (int(x) + 1, int(y) + 1), colour, -1)
        if len(at[inside]):
            x, y = at[inside].min(axis=0)
            cv2.putText(picture, detection.name, (int(x), max(int(y) - 3, 10)), cv2.FONT_HERSHEY_SIMPLEX, 0.4, colour,
                        1, cv2.LINE_AA)
    return picture


def strength_image(strength: np.ndarray) -> np.ndarray:
    """The cartoon's soft map (:attr:`vmcl.result.Result.boundary_strength`) as a picture: black for 0,
    white for 1, the contours drawn dark on white paper as boundary benchmarks show them.

    Parameters
    ----------
    strength : float (H, W) in [0, 1]

    Returns
    -------
    uint8 RGB (H, W, 3)
    """
    strength = real_host_array(strength, "strength", ndims=(2,))
    if strength.dtype.kind != "f" or not np.isfinite(strength).all() or strength.min() < 0 or strength.max() > 1:
        raise InputValueError("strength must be finite floats in [0, 1]")
    return to_uint8(np.repeat(255 * (1 - strength[..., None]), 3, axis=2))


def images(result: Result) -> dict[str, np.ndarray]:
    """The report's pictures of a run, by file stem, in the order the report shows them."""
    return {stem: picture for stem, (picture, _) in images_with_captions(result).items()}


def images_with_captions(result: Result) -> dict[str, tuple[np.ndarray, str]]:
    """The report's pictures of a run with their captions: the cartoon, the cues' support and the input,
    then each registered cue's own (:meth:`vmcl.cues.CueModule.pictures`), then the brightness edges."""
    if not isinstance(result, Result):
        raise InputTypeError(f"result must be a vmcl.result.Result, got {type(result).__name__}")
    grey = _grey(result.image)
    out = {"cartoon": (labels_image(result.image, result.labels), _CAPTIONS["cartoon"]),
           "strength": (strength_image(result.boundary_strength), _CAPTIONS["strength"]),
           "support": (support_image(result.image, result.support), _CAPTIONS["support"]),
           "input": (to_uint8(255 * np.repeat(grey[..., None], 3, axis=2) if result.image.ndim == 2
                               else 255 * np.clip(result.image, 0, 1)), _CAPTIONS["input"])}
    for cue in registered():
        for stem, picture in cue.pictures(result).items():
            # A picture's name is its file's stem in the report's folder: a plain name of no other picture's,
            # or it would be written outside the folder or over another's.
            if not (isinstance(stem, str) and _PICTURE_NAME.fullmatch(stem)):
                raise InputValueError(f"cue {cue.name!r}: pictures() names a picture {stem!r}; a name is 1 to 64 "
                                      "letters, digits, _ or - (it is the picture's file name)")
            if stem in out or stem in _CAPTIONS:
                raise InputValueError(f"cue {cue.name!r}: pictures() names a picture {stem!r}, which another "
                                      "picture of the report has")
            out[stem] = picture
    edges = np.where(result.edges, int(Cue.BRIGHTNESS), 0).astype(np.uint8)
    out["edges"] = (support_image(result.image, edges), _CAPTIONS["edges"])
    if result.grouping is not None:
        out["grouping"] = (grouping_image(result.image, result.grouping), _CAPTIONS["grouping"])
    if result.recognition is not None:
        out["recognition"] = (recognition_image(result.image, result.recognition), _CAPTIONS["recognition"])
    return out


_PICTURE_NAME = re.compile(r"[A-Za-z0-9_-]{1,64}")

_CAPTIONS = {
    "cartoon": "The cartoon, the discontinuities by label: depth red, orientation purple, albedo blue, "
               "shadow dark grey, specular yellow, texture green",
    "strength": "The cartoon's soft map: the strength of a boundary, from white (none) to black (certain)",
    "support": "The cues' support: discontinuities by cue (red stereo, orange motion, blue colour, green texture, "
               "magenta any cue registered at run time; grey: brightness edges no cue supports) over the faded image",
    "input": "The left image",
    "edges": "Canny's brightness edges (those the MRFs are coupled to)",
    "grouping": "Grouping: the edge curves, darker the more salient; junctions by type (T red, with a tick "
                "towards the occluding side; Y green; arrow blue; L orange; X purple); paired T-junctions "
                "joined in cyan",
    "recognition": "Recognition: each object found, its model's boundary where the image's edges support it "
                   "(unsupported in dark red), its corners and its name",
}


def encode_png(rgb: np.ndarray) -> bytes:
    """PNG bytes of an RGB uint8 image."""
    real_host_array(rgb, "rgb", ndims=(3,))
    if rgb.dtype != np.uint8 or rgb.shape[2] != 3:
        raise InputValueError(f"rgb must be a uint8 (H, W, 3) array, got {rgb.dtype} of shape {rgb.shape}")
    ok, data = cv2.imencode(".png", cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR))
    if not ok:
        raise RuntimeError("OpenCV could not encode a PNG")
    return data.tobytes()


def _box(points: np.ndarray) -> str:
    """The box of a detection's boundary points in the image, as text; "-" for none."""
    if not len(points):
        return "-"
    (x0, y0), (x1, y1) = points.min(axis=0), points.max(axis=0)
    return f"({x0:.0f}, {y0:.0f}) to ({x1:.0f}, {y1:.0f})"


def _table(header: Sequence[object], rows: Sequence[Sequence[object]]) -> str:
    head = "".join(f"<th>{html.escape(str(h))}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in row) + "</tr>" for row in rows)
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def _grouping_table(grouping: Grouping) -> str:
    counts = grouping.junctions.counts()
    rows = [("curves", len(grouping.curves)), *((f"{kind} junctions", n) for kind, n in counts.items()),
            ("T-junctions repaired across a gap", int(np.count_nonzero(grouping.junctions.gap > 0))),
            ("T-junction pairs", len(grouping.pairs)), ("groups of curves", len(grouping.groups))]
    return _table(("what", "count"), rows)


def write_report(result: Result, folder: str | Path, *, title: str = "Vision Machine run",
                 evaluation: Mapping[str, Sequence[Sequence[object]]] | None = None) -> dict[str, Path]:
    """Write the run's PNGs and report.html (images inline) into ``folder`` (created if missing).

    Files of those names already in ``folder`` are never overwritten: the call is refused instead.

    Parameters
    ----------
    result : Result
    folder : str or Path
    title : str
    evaluation : mapping of table title to rows, optional
        Tables shown first (e.g. scores against ground truth); each table's first row is its header.

    Returns
    -------
    dict of str to Path
        Every file written, by stem ("report" for the HTML).
    """
    if not isinstance(title, str):
        raise InputTypeError(f"title must be a str, got {type(title).__name__}")
    if evaluation is not None and not isinstance(evaluation, Mapping):
        raise InputTypeError(f"evaluation must be a mapping of table title to rows, got {type(evaluation).__name__}")
    # Checked before anything is written: a page that fails half way leaves pictures the next call refuses.
    try:
        title.encode("utf-8")
    except UnicodeEncodeError:
        raise InputValueError("title holds characters UTF-8 cannot write (a lone surrogate)") from None
    for name, rows in (evaluation or {}).items():
        if (not isinstance(rows, Sequence) or isinstance(rows, str) or not rows
                or not all(isinstance(row, Sequence) and not isinstance(row, str) for row in rows)):
            raise InputValueError(f"evaluation[{name!r}] must be a table: a header row, then rows (sequences)")
    if not isinstance(folder, (str, Path)):
        raise InputTypeError(f"folder must be a str or Path, got {type(folder).__name__}")
    pictures = images_with_captions(result)
    folder = Path(folder)
    refuse_names_present(folder, {*(f"{stem}.png" for stem in pictures), "report.html"}.__contains__, "the report")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except (FileExistsError, NotADirectoryError):
        # The folder named, or one above it, is a file: refused before anything is written, the file untouched.
        raise InputValueError(f"folder {folder} is not a folder: it or a folder above it is a file") from None
    written = {}
    figures = []
    for stem, (picture, caption) in pictures.items():
        data = encode_png(picture)
        path = folder / f"{stem}.png"
        path.write_bytes(data)
        written[stem] = path
        inline = base64.b64encode(data).decode("ascii")
        figures.append(f'<figure><img alt="{html.escape(stem)}" src="data:image/png;base64,{inline}">'
                       f"<figcaption>{html.escape(caption)}</figcaption></figure>")
    sections = [f"<h1>{html.escape(title)}</h1>",
                (f"<p>{result.image.shape[1]} x {result.image.shape[0]} pixels, "
                 f"{html.escape(', '.join(result.stages))}; {result.total_ms:.0f} ms in all.</p>")]
    sections += [f"<p class=note>{html.escape(note)}</p>" for note in result.notes]
    for name, rows in (evaluation or {}).items():
        header, *body = rows
        sections.append(f"<h2>{html.escape(name)}</h2>" + _table(header, body))
    if result.grouping is not None:
        sections.append("<h2>Grouping</h2>" + _grouping_table(result.grouping))
    if result.recognition is not None:
        # Where each object lies: the box of its boundary in the image (its view's corner features, which
        # the picture draws, are many and repeat one another: a list of them says little).
        rows = [(d.name, d.view, f"{d.score:.2f}", f"{d.significance:.1f}",
                 "-" if np.isnan(d.inner_found) else f"{d.inner_found:.2f}", f"{d.corners_found:.2f}",
                 _box(d.boundary)) for d in result.recognition]
        sections.append("<h2>Recognition</h2>" + (_table(("object", "view", "score", "significance",
                                                          "inner markings found", "corners found",
                                                          "boundary's box (x, y) to (x, y)"), rows)
                                                  if rows else "<p>No object found.</p>"))
    sections.append("<h2>Fields</h2>" + "".join(figures))
    stage_rows = [(name, f"{ms:.1f}") for name, ms in result.stages.items()] + [("total", f"{result.total_ms:.1f}")]
    sections.append("<h2>Time per stage</h2>" + _table(("stage", "wall ms"), stage_rows))
    if result.kernels:
        ranked = sorted(result.kernels.items(), key=lambda item: -item[1]["total_ms"])
        rows = [(name, t["calls"], f"{t['total_ms']:.2f}", f"{t['mean_ms']:.3f}") for name, t in ranked]
        sections.append("<h2>Device time per kernel</h2>" + _table(("kernel", "calls", "total ms", "mean ms"), rows))
    params = [(f"{section}.{key}", value) for section, entries in result.config.to_dict().items()
              for key, value in entries.items()]
    sections.append("<h2>Parameters</h2>" + _table(("parameter", "value"), params))
    page = ("<!DOCTYPE html><html lang=en><head><meta charset=utf-8>"
            f"<title>{html.escape(title)}</title><style>"
            "body{font-family:sans-serif;margin:2em;max-width:80em}figure{display:inline-block;margin:0 1em 1em 0;"
            "vertical-align:top;max-width:32em}img{max-width:100%;image-rendering:pixelated}"
            "table{border-collapse:collapse;margin-bottom:1em}td,th{border:1px solid #ccc;padding:2px 8px;"
            "text-align:left}.note{color:#a40}</style></head><body>" + "".join(sections) + "</body></html>")
    path = folder / "report.html"
    path.write_text(page, encoding="utf-8")
    written["report"] = path
    return written
