"""The stereo evaluation: vmcl's depth-only pipeline beside OpenCV's block matchers on Middlebury ground truth.

One harness, used by ``vmcl eval stereo`` and by benchmarks/stereo.py, so that every figure vmcl reports
about its stereo comes from the same reading of the data and the same configuration of the baselines:

- the data: any scene folder in a Middlebury layout (:func:`vmcl.datasets.read_stereo_folder`);
- the methods: vmcl's pipeline with only stereo enabled, which finds its disparity range from the images
  (:func:`vmcl_method`), and OpenCV's StereoBM and StereoSGBM (in its default MODE_SGBM and in
  MODE_SGBM_3WAY) configured as OpenCV documents them (:func:`opencv_baselines`). Only the baselines
  are told how many disparities to search: the number the data set publishes (info.txt, calib.txt),
  else the range vmcl estimates from the images, never the ground truth;
- the figures (:func:`evaluate_pair`): Middlebury's bad-pixel rates at 0.5, 1 and 2 px over each mask the
  scene has (nonocc, all, disc; every pixel of known disparity where it has none), a pixel without a
  value counted as bad, with the density and the mean absolute error beside them
  (:func:`vmcl.metrics.evaluate_disparity`); the wall time of a call after a warm-up call; and, for each
  baseline, the bad-1 rate on the pixels that baseline matched, its own beside vmcl's, so that a sparse
  baseline is also compared where it answers. A mask that marks no pixel leaves its region unscored, and a
  baseline that cannot run on the pair (too small for its block, more disparities published than it can
  search) is marked as not run: either is named with the reason, and the rest of the pair is still scored;
- the notes: how each method was configured for the pair, and what vmcl's run said about it
  (:attr:`vmcl.result.Result.notes`: the disparity range it found, views that look swapped).

OpenCV's configuration, from its documentation: grey 8-bit input (``cv2.cvtColor`` RGB to grey, so
``cn = 1``); StereoBM with block 15 (OpenCV's Python stereo tutorial) and numDisparities a multiple of
16; StereoSGBM with block 5, ``P1 = 8 * cn * blockSize**2`` and ``P2 = 32 * cn * blockSize**2`` (the
values its documentation gives as reasonable), uniquenessRatio 10 (its documentation says 5 to 15 is
usually good enough; its default, 0, turns the check off). Every other parameter is OpenCV's default.
OpenCV's disparities are fixed point (16 times the disparity); those below ``minDisparity`` (0 here) mean
"no value" and become NaN.

References
----------
D. Scharstein and R. Szeliski, "A taxonomy and evaluation of dense two-frame stereo correspondence
algorithms", IJCV 47(1/2/3):7-42, 2002. H. Hirschmüller, "Stereo processing by semiglobal matching and
mutual information", IEEE TPAMI 30(2):328-341, 2008.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import cv2
import numpy as np

from vmcl.cm.core import check_bool, check_choice, check_int, check_unmasked
from vmcl.datasets import StereoPair
from vmcl.early.disparity_range import estimate_range
from vmcl.errors import InputError, InputTypeError, InputValueError
from vmcl.machine import Machine
from vmcl.metrics import evaluate_disparity
from vmcl.pictures import eight_bits

__all__ = [
    "BM_BLOCK",
    "DEPTH_ONLY",
    "SGBM_BLOCK",
    "SGBM_MODES",
    "THRESHOLDS",
    "UNIQUENESS_RATIO",
    "MatchedComparison",
    "MethodScores",
    "PairEvaluation",
    "StereoMethod",
    "baseline_disparities",
    "evaluate_pair",
    "grey",
    "markdown_tables",
    "opencv_baselines",
    "opencv_disparity",
    "stereo_bm",
    "stereo_sgbm",
    "vmcl_method",
]

BM_BLOCK = 15
"""StereoBM's block size, as OpenCV's Python stereo tutorial sets it."""
SGBM_BLOCK = 5
"""StereoSGBM's block size."""
UNIQUENESS_RATIO = 10
"""StereoSGBM's uniquenessRatio: OpenCV's documentation says 5 to 15 is usually good enough."""
SGBM_MODES = {"MODE_SGBM": cv2.STEREO_SGBM_MODE_SGBM, "3WAY": cv2.STEREO_SGBM_MODE_SGBM_3WAY}
"""StereoSGBM's modes compared: OpenCV's default (5 directions) and its faster 3-way variant."""
_OPENCV_NAMES = ("OpenCV StereoBM", *(f"OpenCV StereoSGBM {mode}" for mode in SGBM_MODES))
THRESHOLDS = (0.5, 1.0, 2.0)
"""The bad-pixel thresholds reported, in pixels."""

