"""Bad and extreme inputs against every public function of vmcl: a refusal that names the argument, or a
result of the right kind; never a crash, a hang or an exception of another type.

Each public callable has a row in :data:`TABLE`: a valid call (every argument as a JSON-able spec) and the
kind of each argument. Hypothesis picks one argument and a bad value of its kind (an array of the wrong
shape, dtype, order, scale or place; a number that is NaN, infinite, huge, negative or not a number; an
unknown name; a missing file ...). The cases run in a worker subprocess (this file run as a script), one
JSON line in and one out per case, so a segfault or a hang fails the case that caused it instead of
killing the test run; the worker is then restarted for the cases that remain.

A case passes when the call
- raises :class:`vmcl.errors.InputError` whose message contains the argument's name, or
- returns a result whose structure, dtypes and (unless the arrays' shapes were changed) dimensions are
  those of the valid call's result, or
- for a path argument, raises FileNotFoundError (a missing file is not a bad value of the argument).

Both variants are derandomized: the short one draws 12 cases per callable, the long one (marked ``slow``;
``-m "not slow"`` leaves it out) up to 300, which exhausts most callables' cases. Measured on one core with
PoCL's kernel cache warm: 5 s and 12 s. ``VMCL_SWEEP_LOG=file`` records every case and its outcome.
"""

from __future__ import annotations

import dataclasses
import importlib.util
import json
import os
import select
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

TEST_CASE_TIMEOUT_S = 30.0  # one case: a hang, not a slow run (the slowest valid case takes about 1 s)
REPO = Path(__file__).resolve().parents[1]

# --------------------------------------------------------------------------------------------- specs
# A value spec is JSON: plain JSON values stand for themselves; a dict with one of these keys builds:
#   {"array": shape, "dtype": d, "fill": f, "order": "C"|"F"|"strided", "device": bool}
#   {"float": "nan"|"inf"|"-inf"}, {"tuple": [...]}, {"complex": [re, im]}, {"np": dtype, "value": v}
#   {"make": name}: an object built by the worker (see _MAKERS), {"path": kind}: a file the worker writes.


def arr(shape, dtype="float32", fill="rand", **extra) -> dict:
    return {"array": list(shape), "dtype": dtype, "fill": fill, **extra}


def tup(*items) -> dict:
    return {"tuple": list(items)}


def make(name: str) -> dict:
    return {"make": name}


def path(kind: str) -> dict:
    return {"path": kind}


IMG = arr((16, 16))
RGB = arr((16, 16, 3))
MASK = arr((16, 16), "bool", "bits")
LINE_H, LINE_V = arr((16, 15), "bool", "bits"), arr((15, 16), "bool", "bits")
SUPPORT = arr((16, 16), "uint8", "randint:32")


@dataclasses.dataclass(frozen=True)
class Entry:
    """A callable (``module:qualname``), its valid call, and the kind of each argument to vary."""

    target: str
    call: dict
    kinds: dict  # argument -> kind (see _mutations); arguments left out are not varied
    aliases: dict  # argument -> the word (or words) a refusal may name it by instead (as_image's caller-given
    # name; a Config's section.key)


def _e(target: str, **call) -> Entry:
    kinds = call.pop("kinds")
    return Entry(target, call, kinds, call.pop("aliases", {}))


_A, _N, _I, _C, _B, _O, _T, _P, _M = ("array", "number", "int", "choice", "bool", "opaque", "tuple", "path",
                                      "machine")
# Optional arguments: None is one of their valid values.
_ON = "optional_number"
_OA = "optional_array"
_OT = "optional_tuple"

