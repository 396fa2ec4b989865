"""Pictures of the machine's dense fields: disparity with its scale, flow in the colour wheel, scalar fields.

Seed section "The Vision Machine System": besides the cartoon, the machine gives "interpolated depth,
motion, texture, and color fields". Each picture here is a NumPy RGB uint8 image a person reads at a
glance; the cues (:mod:`vmcl.cues`) choose which of their fields to show, and :mod:`vmcl.report` puts
them in the report.

References
----------
S. Baker, D. Scharstein, J. P. Lewis, S. Roth, M. J. Black and R. Szeliski, "A database and evaluation
methodology for optical flow", IJCV 92(1):1-31, 2011 (the colour wheel).
"""

from __future__ import annotations

import cv2
import numpy as np

from vmcl.cm.core import check_real, real_host_array
from vmcl.errors import InputValueError

_BAR = 28  # height in pixels of the colour scale under the disparity map


def _optional_real(value, name: str) -> float | None:
    return None if value is None else check_real(value, name)


def to_uint8(rgb: np.ndarray) -> np.ndarray:
    """Values on the 0..255 scale (a real NumPy array) as uint8, rounded and clipped."""
    real_host_array(rgb, "rgb", ndims=tuple(range(1, 4)), empty=True)
    return np.clip(np.round(rgb), 0, 255).astype(np.uint8)


def eight_bits(image: np.ndarray) -> np.ndarray:
    """A picture at 8 bits: a uint16 one's levels / 257, rounded (65535 becomes 255); a uint8 one as it is.
    For what takes 8-bit images only (OpenCV's block matchers, its corner tracker)."""
    real_host_array(image, "image", ndims=tuple(range(1, 4)), empty=True)
    if image.dtype == np.uint8:
        return image
    if image.dtype != np.uint16:
        raise InputValueError(f"image must be uint8 or uint16, got {image.dtype}")
    # Rounded, as the levels are never negative; OpenCV drops a trailing axis of one channel: put back.
    return cv2.convertScaleAbs(image, alpha=1 / 257).reshape(image.shape)


