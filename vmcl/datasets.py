"""Readers for the field's evaluation data: Middlebury stereo and flow, Yosemite, BSDS500.

The seed paper measures each module "on synthetic and natural images"; these readers give the natural
half, with the ground truth in vmcl's conventions (``vmcl.scenes`` gives the synthetic half):

- disparity of the left view, d >= 0 with ``I_left(x, y) = I_right(x - d, y)``, NaN where unknown;
- flow (u, v) with ``I_t(x, y) = I_t+1(x + u, y + v)``, NaN where unknown;
- masks as boolean arrays, True where a pixel is evaluated.

The layout and encodings are those of ``shared/datasets/README.md`` and each group's PROVENANCE.md
(Scharstein and Szeliski 2002 and 2003 for stereo, Baker et al. 2011 for flow, Barron, Fleet and
Beauchemin 1994 for Yosemite, Arbelaez et al. 2011 for BSDS500). The root folder is always an argument;
nothing is downloaded and nothing is silently resized or rescaled.
"""

from __future__ import annotations

import os
import sys
import tempfile
import zlib
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np
import scipy.io

from vmcl.cm.core import check_bool, check_choice, check_int, check_real, check_real_dtype, real_host_array
from vmcl.errors import InputTypeError, InputValueError

__all__ = [
    "FLOW_SCENES",
    "FLO_TAG",
    "STEREO_SCENES",
    "BSDSImage",
    "BSDSSet",
    "FlowPair",
    "StereoPair",
    "load_bsds",
    "load_flow",
    "load_stereo",
    "read_disparity",
    "read_flo",
    "read_image",
    "read_mask",
    "read_pfm",
    "write_flo",
    "write_pfm",
]

FLO_TAG = 202021.25
"""The float32 tag ("PIEH" in ASCII) that opens a Middlebury .flo file."""

_FLO_UNKNOWN_ABOVE = 1e9
# Middlebury's flowIO writes unknown vectors as 1e10 (UNKNOWN_FLOW in flowIO.h).
_FLO_UNKNOWN_WRITTEN = np.float32(1e10)


# --------------------------------------------------------------------------------------------- files


def _as_path(path, name: str = "path") -> Path:
    if not isinstance(path, (str, os.PathLike)):
        raise InputTypeError(f"{name} must be a str or an os.PathLike, got {type(path).__name__}")
    return Path(path)


def _existing(path) -> Path:
    path = _as_path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no such file: {path}")
    return path


def read_image(path) -> np.ndarray:
    """Read an 8- or 16-bit image (PNG, PPM/PGM, JPEG) as stored: (H, W) grey or (H, W, 3) RGB.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    ndarray
        uint8 or uint16; colour images in RGB order (OpenCV's BGR is reversed).

    Raises
    ------
    FileNotFoundError
        If the file does not exist.
    ValueError
        If it is a folder, cannot be decoded as an image, or is a PNG or JPEG cut short or corrupt
        (OpenCV would decode what it can and fill the rest with grey).
    """
    path = _as_path(path)
    if path.is_dir():
        raise InputValueError(f"{path} is a folder, not an image file")
    path = _existing(path)
    data = path.read_bytes()
    if not data:
        raise InputValueError(f"{path} is empty, not an image")
    if data.startswith(_PNG_SIGNATURE):
        damage = _png_damage(data)
    elif data.startswith(_JPEG_START):
        damage = _jpeg_damage(data)
    else:
        damage = None
    if damage is not None:
        raise InputValueError(f"{path} is damaged: {damage}")
    image, printed = _decode(data)
    warnings = [line for line in printed.splitlines() if line.startswith(_LIBJPEG_DAMAGE)]
    if warnings:
        raise InputValueError(f"{path} is damaged: its decoder says {warnings[0]!r}")
    if image is None:
        raise InputValueError(f"cannot decode an image from {path}")
    sys.stderr.write(printed)  # the decoders' other notes (e.g. libpng's about colour profiles) stay visible
    if image.ndim == 3:
        if image.shape[2] == 4:
            raise InputValueError(f"{path} has an alpha channel; expected grey or RGB")
        image = np.ascontiguousarray(image[..., ::-1])
    return image