TABLE: tuple[Entry, ...] = (
    # ------------------------------------------------------------------ cm
    _e("vmcl.cm.doubling:label", mask=MASK, connectivity=8, relabel=False, method="doubling",
       kinds={"mask": _A, "connectivity": _I, "relabel": _B, "method": _C, "machine": _M}),
    _e("vmcl.cm.doubling:rank", next=make("chain"), kinds={"next": _A, "machine": _M}),
    _e("vmcl.cm.doubling:principal", next=make("ring"), kinds={"next": _A, "machine": _M}),
    _e("vmcl.cm.doubling:principal_from_predecessors", prev=make("ring"), kinds={"prev": _A, "machine": _M}),
    _e("vmcl.cm.filters:binomial", image=IMG, passes=2, kinds={"image": _A, "passes": _I, "machine": _M}),
    _e("vmcl.cm.filters:max_passes", height=16, width=16, kinds={"height": _I, "width": _I}),
    _e("vmcl.cm.filters:window_max", x=IMG, radius=2, kinds={"x": _A, "radius": _I, "machine": _M}),
    _e("vmcl.cm.news:shift", x=IMG, dx=1, dy=-1, border="zero",
       kinds={"x": _A, "dx": _I, "dy": _I, "border": _C, "machine": _M}),
    _e("vmcl.cm.reduce:reduce", x=IMG, op="sum", kinds={"x": _A, "op": _C, "machine": _M}),
    _e("vmcl.cm.reduce:extremes", x=IMG, kinds={"x": _A, "machine": _M}),
    _e("vmcl.cm.reduce:histogram", x=IMG, bins=8, range=tup(0.0, 1.0), tile=None,
       kinds={"x": _A, "bins": _I, "range": _T, "tile": _OT, "machine": _M}),
    _e("vmcl.cm.reduce:histogram_to_top", x=arr((16, 16), device=True), bins=8, top=make("device_one"), lo=0.0,
       kinds={"x": _A, "bins": _I, "top": _A, "lo": _N, "machine": _M}),
    _e("vmcl.cm.router:get", field=IMG, address=arr((16, 16), "int32", "randint:256"),
       kinds={"field": _A, "address": _A, "machine": _M}),
    _e("vmcl.cm.router:send", values=IMG, address=arr((16, 16), "int32", "randint:64"), size=64,
       combine="sum", fill=0.0,
       kinds={"values": _A, "address": _A, "size": _I, "combine": _C, "fill": _N, "machine": _M}),
    _e("vmcl.cm.scan:scan", x=IMG, op="plus", axis=-1, exclusive=False, segments=None, method="work_efficient",
       kinds={"x": _A, "op": _C, "axis": _I, "exclusive": _B, "segments": _OA, "method": _C, "machine": _M}),
    _e("vmcl.cm.scan:box_sum", x=IMG, radius=2, axes=tup(-2, -1),
       kinds={"x": _A, "radius": _I, "axes": _T, "machine": _M}),
    _e("vmcl.cm.scan:column_groups", width=16, kinds={"width": _I}),
    # ------------------------------------------------------------------ early
    _e("vmcl.early.color:hue", rgb=RGB, min_intensity=None, chromaticity=False,
       kinds={"rgb": _A, "min_intensity": _ON, "chromaticity": _B, "machine": _M}),
    _e("vmcl.early.color:albedo_edges", rgb=RGB, min_intensity=None, threshold=None,
       kinds={"rgb": _A, "min_intensity": _ON, "threshold": _ON, "machine": _M}),
    _e("vmcl.early.edges:zero_crossings", image=IMG, sigma=2.0, method="log", min_slope=0.0,
       kinds={"image": _A, "sigma": _N, "method": _C, "min_slope": _N, "machine": _M}),
    _e("vmcl.early.edges:hysteresis_threshold", image=IMG, low_threshold=0.3, high_threshold=0.6,
       method="doubling",
       kinds={"image": _A, "low_threshold": _N, "high_threshold": _N, "method": _C, "machine": _M}),
    _e("vmcl.early.edges:canny", image=IMG, sigma=2.0, low_threshold=None, high_threshold=None,
       use_quantiles=False, interpolate=True, method="doubling", noise="global", return_gradient=False,
       kinds={"image": _A, "sigma": _N, "low_threshold": _ON, "high_threshold": _ON, "use_quantiles": _B,
              "interpolate": _B, "method": _C, "noise": _C, "return_gradient": _B, "machine": _M}),
    _e("vmcl.early.filters:gaussian_taps", sigma=2.0, kinds={"sigma": _N}),
    _e("vmcl.early.filters:binomial_passes", sigma=2.0, kinds={"sigma": _N}),
    _e("vmcl.early.filters:gaussian", image=IMG, sigma=2.0, method="binomial",
       kinds={"image": _A, "sigma": _N, "method": _C, "machine": _M}),
    _e("vmcl.early.filters:laplacian_of_gaussian", image=IMG, sigma=2.0,
       kinds={"image": _A, "sigma": _N, "machine": _M}),
    _e("vmcl.early.filters:difference_of_gaussians", image=IMG, low_sigma=1.0, high_sigma=None,
       kinds={"image": _A, "low_sigma": _N, "high_sigma": _ON, "machine": _M}),
    _e("vmcl.early.motion:flow", frame0=IMG, frame1=IMG, delta=2, patch=5, features="brightness", subpixel=True,
       levels=1, sigma=None, speed_penalty=0.001, method="running", boundary_score=None, prediction=None,
       kinds={"frame0": _A, "frame1": _A, "delta": _I, "patch": _I, "features": _C, "subpixel": _B,
              "levels": _I, "sigma": _ON, "speed_penalty": _N, "method": _C, "boundary_score": _ON,
              "prediction": _OA, "machine": _M}),
    _e("vmcl.early.motion:pyramid_levels", shape=tup(64, 64), patch=11, delta=4, coarsest=32,
       kinds={"shape": _T, "patch": _I, "delta": _I, "coarsest": _I}),
    _e("vmcl.early.motion:reach", delta=4, levels=2, kinds={"delta": _I, "levels": _I}),
    _e("vmcl.early.motion:votes", frame0=IMG, frame1=IMG, delta=2, patch=5, features="brightness", sigma=None,
       kinds={"frame0": _A, "frame1": _A, "delta": _I, "patch": _I, "features": _C, "sigma": _ON,
              "machine": _M}),
    _e("vmcl.early.noise:noise_rule", low=2.0, high=4.1, kinds={"low": _N, "high": _N}),
    _e("vmcl.early.noise:noise_thresholds", magnitude=IMG, noise="global",
       kinds={"magnitude": _A, "noise": _C, "machine": _M}),
    _e("vmcl.early.registration:find_dots", image=make("dots"), polarity="dark", threshold=None, min_area=4,
       kinds={"image": _A, "polarity": _C, "threshold": _ON, "min_area": _I, "machine": _M}),
    _e("vmcl.early.registration:match_dots", left=make("dot_coords"), right=make("dot_coords"), max_shift=3.0,
       kinds={"left": _A, "right": _A, "max_shift": _N}),
    _e("vmcl.early.registration:WarpTable.from_dots", left=make("dot_coords"), right=make("dot_coords"),
       shape=tup(16, 16), vergence=0.0, kinds={"left": _A, "right": _A, "shape": _T, "vergence": _N}),
    _e("vmcl.early.registration:WarpTable.calibrate", left_image=make("dots"), right_image=make("dots"),
       max_shift=3.0, vergence=0.0, polarity="dark",
       kinds={"left_image": _A, "right_image": _A, "max_shift": _N, "vergence": _N, "polarity": _C,
              "machine": _M}),
    _e("vmcl.early.registration:warp", image=IMG, table=make("warp_table"),
       kinds={"image": _A, "table": _O, "machine": _M}),
    _e("vmcl.early.registration:TableStore.add", self=make("store"), table=make("warp_table_2"),
       kinds={"table": _O}),
    _e("vmcl.early.registration:TableStore.table_for", self=make("store"), vergence=0.5,
       kinds={"vergence": _N}),
    _e("vmcl.early.registration:TableStore.load", path=path("store"), kinds={"path": _P}),
    _e("vmcl.early.sign_correlation:sign_correlation", f=IMG, g=IMG, kinds={"f": _A, "g": _A, "machine": _M}),
    _e("vmcl.early.sign_correlation:arcsine_law", correlation=0.5, kinds={"correlation": _N}),
    _e("vmcl.early.stereo:match", left=IMG, right=IMG, d_min=0, d_max=4, features="canny", patch=5, sigma=2.0,
       min_score=0.3, bimodal=0.3, dip=0.8, min_votes=3.0, shiftable=False, barriers=None,
       kinds={"left": _A, "right": _A, "d_min": _I, "d_max": _I, "features": _C, "patch": _I, "sigma": _N,
              "min_score": _N, "bimodal": _N, "dip": _N, "min_votes": _N, "shiftable": _B, "barriers": _OA,
              "machine": _M}),
    _e("vmcl.early.stereo:match_features", left=MASK, right=MASK, left_attribute=IMG, right_attribute=IMG,
       d_min=0, d_max=4, compatible="direction", patch=5, direction_tolerance=0.35,
       kinds={"left": _A, "right": _A, "left_attribute": _A, "right_attribute": _A, "d_min": _I, "d_max": _I,
              "compatible": _C, "patch": _I, "direction_tolerance": _N, "machine": _M}),
    _e("vmcl.early.stereo:check_pair", left=IMG, right=IMG,
       kinds={"left": _A, "right": _A, "machine": _M}),
    _e("vmcl.early.stereo:direction_code", angle=0.5, kinds={"angle": _N}),
    _e("vmcl.early.stereo:check_range", d_min=0, d_max=4, width=16, kinds={"d_min": _I, "d_max": _I, "width": _I}),
    _e("vmcl.early.semiglobal:check_paths", paths=4, name="paths", kinds={"paths": _I}),
    _e("vmcl.early.semiglobal:max_p2", paths=8, kinds={"paths": _I}),
    _e("vmcl.early.semiglobal:match_semiglobal", left=IMG, right=IMG, d_min=0, d_max=4, census_threshold=3.0,
       ad_weight=1.0, ad_colour=False, match_exposure=True, p1=48, p2=64.0, edge_gain=0.0, paths=8, subpixel=True, tolerance=1,
       occlusion_geometry=True, refine=True, refine_radius=2, refine_colour=0.1, refine_stride=1,
       kinds={"left": _A, "right": _A, "d_min": _I, "d_max": _I, "census_threshold": _N, "ad_weight": _N,
              "ad_colour": _B, "match_exposure": _B, "p1": _I,
              "p2": _N, "edge_gain": _N, "paths": _I, "subpixel": _B, "tolerance": _I,
              "occlusion_geometry": _B, "refine": _B, "refine_radius": _I,
              "refine_colour": _N, "refine_stride": _I, "machine": _M}),
    _e("vmcl.early.motion_refine:refine_flow", flow=arr((16, 16, 2)), image=IMG, radius=2,
       sigma_colour=0.1, stride=1, kinds={"flow": _A, "image": _A, "radius": _I, "sigma_colour": _N, "stride": _I,
                                          "machine": _M}),
    _e("vmcl.early.lucas_kanade:lucas_kanade", flow=arr((16, 16, 2)), frame0=IMG, frame1=IMG, window=2.0,
       iterations=2, highpass=2.0, kinds={"flow": _A, "frame0": _A, "frame1": _A, "window": _N, "iterations": _I,
                                          "highpass": _N, "machine": _M}),
    _e("vmcl.early.variational:variational_refine", flow=arr((16, 16, 2)), frame0=IMG, frame1=IMG, alpha=20.0,
       delta=5.0, gamma=10.0, iterations=2, sweeps=2, levels=2, prior=arr((16, 16, 2)), beta=1.0,
       kinds={"flow": _A, "frame0": _A, "frame1": _A, "alpha": _N, "delta": _N, "gamma": _N, "iterations": _I,
              "sweeps": _I, "levels": _I, "prior": _OA, "beta": _N, "machine": _M}),
    _e("vmcl.early.weighted_median:check_sigma_colour", sigma_colour=0.1, name="sigma_colour",
       kinds={"sigma_colour": _N}),
    _e("vmcl.early.weighted_median:weighted_median", values=IMG, image=IMG, low=0.0, high=4.0, where=None,
       voters=None, radius=2, sigma_colour=0.1, sigma_space=2.0, stride=1, bin_width=1.0,
       kinds={"values": _A, "image": _A, "low": _N, "high": _N, "where": _OA, "voters": _OA, "radius": _I,
              "sigma_colour": _N, "sigma_space": _N, "stride": _I, "bin_width": _N, "machine": _M}),
    _e("vmcl.early.disparity_range:range_to_search", left=IMG, right=IMG, d_min=0, d_max=4,
       kinds={"left": _A, "right": _A, "d_min": _I, "d_max": _I, "machine": _M}),
    _e("vmcl.early.rectification:row_alignment", left=IMG, right=IMG, disparity=0.0,
       kinds={"left": _A, "right": _A, "disparity": _N}),
    _e("vmcl.early.disparity_range:estimate_range", left=IMG, right=IMG, max_disparity=1 / 3, coarse_side=48,
       patch=11, min_score=0.8, quantile=0.005, margin=1, widen=0.25, min_share=0.05,
       kinds={"left": _A, "right": _A, "max_disparity": _N, "coarse_side": _I, "patch": _I, "min_score": _N,
              "quantile": _N, "margin": _I, "widen": _N, "min_share": _N, "machine": _M}),
    _e("vmcl.early.disparity_range:fallback_range", width=16, max_disparity=1 / 3,
       kinds={"width": _I, "max_disparity": _N}),
    _e("vmcl.early.boundary_probability:boundary_probability", image=RGB, model=None,
       kinds={"image": _A, "model": _O, "machine": _M}),
    _e("vmcl.early.boundary_probability:oriented_gradients", image=IMG, model=None,
       kinds={"image": _A, "model": _O, "machine": _M}),
    _e("vmcl.early.boundary_probability:bank_responses", image=RGB, kinds={"image": _A, "machine": _M}),
    _e("vmcl.early.boundary_probability:sample_step", sigma=6.0, kinds={"sigma": _N}),
    _e("vmcl.boundary_evaluation:canny_sweep", image=RGB, count=3, kinds={"image": _A, "count": _I, "machine": _M}),
    _e("vmcl.boundary_evaluation:opencv_canny_sweep", image=arr((16, 16, 3), "uint8", "randint:255"), count=3,
       kinds={"image": _A, "count": _I}),
    _e("vmcl.boundary_evaluation:sweep_thresholds", count=3, kinds={"count": _I}),
    _e("vmcl.early.texture:density", image=IMG, fine_sigma=1.0, coarse_sigma=2.0, threshold=0.1, radius=4,
       kinds={"image": _A, "fine_sigma": _N, "coarse_sigma": _N, "threshold": _N, "radius": _I, "machine": _M}),
    _e("vmcl.early.texture:texture_edges", image=IMG, fine_sigma=1.0, coarse_sigma=2.0, threshold=0.1, radius=4,
       edge_threshold=None, noise_factor=3.5,
       kinds={"image": _A, "fine_sigma": _N, "coarse_sigma": _N, "threshold": _N, "radius": _I,
              "edge_threshold": _ON, "noise_factor": _N, "machine": _M}),
    # ------------------------------------------------------------------ mrf
    _e("vmcl.mrf:LinePrior", line=1.0, end=0.5, crossing=1.5, kinds={"line": _N, "end": _N, "crossing": _N}),
    _e("vmcl.mrf:EnergyModel", alpha=1.0, beta=1.0, kappa=1.0, levels=32, edge_gain=0.5, edge_radius=1,
       require_edge=False, prior=make("prior"),
       kinds={"alpha": _N, "beta": _N, "kappa": _N, "levels": _I, "edge_gain": _N, "edge_radius": _I,
              "require_edge": _B, "prior": _O}),
    _e("vmcl.mrf:AnnealSchedule", t0=4.0, t_factor=0.95, sweeps=10, quench=2,
       kinds={"t0": _N, "t_factor": _N, "sweeps": _I, "quench": _I}),
    _e("vmcl.mrf:MpmSchedule", mpm_temperature=1.0, burn_in=2, samples=2,
       kinds={"mpm_temperature": _N, "burn_in": _I, "samples": _I}),
    _e("vmcl.mrf:MeanFieldSchedule", mf_t0=4.0, mf_factor=0.8, mf_steps=2, mf_iterations=2, quench=2,
       kinds={"mf_t0": _N, "mf_factor": _N, "mf_steps": _I, "mf_iterations": _I, "quench": _I}),
    _e("vmcl.mrf:IcmSchedule", icm_sweeps=3, kinds={"icm_sweeps": _I}),
    _e("vmcl.mrf:Settings", model=make("energy_model"), schedules={}, kinds={"model": _O, "schedules": "mapping"}),
    _e("vmcl.mrf:backfill", primary=IMG, secondary=IMG, secondary_confidence=IMG,
       kinds={"primary": _A, "secondary": _A, "secondary_confidence": _A, "machine": _M}),
    _e("vmcl.mrf:boundary_map", line_h=LINE_H, line_v=LINE_V, kinds={"line_h": _A, "line_v": _A}),
    _e("vmcl.mrf:energy", f=IMG, line_h=LINE_H, line_v=LINE_V, data=IMG, confidence=None, edges=None,
       kind="smooth", model=None,
       kinds={"f": _A, "line_h": _A, "line_v": _A, "data": _A, "confidence": _OA, "edges": _OA, "kind": _C,
              "model": _O}),
    _e("vmcl.mrf:preset", cue="stereo", kinds={"cue": _C}),
    _e("vmcl.mrf:sample", data=arr((12, 12)), confidence=None, edges=None, kind="smooth", model=None,
       temperature=1.0, sweeps=2, lines=True, start=None, seed=0,
       kinds={"data": _A, "confidence": _OA, "edges": _OA, "kind": _C, "model": _O, "temperature": _N,
              "sweeps": _I, "lines": _B, "start": _OA, "seed": _I, "machine": _M}),
    # ------------------------------------------------------------------ learn
    _e("vmcl.learn:fit_pseudolikelihood", examples=[make("example")], kind="smooth", levels=None, fixed=None,
       ridge=1e-6, tolerance=1e-9, max_iterations=20,
       kinds={"examples": _O, "kind": _C, "fixed": _O, "ridge": _N, "tolerance": _N, "max_iterations": _I,
              "machine": _M}),
    _e("vmcl.learn.pseudolikelihood:check_fixed", fixed={"alpha": 1.0}, kind="smooth", sites="all",
       kinds={"fixed": _O, "kind": _C, "sites": _C}),
    _e("vmcl.learn:Pseudolikelihood", examples=[make("example")], kind="smooth", levels=None,
       kinds={"examples": _O, "kind": _C, "machine": _M}),
    _e("vmcl.learn:Pseudolikelihood.terms", self=make("pseudolikelihood"), theta=make("theta"),
       kinds={"theta": _O}),
    _e("vmcl.learn:cross_validate", data=IMG, confidence=None, edges=None, kind="smooth", model=None, method="icm",
       candidates=[0.5, 1.0], holdout=0.25, folds=1, seed=0,
       kinds={"data": _A, "confidence": _OA, "edges": _OA, "kind": _C, "model": _O, "method": _C,
              "holdout": _N, "folds": _I, "seed": _I, "machine": _M}),
    _e("vmcl.learn:estimate_noise", data=IMG, confidence=None, edges=None, kind="smooth", model=None, sigma=None,
       iterations=2, burn_in=0, sweeps=1, seed=0,
       kinds={"data": _A, "confidence": _OA, "kind": _C, "model": _O, "sigma": _ON, "burn_in": _I, "sweeps": _I, "seed": _I, "machine": _M}),
    _e("vmcl.learn:fit_restoration", examples=[make("example")], start=make("settings"), kind="smooth",
       candidates_only=False, method="icm", parameters=["alpha", "end"], weights=None, tolerance=1.0, evaluations=3,
       step_floor=0.1,
       kinds={"examples": _O, "start": _O, "kind": _C, "candidates_only": _B, "method": _C, "parameters": _O,
              "weights": _O, "tolerance": _N, "evaluations": _I, "step_floor": _N, "machine": _M}),
    _e("vmcl.learn:model_overrides", model=make("energy_model"), kappa=False, kinds={"model": _O, "kappa": _B}),
    _e("vmcl.learn:restoration_error", field=IMG, line_h=LINE_H, line_v=LINE_V, example=make("example"),
       tolerance=1.0, kinds={"field": _A, "line_h": _A, "line_v": _A, "example": _O, "tolerance": _N}),
    _e("vmcl.learn.labelling_fit:labeller_provenance", presets=["blocks", "cues"], seeds=[0, 1], shape=tup(64, 80),
       noise=0.01, kinds={"presets": _O, "seeds": _O, "shape": _T, "noise": _N}),
    _e("vmcl.learn:scan_temperature", data=IMG, kind="smooth", model=None, temperatures=[0.5, 1.0, 2.0],
       sweeps=1, lines=True, margin=1.5, seed=0,
       kinds={"data": _A, "kind": _C, "model": _O, "sweeps": _I, "lines": _B, "margin": _N,
              "seed": _I, "machine": _M}),
    _e("vmcl.learn.examples:jump_lines", field=IMG, jump=1.0, valid=None,
       kinds={"field": _A, "jump": _N, "valid": _OA}),
    _e("vmcl.learn.examples:segmentation_example", data=IMG, confidence=None, edges=MASK,
       segmentation=arr((16, 16), "int32", "randint:4"), model=make("energy_model"),
       kinds={"data": _A, "confidence": _OA, "segmentation": _A, "model": _O}),
    _e("vmcl.learn.examples:truth_example", truth=IMG, data=IMG, confidence=None, edges=MASK, valid=None, jump=1.0,
       kinds={"truth": _A, "jump": _N, "valid": _OA}),
    # ------------------------------------------------------------------ group
    _e("vmcl.group:link_edges", edges=MASK, magnitude=None, smoothing=2.0,
       kinds={"edges": _A, "magnitude": _OA, "smoothing": _N, "machine": _M}),
    _e("vmcl.group:structural_saliency", edges=MASK, tangent=None, strength=None, iterations=4, gap_attenuation=0.85,
       curvature_scale=1.0, kinds={"edges": _A, "tangent": _OA, "strength": _OA, "iterations": _I,
                                   "gap_attenuation": _N, "curvature_scale": _N, "machine": _M}),
    _e("vmcl.group:saliency_strength", edges=MASK, magnitude=IMG, kinds={"edges": _A, "magnitude": _A, "machine": _M}),
    _e("vmcl.group:find_junctions", curves=make("curves"), gap=6.0, min_length=5, corner=60.0, straight=25.0,
       merge=3.0, kinds={"curves": _O, "gap": _N, "min_length": _I, "corner": _N, "straight": _N, "merge": _N}),
    _e("vmcl.group:group_curves", junctions=make("junctions"), image=None, alignment=20.0, max_distance=100.0,
       contrast=0.1, kinds={"junctions": _O, "image": _OA, "alignment": _N, "max_distance": _N, "contrast": _N}),
    _e("vmcl.group:repair_edges", edges=MASK, junctions=make("junctions"), kinds={"edges": _A, "junctions": _O}),
    _e("vmcl.group:local_saliency", curves=make("curves"), length_exponent=0.5, curvature_scale=0.5,
       kinds={"curves": _O, "length_exponent": _N, "curvature_scale": _N}),
    _e("vmcl.group:saliency_map", curves=make("curves"), values=make("curve_values"),
       kinds={"curves": _O, "values": _A}),
    _e("vmcl.group:salient_edges", curves=make("curves"), saliency=make("curve_values"), threshold=0.5,
       kinds={"curves": _O, "saliency": _A, "threshold": _N}),
    _e("vmcl.group:group", edges=MASK, magnitude=None, image=None, threshold=0.0, length_exponent=0.5,
       curvature_scale=0.5, gap=6.0, alignment=20.0,
       kinds={"edges": _A, "magnitude": _OA, "image": _OA, "threshold": _N, "length_exponent": _N,
              "curvature_scale": _N, "gap": _N, "alignment": _N, "machine": _M}),
    # ------------------------------------------------------------------ recognize
    _e("vmcl.recognize:image_features", image=arr((32, 32)), sigma=1.5, corner=45.0, gap=6.0,
       kinds={"image": _A, "sigma": _N, "corner": _N, "gap": _N, "machine": _M}),
    _e("vmcl.recognize:features_of", image=arr((32, 32)), sigma=1.5, corner=45.0,
       kinds={"image": _A, "sigma": _N, "corner": _N, "machine": _M}),
    _e("vmcl.recognize:edge_features", edges=MASK, magnitude=None, corner=45.0, gap=6.0,
       kinds={"edges": _A, "magnitude": _OA, "corner": _N, "gap": _N, "machine": _M}),
    _e("vmcl.recognize:view_of", features=make("object_features"), mask=None, spacing=2,
       kinds={"features": _O, "mask": _OA, "spacing": _I}),
    _e("vmcl.recognize:learn", name="ell", images=[make("object_image")], masks=None, sigma=1.5, corner=45.0,
       sources=None, kinds={"name": _C, "images": _O, "masks": _O, "sigma": _N, "corner": _N, "sources": _O,
                            "machine": _M}),
    _e("vmcl.recognize:save_model", model=make("model"), folder=path("new_dir"), replace=False,
       kinds={"model": _O, "folder": _P, "replace": _B}),
    _e("vmcl.recognize:load_model", path=path("vmodel"), kinds={"path": _P}),
    _e("vmcl.recognize:model_path", folder=path("dir"), name="box", folder_name=None,
       kinds={"folder": _P, "name": _C, "folder_name": _O}),
    _e("vmcl.recognize:Library", models=[make("model")], kinds={"models": _O}),
    _e("vmcl.recognize:Library.load", folder=path("library"), kinds={"folder": _P}),
    _e("vmcl.recognize:Index.build", library=make("library"), neighbours=8, kinds={"library": _O, "neighbours": _I}),
    _e("vmcl.recognize:index_for", library=make("library"), neighbours=8, kinds={"library": _O, "neighbours": _I}),
    _e("vmcl.recognize:corner_pairs", corners=arr((5, 2), "float64"), neighbours=3, groups=None,
       kinds={"corners": _A, "neighbours": _I, "groups": _OA}),
    _e("vmcl.recognize:pair_keys", corners=arr((5, 2), "float64"), bisector=arr((5,), "float64"),
       opening=arr((5,), "float64"), pairs=make("corner_pairs"), radius=None, soft=False,
       kinds={"corners": _A, "bisector": _A, "opening": _A, "pairs": _A, "radius": _OA, "soft": _B}),
    _e("vmcl.recognize:vote", index=make("index"), corners=arr((5, 2), "float64"), bisector=arr((5,), "float64"),
       opening=arr((5,), "float64"), pairs=make("corner_pairs"), radius=None, scales=tup(0.25, 4.0), candidates=64,
       min_votes=2,
       kinds={"index": _O, "corners": _A, "bisector": _A, "opening": _A, "pairs": _A, "radius": _OA, "scales": _T,
              "candidates": _I, "min_votes": _I, "machine": _M}),
    _e("vmcl.recognize:vote_numpy", index=make("index"), corners=arr((5, 2), "float64"),
       bisector=arr((5,), "float64"), opening=arr((5,), "float64"), pairs=make("corner_pairs"), radius=None,
       scales=tup(0.25, 4.0), candidates=64, min_votes=2,
       kinds={"index": _O, "corners": _A, "bisector": _A, "opening": _A, "pairs": _A, "radius": _OA, "scales": _T,
              "candidates": _I, "min_votes": _I}),
    _e("vmcl.recognize:anchors_of", features=make("object_features"), kinds={"features": _O}),
    _e("vmcl.recognize:arcs_of", curves=make("curves"), kinds={"curves": _O}),
    _e("vmcl.recognize:select_regions", edges=MASK, saliency_map=IMG, min_area=4, max_fraction=0.5,
       kinds={"edges": _A, "saliency_map": _A, "min_area": _I, "max_fraction": _N, "machine": _M}),
    _e("vmcl.recognize:corner_regions", regions=make("regions"), corners=arr((5, 2), "float64"),
       bisector=arr((5,), "float64"), reach=3.0, top=8,
       kinds={"regions": _O, "corners": _A, "bisector": _A, "reach": _N, "top": _I}),
    _e("vmcl.recognize:carry", transform=arr((3, 3), "float64"), points=arr((5, 2), "float64"),
       kinds={"transform": _A, "points": _A}),
    _e("vmcl.recognize:distance_transform", edges=MASK, kinds={"edges": _A, "machine": _M}),
    _e("vmcl.recognize:distance_transform_numpy", edges=MASK, kinds={"edges": _A}),
    _e("vmcl.recognize:support", nearest=make("nearest"), tangent_map=IMG, points=arr((6, 2), "float64"),
       tangents=arr((6,), "float64"), point_ranges=make("point_ranges"), transforms=make("transforms"),
       kinds={"nearest": _A, "tangent_map": _A, "points": _A, "tangents": _A, "point_ranges": _A,
              "transforms": _A, "machine": _M}),
    _e("vmcl.recognize:support_numpy", nearest=make("nearest"), tangent_map=IMG, points=arr((6, 2), "float64"),
       tangents=arr((6,), "float64"), point_ranges=make("point_ranges"), transforms=make("transforms"),
       kinds={"nearest": _A, "tangent_map": _A, "points": _A, "tangents": _A, "point_ranges": _A,
              "transforms": _A}),
    _e("vmcl.recognize:refine", nearest=make("nearest"), tangent_map=IMG, points=arr((6, 2), "float64"),
       tangents=arr((6,), "float64"), point_ranges=make("point_ranges"), transforms=make("transforms"),
       transform="similarity", tolerance=2.0, angle=25.0, start=4.0, iterations=2,
       kinds={"nearest": _A, "tangent_map": _A, "points": _A, "tangents": _A, "point_ranges": _A,
              "transforms": _A, "transform": _C, "tolerance": _N, "angle": _N, "start": _N, "iterations": _I,
              "machine": _M}),
    # The image's content decides how many objects are found (the result's length): valid changes of the
    # thresholds change it, so they are checked for their refusals only in tests/test_recognize.py.
    _e("vmcl.recognize:recognize", image=make("object_image"), library=make("library"), stretch=1.3, arcs=True,
       depth=None, kinds={"image": _A, "library": _O, "transform": _C, "stretch": _N, "arcs": _B, "depth": _OA,
                          "machine": _M}),
    _e("vmcl.scenes:object_view", name="ell", yaw=0.0, shape=tup(48, 48), scale=None, background=0.2, albedo=0.8,
       noise=0.0, seed=0, kinds={"name": _C, "yaw": _N, "shape": _T, "scale": _ON, "background": _N,
                                 "albedo": _N, "noise": _N, "seed": _I}),
    # How many objects a scene holds is its objects argument: tests/test_scenes_recognition.py checks the rest.
    _e("vmcl.scenes:recognition_scene", shape=tup(96, 96), objects=1, library=None, occlusion=tup(0.0, 0.9),
       clutter=1, views=tup(-40.0, 40.0), size=tup(15.0, 20.0), noise=0.0, stereo=False, seed=0,
       kinds={"library": _O, "occlusion": _T, "clutter": _I, "views": _T, "size": _T, "noise": _N, "stereo": _B,
              "seed": _I}),
    _e("vmcl.scenes:example_views", name="ell", shape=tup(48, 48), kinds={"name": _C, "shape": _T}),
    _e("vmcl.scenes:example_library", names=["ell"], kinds={"names": _O, "machine": _M}),
    _e("vmcl.metrics:recognition_scores", detections=[], placements=[make("placement")],
       learned={"ell": [make("placement")]}, tolerance=0.25,
       kinds={"detections": _O, "learned": _O, "tolerance": _N}),
    _e("vmcl.report:recognition_image", image=arr((48, 48)), detections=[],
       kinds={"image": _A, "detections": _O}),
    _e("vmcl.scenes:clutter_display", shape=tup(64, 64), segments=20, length=tup(5.0, 10.0), gaps=2, gap_length=3,
       seed=0, kinds={"shape": _T, "segments": _I, "length": _T, "gaps": _I, "gap_length": _I, "seed": _I}),
    # The scene's shape, polygons, seed and margin decide how many junctions it has, so valid changes of them
    # change the result's structure; tests/test_scenes_occlusion.py checks their refusals.
    _e("vmcl.scenes:render_occlusion", shape=tup(32, 32), polygons=3, seed=0, noise=0.0, antialias=True, margin=2,
       kinds={"noise": _N, "antialias": _B}),
    _e("vmcl.scenes:occlusion_scene", polygons=make("polygons"), greys=[0.2, 0.8], shape=tup(32, 32),
       background=0.5, noise=0.0, seed=0, antialias=True, margin=2,
       kinds={"background": _N, "noise": _N, "antialias": _B}),
    _e("vmcl.fitted:check_writable", path=path("new"), kinds={"path": _P}),
    _e("vmcl.fitted:config_sha256", settings={"edges": {"sigma": 1.0}}, kinds={"settings": _O}),
    _e("vmcl.fitted:toml_values", value={"edges": {"sigma": 1.0}}, where="", kinds={"where": _O}),
    _e("vmcl.learn.cue_fit:check_machine", vm=make("vision_machine"), kinds={"vm": _O}),
    _e("vmcl.fitted:check_fitted", values={"edges": {"sigma": 1.0}}, source="x.toml",
       kinds={"values": "mapping"}),
    _e("vmcl.mrf:restore", data=arr((12, 12)), confidence=None, edges=None, kind="smooth", method="icm",
       model=make("energy_model"), schedule=make("icm_schedule"), seed=0,
       kinds={"data": _A, "confidence": _OA, "edges": _OA, "kind": _C, "method": _C, "model": _O,
              "schedule": _O, "seed": _I, "machine": _M}),
    _e("vmcl.mrf:score_confidence", score=IMG, floor=0.5, weight=1.0,
       kinds={"score": _A, "floor": _N, "weight": _N, "machine": _M}),
    _e("vmcl.mrf:mask_confidence", data=IMG, mask=MASK, weight=1.0, masked_weight=0.5,
       kinds={"data": _A, "mask": _A, "weight": _N, "masked_weight": _N, "machine": _M}),
    # ------------------------------------------------------------------ integration and labelling
    _e("vmcl.integrate:boundary", line_h=LINE_H, line_v=LINE_V, kinds={"line_h": _A, "line_v": _A, "machine": _M}),
    _e("vmcl.labels:cue_bit", cue="stereo", kinds={"cue": _C}),
    _e("vmcl.labels:rule_label", cue="stereo", kinds={"cue": _C}),
    _e("vmcl.integrate:restore_cue", data=arr((12, 12)), confidence=None, coupling=None, kind="smooth",
       candidates_only=False, settings=make("settings"), method="icm", seed=0,
       kinds={"data": _A, "confidence": _OA, "kind": _C, "candidates_only": _B, "settings": _O, "method": _C,
              "seed": _I, "machine": _M}),
    _e("vmcl.integrate:integrate", lines=make("lines"), edges=MASK, owners=None, shape=None,
       kinds={"lines": _O, "edges": _OA, "owners": _O, "shape": _OT, "machine": _M}),
    _e("vmcl.labelling:candidate_bits", inputs=["stereo", "colour"], kinds={"inputs": "names"}),
    _e("vmcl.labelling:LinearLabeller", weights=make("weights"), fitted_on="", kinds={"weights": _O}),
    _e("vmcl.labelling:LinearLabeller.load", path=None, kinds={"path": _P}),
    _e("vmcl.labelling:LinearLabeller.for_inputs", self=make("labeller"), inputs=["stereo"],
       kinds={"inputs": "names"}),
    _e("vmcl.labelling:features", support=SUPPORT, image=IMG, disparity=None, flow=None, hue=None,
       kinds={"support": _A, "image": _A, "disparity": _OA, "flow": _OA, "hue": _OA, "machine": _M}),
    _e("vmcl.labelling:fit_targets", truth=arr((16, 16), "uint8", "randint:7"), tolerance=None,
       kinds={"truth": _A, "tolerance": _OA}),
    _e("vmcl.labelling:classify", support=SUPPORT, image=IMG, disparity=IMG, flow=None, hue=None, texture=True,
       labeller=None, probability=arr((16, 16)),
       kinds={"support": _A, "image": _A, "disparity": _OA, "flow": _OA, "hue": _OA, "texture": _B,
              "labeller": _O, "probability": _OA, "machine": _M}),
    _e("vmcl.labelling:label", support=SUPPORT, image=IMG, disparity=IMG, flow=None, hue=None, texture=True,
       labeller=None,
       kinds={"support": _A, "image": _A, "disparity": _OA, "flow": _OA, "hue": _OA, "texture": _B,
              "labeller": _O, "machine": _M}),
    # ------------------------------------------------------------------ metrics
    _e("vmcl.metrics:evaluate_disparity", disparity=IMG, ground_truth=IMG, mask=None, thresholds=[0.5, 1.0],
       kinds={"disparity": _A, "ground_truth": _A, "mask": _OA, "thresholds": _T}),
    _e("vmcl.metrics:endpoint_error", flow=arr((16, 16, 2)), ground_truth=arr((16, 16, 2)),
       kinds={"flow": _A, "ground_truth": _A}),
    _e("vmcl.metrics:angular_error", flow=arr((16, 16, 2)), ground_truth=arr((16, 16, 2)),
       kinds={"flow": _A, "ground_truth": _A}),
    _e("vmcl.metrics:evaluate_flow", flow=arr((16, 16, 2)), ground_truth=arr((16, 16, 2)), mask=None,
       kinds={"flow": _A, "ground_truth": _A, "mask": _OA}),
    _e("vmcl.metrics:boundary_counts", edge_map=IMG, ground_truths=[MASK], thresholds=3, max_dist=0.0075,
       thin=True, kinds={"edge_map": _A, "ground_truths": _O, "thresholds": _I, "max_dist": _N, "thin": _B}),
    _e("vmcl.metrics:evaluate_boundaries", edge_maps=[IMG], ground_truths=[[MASK]], thresholds=3,
       max_dist=0.0075, thin=True, workers=1,
       kinds={"edge_maps": _O, "ground_truths": _O, "thresholds": _I, "max_dist": _N, "thin": _B,
              "workers": _I}),
    _e("vmcl.boundary_evaluation:local_saliency_sweep", image=arr((32, 32)), length_exponent=None, curvature_scale=None,
       kinds={"image": _A, "length_exponent": _ON, "curvature_scale": _ON, "machine": _M}),
    _e("vmcl.boundary_evaluation:structural_saliency_sweep", image=arr((32, 32)), iterations=3, gap_attenuation=None,
       kinds={"image": _A, "iterations": _I, "gap_attenuation": _ON, "machine": _M}),
    _e("vmcl.metrics:match_points", truth=arr((5, 2), "float64"), found=arr((4, 2), "float64"), tolerance=0.5,
       kinds={"truth": _A, "found": _A, "tolerance": _N}),
    _e("vmcl.metrics:point_scores", truth=arr((5, 2), "float64"), found=arr((4, 2), "float64"), tolerance=0.5,
       ignore=None, exclude=None, kinds={"truth": _A, "found": _A, "tolerance": _N, "ignore": _OA, "exclude": _OA}),
    _e("vmcl.metrics:segmentation_junctions", segmentation=arr((16, 16), "int32", "randint:4"), merge=2.0,
       kinds={"segmentation": _A, "merge": _N}),
    _e("vmcl.metrics:detection_scores", predicted=MASK, truth=MASK, tolerance=1.0,
       kinds={"predicted": _A, "truth": _A, "tolerance": _N}),
    _e("vmcl.metrics:within_tolerance", truth=MASK, tolerance=1.0, kinds={"truth": _A, "tolerance": _N}),
    _e("vmcl.metrics:label_scores", predicted=arr((16, 16), "uint8", "randint:7"),
       truth=arr((16, 16), "uint8", "randint:7"), tolerance=1.0, labels=None,
       kinds={"predicted": _A, "truth": _A, "tolerance": _N, "labels": "names"}),
    # ------------------------------------------------------------------ scenes
    _e("vmcl.scenes:Texture", kind="blobs", scale=1.0, contrast=0.5, angle=0.0, size=0.1, fill=0.5,
       kinds={"kind": _C, "scale": _N, "contrast": _N, "angle": _N, "size": _N, "fill": _N}),
    _e("vmcl.scenes:Mark", shape="rect", bounds=tup(0.0, 0.0, 1.0, 1.0), colour=tup(0.5, 0.5, 0.5), texture=None,
       kinds={"shape": _C, "bounds": _T, "colour": _T, "texture": _O}),
    _e("vmcl.scenes:Face", origin=tup(0.0, 0.0, 5.0), u_axis=tup(1.0, 0.0, 0.0), v_axis=tup(0.0, 1.0, 0.0),
       size=tup(1.0, 1.0), colour=tup(0.5, 0.5, 0.5),
       kinds={"origin": _T, "u_axis": _T, "v_axis": _T, "size": _OT, "colour": _T}),
    _e("vmcl.scenes:Motion.matrix", self=make("motion"), kinds={}),
    _e("vmcl.scenes:Motion", translation=tup(0.1, 0.0, 0.0), rotation=tup(0.0, 0.1, 0.0),
       centre=tup(0.0, 0.0, 5.0), kinds={"translation": _T, "rotation": _T, "centre": _T}),
    _e("vmcl.scenes:Body", faces=make("faces"), motion=make("motion"), name="b",
       kinds={"faces": _O, "motion": _O, "name": _C}),
    _e("vmcl.scenes:Light", direction=tup(-0.4, -0.6, -0.7), colour=tup(1.0, 1.0, 1.0), ambient=0.3,
       specular=0.0, shininess=60.0,
       kinds={"direction": _T, "colour": _T, "ambient": _N, "specular": _N, "shininess": _N}),
    _e("vmcl.scenes:Camera", shape=tup(64, 64), focal=64.0, baseline=0.15,
       kinds={"shape": _T, "focal": _N, "baseline": _N}),
    _e("vmcl.scenes:World", camera=make("camera"), light=make("light"), bodies=make("bodies"),
       kinds={"camera": _O, "light": _O, "bodies": _O}),
    _e("vmcl.scenes:box", centre=tup(0.0, 0.0, 5.0), size=tup(1.0, 1.0, 1.0), colour=tup(0.5, 0.5, 0.5),
       rotation=tup(0.0, 0.2, 0.0), kinds={"centre": _T, "size": _T, "colour": _T, "rotation": _T}),
    _e("vmcl.scenes:fold", left=tup(-1.0, 0.0, 5.0), crease=tup(0.0, 0.0, 4.0), right=tup(1.0, 0.0, 5.0),
       height=1.0, colour=tup(0.5, 0.5, 0.5),
       kinds={"left": _T, "crease": _T, "right": _T, "height": _N, "colour": _T}),
    _e("vmcl.scenes:preset", name="blocks", shape=tup(64, 64), specular=False,
       kinds={"name": _C, "shape": _T, "specular": _B}),
    _e("vmcl.scenes:render", world=make("world"), seed=0, noise=0.0, frame=0,
       kinds={"world": _O, "seed": _I, "noise": _N, "frame": _I}),
    _e("vmcl.scenes:advance", world=make("world"), steps=1, speeds=None, kinds={"world": _O, "steps": _I, "speeds": _OA}),
    # ------------------------------------------------------------------ datasets
    _e("vmcl.datasets:read_image", path=path("png"), picture=False, check=None,
       kinds={"path": _P, "picture": _B, "check": _O}),
    _e("vmcl.datasets:from_opencv", image=IMG, name="an image", opaque_alpha=False,
       kinds={"image": _A, "name": _O, "opaque_alpha": _B}),
    _e("vmcl.datasets:read_mask", path=path("png"), value=255, kinds={"path": _P, "value": _I}),
    _e("vmcl.datasets:read_pfm", path=path("pfm"), kinds={"path": _P}),
    _e("vmcl.datasets:write_pfm", path=path("new"), image=IMG, kinds={"path": _P, "image": _A}),
    _e("vmcl.datasets:read_disparity", path=path("png"), scale=8.0, unknown=0,
       kinds={"path": _P, "scale": _N, "unknown": _I}),
    _e("vmcl.datasets:read_flo", path=path("flo"), raw=False, kinds={"path": _P, "raw": _B}),
    _e("vmcl.datasets:write_flo", path=path("new"), flow=arr((16, 16, 2)), kinds={"path": _P, "flow": _A}),
    _e("vmcl.datasets:load_stereo", name="tsukuba", root=path("empty_dir"), kinds={"name": _C, "root": _P}),
    _e("vmcl.datasets:load_flow", name="Venus", root=path("empty_dir"), colour=False,
       kinds={"name": _C, "root": _P, "colour": _B}),
    _e("vmcl.datasets:load_bsds", root=path("empty_dir"), split="test", kinds={"root": _P, "split": _C}),
    _e("vmcl.datasets:read_bsds_folder", folder=path("empty_dir"), split="test", kinds={"folder": _P, "split": _C}),
    _e("vmcl.datasets:read_stereo_folder", folder=path("stereo_dir"), kinds={"folder": _P}),
    _e("vmcl.datasets:write_stereo_folder", folder=path("new_dir"), left=arr((16, 16), "uint8"),
       right=arr((16, 16), "uint8"), disparity=IMG, ndisp=16,
       kinds={"folder": _P, "left": _A, "right": _A, "disparity": _A, "ndisp": _I}),
    _e("vmcl.datasets:find_stereo_folders", root=path("empty_dir"), depth=4, kinds={"root": _P, "depth": _I}),
    _e("vmcl.datasets:read_flow_folder", folder=path("flow_dir"), kinds={"folder": _P}),
    _e("vmcl.datasets:find_flow_folders", root=path("empty_dir"), depth=4, kinds={"root": _P, "depth": _I}),
    _e("vmcl.datasets:stereo_folders_lacking", root=path("empty_dir"), depth=4, kinds={"root": _P, "depth": _I}),
    _e("vmcl.datasets:stereo_views", folder=path("empty_dir"), kinds={"folder": _P}),
    _e("vmcl.datasets:find_bsds_folders", root=path("empty_dir"), depth=4, kinds={"root": _P, "depth": _I}),
    _e("vmcl.datasets:flow_folders_lacking", root=path("empty_dir"), depth=4, kinds={"root": _P, "depth": _I}),
    # ------------------------------------------------------------------ sequences
    _e("vmcl.flow_evaluation:motion_only", config=None, kinds={"config": _O}),
    # ------------------------------------------------------------------ stereo evaluation
    _e("vmcl.stereo_evaluation:grey", image=arr((16, 16), "uint8", "randint:256"), kinds={"image": _A}),
    _e("vmcl.stereo_evaluation:stereo_bm", num_disparities=16, kinds={"num_disparities": _I}),
    _e("vmcl.stereo_evaluation:stereo_sgbm", num_disparities=16, mode="3WAY",
       kinds={"num_disparities": _I, "mode": _C}),
    _e("vmcl.stereo_evaluation:opencv_disparity", matcher=make("stereo_sgbm"),
       left=arr((16, 32), "uint8", "randint:256"), right=arr((16, 32), "uint8", "randint:256"),
       kinds={"matcher": _O, "left": _A, "right": _A}),
    _e("vmcl.stereo_evaluation:baseline_disparities", pair=make("stereo_pair"), kinds={"pair": _O}),
    _e("vmcl.stereo_evaluation:opencv_baselines", pair=make("stereo_pair"), kinds={"pair": _O}),
    _e("vmcl.stereo_evaluation:vmcl_method", config=None, kinds={"config": _O, "machine": _M}),
    _e("vmcl.stereo_evaluation:evaluate_pair", pair=make("stereo_pair"), methods=make("stereo_methods"), warm=False,
       kinds={"pair": _O, "methods": _O, "warm": _B}),
    _e("vmcl.stereo_evaluation:markdown_tables", evaluations=make("evaluations"), kinds={"evaluations": _O}),
    # ------------------------------------------------------------------ patterns, eye-head, report
    _e("vmcl.patterns:spiral", size=16, corridor=1, kinds={"size": _I, "corridor": _I}),
    _e("vmcl.eyehead:table_for_fixation", head=make("head"), store=make("store"), kinds={"head": _O, "store": _O}),
    _e("vmcl.pictures:disparity_image", disparity=IMG, vmin=None, vmax=None,
       kinds={"disparity": _A, "vmin": _ON, "vmax": _ON}),
    _e("vmcl.pictures:flow_image", flow=arr((16, 16, 2)), max_flow=None, kinds={"flow": _A, "max_flow": _ON}),
    _e("vmcl.report:labels_image", image=RGB, labels=arr((16, 16), "uint8", "randint:7"),
       kinds={"image": _A, "labels": _A}),
    _e("vmcl.report:support_image", image=RGB, support=SUPPORT, kinds={"image": _A, "support": _A}),
    _e("vmcl.report:strength_image", strength=arr((16, 16), "float32", "rand"), kinds={"strength": _A}),
    _e("vmcl.pictures:field_image", values=IMG, kinds={"values": _A}),
    _e("vmcl.pictures:to_uint8", rgb=arr((16, 16, 3)), kinds={"rgb": _A}),
    _e("vmcl.pictures:eight_bits", image=arr((16, 16), "uint16"), kinds={"image": _A}),
    _e("vmcl.report:grouping_image", image=IMG, grouping=make("grouping"), kinds={"image": _A, "grouping": _O}),
    _e("vmcl.report:encode_png", rgb=arr((16, 16, 3), "uint8", "randint:256"), kinds={"rgb": _A}),
    _e("vmcl.report:images", result=make("result"), kinds={"result": _O}),
    _e("vmcl.report:images_with_captions", result=make("result"), kinds={"result": _O}),
    _e("vmcl.report:write_report", result=make("result"), folder=path("new_dir"), title="t", evaluation=None,
       kinds={"result": _O, "folder": _P, "title": _C, "evaluation": _O}),
    # ------------------------------------------------------------------ pipeline, machine
    _e("vmcl.pipeline:as_image", array=IMG, name="left", kinds={"array": _A}, aliases={"array": "left"}),
    _e("vmcl.pipeline:Config.from_dict", values={"edges": {"sigma": 1.5}}, kinds={"values": "mapping"},
       aliases={"values": ("config", "edges.", "stereo.", "motion.", "colour.", "texture.", "mrf.", "labels.")}),
    _e("vmcl.pipeline:EdgesConfig", sigma=2.0, low_threshold=None, high_threshold=None, use_quantiles=False,
       saliency="none", kinds={"sigma": _N, "low_threshold": _ON, "high_threshold": _ON, "use_quantiles": _B,
                               "saliency": _C}),
    _e("vmcl.pipeline:GroupingConfig", enabled=True, threshold=0.5, length_exponent=0.5, curvature_scale=0.5, gap=6.0,
       alignment=20.0, structural_threshold=5.0, iterations=30, gap_attenuation=0.85,
       kinds={"enabled": _B, "threshold": _N, "length_exponent": _N, "curvature_scale": _N, "gap": _N,
              "alignment": _N, "structural_threshold": _N, "iterations": _I, "gap_attenuation": _N}),
    _e("vmcl.pipeline:StereoConfig", d_min=None, d_max=None, max_disparity=0.05, patch=11, backfill_floor=0.9,
       paths=8, kinds={"d_min": _I, "d_max": _I, "max_disparity": _N, "patch": _I, "backfill_floor": _N, "paths": _I}),
    _e("vmcl.pipeline:MotionConfig", delta=4, patch=11, levels=None, features="brightness", confidence_floor=0.7,
       kinds={"delta": _I, "patch": _I, "levels": _I, "features": _C, "confidence_floor": _N}),
    _e("vmcl.pipeline:TextureConfig", fine_sigma=1.0, coarse_sigma=4.0, threshold=0.08, radius=24, noise_factor=3.5,
       kinds={"fine_sigma": _N, "coarse_sigma": _N, "threshold": _N, "radius": _I, "noise_factor": _N}),
    _e("vmcl.pipeline:MrfConfig", method="meanfield", seed=0, schedule="fast", cross_validate=False,
       kinds={"method": _C, "seed": _I, "schedule": _C, "cross_validate": _B}),
    _e("vmcl.pipeline:LabelsConfig", method="linear", weights=None, kinds={"method": _C, "weights": _P}),
    _e("vmcl.pipeline:TimeConfig", enabled=True, gain=1.0, memory=2.0, tolerance=0.05, scene_cut=0.5, warm=True,
       predict_search=True, kinds={"enabled": _B, "gain": _N, "memory": _N, "tolerance": _N, "scene_cut": _N,
                                   "warm": _B, "predict_search": _B}),
    _e("vmcl.pipeline:VisionMachine", config=None, kinds={"config": _O, "machine": _M}),
    _e("vmcl.pipeline:VisionMachine.run", self=make("vision_machine"), left=IMG, right=None, next=None,
       kinds={"left": _A, "right": _OA, "next": _OA}),
    _e("vmcl.pipeline:VisionMachine.measure", self=make("vision_machine"), left=IMG, right=None, next=None,
       kinds={"left": _A, "right": _OA, "next": _OA}),
    _e("vmcl.machine:kernel_source", family="mrf", kinds={"family": _C}),
    _e("vmcl.machine:Machine", device=None, profile=False, local_size=None,
       kinds={"device": _C, "profile": _B, "local_size": _I}),
    # ------------------------------------------------------------------ distributed (what needs no cluster)
    _e("vmcl.distributed:run_frame", left=IMG, right=None, next=None, config={"motion": {"patch": 11}},
       kinds={"left": _A, "right": _OA, "next": _OA, "config": "mapping"},
       aliases={"config": ("config", "edges.", "stereo.", "motion.", "colour.", "texture.", "mrf.", "labels.")}),
    _e("vmcl.distributed:stitch", chunks=[[tup(0, make("result"))]], kinds={"chunks": _O}),
    _e("vmcl.distributed:batch_items", inputs=[path("png")], frames=False, kinds={"inputs": "names", "frames": _B}),
    _e("vmcl.distributed:local_cluster_size", workers=None, threads=None, kinds={"workers": _I, "threads": _I}),
    _e("vmcl.distributed:MachinePlugin", device=None, kinds={"device": _C}),
    _e("vmcl.distributed:check_zarr", out=make("batch_out"), items=make("batch_items"), fields=["labels"],
       kinds={"out": _P, "items": _O, "fields": "names"}),
    _e("vmcl.distributed:write_zarr", out=make("batch_out"), items=make("batch_items"), field="disparity",
       failed=(), kinds={"out": _P, "items": _O, "field": _C, "failed": "names"}),
)

