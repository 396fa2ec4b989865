"""Labels of the discontinuities by a linear classifier: the integration stage's "cartoon".

Seed section "Integration via labeling with a linear classifier": Gamble, Geiger, Weinshall and Poggio
"used a simple linear classifier to label edges at pixels where there exists an intensity discontinuity,
using the output of the line process associated with each low-level vision module"; "each output unit is
a weighted linear combination of its inputs", and "the output is a real value vector of each labels'
support". Here the candidates are the pixels with a brightness edge or a cue's line on them (the cues'
line processes are coupled to the brightness edges, but a boundary seen by one cue alone, such as an
isoluminant colour edge, has no brightness edge), and the label of largest support wins; "none" is one
of the labels, so the classifier also decides which candidates are discontinuities at all.

The inputs (:data:`FEATURES`) are the line processes and the brightness edge within one pixel, as the
paper's, and a few local measures of the restored fields that the line processes do not carry: the
disparity's and the flow's jumps over 3 and 7 px windows, the disparity's crease (second difference at
3 px), the steps of log brightness (3 and 5 px) and of hue (3 px), and the whitest and brightest pixel
within 2 px (highlights take the light's colour). The weights are fitted by multinomial logistic
regression (the outputs stay linear in the inputs; the softmax only shapes the fit) to rendered scenes
with exact labels (:mod:`vmcl.scenes`), once for every combination of the inputs a run can have, so a
run without stereo uses weights fitted without stereo's inputs. benchmarks/labelling.py fits them,
writes ``vmcl/labelling.json`` and measures the classifier on images and presets it was not fitted to.

NumPy in gives NumPy out; device arrays in give a device array out.

References
----------
E. Gamble, D. Geiger, T. Poggio and D. Weinshall, "Integration of vision modules and labeling of surface
discontinuities", IEEE SMC 19(6):1576-1581, 1989.
T. Poggio et al., "The MIT Vision Machine", Proc. DARPA Image Understanding Workshop, 177-198, 1988.
"""

from __future__ import annotations

import functools
import itertools
import json
import os
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
import pyopencl.array as cl_array

from vmcl import metrics
from vmcl.cm.core import ArrayLike, check_bool, check_real, machine_for, real_host_array
from vmcl.cm.core import field as device_field
from vmcl.errors import InputTypeError, InputValueError
from vmcl.fitted import check_fitted_json, with_data, write_fitted_json
from vmcl.labels import BIT_DEFINES, CUES, Cue, Label, cue_bit
from vmcl.machine import Machine

INPUTS = CUES
"""What a run may lack: the cues (:data:`vmcl.labels.CUES`). The features of a missing cue are 0 and its
weights were fitted without them."""

_FEATURE_TABLE = (
    # (name, the cue it needs, or None for the image's own)
    ("stereo line", "stereo"), ("motion line", "motion"), ("colour line", "colour"), ("texture line", "texture"),
    ("brightness edge", None),
    ("disparity jump 3", "stereo"), ("disparity jump 7", "stereo"), ("disparity crease", "stereo"),
    ("flow jump 3", "motion"), ("flow jump 7", "motion"),
    ("log brightness step 3", None), ("log brightness step 5", None),
    ("hue step 3", "colour"), ("whiteness 5", "colour"), ("brightness 5", None),
)

FEATURES = tuple(name for name, _ in _FEATURE_TABLE)
"""The classifier's inputs, in the kernel's slot order (kernels/labelling.cl reads each slot by the
name :data:`SLOT_DEFINES` gives it)."""

SLOT_DEFINES = {"F_" + name.upper().replace(" ", "_"): k for k, name in enumerate(FEATURES)}
"""The kernel's -D names of the feature slots, e.g. F_DISPARITY_JUMP_3."""

_NEEDS = {cue: tuple(k for k, (_, needs) in enumerate(_FEATURE_TABLE) if needs == cue) for cue in INPUTS}

CLASSES = (Label.NONE, Label.DEPTH, Label.ORIENTATION, Label.ALBEDO, Label.SHADOW, Label.SPECULAR,
           Label.TEXTURE)
"""The classifier's outputs: NONE leaves a candidate out of the cartoon."""