def disparity_image(disparity: np.ndarray, *, vmin: float | None = None, vmax: float | None = None) -> np.ndarray:
    """Disparity colour-mapped (turbo: near is red, far is blue) with a labelled scale bar underneath.

    Parameters
    ----------
    disparity : (H, W) float array, NaN where unknown (drawn black, as are infinite values)
    vmin, vmax : float, optional
        The range of the colour map, vmin <= vmax; default the finite values' range. Equal ends (a field of
        one value, as its own range gives them) draw that value at the far end of the map.

    Returns
    -------
    uint8 RGB (H + 28, W, 3)
    """
    real_host_array(disparity, "disparity", ndims=(2,))
    vmin, vmax = _optional_real(vmin, "vmin"), _optional_real(vmax, "vmax")
    if vmin is not None and vmax is not None and vmin > vmax:
        raise InputValueError(f"vmin must not exceed vmax, got {vmin} and {vmax}")
    finite = np.isfinite(disparity)
    # The finite values' range (an infinite value, like a NaN, is drawn black: it would stretch the scale to it).
    shown = disparity[finite]
    low = vmin if vmin is not None else (float(shown.min()) if shown.size else 0.0)
    high = vmax if vmax is not None else (float(shown.max()) if shown.size else 1.0)
    span = max(high - low, 1e-6)
    width = disparity.shape[1]
    scaled = np.where(finite, (disparity - low) / span, 0.0)
    codes = to_uint8(np.clip(scaled, 0, 1) * 255)
    picture = cv2.cvtColor(cv2.applyColorMap(codes, cv2.COLORMAP_TURBO), cv2.COLOR_BGR2RGB)
    picture[~finite] = 0
    bar = np.full((_BAR, width, 3), 255, np.uint8)
    ramp = to_uint8(np.linspace(0, 255, width))[None, :].repeat(10, axis=0)
    bar[2:12] = cv2.cvtColor(cv2.applyColorMap(ramp, cv2.COLORMAP_TURBO), cv2.COLOR_BGR2RGB)
    for fraction, align in ((0.0, 0), (0.5, 1), (1.0, 2)):
        text = f"{low + fraction * span:.1f}" + (" px" if fraction == 1.0 else "")
        (tw, _), _ = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, 0.35, 1)
        x = [1, (width - tw) // 2, width - tw - 1][align]
        cv2.putText(bar, text, (max(x, 0), _BAR - 4), cv2.FONT_HERSHEY_SIMPLEX, 0.35, (0, 0, 0), 1, cv2.LINE_AA)
    return np.concatenate([picture, bar], axis=0)


def _colour_wheel() -> np.ndarray:
    """The Middlebury wheel's 55 colours: red-yellow-green-cyan-blue-magenta in 15/6/4/11/13/6 steps."""
    segments = ((15, (255, 0, 0), (255, 255, 0)), (6, (255, 255, 0), (0, 255, 0)), (4, (0, 255, 0), (0, 255, 255)),
                (11, (0, 255, 255), (0, 0, 255)), (13, (0, 0, 255), (255, 0, 255)), (6, (255, 0, 255), (255, 0, 0)))
    rows = []
    for steps, start, end in segments:
        t = np.arange(steps)[:, None] / steps
        rows.append(np.array(start) * (1 - t) + np.array(end) * t)
    return np.concatenate(rows) / 255.0


def flow_image(flow: np.ndarray, *, max_flow: float | None = None) -> np.ndarray:
    """Flow in the Middlebury colour wheel: hue is the direction, saturation the speed; NaN is black.

    Parameters
    ----------
    flow : (H, W, 2) float array, (u, v) with x right and y down
    max_flow : float, optional
        The speed drawn fully saturated; default the largest finite speed.

    Returns
    -------
    uint8 RGB (H, W, 3), with the wheel itself drawn in the top-left corner as the key.
    """
    real_host_array(flow, "flow", ndims=(3,))
    if flow.shape[2] != 2:
        raise InputValueError(f"flow must be (H, W, 2), got shape {flow.shape}")
    if max_flow is not None:
        max_flow = check_real(max_flow, "max_flow", above=0)
    u, v = flow[..., 0], flow[..., 1]
    known = np.isfinite(u) & np.isfinite(v)
    speed = np.hypot(np.where(known, u, 0), np.where(known, v, 0))
    scale = max(float(speed.max()) if max_flow is None else max_flow, 1e-6)
    picture = _wheel_colours(np.where(known, u, 0) / scale, np.where(known, v, 0) / scale)
    picture[~known] = 0
    size = min(48, *flow.shape[:2]) // 2 * 2
    if size >= 16:
        y, x = (np.mgrid[:size, :size] - (size - 1) / 2) / (size / 2)
        key = _wheel_colours(x, y)
        key[np.hypot(x, y) > 1] = 255
        picture[:size, :size] = key
    return picture


def _wheel_colours(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    wheel = _colour_wheel()
    n = len(wheel)
    radius = np.minimum(np.hypot(u, v), 1.0)
    angle = np.arctan2(-v, -u) / np.pi  # Baker et al.'s convention
    position = (angle + 1) / 2 * (n - 1)
    k0 = np.floor(position).astype(int)
    k1 = (k0 + 1) % n
    f = (position - k0)[..., None]
    colour = (1 - f) * wheel[k0] + f * wheel[k1]
    colour = 1 - radius[..., None] * (1 - colour)  # slow motion fades to white
    return to_uint8(colour * 255)


def field_image(values: np.ndarray) -> np.ndarray:
    """A scalar field (hue, texture density) as grey levels over its finite range; NaN is black."""
    real_host_array(values, "values", ndims=(2,))
    finite = np.isfinite(values)
    if not finite.any():
        return np.zeros(values.shape + (3,), np.uint8)
    low, high = float(values[finite].min()), float(values[finite].max())
    scaled = np.where(finite, (values - low) / max(high - low, 1e-6), 0.0)
    return np.repeat(to_uint8(scaled * 255)[..., None], 3, axis=2)


__all__ = ["disparity_image", "eight_bits", "field_image", "flow_image", "to_uint8"]