DEPTH_ONLY = {"motion": {"enabled": False}, "colour": {"enabled": False}, "texture": {"enabled": False},
              "grouping": {"enabled": False}, "labels": {"boundary_probability": False}}
"""The Config (as :meth:`vmcl.pipeline.Config.from_dict` takes it) of the depth-only machine the evaluation
runs: stereo with its defaults and nothing the disparity does not depend on."""

_CN = 1  # channels of the images OpenCV's matchers are given (grey)
_KNOWN = "known"  # the region of a scene without masks: every pixel of known disparity


# --------------------------------------------------------------------------------------------- methods


@dataclass(frozen=True)
class StereoMethod:
    """A disparity method under evaluation.

    Attributes
    ----------
    name : str
    compute : callable
        ``compute(left, right)`` with the images as read (:class:`vmcl.datasets.StereoPair`), returns the
        left-view disparity, (H, W) float32, NaN where the method gives no value. A baseline that cannot run
        on the pair raises :class:`vmcl.errors.InputError` saying why.
    baseline : bool
        A reference method (OpenCV's): the evaluation compares the others with it on the pixels it matched,
        and marks it as not run, with the reason, where it cannot run on the pair.
    note : str
        How the method was configured for the pair, printed under the tables.
    compute_with_notes : callable, optional
        ``compute_with_notes(left, right)`` returns ``compute``'s disparity and the notes the method made on
        the pair (list of str, each ready to print); the evaluation calls it, where given, instead of
        ``compute``, so that what a method said about a pair is kept beside its scores.
    """

    name: str
    compute: Callable[[np.ndarray, np.ndarray], np.ndarray]
    baseline: bool = False
    note: str = ""
    compute_with_notes: Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, list[str]]] | None = None


def grey(image: np.ndarray) -> np.ndarray:
    """An image as OpenCV's stereo matchers take it: 8-bit grey (RGB converted by ``cv2.cvtColor``).

    Parameters
    ----------
    image : (H, W) or (H, W, 3) uint8 array
        Grey or RGB.

    Returns
    -------
    (H, W) uint8 array
    """
    return _grey(image, "image")


def _grey(image, name: str) -> np.ndarray:
    """:func:`grey`, refusals naming the argument ``name``."""
    if not isinstance(image, np.ndarray):
        raise InputTypeError(f"{name} must be a NumPy array, got {type(image).__name__}")
    check_unmasked(image, name)
    if image.dtype != np.uint8:
        # OpenCV's block matchers take 8-bit images only; a 16-bit file is not silently rescaled.
        raise InputValueError(f"{name} must be uint8 for OpenCV's stereo matchers, got {image.dtype}")
    if image.ndim == 3 and image.shape[2] == 3:
        return cv2.cvtColor(image, cv2.COLOR_RGB2GRAY)
    if image.ndim == 2:
        return image
    raise InputValueError(f"{name} must have shape (H, W) or (H, W, 3), got {image.shape}")


_MAX_DISPARITIES = 2048
"""OpenCV's matchers write 16 * d to an int16 map: disparities 0 .. 2047 (numDisparities 2048) fit."""


def _check_disparities(count) -> int:
    count = check_int(count, "num_disparities", minimum=16, maximum=_MAX_DISPARITIES)
    if count % 16:
        raise InputValueError(f"num_disparities must be a multiple of 16 (OpenCV's requirement), got {count}")
    return count


def stereo_bm(num_disparities: int) -> cv2.StereoBM:
    """OpenCV's StereoBM with block 15 and ``num_disparities``, its other parameters OpenCV's defaults.

    Parameters
    ----------
    num_disparities : int
        A positive multiple of 16, at most 2048 (OpenCV's 16-bit fixed-point output holds disparities
        below 2048): disparities 0 .. num_disparities - 1 are searched.

    Returns
    -------
    cv2.StereoBM
    """
    return cv2.StereoBM.create(numDisparities=_check_disparities(num_disparities), blockSize=BM_BLOCK)


