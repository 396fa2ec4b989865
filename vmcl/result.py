"""What one run of the machine gives: :class:`Result`.

It lives apart from :mod:`vmcl.pipeline` so that the cues (:mod:`vmcl.cues`), which declare the Result
fields they fill, and the report sit below the machine that runs them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from vmcl.group import Grouping
    from vmcl.pipeline import Config
    from vmcl.recognize import Detection


@dataclass
class Result:
    """What :meth:`VisionMachine.run` returns: host (NumPy) fields, the cartoon and the timings.

    Fields a run had no input for are None. Line processes follow :mod:`vmcl.scenes`: ``line_h`` is
    (H, W - 1), ``line_v`` (H - 1, W).

    Attributes
    ----------
    image : float32 (H, W) or (H, W, 3)
        The left image in [0, 1], as the machine saw it.
    edges : bool (H, W)
        Canny's brightness edges.
    grouping : vmcl.group.Grouping or None
        The edges' curves, their local saliency, junctions (T, Y, arrow, L, X), repairs and T-junction
        pairs (None with ``grouping.enabled`` off).
    recognition : list of vmcl.recognize.Detection or None
        The library's objects found in the left image, best first (None without ``recognition.models``).
    hue, colour_edges : float32 (H, W) (NaN where not valid), bool (H, W)
        The hue H = R / (R + G) and its albedo-edge candidates (RGB input only).
    density, texture_edges : float32 (H, W), bool (H, W)
        Texton density and its edge candidates.
    sparse_disparity : float32 (H, W)
        The feature (edge) matcher's disparities (of the feedback pass when there is one), NaN where none;
        None when ``[stereo] feature_matches`` is off (the default: the dense matcher alone, ``disparity``).
    first_pass_disparity : float32 (H, W)
        The feature matcher's disparities before feedback (None without feedback or feature matches).
    stereo_discontinuity : bool (H, W)
        Features whose votes were bimodal over d (None without feature matches).
    half_occluded : bool (H, W)
        Pixels the right camera does not see (the semi-global matcher's left-right check and occlusion
        geometry; None with another dense matcher): their disparity in ``disparity`` is the
        restoration's, from the background beside them.
    out_of_range : bool (H, W)
        Pixels whose best semi-global match was an end of the searched range: their disparity may lie
        outside it (the seed's areas outside the matcher's disparity range); restored from their
        neighbours. None with another dense matcher.
    disparity : float32 (H, W)
        Dense disparity: the stereo MRF's restoration.
    raw_flow, flow : float32 (H, W, 2)
        The motion module's flow (NaN where none) and its MRF restoration.
    restored : dict of str to ndarray
        Each cue's restored field, by cue (:data:`vmcl.labels.CUES`): "stereo" (the disparity, =
        ``disparity``), "motion" (the flow, = ``flow``), "colour" (hue), "texture" (texton density).
    lines : dict of str to (line_h, line_v)
        Each cue's line process (bool).
    support : uint8 (H, W)
        :class:`vmcl.labels.Cue` bits: which cues put a discontinuity at each pixel (a line site's pixel
        is its left or upper one; a stereo line's is its nearer one, :func:`vmcl.integrate.integrate`'s
        ``owners``).
    labels : uint8 (H, W)
        The cartoon: :class:`vmcl.labels.Label` codes of the discontinuity pixels (``labels.method``
        says how they are chosen; :mod:`vmcl.labelling` by default).
    boundary_strength : float32 (H, W) in [0, 1]
        The cartoon's soft map: the image's probability of boundary from brightness, colour and texture
        (:mod:`vmcl.early.boundary_probability`, thinned to one-pixel contours), raised to the linear
        classifier's support for a discontinuity where a stereo or motion line marks a candidate
        (:func:`vmcl.labelling.classify`; with ``labels.method = "rule"``, the image's probability
        alone). Threshold it, or sweep it, to compare with an edge detector.
    stages : dict of str to float
        Wall time of each stage in ms, in the order run (device work included: each stage ends with
        the queue drained).
    kernels : dict of str to dict
        Per-kernel device time, as :meth:`vmcl.Machine.timings` gives it (empty without profiling; mixed
        with other threads' runs when several threads share one profiling Machine).
    config : Config
    notes : list of str
        What the run found out about its inputs or could not do: the disparity range found from the
        images, a cue whose module measured nothing to restore.
    """

    image: np.ndarray
    edges: np.ndarray
    support: np.ndarray
    labels: np.ndarray
    boundary_strength: np.ndarray
    config: Config
    grouping: Grouping | None = None
    recognition: list[Detection] | None = None
    hue: np.ndarray | None = None
    colour_edges: np.ndarray | None = None
    density: np.ndarray | None = None
    texture_edges: np.ndarray | None = None
    sparse_disparity: np.ndarray | None = None
    first_pass_disparity: np.ndarray | None = None
    stereo_discontinuity: np.ndarray | None = None
    half_occluded: np.ndarray | None = None
    out_of_range: np.ndarray | None = None
    disparity: np.ndarray | None = None
    raw_flow: np.ndarray | None = None
    flow: np.ndarray | None = None
    restored: dict[str, np.ndarray] = field(default_factory=dict)
    lines: dict[str, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)
    stages: dict[str, float] = field(default_factory=dict)
    kernels: dict[str, dict[str, float]] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)

    @property
    def discontinuities(self) -> np.ndarray:
        """bool (H, W): the integrated discontinuity map, the labelled pixels of the cartoon."""
        return self.labels != 0

    @property
    def total_ms(self) -> float:
        """Wall time of the whole run in ms."""
        return sum(self.stages.values())


__all__ = ["Result"]
