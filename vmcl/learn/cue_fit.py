"""Fit a cue's MRF to a data set with ground truth: what ``vmcl fit`` runs.

Seed section "Learning and parameter estimation". Every example of the data set (a stereo pair with its
true disparity, a frame pair with its true flow) gives the cue's measurement as the machine makes it
(:meth:`vmcl.pipeline.VisionMachine.measure`) beside the truth (:func:`vmcl.learn.examples.truth_example`);
:func:`vmcl.learn.fit_pseudolikelihood` fits the cue's MRF to all of them at once; the result is the
``[mrf.<cue>]`` table a Config loads, with what it was fitted on (:mod:`vmcl.fitted`).

The fitted file is the whole machine the fit measured with: the measuring Config's settings that differ
from the defaults (its ``[stereo]``, ``[edges]`` ... as given with ``vmcl fit --config``) beside the fitted
table, so that loading it measures as the fit did; its parameters' hash covers them all.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from numbers import Real
from pathlib import Path
from typing import Any

import numpy as np

from vmcl import datasets
from vmcl.cm.core import check_bool, check_choice, check_real
from vmcl.cues import registered
from vmcl.errors import InputError, InputTypeError, InputValueError
from vmcl.fitted import code_sha256, config_sha256, files_sha256, toml_values
from vmcl.labels import CUES
from vmcl.learn import examples as learn_examples
from vmcl.learn import pseudolikelihood, restoration_fit
from vmcl.learn.pseudolikelihood import (
    Example,
    PseudolikelihoodFit,
    check_fixed,
    fit_pseudolikelihood,
    model_overrides,
)
from vmcl.learn.restoration_fit import fit_restoration
from vmcl.machine import Machine

__all__ = ["FITTABLE_CUES", "CueFit", "check_machine", "cue_examples", "fit_cue"]

FITTABLE_CUES = ("stereo", "motion", "colour", "texture")
"""The cues whose ground truth the data set readers give: disparity (stereo), flow (motion), human
segmentations (colour and texture, from BSDS-layout folders)."""


@dataclass(frozen=True)
class CueFit:
    """A cue's fitted MRF.

    Attributes
    ----------
    cue : str
    fit : PseudolikelihoodFit
    tables : dict
        The Config to write with :func:`vmcl.fitted.write_fitted`: ``{"mrf": {cue: {...}}}``, the fitted model
        as a Config's overrides (alpha, beta, edge_gain and the prior's table, beside any other override the
        measuring Config gave the cue), and every other setting of the measuring Config that differs from
        the defaults (its ``[stereo]``, ``[edges]`` ...), so that the file, loaded, measures as the fit did.
    provenance : dict
        The ``[fitted]`` entries: the examples' names, one SHA-256 over their files, the code's hash, the
        measuring Config's hash, the method, the scored sites, the parameters held and those the examples
        carry no information on (``uninformed``: kept at the measuring Config's values).
    left_out : tuple of str
        The folders below the roots that look like examples but lack part of them (their ground truth), so
        were not fitted: one line each, saying why.
    """

    cue: str
    fit: PseudolikelihoodFit
    tables: dict[str, Any]
    provenance: dict[str, Any]
    left_out: tuple[str, ...] = field(default=())


def cue_examples(cue: str, roots: Sequence[str | Path], vm: Any, *,
                 jump: float = learn_examples.DEFAULT_JUMP) -> tuple[list[Example], list[str], list[Path], list[str]]:
    """The examples of every data set folder at or below ``roots`` for ``cue``.

    Parameters
    ----------
    cue : {"stereo", "motion", "colour", "texture"}
    roots : str, Path or a sequence of them
        Folders :func:`vmcl.datasets.find_stereo_folders` (stereo) or :func:`vmcl.datasets.find_flow_folders`
        (motion) searches, or BSDS-layout folders (colour, texture: :func:`vmcl.datasets.read_bsds_folder`,
        its training split in the distribution's layout), whose first annotator's segmentation is the
        desired solution (:func:`vmcl.learn.examples.segmentation_example`). An example found below several
        of them is taken once.
    vm : vmcl.pipeline.VisionMachine
        The machine whose measurements are the data (its Config decides the early modules' settings).
    jump : float
        The truth's discontinuities (:func:`vmcl.learn.examples.jump_lines`).

    Returns
    -------
    (examples, names, files, left_out)
        The examples, their folders' names, the files read (for the data's hash), and the folders below the
        roots that look like examples but lack part of them (their ground truth, a layout's other files:
        :func:`vmcl.datasets.stereo_folders_lacking`, :func:`vmcl.datasets.flow_folders_lacking`; none for
        the BSDS-layout cues), one line each, saying why.

    Raises
    ------
    InputValueError
        A root that is not a folder; no folder with ground truth for the cue below ``roots``; a truth with no
        known value, or a negative disparity.
    InputTypeError
        ``roots`` not paths, ``vm`` not a VisionMachine.
    """
    check_choice(cue, "cue", FITTABLE_CUES)
    roots = _roots(roots)
    check_machine(vm)
    examples, names, files = [], [], []
    lacking = {"stereo": datasets.stereo_folders_lacking, "motion": datasets.flow_folders_lacking}.get(cue)
    passed_over: dict[Path, str] = {}  # by place, as the examples: overlapping roots name a folder once
    # Roots that overlap (a folder and one below it, or one given twice) would count an example twice, and
    # the standard errors would claim that much more certainty.
    seen: set[Path] = set()

    def new(path: str | Path) -> bool:
        place = Path(path).resolve()
        if place in seen:
            return False
        seen.add(place)
        return True

    for root in roots:
        for folder, why in lacking(root) if lacking is not None else ():
            passed_over.setdefault(Path(folder).resolve(), f"left out {folder}: {why}")
        if cue == "stereo":
            for folder in filter(new, datasets.find_stereo_folders(root)):
                pair = datasets.read_stereo_folder(folder)
                mask = pair.masks.get("nonocc", np.isfinite(pair.disparity))
                _check_truth(folder, pair.disparity, mask, "disparity")
                measured = _measured(vm, cue, pair.name, pair.left, pair.right)
                examples.append(learn_examples.truth_example(pair.disparity, measured.data, measured.confidence,
                                                             measured.coupling, valid=mask, jump=jump))
                names.append(pair.name)
                files += sorted(p for p in Path(folder).iterdir() if p.is_file())
        elif cue in ("colour", "texture"):
            model = vm.config.mrf.settings(cue).model
            try:
                images = [item for item in datasets.read_bsds_folder(root, split="train") if new(item.files[0])]
            except FileNotFoundError:
                images = []
            for item in images:
                found = _measured(vm, cue, item.name, item.image)
                examples.append(learn_examples.segmentation_example(found.data, found.confidence, found.coupling,
                                                                    item.segmentations[0], model))
                names.append(item.name)
            # The files the images were read from, links followed as the reading followed them.
            files += [path for item in images for path in item.files]
        else:
            for folder in filter(new, datasets.find_flow_folders(root)):
                sequence = datasets.read_flow_folder(folder)
                _check_truth(folder, sequence.flow, sequence.mask, "flow")
                first = datasets.read_image(sequence.frames[sequence.index])
                second = datasets.read_image(sequence.frames[sequence.index + 1])
                measured = _measured(vm, cue, sequence.name, first, next=second)
                examples.append(learn_examples.truth_example(sequence.flow, measured.data, measured.confidence,
                                                             measured.coupling, valid=sequence.mask, jump=jump))
                names.append(sequence.name)
                files += sorted(p for p in Path(folder).iterdir() if p.is_file())
    if not examples:
        reader = {"stereo": "stereo folders (Middlebury layout)", "motion": "flow folders with ground truth"}.get(
            cue, "BSDS-layout images with segmentations")
        raise InputValueError(f"no {reader} at or below {', '.join(map(str, roots))}: nothing to fit {cue} to"
                              + "".join(f"; {line}" for line in passed_over.values()))
    return examples, names, files, list(passed_over.values())


def _roots(roots: Any) -> list[Path]:
    """``roots`` as folders: one path, or a non-empty sequence of them, each an existing folder."""
    if isinstance(roots, (str, os.PathLike)):
        roots = [roots]
    if not isinstance(roots, Sequence) or not all(isinstance(root, (str, os.PathLike)) for root in roots):
        raise InputTypeError(f"roots must be a folder's path or a sequence of them, got {type(roots).__name__}")
    if not roots:
        raise InputValueError("roots is empty: give one or more folders of examples")
    for root in roots:
        if not Path(root).is_dir():
            raise InputValueError(f"roots: {root} is not a folder")
    return [Path(root) for root in roots]


def check_machine(vm: Any) -> None:
    """Refuse a ``vm`` that is not a :class:`vmcl.pipeline.VisionMachine` (the machine a fit measures with or
    runs), by name."""
    from vmcl.pipeline import VisionMachine

    if not isinstance(vm, VisionMachine):
        raise InputTypeError(f"vm must be a vmcl.pipeline.VisionMachine, got {type(vm).__name__}")


def _check_truth(folder: Path, truth: np.ndarray, mask: np.ndarray | None, what: str) -> None:
    """Refuse, by folder, a ground truth with nothing known (an example of no site), or a negative disparity
    (vmcl's is the left view's, d >= 0, as :func:`vmcl.datasets.write_stereo_folder` holds: a negative one is
    a map of the other view or of the other sign, whose fit would be of nothing the machine measures)."""
    known = np.all(np.isfinite(truth.reshape(*truth.shape[:2], -1)), axis=2)
    if mask is not None:
        known &= np.asarray(mask) != 0
    if not known.any():
        raise InputValueError(f"{folder}: its ground-truth {what} has no known value (NaN, or outside its mask, "
                              "everywhere): nothing to fit to")
    if what == "disparity" and float(truth[known].min()) < 0:
        raise InputValueError(f"{folder}: its ground-truth disparity goes down to {float(truth[known].min()):g}, "
                              "and vmcl's disparity is the left view's, d >= 0 (I_left(x, y) = I_right(x - d, y)): "
                              "a map of the right view, or of the other sign?")


def _measured(vm: Any, cue: str, name: str, left: np.ndarray, right: np.ndarray | None = None,
              next: np.ndarray | None = None) -> Any:
    """``cue``'s measurement of the example ``name`` (:meth:`vmcl.pipeline.VisionMachine.measure`), refused
    by name where the machine does not run the cue on it."""
    measured = vm.measure(left, right, next)
    if cue not in measured:
        grey = "grey, or " if cue == "colour" else ""  # of the fittable cues, colour alone needs RGB
        raise InputValueError(f"{name}: the {cue} cue does not run on this image ({grey}[{cue}] enabled = false)")
    return measured[cue]


def fit_cue(cue: str, roots: Sequence[str | Path], *, vm: Any = None, jump: float = learn_examples.DEFAULT_JUMP,
            fixed: Mapping[str, float] | None = None, fixed_name: str | None = None, ridge: float = 1e-6,
            refine: bool = False, machine: Machine | None = None) -> CueFit:
    """Fit ``cue``'s MRF by maximum pseudolikelihood to every example below ``roots`` (and optionally then
    to its restorations' errors).

    Parameters
    ----------
    cue : {"stereo", "motion", "colour", "texture"}
    roots : str, Path or a sequence of them
        Data set folders (see :func:`cue_examples`).
    vm : vmcl.pipeline.VisionMachine, optional
        Whose measurements are the data; default the default Config's machine on ``machine``.
    jump, ridge
        As :func:`vmcl.learn.examples.jump_lines` and :func:`vmcl.learn.fit_pseudolikelihood` take them.
    fixed : mapping of str to float, optional
        Natural parameters held; default, for the piecewise smooth cues (stereo, motion),
        ``{"coupling": 1.0}``: the membrane's weight at T = 1, the units
        the presets' schedules are measured in. Ground truth is far smoother inside its surfaces than a
        membrane sample (a plane's neighbours predict it exactly), so a free coupling grows without bound
        and takes the data weight to 0; held, the data weight and the line potentials are fitted in the
        energy's own units. ``{}`` fits everything (the default of the piecewise constant cues, whose
        Potts cost kappa is a parameter of the energy at T = 1).
    fixed_name : str, optional
        What the caller calls ``fixed`` (a command's option, e.g. "--fix"): a held value refused then begins
        with it, as ``--fix coupling=0: ``, and a fit refused for want of a held coupling advises
        ``--fix coupling=1``, so that the messages name what the caller's user gives.
    refine : bool
        Then move the fitted parameters to lower the errors of the machine's own restorations of the
        examples (:func:`vmcl.learn.fit_restoration`: pixels more than ``jump`` off, missed and false
        lines; the cue's mean-field schedule). Only for the piecewise smooth cues (stereo, motion), whose
        truth has a scale in pixels.
    machine : vmcl.Machine, optional

    Returns
    -------
    CueFit
        Its parameters the examples carry no information on (``fit.uninformed``) keep the measuring Config's
        values.
    """
    from vmcl.pipeline import VisionMachine

    check_choice(cue, "cue", FITTABLE_CUES)
    check_real(jump, "jump", above=0)
    roots = _roots(roots)
    vm = VisionMachine(machine=machine) if vm is None else vm
    check_machine(vm)
    tables = _settings_tables(vm.config, cue)  # a Config the file cannot hold is refused before the work
    module = next(c for c in registered() if c.name == cue)
    if check_bool(refine, "refine") and module.kind != "smooth":
        raise InputValueError(f"refine: the {cue} cue's truth is a segmentation, with no scale in pixels to count "
                              "a restoration's wrong values by; refine fits the piecewise smooth cues (stereo, motion)")
    fixed = ({"coupling": 1.0} if module.kind == "smooth" else {}) if fixed is None else fixed
    _check_held(fixed, module.kind, fixed_name)  # before the examples are measured, which takes the time
    examples, names, files, left_out = cue_examples(cue, roots, vm, jump=jump)
    base = vm.config.mrf.settings(cue, module.settings).model
    fit = fit_pseudolikelihood(examples, kind=module.kind, fixed=fixed, ridge=ridge,
                               edge_radius=base.edge_radius if module.candidates_only else None,
                               machine=vm.machine)
    # The advice of a refused fit names how this caller holds the coupling.
    model = fit.model(base, **({} if fixed_name is None else {"held_coupling": f"{fixed_name} coupling=1"}))
    error = None
    if refine:
        settings = vm.config.mrf.settings(cue, module.settings)
        start = settings.override(model_overrides(model))
        refined = fit_restoration(examples, start, kind=module.kind, candidates_only=module.candidates_only,
                                  tolerance=jump, machine=vm.machine)
        model, error = refined.settings.model, (refined.start_error, refined.error, refined.evaluations,
                                                refined.converged)
    tables["mrf"][cue].update(model_overrides(model, kappa=module.kind == "constant"))
    provenance: dict[str, Any] = {
        "what": f"mrf.{cue}",
        "method": "maximum pseudolikelihood (vmcl.learn.fit_pseudolikelihood)" + (
            ", then the restorations' error (vmcl.learn.fit_restoration)" if refine else ""),
        "data": names,
        "data_sha256": files_sha256(files),
        "code_sha256": code_sha256(pseudolikelihood, learn_examples, _kernel_path(),
                                   *((restoration_fit,) if refine else ())),
        "jump": float(jump) if module.kind == "smooth" else "segment boundaries (first annotator)",
        "ridge": float(ridge),
        "fixed": sorted(fixed),
        "uninformed": list(fit.uninformed),
        "config_sha256": config_sha256(vm.config.to_dict()),
        "sites": [fit.sites["pixels"], fit.sites["lines"]],
        "temperature": fit.temperature,
        "converged": fit.converged,
    }
    if error is not None:
        provenance["restoration_error"] = [float(error[0]), float(error[1])]
        provenance["restoration_settings_scored"] = int(error[2])
        provenance["restoration_converged"] = bool(error[3])
    return CueFit(cue, fit, tables, provenance, tuple(left_out))


def _check_held(fixed: Any, kind: str, fixed_name: str | None) -> None:
    """:func:`vmcl.learn.pseudolikelihood.check_fixed` of ``fixed``; with ``fixed_name``, a refused held value
    is said as the caller's user gave it (``--fix coupling=0: ...``), checked one at a time to know which."""
    if fixed_name is not None and not isinstance(fixed_name, str):
        raise InputTypeError(f"fixed_name must be a str or None, got {type(fixed_name).__name__}")
    if fixed_name is not None and isinstance(fixed, Mapping):
        for name, value in fixed.items():
            try:
                check_fixed({name: value}, kind=kind)
            except InputError as error:
                given = f"{value:g}" if isinstance(value, Real) else repr(value)
                raise type(error)(f"{fixed_name} {name}={given}: {error}") from None
    check_fixed(fixed, kind=kind)


def _settings_tables(config: Any, cue: str) -> dict[str, Any]:
    """The tables of a fitted file before the fit: every setting of ``config`` (a :class:`vmcl.pipeline.Config`)
    that differs from the defaults, as plain TOML values, with its ``[mrf.<cue>]`` table (empty where the
    Config overrides nothing) for the fitted values to update.

    A fitted file is loaded as the whole Config: without the measuring settings it would pair the fitted
    MRF with the default early modules, whose measurements are not those it was fitted to.

    Raises
    ------
    InputValueError
        A setting TOML cannot hold (None where the default is not, a float that is not finite).
    """
    from vmcl.pipeline import Config

    if not isinstance(config, Config):
        raise InputTypeError(f"config must be a vmcl.pipeline.Config, got {type(config).__name__}")
    check_choice(cue, "cue", FITTABLE_CUES)
    default, given = Config().to_dict(), config.to_dict()
    tables: dict[str, Any] = {}
    for name, section in given.items():
        changed = {key: value for key, value in section.items()
                   if not (name == "mrf" and key in CUES) and value != default[name][key]}
        if name == "mrf":
            changed.update({other: section[other] for other in CUES if section[other] or other == cue})
        if changed:
            tables[name] = changed
    try:
        return toml_values(tables)
    except InputValueError as error:
        raise InputValueError(f"config: {error}, so the fitted file could not give the machine it measured with; "
                              "leave it at its default") from None


def _kernel_path() -> Path:
    from vmcl.machine import kernels_dir

    return kernels_dir() / "pseudolikelihood.cl"