# Public names that take no input to check: records vmcl returns, enums, plumbing that takes a Machine
# first (imported by other vmcl modules, not meant for users), and calls without arguments.
EXEMPT = {
    "vmcl.early.color:Hue", "vmcl.early.color:AlbedoEdges", "vmcl.early.edges:ZeroCrossings",
    "vmcl.early.motion:FlowResult", "vmcl.early.stereo:StereoMatch", "vmcl.early.texture:TextureEdges",
    "vmcl.early.edges:CannyResult",
    "vmcl.mrf:Restoration", "vmcl.mrf:NothingToRestore", "vmcl.labels:Cue", "vmcl.integrate:Integration", "vmcl.labels:Label",
    "vmcl.scenes:Scene", "vmcl.metrics:BoundaryCounts", "vmcl.metrics:BoundaryScores",
    "vmcl.metrics:DetectionScores", "vmcl.metrics:DisparityScores", "vmcl.metrics:FlowScores",
    "vmcl.datasets:BSDSImage", "vmcl.datasets:BSDSSet", "vmcl.datasets:FlowPair", "vmcl.datasets:StereoPair",
    "vmcl.early.semiglobal:SemiGlobalMatch", "vmcl.early.disparity_range:DisparityRange",
    "vmcl.early.rectification:RowAlignment",
    "vmcl.early.boundary_probability:BoundaryProbability", "vmcl.labelling:Labelling",
    # Checked on construction (tests/test_early_boundary_probability.py); load and save read and write files.
    "vmcl.early.boundary_probability:BoundaryModel", "vmcl.early.boundary_probability:feature_names",
    # Need BSDS images with human boundaries: tests/test_boundary_evaluation.py runs them.
    "vmcl.boundary_evaluation:boundary_maps", "vmcl.boundary_evaluation:score_maps", "vmcl.boundary_evaluation:MapSet",
    "vmcl.stereo_evaluation:MethodScores", "vmcl.stereo_evaluation:MatchedComparison",
    "vmcl.stereo_evaluation:PairEvaluation", "vmcl.stereo_evaluation:StereoMethod",
    "vmcl.result:Result", "vmcl.pipeline:Config", "vmcl.early.registration:WarpTable",
    "vmcl.early.registration:TableStore", "vmcl.pipeline:ColourConfig",
    "vmcl.cm.scan:scan_rows_into", "vmcl.cm.scan:exclusive_sum_into", "vmcl.early.noise:threshold_field",
    "vmcl.labelling:default_labeller", "vmcl.machine:default_machine", "vmcl.machine:list_devices",
    "vmcl.machine:kernels_dir", "vmcl.machine:NoOpenCLPlatformError",
    "vmcl.labels:cue_names", "vmcl.cues:registered", "vmcl.cues:CueModule", "vmcl.cues:Measurement",
    "vmcl.cues:RunInputs",
    # Narrows a result vmcl made on the device for the type checker; a host array there is vmcl's defect.
    "vmcl.machine:on_device",
    # A loop of advance and render (both swept) whose length is its frames argument, so the sweep's valid
    # counts change its result's shape; tests/test_temporal.py checks it.
    "vmcl.scenes:render_sequence",
    # Results and what reads or writes whole sequences: tests/test_flow_evaluation.py, tests/test_cli_sequences.py
    # and tests/test_temporal.py check them; the readers they call (read_flow_folder, open_frames) are swept.
    "vmcl.datasets:FlowSequence", "vmcl.flow_evaluation:FlowRow", "vmcl.flow_evaluation:evaluate_sequence",
    "vmcl.flow_evaluation:baselines", "vmcl.frame_sources:FrameSource", "vmcl.sequence_output:SequenceWriter",
    "vmcl.sequence_output:check_fps",
    # Any folder of images is a valid sequence whose length sets the result's shape; tests/test_cli_sequences.py
    # checks their refusals.
    "vmcl.frame_sources:open_frames", "vmcl.frame_sources:is_sequence",
    # Text helpers of the sequence output, called with the paths and counts the lines above made: the order of
    # frame files (a sort key of any path's text) and "1 frame" / "n frames"; tests/test_cli_sequences.py.
    "vmcl.frame_sources:frame_order", "vmcl.sequence_output:frame_count",
    # Reads the images as_image (swept) has accepted, for a note: tests/test_pipeline.py checks its notes.
    "vmcl.pipeline:range_note",
    # A stream's device state, made and fed only by VisionMachine.stream from checked images and Configs.
    "vmcl.temporal:Memory", "vmcl.temporal:Carried",
    # Change the machine's cues for the whole process, or check a cue's declaration: tests/test_cues.py checks
    # their refusals.
    "vmcl.labels:add_cue", "vmcl.labels:remove_cue", "vmcl.cues:register", "vmcl.cues:unregister",
    "vmcl.cues:refine_stage_of",
    # Device-level building blocks of the early layer: they take images already checked by
    # vmcl.cm.core.image_field, and the sweeps of gaussian, canny and zero_crossings reach them.
    "vmcl.early.filters:separable_gaussian", "vmcl.early.filters:discrete_laplacian", "vmcl.early.filters:grey_field",
    "vmcl.early.filters:channel_planes", "vmcl.early.filters:device_taps",
    # The flow refinements' shared checks: the sweeps of lucas_kanade and variational_refine reach them with
    # every bad flow and frame.
    "vmcl.early.flow_frames:check_flow_frames", "vmcl.early.flow_frames:smoothed_frames",
    # Needs a head that has run a calibration pattern in front of it; table_for_fixation covers the glue.
    "vmcl.eyehead:calibrate_vergences",
    # Need a running Dask cluster: tests/test_distributed.py starts one and checks their refusals.
    "vmcl.distributed:map_frames", "vmcl.distributed:map_sequence", "vmcl.distributed:run_batch",
    "vmcl.distributed:cluster_client",
    # The tasks map_sequence and run_batch submit, with the arguments those calls checked.
    "vmcl.distributed:run_chunk", "vmcl.distributed:render_item",
    # Combines a DisparityRange (estimate_range's, swept) with ends the Config checked; range_to_search and
    # the stereo cue call it, and tests/test_disparity_range.py checks it.
    "vmcl.early.disparity_range:with_given_ends",
    # Lists a batch folder's stores (any folder, or none, is valid); tests/test_distributed.py checks it.
    "vmcl.distributed:vmcl_stores",
    # Records vmcl returns, and the worker's Machine (no arguments).
    "vmcl.distributed:BatchItem", "vmcl.distributed:ItemOutput", "vmcl.distributed:ItemStatus",
    "vmcl.distributed:LocalClusterSize", "vmcl.distributed:worker_machine", "vmcl.distributed:ZarrStore",
    # Records of vmcl.learn, checked when a fit reads them (tests/test_learn_pseudolikelihood.py).
    "vmcl.learn:Example", "vmcl.learn:PseudolikelihoodFit", "vmcl.learn:CrossValidation", "vmcl.learn:NoiseEstimate",
    "vmcl.learn:TemperatureScan", "vmcl.learn:RestorationFit", "vmcl.learn.cue_fit:CueFit", "vmcl.pipeline:CueData",
    # Run the whole machine on rendered scenes (seconds each): tests/test_learn_labelling_fit.py runs them and
    # their refusals.
    "vmcl.learn.labelling_fit:rendered_runs", "vmcl.learn.labelling_fit:fit_labeller",
    # Reads a Result of those runs (refuses anything else by type; tests/test_learn_labelling_fit.py).
    "vmcl.learn.labelling_fit:labelling_fields",
    # Need data set folders with ground truth: tests/test_learn_fit.py runs them and their refusals.
    "vmcl.learn.cue_fit:fit_cue", "vmcl.learn.cue_fit:cue_examples",
    # Hash and write what vmcl itself made (fit_cue's tables, the files it read); tests/test_learn_fit.py.
    "vmcl.fitted:parameters_sha256", "vmcl.fitted:files_sha256", "vmcl.fitted:code_sha256", "vmcl.fitted:write_fitted",
    "vmcl.fitted:fitted_record", "vmcl.fitted:write_fitted_json", "vmcl.fitted:check_fitted_json",
    "vmcl.fitted:with_data", "vmcl.fitted:FittedVersionWarning",
    # Records of vmcl.group and the scenes it is tested on, made by the calls above.
    "vmcl.group:Curve", "vmcl.group:Curves", "vmcl.group:Junctions", "vmcl.group:Grouping",
    "vmcl.group:StructuralSaliency", "vmcl.scenes:ClutterDisplay", "vmcl.scenes:Junction", "vmcl.scenes:OcclusionScene",
    # Records of vmcl.recognize and the scenes it is tested on, made by the calls above.
    "vmcl.recognize:Features", "vmcl.recognize:View", "vmcl.recognize:Model", "vmcl.recognize:Index",
    "vmcl.recognize:Candidates", "vmcl.recognize:Detection", "vmcl.recognize:NearestEdge", "vmcl.recognize:Support",
    "vmcl.recognize:Verified", "vmcl.recognize:Regions", "vmcl.scenes:SceneObject", "vmcl.scenes:Placement",
    "vmcl.scenes:RecognitionScene", "vmcl.pipeline:RecognitionConfig", "vmcl.metrics:RecognitionScores",
}