_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
_JPEG_START = b"\xff\xd8\xff"  # start of image, then the first segment's marker
_LIBJPEG_DAMAGE = ("Corrupt JPEG data", "Premature end of JPEG file")  # libjpeg's warnings about bad data


def _png_damage(data: bytes) -> str | None:
    """Why a PNG is damaged (a chunk cut short or failing its CRC, no IEND chunk), or None."""
    at = len(_PNG_SIGNATURE)
    while at + 12 <= len(data):
        length = int.from_bytes(data[at:at + 4], "big")
        kind = data[at + 4:at + 8].decode("latin-1")
        end = at + 12 + length
        if end > len(data):
            break
        if zlib.crc32(data[at + 4:end - 4]) != int.from_bytes(data[end - 4:end], "big"):
            return f"its {kind} chunk at byte {at} fails its CRC check"
        if kind == "IEND":
            return None
        at = end
    return "it ends before its IEND chunk (cut short)"


def _jpeg_damage(data: bytes) -> str | None:
    """Why a JPEG is damaged (cut short in its headers, or no end-of-image marker after the scan), or None.

    The segments before the first scan carry their lengths, so an EXIF thumbnail's own end marker is
    stepped over; in the scans every 0xFF byte of data is followed by 0x00, so the first 0xFF 0xD9 after
    the scan starts is the image's end. Bytes after it (camera trailers) are allowed.
    """
    at = 2
    while at + 4 <= len(data):
        if data[at] != 0xFF:
            return f"no segment marker at byte {at}"
        marker = data[at + 1]
        if marker == 0xFF or 0xD0 <= marker <= 0xD8 or marker == 0x01:
            at += 1 if marker == 0xFF else 2  # fill bytes and the markers without a length
            continue
        if marker == 0xD9:
            return "it ends before any image data"
        if marker == 0xDA:
            if data.find(b"\xff\xd9", at) < 0:
                return "it has no end-of-image marker (cut short)"
            return None
        at += 2 + int.from_bytes(data[at + 2:at + 4], "big")
    return "it ends inside its headers (cut short)"


def _decode(data: bytes) -> tuple[np.ndarray | None, str]:
    """OpenCV's decoding of an image file's bytes, and what its decoders printed meanwhile.

    libjpeg reports corrupt or missing data only by printing a warning on the process's stderr (file
    descriptor 2, where the C libraries write), and OpenCV returns the image with the rest grey; so that
    descriptor is caught around the call.
    """
    array = np.frombuffer(data, np.uint8)
    sys.stderr.flush()
    try:
        saved = os.dup(2)
    except OSError:  # no stderr to catch (a daemon): decode without
        return cv2.imdecode(array, cv2.IMREAD_UNCHANGED), ""
    try:
        with tempfile.TemporaryFile() as caught:
            os.dup2(caught.fileno(), 2)
            try:
                image = cv2.imdecode(array, cv2.IMREAD_UNCHANGED)
            finally:
                os.dup2(saved, 2)
            caught.seek(0)
            return image, caught.read().decode(errors="replace")
    finally:
        os.close(saved)


def _single_channel(path) -> np.ndarray:
    """A grey map, also when stored as three identical channels (as several Middlebury PNGs are)."""
    image = read_image(_as_path(path))
    if image.ndim == 3:
        if not (image == image[..., :1]).all():
            raise InputValueError(f"{path} has three different channels; expected a single-channel map")
        image = image[..., 0]
    return image


def read_mask(path, *, value: int = 255) -> np.ndarray:
    """Read an evaluation mask: True where the stored grey level equals ``value``.

    Parameters
    ----------
    path : str or Path
        A Middlebury v2 mask (nonocc.png, all.png, disc.png) or any 8-bit mask.
    value : int
        The grey level meaning "evaluate" (255 for every Middlebury v2 mask; in disc.png, 255 marks
        pixels near depth discontinuities and 128 the other non-occluded pixels).

    Returns
    -------
    (H, W) bool array
    """
    check_int(value, "value", minimum=0)
    return _single_channel(path) == value


