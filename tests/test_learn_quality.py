"""Learned parameters against the hand-set ones on scenes the fit never saw: the stereo MRF fitted by
`vmcl fit`'s method (maximum pseudolikelihood on the truth, coupling held at 1) on three vmcl.scenes
presets, then the restored disparity's bad-1 rate and the depth discontinuities' F on the two others."""

import numpy as np
import pytest

from vmcl import metrics, mrf, scenes
from vmcl.cues.stereo import StereoCue
from vmcl.integrate import restore_cue
from vmcl.labels import Label
from vmcl.learn import fit_pseudolikelihood
from vmcl.learn.examples import truth_example
from vmcl.pipeline import Config, VisionMachine

ONLY_STEREO = {"motion": {"enabled": False}, "colour": {"enabled": False}, "texture": {"enabled": False}}


def _measured(vm, names):
    found = []
    for name in names:
        for seed in (0, 1):
            scene = scenes.render(scenes.preset(name, shape=(256, 256)), seed=seed, noise=0.01)
            found.append((scene, vm.measure(scene.left, scene.right)["stereo"]))
    return found


def _scores(pairs, settings, machine):
    bad, found = [], []
    for scene, measured in pairs:
        restored = restore_cue(measured.data, confidence=measured.confidence, coupling=measured.coupling,
                               kind="smooth", candidates_only=False, settings=settings, method="meanfield",
                               machine=machine)
        bad.append(metrics.evaluate_disparity(restored.field, scene.disparity, mask=~scene.occluded_stereo).bad[1.0])
        lines = mrf.boundary_map(restored.line_h, restored.line_v)
        found.append(metrics.detection_scores(lines, scene.labels == Label.DEPTH, tolerance=1.0).f)
    return float(np.mean(bad)), float(np.mean(found))


@pytest.mark.xfail(strict=True, reason=(
    "benchmarks/results/learn.md, left-out presets: bad-1 0.77% learned against 0.69% hand-set, depth "
    "discontinuity F 0.188 against 0.548; on seeds no fit has read (5, 6) 0.91% / 0.193 against 0.83% / 0.515, "
    "so the hand-set weights' lead is not their having been chosen on these renderings. Fitted on ground truth, "
    "the line prior makes ends dear and continuations cheap (the truth's lines are whole contours) and the data "
    "weight lower; the truth is no sample of the membrane. Fitting the restorations' own error on the training "
    "presets (vmcl.learn.fit_restoration) does not close it (0.89% / 0.184 on seeds 5, 6): on corridor and "
    "shadows every setting finds the depth lines at F 0.1-0.2 and textures has none, so those presets cannot "
    "teach the lines blocks and cues show"))
def test_learned_stereo_mrf_generalises_to_left_out_presets(machine):
    vm = VisionMachine(Config.from_dict(ONLY_STEREO), machine=machine)
    train = _measured(vm, ("corridor", "shadows", "textures"))
    test = _measured(vm, ("blocks", "cues"))
    examples = [truth_example(np.where(scene.occluded_stereo, np.nan, scene.disparity), m.data, m.confidence,
                              m.coupling) for scene, m in train]
    model = fit_pseudolikelihood(examples, fixed={"coupling": 1.0}, machine=machine).model()
    hand = Config().mrf.settings("stereo", StereoCue.settings)
    learned = hand.override({"alpha": model.alpha, "beta": model.beta, "edge_gain": model.edge_gain,
                             "prior": model.prior})
    hand_bad, hand_f = _scores(test, hand, machine)
    learned_bad, learned_f = _scores(test, learned, machine)
    assert learned_bad <= hand_bad and learned_f >= hand_f
