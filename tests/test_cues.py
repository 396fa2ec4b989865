"""The cue registry: a new cue is one module and a register() call, and it flows through the whole run."""

import numpy as np
import pytest

from vmcl import cues, scenes
from vmcl.cues import CueModule, Measurement
from vmcl.errors import InputError
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


def _cue(name, **declared):
    """A BrightnessCue of another name, with some declarations changed."""
    return type("Declared", (BrightnessCue,), {"name": name, **declared})()


@pytest.mark.parametrize("declared, match", [
    ({"restored_as": "labels"}, "'labels', which the machine fills itself"),
    ({"fields": ("notes",)}, "'notes', which the machine fills itself"),
    ({"fields": ("stages", "density")}, "'stages', which the machine fills itself"),
    ({"restored_as": "hue"}, "'hue', which the 'colour' cue fills"),
    ({"restored_as": "disparity"}, "'disparity', which the 'stereo' cue fills"),
    ({"fields": ("raw_flow",)}, "'raw_flow', which the 'motion' cue fills"),
    ({"fields": ("flow",), "restored_as": "flow"}, "'flow', which the 'motion' cue fills"),
])
def test_a_cue_cannot_fill_what_the_machine_or_another_cue_fills(declared, match):
    # The machine's own attributes crashed the run with a bare TypeError (Result given them twice); another
    # cue's were overwritten in silence.
    with pytest.raises(ValueError, match=f"cue 'filler' declares the Result attribute {match}"):
        cues.register(_cue("filler", **declared))
    assert "filler" not in cue_names()


def test_a_cue_cannot_fill_what_a_cue_registered_before_it_fills(toy_cue):
    class Hue(BrightnessCue):
        name = "grey_hue"
        restored_as = None
        fields = ("first_pass_disparity",)

    with pytest.raises(ValueError, match="'first_pass_disparity', which the 'stereo' cue fills"):
        cues.register(Hue())


def test_every_result_attribute_is_the_machines_or_one_built_in_cues():
    owners = [name for cue in cues.registered() for name in (*cue.fields, cue.restored_as) if name]
    assert len(owners) == len(set(owners)) and not set(owners) & cues.MACHINE_FIELDS
    assert set(owners) | cues.MACHINE_FIELDS == set(Result.__dataclass_fields__)


@pytest.mark.parametrize("name", ["time", "grouping", "boundaries", "recognition", "to_dict", "from_dict",
                                  "from_toml", "edges", "mrf", "labels"])
def test_a_cue_cannot_take_the_name_of_any_config_attribute_or_stage(name):
    # "recognition" crashed the run (its section has no enabled), "grouping" followed that section's switch,
    # "boundaries" shared that stage's timing.
    with pytest.raises(ValueError, match=f"a cue cannot be named '{name}'"):
        cues.register(_cue(name))


def test_every_stage_name_of_the_run_is_reserved():
    config = Config.from_dict({"stereo": {"feature_matches": True}, "edges": {"saliency": "local"}})
    vm = VisionMachine(config)
    vm.library = object()  # stands for a model library: stages() only asks whether there is one
    stages = vm.stages(right=True, next=True, rgb=True, streaming=True)
    own = {stage for stage in stages if stage not in CUES and not stage.startswith("mrf ")}
    assert {"time", "grouping", "boundaries", "feedback", "recognition"} <= own <= cues.RESERVED


def test_a_refinement_stage_cannot_take_another_stages_name():
    for stage in ("integrate", "colour", "mrf stereo", "refined_cue", "to_dict"):
        refining = _cue("refined_cue", refine_stage=lambda self, config, stage=stage: stage)
        with pytest.raises(ValueError, match=f"refine_stage\\(\\) is '{stage}', the name of another stage"):
            cues.register(refining)
    with pytest.raises(TypeError, match="refine_stage\\(\\) must return a stage name"):
        cues.register(_cue("refined_cue", refine_stage=lambda self, config: 1))
    assert "refined_cue" not in cue_names()