def stereo_sgbm(num_disparities: int, mode: str = "3WAY") -> cv2.StereoSGBM:
    """OpenCV's StereoSGBM as its documentation configures it for grey images.

    Block 5, ``P1 = 8 * cn * blockSize**2 = 200``, ``P2 = 32 * cn * blockSize**2 = 800`` with ``cn = 1``,
    uniquenessRatio 10, minDisparity 0; the other parameters OpenCV's defaults.

    Parameters
    ----------
    num_disparities : int
        A positive multiple of 16, at most 2048.
    mode : {"3WAY", "MODE_SGBM"}
        ``cv2.STEREO_SGBM_MODE_SGBM_3WAY`` or OpenCV's default ``cv2.STEREO_SGBM_MODE_SGBM``.

    Returns
    -------
    cv2.StereoSGBM
    """
    count = _check_disparities(num_disparities)
    mode = check_choice(mode, "mode", SGBM_MODES)
    area = SGBM_BLOCK * SGBM_BLOCK
    return cv2.StereoSGBM.create(minDisparity=0, numDisparities=count, blockSize=SGBM_BLOCK, P1=8 * _CN * area,
                                 P2=32 * _CN * area, uniquenessRatio=UNIQUENESS_RATIO, mode=SGBM_MODES[mode])


def opencv_disparity(matcher, left: np.ndarray, right: np.ndarray) -> np.ndarray:
    """A matcher's disparity in pixels: its fixed-point output / 16, NaN where it gives none.

    Parameters
    ----------
    matcher : cv2.StereoMatcher
        With minDisparity 0 (:func:`stereo_bm`, :func:`stereo_sgbm`).
    left, right : ndarray
        uint8 grey or RGB images of one shape (:func:`grey` converts them), larger than the matcher's block
        on each side; for StereoSGBM, wider than numDisparities plus half the block; for StereoBM, narrower
        than numDisparities (no value anywhere) or at least numDisparities plus the block less one.

    Returns
    -------
    (H, W) float32 array
        OpenCV's values below ``minDisparity * 16 = 0`` (its "no value", ``(minDisparity - 1) * 16``) are NaN.
    """
    if not isinstance(matcher, cv2.StereoMatcher):
        raise InputTypeError(f"matcher must be a cv2.StereoMatcher, got {type(matcher).__name__}")
    if matcher.getMinDisparity() != 0:
        raise InputValueError(f"matcher must have minDisparity 0, got {matcher.getMinDisparity()}")
    left, right = _grey(left, "left"), _grey(right, "right")
    if left.shape[:2] != right.shape[:2]:
        raise InputValueError(f"left and right must have one size, got {left.shape[:2]} and {right.shape[:2]}")
    height, width = left.shape[:2]
    block, count = matcher.getBlockSize(), matcher.getNumDisparities()
    # Below these sizes OpenCV raises errors (the block must be smaller than the image; StereoSGBM: a row must
    # hold the disparities and half a block), StereoSGBM's 3-way mode can abort the process, and StereoBM
    # returns memory it never wrote (disparities of 2000 px, different each call) where a row holds the
    # disparities but not a block more.
    if min(height, width) <= block:
        raise InputValueError(f"left and right must be larger than the matcher's block ({block} pixels) on each "
                              f"side, got {height} x {width}")
    if isinstance(matcher, cv2.StereoSGBM) and width <= count + block // 2:
        raise InputValueError(f"left and right must be wider than StereoSGBM's numDisparities plus half its block "
                              f"({count} + {block // 2} pixels), got {width}")
    if isinstance(matcher, cv2.StereoBM) and count <= width < count + block - 1:
        raise InputValueError(f"left and right must be at least StereoBM's numDisparities plus its block less one "
                              f"({count} + {block - 1} pixels) wide, got {width}")
    raw = matcher.compute(left, right)
    disparity = raw.astype(np.float32) / np.float32(16)
    disparity[raw < 0] = np.nan
    return disparity