PUBLIC_MODULES = (
    "vmcl.cm.doubling", "vmcl.cm.filters", "vmcl.cm.news", "vmcl.cm.reduce", "vmcl.cm.router", "vmcl.cm.scan",
    "vmcl.early.color", "vmcl.early.edges", "vmcl.early.filters", "vmcl.early.motion", "vmcl.early.noise",
    "vmcl.early.registration", "vmcl.early.sign_correlation", "vmcl.early.stereo", "vmcl.early.texture",
    "vmcl.early.semiglobal", "vmcl.early.disparity_range", "vmcl.early.boundary_probability",
    "vmcl.early.weighted_median", "vmcl.early.lucas_kanade", "vmcl.early.variational", "vmcl.early.flow_frames",
    "vmcl.early.rectification",
    "vmcl.mrf", "vmcl.integrate", "vmcl.labels", "vmcl.cues", "vmcl.labelling", "vmcl.metrics", "vmcl.scenes", "vmcl.datasets",
    "vmcl.patterns", "vmcl.eyehead", "vmcl.report", "vmcl.pictures", "vmcl.pipeline", "vmcl.result", "vmcl.machine",
    "vmcl.stereo_evaluation", "vmcl.distributed", "vmcl.boundary_evaluation", "vmcl.flow_evaluation",
    "vmcl.frame_sources", "vmcl.sequence_output", "vmcl.temporal", "vmcl.learn", "vmcl.learn.examples",
    "vmcl.learn.cue_fit", "vmcl.learn.labelling_fit", "vmcl.fitted", "vmcl.group", "vmcl.recognize",
)


