"""Fit a cue's MRF to a data set with ground truth: what ``vmcl fit`` runs.

Seed section "Learning and parameter estimation". Every example of the data set (a stereo pair with its
true disparity, a frame pair with its true flow) gives the cue's measurement as the machine makes it
(:meth:`vmcl.pipeline.VisionMachine.measure`) beside the truth (:func:`vmcl.learn.examples.truth_example`);
:func:`vmcl.learn.fit_pseudolikelihood` fits the cue's MRF to all of them at once; the result is the
``[mrf.<cue>]`` table a Config loads, with what it was fitted on (:mod:`vmcl.fitted`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from vmcl import datasets
from vmcl.cm.core import check_bool, check_choice, check_real
from vmcl.cues import registered
from vmcl.errors import InputValueError
from vmcl.fitted import code_sha256, files_sha256
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

__all__ = ["FITTABLE_CUES", "CueFit", "cue_examples", "fit_cue"]

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
        ``{"mrf": {cue: {...}}}``: the fitted model as a Config's overrides (alpha, beta, edge_gain and the
        prior's table), to write with :func:`vmcl.fitted.write_fitted`.
    provenance : dict
        The ``[fitted]`` entries: the examples' names, one SHA-256 over their files, the code's hash, the
        method, the scored sites and the fitted natural parameters.
    """

    cue: str
    fit: PseudolikelihoodFit
    tables: dict[str, Any]
    provenance: dict[str, Any]


def cue_examples(cue: str, roots: Sequence[str | Path], vm: Any, *,
                 jump: float = learn_examples.DEFAULT_JUMP) -> tuple[list[Example], list[str], list[Path]]:
    """The examples of every data set folder at or below ``roots`` for ``cue``.

    Parameters
    ----------
    cue : {"stereo", "motion", "colour", "texture"}
    roots : sequence of str or Path
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
    (examples, names, files)
        The examples, their folders' names, and the files read (for the data's hash).

    Raises
    ------
    InputValueError
        No folder with ground truth for the cue below ``roots``.
    """
    check_choice(cue, "cue", FITTABLE_CUES)
    examples, names, files = [], [], []
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
        if cue == "stereo":
            for folder in filter(new, datasets.find_stereo_folders(root)):
                pair = datasets.read_stereo_folder(folder)
                mask = pair.masks.get("nonocc", np.isfinite(pair.disparity))
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
        raise InputValueError(f"no {reader} at or below {', '.join(map(str, roots))}: nothing to fit {cue} to")
    return examples, names, files


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
            fixed: Mapping[str, float] | None = None, ridge: float = 1e-6, refine: bool = False,
            machine: Machine | None = None) -> CueFit:
    """Fit ``cue``'s MRF by maximum pseudolikelihood to every example below ``roots`` (and optionally then
    to its restorations' errors).

    Parameters
    ----------
    cue : {"stereo", "motion", "colour", "texture"}
    roots : sequence of str or Path
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
    refine : bool
        Then move the fitted parameters to lower the errors of the machine's own restorations of the
        examples (:func:`vmcl.learn.fit_restoration`: pixels more than ``jump`` off, missed and false
        lines; the cue's mean-field schedule). Only for the piecewise smooth cues (stereo, motion), whose
        truth has a scale in pixels.
    machine : vmcl.Machine, optional

    Returns
    -------
    CueFit
    """
    from vmcl.pipeline import VisionMachine

    check_choice(cue, "cue", FITTABLE_CUES)
    check_real(jump, "jump", above=0)
    vm = VisionMachine(machine=machine) if vm is None else vm
    module = next(c for c in registered() if c.name == cue)
    if check_bool(refine, "refine") and module.kind != "smooth":
        raise InputValueError(f"refine: the {cue} cue's truth is a segmentation, with no scale in pixels to count "
                              "a restoration's wrong values by; refine fits the piecewise smooth cues (stereo, motion)")
    fixed = ({"coupling": 1.0} if module.kind == "smooth" else {}) if fixed is None else fixed
    check_fixed(fixed, kind=module.kind)  # before the examples are measured, which takes the time
    examples, names, files = cue_examples(cue, roots, vm, jump=jump)
    base = vm.config.mrf.settings(cue, module.settings).model
    fit = fit_pseudolikelihood(examples, kind=module.kind, fixed=fixed, ridge=ridge,
                               edge_radius=base.edge_radius if module.candidates_only else None,
                               machine=vm.machine)
    model = fit.model(base)
    error = None
    if refine:
        settings = vm.config.mrf.settings(cue, module.settings)
        start = settings.override(model_overrides(model))
        refined = fit_restoration(examples, start, kind=module.kind, candidates_only=module.candidates_only,
                                  tolerance=jump, machine=vm.machine)
        model, error = refined.settings.model, (refined.start_error, refined.error, refined.evaluations,
                                                refined.converged)
    table = model_overrides(model, kappa=module.kind == "constant")
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
        "sites": [fit.sites["pixels"], fit.sites["lines"]],
        "temperature": fit.temperature,
        "converged": fit.converged,
    }
    if error is not None:
        provenance["restoration_error"] = [float(error[0]), float(error[1])]
        provenance["restoration_settings_scored"] = int(error[2])
        provenance["restoration_converged"] = bool(error[3])
    return CueFit(cue, fit, {"mrf": {cue: table}}, provenance)


def _kernel_path() -> Path:
    from vmcl.machine import kernels_dir

    return kernels_dir() / "pseudolikelihood.cl"

