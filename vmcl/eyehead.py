"""Glue between the eye-head and stereo registration: the vergence angle picks the warp table.

Seed sections "The Eye-Head system" and "Stereo" (Memory-based registration and calibration): warp
tables are stored "for each of a few convergence angles of the two cameras (assuming symmetric
convergence)", are "independent of the position of the head", and a table for an intermediate fixation
is interpolated. This is the only place where vmcl touches the ``hardware`` package.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from hardware.head import Head
from vmcl.cm.core import check_real
from vmcl.early.registration import TableStore, WarpTable
from vmcl.errors import InputTypeError, InputValueError
from vmcl.machine import Machine

__all__ = ["Capture", "calibrate_vergences", "table_for_fixation"]

Capture = Callable[[], tuple[np.ndarray, np.ndarray]]


def table_for_fixation(head: Head, store: TableStore) -> WarpTable:
    """The warp table for the eyes' current vergence (stored, or interpolated between stored angles)."""
    _check_glue(head, store)
    return store.table_for(head.vergence())


def _check_glue(head, store) -> None:
    if not isinstance(head, Head):
        raise InputTypeError(f"head must be a hardware.head.Head, got {type(head).__name__}")
    if not isinstance(store, TableStore):
        raise InputTypeError(f"store must be a vmcl.early.registration.TableStore, got {type(store).__name__}")


def calibrate_vergences(head: Head, store: TableStore, capture: Capture, *, distances: list[float],
                        baseline: float, max_shift: float, machine: Machine | None = None) -> list[float]:
    """Learn a warp table at each fixation distance from a dot pattern placed at that distance.

    Parameters
    ----------
    head : hardware.head.Head
        A homed head; the eyes converge symmetrically on each distance in turn.
    store : TableStore
        Receives one table per distance, keyed by the vergence the head reports.
    capture : callable
        Returns the (left, right) grey images of the dot pattern as the eyes now see it.
    distances : list of float
        Fixation distances, metres.
    baseline : float
        Distance between the eyes, metres.
    max_shift : float
        Largest dot displacement between the two images, pixels (see ``match_dots``).

    Returns
    -------
    The vergence angles (degrees) of the tables added.
    """
    _check_glue(head, store)
    if not callable(capture):
        raise InputTypeError(f"capture must be a callable returning (left, right) images, got {type(capture).__name__}")
    if not isinstance(distances, (list, tuple)) or not distances:
        raise InputValueError("distances must name at least one fixation distance")
    # Every distance and the baseline checked before the first table goes into the store: a bad one found
    # midway would leave the store holding part of a calibration.
    for k, distance in enumerate(distances):
        check_real(distance, f"distances[{k}]", above=0)
    check_real(baseline, "baseline", above=0)
    angles = []
    for distance in distances:
        head.fixate(distance, baseline=baseline)
        left, right = capture()
        vergence = head.vergence()
        store.add(WarpTable.calibrate(left, right, max_shift=max_shift, vergence=vergence, machine=machine))
        angles.append(vergence)
    return angles