def read_pfm(path) -> np.ndarray:
    """Read a PFM file (Middlebury 2014 disparities) as float32, top row first, infinities as NaN.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    (H, W) or (H, W, 3) float32 array

    Notes
    -----
    PFM stores rows bottom to top; the sign of the scale field gives the byte order (negative: little
    endian). Middlebury marks unknown disparities with infinity, returned here as NaN.
    """
    path = _existing(path)
    with path.open("rb") as f:
        header = f.readline().strip()
        if header not in (b"PF", b"Pf"):
            raise InputValueError(f"{path} is not a PFM file (header {header[:8]!r})")
        dims = f.readline().split()
        scale_line = f.readline().strip()
        try:
            width, height = int(dims[0]), int(dims[1])
            scale = float(scale_line)
        except (IndexError, ValueError):
            raise InputValueError(f"{path} has a malformed PFM header") from None
        channels = 3 if header == b"PF" else 1
        dtype = "<f4" if scale < 0 else ">f4"
        data = np.frombuffer(f.read(), dtype=dtype)
    if data.size != width * height * channels:
        raise InputValueError(f"{path}: expected {width * height * channels} floats, found {data.size}")
    shape = (height, width, 3) if channels == 3 else (height, width)
    image = np.flipud(data.reshape(shape)).astype(np.float32)
    image[np.isinf(image)] = np.nan
    return image


def write_pfm(path, image) -> None:
    """Write a float image as little-endian PFM (NaN written as infinity, Middlebury's "unknown").

    Parameters
    ----------
    path : str or Path
    image : (H, W) or (H, W, 3) array
    """
    image = real_host_array(image, "image", ndims=(2, 3)).astype(np.float32)
    if image.ndim == 3 and image.shape[2] != 3:
        raise InputValueError(f"image must have shape (H, W) or (H, W, 3), got {image.shape}")
    header = b"PF" if image.ndim == 3 else b"Pf"
    data = np.where(np.isnan(image), np.float32(np.inf), image)
    with _as_path(path).open("wb") as f:
        f.write(header + b"\n" + f"{image.shape[1]} {image.shape[0]}\n-1.0\n".encode())
        f.write(np.flipud(data).astype("<f4").tobytes())


def read_disparity(path, *, scale: float | None = None, unknown: int | None = 0) -> np.ndarray:
    """Read a ground-truth disparity map in pixels, NaN where unknown.

    Parameters
    ----------
    path : str or Path
        An 8-bit PGM/PNG (disparity = grey / scale) or a PFM (disparity as stored).
    scale : float
        The grey levels per pixel of disparity (tsukuba 16; venus, sawtooth, map 8; teddy 4).
        Required for PGM/PNG, not allowed for PFM.
    unknown : int or None
        The grey level that means "unknown" (0 in every Middlebury map), or None if there is none.

    Returns
    -------
    (H, W) float32 array
    """
    path = _as_path(path)
    if unknown is not None:
        check_int(unknown, "unknown", minimum=0)
    if path.suffix.lower() == ".pfm":
        if scale is not None:
            raise InputValueError("scale applies to 8-bit maps; a PFM stores disparities directly")
        disparity = read_pfm(path)
        if disparity.ndim != 2:
            raise InputValueError(f"{path} holds a 3-channel PFM; expected one channel of disparities")
        return disparity
    if scale is None:
        raise InputValueError(f"scale must be a positive number for an 8-bit map such as {path.name}, got None")
    check_real(scale, "scale (grey levels per pixel of disparity)", above=0)
    grey = _single_channel(path)
    disparity = grey.astype(np.float32) / np.float32(scale)
    if unknown is not None:
        disparity[grey == unknown] = np.nan
    return disparity


def read_flo(path, *, raw: bool = False) -> np.ndarray:
    """Read a Middlebury .flo flow file as (H, W, 2) float32 (u, v), unknown vectors as NaN.

    Parameters
    ----------
    path : str or Path
    raw : bool
        Return the stored values unchanged, unknown vectors included (their stored magnitude exceeds
        1e9), for byte-exact copies.

    Returns
    -------
    (H, W, 2) float32 array

    Notes
    -----
    Format: float32 tag 202021.25, int32 width, int32 height, then u and v interleaved row by row, all
    little endian. A vector is unknown when ``|u| > 1e9`` or ``|v| > 1e9``.
    """
    path = _existing(path)
    check_bool(raw, "raw")
    data = path.read_bytes()
    if len(data) < 12 or np.frombuffer(data[:4], "<f4")[0] != FLO_TAG:
        raise InputValueError(f"{path} is not a .flo file (bad tag)")
    width, height = (int(v) for v in np.frombuffer(data[4:12], "<i4"))
    expected = 12 + 8 * width * height
    if width < 1 or height < 1 or len(data) != expected:
        raise InputValueError(f"{path}: header says {width}x{height}, i.e. {expected} bytes, file has {len(data)}")
    flow = np.frombuffer(data[12:], "<f4").reshape(height, width, 2).astype(np.float32)
    if not raw:
        flow[(np.abs(flow) > _FLO_UNKNOWN_ABOVE).any(axis=-1)] = np.nan
    return flow


