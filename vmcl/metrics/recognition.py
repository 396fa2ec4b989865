"""Recognised objects against the objects a scene holds: recognition rate, false detections and pose error.

The figures model-based recognition reports (Grimson's and Huttenlocher's): the fraction of the objects
present that are found, the false detections per image, and the pose's error at the model's corners. A
detection finds an object when it names it and its pose carries the model's corners onto the object's:
each of the object's visible corners that the detection's view shows lies, on average, within
``tolerance`` (a fraction of the object's size) of the nearest carried corner. Nearest, not the corner of
the same index: a symmetric object (a star) has several right poses. Only the corners the view shows: a
3-D object seen a degree past its learned view shows a sliver of a face the view sees edge-on, and that
face's far corners are none of the view's, so no pose of the view carries one there (it was scored
against whichever corner lay nearest, 20 px off). The pose error is that mean distance in pixels; each
object is found at most once (the detection with the smallest error), and every other detection is false.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from vmcl.cm.core import check_real
from vmcl.errors import InputTypeError, InputValueError
from vmcl.metrics.points import one_to_one
from vmcl.recognize import Detection
from vmcl.scenes import Placement

__all__ = ["RecognitionScores", "recognition_scores"]


@dataclass(frozen=True)
class RecognitionScores:
    """What :func:`recognition_scores` returns for one image.

    Attributes
    ----------
    found : tuple of bool
        Per object of the scene (its placements' order), whether a detection found it.
    pose_error : tuple of float
        Per object, the found pose's mean corner error in pixels (NaN where not found).
    false : int
        Detections that found no object.
    """

    found: tuple[bool, ...]
    pose_error: tuple[float, ...]
    false: int


def _corner_error(detection: Detection, learned: Placement, truth: Placement) -> float:
    carried = detection.locate(learned.corners)
    shown = np.isin(truth.corner_ids, learned.corner_ids)
    corners = truth.corners[shown] if shown.any() else truth.corners  # (a view sharing none: all of them)
    distance = np.hypot(corners[:, None, 0] - carried[None, :, 0], corners[:, None, 1] - carried[None, :, 1])
    return float(distance.min(axis=1).mean())


def recognition_scores(detections: Sequence[Detection], placements: Sequence[Placement],
                       learned: Mapping[str, Sequence[Placement]], *, tolerance: float = 0.25) -> RecognitionScores:
    """Score one image's detections against the objects it holds.

    Parameters
    ----------
    detections : sequence of vmcl.recognize.Detection
    placements : sequence of vmcl.scenes.Placement
        The objects in the image (:attr:`vmcl.scenes.RecognitionScene.placements`).
    learned : mapping of str to sequence of Placement
        Per model name, the placement of the object in each view it was learned from (in the view's
        order, :func:`vmcl.scenes.object_view`'s), which puts the model's corners in its frame.
    tolerance : float
        The largest mean corner error for a detection to find an object, as a fraction of the object's
        scale (its rms radius in pixels), > 0.

    Returns
    -------
    RecognitionScores
    """
    for name, values in (("detections", detections), ("placements", placements)):
        if isinstance(values, str) or not isinstance(values, Sequence):
            raise InputTypeError(f"{name} must be a sequence, got {type(values).__name__}")
    if not all(isinstance(d, Detection) for d in detections):
        raise InputTypeError("detections must hold vmcl.recognize.Detection")
    if not all(isinstance(p, Placement) for p in placements):
        raise InputTypeError("placements must hold vmcl.scenes.Placement")
    if not isinstance(learned, Mapping):
        raise InputTypeError(f"learned must be a mapping of model name to placements, got {type(learned).__name__}")
    for name, placed in learned.items():
        if (isinstance(placed, str) or not isinstance(placed, Sequence)
                or not all(isinstance(p, Placement) for p in placed)):
            raise InputTypeError(f"learned[{name!r}] must be a sequence of vmcl.scenes.Placement (one per view), got "
                                 f"{type(placed).__name__}")
        other = next((p.name for p in placed if p.name != name), None)
        if other is not None:  # another object's views scored every detection of this one as false
            raise InputValueError(f"learned[{name!r}] holds a placement of {other!r}: each model's views must be "
                                  "placements of that object")
    tolerance = check_real(tolerance, "tolerance", above=0)
    errors = np.full((len(placements), len(detections)), np.inf)
    for j, detection in enumerate(detections):
        views = learned.get(detection.name)
        if views is None:
            continue
        if not 0 <= detection.view < len(views):
            raise InputValueError(f"learned[{detection.name!r}] has {len(views)} views; a detection is of view "
                                  f"{detection.view}")
        for i, placement in enumerate(placements):
            if placement.name == detection.name:
                error = _corner_error(detection, views[detection.view], placement)
                if error <= tolerance * placement.scale:
                    errors[i, j] = error
    # As many objects found as the detections can find one to one, of least total error among those: an
    # object matched greedily took the detection a later one needed.
    pose_error = np.full(len(placements), np.nan)
    rows, cols = one_to_one(errors, np.isfinite(errors)) if errors.size else (np.zeros(0, int), np.zeros(0, int))
    pose_error[rows] = errors[rows, cols]
    found = tuple(bool(f) for f in np.isfinite(pose_error))
    return RecognitionScores(found, tuple(float(e) for e in pose_error), len(detections) - len(cols))