WEIGHTS_FILE = Path(__file__).with_name("labelling.json")

# The label a pixel is fitted to: the ground truth's on it or on a 4-neighbour (a line of the MRF sits
# on either side of the site it marks), or within a true pixel's wider tolerance, in the ground truth's own
# precedence (fit_targets).
_FIT_PRECEDENCE = (Label.DEPTH, Label.ORIENTATION, Label.ALBEDO, Label.TEXTURE, Label.SHADOW, Label.SPECULAR)


def _input_names(inputs: Iterable[str], name: str = "inputs") -> set[str]:
    """``inputs`` checked as a collection of names from :data:`INPUTS` (a lone string is refused: its
    letters name nothing)."""
    if isinstance(inputs, str) or not isinstance(inputs, Iterable):
        raise InputTypeError(f"{name} must be a collection of names from {', '.join(INPUTS)}, "
                             f"got {type(inputs).__name__}")
    names = list(inputs)
    unknown = [n for n in names if not isinstance(n, str) or n not in INPUTS]
    if unknown:
        raise InputValueError(f"{name} holds {unknown!r}, which name no input; inputs are {', '.join(INPUTS)}")
    return set(names)


def _key(inputs: Iterable[str]) -> str:
    inputs = _input_names(inputs)
    return "+".join(name for name in INPUTS if name in inputs) or "image"


_INPUT_SETS = tuple(c for k in range(len(INPUTS) + 1) for c in itertools.combinations(INPUTS, k))

KEYS = tuple(_key(c) for c in _INPUT_SETS)
"""The keys of the weights: one per set of inputs, "image" for none."""

def candidate_bits(inputs: Iterable[str]) -> int:
    """The support bits that make a candidate when these inputs ran: theirs and the brightness edge's."""
    bits = Cue.BRIGHTNESS
    for name in _input_names(inputs):
        bits |= cue_bit(name)
    return int(bits)


CANDIDATE_BITS = candidate_bits(INPUTS)
"""Support bits that make a pixel a candidate when every input ran."""


