"""No input, however extreme, takes the process down.

A sweep of extreme scales (1e-42, subnormal, to 1e38) and of arrays holding inf, -inf or NaN through one
representative public call per kernel family (kernels/*.cl). Each case must give a correct result or an
InputValueError / InputTypeError whose message names the argument; never a crash, a hang or another
exception. The cases run in a subprocess (this file is also its driver, printing one JSON line per case),
so a segfault fails its own case: the driver is started again on the cases after it.

"Correct" is checked against an oracle where one exists: NumPy/SciPy for the primitives (data movement,
scans, reductions, histograms, the Gaussians, the box sum, warping), the scale-1 result for what is
scale-invariant (Canny's edges with noise-estimated thresholds, the noise estimate, connected
components). The modules that take brightness images in [0, 1] (stereo, motion, colour, texture, MRF
restoration, labelling) have no scale to be invariant to: for them a correct result is arrays of the
documented shape holding no infinity where the input held none.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

SCALES = {"1e-42": 1e-42, "1e-30": 1e-30, "1e-10": 1e-10, "1": 1.0, "1e10": 1e10, "1e30": 1e30, "1e38": 1e38}
SPECIALS = ("inf", "-inf", "nan")
TIMEOUT = 240  # seconds for the whole sweep in one process; a hang fails the case that was running

# -- the driver (runs in the subprocess) -----------------------------------------------------------------


def _base(shape=(40, 56)) -> np.ndarray:
    """A smooth grey image in [0, 1] with edges and texture, deterministic."""
    y, x = np.mgrid[: shape[0], : shape[1]].astype(np.float64)
    image = 0.3 + 0.4 * ((x > shape[1] / 2) ^ (y > shape[0] / 2)) + 0.1 * np.sin(x / 3.0) * np.cos(y / 5.0)
    image += 0.02 * np.random.default_rng(0).standard_normal(shape)
    return np.clip(image, 0.0, 1.0).astype(np.float32)


def _input(kind: str, image: np.ndarray) -> np.ndarray:
    if kind in SCALES:
        return (image * np.float32(SCALES[kind])).astype(np.float32)
    special = image.copy()
    special[image.shape[0] // 2, image.shape[1] - 3] = np.float32(kind)
    return special


def _scale(kind: str) -> float:
    return SCALES.get(kind, 1.0)


class Wrong(Exception):
    """The call returned, but not the oracle's answer."""


def _expect(condition: bool, what: str) -> None:
    if not condition:
        raise Wrong(what)


def _close(got, want, scale: float, rtol: float = 1e-5) -> None:
    got, want = np.asarray(got, np.float64), np.asarray(want, np.float64)
    # float32 cannot hold more than its range: where the oracle overflows it, infinity is right.
    want = np.where(np.abs(want) > np.finfo(np.float32).max, np.sign(want) * np.inf, want)
    atol = scale * rtol + 1e-44  # subnormal inputs keep only a few bits
    _expect(got.shape == want.shape, f"shape {got.shape} != {want.shape}")
    bad = ~np.isclose(got, want, rtol=rtol, atol=atol, equal_nan=True)
    _expect(not bad.any(), f"{bad.sum()} values differ from the oracle, e.g. {got[bad][:3]} vs {want[bad][:3]}")


def _same_partition(a: np.ndarray, b: np.ndarray) -> bool:
    pairs = np.unique(np.stack([a.ravel(), b.ravel()]), axis=1)
    return len(np.unique(pairs[0])) == pairs.shape[1] == len(np.unique(pairs[1]))


def _sane(result, finite_input: bool) -> None:
    """Every array in the result has no infinity (when the input had none)."""
    leaves = result if isinstance(result, tuple) else getattr(result, "__dict__", {}).values() or [result]
    for leaf in leaves:
        if isinstance(leaf, np.ndarray) and leaf.dtype.kind == "f" and finite_input:
            _expect(not np.isinf(leaf).any(), "infinite values in the result of a finite input")


def _binomial_oracle(x: np.ndarray, passes: int) -> np.ndarray:
    out = x.astype(np.float64)
    for _ in range(passes):
        p = np.pad(out, 1, mode="edge")
        rows = (p[:, :-2] + 2 * p[:, 1:-1] + p[:, 2:]) / 4
        out = (rows[:-2] + 2 * rows[1:-1] + rows[2:]) / 4
    return out


def case_news(kind):
    from vmcl.cm import news

    x = _input(kind, _base())
    want = np.zeros_like(x)
    want[:, 1:] = x[:, :-1]
    got = news.shift(x, 1, 0)
    _expect(np.array_equal(got, want, equal_nan=True), "shift moved values wrongly")