# --------------------------------------------------------------------------------------------- mutations

_FLOATS = [None, "1.0", [1.0], True, {"float": "nan"}, {"float": "inf"}, {"float": "-inf"}, -1.0, 0.0, 1e30,
           -1e30, 1e-30, 2**64, {"complex": [1.0, 1.0]}, {"np": "float32", "value": "nan"}]
_INTS = [None, "3", [3], True, 2.5, {"float": "nan"}, -1, 0, 1, 2**31, 2**63, -(2**63), 10**30,
         {"np": "int64", "value": 3}, {"np": "float64", "value": 3.0}]
_CHOICES = ["bogus", "", None, 3, ["x"], {"float": "nan"}]
# NumPy's False is a bool (accepted); True would be too, but changes some results' type (canny's gradient).
_BOOLS = [None, "yes", 2, 1.0, {"np": "bool", "value": False}, [True]]
_OPAQUES = [None, 3, "x", [], {"float": "nan"}]
_TUPLES = [None, tup(), tup(1), tup(1, 2, 3, 4, 5), tup("a", "b"), tup({"float": "nan"}, {"float": "nan"}),
           tup({"float": "inf"}, 1.0), tup(-1, -1), tup(0, 0), tup(10**9, 10**9), 3, "ab", [1, 2],
           tup(2.5, 2.5, 2.5), tup(True, False)]