@dataclass(frozen=True, eq=False)
class LinearLabeller:
    """Weights of the linear network, one (1 + len(FEATURES), len(CLASSES)) matrix per set of inputs.

    Attributes
    ----------
    weights : mapping of str to ndarray
        Keyed by the inputs present, joined by "+" in :data:`INPUTS` order ("stereo+motion+colour+texture",
        ..., "image" for none); row 0 is the bias.
    fitted_on : str
        What the weights were fitted to.
    record : mapping or None
        The file's ``"fitted"`` record when it was loaded from a fitted file (:mod:`vmcl.fitted`: the data,
        the code's hash, the date, the parameters' hash, checked when loaded); None otherwise.
    """

    weights: Mapping[str, np.ndarray]
    fitted_on: str = ""
    record: Mapping[str, Any] | None = None
    # Device copies by (machine, key): uploaded once, not per labelling.
    _on_device: dict = field(default_factory=dict, init=False, repr=False)

    def __post_init__(self):
        if not isinstance(self.weights, Mapping):
            raise InputTypeError(f"weights must be a mapping of input-set key to weight matrix, got "
                                 f"{type(self.weights).__name__}")
        if not isinstance(self.fitted_on, str):
            raise InputTypeError(f"fitted_on must be a str, got {type(self.fitted_on).__name__}")
        expected = (1 + len(FEATURES), len(CLASSES))
        for key, w in self.weights.items():
            if key not in KEYS:
                raise InputValueError(f"weights key {key!r} names no set of inputs; keys are {', '.join(KEYS)}")
            if not isinstance(w, np.ndarray) or w.dtype.kind not in "iuf":
                raise InputTypeError(f"weights[{key!r}] must be a real NumPy array, got {type(w).__name__} "
                                     f"{getattr(w, 'dtype', '')}")
            if np.shape(w) != expected:
                raise InputValueError(f"weights[{key!r}] must have shape {expected}, got {np.shape(w)}")
            if not np.all(np.isfinite(w)):
                raise InputValueError(f"weights[{key!r}] must be finite")

    def for_inputs(self, inputs: Iterable[str]) -> np.ndarray:
        key = _key(inputs)
        if key not in self.weights:
            raise InputValueError(f"the labeller has no weights for the inputs {key!r}; it has {sorted(self.weights)}")
        return np.asarray(self.weights[key], np.float32)

    def on_device(self, inputs: Iterable[str], machine: Machine):
        """:meth:`for_inputs` as a device array of ``machine`` (kept for later calls)."""
        key = (machine, _key(inputs))
        if key not in self._on_device:
            self._on_device[key] = machine.to_device(self.for_inputs(inputs))
        return self._on_device[key]

    @classmethod
    def load(cls, path: str | Path | None = None) -> LinearLabeller:
        """The weights in ``path`` (default: the fitted ones shipped with vmcl)."""
        if path is not None and not isinstance(path, (str, os.PathLike)):
            raise InputTypeError(f"path must be a str, an os.PathLike or None, got {type(path).__name__}")
        path = WEIGHTS_FILE if path is None else Path(path)
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, json.JSONDecodeError, RecursionError) as error:
            # RecursionError: a file nested deeper than the decoder can follow is damaged, not weights.
            raise InputValueError(f"{path}: cannot be read as labelling weights ({error})") from None
        if not isinstance(data, dict) or not isinstance(data.get("weights"), dict):
            # A bad file is a bad value of the argument, whatever JSON type it holds.
            raise InputValueError(f"{path}: not labelling weights (a JSON object with a 'weights' object)")
        record = check_fitted_json(data, str(path))
        features, classes = data.get("features", []), data.get("classes", [])
        if not isinstance(features, list) or not isinstance(classes, list):
            # null or a number where the lists belong: a damaged file (tuple() of them would be a TypeError).
            raise InputValueError(f"{path}: not labelling weights ('features' and 'classes' must be lists)")
        if tuple(features) != FEATURES or tuple(classes) != tuple(c.name for c in CLASSES):
            raise InputValueError(f"{path} was fitted to other features or labels than this vmcl's")
        try:
            weights = {k: np.asarray(v, np.float32) for k, v in data["weights"].items()}
            return cls(weights, str(data.get("fitted_on", "")), record)
        except (ValueError, TypeError) as error:
            raise InputValueError(f"{path}: {error}") from None

    def save(self, path: str | Path, provenance: Mapping[str, Any] | None = None) -> Path:
        """Write the weights as JSON with their ``"fitted"`` record (:func:`vmcl.fitted.write_fitted_json`):
        to a new file or one vmcl fitted, never over another file.

        Parameters
        ----------
        path : str or Path
        provenance : mapping, optional
            What the record says they were fitted on and by what (e.g. ``code_sha256``); its ``data``
            defaults to :attr:`fitted_on`.

        Returns
        -------
        Path
            The file written.
        """
        data = {"features": list(FEATURES), "classes": [c.name for c in CLASSES], "fitted_on": self.fitted_on,
                # As they are (JSON keeps a float's shortest exact decimals): rounded, a labeller saved and read
                # back labelled a little differently from the one that was fitted.
                "weights": {k: np.asarray(w, np.float64).tolist() for k, w in self.weights.items()}}
        return write_fitted_json(path, data, with_data(self.fitted_on, provenance))

    @classmethod
    def fit(cls, samples: Iterable[tuple[np.ndarray, ...]], *, l2: float = 1e-3,
            fitted_on: str = "", input_sets: Iterable[Iterable[str]] | None = None) -> LinearLabeller:
        """Fit the weights to (features, support, truth[, tolerance]) samples, for every combination of inputs.

        Parameters
        ----------
        samples : iterable of (features, support, truth) or (features, support, truth, tolerance)
            features: float32 (len(FEATURES), H, W) from :func:`features` with every input present;
            support: uint8 (H, W), :class:`vmcl.labels.Cue` bits; truth: the scene's Label map;
            tolerance: the scene's match tolerance per true pixel (:func:`fit_targets`).
        l2 : float
            Weight decay on the non-bias weights.
        fitted_on : str
            Recorded with the weights.
        input_sets : iterable of sets of :data:`INPUTS`, optional
            The combinations to fit weights for; default all 16.

        Notes
        -----
        Multinomial logistic regression by L-BFGS (scipy), each label's samples weighted by the inverse
        square root of its count, so that the rare labels (specular, orientation) are not drowned by "none"
        and the classes are still weighed toward how often they occur.
        """
        from scipy.optimize import minimize

        check_real(l2, "l2", minimum=0)
        sets = [tuple(p) for p in (_INPUT_SETS if input_sets is None else input_sets)]
        for present in sets:
            if isinstance(present, str) or not set(present) <= set(INPUTS):
                raise InputValueError(f"input_sets: each must be a collection of {', '.join(INPUTS)}, got {present!r}")
        if not sets:
            raise InputValueError("input_sets must name at least one set of inputs")
        rows, bits, targets = [], [], []
        index_of = np.zeros(256, np.int64)  # Label code -> output row
        index_of[[int(c) for c in CLASSES]] = np.arange(len(CLASSES))
        for sample in samples:
            if not isinstance(sample, (tuple, list)) or len(sample) not in (3, 4):
                raise InputValueError(f"samples must hold (features, support, truth[, tolerance]) tuples, got {sample!r:.60}")
            feats, support, truth = np.asarray(sample[0], np.float32), np.asarray(sample[1]), np.asarray(sample[2])
            tolerance = np.asarray(sample[3]) if len(sample) == 4 else None
            if feats.shape != (len(FEATURES),) + support.shape or truth.shape != support.shape:
                raise InputValueError(f"a sample's features must be ({len(FEATURES)}, H, W) and its support and truth "
                                 f"(H, W); got {feats.shape}, {support.shape}, {truth.shape}")
            if not np.all(np.isfinite(feats)):
                raise InputValueError("a sample's features must be finite")
            candidates = (support & CANDIDATE_BITS) != 0
            rows.append(np.moveaxis(feats, 0, -1)[candidates])
            bits.append(support[candidates])
            targets.append(index_of[fit_targets(truth, tolerance)[candidates]])
        if not rows or not sum(len(r) for r in rows):
            raise InputValueError("samples must hold at least one candidate pixel (support bits set)")
        x_all, bits_all, y_all = (np.concatenate(a) for a in (rows, bits, targets))
        nc = len(CLASSES)
        weights = {}
        for present in sets:
            # A set's candidates: pixels a cue of the set or a brightness edge marks.
            chosen = (bits_all & candidate_bits(present)) != 0
            x, y = x_all[chosen].astype(np.float64), y_all[chosen]
            n = len(y)
            count = np.bincount(y, minlength=nc) + 1.0
            sample_weight = (1.0 / np.sqrt(count))[y]
            sample_weight *= n / sample_weight.sum()
            onehot = np.eye(nc)[y]
            kept = np.ones(len(FEATURES), bool)
            for name in set(INPUTS) - set(present):
                kept[list(_NEEDS[name])] = False
            design = np.concatenate([np.ones((n, 1)), x[:, kept]], axis=1)
            p = design.shape[1]

            def loss_and_gradient(theta, design=design, p=p, n=n, y=y, onehot=onehot, sample_weight=sample_weight):
                w = theta.reshape(p, nc)
                z = design @ w
                z -= z.max(axis=1, keepdims=True)
                prob = np.exp(z)
                prob /= prob.sum(axis=1, keepdims=True)
                loss = -(sample_weight * np.log(prob[np.arange(n), y] + 1e-12)).sum() / n + l2 * (w[1:] ** 2).sum()
                grad = design.T @ ((prob - onehot) * sample_weight[:, None]) / n
                grad[1:] += 2 * l2 * w[1:]
                return loss, grad.ravel()

            found = minimize(loss_and_gradient, np.zeros(p * nc), jac=True, method="L-BFGS-B",
                             options={"maxiter": 1000})
            if not found.success:
                raise RuntimeError(f"the fit for inputs {_key(present)!r} did not converge: {found.message}")
            full = np.zeros((1 + len(FEATURES), nc))
            full[np.concatenate([[True], kept])] = found.x.reshape(p, nc)
            weights[_key(present)] = full.astype(np.float32)
        return cls(weights, fitted_on)


