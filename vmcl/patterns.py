"""Binary test patterns whose structure is known exactly, for the primitives' tests and benchmarks.

The spiral is the worst case of the seed's "Edge detection" (Canny hysteresis): spreading activation
needs O(m) steps for a chain of m pixels, distance doubling O(log m).
"""

from __future__ import annotations

import numpy as np

from vmcl.cm.core import check_int
from vmcl.errors import InputValueError

__all__ = ["spiral"]

_HEADINGS = ((0, 1), (1, 0), (0, -1), (-1, 0))
_LARGEST = 8192


def spiral(size: int, *, corridor: int = 1) -> np.ndarray:
    """A square spiral of walls and gaps ``corridor`` pixels wide: one 4-connected component.

    Parameters
    ----------
    size : int
        The mask is size x size (corridor <= size <= 8192).
    corridor : int
        Width of the wall and of the gap between turns.

    Returns
    -------
    bool array (size, size). The wall's path from the outer corner to the centre is about
    size**2 / (2 * corridor) pixels long.
    """
    # The turtle walks in Python, one step per cell of its path: 8192 x 8192 is already slow, and no
    # device holds much more.
    size = check_int(size, "size", minimum=1, maximum=_LARGEST)
    corridor = check_int(corridor, "corridor", minimum=1)
    if size < corridor:
        raise InputValueError(f"need 1 <= corridor <= size, got size={size}, corridor={corridor}")
    cells = size // corridor
    drawn = np.zeros((cells, cells), bool)
    y = x = heading = turns = 0
    drawn[0, 0] = True
    # Walk like a turtle, turning right whenever the next step would touch the wall already drawn
    # (a cell two steps ahead must be free too, which keeps a one-cell gap); stop when no turn helps.
    while turns < 2:
        dy, dx = _HEADINGS[heading]
        ny, nx, ay, ax = y + dy, x + dx, y + 2 * dy, x + 2 * dx
        step_free = 0 <= ny < cells and 0 <= nx < cells and not drawn[ny, nx]
        beyond_free = not (0 <= ay < cells and 0 <= ax < cells) or not drawn[ay, ax]
        if step_free and beyond_free:
            y, x, turns = ny, nx, 0
            drawn[y, x] = True
        else:
            heading, turns = (heading + 1) % 4, turns + 1
    mask = np.kron(drawn, np.ones((corridor, corridor), bool))
    return np.pad(mask, ((0, size - mask.shape[0]), (0, size - mask.shape[1])))