def write_flo(path, flow) -> None:
    """Write (H, W, 2) flow as a Middlebury .flo file; NaN vectors are written as unknown (1e10).

    Parameters
    ----------
    path : str or Path
    flow : (H, W, 2) array
    """
    flow = check_real_dtype(flow, "flow")
    if flow.ndim != 3 or flow.shape[2] != 2 or flow.shape[0] < 1 or flow.shape[1] < 1:
        raise InputValueError(f"flow must have shape (H, W, 2), got {flow.shape}")
    flow = flow.astype("<f4")
    flow[np.isnan(flow).any(axis=-1)] = _FLO_UNKNOWN_WRITTEN
    header = np.array([FLO_TAG], "<f4").tobytes() + np.array(flow.shape[1::-1], "<i4").tobytes()
    _as_path(path).write_bytes(header + flow.tobytes())


# --------------------------------------------------------------------------------------------- stereo


@dataclass(frozen=True)
class StereoPair:
    """A rectified stereo pair with its left-view ground truth.

    Attributes
    ----------
    name : str
    left, right : ndarray
        uint8 images, (H, W, 3) RGB or (H, W) grey.
    disparity : (H, W) float32 array
        Left-view disparity in pixels, NaN where unknown.
    masks : dict of str to (H, W) bool array
        Middlebury v2 evaluation masks "nonocc", "all", "disc" where the data set has them.
    disparity_range : (float, float)
        Smallest and largest known disparity.
    scale : float
        Grey levels per pixel of disparity in the stored map.
    folder : Path
    """

    name: str
    left: np.ndarray
    right: np.ndarray
    disparity: np.ndarray
    masks: dict[str, np.ndarray]
    disparity_range: tuple[float, float]
    scale: float
    folder: Path


# name -> (group folder, left, right, ground truth, scale, whether the v2 masks are there)
_STEREO = {
    "tsukuba": ("middlebury_stereo_v2eval/tsukuba", "imL.png", "imR.png", "groundtruth.png", 16.0, True),
    "venus": ("middlebury_stereo_v2eval/venus", "imL.png", "imR.png", "groundtruth.png", 8.0, True),
    "teddy": ("middlebury_stereo_v2eval/teddy", "imL.png", "imR.png", "groundtruth.png", 4.0, True),
    "sawtooth": ("middlebury_stereo_2001/sawtooth", "im2.ppm", "im6.ppm", "disp2.pgm", 8.0, False),
    "map": ("middlebury_stereo_2001/map", "im0.pgm", "im1.pgm", "disp0.pgm", 8.0, False),
}
STEREO_SCENES = tuple(_STEREO)


def _lookup(name: str, table: dict, what: str):
    if not isinstance(name, str):
        raise InputTypeError(f"name must be the name of a {what} (a str), got {type(name).__name__}")
    key = name.lower()
    if key not in table:
        raise InputValueError(f"unknown {what} {name!r}; name must be one of {', '.join(table)}")
    return key, table[key]