def fit_targets(truth: np.ndarray, tolerance: np.ndarray | None = None) -> np.ndarray:
    """The label each pixel is fitted to: the truth's on it or on a 4-neighbour (within 1 px), in
    precedence order.

    With ``tolerance`` (a rendered scene's ``Scene.tolerance``: per true pixel, the distance within which
    it counts as found), a true pixel also reaches the pixels farther within its tolerance: a texture-only
    boundary, known only to within its texels, is fitted on the lines near it, as it is scored. Such far
    reaches come first, so that every label's own pixels and their 4-neighbours still take that label.
    """
    real_host_array(truth, "truth", ndims=(2,), empty=True)
    if truth.dtype.kind not in "iu":
        raise InputTypeError(f"truth must be an integer Label map, got dtype {truth.dtype}")
    if tolerance is not None:
        real_host_array(tolerance, "tolerance", ndims=(2,), empty=True)
        if tolerance.shape != truth.shape:
            raise InputValueError(f"tolerance has shape {tolerance.shape}, truth {truth.shape}: they must match")
    out = np.zeros(truth.shape, np.uint8)
    if tolerance is not None:
        # Only true pixels known to more than 1 px reach farther than the pass below paints anyway.
        for label in reversed(_FIT_PRECEDENCE):
            out[metrics.within_tolerance((truth == label) & (tolerance > 1), tolerance)] = label
    for label in reversed(_FIT_PRECEDENCE):
        out[metrics.within_tolerance(truth == label, 1.0)] = label
    return out


