"""The probability of a boundary at every pixel of one image, from brightness, colour and texture.

Seed sections "Integration via labeling with a linear classifier" and "Texture": the integration stage
combines the cues' discontinuities by a linear classifier. On a photograph the monocular cues are the
brightness, the colour and the texture; each is measured here as an oriented gradient at the model's
scales (three in the shipped model), and the gradients are combined by logistic regression fitted to
human boundaries (Martin, Fowlkes and Malik's probability of boundary, with Gaussian derivatives for
their half-discs).

The cues
--------
- Brightness and colour: CIE L*, a* and b* (a* the red-green and b* the yellow-blue opponent channel,
  the second chromatic channel beside the seed's red-green hue), each smoothed by a Gaussian of width
  sigma and differentiated across the boundary's normal, scale-normalised by sigma so a step gives the
  same peak at every scale.
- Texture: every pixel is labelled with its nearest texton, a cluster of the responses of a small
  filter bank (first and second directional derivatives at four orientations and the Laplacian, at two
  scales) compressed by their norm (Malik et al. 2001); the textons' indicator planes are smoothed at
  twice the scale (on a grid of every :func:`sample_step`-th row and column, a sigma apart: a Gaussian
  leaves little finer than its width), and the texture gradient across a normal is the norm of the
  histograms' derivative, read from a 2 x 2 tensor (the sum over textons of the gradient's outer
  product) so that any orientation costs three products. The tensor is integrated (smoothed) at the
  texture's scale, as a structure tensor is: a contrast edge is a band of textons of its own, and the
  histograms' derivative peaks on either side of such a band; integration merges the two peaks into one
  on the band.

At each of eight orientations the classifier's linear score of the gradients is computed (of the
gradients, their square roots, which let it bend its response to contrast, and the square roots of each
gradient over the mean, in a surround of SURROUND_SIGMA pixels, of its largest value over all orientations: surround
suppression, which weighs a gradient among many like it, a texture's inner edges, below the same
gradient alone), the best orientation wins, and its logistic is the probability. Non-maximum suppression across the winning orientation thins it to the
one-pixel contours a boundary benchmark scores.

The texton centres, the scales and the weights are a :class:`BoundaryModel`; the one shipped with vmcl
(``boundary_probability.json``) was fitted by benchmarks/boundary_fit.py to the BSDS500 training images
and nothing else.

NumPy in gives NumPy out; device arrays in give device arrays out.

References
----------
D. Martin, C. Fowlkes and J. Malik, "Learning to detect natural image boundaries using local brightness,
color, and texture cues", IEEE TPAMI 26(5):530-549, 2004.
J. Malik, S. Belongie, T. Leung and J. Shi, "Contour and texture analysis for image segmentation",
IJCV 43(1):7-27, 2001.
T. Poggio et al., "The MIT Vision Machine", Proc. DARPA Image Understanding Workshop, 177-198, 1988.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
import pyopencl.array as cl_array

from vmcl.cm.core import (
    IMAGE_TYPES,
    ArrayLike,
    check_real,
    check_unit_image,
    full_scale,
    image_field,
    launch_rows,
    machine_for,
    result,
    vector_kernel,
)
from vmcl.early.filters import device_taps
from vmcl.errors import InputTypeError, InputValueError
from vmcl.fitted import check_fitted_json, with_data, write_fitted_json
from vmcl.machine import Machine

__all__ = [
    "BANK_SIGMAS",
    "FEATURES",
    "MODEL_FILE",
    "ORIENTATIONS",
    "SAMPLES_PER_SIGMA",
    "BoundaryModel",
    "BoundaryProbability",
    "bank_responses",
    "boundary_probability",
    "oriented_gradients",
    "sample_step",
]

MODEL_FILE = Path(__file__).with_name("boundary_probability.json")

ORIENTATIONS = 8
"""Orientations of the normal, evenly over [0, pi)."""

BANK_SIGMAS = (1.0, 2.0)
"""The two scales of the texton filter bank, in pixels."""

BANK_SIZE = 18
"""Responses per pixel: 9 per scale (first and second derivatives at four orientations, the Laplacian)."""

TEXTURE_RATIO = 2.0
"""The texture gradient's scale over the brightness's: a histogram needs more pixels than a mean."""

SAMPLES_PER_SIGMA = 1.0
"""Samples per Gaussian width of the map's wide smoothings (:func:`sample_step`: every ``max(1, floor(sigma /
SAMPLES_PER_SIGMA))``-th pixel), chosen on held-out training images by benchmarks/boundary_sampling_fit.py
(among 3, 2, 1.5 and 1 per sigma, the fewest whose boundary scores stay within 0.002 of the exact
smoothings'). At every texture scale of two pixels or more (all three of the shipped model's), the
textons' histograms are computed at every step-th row and column, their tensor is formed (five-point
derivatives) and integrated on that grid, and the integrated tensor is interpolated bilinearly to every
pixel; the surround is smoothed at every step-th row and interpolated linearly between. A Gaussian of width
sigma keeps under 1% (e^(-pi^2 / 2)) of a wave at the highest frequency a grid a sigma apart carries, so the
histograms hardly alias; their tensor, a sum of products, reaches twice as high and aliases more, and the
interpolation moves the texture features by a few percent of their range (tests/test_early_boundary_probability.py
bounds both). The widest texture scale's histograms, a row and a column pass over 32 planes at 97 taps, were
the map's largest cost. The brightness and colour gradients, which place the boundary, are smoothed at
every pixel."""

SURROUND_SIGMA = 10.0
"""Width of the Gaussian surround whose mean gradient each gradient is compared with, in pixels."""

SURROUND_FLOOR = 0.02
"""Added to the surround's mean gradient, so that a gradient in a flat surround is not made infinite."""

