"""The cue registry: a new cue is one module and a register() call, and it flows through the whole run."""

import numpy as np
import pytest

from vmcl import cues, scenes
from vmcl.cues import CueModule, Measurement
from vmcl.labels import CUES, Cue, Label, cue_bit, cue_names
from vmcl.mrf import EnergyModel, Settings, boundary_map
from vmcl.pictures import field_image
from vmcl.pipeline import Config, VisionMachine
from vmcl.report import write_report
from vmcl.result import Result


class BrightnessCue(CueModule):
    """A toy cue: the grey level itself, restored piecewise constant (8 levels) with its own settings."""

    name = "brightness_level"
    kind = "constant"
    label = Label.SHADOW
    settings = Settings(EnergyModel(alpha=200.0, beta=1.5, kappa=4.0, levels=8))

    def measure(self, run):
        return Measurement(run.left, None, run.brightness)

    def pictures(self, result):
        return {"brightness_level": (field_image(result.restored["brightness_level"]), "The toy cue")}


@pytest.fixture
def toy_cue():
    cue = BrightnessCue()
    cues.register(cue)
    try:
        yield cue
    finally:
        cues.unregister(cue.name)


def test_the_built_in_cues_are_registered_in_bit_order():
    assert tuple(cue.name for cue in cues.registered()) == CUES == cue_names()
    assert [cue_bit(name) for name in CUES] == [Cue.STEREO, Cue.MOTION, Cue.COLOUR, Cue.TEXTURE]


def test_a_registered_cue_flows_through_the_run_and_the_report(toy_cue, machine, tmp_path):
    scene = scenes.render(scenes.preset("blocks", shape=(64, 64)), seed=0, noise=0.01)
    grey = scene.left.mean(axis=2).astype(np.float32)
    config = Config.from_dict({"mrf": {"method": "icm"}, "labels": {"method": "rule"}})
    result = VisionMachine(config, machine=machine).run(grey)
    assert "brightness_level" in result.stages and "mrf brightness_level" in result.stages
    restored, lines = result.restored["brightness_level"], result.lines["brightness_level"]
    assert restored.shape == grey.shape and np.isfinite(restored).all()
    # A piecewise constant restoration of the image: close to it away from its edges.
    assert np.median(np.abs(restored - grey)) < 0.05
    marked = boundary_map(*lines)
    assert marked.any()
    bit = cue_bit("brightness_level")
    assert bit == 32
    np.testing.assert_array_equal((result.support & bit) != 0, marked)
    # Its lines are labelled by its rule (texture's lines, where both mark a pixel, come first).
    only_toy = marked & ((result.support & int(Cue.TEXTURE)) == 0)
    assert only_toy.any() and (result.labels[only_toy] == Label.SHADOW).all()
    written = write_report(result, tmp_path / "report")
    assert (tmp_path / "report" / "brightness_level.png").is_file() and "brightness_level" in written
    assert "The toy cue" in written["report"].read_text(encoding="utf-8")


def test_cues_are_refused_with_declarations_the_run_cannot_honour(toy_cue):
    with pytest.raises(ValueError, match="already registered"):
        cues.register(BrightnessCue())
    bad_needs = type("NeedsDepthCamera", (BrightnessCue,), {"name": "depth_camera", "needs": frozenset({"tof"})})
    with pytest.raises(ValueError, match="needs"):
        cues.register(bad_needs())
    bad_field = type("NoSuchField", (BrightnessCue,), {"name": "no_field", "fields": ("nonexistent",)})
    with pytest.raises(ValueError, match="Result does not have"):
        cues.register(bad_field())
    with pytest.raises(TypeError, match="CueModule"):
        cues.register("stereo")
    with pytest.raises(ValueError, match="built-in"):
        cues.unregister("stereo")


def test_every_built_in_cue_declares_fields_the_result_has():
    known = {f for f in Result.__dataclass_fields__}
    for cue in cues.registered():
        assert set(cue.fields) <= known and (cue.restored_as is None or cue.restored_as in known)


def test_a_cue_cannot_take_the_name_of_a_stage_or_a_config_section():
    for name in ("edges", "upload", "mrf", "labels"):
        misnamed = type("Misnamed", (BrightnessCue,), {"name": name})
        with pytest.raises(ValueError, match="cannot be named"):
            cues.register(misnamed())