def _run(support, image, disparity, flow, hue, texture, labeller, machine, classify: bool, probability=None):
    s, host = device_field(support, "support", machine, ndims=(2,), dtypes=(np.uint8,))
    shape = s.shape
    img, _ = device_field(image, "image", machine, ndims=(2, 3), dtypes=(np.float32,))
    if img.shape[:2] != shape or (img.ndim == 3 and img.shape[2] != 3):
        raise InputValueError(f"image must be (H, W) or (H, W, 3) with the support's (H, W) {shape}, got {img.shape}")
    present = {"texture"} if check_bool(texture, "texture") else set()
    fields: dict[str, cl_array.Array | None] = {}
    for name, array, ndims, wanted, needs in (("disparity", disparity, (2,), shape, "stereo"),
                                              ("flow", flow, (3,), shape + (2,), "motion"),
                                              ("hue", hue, (2,), shape, "colour")):
        if array is None:
            fields[name] = None
            continue
        checked, _ = device_field(array, name, machine, ndims=ndims, dtypes=(np.float32,))
        if checked.shape != wanted:
            raise InputValueError(f"{name} must have shape {wanted}, got {checked.shape}")
        fields[name] = checked
        present.add(needs)
    placeholder = machine.empty(1, np.float32)  # never read: its input's HAS_ define is 0
    args = [s, img] + [placeholder if fields[n] is None else fields[n] for n in ("disparity", "flow", "hue")]
    defines = {"NF": len(FEATURES), "NC": len(CLASSES), "RGB": int(img.ndim == 3), "CLASSIFY": int(classify),
               "HAS_STEREO": int("stereo" in present), "HAS_MOTION": int("motion" in present),
               "HAS_COLOUR": int("colour" in present), "CANDIDATE_BITS": candidate_bits(present),
               "CODES": ",".join(str(int(c)) for c in CLASSES), **BIT_DEFINES, **SLOT_DEFINES}
    height, width = shape
    if classify:
        labels, strength = machine.empty(shape, np.uint8), machine.empty(shape, np.float32)
        if probability is not None:
            probability, _ = device_field(probability, "probability", machine, ndims=(2,), dtypes=(np.float32,))
            if probability.shape != shape:
                raise InputValueError(f"probability must have the support's shape {shape}, got {probability.shape}")
        kernel = machine.kernel("labelling", "label_features", HAS_PROBABILITY=int(probability is not None), **defines)
        args += [labeller.on_device(present, machine), placeholder if probability is None else probability, labels,
                 strength]
        machine.launch(kernel, (width, height), *args, np.int64(width), np.int64(height))
        return Labelling(labels.get(), strength.get()) if host else Labelling(labels, strength)
    out = machine.empty((len(FEATURES),) + shape, np.float32)
    kernel = machine.kernel("labelling", "label_features", HAS_PROBABILITY=0, **defines)
    machine.launch(kernel, (width, height), *args, out, np.int64(width), np.int64(height))
    return out.get() if host else out


