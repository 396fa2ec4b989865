"""Examples to learn from: a cue's measurement beside its ground truth.

Seed section "Learning and parameter estimation", the second stage ("data and desired solution are
given"). The desired solution of a cue's MRF is its true field (a disparity map, a flow field) with its
line process where the true field jumps; the data, its confidence and the coupling edges are what the
cue's early module gives the MRF on the same images (:meth:`vmcl.pipeline.VisionMachine.measure`).
"""

from __future__ import annotations

import numpy as np

from vmcl.cm.core import check_real
from vmcl.errors import InputValueError
from vmcl.learn.pseudolikelihood import Example
from vmcl.mrf.energy import host_field

__all__ = ["DEFAULT_JUMP", "jump_lines", "truth_example"]

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