_PATHS = [path("missing"), path("dir"), path("garbage"), path("empty"), None, 3, path("png"), path("flo")]
_MACHINES = ["cpu", 3, {"make": "foreign_device_array"}]
_NAMES = [["bogus"], "stereo", None, [3], [], [None], {"float": "nan"}]
_MAPPINGS = [{"bogus": {}}, {"edges": {"sigma": "x"}}, {"edges": 3}, None, [], {"mrf": {"method": "x"}},
             {"edges": {"bogus": 1}}, {"stereo": {"patch": -1}}, {"mrf": {"stereo": {"alpha": "x"}}}, "edges"]

_DTYPES = ["bool", "int8", "uint8", "int32", "int64", "float16", "float64", "complex64", "object", "<U3"]
_FILLS = ["nan", "inf", "-inf", "huge", "-huge", "tiny", "neg", "zeros", "nanpart"]


def _shape_variants(shape: list[int]) -> list[list[int]]:
    out = [[0] + shape[1:], shape[:1] + [0] + shape[2:], [1, 1] + shape[2:], [1] + shape[1:],
           shape[:1] + [1] + shape[2:], shape[:-1], shape + [2], [2, 2048] + shape[2:], [5] + shape[1:]]
    if len(shape) >= 3:
        out.append(shape[:-1] + [shape[-1] + 1])
    if len(shape) == 1:
        out += [[1], [4096]]
    return [s for s in out if s]


def _mutations(kind: str, base):
    """The bad values of one argument of this kind, as a Hypothesis strategy of (label, spec)."""
    from hypothesis import strategies as st

    def listed(label, values):
        return st.sampled_from(values).map(lambda v: (label, v))

    if kind in ("array", "optional_array"):
        if not (isinstance(base, dict) and "array" in base):
            base = arr((16, 16))
        def variant(k):
            return {**base, **k}
        strategies = [
            st.sampled_from(_shape_variants(base["array"])).map(lambda s: ("shape", variant({"array": s}))),
            st.sampled_from(_DTYPES).map(lambda d: ("dtype", variant({"dtype": d}))),
            st.sampled_from(_FILLS).map(lambda f: ("fill", variant({"fill": f}))),
            st.sampled_from(["F", "strided"]).map(lambda o: ("order", variant({"order": o}))),
            st.just(("device", variant({"device": True}))),
            st.sampled_from([None, "abc", 3.0, {"tolist": base}, tup(1, 2)]).map(lambda v: ("type", v)),
        ]
        return st.one_of(strategies)
    table = {"number": _FLOATS, "optional_number": _FLOATS, "optional_tuple": _TUPLES, "int": _INTS, "choice": _CHOICES, "bool": _BOOLS,
             "opaque": _OPAQUES, "tuple": _TUPLES, "path": _PATHS, "machine": _MACHINES, "names": _NAMES,
             "mapping": _MAPPINGS}
    return listed(kind, table[kind])


def cases(entry: Entry):
    """Strategy: a case of ``entry`` with one argument replaced by a bad value."""
    from hypothesis import strategies as st

    names = sorted(entry.kinds)
    if not names:
        return st.just({"target": entry.target, "call": entry.call, "argument": None, "label": "valid"})

    def one(name):
        return _mutations(entry.kinds[name], entry.call.get(name)).map(
            lambda lv: {"target": entry.target, "call": {**entry.call, name: lv[1]}, "argument": name,
                        "label": lv[0]})
    return st.sampled_from(names).flatmap(one)


# --------------------------------------------------------------------------------------------- the worker


class Worker:
    """The subprocess that runs cases; restarted after a crash or a hang."""

    def __init__(self) -> None:
        self.process = None
        self.log = None

    def start(self) -> None:
        self.log = tempfile.TemporaryFile()  # noqa: SIM115 - closed in stop(), after the worker ends
        env = {**os.environ, "PYTHONFAULTHANDLER": "1"}
        self.process = subprocess.Popen([sys.executable, str(Path(__file__).resolve()), "--worker"], cwd=REPO,
                                        stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=self.log, env=env)

    def stop(self) -> str:
        """Kill the worker; the tail of what it wrote to stderr."""
        if self.process is None:
            return ""
        if self.process.poll() is None:
            self.process.kill()
        self.process.wait()
        self.log.seek(0)
        tail = self.log.read()[-3000:].decode(errors="replace")
        self.log.close()
        self.process = None
        return tail

    def run(self, case: dict, timeout: float = TEST_CASE_TIMEOUT_S) -> dict:
        if self.process is None:
            self.start()
        try:
            self.process.stdin.write((json.dumps(case) + "\n").encode())
            self.process.stdin.flush()
        except BrokenPipeError:
            pass
        ready, _, _ = select.select([self.process.stdout], [], [], timeout)
        line = self.process.stdout.readline() if ready else b""
        if line:
            return json.loads(line)
        hung = not ready
        code = self.process.poll()
        tail = self.stop()
        what = f"hung (no answer in {timeout:.0f} s)" if hung else f"worker died (exit status {code})"
        return {"ok": False, "why": f"{what}; its stderr ends:\n{tail}"}


def _describe(case: dict) -> str:
    value = case["call"].get(case["argument"]) if case["argument"] else None
    return f"{case['target']}({case['argument']}={json.dumps(value)}) [{case['label']}]"


@pytest.fixture(scope="module")
def worker():
    w = Worker()
    yield w
    w.stop()


def _check(worker: Worker, case: dict) -> None:
    answer = worker.run(case)
    assert answer["ok"], f"{_describe(case)}: {answer['why']}"


def _sweep_settings(examples: int):
    from hypothesis import HealthCheck, Phase, settings

    # No shrinking: every case is one subprocess round trip, and the first failing case already says
    # which argument and which kind of bad value.
    return settings(max_examples=examples, derandomize=True, database=None, deadline=None,
                    phases=(Phase.explicit, Phase.generate),
                    suppress_health_check=list(HealthCheck))


def _run_sweep(entry: Entry, examples: int, worker: Worker) -> None:
    from hypothesis import given

    @_sweep_settings(examples)
    @given(case=cases(entry))
    def sweep(case):
        _check(worker, case)

    sweep()