def case_scan(kind):
    from vmcl.cm import scan

    x = _input(kind, _base())
    _expect(np.array_equal(scan.scan(x, op="max"), np.fmax.accumulate(x, axis=1), equal_nan=True), "max scan")


def case_router(kind):
    from vmcl.cm import router

    x = _input(kind, _base()).ravel()
    address = np.random.default_rng(1).permutation(x.size).astype(np.int32)
    _expect(np.array_equal(router.get(x, address), x[address], equal_nan=True), "router get")


def case_doubling(kind):
    from scipy import ndimage

    from vmcl.cm import doubling

    x = _input(kind, _base())
    mask = x > np.float32(0.5 * _scale(kind))
    want, _ = ndimage.label(mask, structure=np.ones((3, 3)))
    got = np.asarray(doubling.label(mask, relabel=True))
    _expect(_same_partition(np.where(mask, got, -1), np.where(mask, want, -1)), "components differ")


def case_reduce(kind):
    from vmcl.cm import reduce

    x = _input(kind, _base())
    _expect(np.array_equal(reduce.reduce(x, "max"), np.fmax.reduce(x, axis=None), equal_nan=True), "max")
    top = float(np.fmax.reduce(np.where(np.isinf(x), np.nan, x), axis=None))
    got = reduce.histogram(x, 16, (0.0, top))
    want, _ = np.histogram(x[np.isfinite(x)].astype(np.float64), 16, (0.0, top))
    # float32 bin positions may move a value on an inner edge to the next bin.
    _expect(got.sum() == want.sum() and np.abs(got - want).sum() <= 0.01 * x.size, f"histogram {got} vs {want}")


def case_filters(kind):
    from vmcl.cm import filters

    x = _input(kind, _base())
    _close(filters.binomial(x, 2), _binomial_oracle(x, 2), _scale(kind))


def case_gaussian(kind):
    from scipy import ndimage

    from vmcl.early import filters

    x = _input(kind, _base())
    want = ndimage.gaussian_filter(x.astype(np.float64), 1.5, mode="nearest", truncate=4.0)
    _close(filters.gaussian(x, sigma=1.5, method="exact"), want, _scale(kind))


def case_edges(kind):
    from vmcl.early import edges

    reference = edges.canny(_base(), sigma=1.0)
    got = edges.canny(_input(kind, _base()), sigma=1.0)
    _expect(np.array_equal(got, reference), f"{(got != reference).sum()} edge pixels differ from scale 1")


def case_noise(kind):
    from vmcl.early import edges, noise

    _, magnitude, _ = edges.canny(_base(), sigma=1.0, low_threshold=0, high_threshold=0, return_gradient=True)
    reference = noise.noise_thresholds(magnitude).astype(np.float64)
    got = noise.noise_thresholds(_input(kind, magnitude))
    rtol = 2e-2 if _scale(kind) < 1e-37 else 1e-5  # subnormal magnitudes hold a few bits
    _close(got, reference * _scale(kind), _scale(kind), rtol=rtol)


def case_box(kind):
    from scipy import ndimage

    from vmcl.cm import scan

    x = _input(kind, _base())
    want = ndimage.uniform_filter(x.astype(np.float64), 5, mode="constant") * 25
    got = scan.box_sum(x, 2)
    if kind in SPECIALS:  # documented: a non-finite value spoils the rest of its row and columns
        return
    _close(got, want, _scale(kind) * 25, rtol=1e-4)


def case_registration(kind):
    from vmcl.early import registration

    x = _input(kind, _base())
    h, w = x.shape
    yy, xx = np.mgrid[:h, :w].astype(np.float32)
    table = np.stack([xx + 0.5, yy], axis=-1)
    want = np.full(x.shape, np.nan)
    want[:, :-1] = 0.5 * x[:, :-1].astype(np.float64) + 0.5 * x[:, 1:]
    _close(registration.warp(x, table), want, _scale(kind))


def case_registration_table(kind):
    """Positions (the warp's addresses) scaled or non-finite: outside the image reads NaN, never memory."""
    from vmcl.early import registration

    x = _base()
    h, w = x.shape
    yy, xx = np.mgrid[:h, :w].astype(np.float32)
    table = np.stack([_input(kind, xx), yy], axis=-1)
    got = registration.warp(x, table)
    sx = table[..., 0].astype(np.float64)
    inside = np.isfinite(sx) & (sx >= 0) & (sx <= w - 1)
    _expect(np.isnan(got[~inside]).all(), "values read outside the image")
    whole = inside & (sx == np.floor(sx))
    _expect(np.array_equal(got[whole], x[yy[whole].astype(int), sx[whole].astype(int)]), "samples on pixels")


