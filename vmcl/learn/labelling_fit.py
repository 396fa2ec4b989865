"""Fit the integration stage's linear classifier to rendered scenes: what ``vmcl fit labelling`` runs.

Seed section "Integration via labeling with a linear classifier": the network's weights are learned from
examples whose labels are known. :mod:`vmcl.scenes` renders each preset with its exact discontinuities
and their physical causes; the machine runs on every rendering with the rule labels (so its inputs do not
depend on earlier weights), and :meth:`vmcl.labelling.LinearLabeller.fit` fits one weight matrix per set
of inputs to the candidates' features against the scene's labels, within each pixel's tolerance
(:attr:`vmcl.scenes.Scene.tolerance`). The shipped weights (``vmcl/labelling.json``) are this fit at its
defaults (benchmarks/labelling.py writes them and measures them on seeds and presets they never saw).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from vmcl import labelling, scenes
from vmcl.cm.core import check_int, check_real
from vmcl.errors import InputTypeError, InputValueError
from vmcl.fitted import code_sha256
from vmcl.learn.cue_fit import check_machine

__all__ = ["DEFAULT_SEEDS", "DEFAULT_SHAPE", "RenderedRun", "fit_labeller", "labeller_provenance", "labelling_fields",
           "rendered_runs"]

DEFAULT_SEEDS = (0, 1)
"""The noise seeds of the shipped fit (a seed changes the textures' random elements and the noise)."""
DEFAULT_SHAPE = (256, 256)

RenderedRun = tuple[Any, np.ndarray, np.ndarray]
"""(the machine's Result with the rule labels, the scene's true labels, their per-pixel tolerance)."""


def rendered_runs(vm: Any, *, presets: Sequence[str] = scenes.PRESETS, seeds: Sequence[int] = DEFAULT_SEEDS,
                  shape: tuple[int, int] = DEFAULT_SHAPE,
                  noise: float = 0.01) -> dict[tuple[str, bool, int], RenderedRun]:
    """The machine's runs on every preset, with and without highlights, for every seed.

    Parameters
    ----------
    vm : vmcl.pipeline.VisionMachine
        Its Config's ``labels.method`` must be "rule": the classifier's inputs must not depend on weights.
    presets : sequence of str
        Names of :data:`vmcl.scenes.PRESETS`.
    seeds : sequence of int
    shape : (int, int)
        Each rendering's size, at least 64 x 64.
    noise : float
        The renderings' noise.

    Returns
    -------
    dict
        (preset, specular, seed) -> :data:`RenderedRun`.
    """
    check_machine(vm)
    if vm.config.labels.method != "rule":
        raise InputValueError("vm must label by rule (labels.method = \"rule\"): the classifier is fitted to "
                              "the candidates, not to an earlier classifier's labels")
    presets, seeds, (height, width) = _names(presets), _seeds(seeds), _shape(shape)
    check_real(noise, "noise", minimum=0)
    found = {}
    for name in presets:
        for specular in (False, True):
            world = scenes.preset(name, shape=(height, width), specular=specular)
            for seed in seeds:
                scene = scenes.render(world, seed=seed, noise=noise)
                found[name, specular, seed] = (vm.run(scene.left, scene.right, scene.left_next), scene.labels,
                                               scene.tolerance)
    return found


def fit_labeller(runs: Iterable[RenderedRun], *, fitted_on: str = "",
                 input_sets: Iterable[Iterable[str]] | None = None, machine: Any = None) -> labelling.LinearLabeller:
    """The linear classifier fitted to ``runs`` (:meth:`vmcl.labelling.LinearLabeller.fit`): each run's
    candidates' features (:func:`vmcl.labelling.features`, from the run's fields) against its labels.

    Parameters
    ----------
    runs : iterable of RenderedRun
    fitted_on : str
        What the weights will say they were fitted to.
    input_sets : iterable of iterables of str, optional
        The sets of inputs to fit weights for (default every one).
    machine : vmcl.Machine, optional
    """
    from vmcl.result import Result

    if not isinstance(fitted_on, str):
        raise InputTypeError(f"fitted_on must be a str, got {type(fitted_on).__name__}")
    try:
        items = list(runs)
    except TypeError:
        raise InputTypeError(f"runs must be an iterable of (Result, labels, tolerance), got {type(runs).__name__}"
                             ) from None
    if not items:
        raise InputValueError("runs is empty: nothing to fit the labeller to")
    for k, item in enumerate(items):
        if not (isinstance(item, tuple) and len(item) == 3 and isinstance(item[0], Result)):
            raise InputTypeError(f"runs[{k}] must be a (vmcl.Result, labels, tolerance) tuple, got "
                                 f"{type(item).__name__}")

    def samples():
        for result, truth, tolerance in items:
            yield (labelling.features(result.support, result.image, machine=machine, **labelling_fields(result)),
                   result.support, truth, tolerance)

    return labelling.LinearLabeller.fit(samples(), fitted_on=fitted_on, input_sets=input_sets)


def labelling_fields(result: Any) -> dict[str, Any]:
    """The restored fields of a run that :func:`vmcl.labelling.features` reads beside its candidates."""
    from vmcl.result import Result

    if not isinstance(result, Result):
        raise InputTypeError(f"result must be a vmcl.Result, got {type(result).__name__}")
    return {"disparity": result.disparity, "flow": result.flow, "hue": result.restored.get("colour")}


def labeller_provenance(*, presets: Sequence[str] = scenes.PRESETS, seeds: Sequence[int] = DEFAULT_SEEDS,
                        shape: tuple[int, int] = DEFAULT_SHAPE, noise: float = 0.01,
                        config: Any = None) -> tuple[str, dict[str, Any]]:
    """What a labeller fitted by :func:`rendered_runs` and :func:`fit_labeller` was fitted on: the text of
    its ``fitted_on`` and its ``"fitted"`` record's entries: the renderer's code (the examples' data), the
    fitting code, and the Config of the machine whose candidates and fields were fitted (default the
    default Config), each hashed; the rest of the machine is the record's vmcl version."""
    from vmcl.fitted import config_sha256
    from vmcl.pipeline import Config

    config = Config() if config is None else config
    if not isinstance(config, Config):
        raise InputTypeError(f"config must be a vmcl.pipeline.Config or None, got {type(config).__name__}")
    height, width = _shape(shape)
    check_real(noise, "noise", minimum=0)
    fitted_on = (f"vmcl.scenes presets {', '.join(_names(presets))} at {height} x {width}, with and without "
                 f"highlights, noise {noise:g}, seeds {tuple(_seeds(seeds))}")
    renderer = sorted(Path(scenes.__file__).parent.glob("*.py"))
    # The labels are fitted with the rule labelling whatever the Config says: the method is not hashed.
    settings = {name: {k: v for k, v in section.items() if (name, k) != ("labels", "method")}
                for name, section in config.to_dict().items()}
    return fitted_on, {"data_sha256": code_sha256(*renderer), "code": "vmcl.learn.labelling_fit",
                       "code_sha256": code_sha256(Path(__file__), labelling),
                       "config_sha256": config_sha256(settings)}


def _sequence(values: Any, name: str) -> list:
    if isinstance(values, (str, bytes)) or not isinstance(values, Sequence):
        raise InputTypeError(f"{name} must be a sequence, got {type(values).__name__}")
    if not values:
        raise InputValueError(f"{name} is empty")
    return list(values)


def _seeds(seeds: Any) -> list[int]:
    return [check_int(seed, "seeds", minimum=0) for seed in _sequence(seeds, "seeds")]


def _shape(shape: Any) -> tuple[int, int]:
    if not isinstance(shape, tuple) or len(shape) != 2:
        raise InputTypeError(f"shape must be a (height, width) tuple, got {shape!r}")
    height, width = (check_int(n, "shape", minimum=64) for n in shape)
    return height, width


def _names(presets: Any) -> list[str]:
    names = _sequence(presets, "presets")
    for name in names:
        if name not in scenes.PRESETS:
            raise InputValueError(f"presets: {name!r} is not a vmcl.scenes preset; they are "
                                  f"{', '.join(scenes.PRESETS)}")
    return names