# vmcl.distributed needs the dask extra (pip install 'vmcl[dask]'; the test extra brings it): without it, its
# rows are skipped, not failed.
_WITHOUT_DASK = importlib.util.find_spec("distributed") is None


def _rows(entries: list[Entry]) -> list:
    skip = pytest.mark.skip(reason="vmcl.distributed needs the dask extra: pip install 'vmcl[dask]'")
    return [pytest.param(e, marks=skip) if _WITHOUT_DASK and e.target.startswith("vmcl.distributed:") else e
            for e in entries]


@pytest.mark.parametrize("entry", _rows(TABLE), ids=lambda e: e.target)
def test_valid_call_of_the_table_works(entry, worker):
    """The sweep's reference: the table's own call must succeed, or the sweep measures nothing."""
    _check(worker, {"target": entry.target, "call": entry.call, "argument": None, "label": "valid"})


@pytest.mark.parametrize("entry", _rows(TABLE), ids=lambda e: e.target)
def test_bad_inputs_are_refused_by_name(entry, worker):
    _run_sweep(entry, 12, worker)


def _masked_cases(entry: Entry) -> list[dict]:
    """One case per host array argument of ``entry``: that array masked at its first value."""
    return [{"target": entry.target, "call": {**entry.call, name: {**value, "masked": True}}, "argument": name,
             "label": "masked"}
            for name, value in entry.call.items()
            if entry.kinds.get(name) in ("array", "optional_array") and isinstance(value, dict) and "array" in value
            and not value.get("device") and all(value["array"])]


@pytest.mark.parametrize("entry", _rows([e for e in TABLE if _masked_cases(e)]), ids=lambda e: e.target)
def test_masked_arrays_are_refused_by_name(entry, worker):
    """vmcl reads every value of an array, so a masked array's mask would be lost without a word: refused."""
    for case in _masked_cases(entry):
        _check(worker, case)


@pytest.mark.slow
@pytest.mark.parametrize("entry", _rows(TABLE), ids=lambda e: e.target)
def test_bad_inputs_are_refused_by_name_long(entry, worker):
    _run_sweep(entry, 300, worker)


def test_every_public_callable_is_swept_or_exempt():
    import importlib
    import inspect

    listed = {e.target for e in TABLE}
    covered = listed | {t.rsplit(".", 1)[0] for t in listed if "." in t.split(":")[1]} | EXEMPT
    missing = []
    for module_name in PUBLIC_MODULES:
        if _WITHOUT_DASK and module_name == "vmcl.distributed":
            continue
        module = importlib.import_module(module_name)
        names = getattr(module, "__all__", None) or [n for n in vars(module) if not n.startswith("_")]
        for name in names:
            obj = getattr(module, name)
            if not callable(obj) or not (inspect.isfunction(obj) or inspect.isclass(obj)):
                continue
            home = str(getattr(obj, "__module__", ""))
            if home != module_name and not home.startswith(module_name + "."):
                continue  # imported from elsewhere: swept under its own module (a package's own modules count)
            if f"{module_name}:{name}" not in covered:
                missing.append(f"{module_name}:{name}")
    assert not missing, f"public callables with no row in TABLE and no exemption: {missing}"


# --------------------------------------------------------------------------------------------- worker side


def _build(spec, ctx):
    import numpy as np

    if isinstance(spec, list):
        return [_build(s, ctx) for s in spec]
    if not isinstance(spec, dict):
        return spec
    if "array" in spec:
        return _array(spec, ctx)
    if "tuple" in spec:
        return tuple(_build(s, ctx) for s in spec["tuple"])
    if "float" in spec:
        return float(spec["float"])
    if "complex" in spec:
        return complex(*spec["complex"])
    if "np" in spec:
        value = spec["value"]
        return np.dtype(spec["np"]).type(float(value) if value == "nan" else value)
    if "tolist" in spec:
        value = _array(spec["tolist"], ctx)
        return (value.get() if hasattr(value, "get") else value).tolist()
    if "make" in spec:
        return _MAKERS[spec["make"]](ctx)
    if "path" in spec:
        return _path(spec["path"], ctx)
    return {k: _build(v, ctx) for k, v in spec.items()}


def _array(spec, ctx):
    import numpy as np

    shape, dtype, fill = tuple(spec["array"]), np.dtype(spec.get("dtype", "float32")), spec.get("fill", "rand")
    rng = np.random.default_rng(0)
    count = int(np.prod(shape))
    if fill == "rand":
        values = rng.random(shape)
    elif fill == "bits":
        values = rng.random(shape) < 0.3
    elif fill.startswith("randint:"):
        values = rng.integers(0, int(fill.split(":")[1]), shape)
    elif fill == "zeros":
        values = np.zeros(shape)
    elif fill == "nanpart":
        values = rng.random(shape)
        values.flat[::3] = np.nan
    else:
        scalar = {"nan": np.nan, "inf": np.inf, "-inf": -np.inf, "huge": 1e30, "-huge": -1e30, "tiny": 1e-30,
                  "neg": -0.5}[fill]
        values = np.full(shape, scalar)
    if dtype.kind in "iub" and np.asarray(values).dtype.kind == "f":
        info = np.iinfo(dtype) if dtype.kind in "iu" else None
        finite = np.nan_to_num(values, nan=0, posinf=info.max if info else 1, neginf=info.min if info else 0)
        values = np.clip(finite, info.min, info.max) if info else finite != 0
    with np.errstate(all="ignore"):
        out = np.asarray(values).astype(dtype) if count else np.zeros(shape, dtype)
    order = spec.get("order", "C")
    if order == "F":
        out = np.asfortranarray(out)
    elif order == "strided":
        big = np.repeat(out, 2, axis=-1) if out.ndim else out
        out = big[..., ::2]
    if spec.get("masked"):
        mask = np.zeros(out.shape, bool)
        mask.flat[:1] = True
        return np.ma.masked_array(out, mask=mask)
    if spec.get("device"):
        if out.dtype.kind in "OU":
            return out
        if not out.size:  # Machine.to_device cannot copy an empty array; an empty device array is still one
            return ctx["machine"].empty(out.shape, out.dtype)
        return ctx["machine"].to_device(np.ascontiguousarray(out))
    return out


def _path(kind, ctx):
    import numpy as np

    root = ctx["tmp"]
    if kind == "missing":
        return str(root / "missing" / "nothing.png")
    if kind == "dir":
        return str(root)
    if kind in ("empty_dir", "new_dir"):
        folder = Path(tempfile.mkdtemp(dir=root))
        return str(folder / "out") if kind == "new_dir" else str(folder)
    if kind == "new":
        return str(Path(tempfile.mkdtemp(dir=root)) / "out.bin")
    target = root / f"file.{kind}"
    if kind == "garbage":
        target.write_bytes(b"\x00\xffnot any format\n" * 10)
    elif kind == "empty":
        target.write_bytes(b"")
    elif kind == "png":
        import cv2

        cv2.imwrite(str(target), (np.arange(256, dtype=np.uint8).reshape(16, 16)))
    elif kind == "pfm":
        from vmcl.datasets import write_pfm

        write_pfm(target, np.ones((16, 16), np.float32))
    elif kind == "flo":
        from vmcl.datasets import write_flo

        write_flo(target, np.zeros((16, 16, 2), np.float32))
    elif kind == "store":
        _MAKERS["store"](ctx).save(target.with_suffix(".npz"))
        target = target.with_suffix(".npz")
    elif kind == "stereo_dir":
        return str(_stereo_dir(ctx))
    elif kind in ("vmodel", "library"):
        from vmcl.recognize import save_model

        folder = Path(tempfile.mkdtemp(dir=root))
        written = save_model(_MAKERS["model"](ctx), folder)
        return str(written if kind == "vmodel" else folder)
    elif kind == "flow_dir":
        import cv2

        from vmcl.datasets import write_flo

        folder = Path(tempfile.mkdtemp(dir=root))
        for name in ("frame10.png", "frame11.png"):
            cv2.imwrite(str(folder / name), np.arange(256, dtype=np.uint8).reshape(16, 16))
        write_flo(folder / "flow10.flo", np.zeros((16, 16, 2), np.float32))
        return str(folder)
    return str(target)


def _stereo_dir(ctx) -> Path:
    """A scene folder in the Middlebury 2014 layout. 16 x 32: OpenCV's StereoSGBM needs rows wider than
    calib.txt's 16 disparities plus half its block, which the evaluation's baselines are given."""
    import cv2
    import numpy as np

    from vmcl.datasets import write_pfm

    folder = Path(tempfile.mkdtemp(dir=ctx["tmp"]))
    rng = np.random.default_rng(0)
    for name in ("im0.png", "im1.png"):
        cv2.imwrite(str(folder / name), rng.integers(0, 256, (16, 32), dtype=np.uint8))
    write_pfm(folder / "disp0.pfm", np.ones((16, 32), np.float32))
    (folder / "calib.txt").write_text("ndisp=16\n")
    return folder


def _stereo_pair(ctx):
    from vmcl.datasets import read_stereo_folder

    return read_stereo_folder(_stereo_dir(ctx))


def _stereo_methods(ctx):
    import numpy as np

    from vmcl.stereo_evaluation import StereoMethod, opencv_baselines

    def ones(left, right):
        return np.ones(left.shape[:2], np.float32)

    return [StereoMethod("ones", ones, note="every disparity 1"), *opencv_baselines(_stereo_pair(ctx))]


def _evaluations(ctx):
    from vmcl.stereo_evaluation import evaluate_pair

    return [evaluate_pair(_stereo_pair(ctx), _stereo_methods(ctx), warm=False)]


def _dots(ctx):
    import numpy as np

    image = np.ones((48, 48), np.float32)
    for y in range(6, 48, 12):
        for x in range(6, 48, 12):
            image[y - 1:y + 2, x - 1:x + 2] = 0.0
    return image


def _warp_table(ctx, vergence=0.0):
    import numpy as np

    from vmcl.early.registration import WarpTable

    ys, xs = np.indices((16, 16), dtype=np.float32)
    return WarpTable(np.stack([xs + 0.5, ys], axis=-1), vergence=vergence, dots=4)


def _store(ctx):
    from vmcl.early.registration import TableStore

    store = TableStore()
    store.add(_warp_table(ctx, 0.0))
    store.add(_warp_table(ctx, 1.0))
    return store


def _result(ctx):
    import numpy as np

    from vmcl.pipeline import Config
    from vmcl.result import Result

    rng = np.random.default_rng(0)
    image = rng.random((16, 16, 3)).astype(np.float32)
    return Result(image=image, edges=rng.random((16, 16)) < 0.2, support=rng.integers(0, 32, (16, 16), np.uint8),
                  labels=rng.integers(0, 7, (16, 16), np.uint8), config=Config(),
                  boundary_strength=rng.random((16, 16)).astype(np.float32),
                  disparity=rng.random((16, 16)).astype(np.float32),
                  sparse_disparity=rng.random((16, 16)).astype(np.float32),
                  flow=rng.random((16, 16, 2)).astype(np.float32))


def _world(ctx):
    from vmcl import scenes

    return scenes.preset("cues", shape=(64, 64))


def _head(ctx):
    from hardware.head import Head

    head = Head("sim://")
    return head


def _batch_out(ctx) -> str:
    """A batch's folder holding one finished item, "a" (its fields.npz only), as write_zarr reads it."""
    import numpy as np

    from vmcl.output_folder import output_folder

    out = Path(tempfile.mkdtemp(dir=ctx["tmp"]))
    with output_folder(out / "a") as work:
        np.savez_compressed(work / "fields.npz", disparity=np.ones((16, 16), np.float32))
    return str(out)


def _batch_items(ctx):
    from vmcl.distributed import BatchItem

    return [BatchItem("a", "image", (Path(_path("png", ctx)),))]


def _foreign_device_array(ctx):
    import numpy as np
    import pyopencl as cl
    import pyopencl.array as cl_array

    other = ctx.setdefault("foreign", cl.Context([ctx["machine"].context.devices[0]]))
    queue = cl.CommandQueue(other)
    return cl_array.to_device(queue, np.zeros((16, 16), np.float32))