def case_stereo(kind):
    from vmcl.early import stereo

    left = _input(kind, _base())
    right = np.roll(left, -2, axis=1)
    _sane(stereo.match(left, right, d_min=0, d_max=4), kind in SCALES)


def case_motion(kind):
    from vmcl.early import motion

    f0 = _input(kind, _base())
    _sane(motion.flow(f0, np.roll(f0, 1, axis=1), delta=2, patch=5), kind in SCALES)


def case_color(kind):
    from vmcl.early import color

    grey = _input(kind, _base())
    rgb = np.stack([grey, grey * np.float32(0.5), grey[::-1]], axis=-1)
    _sane(color.hue(rgb), kind in SCALES)


def case_texture(kind):
    from vmcl.early import texture

    x = _input(kind, _base())
    _sane(texture.density(x, fine_sigma=1.0, coarse_sigma=2.0, threshold=0.01 * _scale(kind), radius=3),
          kind in SCALES)


def case_mrf(kind):
    from vmcl.mrf import restore

    _sane(restore(_input(kind, _base()), method="icm"), kind in SCALES)


def case_labelling(kind):
    from vmcl import labelling

    image = _input(kind, _base())
    support = np.zeros(image.shape, np.uint8)
    support[10:30, 28] = 1
    _sane(labelling.label(support, image), kind in SCALES)


FAMILIES = {
    "news": case_news, "scan": case_scan, "router": case_router, "doubling": case_doubling,
    "reduce": case_reduce, "cm_filters": case_filters, "early_filters": case_gaussian, "edges": case_edges,
    "noise": case_noise, "scan_box": case_box, "registration": case_registration,
    "registration_table": case_registration_table, "stereo": case_stereo, "motion": case_motion,
    "color": case_color, "texture": case_texture, "mrf": case_mrf, "labelling": case_labelling,
}
CASES = [f"{family}:{kind}" for family in FAMILIES for kind in (*SCALES, *SPECIALS)]
# The argument each family's refusal must name.
ARGUMENTS = {"news": "x", "scan": "x", "router": "field", "doubling": "mask", "reduce": "x",
             "cm_filters": "image", "early_filters": "image", "edges": "image", "noise": "magnitude",
             "scan_box": "x", "registration": "image",
             "registration_table": "table", "stereo": "left", "motion": "frame0", "color": "rgb",
             "texture": "image", "mrf": "data", "labelling": "image"}


def _run_case(name: str) -> dict:
    from vmcl.errors import InputError

    family, kind = name.split(":")
    try:
        FAMILIES[family](kind)
    except Wrong as wrong:
        return {"case": name, "outcome": "wrong", "detail": str(wrong)}
    except InputError as refusal:
        named = ARGUMENTS[family] in str(refusal)
        return {"case": name, "outcome": "refused" if named else "unnamed refusal", "detail": str(refusal)}
    except Exception as error:  # noqa: BLE001 - any other exception is what this sweep reports
        return {"case": name, "outcome": "error", "detail": f"{type(error).__name__}: {error}"}
    return {"case": name, "outcome": "ok", "detail": ""}


def _driver(names: list[str]) -> None:
    for name in names:
        print(json.dumps({"case": name, "outcome": "started"}), flush=True)
        print(json.dumps(_run_case(name)), flush=True)


# -- the test (runs in pytest) ---------------------------------------------------------------------------


def _sweep() -> dict[str, dict]:
    """Every case's outcome: the driver is restarted after the case that took it down."""
    outcomes: dict[str, dict] = {}
    remaining = list(CASES)
    while remaining:
        try:
            proc = subprocess.run([sys.executable, str(Path(__file__).resolve()), *remaining], check=False,
                                  capture_output=True, text=True, timeout=TIMEOUT)
            stdout, died = proc.stdout, f"died with exit status {proc.returncode}"
        except subprocess.TimeoutExpired as timeout:
            stdout, died = (timeout.stdout or b"").decode(), f"hung past {TIMEOUT} s"
        started = None
        for line in stdout.splitlines():
            record = json.loads(line)
            if record["outcome"] == "started":
                started = record["case"]
            else:
                outcomes[record["case"]] = record
                started = None
        if started is not None:
            outcomes[started] = {"case": started, "outcome": "crash", "detail": died}
        remaining = [name for name in remaining if name not in outcomes]
    return outcomes


@pytest.fixture(scope="module")
def sweep() -> dict[str, dict]:
    return _sweep()


@pytest.mark.parametrize("name", CASES)
def test_extreme_input_gives_a_result_or_a_named_refusal(sweep, name):
    record = sweep[name]
    assert record["outcome"] in ("ok", "refused"), f"{name}: {record['outcome']}: {record['detail']}"


if __name__ == "__main__":
    _driver(sys.argv[1:])