class Labelling(NamedTuple):
    """The classifier's output at every pixel.

    Attributes
    ----------
    labels : uint8 (H, W)
        The :class:`vmcl.labels.Label` code of the largest support at each candidate; 0 (NONE) elsewhere.
    strength : float32 (H, W) in [0, 1]
        The strength of a discontinuity (:func:`classify`): the classifier's support for some
        discontinuity is 1 minus the softmax's probability of NONE (the model the weights were fitted as).
    """

    labels: ArrayLike
    strength: ArrayLike


def features(support: ArrayLike, image: ArrayLike, *, disparity: ArrayLike | None = None,
             flow: ArrayLike | None = None, hue: ArrayLike | None = None,
             machine: Machine | None = None) -> ArrayLike:
    """The classifier's inputs at every pixel, float32 (len(FEATURES), H, W); see :func:`label`."""
    machine = machine_for(machine)
    return _run(support, image, disparity, flow, hue, True, None, machine, classify=False)


def label(support: ArrayLike, image: ArrayLike, *, disparity: ArrayLike | None = None,
          flow: ArrayLike | None = None, hue: ArrayLike | None = None, texture: bool = True,
          labeller: LinearLabeller | None = None, machine: Machine | None = None) -> ArrayLike:
    """The cartoon: a :class:`vmcl.labels.Label` code at every labelled discontinuity, 0 elsewhere.

    Parameters
    ----------
    support : (H, W) uint8
        :class:`vmcl.labels.Cue` bits (:func:`vmcl.integrate.integrate`'s support map): the
        candidates are the pixels with a brightness edge or a line of a cue that ran.
    image : (H, W) or (H, W, 3) float32
        The image in [0, 1].
    disparity, hue : (H, W) float32, optional
        The restored disparity (stereo) and hue (colour); NaN where there is none.
    flow : (H, W, 2) float32, optional
        The restored flow (motion).
    texture : bool
        Whether the texture cue ran (its line bit in ``support`` means something).
    labeller : LinearLabeller, optional
        Default: the fitted weights shipped with vmcl (:meth:`LinearLabeller.load`). The weights used
        are those fitted for the inputs given.
    machine : vmcl.Machine, optional

    Returns
    -------
    uint8 (H, W): NumPy for NumPy support, a device array for a device support.
    """
    return classify(support, image, disparity=disparity, flow=flow, hue=hue, texture=texture, labeller=labeller,
                    machine=machine).labels


def classify(support: ArrayLike, image: ArrayLike, *, disparity: ArrayLike | None = None,
             flow: ArrayLike | None = None, hue: ArrayLike | None = None, texture: bool = True,
             labeller: LinearLabeller | None = None, probability: ArrayLike | None = None,
             machine: Machine | None = None) -> Labelling:
    """:func:`label`'s labels with the strength of a discontinuity at every pixel.

    Parameters as :func:`label`'s, and:

    probability : (H, W) float32 in [0, 1], optional
        The image's probability of boundary (:func:`vmcl.early.boundary_probability.boundary_probability`).
        With it the strength is this probability, raised to the classifier's support where a stereo or
        motion line marks a candidate (what one image cannot show); without it, the classifier's
        support at the candidates and 0 elsewhere.

    Returns a :class:`Labelling`: NumPy fields for NumPy support, device arrays for a device support.
    """
    machine = machine_for(machine)
    if labeller is not None and not isinstance(labeller, LinearLabeller):
        raise InputTypeError(f"labeller must be a LinearLabeller or None, got {type(labeller).__name__}")
    return _run(support, image, disparity, flow, hue, texture, labeller or default_labeller(), machine,
                classify=True, probability=probability)


@functools.cache
def default_labeller() -> LinearLabeller:
    """The shipped weights, read once."""
    return LinearLabeller.load()


__all__ = ["CANDIDATE_BITS", "CLASSES", "FEATURES", "INPUTS", "KEYS", "Labelling", "LinearLabeller", "candidate_bits",
           "classify", "default_labeller", "features", "fit_targets", "label"]
