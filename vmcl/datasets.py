"""Readers for the field's evaluation data: Middlebury stereo and flow, Yosemite, BSDS500.

The seed paper measures each module "on synthetic and natural images"; these readers give the natural
half, with the ground truth in vmcl's conventions (``vmcl.scenes`` gives the synthetic half):

- disparity of the left view, d >= 0 with ``I_left(x, y) = I_right(x - d, y)``, NaN where unknown;
- flow (u, v) with ``I_t(x, y) = I_t+1(x + u, y + v)``, NaN where unknown;
- masks as boolean arrays, True where a pixel is evaluated.

The layout and encodings are those of ``shared/datasets/README.md`` and each group's PROVENANCE.md
(Scharstein and Szeliski 2002 and 2003 for stereo, Baker et al. 2011 for flow, Barron, Fleet and
Beauchemin 1994 for Yosemite, Arbelaez et al. 2011 for BSDS500). The root folder is always an argument;
nothing is downloaded and nothing is silently resized or rescaled. A stereo scene in any Middlebury layout
(2001, 2003, v2 evaluation, 2005/2006, 2014/2021) is read by its folder's path (``read_stereo_folder``,
``find_stereo_folders``), whatever its name; ``load_stereo`` names the shared ones.
"""

from __future__ import annotations

import math
import os
import re
import sys
import tempfile
import zlib
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path

import cv2
import numpy as np
import scipy.io

from vmcl.cm.core import (
    check_bool,
    check_choice,
    check_int,
    check_real,
    check_real_dtype,
    full_scale,
    real_host_array,
)
from vmcl.errors import InputTypeError, InputValueError

__all__ = [
    "DEEPER_LEVELS",
    "FLOW_SCENES",
    "FLO_TAG",
    "FLO_UNKNOWN_ABOVE",
    "IMAGE_SUFFIXES",
    "PNG_SIGNATURE",
    "SINTEL_FIELD_FOLDERS",
    "STEREO_SCENES",
    "BSDSImage",
    "BSDSSet",
    "FlowPair",
    "FlowSequence",
    "StereoPair",
    "find_bsds_folders",
    "find_flow_folders",
    "find_stereo_folders",
    "flow_folders_lacking",
    "from_opencv",
    "load_bsds",
    "load_flow",
    "load_stereo",
    "read_bsds_folder",
    "read_disparity",
    "read_flo",
    "read_flow_folder",
    "read_image",
    "read_mask",
    "read_pfm",
    "read_stereo_folder",
    "stereo_folders_lacking",
    "stereo_views",
    "write_flo",
    "write_pfm",
    "write_stereo_folder",
]

FLO_TAG = 202021.25
"""The float32 tag ("PIEH" in ASCII) that opens a Middlebury .flo file."""

FLO_UNKNOWN_ABOVE = 1e9
"""A .flo vector whose component exceeds this in magnitude is unknown (Middlebury's flowIO convention)."""
# Middlebury's flowIO writes unknown vectors as 1e10 (UNKNOWN_FLOW in flowIO.h).
_FLO_UNKNOWN_WRITTEN = np.float32(1e10)


# --------------------------------------------------------------------------------------------- files


def _as_path(path, name: str = "path") -> Path:
    if not isinstance(path, (str, os.PathLike)):
        raise InputTypeError(f"{name} must be a str or an os.PathLike, got {type(path).__name__}")
    return Path(path)


def _existing(path, what: str = "a file") -> Path:
    """``path`` checked to be a file: a folder is refused as a bad value (it exists, so "no such file" would
    mislead), anything else missing as FileNotFoundError; ``what`` says which file was wanted."""
    path = _as_path(path)
    if path.is_dir():
        raise InputValueError(f"{path} is a folder, not {what}")
    if not path.is_file():
        raise FileNotFoundError(f"no such file: {path}")
    return path


IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".ppm", ".pgm", ".pbm", ".pnm", ".bmp", ".tif", ".tiff", ".webp")
"""The file suffixes (any case) of images :func:`read_image` reads: what a folder of frames, a batch's input
folder or a flow folder's numbered frames are taken from."""


def read_image(path, *, picture: bool = False, check: Callable[[Path, bytes], None] | None = None) -> np.ndarray:
    """Read an image as stored (PNG, PPM/PGM, JPEG, BMP, WebP, TIFF ..., what OpenCV reads): (H, W) grey or
    (H, W, 3) RGB; a JPEG turned upright as its EXIF orientation says (as viewers show it).

    Parameters
    ----------
    path : str or Path
    picture : bool
        Read a picture's brightness: a PGM or PPM whose declared maximum (its header's maxval) lies below its
        type's full scale is scaled to that scale, as viewers show it (a 10-bit PGM's 1023 is white, not
        1/64 of it). False (the default): the values as stored, as maps of data (a disparity, a mask) need.
    check : callable, optional
        ``check(path, data)``, run on the file's bytes before they are decoded: a caller's own refusal, such
        as :mod:`vmcl.frame_sources`' of a frame file that holds several pages, which then need not open the
        file again. It refuses by raising and returns None; any other return is refused (a predicate's
        False would otherwise refuse nothing).

    Returns
    -------
    ndarray
        As stored: uint8 or uint16 for 8- and 16-bit files, float32 (or float64) for a TIFF or PFM of floats,
        and a TIFF's other types (signed integers) as OpenCV gives them; colour images in RGB order (OpenCV's
        BGR is reversed).

    Raises
    ------
    FileNotFoundError
        If the file does not exist.
    ValueError
        If it is a folder, cannot be decoded as an image, is larger than OpenCV's limits, or is a PNG or
        JPEG cut short or corrupt (OpenCV would decode what it can and fill the rest with grey).
    """
    if check is not None and not callable(check):
        raise InputTypeError(f"check must be a callable (path, data) or None, got {type(check).__name__}")
    path = _existing(path, "an image file")
    data = path.read_bytes()
    if check is not None and (returned := check(path, data)) is not None:
        raise InputTypeError(f"check must refuse by raising and return None, got {returned!r}")
    refusal = _refused_undecoded(data)
    if refusal is not None:
        raise InputValueError(f"{path} {refusal}")
    try:
        image, printed = _decode(data)
    except cv2.error as error:
        # OpenCV refuses by a failed assertion, not None, an image over its size limits (which its header
        # declares, however small the file) and some damage the checks above do not see.
        limit = re.search(r"CV_IO_MAX_IMAGE_\w+", str(error))
        if limit is not None:
            raise InputValueError(f"{path} is larger than OpenCV decodes: over its limit {limit.group()} (by "
                                  "default 2^30 pixels, 2^20 columns or rows)") from None
        raise InputValueError(f"cannot decode an image from {path} ({' '.join(str(error).split())})") from None
    warnings = [line for line in printed.splitlines() if line.startswith(_LIBJPEG_DAMAGE)]
    if warnings:
        raise InputValueError(f"{path} is damaged: its decoder says {warnings[0]!r}")
    if image is None:
        raise InputValueError(f"cannot decode an image from {path}")
    sys.stderr.write(printed)  # the decoders' other notes (e.g. libpng's about colour profiles) stay visible
    image = from_opencv(image, name=str(path))
    if check_bool(picture, "picture") and (maxval := _pnm_maxval(data)) is not None:
        full = np.iinfo(image.dtype).max
        if int(image.max(initial=0)) > maxval:
            raise InputValueError(f"{path} holds values up to {int(image.max())} above its declared maximum {maxval}")
        if maxval < full:
            image = np.round(image.astype(np.float64) * (full / maxval)).astype(image.dtype)
    return image


