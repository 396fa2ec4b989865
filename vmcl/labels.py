"""The machine's vocabulary: the cues it integrates and the physical causes it labels.

Seed sections "Organization of integration" and "Labeling the physical origin of edges". Every module
that names a cue or a label takes the names from here: the pipeline, integration, labelling, the report
and the scene renderer (whose ground truth uses the same :class:`Label` codes).
"""

from __future__ import annotations

from enum import IntEnum, IntFlag

from vmcl.errors import InputTypeError, InputValueError

__all__ = [
    "BIT_DEFINES",
    "CUES",
    "RULE_LABELS",
    "RULE_PRECEDENCE",
    "Cue",
    "Label",
    "add_cue",
    "cue_bit",
    "cue_names",
    "remove_cue",
    "rule_label",
]


class Label(IntEnum):
    """Physical cause of a discontinuity (seed paper, "Labeling the physical origin of edges").

    TEXTURE is an albedo edge between regions of equal colour that differ only in texture; merge it
    with ALBEDO for the paper's five classes.
    """

    NONE = 0
    DEPTH = 1
    ORIENTATION = 2
    ALBEDO = 3
    SHADOW = 4
    SPECULAR = 5
    TEXTURE = 6


class Cue(IntFlag):
    """Bits of the support map: the cues whose line process marks a pixel, and the brightness edges."""

    STEREO = 1
    MOTION = 2
    COLOUR = 4
    TEXTURE = 8
    BRIGHTNESS = 16


CUES = ("stereo", "motion", "colour", "texture")
"""The cues with a line process, each by the one name it has everywhere (its configuration section, its
MRF preset and overrides, its restored field and line process in a Result, the classifier's inputs), in
the order of their :class:`Cue` bits. A cue is named after the module that measures it; stereo's
restored field is the disparity (depth), motion's the flow."""

BIT_DEFINES = {f"BIT_{bit.name}": int(bit) for bit in Cue}
"""The kernels' -D names of the :class:`Cue` bits (integrate.cl, labelling.cl)."""


RULE_LABELS = {"stereo": Label.DEPTH, "motion": Label.DEPTH, "colour": Label.ALBEDO, "texture": Label.TEXTURE}
"""The physical reading of each cue's line under the rule labelling (:func:`vmcl.integrate.integrate`): a
jump of depth or of motion is an occluding contour, a change of hue a change of albedo (shadows and
shading leave hue unchanged), a change of texture alone a texture boundary."""

RULE_PRECEDENCE = (Label.DEPTH, Label.ORIENTATION, Label.ALBEDO, Label.TEXTURE, Label.SHADOW, Label.SPECULAR)
"""Where several cues mark a pixel, the rule label is the first of theirs in this order (the most
specific cause first, as the scenes' ground truth orders them)."""

_FREE_BITS = (32, 64, 128)  # the support map is uint8; BRIGHTNESS holds 16
_EXTRA: dict[str, tuple[int, Label]] = {}  # cues registered beyond CUES: name -> (bit, rule label)


def _check_name(cue) -> str:
    if not isinstance(cue, str):
        raise InputTypeError(f"cue must be a str, one of {', '.join(cue_names())}; got {type(cue).__name__}")
    if cue not in CUES and cue not in _EXTRA:
        raise InputValueError(f"cue must be one of {', '.join(cue_names())}, got {cue!r}")
    return cue


def cue_names() -> tuple[str, ...]:
    """Every cue the machine knows: :data:`CUES`, then those added with :func:`add_cue`, in bit order."""
    return CUES + tuple(_EXTRA)


def cue_bit(cue: str) -> int:
    """The support bit of the cue named ``cue`` (a :class:`Cue` member for the cues of :data:`CUES`)."""
    _check_name(cue)
    return Cue[cue.upper()] if cue in CUES else _EXTRA[cue][0]


def rule_label(cue: str) -> Label:
    """The label the rule labelling gives a pixel the cue ``cue`` marks (see :data:`RULE_LABELS`)."""
    _check_name(cue)
    return RULE_LABELS[cue] if cue in CUES else _EXTRA[cue][1]


def add_cue(name: str, label: Label) -> int:
    """Give a new cue a support bit and its rule label; returns the bit (adding a name twice returns its bit).

    The support map is uint8 with :data:`CUES` and BRIGHTNESS in its five low bits, so three cues can be
    added. :func:`vmcl.cues.register` calls this; a cue's name must be a Python identifier.
    """
    if not isinstance(name, str) or not name.isidentifier():
        raise InputTypeError(f"name must be an identifier string, got {name!r}")
    if not isinstance(label, Label) or label == Label.NONE:
        raise InputTypeError(f"label must be a Label other than NONE, got {label!r}")
    if name in CUES:
        raise InputValueError(f"name {name!r} is a cue the machine already has")
    if name in _EXTRA:
        if _EXTRA[name][1] != label:
            raise InputValueError(f"cue {name!r} was added with the label {_EXTRA[name][1].name}, not {label.name}")
        return _EXTRA[name][0]
    if len(_EXTRA) == len(_FREE_BITS):
        raise InputValueError(f"the support map has no bit left for cue {name!r} ({len(_FREE_BITS)} added already)")
    _EXTRA[name] = (_FREE_BITS[len(_EXTRA)], label)
    return _EXTRA[name][0]


def remove_cue(name: str) -> None:
    """Forget a cue added with :func:`add_cue` (the last added only, so that the bits stay packed)."""
    if not _EXTRA or name != list(_EXTRA)[-1]:
        raise InputValueError(f"only the last added cue can be removed, got {name!r}")
    del _EXTRA[name]
