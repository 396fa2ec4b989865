"""The exceptions vmcl raises when it refuses its input.

Every refusal is an :class:`InputError`, and also the built-in exception a caller expects
(``ValueError`` for a bad value, ``TypeError`` for a bad type), so ``except ValueError`` keeps working.
The ``vmcl`` command reports an InputError as one line with exit status 2; any other exception is a
defect in vmcl (or in a library under it) and keeps its traceback, exit status 1.
"""

from __future__ import annotations

__all__ = ["InputError", "InputTypeError", "InputValueError"]


class InputError(Exception):
    """vmcl refused an argument: the message names it and says what was expected."""


class InputValueError(InputError, ValueError):
    """An argument of the right type with a value vmcl cannot take (shape, range, NaN, size)."""


class InputTypeError(InputError, TypeError):
    """An argument of a type vmcl does not take."""