def load_stereo(name: str, root) -> StereoPair:
    """Load a Middlebury stereo scene with its left-view disparity and evaluation masks.

    Parameters
    ----------
    name : str
        "tsukuba", "venus", "teddy" (Middlebury v2 set, with nonocc/all/disc masks), "sawtooth" or
        "map" (2001 set, no masks); case-insensitive.
    root : str or Path
        The data sets folder (``shared/datasets``).

    Returns
    -------
    StereoPair

    Notes
    -----
    Tsukuba's disparities are for the pair (col3, col4), scale 16, with 22,896 unknown border pixels;
    teddy's are quarter size, scale 4.

    Examples
    --------
    >>> pair = load_stereo("tsukuba", "../shared/datasets")  # doctest: +SKIP
    >>> pair.disparity_range, int(pair.masks["nonocc"].sum())  # doctest: +SKIP
    ((5.0, 14.0), 85438)

    References
    ----------
    D. Scharstein and R. Szeliski, IJCV 47:7-42, 2002 (tsukuba, venus, sawtooth, map) and CVPR 2003
    (teddy).
    """
    key, (folder, left, right, truth, scale, has_masks) = _lookup(name, _STEREO, "stereo scene")
    folder = _as_path(root, "root") / folder
    disparity = read_disparity(folder / truth, scale=scale)
    masks = {m: read_mask(folder / f"{m}.png") for m in ("nonocc", "all", "disc")} if has_masks else {}
    return StereoPair(
        name=key,
        left=read_image(folder / left),
        right=read_image(folder / right),
        disparity=disparity,
        masks=masks,
        disparity_range=(float(np.nanmin(disparity)), float(np.nanmax(disparity))),
        scale=scale,
        folder=folder,
    )


# --------------------------------------------------------------------------------------------- flow


@dataclass(frozen=True)
class FlowPair:
    """Two frames with the ground-truth flow from the first to the second.

    Attributes
    ----------
    name : str
    frame0, frame1 : ndarray
        uint8 frames, (H, W) grey or (H, W, 3) RGB.
    flow : (H, W, 2) float32 array
        (u, v) with ``frame0(x, y) = frame1(x + u, y + v)``; NaN where unknown.
    mask : (H, W) bool array
        Pixels to evaluate: known flow, and for Yosemite not the sky.
    folder : Path
    """

    name: str
    frame0: np.ndarray
    frame1: np.ndarray
    flow: np.ndarray
    mask: np.ndarray
    folder: Path


_FLOW = {
    "dimetrodon": "middlebury_flow/Dimetrodon",
    "grove2": "middlebury_flow/Grove2",
    "hydrangea": "middlebury_flow/Hydrangea",
    "rubberwhale": "middlebury_flow/RubberWhale",
    "venus": "middlebury_flow/Venus",
    "yosemite": "yosemite/yosemite",
}
FLOW_SCENES = ("Dimetrodon", "Grove2", "Hydrangea", "RubberWhale", "Venus", "Yosemite")


def load_flow(name: str, root, *, colour: bool = False) -> FlowPair:
    """Load a Middlebury flow sequence (or Yosemite) with its ground-truth flow.

    Parameters
    ----------
    name : str
        "Dimetrodon", "Grove2", "Hydrangea", "RubberWhale", "Venus" or "Yosemite"; case-insensitive.
    root : str or Path
        The data sets folder (``shared/datasets``).
    colour : bool
        Load RGB frames (RubberWhale only; the others are stored in grey).

    Returns
    -------
    FlowPair

    Notes
    -----
    Yosemite's sky has no real ground truth (it is a layer of evolving noise, stored as exactly
    (1, 0)); following the usual practice its mask excludes it.

    References
    ----------
    S. Baker et al., IJCV 92(1):1-31, 2011; J. L. Barron, D. J. Fleet, S. S. Beauchemin, IJCV
    12(1):43-77, 1994 (Yosemite).
    """
    key, folder = _lookup(name, _FLOW, "flow sequence")
    folder = _as_path(root, "root") / folder
    check_bool(colour, "colour")
    frames: tuple[str, ...]  # a pair of file names, under color/ for the colour frames
    if key == "yosemite":
        frames, truth = ("yos9.png", "yos10.png"), "correct_yos.flo"
    else:
        frames, truth = ("frame10.png", "frame11.png"), "flow10.flo"
    if colour:
        if key != "rubberwhale":
            raise InputValueError(f"colour frames exist only for RubberWhale, not {name!r}")
        frames = tuple(f"color/{f}" for f in frames)
    flow = read_flo(folder / truth)
    mask = np.isfinite(flow).all(axis=-1)
    if key == "yosemite":
        mask &= ~((flow[..., 0] == 1.0) & (flow[..., 1] == 0.0))
    return FlowPair(
        name=FLOW_SCENES[list(_FLOW).index(key)],
        frame0=read_image(folder / frames[0]),
        frame1=read_image(folder / frames[1]),
        flow=flow,
        mask=mask,
        folder=folder,
    )


