"""Examples to learn from: a cue's measurement beside its ground truth.

Seed section "Learning and parameter estimation", the second stage ("data and desired solution are
given"). The desired solution of a cue's MRF is its true field (a disparity map, a flow field) with its
line process where the true field jumps; for the piecewise constant cues (colour, texture), which have no
true field, a human segmentation: each segment at one level, lines between segments. The data, its
confidence and the coupling edges are what the cue's early module gives the MRF on the same images
(:meth:`vmcl.pipeline.VisionMachine.measure`).
"""

from __future__ import annotations

import numpy as np

from vmcl.cm.core import check_real, check_unmasked
from vmcl.errors import InputTypeError, InputValueError
from vmcl.learn.pseudolikelihood import Example
from vmcl.mrf.energy import EnergyModel, host_field, resolve_levels

__all__ = ["DEFAULT_JUMP", "jump_lines", "segmentation_example", "truth_example"]

DEFAULT_JUMP = 1.0
"""A true field's discontinuity: neighbours more than this apart (pixels of disparity or flow), the
tolerance of the field's own bad-1 measure."""


def jump_lines(field: np.ndarray, *, jump: float = DEFAULT_JUMP,
               valid: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The line process of a true field: on between two known neighbours more than ``jump`` apart.

    Parameters
    ----------
    field : (H, W) or (H, W, C) array
        NaN where unknown.
    jump : float
        > 0, in the field's units (the Euclidean distance of vectors).
    valid : (H, W) bool array, optional
        Where the field is known (default: where it is finite).

    Returns
    -------
    (line_h (H, W - 1), line_v (H - 1, W)) bool arrays
    """
    f = host_field(field, "field", ndims=(2, 3)).astype(np.float64)
    check_real(jump, "jump", above=0)
    values = f.reshape(*f.shape[:2], -1)
    known = np.all(np.isfinite(values), axis=2)
    if valid is not None:
        mask = host_field(valid, "valid", ndims=(2,), empty=True) != 0
        if mask.shape != known.shape:
            raise InputValueError(f"valid must have the field's shape {known.shape}, got {mask.shape}")
        known &= mask
    filled = np.where(known[..., None], values, 0.0)
    dh = np.sqrt(np.sum((filled[:, 1:] - filled[:, :-1]) ** 2, axis=2))
    dv = np.sqrt(np.sum((filled[1:] - filled[:-1]) ** 2, axis=2))
    return (dh > jump) & known[:, 1:] & known[:, :-1], (dv > jump) & known[1:] & known[:-1]


def truth_example(truth: np.ndarray, data: np.ndarray, confidence: np.ndarray | None, edges: np.ndarray, *,
                  valid: np.ndarray | None = None, jump: float = DEFAULT_JUMP) -> Example:
    """An :class:`Example`: the true field and its :func:`jump_lines` as the desired solution, with a
    cue's measurement (data, confidence, coupling edges) as the data.

    Parameters
    ----------
    truth : (H, W) or (H, W, C) array
        The true field, NaN where unknown.
    data, confidence, edges
        The cue's measurement (:class:`vmcl.pipeline.CueData`'s fields).
    valid : (H, W) bool array, optional
        Where the truth holds (e.g. a data set's evaluation mask); default where it is finite.
    jump : float
    """
    f = host_field(truth, "truth", ndims=(2, 3)).astype(np.float32)
    known = np.all(np.isfinite(f.reshape(*f.shape[:2], -1)), axis=2)
    if valid is not None:
        mask = host_field(valid, "valid", ndims=(2,), empty=True)
        if mask.shape != known.shape:
            raise InputValueError(f"valid must have the truth's shape {known.shape}, got {mask.shape}")
        known &= mask != 0
    line_h, line_v = jump_lines(f, jump=jump, valid=known)
    return Example(f, line_h, line_v, data=data, confidence=confidence, edges=edges, valid=known)


def segmentation_example(data: np.ndarray, confidence: np.ndarray | None, edges: np.ndarray,
                         segmentation: np.ndarray, model: EnergyModel) -> Example:
    """An :class:`Example` of a piecewise constant cue from a segmentation of its image (e.g. a BSDS
    annotator's): each segment at the level nearest the median of its measurements (the image's median
    where it has none), the levels spread over the data's range as :func:`vmcl.mrf.restore` spreads
    ``model.levels``; lines between different segments.

    Parameters
    ----------
    data, confidence, edges
        The cue's measurement (:class:`vmcl.pipeline.CueData`'s fields), scalar.
    segmentation : (H, W) integer array
        Segment labels.
    model : EnergyModel
        The cue's energy (its levels: a count, or the levels themselves).
    """
    if not isinstance(model, EnergyModel):
        raise InputTypeError(f"model must be a vmcl.mrf.EnergyModel, got {type(model).__name__}")
    g = host_field(data, "data", ndims=(2,)).astype(np.float64)
    check_unmasked(segmentation, "segmentation")
    labels = np.asarray(segmentation)
    if labels.shape != g.shape or labels.dtype.kind not in "iu":
        raise InputValueError(f"segmentation must be integer labels of the data's shape {g.shape}, got "
                              f"{labels.dtype} {labels.shape}")
    finite = np.isfinite(g)
    if not finite.any():
        raise InputValueError("data has no measurement: no level to give any segment")
    levels = resolve_levels(model, float(g[finite].min()), float(g[finite].max()))
    field = np.empty(g.shape, np.float32)
    fallback = float(np.median(g[finite]))
    for label in np.unique(labels):
        where = labels == label
        values = g[where & finite]
        target = float(np.median(values)) if values.size else fallback
        field[where] = levels[int(np.argmin(np.abs(levels - target)))]
    line_h, line_v = jump_lines(labels.astype(np.float64), jump=0.5)
    return Example(field, line_h, line_v, data=data, confidence=confidence, edges=edges,
                   levels=tuple(float(v) for v in levels))