def _makers():
    import numpy as np

    def faces(ctx):
        from vmcl import scenes

        return scenes.box((0.0, 0.0, 5.0), (1.0, 1.0, 1.0), colour=(0.5, 0.5, 0.5))

    def labeller(ctx):
        from vmcl.labelling import default_labeller

        return default_labeller()

    def vision_machine(ctx):
        from vmcl.pipeline import Config, VisionMachine

        if "vm" not in ctx:
            # An 11-pixel patch: the default 21 would not fit the 16 x 16 images.
            config = Config.from_dict({"mrf": {"schedule": "fast"}, "motion": {"patch": 11}})
            ctx["vm"] = VisionMachine(config, machine=ctx["machine"])
        return ctx["vm"]

    def energy_model(ctx):
        from vmcl.mrf import EnergyModel

        return EnergyModel()

    def settings(ctx):
        from vmcl.mrf import IcmSchedule, Settings

        return Settings(schedules={"icm": IcmSchedule(icm_sweeps=3)})

    def icm_schedule(ctx):
        from vmcl.mrf import IcmSchedule

        return IcmSchedule(icm_sweeps=3)

    def camera(ctx):
        from vmcl.scenes import Camera

        return Camera((64, 64), 64.0, 0.15)

    return {
        "object_image": lambda ctx: __import__("vmcl.scenes", fromlist=["object_view"]).object_view(
            "ell", shape=(48, 48))[0],
        "object_features": lambda ctx: __import__("vmcl.recognize", fromlist=["image_features"]).image_features(
            _MAKERS["object_image"](ctx), machine=ctx["machine"]),
        "model": _model,
        "placement": lambda ctx: __import__("vmcl.scenes", fromlist=["object_view"]).object_view(
            "ell", shape=(48, 48))[1],
        "library": lambda ctx: __import__("vmcl.recognize", fromlist=["Library"]).Library([_model(ctx)]),
        "index": lambda ctx: __import__("vmcl.recognize", fromlist=["Index"]).Index.build(_MAKERS["library"](ctx)),
        "corner_pairs": lambda ctx: np.array([[0, 1], [1, 0], [2, 3], [3, 2], [1, 4]], np.int64),
        "regions": lambda ctx: __import__("vmcl.recognize", fromlist=["select_regions"]).select_regions(
            _array(MASK, ctx), np.ones((16, 16)), min_area=4, machine=ctx["machine"]),
        "nearest": lambda ctx: __import__("vmcl.recognize", fromlist=["distance_transform"]).distance_transform(
            np.eye(16, dtype=bool), machine=ctx["machine"]).nearest,
        "point_ranges": lambda ctx: np.array([[0, 4], [2, 6]], np.int64),
        "transforms": lambda ctx: np.array([[[1.0, 0.0, 2.0], [0.0, 1.0, 1.0]], [[0.9, -0.1, 3.0], [0.1, 0.9, 2.0]]]),
        "chain": lambda ctx: np.append(np.arange(1, 16, dtype=np.int32), np.int32(-1)),
        "curves": _curves,
        "grouping": lambda ctx: __import__("vmcl.group", fromlist=["group"]).group(
            np.eye(16, dtype=bool) | np.eye(16, dtype=bool)[::-1], machine=ctx["machine"]),
        "junctions": lambda ctx: __import__("vmcl.group", fromlist=["find_junctions"]).find_junctions(_curves(ctx)),
        "curve_values": lambda ctx: np.linspace(0.0, 1.0, len(_curves(ctx))),
        "polygons": lambda ctx: [np.array([[4.0, 4.0], [20.0, 4.0], [20.0, 20.0], [4.0, 20.0]]),
                                 np.array([[12.0, 12.0], [28.0, 12.0], [28.0, 28.0], [12.0, 28.0]])],
        "ring": lambda ctx: np.roll(np.arange(16, dtype=np.int32), -1),
        "device_one": lambda ctx: ctx["machine"].to_device(np.ones(1, np.float32)),
        "dots": _dots,
        "dot_coords": lambda ctx: np.array([[2.0, 2.0], [12.0, 3.0], [4.0, 13.0], [13.0, 12.0], [8.0, 8.0]]),
        "warp_table": _warp_table,
        "warp_table_2": lambda ctx: _warp_table(ctx, 2.0),
        "store": _store,
        "prior": lambda ctx: __import__("vmcl.mrf", fromlist=["LinePrior"]).LinePrior(),
        "energy_model": energy_model, "icm_schedule": icm_schedule, "settings": settings,
        "lines": lambda ctx: {"stereo": (_array(LINE_H, ctx), _array(LINE_V, ctx))},
        "weights": lambda ctx: dict(labeller(ctx).weights),
        "labeller": labeller,
        "motion": lambda ctx: __import__("vmcl.scenes", fromlist=["Motion"]).Motion((0.1, 0.0, 0.0)),
        "faces": faces,
        "camera": camera,
        "light": lambda ctx: __import__("vmcl.scenes", fromlist=["Light"]).Light(),
        "bodies": lambda ctx: (__import__("vmcl.scenes", fromlist=["Body"]).Body(faces(ctx)),),
        "world": _world,
        "head": _head,
        "result": _result,
        "vision_machine": vision_machine,
        "example": _example,
        "pseudolikelihood": lambda ctx: __import__("vmcl.learn", fromlist=["Pseudolikelihood"]).Pseudolikelihood(
            [_example(ctx)], machine=ctx["machine"]),
        "theta": lambda ctx: dict.fromkeys(__import__("vmcl.learn", fromlist=["PARAMETERS"]).PARAMETERS, 0.5),
        "foreign_device_array": _foreign_device_array,
        "stereo_pair": _stereo_pair,
        "batch_out": _batch_out,
        "batch_items": _batch_items,
        "stereo_methods": _stereo_methods,
        "evaluations": _evaluations,
        "stereo_sgbm": lambda ctx: __import__("vmcl.stereo_evaluation", fromlist=["stereo_sgbm"]).stereo_sgbm(16),
    }


def _model(ctx):
    from vmcl.recognize import learn

    return learn("ell", [_MAKERS["object_image"](ctx)], machine=ctx["machine"])


def _curves(ctx):
    import numpy as np

    from vmcl.group import link_edges

    drawing = np.zeros((16, 16), bool)
    drawing[8, 1:15] = True
    drawing[2:8, 7] = True
    drawing[12, 2:6] = True
    return link_edges(drawing, machine=ctx["machine"])


def _example(ctx):
    import numpy as np

    from vmcl.learn import Example

    rng = np.random.default_rng(0)
    field = rng.normal(size=(16, 16)).astype(np.float32)
    return Example(field, rng.random((16, 15)) < 0.2, rng.random((15, 16)) < 0.2, data=field + 0.1,
                   edges=rng.random((16, 16)) < 0.3)


_MAKERS: dict = {}


def _resolve(target: str):
    import importlib

    module_name, qualname = target.split(":")
    obj = importlib.import_module(module_name)
    for part in qualname.split("."):
        obj = getattr(obj, part)
    return obj


def _signature(value):
    """What a result must keep when an input changes: containers, types, array dtypes and ndims."""
    import numpy as np
    import pyopencl.array as cl_array

    if isinstance(value, (np.ndarray, cl_array.Array)):
        if value.ndim == 0:
            return "number"
        return ["array", str(value.dtype), value.ndim]
    if isinstance(value, (bool, np.bool_)):
        return "bool"
    if isinstance(value, (int, float, np.number)):
        return "number"
    if isinstance(value, tuple) and hasattr(value, "_fields"):
        return [type(value).__name__, [_signature(v) for v in value]]
    if isinstance(value, tuple):
        return ["tuple", [_signature(v) for v in value]]
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return [type(value).__name__, [_signature(getattr(value, f.name)) for f in dataclasses.fields(value)]]
    if isinstance(value, (list, dict)):
        return type(value).__name__  # lengths and keys follow the input
    return type(value).__name__


# 0/1 maps are bool on the host and uint8 on the device (the package's convention).
_SAME_DTYPE = {"bool": "uint8"}


def _same_kind(got, want, check_ndim: bool, check_dtype: bool = True) -> bool:
    if want == "NoneType":
        return True  # an optional field the valid call left unset: any value set may follow the input
    if isinstance(want, list) and want and want[0] == "array":
        if not (isinstance(got, list) and got[0] == "array"):
            return False
        dtypes = {_SAME_DTYPE.get(d, d) for d in (got[1], want[1])}
        return (len(dtypes) == 1 or not check_dtype) and (not check_ndim or got[2] == want[2])
    if isinstance(want, list) and want[0] == "tuple" and got == "list":
        return True  # a sequence given as a list and kept as one
    if isinstance(want, list):
        return (isinstance(got, list) and got[0] == want[0] and len(got[1]) == len(want[1])
                and all(_same_kind(g, w, check_ndim, check_dtype) for g, w in zip(got[1], want[1])))
    return got == want


def _run_case(case: dict, ctx: dict) -> dict:
    import inspect

    from vmcl.errors import InputError

    target = _resolve(case["target"])
    argument = case["argument"]
    try:
        kwargs = {k: _build(v, ctx) for k, v in case["call"].items()}
        try:
            takes_machine = "machine" in inspect.signature(target).parameters
        except (TypeError, ValueError):  # a built-in without a signature: no machine to give it
            takes_machine = False
        if takes_machine and "machine" not in kwargs and case["target"] != "vmcl.machine:Machine":
            kwargs["machine"] = ctx["machine"]
    except Exception as error:  # noqa: BLE001 - a broken table row, reported as such
        return {"ok": False, "why": f"the sweep could not build the case: {type(error).__name__}: {error}"}
    try:
        value = target(**kwargs)
    except InputError as error:
        if argument is None:
            return {"ok": False, "why": f"the valid call was refused: {error}"}
        entry = next(e for e in TABLE if e.target == case["target"])
        alias = entry.aliases.get(argument, argument)
        words = [argument, *([alias] if isinstance(alias, str) else alias)]
        if entry.kinds.get(argument) == "path" and isinstance(kwargs.get(argument), str):
            words.append(kwargs[argument])  # a bad file is named by its path
        named = any(word in str(error) for word in words)
        return {"ok": named, "why": f"refused without naming {argument!r}: {type(error).__name__}: {error}"}
    except OSError as error:
        # The system's refusal of a path (missing, a folder, not writable) names the path; a loader's
        # missing data set is missing files, whatever argument was varied.
        entry = next(e for e in TABLE if e.target == case["target"])
        path_named = entry.kinds.get(argument) == "path" and str(kwargs.get(argument)) in str(error)
        missing = isinstance(error, FileNotFoundError) and _expect_missing(case["target"])
        return {"ok": path_named or missing, "why": f"{type(error).__name__}: {error}"}
    except BaseException as error:  # noqa: BLE001 - every other exception is the finding
        import traceback

        where = traceback.extract_tb(error.__traceback__)[-1]
        return {"ok": False, "why": f"{type(error).__name__}: {str(error)[:300]} (at {where.filename}:{where.lineno})"}
    if case["label"] == "masked":
        return {"ok": False, "why": "a masked array with a masked value was accepted: its mask was lost"}
    got = _signature(value)
    if argument is None:
        ctx["reference"][case["target"]] = got
        return {"ok": True, "why": ""}
    entry = next(e for e in TABLE if e.target == case["target"])
    if case["call"][argument] is None and entry.kinds[argument].startswith("optional"):
        return {"ok": True, "why": ""}  # None is a valid value of an optional argument
    want = ctx["reference"].get(case["target"])
    if want is None:
        ref = _run_case({**case, "call": next(e.call for e in TABLE if e.target == case["target"]),
                         "argument": None}, ctx)
        if not ref["ok"]:
            return {"ok": False, "why": f"(the valid call fails too) {ref['why']}"}
        want = ctx["reference"][case["target"]]
    # Only an array of the same shape must give results of the same dimensions and dtypes: other values
    # may choose another output (a tiled histogram, chromaticity planes; an int32 field for bool input).
    ok = _same_kind(got, want, check_ndim=case["label"] in ("fill", "order", "device"),
                    check_dtype=case["label"] != "dtype")
    return {"ok": ok, "why": f"accepted, but returned {json.dumps(got)} instead of {json.dumps(want)}"}


def _expect_missing(target: str) -> bool:
    return target.startswith(("vmcl.datasets:load_", "vmcl.datasets:read_bsds_folder"))


def _serve() -> None:
    import warnings

    from vmcl import default_machine

    warnings.simplefilter("ignore")
    _MAKERS.update(_makers())
    with tempfile.TemporaryDirectory() as tmp:
        ctx = {"machine": default_machine(), "tmp": Path(tmp), "reference": {}}
        out = sys.stdout
        sys.stdout = sys.stderr  # anything a case prints must not corrupt the answers
        # VMCL_SWEEP_LOG names a file that receives every case with its outcome (for counting, by hand).
        log = open(os.environ["VMCL_SWEEP_LOG"], "a") if os.environ.get("VMCL_SWEEP_LOG") else None  # noqa: SIM115
        for line in sys.stdin:
            case = json.loads(line)
            answer = _run_case(case, ctx)
            if log is not None:
                log.write(json.dumps({"target": case["target"], "argument": case["argument"],
                                      "label": case["label"], **answer}) + "\n")
                log.flush()
            out.write(json.dumps(answer) + "\n")
            out.flush()


if __name__ == "__main__" and sys.argv[1:] == ["--worker"]:
    sys.path.insert(0, str(REPO / "tests"))
    _serve()
