"""The machine's vocabulary: the cues it integrates and the physical causes it labels.

Seed sections "Organization of integration" and "Labeling the physical origin of edges". Every module
that names a cue or a label takes the names from here: the pipeline, integration, labelling, the report
and the scene renderer (whose ground truth uses the same :class:`Label` codes).
"""

from __future__ import annotations

from enum import IntEnum, IntFlag

from vmcl.errors import InputTypeError, InputValueError


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

CUE_BITS = Cue.STEREO | Cue.MOTION | Cue.COLOUR | Cue.TEXTURE
"""The bits that make a pixel a discontinuity of the cartoon (brightness alone does not)."""

BIT_DEFINES = {f"BIT_{bit.name}": int(bit) for bit in Cue}
"""The kernels' -D names of the :class:`Cue` bits (integrate.cl, labelling.cl)."""


def cue_bit(cue: str) -> Cue:
    """The support bit of the cue named ``cue`` (one of :data:`CUES`)."""
    if not isinstance(cue, str):
        raise InputTypeError(f"cue must be a str, one of {', '.join(CUES)}; got {type(cue).__name__}")
    if cue not in CUES:
        raise InputValueError(f"cue must be one of {', '.join(CUES)}, got {cue!r}")
    return Cue[cue.upper()]