_ALPHA_REFUSED = "has an alpha channel; expected grey or RGB"


def from_opencv(image: np.ndarray, *, name: str = "image", opaque_alpha: bool = False) -> np.ndarray:
    """An image as OpenCV decodes it (colour in BGR order), as vmcl returns one: grey, or colour in RGB order,
    contiguous. An alpha channel is refused, naming ``name``; with ``opaque_alpha`` it is dropped where it is
    opaque at every pixel, as OpenCV gives an animation's frames one, and refused where it is not (a
    transparent pixel has no colour to take). Not for an image already in RGB order: its channels would be
    reversed."""
    if not isinstance(name, str):
        raise InputTypeError(f"name must be a str, got {type(name).__name__}")
    real_host_array(image, name, ndims=(2, 3))
    if image.ndim == 3 and image.shape[2] not in (3, 4):
        raise InputValueError(f"{name} must be (H, W), (H, W, 3) or (H, W, 4), got shape {image.shape}")
    if image.ndim == 3:
        if image.shape[2] == 4:
            if not opaque_alpha:
                raise InputValueError(f"{name} {_ALPHA_REFUSED}")
            if float(image[..., 3].min()) < full_scale(image.dtype):
                raise InputValueError(f"{name} has transparent pixels; expected grey or RGB")
            image = image[..., :3]
        image = image[..., ::-1]
    return np.ascontiguousarray(image)


def _refused_undecoded(data: bytes) -> str | None:
    """Why :func:`read_image` refuses a file from its bytes alone, before decoding them, said after its name
    ("is damaged: ..."): empty, a PNG or JPEG cut short or corrupt (OpenCV would decode what it can and fill
    the rest with grey), or a PNG whose header declares an alpha channel; None where they pass."""
    if not data:
        return "is empty, not an image"
    if data.startswith(PNG_SIGNATURE):
        damage = _png_damage(data)
    elif data.startswith(_JPEG_START):
        damage = _jpeg_damage(data)
    else:
        damage = None
    if damage is not None:
        return f"is damaged: {damage}"
    # IHDR comes first; its colour types 4 and 6 are grey and RGB with alpha.
    if data.startswith(PNG_SIGNATURE) and data[12:16] == b"IHDR" and len(data) > 25 and data[25] in (4, 6):
        return _ALPHA_REFUSED
    return None


def _pnm_maxval(data: bytes) -> int | None:
    """A grey or colour PNM's (P2, P3, P5, P6) declared maximum value, None for other files."""
    if data[:2] not in (b"P2", b"P3", b"P5", b"P6"):
        return None
    words: list[bytes] = []
    for line in data[2:2048].splitlines():
        words += line.split(b"#", 1)[0].split()
        if len(words) >= 3:
            return int(words[2]) if words[2].isdigit() and int(words[2]) > 0 else None
    return None


PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
"""The eight bytes a PNG file starts with."""
_JPEG_START = b"\xff\xd8\xff"  # start of image, then the first segment's marker
_LIBJPEG_DAMAGE = ("Corrupt JPEG data", "Premature end of JPEG file")  # libjpeg's warnings about bad data


def _png_damage(data: bytes) -> str | None:
    """Why a PNG is damaged (a chunk cut short or failing its CRC, no IEND chunk), or None."""
    at = len(PNG_SIGNATURE)
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
    # IMREAD_UNCHANGED keeps depth and alpha but skips the EXIF orientation; a JPEG (no alpha) is decoded as
    # OpenCV turns it upright: a camera stores its pictures as its sensor lay, and a portrait photograph read
    # as stored was matched along its columns.
    flags = cv2.IMREAD_ANYCOLOR | cv2.IMREAD_ANYDEPTH if data.startswith(_JPEG_START) else cv2.IMREAD_UNCHANGED
    sys.stderr.flush()
    try:
        saved = os.dup(2)
    except OSError:  # no stderr to catch (a daemon): decode without
        return cv2.imdecode(array, flags), ""
    try:
        with tempfile.TemporaryFile() as caught:
            os.dup2(caught.fileno(), 2)
            try:
                image = cv2.imdecode(array, flags)
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
    path = _existing(path, "a PFM file")
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
        if width < 1 or height < 1 or len(dims) != 2 or not math.isfinite(scale):
            raise InputValueError(f"{path} has a malformed PFM header: size {width} x {height}, scale {scale:g} "
                                  "(a size of at least 1 x 1 and a finite scale, its sign the byte order)")
        channels = 3 if header == b"PF" else 1
        dtype = "<f4" if scale < 0 else ">f4"
        raw = f.read()
    expected = width * height * channels
    if len(raw) != 4 * expected:
        raise InputValueError(f"{path}: expected {expected} floats ({4 * expected} bytes), found {len(raw)} bytes")
    data = np.frombuffer(raw, dtype=dtype)
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