# --------------------------------------------------------------------------------------------- BSDS


@dataclass(frozen=True)
class BSDSImage:
    """One BSDS500 image with its human annotations.

    Attributes
    ----------
    name : str
        The image id.
    image : (H, W, 3) uint8 array
    boundaries : (K, H, W) bool array
        Each of the K annotators' thin boundary map.
    segmentations : (K, H, W) uint16 array
        Each annotator's segment labels (1..n).
    edge_map : (H, W) float64 array or None
        For the golden set: the benchmark's own test edge map (png / 255).
    """

    name: str
    image: np.ndarray
    boundaries: np.ndarray
    segmentations: np.ndarray
    edge_map: np.ndarray | None = None


@dataclass(frozen=True)
class BSDSSet:
    """A set of BSDS500 images.

    Attributes
    ----------
    split : str
        "test" or "golden".
    images : list of BSDSImage
        In sorted (string) order of their ids.
    expected : dict of str to float
        For the golden set, the official benchmark's expected figures (bench/data/test_2/eval_bdry.txt):
        ods_threshold, ods_recall, ods_precision, ods_f, ois_recall, ois_precision, ois_f,
        average_precision. Empty for the test split.
    """

    split: str
    images: list[BSDSImage]
    expected: dict[str, float] = field(default_factory=dict)


_EXPECTED_KEYS = (
    "ods_threshold", "ods_recall", "ods_precision", "ods_f", "ois_recall", "ois_precision", "ois_f",
    "average_precision",
)


def _bsds_annotations(path: Path) -> tuple[np.ndarray, np.ndarray]:
    cells = scipy.io.loadmat(_existing(path))["groundTruth"][0]
    boundaries = np.stack([c["Boundaries"][0, 0].astype(bool) for c in cells])
    segmentations = np.stack([c["Segmentation"][0, 0].astype(np.uint16) for c in cells])
    return boundaries, segmentations


def load_bsds(root, *, split: str = "test") -> BSDSSet:
    """Load BSDS500 images with their human boundaries and segmentations.

    Parameters
    ----------
    root : str or Path
        The data sets folder (``shared/datasets``).
    split : {"test", "golden"}
        "test": the BSDS500 test images present under bsds500/test (10 here); "golden": the boundary
        benchmark's own 5-image test (bench/data) with its edge maps and expected figures.

    Returns
    -------
    BSDSSet

    References
    ----------
    P. Arbelaez, M. Maire, C. Fowlkes and J. Malik, "Contour detection and hierarchical image
    segmentation", IEEE TPAMI 33(5):898-916, 2011.
    """
    base = _as_path(root, "root") / "bsds500"
    check_choice(split, "split", ("test", "golden"))
    if split == "test":
        folders = sorted(p for p in (base / "test").glob("*") if p.is_dir())
        if not folders:
            raise FileNotFoundError(f"no BSDS500 test images under {base / 'test'}")
        images = [
            BSDSImage(f.name, read_image(f / f"{f.name}.jpg"), *_bsds_annotations(f / f"{f.name}.mat"))
            for f in folders
        ]
        return BSDSSet(split, images)
    if split != "golden":
        raise InputValueError(f"split must be 'test' or 'golden', got {split!r}")
    golden = base / "bench_golden"
    names = sorted(p.stem for p in (golden / "groundTruth").glob("*.mat"))
    if not names:
        raise FileNotFoundError(f"no golden ground truth under {golden / 'groundTruth'}")
    images = [
        BSDSImage(
            n,
            read_image(golden / "images" / f"{n}.jpg"),
            *_bsds_annotations(golden / "groundTruth" / f"{n}.mat"),
            edge_map=_single_channel(golden / "png" / f"{n}.png") / 255.0,
        )
        for n in names
    ]
    values = _existing(golden / "expected_test_2" / "eval_bdry.txt").read_text().split()
    if len(values) != len(_EXPECTED_KEYS):
        raise InputValueError(f"eval_bdry.txt holds {len(values)} numbers, expected {len(_EXPECTED_KEYS)}")
    return BSDSSet(split, images, dict(zip(_EXPECTED_KEYS, map(float, values))))

