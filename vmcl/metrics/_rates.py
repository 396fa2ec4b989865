"""Rates of matched counts shared by the boundary and detection measures: ratios and the F-measure.

Both are defined as 0 where the denominator is 0 (nothing to match, or neither precision nor recall),
as the BSDS benchmark does, so an empty threshold or image gives a rate instead of a division warning.
"""

from __future__ import annotations

import numpy as np

__all__ = ["f_measure", "ratio"]


def f_measure(precision, recall):
    """Harmonic mean of precision and recall, elementwise (0 where both are 0)."""
    precision = np.asarray(precision, dtype=np.float64)
    recall = np.asarray(recall, dtype=np.float64)
    total = precision + recall
    return 2.0 * precision * recall / (total + (total == 0))


def ratio(count, total):
    """``count / total`` elementwise (0 where the total is 0)."""
    count = np.asarray(count, dtype=np.float64)
    total = np.asarray(total, dtype=np.float64)
    return count / (total + (total == 0))