def write_stereo_folder(folder, left, right, disparity, *, ndisp: int | None = None) -> Path:
    """Write a stereo pair and its disparity as a Middlebury 2014-layout scene folder, which
    :func:`read_stereo_folder` reads back (rendered scenes as data sets, for ``vmcl eval stereo`` or
    ``vmcl batch``).

    Parameters
    ----------
    folder : str or Path
        A new or empty folder (made with its parents if missing): vmcl writes only its own files.
    left, right : (H, W) or (H, W, 3) arrays of one shape
        uint8 as they are, or floats in [0, 1] (as :mod:`vmcl.scenes` renders them), rounded to 8 bits.
    disparity : (H, W) float array
        The left view's disparity, >= 0 (vmcl's convention), NaN where unknown (written as infinity,
        Middlebury's unknown).
    ndisp : int, optional
        calib.txt's disparity count; default: the largest finite disparity rounded up, plus one.

    Returns
    -------
    Path
        The folder: im0.png, im1.png, disp0.pfm and calib.txt.
    """
    folder = _as_path(folder, "folder")
    if folder.exists() and (not folder.is_dir() or any(folder.iterdir())):
        raise InputValueError(f"folder must be new or empty, got {folder}")
    images = []
    for name, image in (("left", left), ("right", right)):
        image = real_host_array(image, name, ndims=(2, 3))
        if image.ndim == 3 and image.shape[2] != 3:
            raise InputValueError(f"{name} must be grey (H, W) or RGB (H, W, 3), got shape {image.shape}")
        if image.dtype != np.uint8:
            image = image.astype(np.float64)  # other integer types would overflow when scaled
            if not (np.isfinite(image).all() and image.min() >= 0 and image.max() <= 1):
                raise InputValueError(f"{name} must be uint8 or floats in [0, 1]")
            image = np.round(image * 255).astype(np.uint8)
        images.append(image)
    if images[0].shape != images[1].shape:
        raise InputValueError(f"left and right must have the same shape, got {images[0].shape} and {images[1].shape}")
    truth = real_host_array(disparity, "disparity", ndims=(2,)).astype(np.float32)
    if truth.shape != images[0].shape[:2]:
        raise InputValueError(f"disparity must have the images' shape {images[0].shape[:2]}, got {truth.shape}")
    finite = truth[np.isfinite(truth)]
    if finite.size and finite.min() < 0:
        # Checked before ndisp's default (the largest disparity plus one), which would otherwise be refused
        # as an ndisp the caller never gave.
        raise InputValueError(f"disparity must be >= 0 where known (the left view's, I_left(x, y) = "
                              f"I_right(x - d, y)), got values down to {float(finite.min()):g}")
    if ndisp is None:
        ndisp = int(np.ceil(finite.max())) + 1 if finite.size else 1
    ndisp = check_int(ndisp, "ndisp", minimum=1)
    folder.mkdir(parents=True, exist_ok=True)
    for path, image in ((folder / "im0.png", images[0]), (folder / "im1.png", images[1])):
        written = cv2.imwrite(str(path), cv2.cvtColor(image, cv2.COLOR_RGB2BGR) if image.ndim == 3 else image)
        if not written:
            raise OSError(f"cannot write {path}")
    write_pfm(folder / "disp0.pfm", truth)
    (folder / "calib.txt").write_text(f"ndisp={ndisp}\n")
    return folder


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

    Raises
    ------
    ValueError
        If a PGM/PNG is not 8-bit, ``scale`` is missing for one or given for a PFM, or a PFM has 3 channels.
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
    if grey.dtype != np.uint8:
        # Middlebury's maps are 8-bit; a 16-bit map's levels divided by an 8-bit scale would give disparities
        # far wider than the image (and other sets' 16-bit maps, KITTI's, have their own encoding).
        raise InputValueError(f"{path} is a {8 * grey.dtype.itemsize}-bit map; expected an 8-bit PGM/PNG "
                              "(disparity = grey / scale) or a PFM (disparities as stored)")
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

    Raises
    ------
    FileNotFoundError
        If there is no such file.
    ValueError
        If ``path`` is a folder, or the file is not a .flo file or is cut short.

    Notes
    -----
    Format: float32 tag 202021.25, int32 width, int32 height, then u and v interleaved row by row, all
    little endian. A vector is unknown when ``|u| > 1e9`` or ``|v| > 1e9``.
    """
    path = _existing(path, "a .flo file")
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
        flow[(np.abs(flow) > FLO_UNKNOWN_ABOVE).any(axis=-1)] = np.nan
    return flow


def write_flo(path, flow) -> None:
    """Write (H, W, 2) flow as a Middlebury .flo file; NaN vectors are written as unknown (1e10).

    Parameters
    ----------
    path : str or Path
    flow : (H, W, 2) integer or float array
        Stored as float32.

    Raises
    ------
    TypeError
        If ``flow`` is not a NumPy array of numbers (a bool array is refused: it holds no displacement).
    ValueError
        If its shape is not (H, W, 2), or it holds a finite value beyond float32's range (about 3.4e38),
        which would be stored as infinity and read back as unknown.

    Notes
    -----
    The format marks whole vectors unknown, not components: a vector with one NaN component is written
    as unknown as a whole (both components 1e10) and read back as (NaN, NaN). Any stored component above
    1e9 in magnitude, infinities included, makes its vector unknown to :func:`read_flo`; such values
    are written as given (Middlebury's own unknown, 1e10, copies byte for byte).
    """
    flow = check_real_dtype(flow, "flow")
    if flow.dtype.kind == "b":
        raise InputTypeError("flow must hold numbers (integer or float), got dtype bool")
    if flow.ndim != 3 or flow.shape[2] != 2 or flow.shape[0] < 1 or flow.shape[1] < 1:
        raise InputValueError(f"flow must have shape (H, W, 2), got {flow.shape}")
    with np.errstate(over="ignore"):  # the overflow is refused below, by name, not left to NumPy's warning
        stored = flow.astype("<f4")
    overflow = np.isinf(stored) & np.isfinite(flow)
    if overflow.any():
        raise InputValueError(f"flow holds {flow[overflow][0]:g}, beyond float32's range (about 3.4e38) that a "
                              ".flo file stores: it would be written as infinity and read back as unknown")
    flow = stored
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
        Images as stored: (H, W, 3) RGB or (H, W) grey, uint8 (uint16 where a file holds 16 bits).
    disparity : (H, W) float32 array
        Left-view disparity in pixels, NaN where unknown.
    masks : dict of str to (H, W) bool array
        Evaluation masks where the data set has them: Middlebury v2's "nonocc", "all", "disc"; for a
        2014 folder with mask0nocc.png, "nonocc" and "all". Empty when it has none.
    disparity_range : (float, float)
        Smallest and largest known disparity.
    scale : float
        Grey levels per pixel of disparity in the stored map (1 for a PFM, which stores disparities).
    folder : Path
    published_disparities : int or None
        The number of disparities the data set publishes for the pair (0 .. n - 1): info.txt's maximum
        disparity plus one, or calib.txt's ``ndisp``; None where the folder publishes none.
    """

    name: str
    left: np.ndarray
    right: np.ndarray
    disparity: np.ndarray
    masks: dict[str, np.ndarray]
    disparity_range: tuple[float, float]
    scale: float
    folder: Path
    published_disparities: int | None = None


def _stereo_pair(folder: Path, left: Path, right: Path, disparity: np.ndarray, truth: Path, *, scale: float,
                 masks: dict[str, np.ndarray] | None = None, published: int | None = None,
                 left_image: np.ndarray | None = None) -> StereoPair:
    """A StereoPair from files already found (the left image already read, where given), its sizes and
    masks checked against the ground truth."""
    left_image = read_image(left) if left_image is None else left_image
    right_image = read_image(right)
    if left_image.shape != right_image.shape:
        raise InputValueError(f"{folder}: {left.name} is {left_image.shape} and {right.name} is "
                              f"{right_image.shape}; a stereo pair must have one size")
    if disparity.shape != left_image.shape[:2]:
        raise InputValueError(f"{folder}: {truth.name} is {disparity.shape}, the images "
                              f"{left_image.shape[:2]}; the ground truth must have the images' size")
    known = np.isfinite(disparity)
    if not known.any():
        raise InputValueError(f"{truth} holds no known disparity")
    masks = masks or {}
    for mask_name, mask in masks.items():
        # The evaluation needs the truth wherever a mask says "evaluate".
        if mask.shape != known.shape or (mask & ~known).any():
            raise InputValueError(f"{folder}: the {mask_name} mask does not lie within the known ground truth "
                                  f"of {truth.name}")
    return StereoPair(
        name=folder.name,
        left=left_image,
        right=right_image,
        disparity=disparity,
        masks=masks,
        disparity_range=(float(np.nanmin(disparity)), float(np.nanmax(disparity))),
        scale=scale,
        folder=folder,
        published_disparities=published,
    )


def _numbers_file(path: Path) -> list[str]:
    return path.read_text(encoding="ascii", errors="replace").split()


def _read_v2(folder: Path, files: list[Path]) -> StereoPair:
    left, right, truth, info = files
    words = _numbers_file(info)
    try:
        scale = float(words[0])
        published = int(words[1]) + 1 if len(words) > 1 else None
    except (IndexError, ValueError):
        raise InputValueError(f"{info} must hold the ground truth's scale on its first line and the maximum "
                              f"disparity on its second, got {' '.join(words)[:40]!r}") from None
    disparity = read_disparity(truth, scale=scale)
    masks = {m: read_mask(folder / f"{m}.png") for m in ("nonocc", "all", "disc") if (folder / f"{m}.png").is_file()}
    if published is not None and published < 1:
        raise InputValueError(f"{info}: the maximum disparity on its second line must be >= 0, got {published - 1}")
    return _stereo_pair(folder, left, right, disparity, truth, scale=scale, masks=masks, published=published)


def _calibration(path: Path) -> dict[str, str]:
    """calib.txt's ``key=value`` lines (Middlebury 2014 and 2021)."""
    entries = {}
    for line in path.read_text(encoding="ascii", errors="replace").splitlines():
        key, sep, value = line.partition("=")
        if sep:
            entries[key.strip()] = value.strip()
    return entries


def _read_2014(folder: Path, files: list[Path]) -> StereoPair:
    left, right, truth, calib = files
    entries = _calibration(calib)
    published = None
    if "ndisp" in entries:
        try:
            published = int(entries["ndisp"])
        except ValueError:
            raise InputValueError(f"{calib}: ndisp must be an integer, got {entries['ndisp']!r}") from None
        if published < 1:
            raise InputValueError(f"{calib}: ndisp must be >= 1, got {published}")
    disparity = read_disparity(truth)
    masks = {}
    mask_file = folder / "mask0nocc.png"
    if mask_file.is_file():
        # MiddEval3's mask: 255 non-occluded, 128 occluded, 0 no ground truth; its "all" is 255 and 128.
        levels = _single_channel(mask_file)
        masks = {"nonocc": levels == 255, "all": (levels == 255) | (levels == 128)}
    return _stereo_pair(folder, left, right, disparity, truth, scale=1.0, masks=masks, published=published)


# The 2005 and 2006 sets were published in three sizes (their pages: full size 1240 to 1396 pixels wide and
# 1110 high, half size 620 to 698 by 555, third size 413 to 465 by 370), and disp1.png holds the disparity
# of the full-size pair at every size: divided by 2 at half size and by 3 at third size.
_SIZES_2005 = ((400, 470, 3.0, "third"), (600, 700, 2.0, "half"), (1200, 1400, 1.0, "full"))


def _read_2005(folder: Path, files: list[Path]) -> StereoPair:
    left, right, truth = files
    image = read_image(left)
    width = image.shape[1]
    for low, high, scale, _ in _SIZES_2005:
        if low <= width <= high:
            break
    else:
        sizes = ", ".join(f"{size} size {low} to {high} px wide" for low, high, _, size in _SIZES_2005)
        raise InputValueError(f"{left} is {width} px wide, not a size the 2005/2006 sets were published in "
                              f"({sizes}); the scale of {truth.name} cannot be decided")
    disparity = read_disparity(truth, scale=scale)
    return _stereo_pair(folder, left, right, disparity, truth, scale=scale, left_image=image)


def _read_tsukuba(folder: Path, files: list[Path]) -> StereoPair:
    left, right, truth = files
    return _stereo_pair(folder, left, right, read_disparity(truth, scale=16.0), truth, scale=16.0)


# The im2/im6/disp2 layout is shared by the 2001 sets (about 434 x 383, scale 8) and the 2003 sets (quarter
# size 450 x 375, scale 4; half size 900 x 750, scale 2): the size tells them apart.
_SIZES_IM2 = (((450, 450), (375, 375), 4.0), ((900, 900), (750, 750), 2.0), ((430, 435), (380, 383), 8.0))


def _read_im2(folder: Path, files: list[Path]) -> StereoPair:
    left, right, truth = files
    image = read_image(left)
    height, width = image.shape[:2]
    for (w_low, w_high), (h_low, h_high), scale in _SIZES_IM2:
        if w_low <= width <= w_high and h_low <= height <= h_high:
            break
    else:
        raise InputValueError(f"{left} is {width} x {height}, not a size the 2001 sets (about 434 x 383, scale 8) "
                              f"or the 2003 sets (450 x 375, scale 4; 900 x 750, scale 2) were published in; "
                              f"the scale of {truth.name} cannot be decided")
    return _stereo_pair(folder, left, right, read_disparity(truth, scale=scale), truth, scale=scale,
                        left_image=image)


def _read_map(folder: Path, files: list[Path]) -> StereoPair:
    left, right, truth = files
    return _stereo_pair(folder, left, right, read_disparity(truth, scale=8.0), truth, scale=8.0)


@dataclass(frozen=True)
class _Layout:
    description: str
    files: tuple[tuple[str, ...], ...]  # each file the layout needs, by its accepted names
    read: Callable[[Path, list[Path]], StereoPair]


# Tried in this order; the first whose files are all there reads the folder.
_LAYOUTS = (
    _Layout("Middlebury v2 evaluation: imL.png, imR.png, groundtruth.png, info.txt (masks nonocc.png, all.png, "
            "disc.png where given)", (("imL.png",), ("imR.png",), ("groundtruth.png",), ("info.txt",)), _read_v2),
    _Layout("Middlebury 2014/2021: im0.png, im1.png, disp0.pfm or disp0GT.pfm, calib.txt (mask0nocc.png where "
            "given)", (("im0.png",), ("im1.png",), ("disp0.pfm", "disp0GT.pfm"), ("calib.txt",)), _read_2014),
    _Layout("Middlebury 2005/2006: view1.png, view5.png, disp1.png",
            (("view1.png",), ("view5.png",), ("disp1.png",)), _read_2005),
    _Layout("Middlebury 2001 tsukuba: scene1.row3.col3.ppm, scene1.row3.col4.ppm, truedisp.row3.col3.pgm",
            (("scene1.row3.col3.ppm",), ("scene1.row3.col4.ppm",), ("truedisp.row3.col3.pgm",)), _read_tsukuba),
    _Layout("Middlebury 2001/2003: im2 and im6 (.ppm or .png), disp2 (.pgm or .png)",
            (("im2.ppm", "im2.png"), ("im6.ppm", "im6.png"), ("disp2.pgm", "disp2.png")), _read_im2),
    _Layout("Middlebury 2001 map: im0.pgm, im1.pgm, disp0.pgm", (("im0.pgm",), ("im1.pgm",), ("disp0.pgm",)),
            _read_map),
)


def _stereo_layout(folder: Path) -> tuple[_Layout, list[Path]] | None:
    """The first layout whose files are all in ``folder``, with the files found; None if there is none."""
    for layout in _LAYOUTS:
        found = [next((folder / n for n in names if (folder / n).is_file()), None) for names in layout.files]
        if all(path is not None for path in found):
            return layout, [path for path in found if path is not None]
    return None


def read_stereo_folder(folder) -> StereoPair:
    """Read the stereo pair and left-view ground truth of one scene folder in a Middlebury layout.

    The layout is found from the files the folder holds (the first of these that fits):

    - Middlebury v2 evaluation: imL.png, imR.png, groundtruth.png (grey / info.txt's first line), info.txt
      (its second line, the maximum disparity, plus one gives ``published_disparities``), and the masks
      nonocc.png, all.png, disc.png where given (255 = evaluate);
    - 2014 and 2021: im0.png, im1.png, disp0.pfm or disp0GT.pfm (infinity = unknown), calib.txt
      (``ndisp`` gives ``published_disparities``); mask0nocc.png where given gives "nonocc" (255) and
      "all" (255 or 128, MiddEval3's pixels with ground truth);
    - 2005 and 2006: view1.png, view5.png, disp1.png; disp1 holds the full-size disparity at every size
      the sets were published in, so the scale is decided from the image width as those pages state the
      sizes: 1200 to 1400 px wide (full size, 1240 to 1396) scale 1, 600 to 700 (half size, 620 to 698)
      scale 2, 400 to 470 (third size, 413 to 465) scale 3; another width is refused;
    - 2001 tsukuba: scene1.row3.col3.ppm, scene1.row3.col4.ppm, truedisp.row3.col3.pgm (scale 16);
    - 2001 and 2003: im2, im6 (.ppm or .png), disp2 (.pgm or .png); the size decides the scale: 2001's
      sets (430 to 435 x 380 to 383) 8, 2003's quarter size (450 x 375) 4, half size (900 x 750) 2;
    - 2001 map: im0.pgm, im1.pgm, disp0.pgm (scale 8).

    Grey level 0 of an 8-bit map means "unknown". Nothing is resized or rescaled beyond the scale.

    Parameters
    ----------
    folder : str or Path
        One scene's folder, under any name.

    Returns
    -------
    StereoPair
        Named after the folder.

    Raises
    ------
    FileNotFoundError
        If the folder does not exist.
    ValueError
        If it matches no layout (the message names the folder and the layouts looked for), or its files
        disagree (sizes, a mask outside the known ground truth, an unreadable info.txt or calib.txt).

    Examples
    --------
    >>> pair = read_stereo_folder("../shared/datasets/middlebury_stereo_v2eval/teddy")  # doctest: +SKIP
    >>> pair.scale, pair.published_disparities, sorted(pair.masks)  # doctest: +SKIP
    (4.0, 60, ['all', 'disc', 'nonocc'])

    References
    ----------
    D. Scharstein and R. Szeliski, IJCV 47:7-42, 2002 (2001 sets) and CVPR 2003 (2003 sets); D. Scharstein
    and C. Pal, CVPR 2007, and H. Hirschmüller and D. Scharstein, CVPR 2007 (2005 and 2006 sets);
    D. Scharstein et al., GCPR 2014 (2014 sets).
    """
    folder = _as_path(folder, "folder")
    if not folder.exists():
        raise FileNotFoundError(f"no such folder: {folder}")
    if not folder.is_dir():
        raise InputValueError(f"folder must be a scene's folder, got the file {folder}")
    found = _stereo_layout(folder)
    if found is None:
        looked_for = "; ".join(layout.description for layout in _LAYOUTS)
        raise InputValueError(f"folder {folder} holds no stereo pair in a Middlebury layout; looked for {looked_for}")
    layout, files = found
    return layout.read(folder, files)


def find_stereo_folders(root, *, depth: int = 4) -> list[Path]:
    """The scene folders in a Middlebury layout at or below ``root``.

    Parameters
    ----------
    root : str or Path
        A scene folder (returned alone), or a folder holding scene folders at any depth up to ``depth``
        (a data sets folder such as ``shared/datasets``).
    depth : int
        How many levels below ``root`` are searched (>= 1). A scene folder's subfolders are not.

    Returns
    -------
    list of Path
        Sorted; empty when there is none. Hidden folders (names starting with ".") are skipped.

    Raises
    ------
    FileNotFoundError
        If ``root`` is not a folder.
    """
    return _find_folders(root, depth, lambda folder: _stereo_layout(folder) is not None)


def _stereo_lack(folder: Path) -> str | None:
    """What a folder holding a layout's two views lacks of that layout's other files (its ground truth,
    calib.txt, info.txt), said in words; None when it holds no layout's views, or a whole layout."""
    if _stereo_layout(folder) is not None:
        return None
    for layout in _LAYOUTS:
        views, rest = layout.files[:2], layout.files[2:]
        if all(any((folder / n).is_file() for n in names) for names in views):
            missing = [" or ".join(names) for names in rest if not any((folder / n).is_file() for n in names)]
            return f"it holds the two views of the {layout.description.split(':')[0]} layout, but not {', '.join(missing)}"
    return None


def stereo_views(folder) -> tuple[Path, Path] | None:
    """The left and right view files of the first Middlebury layout whose two views ``folder`` holds,
    whether or not it holds the layout's ground truth and other files; None if it holds no layout's
    views (or is not a folder)."""
    folder = _as_path(folder, "folder")
    for layout in _LAYOUTS:
        views = [next((folder / n for n in names if (folder / n).is_file()), None) for names in layout.files[:2]]
        if views[0] is not None and views[1] is not None:
            return views[0], views[1]
    return None


def stereo_folders_lacking(root, *, depth: int = 4) -> list[tuple[Path, str]]:
    """The folders at or below ``root`` that hold a Middlebury layout's two views but not the rest of it (its
    ground truth, calib.txt or info.txt), which :func:`find_stereo_folders` therefore leaves out, each with
    what it lacks: so that an evaluation can say so rather than pass them over in silence.

    Parameters
    ----------
    root : str or Path
    depth : int
        As :func:`find_stereo_folders`.

    Raises
    ------
    FileNotFoundError
        If ``root`` is not a folder.
    """
    return [(folder, lack) for folder in _find_folders(root, depth, lambda f: _stereo_lack(f) is not None)
            if (lack := _stereo_lack(folder)) is not None]


def _find_folders(root, depth: int, holds: Callable[[Path], bool]) -> list[Path]:
    """The folders at or below ``root`` (``depth`` levels at most, hidden ones skipped) that ``holds``
    accepts, sorted; ``root`` alone when it does; a folder accepted is not searched further."""
    return _walk_folders(root, depth, [holds])[0]


def _walk_folders(root, depth: int, tests: list[Callable[[Path], bool]], *, deeper: int = 0) -> list[list[Path]]:
    """For each of ``tests``, what :func:`_find_folders` finds with it, from one walk: each folder is listed
    once and tried once by each test whose search has not stopped above it, so that searches for several
    kinds of folder do not each walk the tree again.

    The first test's search goes on ``deeper`` levels below ``depth``; there links to folders are not
    followed and a folder that cannot be listed is passed over, as that part of the walk only looks for
    what to mention, and a root high in a large tree must not be walked whole.
    """
    root = _as_path(root, "root")
    check_int(depth, "depth", minimum=1)
    if not root.is_dir():
        raise FileNotFoundError(f"no such folder: {root}")
    found: list[list[Path]] = [[] for _ in tests]
    levels = [depth + deeper] + [depth] * (len(tests) - 1)  # how deep each test's search goes
    here: list[tuple[Path, list[int]]] = [(root, list(range(len(tests))))]  # a level's folders, the tests for each
    level = 0
    while here:  # not up to the depth asked, which may be vast: to where no search goes on
        below: list[tuple[Path, list[int]]] = []
        for folder, searching in here:
            on = []
            for test in searching:
                if tests[test](folder):
                    found[test].append(folder)
                elif level < levels[test]:
                    on.append(test)
            if on:
                below += [(child, on) for child in _subfolders(folder, strict=level < depth)]
        here, level = below, level + 1
    return [sorted(folders) for folders in found]


def _subfolders(folder: Path, *, strict: bool) -> list[Path]:
    """The folders in ``folder`` but hidden ones; not ``strict``: none that is a link, and none where it
    cannot be listed."""
    try:
        return [child for child in folder.iterdir()
                if child.is_dir() and not child.name.startswith(".") and (strict or not child.is_symlink())]
    except OSError:
        if strict:
            raise
        return []


DEEPER_LEVELS = 4
"""How many levels below a search's depth :func:`flow_folders_lacking` still looks for sequences to name."""


# name -> its folder under the data sets folder
_STEREO = {
    "tsukuba": "middlebury_stereo_v2eval/tsukuba",
    "venus": "middlebury_stereo_v2eval/venus",
    "teddy": "middlebury_stereo_v2eval/teddy",
    "sawtooth": "middlebury_stereo_2001/sawtooth",
    "map": "middlebury_stereo_2001/map",
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
    """Load a Middlebury stereo scene of the shared data sets by name (:func:`read_stereo_folder` of its folder).

    Parameters
    ----------
    name : str
        "tsukuba", "venus", "teddy" (Middlebury v2 set, with nonocc/all/disc masks), "sawtooth" or
        "map" (2001 set, no masks); case-insensitive. Any other folder: :func:`read_stereo_folder`.
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
    key, folder = _lookup(name, _STEREO, "stereo scene")
    return replace(read_stereo_folder(_as_path(root, "root") / folder), name=key)


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


@dataclass(frozen=True)
class FlowSequence:
    """A folder of frames in order with the ground-truth flow of one of them.

    Attributes
    ----------
    name : str
        The folder's name, with its parent's where the flow is not beside the frames ("clean/alley_1",
        "other-data/Dimetrodon").
    frames : tuple of Path
        The frames in the order of their numbers. Those up to ``index + 1`` were read and checked; those
        after it were checked as files (not empty, not cut short, no alpha) but not decoded, since nothing
        scored reads them: one of another size, or one OpenCV cannot decode, is refused when it is read.
    index : int
        The frame the ground truth starts from: the flow is from ``frames[index]`` to
        ``frames[index + 1]``; the frames before it are the sequence's past.
    flow : (H, W, 2) float32 array
        (u, v), NaN where unknown.
    mask : (H, W) bool array
        The pixels to score: known flow, not marked invalid (Sintel), not Yosemite's sky.
    occluded : (H, W) bool array or None
        Pixels that leave the view or are hidden in the next frame (Sintel's occlusion maps), when given.
    """

    name: str
    frames: tuple[Path, ...]
    index: int
    flow: np.ndarray
    mask: np.ndarray
    occluded: np.ndarray | None = None


_NUMBERED = re.compile(r"(\d+)$")


def _number(path: Path) -> int | None:
    found = _NUMBERED.search(path.stem)
    return int(found.group(1)) if found else None


SINTEL_FIELD_FOLDERS = frozenset({"flow", "flow_viz", "invalid", "occlusions", "disparities", "disparities_viz",
                                  "depth", "depth_viz", "camdata_left"})
"""The folders MPI-Sintel's training set holds beside its passes (clean, final, albedo), each of a field or
a mask per frame: :func:`find_flow_folders` does not read one as a pass's frames."""


_MIDDLEBURY_FRAMES = ("-data", "-data-gray")  # the endings of the folders Middlebury's download keeps frames in


def _flow_truth(folder: Path) -> tuple[Path, Path | None, Path | None] | None:
    """(the .flo, its invalid map, its occlusion map) of a flow folder, or None when it has none.

    Middlebury: flowNN.flo beside frameNN.png, or as its download lays them out, other-data/<scene> (or
    other-data-gray/<scene>) beside other-gt-flow/<scene>/flowNN.flo; this layout of Sintel's excerpts:
    gt/frame_NNNN.flo with gt/invalid/ and gt/occlusions/; Sintel's own: <pass>/<scene> beside flow/<scene>,
    invalid/<scene>, occlusions/<scene>; Yosemite: correct_yos.flo.
    """
    here = sorted(folder.glob("*.flo"))
    if len(here) == 1:
        return here[0], None, None
    gt = folder / "gt"
    below = sorted(gt.glob("*.flo")) if gt.is_dir() else []
    if len(below) == 1:
        name = below[0].with_suffix(".png").name
        invalid, occlusions = gt / "invalid" / name, gt / "occlusions" / name
        return below[0], invalid if invalid.is_file() else None, occlusions if occlusions.is_file() else None
    beside = folder.parent.parent / "flow" / folder.name
    # Sintel's own folders beside its passes hold fields and masks of the frames, numbered as frames are.
    sintel_field = folder.parent.name in SINTEL_FIELD_FOLDERS
    flows = sorted(beside.glob("*.flo")) if beside.is_dir() and not sintel_field else []
    if flows:
        # Sintel's own layout has a flow for every frame but the last: the sequence ends at its last flow.
        name = flows[-1].with_suffix(".png").name
        invalid = folder.parent.parent / "invalid" / folder.name / name
        occlusions = folder.parent.parent / "occlusions" / folder.name / name
        return flows[-1], invalid if invalid.is_file() else None, occlusions if occlusions.is_file() else None
    for frames in _MIDDLEBURY_FRAMES:  # Middlebury's download: other-data/<scene>, other-gt-flow/<scene>
        if folder.parent.name.endswith(frames):
            truths = folder.parent.parent / (folder.parent.name[:-len(frames)] + "-gt-flow") / folder.name
            flows = sorted(truths.glob("*.flo")) if truths.is_dir() else []
            if len(flows) == 1:
                return flows[0], None, None
    return None


def _frame_runs(folder: Path) -> dict[str, list[Path]]:
    """The folder's numbered images (:data:`IMAGE_SUFFIXES`) by their name with NN for the number
    ("frameNN.png", "frame_NN.png", "yosNN.png", "frameNN.jpg"), each run in number order; Middlebury's colour
    pictures of the flow (flowNN.png, beside flowNN.flo) left out."""
    runs: dict[str, list[Path]] = {}
    for path in folder.iterdir():
        if path.is_file() and path.suffix.lower() in IMAGE_SUFFIXES and _number(path) is not None:
            runs.setdefault(f"{_NUMBERED.sub('', path.stem)}NN{path.suffix.lower()}", []).append(path)
    runs.pop("flowNN.png", None)
    return {name: sorted(paths, key=lambda p: (_number(p), p.name)) for name, paths in sorted(runs.items())}


def _flow_frames(folder: Path, frame: int | None = None) -> list[Path]:
    """The frames of a flow folder: of its runs of numbered PNGs of one name, those that hold ``frame`` and
    the one after it (any run when ``frame`` is None), the longest; none where two are equally long (which
    is the sequence cannot be told)."""
    runs = [run for run in _frame_runs(folder).values()
            if frame is None or {frame, frame + 1} <= {_number(p) for p in run}]
    runs.sort(key=len, reverse=True)
    if len(runs) > 1 and len(runs[1]) == len(runs[0]):
        return []
    return runs[0] if runs else []


def _described(shape: tuple[int, ...]) -> str:
    """An image's size and colour kind, as its shape gives them ("160 x 120 RGB")."""
    return f"{shape[1]} x {shape[0]} {'grey' if len(shape) == 2 else 'RGB'}"


def _frames_around(frames: list[Path], numbers: list[int], index: int, shape: tuple[int, ...]) -> tuple[int, int]:
    """The span ``start, stop`` of ``frames`` (sorted by their ``numbers``) that is one sequence with the scored
    pair ``index, index + 1``: frames numbered one after another, each number held by one file. A gap or a
    number held by two files (frame08.png and frame008.png: which comes first cannot be told) ends the past or
    the future there, rather than join what does not follow. The past is streamed before the pair, so it is
    read: a past frame of another ``shape`` (size and colour kind) than the scored frame's ends it too, and one
    that cannot be read is refused (by :func:`read_image`, naming it). The future is read by nothing, so it is
    not decoded: a frame there that :func:`read_image` refuses from its bytes alone (empty, cut short, a PNG
    with alpha) only ends it."""
    count = Counter(numbers)

    def follows(earlier: int, later: int) -> bool:
        return numbers[later] == numbers[earlier] + 1 and count[numbers[earlier]] == count[numbers[later]] == 1

    def undamaged(path: Path) -> bool:
        try:
            return _refused_undecoded(path.read_bytes()) is None
        except OSError:
            return False

    start, stop = index, index + 2
    while start > 0 and follows(start - 1, start) and read_image(frames[start - 1]).shape == shape:
        start -= 1
    while stop < len(frames) and follows(stop - 1, stop) and undamaged(frames[stop]):
        stop += 1
    return start, stop


def read_flow_folder(folder) -> FlowSequence:
    """Read a folder of frames with ground-truth flow: Middlebury's layout, Sintel's, or Yosemite's.

    Parameters
    ----------
    folder : str or Path
        Numbered frames (frame07.png ... frame14.png, frame_0001.png ...; PNG or another image of
        :data:`IMAGE_SUFFIXES`) and one flow: flowNN.flo
        beside them for frame NN (Middlebury), or in other-gt-flow/<scene>/ beside other-data/<scene>/
        (Middlebury's download; other-data-gray too), gt/frame_NNNN.flo with gt/invalid/ and gt/occlusions/
        masks, or Sintel's <pass>/<scene> folders with flow/<scene>/ beside the pass (the last flow is
        scored), or Yosemite's yos9.png, yos10.png and correct_yos.flo. The sequence is named by its folder,
        with its parent's name where the flow is not beside the frames (in gt/, flow/ or other-gt-flow/:
        "clean/alley_1", "other-data/Dimetrodon"). Its frames are those numbered one after another around the
        scored pair: a gap in the numbers or a number held by two files (frame08.png and frame008.png) ends
        them there, its past before it and its future after it; so does a past frame of another size or kind
        (grey among RGB) than the scored one. A past frame that cannot be read is refused by name (the
        sequence mode streams it). The frames after the scored pair are read by nothing and not decoded: one
        that is refused from its bytes alone (empty, cut short, a PNG with alpha) ends the future there.

    Returns
    -------
    FlowSequence

    Raises
    ------
    FileNotFoundError
        No such folder.
    ValueError
        No flow, fewer than two numbered frames, no frame after the flow's first, two frames of the scored
        pair's numbers (frame010.png beside frame10.png), a past frame that cannot be read, a next frame of
        another size or colour kind, or a flow or mask of another size.
    """
    folder = _as_path(folder, "folder")
    if not folder.is_dir():
        raise FileNotFoundError(f"no such folder: {folder}")
    truth = _flow_truth(folder)
    if truth is None:
        raise InputValueError(f"folder {folder} holds no ground-truth flow (flowNN.flo, gt/*.flo or Sintel's flow/)")
    flo, invalid, occlusions = truth
    frames = _flow_frames(folder, _number(flo)) or _flow_frames(folder)
    if len(frames) < 2:
        runs = _frame_runs(folder)
        if len(runs) > 1:
            raise InputValueError(f"folder {folder} holds numbered images of {len(runs)} names "
                                  f"({', '.join(repr(n) for n in runs)}); which are the frames cannot be told")
        raise InputValueError(f"folder {folder} holds fewer than two numbered frames (*NN.png or another image)")
    numbers = [n for p in frames if (n := _number(p)) is not None]  # every frame's (its run is of numbered ones)
    wanted = _number(flo)
    if wanted is None:  # Yosemite's correct_yos.flo: the flow between its two frames
        if len(frames) != 2:
            raise InputValueError(f"{flo} has no frame number and the folder holds {len(frames)} frames, not two")
        wanted = numbers[0]
    for number in (wanted, wanted + 1):
        # frame010.png and frame10.png are both frame 10: the pair would be one of them and the other, a frame
        # scored against itself (or its copy).
        same = [p.name for p, n in zip(frames, numbers) if n == number]
        if len(same) > 1:
            raise InputValueError(f"folder {folder} holds {len(same)} frames numbered {number} ({', '.join(same)}); "
                                  f"which is frame {number} cannot be told")
    if wanted not in numbers or wanted + 1 not in numbers:
        raise InputValueError(f"{flo} is the flow from frame {wanted} to {wanted + 1}, which the folder lacks")
    index = numbers.index(wanted)  # numbers are sorted and these two unique: frames[index + 1] is wanted + 1
    flow = read_flo(flo)
    scored = read_image(frames[index]).shape
    start, stop = _frames_around(frames, numbers, index, scored)
    frames, index = frames[start:stop], index - start
    following = read_image(frames[index + 1]).shape
    if following != scored:  # the pair is matched pixel to pixel: one size and one colour kind
        raise InputValueError(f"{frames[index + 1]} is {_described(following)}, the frame {frames[index].name} "
                              f"{_described(scored)}")
    size = scored[:2]

    def sized(path: Path, field: np.ndarray) -> np.ndarray:
        # Every file scored with the pair has the frame's size: the flow and the masks.
        if field.shape[:2] != size:
            raise InputValueError(f"{path} is {field.shape[1]} x {field.shape[0]}, the frame {frames[index].name} "
                                  f"{size[1]} x {size[0]}")
        return field

    mask = np.isfinite(sized(flo, flow)).all(axis=-1)
    if invalid is not None:
        mask &= ~sized(invalid, read_mask(invalid))
    occluded = sized(occlusions, read_mask(occlusions)) if occlusions is not None else None
    if flo.name == "correct_yos.flo":  # Yosemite's sky is stored as exactly (1, 0), not measured
        mask &= ~((flow[..., 0] == 1.0) & (flow[..., 1] == 0.0))
    named = folder.resolve()  # "." or ".." has no name of its own
    name = named.name if flo.parent == folder else f"{named.parent.name}/{named.name}"
    return FlowSequence(name, tuple(frames), index, flow, mask, occluded)


def _is_flow_sequence(folder: Path) -> bool:
    return _flow_truth(folder) is not None and len(_flow_frames(folder)) >= 2


def find_flow_folders(root, *, depth: int = 4) -> list[Path]:
    """The folders at or below ``root`` that :func:`read_flow_folder` reads (sorted; hidden ones skipped).

    Parameters
    ----------
    root : str or Path
    depth : int
        Levels below ``root`` searched, >= 1. The sequences below them are not returned;
        :func:`flow_folders_lacking` names them.

    Raises
    ------
    FileNotFoundError
        If ``root`` is not a folder.
    """
    return _find_folders(root, depth, _is_flow_sequence)


def flow_folders_lacking(root, *, depth: int = 4) -> list[tuple[Path, str]]:
    """The folders at or below ``root`` that :func:`find_flow_folders` leaves out though they look like flow
    sequences, each with what it lacks: a ground-truth flow and one numbered frame, not the two it joins;
    numbered frames beside several flows, of which the truth cannot be told; or frames in Middlebury's layout
    (eval-data/<scene>) without their ground truth, as Middlebury publishes its test sequences (folders of
    flows alone, such as
    Sintel's flow/ and gt/, are not sequences and are not listed); and the sequences that lie deeper than
    the ``depth`` levels it searches (up to :data:`DEEPER_LEVELS` levels further), found by searching on below
    them, so that none near is passed over in silence. Sorted by folder.

    Parameters
    ----------
    root : str or Path
    depth : int
        As :func:`find_flow_folders`.

    Raises
    ------
    FileNotFoundError
        If ``root`` is not a folder.
    """
    def flows(folder: Path) -> list[Path]:
        return sorted(folder.glob("*.flo"))

    def lacking(folder: Path) -> bool:
        # Middlebury's other-gt-flow/<scene> holds the flow and its colour picture flowNN.png, no frame.
        if folder.parent.name.endswith("-gt-flow"):
            return False
        if len(flows(folder)) > 1:  # a user's own estimate beside the truth: which is the truth cannot be told
            return len(_flow_frames(folder)) >= 2
        if _flow_truth(folder) is None:  # Middlebury's eval-data/<scene>: its frames, published without truth
            return folder.parent.name.endswith(_MIDDLEBURY_FRAMES) and len(_flow_frames(folder)) >= 2
        return len(_flow_frames(folder)) == 1

    # One walk finds the sequences (to the depth searched and below it) and the folders that lack a part.
    sequences, lacks = _walk_folders(root, depth, [_is_flow_sequence, lacking], deeper=DEEPER_LEVELS)
    found = []
    for folder in lacks:
        several = flows(folder)
        if len(several) > 1:
            lack = (f"it holds {len(several)} flows ({', '.join(p.name for p in several[:3])}"
                    f"{' ...' if len(several) > 3 else ''}): which is the ground truth cannot be told")
        elif (truth := _flow_truth(folder)) is None:
            frames = _flow_frames(folder)
            lack = (f"it holds {len(frames)} numbered frames ({frames[0].name} ...) but no ground-truth flow (flowNN.flo, "
                    "gt/*.flo, Sintel's flow/ or Middlebury's other-gt-flow/)")
        else:
            lack = f"it holds the flow {truth[0].name} but one numbered frame (*NN.png), not the two it joins"
        found.append((folder, lack))
    root = _as_path(root, "root")
    for folder in sequences:
        levels = len(folder.relative_to(root).parts)
        if levels <= depth:  # find_flow_folders finds it
            continue
        why = (f"it is a flow sequence {levels} levels below {root}, deeper than the {depth} levels searched "
               "(search from a folder nearer to it)")
        found.append((folder, why))
    return sorted(found)


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
    files : tuple of Path
        The files it was read from (the image and its annotations), for a record of what a fit read; empty
        for an image made in memory.
    """

    name: str
    image: np.ndarray
    boundaries: np.ndarray
    segmentations: np.ndarray
    edge_map: np.ndarray | None = None
    files: tuple[Path, ...] = ()


@dataclass(frozen=True)
class BSDSSet:
    """A set of BSDS500 images.

    Attributes
    ----------
    split : str
        "test", "train", "golden", or "folder" (read_bsds_folder).
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
    try:
        cells = scipy.io.loadmat(_existing(path))["groundTruth"][0]
        boundaries = np.stack([c["Boundaries"][0, 0].astype(bool) for c in cells])
        segmentations = np.stack([c["Segmentation"][0, 0].astype(np.uint16) for c in cells])
    except FileNotFoundError:
        raise
    except (OSError, ValueError, KeyError, IndexError, TypeError, NotImplementedError) as error:
        # A .mat cut short, of another kind, or without the benchmark's groundTruth cells.
        raise InputValueError(f"{path} is not a BSDS ground-truth file ({type(error).__name__}: {error})") from None
    return boundaries, segmentations


def _bsds_item(name: str, image_path: Path, truth: Path) -> BSDSImage:
    image = read_image(image_path)
    boundaries, segmentations = _bsds_annotations(truth)
    if boundaries.shape[1:] != image.shape[:2]:
        raise InputValueError(f"{truth} is {boundaries.shape[2]} x {boundaries.shape[1]}, its image {image_path.name} "
                              f"{image.shape[1]} x {image.shape[0]}")
    return BSDSImage(name, image, boundaries, segmentations, files=(image_path, truth))


def read_bsds_folder(folder, *, split: str = "test", left_out: list[tuple[Path, str]] | None = None
                     ) -> list[BSDSImage]:
    """The images of a BSDS-layout folder with their human boundaries and segmentations.

    Two layouts are read: one folder per image holding ``<id>.jpg`` and ``<id>.mat`` (as under
    ``shared/datasets/bsds500/test``), or the BSDS500 distribution's ``images/`` and ``groundTruth/``
    folders side by side (``BSR/BSDS500/data``; its ``split`` where the folders hold splits: "test" to
    evaluate, "train" to fit). An image without its ``.mat``, with one that is damaged or of another size,
    or damaged itself, is refused by name; or, where ``left_out`` (a list) is given, appended to it as
    (its file, why) and passed over. The images are in sorted (string) order of their ids.
    """
    folder = _as_path(folder, "folder")
    check_choice(split, "split", ("test", "train", "val"))
    if not folder.is_dir():
        raise FileNotFoundError(f"no such folder: {folder}")
    truths: Path | None = None  # the distribution's ground-truth folder; else each image's .mat is beside it
    if (folder / "images").is_dir() and (folder / "groundTruth").is_dir():
        images, truths = folder / "images", folder / "groundTruth"
        if (images / split).is_dir() and (truths / split).is_dir():
            images, truths = images / split, truths / split
        else:
            splits = sorted(p.name for p in images.iterdir() if p.is_dir() and not p.name.startswith("."))
            if splits and not any(images.glob("*.jpg")):
                raise FileNotFoundError(f"{folder}: images/ and groundTruth/ hold no {split}/ split (images/ holds "
                                        f"{', '.join(splits)})")
        found = sorted(images.glob("*.jpg"))
    else:
        found = sorted(p / f"{p.name}.jpg" for p in folder.iterdir() if (p / f"{p.name}.jpg").is_file())
    pairs = [(p.stem, p, (p if truths is None else truths / p.name).with_suffix(".mat")) for p in found]
    if not pairs:
        raise FileNotFoundError(f"{folder}: no BSDS images (<id>/<id>.jpg, or images/ and groundTruth/ folders)")
    missing = [truth for _, _, truth in pairs if not truth.is_file()]
    if left_out is None and missing:  # refused before any image is read, naming the missing ones together
        raise InputValueError(f"{folder}: images without their ground truth: {', '.join(map(str, missing[:3]))}"
                              + (f" and {len(missing) - 3} more" if len(missing) > 3 else ""))
    items = []
    for name, image, truth in pairs:
        try:
            if truth in missing:
                raise InputValueError(f"no ground truth {truth}")
            items.append(_bsds_item(name, image, truth))
        except InputValueError as error:
            if left_out is None:
                raise
            left_out.append((image, str(error)))
    return items


def find_bsds_folders(root, *, depth: int = 4) -> list[Path]:
    """The folders at or below ``root`` that hold the BSDS500 distribution's ``images/`` and ``groundTruth/``
    folders side by side (``BSR/BSDS500/data`` once unpacked), for :func:`read_bsds_folder`.

    Parameters
    ----------
    root : str or Path
    depth : int
        Levels below ``root`` searched, >= 1.

    Raises
    ------
    FileNotFoundError
        If ``root`` is not a folder.
    """
    return _find_folders(root, depth, lambda folder: (folder / "images").is_dir() and (folder / "groundTruth").is_dir())


def load_bsds(root, *, split: str = "test") -> BSDSSet:
    """Load BSDS500 images with their human boundaries and segmentations.

    Parameters
    ----------
    root : str or Path
        The data sets folder (``shared/datasets``).
    split : {"test", "train", "golden"}
        "test": the BSDS500 test images present under bsds500/test (10 here); "train": the 200 training
        images (the only ones to fit to); "golden": the boundary benchmark's own 5-image test
        (bench/data) with its edge maps and expected figures.

    Returns
    -------
    BSDSSet

    References
    ----------
    P. Arbelaez, M. Maire, C. Fowlkes and J. Malik, "Contour detection and hierarchical image
    segmentation", IEEE TPAMI 33(5):898-916, 2011.
    """
    base = _as_path(root, "root") / "bsds500"
    check_choice(split, "split", ("test", "train", "golden"))
    if split in ("test", "train"):
        if not (base / split).is_dir():
            raise FileNotFoundError(f"no BSDS500 {split} images under {base / split}")
        return BSDSSet(split, read_bsds_folder(base / split))
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