_CUES = ("L", "a", "b", "texture")



def feature_names(scales: tuple[float, ...]) -> tuple[str, ...]:
    """The classifier's inputs for these scales: each cue's gradient, the square roots, then the square
    roots of each gradient over its surround's mean."""
    plain = tuple(f"{cue} {s:g}" for s in scales for cue in _CUES)
    return plain + tuple(f"sqrt {name}" for name in plain) + tuple(f"sqrt {name} / surround" for name in plain)


FEATURES = feature_names((1.5, 3.0, 6.0))
"""The inputs of the shipped model."""


@dataclass(frozen=True, eq=False)
class BoundaryModel:
    """What the probability of boundary is computed with.

    Attributes
    ----------
    scales : tuple of float
        Gaussian widths of the brightness and colour gradients (the texture's are TEXTURE_RATIO times).
    centres : (K, BANK_SIZE) float32 array
        The texton centres, in the compressed filter-bank space; K <= 255.
    weights : (1 + 12 len(scales),) float32 array
        The logistic regression's bias, then one weight per feature (:func:`feature_names`).
    fitted_on : str
        What the model was fitted to.
    record : mapping or None
        The file's ``"fitted"`` record when it was loaded from a fitted file (:mod:`vmcl.fitted`: the data,
        the code's hash, the date, the parameters' hash, checked when loaded); None otherwise.
    """

    scales: tuple[float, ...]
    centres: np.ndarray
    weights: np.ndarray
    fitted_on: str = ""
    record: Mapping[str, Any] | None = None

    def __post_init__(self):
        if not isinstance(self.scales, tuple) or not self.scales or not all(
                isinstance(s, (int, float)) and 0 < s <= 64 for s in self.scales):
            raise InputValueError(f"scales must be a non-empty tuple of widths in (0, 64], got {self.scales!r}")
        for name, value, shape in (("centres", self.centres, (None, BANK_SIZE)),
                                   ("weights", self.weights, (1 + 12 * len(self.scales),))):
            if not isinstance(value, np.ndarray) or value.dtype.kind != "f":
                raise InputTypeError(f"{name} must be a float NumPy array, got {type(value).__name__}")
            if value.ndim != len(shape) or any(want is not None and got != want
                                               for got, want in zip(value.shape, shape)):
                raise InputValueError(f"{name} must have shape {shape} (None: any), got {value.shape}")
            if not np.isfinite(value).all():
                raise InputValueError(f"{name} must be finite")
        if not 1 <= len(self.centres) <= 255:
            raise InputValueError(f"centres must hold 1..255 textons, got {len(self.centres)}")

    @property
    def features(self) -> tuple[str, ...]:
        return feature_names(self.scales)

    @classmethod
    def load(cls, path: str | os.PathLike | None = None) -> BoundaryModel:
        """The model in ``path`` (default: the one fitted to BSDS500's training images, shipped with vmcl)."""
        if path is not None and not isinstance(path, (str, os.PathLike)):
            raise InputTypeError(f"path must be a str, an os.PathLike or None, got {type(path).__name__}")
        path = MODEL_FILE if path is None else Path(path)
        try:
            data = json.loads(Path(path).read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as error:
            raise InputValueError(f"{path}: cannot be read as a boundary model ({error})") from None
        if not isinstance(data, dict):
            raise InputValueError(f"{path}: cannot be read as a boundary model (not a JSON object)")
        record = check_fitted_json(data, str(path))
        try:
            return cls(tuple(float(s) for s in data["scales"]), np.asarray(data["centres"], np.float32),
                       np.asarray(data["weights"], np.float32), str(data.get("fitted_on", "")), record)
        except (KeyError, TypeError, ValueError) as error:
            raise InputValueError(f"{path}: cannot be read as a boundary model ({error})") from None

    def save(self, path: str | os.PathLike, provenance: Mapping[str, Any] | None = None) -> Path:
        """Write the model as JSON with its ``"fitted"`` record (:func:`vmcl.fitted.write_fitted_json`): to a
        new file or one vmcl fitted, never over another file.

        Parameters
        ----------
        path : str or os.PathLike
        provenance : mapping, optional
            What the record says the model was fitted on and by what (e.g. ``data_sha256``,
            ``code_sha256``); its ``data`` defaults to :attr:`fitted_on`.

        Returns
        -------
        Path
            The file written.
        """
        data = {"scales": list(self.scales), "features": list(self.features), "fitted_on": self.fitted_on,
                "centres": np.round(self.centres.astype(np.float64), 5).tolist(),
                "weights": np.round(self.weights.astype(np.float64), 5).tolist()}
        return write_fitted_json(path, data, with_data(self.fitted_on, provenance))


class BoundaryProbability(NamedTuple):
    """The probability of boundary.

    Attributes
    ----------
    probability : float32 (H, W) in [0, 1]
        Thinned: 0 where a neighbour across the boundary's normal is more probable.
    orientation : float32 (H, W)
        The normal's angle in [0, pi) that won, radians (x right, y down).
    dense : float32 (H, W) in [0, 1]
        The probability before thinning.
    """

    probability: ArrayLike
    orientation: ArrayLike
    dense: ArrayLike


_LOADED: dict[str, BoundaryModel] = {}


def _model(model: BoundaryModel | None) -> BoundaryModel:
    if model is None:
        if "shipped" not in _LOADED:
            _LOADED["shipped"] = BoundaryModel.load()
        return _LOADED["shipped"]
    if not isinstance(model, BoundaryModel):
        raise InputTypeError(f"model must be a BoundaryModel or None, got {type(model).__name__}")
    return model


def _image(image, machine: Machine, model_scales: tuple[float, ...], planes: int) -> tuple[cl_array.Array, bool]:
    widest = max(model_scales) * TEXTURE_RATIO
    data, host = image_field(image, machine, what="the probability of boundary", footprint=4 * planes,
                             largest=4 * planes, widths={"the texture's widest Gaussian": widest})
    if isinstance(image, np.ndarray) and data.dtype == np.float32:
        # The sRGB decoding, the Lab conversion and the model fitted on them take brightness in [0, 1]: a
        # float image in 0..255 would be read as another image altogether.
        check_unit_image(image, "image")
    return data, host


def _srgb_linear(levels: np.ndarray) -> np.ndarray:
    """sRGB's decoding of values in [0, 1] to linear light (IEC 61966-2-1)."""
    return np.where(levels <= 0.04045, levels / 12.92, ((levels + 0.055) / 1.055) ** 2.4)


_LINEAR_8BIT = _srgb_linear(np.arange(256) / 255.0).astype(np.float32)

def _constant(machine: Machine, key: object, make) -> cl_array.Array:
    """A read-only float32 table on the device, uploaded once per machine and key
    (:meth:`vmcl.Machine.constant`)."""
    return machine.constant(("vmcl.early.boundary_probability", key),
                            lambda: np.ascontiguousarray(make(), np.float32))




def _kernel(machine: Machine, name: str, **defines: Any):
    """A kernel of kernels/boundary_probability.cl built with the Machine's vector width (VEC), as all but
    the fitting's oriented are, so that kernels with the same other defines share one program (one build
    at first use)."""
    return vector_kernel(machine, "boundary_probability", name, **defines)


def _lab(machine: Machine, data: cl_array.Array) -> cl_array.Array:
    """The (3, H, W) planes L*, a*, b*, each divided by 100."""
    height, width = data.shape[:2]
    planes = machine.empty((3, height, width), np.float32)
    table = data.dtype == np.uint8
    kernel = _kernel(machine, "lab", IN_T=IMAGE_TYPES[data.dtype],
                           CHANNELS=3 if data.ndim == 3 else 1, LINEAR_TABLE=int(table))
    linear = _constant(machine, ("linear", table), lambda: _LINEAR_8BIT if table else np.zeros(1))
    launch_rows(machine, kernel, width, height, data, planes, linear, np.float32(full_scale(data.dtype)),
                np.int64(width), np.int64(height))
    return planes


def sample_step(sigma: float) -> int:
    """The spacing (pixels) of the samples a smoothing of width ``sigma`` (> 0, pixels) is computed at in the
    map's wide smoothings (:data:`SAMPLES_PER_SIGMA`)."""
    return max(1, int(check_real(sigma, "sigma", above=0) // SAMPLES_PER_SIGMA))


def _samples(length: int, step: int) -> int:
    """The samples at 0, step, ... up to the first at or past the last of ``length`` pixels (the passes
    clamp there)."""
    return -(-(length - 1) // step) + 1


def _planes_pass(machine: Machine, name: str, planes: cl_array.Array, out: cl_array.Array, sigma: float,
                 count: int, defines: dict, first: int = 0, step: int = 1) -> None:
    """One pass of the Gaussian of ``sigma`` over the first ``count`` planes of ``planes``, written to planes
    ``first`` .. ``first + count - 1`` of ``out``; ``defines``: those of the program it is taken from. The
    column pass writes every ``step``-th row of ``planes`` (``out`` then has that many rows); the row pass
    has no step."""
    if step != 1 and name != "planes_cols":
        raise ValueError(f"{name} has no step: only the column pass samples rows")
    height, width = planes.shape[1:]
    rows = out.shape[1]
    size = (-(-width // machine.vector_width), rows, count)
    taps, radius = device_taps(machine, (sigma,))
    sampling = (np.int32(step), np.int64(rows)) if name == "planes_cols" else ()
    machine.launch(_kernel(machine, name, **defines), size, planes, out, taps, np.int32(radius),
                   np.int64(first), *sampling, np.int64(width), np.int64(height),
                   local_size=machine.row_local_size(size))


def _smooth(machine: Machine, planes: cl_array.Array, sigma: float, defines: dict, count: int | None = None,
            step: int = 1, out: cl_array.Array | None = None, first: int = 0) -> cl_array.Array:
    """The first ``count`` (default all) planes of a (P, H, W) stack smoothed by the exact Gaussian of
    ``sigma``, into planes ``first`` ... of ``out`` (default a new (count, H, W) stack), which is returned.
    With ``step`` > 1 the column pass writes every step-th row, the row pass smooths those, and the rows
    between are interpolated linearly."""
    height, width = planes.shape[1:]
    count = planes.shape[0] if count is None else count
    if out is None:
        out = machine.empty((count, height, width), np.float32)
    if step == 1:
        rows = machine.empty((count, height, width), np.float32)
        _planes_pass(machine, "planes_rows", planes, rows, sigma, count, defines)
        _planes_pass(machine, "planes_cols", rows, out, sigma, count, defines, first=first)
        return out
    sampled = _samples(height, step)
    columns = machine.empty((count, sampled, width), np.float32)
    _planes_pass(machine, "planes_cols", planes, columns, sigma, count, defines, step=step)
    rows = machine.empty((count, sampled, width), np.float32)
    _planes_pass(machine, "planes_rows", columns, rows, sigma, count, defines)
    _upsample(machine, rows, out, 1, step, first, defines)
    return out


def _upsample(machine: Machine, sampled: cl_array.Array, out: cl_array.Array, step_x: int, step_y: int, first: int,
              defines: dict) -> None:
    """A (P, Hc, Wc) stack sampled at every step_x-th column and step_y-th row, interpolated bilinearly into
    planes ``first`` ... of ``out``."""
    count, coarse_height, coarse_width = sampled.shape
    height, width = out.shape[1:]
    machine.launch(_kernel(machine, "planes_upsample", **defines), (width, height, count), sampled, out,
                   np.int32(step_x), np.int32(step_y), np.int64(first), np.int64(coarse_width),
                   np.int64(coarse_height), np.int64(width), np.int64(height))


def _bank(machine: Machine, lab: cl_array.Array, defines: dict) -> cl_array.Array:
    """The compressed filter-bank responses of the lightness (plane 0 of ``lab``), (H, W, BANK_SIZE);
    ``defines`` hold NBANK."""
    height, width = lab.shape[1:]
    fine, coarse = (_smooth(machine, lab, s, defines, count=1) for s in BANK_SIGMAS)
    out = machine.empty((height, width, BANK_SIZE), np.float32)
    launch_rows(machine, _kernel(machine, "bank", **defines), width, height,
                fine, coarse, out, *map(np.float32, BANK_SIGMAS), np.int64(width), np.int64(height))
    return out


def _components(machine: Machine, data: cl_array.Array, model: BoundaryModel) -> tuple[cl_array.Array, cl_array.Array]:
    """Every scale's gradients of L*, a* and b*, (6 len(scales), H, W), and its integrated texture tensor,
    (3 len(scales), H, W)."""
    height, width = data.shape[:2]
    dims = (np.int64(width), np.int64(height))
    lab = _lab(machine, data)
    defines = _program_defines(model)
    responses = _bank(machine, lab, defines)
    count = len(model.centres)
    labels = machine.empty((height, width), np.uint8)
    launch_rows(machine, _kernel(machine, "nearest", **defines), width, height, responses,
                _constant(machine, ("centres", model), lambda: model.centres), labels, np.int32(count), *dims)
    comp = machine.empty((6 * len(model.scales), height, width), np.float32)
    tensors = machine.empty((3 * len(model.scales), height, width), np.float32)
    steps = [sample_step(TEXTURE_RATIO * sigma) for sigma in model.scales]
    # The histograms' row pass, at the sampled columns of the scale that samples least.
    rows = machine.empty(count * height * max(_samples(width, step) for step in steps), np.float32)
    tensor = machine.empty((3, height, width), np.float32)
    for k, (sigma, step) in enumerate(zip(model.scales, steps)):
        texture_sigma = TEXTURE_RATIO * sigma
        histograms = _histograms(machine, labels, rows, texture_sigma, count, step, defines)
        # Where the histograms are sampled, their tensor is formed on their grid (below), not here (nt 0).
        launch_rows(machine, _kernel(machine, "components", **defines), width, height,
                    _smooth(machine, lab, sigma, defines), histograms, comp, tensor, np.float32(sigma),
                    np.float32(texture_sigma), np.int32(count if step == 1 else 0), np.int32(k), *dims)
        # The tensor integrated at the texture's scale: a band of textons of its own (a contrast edge's)
        # gives the histograms' derivative a peak either side of the band, which integration merges.
        if step == 1:
            _smooth(machine, tensor, texture_sigma, defines, out=tensors, first=3 * k)
            continue
        coarse_height, coarse_width = histograms.shape[1:]
        sampled = machine.empty((3, coarse_height, coarse_width), np.float32)
        machine.launch(_kernel(machine, "sampled_tensor", **defines), (coarse_width, coarse_height), histograms,
                       sampled, np.float32(texture_sigma / step), np.int32(count), np.int64(coarse_width),
                       np.int64(coarse_height))
        _upsample(machine, _smooth(machine, sampled, texture_sigma / step, defines), tensors, step, step, 3 * k,
                  defines)
    return comp, tensors


def _histograms(machine: Machine, labels: cl_array.Array, rows: cl_array.Array, texture_sigma: float, count: int,
                step: int, defines: dict) -> cl_array.Array:
    """The textons' indicator planes smoothed at ``texture_sigma``, at every ``step``-th row and column of the
    image: (count, Hc, Wc); ``rows``: flat scratch of at least count H Wc floats."""
    height, width = labels.shape
    coarse_width, coarse_height = _samples(width, step), _samples(height, step)
    taps, radius = device_taps(machine, (texture_sigma,))
    sampled_rows = rows[:count * height * coarse_width].reshape(count, height, coarse_width)
    machine.launch(_kernel(machine, "histogram_rows", **defines), (coarse_width, height), labels, sampled_rows,
                   taps, np.int32(radius), np.int32(step), np.int64(coarse_width), np.int64(width), np.int64(height))
    out = machine.empty((count, coarse_height, coarse_width), np.float32)
    _planes_pass(machine, "planes_cols", sampled_rows, out, texture_sigma, count, defines, step=step)
    return out


def _directions(machine: Machine) -> cl_array.Array:
    """(cos, sin) of each orientation's angle, o pi / ORIENTATIONS, as the classifier's kernels read them."""
    def table() -> np.ndarray:
        angles = np.arange(ORIENTATIONS) * (np.pi / ORIENTATIONS)
        return np.stack([np.cos(angles), np.sin(angles)], axis=1).astype(np.float32).ravel()
    return _constant(machine, ("directions", ORIENTATIONS), table)


def _defines(model: BoundaryModel) -> dict:
    return {"NORIENT": ORIENTATIONS, "NSCALES": len(model.scales), "NFEAT": 12 * len(model.scales),
            "SURROUND_FLOOR": f"{SURROUND_FLOOR!r}f"}


def _program_defines(model: BoundaryModel) -> dict:
    """The defines of every kernel a model's map takes but lab (whose depend on the image's type): each of
    the file's kernel groups reads only its own, so one program serves them all, one build on a first run
    where there were four."""
    return {"NBANK": BANK_SIZE, "NT": len(model.centres), **_defines(model)}


def _inputs(machine: Machine, data: cl_array.Array, model: BoundaryModel) -> tuple[cl_array.Array, ...]:
    """What the features are read from: the gradients' components, the texture tensors and the surround."""
    height, width = data.shape[:2]
    comp, tensors = _components(machine, data, model)
    strongest = machine.empty((4 * len(model.scales), height, width), np.float32)
    defines = _program_defines(model)
    launch_rows(machine, _kernel(machine, "strongest", **defines), width,
                height, comp, tensors, strongest, np.int64(width), np.int64(height))
    return comp, tensors, _smooth(machine, strongest, SURROUND_SIGMA, defines, step=sample_step(SURROUND_SIGMA))


def bank_responses(image: ArrayLike, *, machine: Machine | None = None) -> ArrayLike:
    """The texton filter bank's compressed responses at every pixel, float32 (H, W, BANK_SIZE): what the
    texton centres cluster (benchmarks/boundary_fit.py fits them by k-means)."""
    machine = machine_for(machine)
    data, host = _image(image, machine, BANK_SIGMAS, BANK_SIZE + 4)
    return result(_bank(machine, _lab(machine, data), {"NBANK": BANK_SIZE}), host)


def oriented_gradients(image: ArrayLike, *, model: BoundaryModel | None = None,
                       machine: Machine | None = None) -> ArrayLike:
    """The classifier's inputs at every pixel and orientation, float32 (ORIENTATIONS, H, W, n features).

    Parameters
    ----------
    image : ndarray or pyopencl.array.Array, (H, W) or (H, W, 3)
        uint8, uint16 or float in [0, 1] (sRGB); grey images have no colour gradient.
    model : BoundaryModel, optional
        Its scales and texton centres are used (default: the shipped model).
    machine : vmcl.Machine, optional

    Returns
    -------
    float32 array; feature j at orientation o (normal angle o pi / ORIENTATIONS) is named
    ``model.features[j]``.
    """
    machine = machine_for(machine)
    model = _model(model)
    nfeat = len(model.features)
    data, host = _image(image, machine, model.scales, len(model.centres) * 2 + ORIENTATIONS * nfeat)
    height, width = data.shape[:2]
    out = machine.empty((ORIENTATIONS, height, width, nfeat), np.float32)
    machine.launch(machine.kernel("boundary_probability", "oriented", **_defines(model)), (width, height),
                   *_inputs(machine, data, model), _directions(machine), out, np.int64(width), np.int64(height))
    return result(out, host)


def boundary_probability(image: ArrayLike, *, model: BoundaryModel | None = None,
                         machine: Machine | None = None) -> BoundaryProbability:
    """The probability of a boundary at every pixel, from brightness, colour and texture.

    Parameters
    ----------
    image : ndarray or pyopencl.array.Array, (H, W) or (H, W, 3)
        uint8, uint16 or float in [0, 1] (sRGB); a grey image gives no colour gradient.
    model : BoundaryModel, optional
        Default: the model fitted to BSDS500's training images (:data:`MODEL_FILE`).
    machine : vmcl.Machine, optional

    Returns
    -------
    BoundaryProbability
        The thinned probability, the winning normal's angle and the probability before thinning.

    Examples
    --------
    >>> import numpy as np
    >>> from vmcl.early.boundary_probability import boundary_probability
    >>> step = np.zeros((48, 48), np.float32); step[:, 24:] = 0.6
    >>> p = boundary_probability(step).probability
    >>> int(np.argmax(p[24])) in (23, 24), bool(p[24, 5] < 0.05)
    (True, True)
    """
    machine = machine_for(machine)
    model = _model(model)
    data, host = _image(image, machine, model.scales, len(model.centres) * 2 + 17 * len(model.scales) + 12)
    height, width = data.shape[:2]
    dims = (np.int64(width), np.int64(height))
    dense = machine.empty((height, width), np.float32)
    theta = machine.empty((height, width), np.uint8)
    defines = _program_defines(model)
    launch_rows(machine, _kernel(machine, "probability", **defines), width, height,
                *_inputs(machine, data, model), _directions(machine),
                _constant(machine, ("weights", model), lambda: model.weights), dense, theta, *dims)
    thinned = machine.empty((height, width), np.float32)
    orientation = machine.empty((height, width), np.float32)
    machine.launch(_kernel(machine, "thin", **defines), (width, height), dense, theta,
                   _directions(machine), thinned, orientation, *dims)
    return BoundaryProbability(result(thinned, host), result(orientation, host), result(dense, host))