def test_a_refinement_stage_named_as_another_under_a_config_is_refused_by_the_machine():
    # Registration asks the default Config only: under this one the cue's refinement would share the
    # stereo cue's feedback stage, its timing and its progress.
    def stage(self, config):
        return "feedback" if config.stereo.feature_matches else None

    cues.register(_cue("refined_cue", refine_stage=stage))
    try:
        VisionMachine(Config())  # no feedback stage: accepted
        with pytest.raises(ValueError, match="cue 'refined_cue': under this Config refine_stage\\(\\) is 'feedback'"):
            VisionMachine(Config.from_dict({"stereo": {"feature_matches": True}}))
    finally:
        cues.unregister("refined_cue")


def test_a_refinement_stage_that_is_no_name_under_a_config_is_refused_by_the_machine():
    def stage(self, config):
        return 1 if config.stereo.feature_matches else None

    cues.register(_cue("refined_cue", refine_stage=stage))
    try:
        with pytest.raises(TypeError, match="cue 'refined_cue': refine_stage\\(\\) must return a stage name \\(str\\) "
                                            "or None, got int"):
            VisionMachine(Config.from_dict({"stereo": {"feature_matches": True}}))
    finally:
        cues.unregister("refined_cue")


def test_a_cue_of_the_users_is_enabled_by_any_config():
    # A cue of its own name with no Config section (or one without an enabled switch) is on; a built-in
    # cue follows its section's switch.
    assert _cue("recognition").enabled(Config()) and _cue("new_cue").enabled(Config())
    off = Config.from_dict({"texture": {"enabled": False}})
    assert not next(cue for cue in cues.registered() if cue.name == "texture").enabled(off)


@pytest.mark.parametrize("declared, error, match", [
    ({"settings": "fast"}, TypeError, "cue 'declared': settings must be a vmcl.mrf.Settings or None, got str"),
    ({"settings": Settings(EnergyModel(alpha=0.0))}, ValueError, "cue 'declared': settings.model.alpha must be > 0"),
    ({"needs": ["rgb"]}, TypeError, "cue 'declared': needs must be a set or frozenset"),
    ({"needs": "rgb"}, TypeError, "cue 'declared': needs must be a set or frozenset"),
    ({"candidates_only": 1}, TypeError, "cue 'declared': candidates_only must be a bool"),
    ({"fields": "density"}, TypeError, "cue 'declared': fields must be a tuple"),
    ({"fields": None}, TypeError, "cue 'declared': fields must be a tuple"),
    ({"restored_as": 3}, TypeError, "cue 'declared': restored_as must be a Result attribute name or None"),
    ({"label": Label.NONE}, TypeError, "cue 'declared': label must be a Label other than NONE"),
    ({"name": ["a"]}, TypeError, "a cue's name must be a str"),
    ({"name": "two words"}, ValueError, "a cue's name must be a Python identifier"),
])
def test_every_declaration_is_checked_at_register(declared, error, match):
    with pytest.raises(error, match=match) as raised:
        cues.register(_cue(**{"name": "declared", **declared}))
    assert isinstance(raised.value, InputError)
    assert "declared" not in cue_names()


def test_unregister_takes_the_last_registered_cue_and_says_so_in_cue_terms(toy_cue):
    second = _cue("second_cue")
    cues.register(second)
    try:
        with pytest.raises(ValueError, match="cue 'brightness_level' cannot be unregistered while 'second_cue', "
                                             "registered after it, is"):
            cues.unregister("brightness_level")
        with pytest.raises(TypeError, match="name must be a cue's name"):
            cues.unregister(["second_cue"])
    finally:
        cues.unregister("second_cue")
    assert cue_names()[-1] == "brightness_level"


def test_a_next_frame_of_another_scene_is_named_beside_the_range_advice(machine):
    # Across a cut the winners pile up at the range's edge, and the note advised only more levels or delta.
    from vmcl.flow_evaluation import motion_only

    rng = np.random.default_rng(7)
    frame, unrelated = (rng.random((96, 128)).astype(np.float32) for _ in range(2))
    notes = VisionMachine(motion_only(Config()), machine=machine).run(frame, next=unrelated).notes
    said = [note for note in notes if "edge of its range" in note]
    assert said and "or the next frame shows another scene (a cut)" in said[0], notes