def baseline_disparities(pair: StereoPair) -> tuple[int, str]:
    """numDisparities for OpenCV's matchers on a pair, and where it comes from.

    The number the data set publishes (:attr:`vmcl.datasets.StereoPair.published_disparities`), else
    the largest disparity :func:`vmcl.early.disparity_range.estimate_range` finds from the images plus
    one (never the ground truth), rounded up to a multiple of 16 as OpenCV requires.

    Parameters
    ----------
    pair : vmcl.datasets.StereoPair

    Returns
    -------
    (int, str)
        The number and a sentence saying where it comes from.
    """
    _check_pair(pair)
    if pair.published_disparities is not None:
        count = pair.published_disparities
        source = f"the data set publishes {count} disparities{_published_by(pair)}"
    else:
        found = estimate_range(pair.left, pair.right)
        count = max(found.d_max, 0) + 1
        basis = "found" if found.decided else "not decided by the images: the fallback"
        source = (f"the data set publishes no disparity range; vmcl's estimate from the images ({basis}) "
                  f"is {found.d_min}..{found.d_max}")
    rounded = -(-max(count, 1) // 16) * 16
    return rounded, f"numDisparities {rounded}: {source}"


def _published_by(pair: StereoPair) -> str:
    """`` (in FILE)`` naming the file of the pair's folder that publishes its disparities (a v2 folder's
    info.txt, a 2014 folder's calib.txt), so that a number a user must fix names where it is; empty for a
    pair that was not read from such a folder."""
    files = [str(pair.folder / name) for name in ("info.txt", "calib.txt") if (pair.folder / name).is_file()]
    return f" (in {' or '.join(files)})" if files else ""


def opencv_baselines(pair: StereoPair) -> list[StereoMethod]:
    """OpenCV's StereoBM and StereoSGBM (MODE_SGBM and 3WAY) for a pair, as OpenCV documents them.

    Parameters
    ----------
    pair : vmcl.datasets.StereoPair
        Gives numDisparities (:func:`baseline_disparities`).

    Returns
    -------
    list of StereoMethod
        "OpenCV StereoBM", "OpenCV StereoSGBM MODE_SGBM", "OpenCV StereoSGBM 3WAY".
        Where numDisparities exceeds what OpenCV can search (2048), each one's ``compute`` raises
        :class:`vmcl.errors.InputValueError` saying so, and :func:`evaluate_pair` marks them as not run.
    """
    count, source = baseline_disparities(pair)
    note = f"OpenCV's matchers: {source}"
    if count > _MAX_DISPARITIES:
        # A number published for the pair (info.txt, calib.txt) that OpenCV cannot search is no reason to
        # leave out the other methods' scores on the pair: the baselines alone cannot run.
        reason = f"{source}, more than the {_MAX_DISPARITIES} OpenCV's matchers can search"
        return [StereoMethod(name, _refusing(reason), baseline=True) for name in _OPENCV_NAMES]
    wide = [name for name, image in (("left", pair.left), ("right", pair.right)) if image.dtype == np.uint16]
    if wide:
        note += (f"; the 16-bit {' and '.join(wide)} view{'s are' if len(wide) == 2 else ' is'} given to them at 8 "
                 "bits (levels / 257, rounded), as their block matchers take 8-bit images only")
    # Each matcher is made once, so that the time of a call is the matching (and the grey conversion).
    matchers = [stereo_bm(count), *(stereo_sgbm(count, mode) for mode in SGBM_MODES)]
    return [_opencv_method(name, matcher, note) for name, matcher in zip(_OPENCV_NAMES, matchers, strict=True)]


def _refusing(reason: str) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    """A ``compute`` that cannot run on its pair, and says why."""
    def compute(left: np.ndarray, right: np.ndarray) -> np.ndarray:
        raise InputValueError(reason)

    return compute


def _opencv_method(name: str, matcher: cv2.StereoMatcher, note: str) -> StereoMethod:
    def compute(left: np.ndarray, right: np.ndarray) -> np.ndarray:
        # Each view by its own type: a pair may hold a 16-bit and an 8-bit view, both of which vmcl takes.
        return opencv_disparity(matcher, *(eight_bits(view) if view.dtype == np.uint16 else view
                                           for view in (left, right)))

    return StereoMethod(name, compute, baseline=True, note=note)


def vmcl_method(config=None, *, machine: Machine | None = None) -> StereoMethod:
    """vmcl's depth-only pipeline: :class:`vmcl.pipeline.VisionMachine`'s dense restored disparity.

    Parameters
    ----------
    config : vmcl.pipeline.Config, optional
        Default: :data:`DEPTH_ONLY`, stereo with its defaults, every other cue, the grouping and the image's
        probability of boundary switched off (an evaluation runs what it measures: none of them changes the
        disparity). The stereo section finds its disparity range from the images unless the config sets
        one (the note says which).
    machine : vmcl.Machine, optional
        As :class:`vmcl.pipeline.VisionMachine` takes it.

    Returns
    -------
    StereoMethod
        "vmcl (dense, MRF)"; one VisionMachine serves every pair. Its ``compute_with_notes`` gives the run's
        :attr:`vmcl.result.Result.notes` (the disparity range found, views that look swapped), each after
        "vmcl: ". Where the run gives no disparity (images of one brightness: nothing to match), the
        disparity has no value anywhere (NaN), and the notes say why.
    """
    from vmcl.pipeline import Config, VisionMachine

    if config is None:
        config = Config.from_dict(DEPTH_ONLY)
    elif not isinstance(config, Config):
        raise InputTypeError(f"config must be a vmcl.pipeline.Config or None, got {type(config).__name__}")
    if not config.stereo.enabled:
        raise InputValueError("config must enable stereo ([stereo] enabled = true) to be evaluated on stereo")
    vm = VisionMachine(config, machine=machine)
    given = (config.stereo.d_min, config.stereo.d_max)
    note = ("vmcl: the disparity range found from the images" if given == (None, None)
            else f"vmcl: the disparity range bounds given by the config, d_min {given[0]}, d_max {given[1]}")

    def compute_with_notes(left: np.ndarray, right: np.ndarray) -> tuple[np.ndarray, list[str]]:
        result = vm.run(left, right)
        if result.disparity is None:
            disparity = np.full(np.shape(left)[:2], np.nan, np.float32)
        else:
            disparity = np.asarray(result.disparity, dtype=np.float32)
        return disparity, [f"vmcl: {line}" for line in result.notes]

    def compute(left: np.ndarray, right: np.ndarray) -> np.ndarray:
        return compute_with_notes(left, right)[0]

    return StereoMethod("vmcl (dense, MRF)", compute, note=note, compute_with_notes=compute_with_notes)


# --------------------------------------------------------------------------------------------- evaluation


@dataclass(frozen=True)
class MethodScores:
    """One method's figures over one region of a pair.

    Attributes
    ----------
    method, region : str
        The region is a mask's name ("nonocc", "all", "disc") or "known" (every pixel of known disparity).
    bad : dict of float to float
        Share (0..1) of the region's pixels whose error exceeds each of :data:`THRESHOLDS`, a pixel
        without a value counted as bad.
    density : float
        Share of the region's pixels with a value.
    mae : float
        Mean absolute error in pixels over the region's pixels with a value (NaN if none has).
    pixels : int
        The region's pixels.
    ms : float
        Wall time of the method's call on the pair (after a warm-up call where the evaluation was warm).
    """

    method: str
    region: str
    bad: dict[float, float]
    density: float
    mae: float
    pixels: int
    ms: float


@dataclass(frozen=True)
class MatchedComparison:
    """Bad-1 rates on the pixels a baseline matched: the baseline's beside another method's.

    Attributes
    ----------
    baseline, method, region : str
        The region is "nonocc" where the pair has that mask, else the first of its masks, else "known".
    matched : int
        The region's pixels the baseline gave a value.
    baseline_bad, method_bad : float
        Share (0..1) of those pixels with an error above 1 px (the method's pixels without a value
        counted as bad); NaN when the baseline matched none.
    """

    baseline: str
    method: str
    region: str
    matched: int
    baseline_bad: float
    method_bad: float


@dataclass(frozen=True)
class PairEvaluation:
    """Every method's figures on one pair.

    Attributes
    ----------
    scene : str
        The pair's name.
    scores : list of MethodScores
        For each method, each region.
    matched : list of MatchedComparison
        For each baseline, each method that is not one.
    notes : list of str
        How the methods that ran were configured for the pair, and what they said about it (vmcl's run
        notes), each note once.
    disparities : dict of str to ndarray
        Each method's disparity, by its name.
    not_run : dict of str to str
        Each baseline that could not run on the pair, and why: it has no scores and no comparison.
    not_scored : dict of str to str
        Each region whose mask marks no pixel, and why: no method has scores there.
    """

    scene: str
    scores: list[MethodScores]
    matched: list[MatchedComparison]
    notes: list[str] = field(default_factory=list)
    disparities: dict[str, np.ndarray] = field(default_factory=dict)
    not_run: dict[str, str] = field(default_factory=dict)
    not_scored: dict[str, str] = field(default_factory=dict)


def _check_pair(pair) -> None:
    if not isinstance(pair, StereoPair):
        raise InputTypeError(f"pair must be a vmcl.datasets.StereoPair, got {type(pair).__name__}")


def _regions(pair: StereoPair) -> tuple[dict[str, np.ndarray], dict[str, str]]:
    """The pair's masks, or every pixel of known disparity where it has none: those that hold a pixel, and
    why each other one is not scored. Refuses a pair with no pixel to score anywhere."""
    if not pair.masks:
        known = np.isfinite(pair.disparity)
        if not known.any():
            raise InputValueError(f"pair {pair.name}: no pixel to evaluate: its ground truth (disparity) has no "
                                  "known value")
        return {_KNOWN: known}, {}
    # A scene without depth jumps (or a crop of one) has an empty disc mask: its other regions still count.
    regions = {name: mask for name, mask in pair.masks.items() if np.any(mask)}
    not_scored = {name: f"the {name} mask of {pair.folder} marks no pixel" for name in pair.masks
                  if name not in regions}
    if not regions:
        raise InputValueError(f"pair {pair.name}: no pixel to evaluate: every mask of {pair.folder} "
                              f"({', '.join(pair.masks)}) marks none")
    return regions, not_scored


def _run(method: StereoMethod, pair: StereoPair, warm: bool) -> tuple[np.ndarray, list[str], float]:
    """The method's disparity on the pair, its notes on it, and the wall ms of the (timed) call."""
    def call() -> tuple[np.ndarray, list[str]]:
        if method.compute_with_notes is not None:
            return method.compute_with_notes(pair.left, pair.right)
        return method.compute(pair.left, pair.right), []

    if warm:
        call()  # builds kernels and buffers: the timed call is the steady state
    start = time.perf_counter()
    disparity, notes = call()
    return disparity, notes, (time.perf_counter() - start) * 1e3


def _bad1(disparity: np.ndarray, pair: StereoPair, mask: np.ndarray) -> float:
    return evaluate_disparity(disparity, pair.disparity, mask=mask, thresholds=(1.0,)).bad[1.0]


def evaluate_pair(pair: StereoPair, methods: Sequence[StereoMethod], *, warm: bool = True) -> PairEvaluation:
    """Evaluate methods on a pair: bad 0.5 / 1 / 2, density, MAE and time, and bad 1 where each baseline matched.

    Parameters
    ----------
    pair : vmcl.datasets.StereoPair
    methods : sequence of StereoMethod
        For example ``[vmcl_method(), *opencv_baselines(pair)]``.
    warm : bool
        Call each method once before the timed call (kernel builds and first allocations not timed).

    Returns
    -------
    PairEvaluation

    Raises
    ------
    InputValueError
        If the pair has no pixel to score (every mask empty), or a method that is not a baseline refuses it.

    Notes
    -----
    Rates are over each mask the pair has (nonocc, all, disc), else over every pixel of known
    disparity ("known"); a pixel without a value counts as bad (:func:`vmcl.metrics.evaluate_disparity`).
    A mask that marks no pixel is not scored (``not_scored`` says which), and a baseline that refuses the
    pair (:class:`vmcl.errors.InputError`: too small for its block, too many disparities) is not run
    (``not_run`` says why); the other regions and methods are scored.
    For each baseline, the other methods' bad-1 rate is also taken on the pixels of the "nonocc" region
    (else the first scored) where the baseline gave a value, beside the baseline's own there.
    """
    _check_pair(pair)
    if isinstance(methods, (str, bytes)) or not isinstance(methods, Sequence):
        raise InputTypeError(f"methods must be a sequence of StereoMethod, got {type(methods).__name__}")
    if not methods or not all(isinstance(m, StereoMethod) for m in methods):
        raise InputValueError("methods must be a non-empty sequence of StereoMethod")
    names = [m.name for m in methods]
    if len(set(names)) != len(names):
        raise InputValueError(f"methods must have distinct names, got {names}")
    warm = check_bool(warm, "warm")
    regions, not_scored = _regions(pair)
    scores, disparities, not_run = [], {}, {}
    notes: dict[str, None] = {}  # ordered, each note once
    for method in methods:
        try:
            disparity, said, ms = _run(method, pair, warm)
        except InputError as error:
            if not method.baseline:  # the methods under evaluation must run: the pair is refused
                raise
            not_run[method.name] = str(error)
            continue
        disparities[method.name] = disparity
        notes.update(dict.fromkeys([method.note] if method.note else []))
        notes.update(dict.fromkeys(said))
        for region, mask in regions.items():
            s = evaluate_disparity(disparity, pair.disparity, mask=mask, thresholds=THRESHOLDS)
            scores.append(MethodScores(method.name, region, s.bad, s.density, s.mae, s.n_evaluated, ms))
    region = "nonocc" if "nonocc" in regions else next(iter(regions))
    matched = []
    for baseline in (m for m in methods if m.baseline and m.name in disparities):
        at = regions[region] & np.isfinite(disparities[baseline.name])
        count = int(np.count_nonzero(at))
        for other in (m for m in methods if not m.baseline):
            if count:
                rates = _bad1(disparities[baseline.name], pair, at), _bad1(disparities[other.name], pair, at)
            else:
                rates = float("nan"), float("nan")
            matched.append(MatchedComparison(baseline.name, other.name, region, count, *rates))
    return PairEvaluation(pair.name, scores, matched, list(notes), disparities, not_run, not_scored)


# --------------------------------------------------------------------------------------------- tables


def _percent(value: float) -> str:
    return "-" if np.isnan(value) else f"{100 * value:.1f}"


def _table(header: Sequence[str], rows: Sequence[Sequence[str]]) -> list[str]:
    return ["| " + " | ".join(header) + " |", "|" + "---|" * len(header),
            *("| " + " | ".join(row) + " |" for row in rows)]


def markdown_tables(evaluations: Sequence[PairEvaluation]) -> list[str]:
    """The evaluations as Markdown: the scores table, the matched-pixels table, and the notes.

    Parameters
    ----------
    evaluations : sequence of PairEvaluation

    Returns
    -------
    list of str
        Lines: each table under a line that says what it holds (a baseline that did not run on a pair has a
        row saying so), then each pair's notes, the baselines not run and the regions not scored, and why.
    """
    if isinstance(evaluations, PairEvaluation) or not isinstance(evaluations, Sequence):
        raise InputTypeError(f"evaluations must be a sequence of PairEvaluation, got {type(evaluations).__name__}")
    if not all(isinstance(e, PairEvaluation) for e in evaluations):
        raise InputTypeError("evaluations must hold only PairEvaluation")
    lines = [("Bad pixels (% with |d - d_gt| > t px; a pixel without a value counts as bad), density (% with a "
              "value), MAE (px, over the pixels with a value), wall ms of a call (after a warm-up call):"), ""]
    header = ("scene", "method", "region", *(f"bad {t:g}" for t in THRESHOLDS), "density", "MAE", "ms")
    lines += _table(header, [row for e in evaluations for row in _score_rows(e)])
    comparisons = [(e.scene, c) for e in evaluations for c in e.matched]
    if comparisons:
        lines += ["", ("Bad 1 (%) on the pixels each baseline matched, the baseline's beside the method's, and the "
                       "method's over the baseline's:"), ""]
        lines += _table(("scene", "region", "baseline", "matched", "baseline bad 1", "method", "method bad 1",
                         "method / baseline"), [
            (scene, c.region, c.baseline, str(c.matched), _percent(c.baseline_bad), c.method, _percent(c.method_bad),
             f"{c.method_bad / c.baseline_bad:.2f}" if c.baseline_bad > 0 else "-")
            for scene, c in comparisons])
    notes = [f"- {e.scene}: {note}" for e in evaluations for note in _notes(e)]
    if notes:
        lines += ["", *notes]
    return lines


def _score_rows(evaluation: PairEvaluation) -> list[tuple[str, ...]]:
    """The scores table's rows of a pair: each method's regions, then a row for each baseline not run."""
    rows = [(evaluation.scene, s.method, s.region, *(_percent(s.bad[t]) for t in THRESHOLDS), _percent(s.density),
             "-" if np.isnan(s.mae) else f"{s.mae:.2f}", f"{s.ms:.1f}") for s in evaluation.scores]
    rows += [(evaluation.scene, name, "not run (see the notes)", *("-" for _ in THRESHOLDS), "-", "-", "-")
             for name in evaluation.not_run]
    return rows


def _notes(evaluation: PairEvaluation) -> list[str]:
    """A pair's notes, then its baselines not run (those refused for one reason on one line) and its regions
    not scored."""
    by_reason: dict[str, list[str]] = {}
    for name, reason in evaluation.not_run.items():
        by_reason.setdefault(reason, []).append(name)
    return [*evaluation.notes, *(f"{', '.join(names)}: not run on this pair: {reason}"
                                 for reason, names in by_reason.items()),
            *(f"region {region} not scored: {reason}" for region, reason in evaluation.not_scored.items())]
