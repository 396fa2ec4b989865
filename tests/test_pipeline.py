"""The integrated machine: configuration, input subsets, device residency, and end-to-end quality on
vmcl.scenes (seed sections "The Vision Machine System" and "Organization of integration")."""

import time
from pathlib import Path

import numpy as np
import pytest

from vmcl import metrics, scenes
from vmcl.errors import InputError
from vmcl.integrate import boundary, integrate
from vmcl.labels import Cue, Label
from vmcl.mrf import boundary_map
from vmcl.pipeline import Config, VisionMachine


@pytest.fixture(scope="module")
def cues_scene():
    return scenes.render(scenes.preset("cues", shape=(256, 256)), seed=0, noise=0.01)


@pytest.fixture(scope="module")
def cues_run(cues_scene, machine):
    s = cues_scene
    return VisionMachine(machine=machine).run(s.left, s.right, s.left_next)


@pytest.fixture(scope="module")
def small_scene():
    return scenes.render(scenes.preset("blocks", shape=(64, 64)), seed=0, noise=0.01)


# -- configuration ---------------------------------------------------------------------------------

def test_config_from_toml_overrides_defaults_and_presets(tmp_path):
    path = tmp_path / "c.toml"
    path.write_text('[stereo]\nd_max = 20\nfeedback = false\n[mrf]\nmethod = "icm"\n[mrf.stereo]\nbeta = 3.0\n')
    config = Config.from_toml(path)
    assert config.stereo.d_max == 20 and not config.stereo.feedback and config.mrf.method == "icm"
    assert config.mrf.settings("stereo").model.beta == 3.0
    assert config.mrf.settings("motion") == Config().mrf.settings("motion")
    assert config.to_dict()["stereo"]["d_max"] == 20


def test_a_config_made_in_python_is_checked_when_made():
    from vmcl.pipeline import MrfConfig

    with pytest.raises(ValueError, match="mrf.stereo.bogus"):
        Config(mrf=MrfConfig(stereo={"bogus": 1}))
    with pytest.raises(TypeError, match="config section stereo must be a vmcl.pipeline.StereoConfig"):
        Config(stereo={"d_max": 3})



def test_a_config_holds_its_own_values_and_refuses_what_a_run_would():
    # A Config kept the caller's override mapping itself (a later change to it changed the Config, and a
    # Result's record of it); grouping.iterations past the network's limit was refused only at run time;
    # progress that is not callable failed after the run had begun.
    overrides = {"beta": 3.0}
    config = Config.from_dict({"mrf": {"stereo": overrides}})
    overrides["beta"] = 99.0
    assert config.mrf.stereo == {"beta": 3.0}
    # The same for an MrfConfig built directly; and a Config hashes, equal ones alike (its overrides are
    # mappings, which made hash() fail).
    from vmcl.pipeline import MrfConfig

    direct = Config(mrf=MrfConfig(stereo=overrides))
    overrides["beta"] = 5.0
    assert direct.mrf.stereo == {"beta": 99.0}
    assert hash(Config()) == hash(Config()) and {Config(), Config()} == {Config()}
    assert hash(direct) == hash(Config.from_dict({"mrf": {"stereo": {"beta": 99.0}}}))
    # Equal Configs hash alike whatever their values' types (a text of them told 3 from 3.0).
    assert hash(Config.from_dict({"mrf": {"stereo": {"beta": 3}}})) == hash(Config.from_dict({"mrf": {"stereo": {"beta": 3.0}}}))
    with pytest.raises(ValueError, match="grouping.iterations must be <= 10000"):
        Config.from_dict({"grouping": {"iterations": 10**9}})
    with pytest.raises(TypeError, match="progress must be a callable"):
        VisionMachine().run(np.zeros((32, 32), np.float32), progress=5)

@pytest.mark.parametrize("text, message", [("[stereo]\nd_maxx = 3\n", "stereo.d_maxx"),
                                           ("[stero]\n", "stero"),
                                           ("[mrf.stereo]\nbetta = 1.0\n", "mrf.stereo.betta"),
                                           ("[stereo\n", "not valid TOML"),
                                           ("[stereo]\nbackfill_floor = 1.5\n", "stereo.backfill_floor"),
                                           ("[stereo]\nbackfill_weight = -0.1\n", "stereo.backfill_weight"),
                                           ("[motion]\nconfidence_floor = nan\n", "motion.confidence_floor"),
                                           ('[labels]\nmethod = "svm"\n', "labels.method"),
                                           ("[stereo]\nintensity_sigma = 0\n", "stereo.intensity_sigma"),
                                           # Accepted, then refused mid-run (alpha) or left the disparity to the
                                           # half-occluded pixels alone (backfill_weight), or overflowed (exponent).
                                           ("[mrf.motion]\nalpha = 0\n", "mrf.motion.alpha must be > 0"),
                                           ("[stereo]\nbackfill_weight = 0\n", "stereo.backfill_weight must be > 0"),
                                           ("[grouping]\nlength_exponent = 200\n", "grouping.length_exponent"),
                                           ('[mrf]\nmethod = "foo"\n', "mrf.method"),
                                           ('[mrf]\nschedule = "slow"\n', "mrf.schedule"),
                                           ("[edges]\nsigma = -1\n", "edges.sigma"),
                                           ("[edges]\nlow_threshold = 0.5\nhigh_threshold = 0.2\n", "edges.low_threshold"),
                                           ("[stereo]\npatch = 10\n", "stereo.patch"),
                                           ('[stereo]\nfeatures = "sift"\n', "stereo.features"),
                                           ("[stereo]\nd_min = 9\nd_max = 3\n", "stereo.d_min"),
                                           ("[stereo]\nmax_disparity = 0\n", "stereo.max_disparity"),
                                           ("[motion]\ndelta = 0\n", "motion.delta"),
                                           ('[motion]\nfeatures = "sift"\n', "motion.features"),
                                           ("[motion]\nlevels = 0\n", "motion.levels"),
                                           ("[motion]\nlucas_kanade_iterations = -1\n",
                                            "motion.lucas_kanade_iterations"),
                                           ("[motion]\nlucas_kanade_window = 0\n", "motion.lucas_kanade_window"),
                                           ("[motion]\nlucas_kanade_highpass = 0.5\n",
                                            "motion.lucas_kanade_highpass"),
                                           ("[motion]\nvariational_iterations = -1\n",
                                            "motion.variational_iterations"),
                                           ("[motion]\nvariational_alpha = -1\n", "motion.variational_alpha"),
                                           ("[time]\nflow_prior = -1\n", "time.flow_prior"),
                                           ("[colour]\nthreshold = -1\n", "colour.threshold"),
                                           ("[texture]\nradius = 0\n", "texture.radius"),
                                           ("[texture]\nthreshold = 0\n", "texture.threshold"),
                                           ("[texture]\nfine_sigma = 5\ncoarse_sigma = 4\n", "texture.fine_sigma")])
def test_bad_config_is_refused_naming_the_key(tmp_path, text, message):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ValueError, match=message):
        Config.from_toml(path)



def test_a_toml_files_settings_are_read_beside_it(tmp_path, monkeypatch):
    # Read from the working directory, a configuration kept with its weights and models failed (or read
    # another folder's) when run from anywhere else.
    from vmcl import labelling

    kept = tmp_path / "experiment"
    (kept / "models").mkdir(parents=True)
    labelling.default_labeller().save(kept / "weights.json")
    (kept / "c.toml").write_text('[labels]\nweights = "weights.json"\n[recognition]\nmodels = "models"\n')
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    config = Config.from_toml(Path("..") / "experiment" / "c.toml")
    assert Path(config.labels.weights).resolve() == (kept / "weights.json").resolve()
    assert Path(config.recognition.models).resolve() == (kept / "models").resolve()
    absolute = tmp_path / "a.toml"
    absolute.write_text(f'[labels]\nweights = "{(kept / "weights.json").as_posix()}"\n')
    assert Config.from_toml(absolute).labels.weights == (kept / "weights.json").as_posix()


def test_weights_can_be_switched_off_from_toml_and_bad_types_are_named(tmp_path):
    path = tmp_path / "c.toml"
    path.write_text("[motion]\nweigh_by_score = false\n[stereo]\nfeature_matches = true\nbackfill = false\n")
    config = Config.from_toml(path)
    assert not config.motion.weigh_by_score and not config.stereo.backfill and config.stereo.feature_matches
    with pytest.raises(ValueError, match="feature_matches and backfill are both off"):
        Config.from_dict({"stereo": {"backfill": False}})
    with pytest.raises(TypeError, match="stereo.backfill_weight"):
        Config.from_dict({"stereo": {"backfill_weight": "0.2"}})
    with pytest.raises(TypeError, match="stereo.shiftable"):
        Config.from_dict({"stereo": {"shiftable": 1}})
    with pytest.raises(TypeError, match="stereo.intensity_sigma"):
        Config.from_dict({"stereo": {"intensity_sigma": "1"}})


def test_intensity_matches_get_shiftable_windows_and_their_sigma(small_scene, machine, monkeypatch):
    """The backfill's intensity matches take stereo.shiftable and stereo.intensity_sigma; the edge matches
    keep stereo.sigma, and the feedback pass's barriers go to the edge matcher only."""
    from vmcl.early import stereo

    calls = []
    real = stereo.match

    def spy(*args, **kwargs):
        calls.append(kwargs)
        return real(*args, **kwargs)

    monkeypatch.setattr(stereo, "match", spy)
    s = small_scene
    config = Config.from_dict({"stereo": {"intensity_sigma": 1.5, "sigma": 2.5, "feature_matches": True,
                                          "dense": "intensity"}, "mrf": {"method": "icm"}})
    VisionMachine(config, machine=machine).run(s.left, s.right)
    intensity = [c for c in calls if c["features"] == "intensity"]
    edges = [c for c in calls if c["features"] != "intensity"]
    assert len(intensity) == 1 and intensity[0]["shiftable"] and intensity[0]["sigma"] == 1.5
    assert intensity[0]["barriers"] is None
    assert len(edges) == 2 and all(c["sigma"] == 2.5 for c in edges) and edges[1]["barriers"] is not None

# -- inputs ----------------------------------------------------------------------------------------

def test_one_grey_image_gives_edges_and_texture_only(small_scene, machine):
    grey = small_scene.left.mean(axis=2)
    result = VisionMachine(machine=machine).run(grey)
    assert result.edges.shape == grey.shape and result.edges.dtype == bool
    assert result.density is not None and result.hue is None
    assert result.disparity is None and result.flow is None
    assert set(result.lines) <= {"texture"}
    assert list(result.stages) == ["upload", "edges", "grouping", "boundaries", "texture", "mrf texture", "integrate",
                                   "download"]


def test_each_input_adds_its_cues(small_scene, machine):
    s = small_scene
    vm = VisionMachine(Config.from_dict({"mrf": {"method": "icm"}}), machine=machine)
    single = vm.run(s.left)
    assert single.hue is not None and single.disparity is None and single.flow is None
    pair = vm.run(s.left, s.right)
    assert pair.disparity.shape == (64, 64) and np.isfinite(pair.disparity).all()
    assert pair.half_occluded is not None and pair.flow is None
    moving = vm.run(s.left, next=s.left_next)
    assert moving.flow.shape == (64, 64, 2) and moving.disparity is None
    grey8 = np.round(s.left * 255).clip(0, 255).astype(np.uint8)
    uint8 = vm.run(grey8)
    np.testing.assert_array_equal(uint8.image, grey8.astype(np.float32) / np.float32(255))


def test_bad_images_are_refused(small_scene, machine):
    vm = VisionMachine(machine=machine)
    with pytest.raises(ValueError, match="right has shape"):
        vm.run(small_scene.left, small_scene.right[:32])
    with pytest.raises(ValueError, match="NaN"):
        vm.run(np.full((32, 32), np.nan, np.float32))
    with pytest.raises(ValueError, match="grey or"):
        vm.run(np.zeros((32, 32, 4), np.float32))
    with pytest.raises(TypeError, match="uint8, uint16 or float"):
        vm.run(np.zeros((32, 32), np.int64))
    # Brightness off the [0, 1] scale is refused, not processed as another image (or, from float64,
    # turned into infinities by the conversion to float32).
    for scale in (255.0, 1e30, -1.0):
        with pytest.raises(ValueError, match=r"left: float images hold brightness in \[0, 1\]"):
            vm.run(small_scene.left * np.float32(scale))
    with pytest.raises(ValueError, match="right: float images"):
        vm.run(small_scene.left, small_scene.right.astype(np.float64) * 1e300)


def test_fields_stay_on_the_device(small_scene, machine, monkeypatch):
    """One upload per image and one download per output: no host round trip between stages."""
    import pyopencl.array as cl_array

    gets, sets = [], []
    original_get, original_set = cl_array.Array.get, cl_array.Array.set
    monkeypatch.setattr(cl_array.Array, "get", lambda self, *a, **k: gets.append(self.size) or original_get(self, *a, **k))
    monkeypatch.setattr(cl_array.Array, "set", lambda self, *a, **k: sets.append(self.size) or original_set(self, *a, **k))
    s = small_scene
    VisionMachine(machine=machine).run(s.left, s.right, s.left_next)
    pixels = 64 * 64
    assert sum(size >= 3 * pixels for size in sets) == 3  # the three images, once each
    large_gets = [size for size in gets if size >= pixels // 2]
    # Fields read back: the downloads at the end (edges, hue, colour edges, density, texture edges,
    # sparse and first-pass disparity, discontinuity flags, raw flow, four restored fields, support,
    # labels and eight line fields), and the grouping stage's reads of its curves (the branch mask and the
    # curve labels, arc positions and tangents, for the junctions found on the host: docs/architecture.md).
    # Everything else read back is a scalar (thresholds, energies).
    assert len(large_gets) <= 25 + 4


def test_timings_per_stage_and_kernel(small_scene):
    s = small_scene
    start = time.perf_counter()
    result = VisionMachine().run(s.left, s.right)  # its own profiling Machine
    wall_ms = (time.perf_counter() - start) * 1e3
    assert list(result.stages) == ["upload", "edges", "grouping", "boundaries", "stereo", "colour", "texture",
                                   "mrf stereo",
                                   "mrf colour", "mrf texture", "integrate", "download"]
    assert all(ms > 0 for ms in result.stages.values()) and result.total_ms <= wall_ms
    # One in-order queue: kernels never overlap, so their device times add up to less than the run's wall time.
    device_ms = sum(entry["total_ms"] for entry in result.kernels.values())
    assert 0 < device_ms <= wall_ms
    assert {"census_costs", "aggregate", "check_views"} <= set(result.kernels)
    for entry in result.kernels.values():
        assert entry["calls"] >= 1 and entry["mean_ms"] == pytest.approx(entry["total_ms"] / entry["calls"])


# -- integration -----------------------------------------------------------------------------------

def test_soft_map_of_one_image_is_its_probability_of_boundary(small_scene, machine):
    from vmcl.early.boundary_probability import boundary_probability

    result = VisionMachine(machine=machine).run(small_scene.left)
    expected = boundary_probability(small_scene.left, machine=machine).probability
    np.testing.assert_array_equal(result.boundary_strength, expected)
    assert result.boundary_strength.dtype == np.float32


@pytest.mark.parametrize("method", ["linear", "rule"])
def test_without_the_image_probability_the_stage_is_left_out_and_the_rest_unchanged(small_scene, machine, method):
    """labels.boundary_probability = false skips the stage "boundaries"; the fields and labels are those of a
    full run, and the strength is the classifier's (or, for the rule labels, 1 where they label a discontinuity)."""
    full = VisionMachine(Config.from_dict({"labels": {"method": method}}), machine=machine).run(
        small_scene.left, small_scene.right)
    config = Config.from_dict({"labels": {"method": method, "boundary_probability": False}})
    vm = VisionMachine(config, machine=machine)
    found = vm.run(small_scene.left, small_scene.right)
    assert "boundaries" not in found.stages
    assert list(found.stages) == vm.stages(right=True, next=False, rgb=small_scene.left.ndim == 3)
    np.testing.assert_array_equal(found.disparity, full.disparity)
    np.testing.assert_array_equal(found.labels, full.labels)
    if method == "rule":  # 1 where it labels a discontinuity (a brightness edge it labels none had 1 too)
        np.testing.assert_array_equal(found.boundary_strength, (found.labels != 0).astype(np.float32))
    else:  # the classifier's support for some discontinuity at the candidates, 0 elsewhere
        candidates = found.support != 0
        assert candidates.sum() > 100
        assert not found.boundary_strength[~candidates].any()
        assert 0 < found.boundary_strength[candidates].min() and found.boundary_strength.max() <= 1
        assert not np.array_equal(found.boundary_strength, full.boundary_strength)


def test_soft_map_adds_the_classifier_where_stereo_or_motion_lines_are(cues_scene, cues_run, machine):
    from vmcl.early.boundary_probability import boundary_probability

    image_only = boundary_probability(cues_run.image, machine=machine).probability
    strength = cues_run.boundary_strength
    assert strength.min() >= 0 and strength.max() <= 1
    unseen = (cues_run.support & (Cue.STEREO | Cue.MOTION)) != 0
    np.testing.assert_array_equal(strength[~unseen], image_only[~unseen])
    assert np.all(strength[unseen] >= image_only[unseen])
    # The depth-only outline (the plate) gains strength from the depth and motion lines: measured 1.49x with
    # the motion defaults of benchmarks/motion_fit.py (the sign of the LoG over 21 px patches, whose lines
    # are fewer and more precise: recall 0.37, precision 0.72 within 2 px) and the labeller refitted on
    # them, 1.9x with the previous ones.
    depth_only = cues_scene.labels == Label.DEPTH
    assert strength[depth_only].mean() > 1.25 * image_only[depth_only].mean()


def test_integrate_matches_boundary_maps_and_labels(machine):
    rng = np.random.default_rng(1)
    lines = {cue: (rng.random((9, 12)) < 0.1, rng.random((8, 13)) < 0.1) for cue in ("stereo", "colour", "texture")}
    edges = rng.random((9, 13)) < 0.2
    support, labels = integrate(lines, edges=edges, machine=machine)
    maps = {cue: boundary_map(*pair) for cue, pair in lines.items()}
    expected = (maps["stereo"] * Cue.STEREO + maps["colour"] * Cue.COLOUR + maps["texture"] * Cue.TEXTURE
                + edges * Cue.BRIGHTNESS)
    np.testing.assert_array_equal(support, expected)
    want = np.where(maps["stereo"], Label.DEPTH,
                    np.where(maps["colour"], Label.ALBEDO, np.where(maps["texture"], Label.TEXTURE, 0)))
    np.testing.assert_array_equal(labels, want)
    np.testing.assert_array_equal(boundary(*lines["stereo"], machine=machine), maps["stereo"])


# -- end to end on the "cues" scene (256 x 256) ----------------------------------------------------

def test_dense_disparity_bad_1_below_2_percent(cues_scene, cues_run):
    visible = ~cues_scene.occluded_stereo & np.isfinite(cues_scene.disparity)
    scores = metrics.evaluate_disparity(cues_run.disparity, cues_scene.disparity, mask=visible)
    assert scores.density == 1.0
    assert scores.bad[1.0] < 0.02  # measured 0.012 with the range found from the images (0.023 with 0..13)


@pytest.mark.parametrize("dense", ["semiglobal", "intensity"])
def test_backfilled_stereo_data_keeps_sub_pixel_disparities(dense, cues_scene, machine):
    """The dense matches' sub-pixel disparities reach the stereo MRF's data unrounded, beside the feature
    matches' or alone (the default)."""
    from vmcl.cues.base import RunInputs
    from vmcl.cues.stereo import StereoCue
    from vmcl.early.edges import canny
    from vmcl.pipeline import as_image

    left, right = (machine.to_device(as_image(image, name)) for image, name in ((cues_scene.left, "left"),
                                                                                (cues_scene.right, "right")))
    for feature_matches in (True, False):
        config = Config.from_dict({"stereo": {"dense": dense, "feature_matches": feature_matches}})
        run = RunInputs(machine, config, left, right, None, canny(left, sigma=config.edges.sigma, machine=machine))
        measured = StereoCue().measure(run)
        data = measured.data.get()
        sparse = measured.fields["sparse_disparity"].get() if feature_matches else np.full(data.shape, np.nan)
        filled = np.isfinite(data) & ~np.isfinite(sparse)
        assert filled.mean() > 0.5
        assert np.mean(data[filled] != np.rint(data[filled])) > 0.8


@pytest.mark.parametrize("paths", [8, 4])
def test_the_number_of_scanline_directions_reaches_the_matcher(paths, cues_scene, machine, monkeypatch):
    import vmcl.cues.stereo as stereo_cue
    from vmcl.stereo_evaluation import DEPTH_ONLY

    seen = []
    matcher = stereo_cue.match_semiglobal

    def spy(*args, **kwargs):
        seen.append(kwargs["paths"])
        return matcher(*args, **kwargs)

    monkeypatch.setattr(stereo_cue, "match_semiglobal", spy)
    config = Config.from_dict({**DEPTH_ONLY, "stereo": {"paths": paths}})
    VisionMachine(config, machine=machine).run(cues_scene.left, cues_scene.right)
    assert seen == [paths]


def test_flow_epe_below_half_a_pixel(cues_scene, cues_run):
    known = ~cues_scene.occluded_motion & np.isfinite(cues_scene.flow).all(axis=-1)
    scores = metrics.evaluate_flow(cues_run.flow, cues_scene.flow, mask=known)
    assert scores.density == 1.0
    assert scores.epe < 0.3  # measured 0.244 (the motion module's own: 0.54)


def test_colour_only_boundary_is_found_by_colour_alone(cues_scene, cues_run):
    """The isoluminant boundary: colour's lines find it, brightness and the other cues do not."""
    albedo = cues_scene.labels == Label.ALBEDO
    colour = boundary_map(*cues_run.lines["colour"])
    assert metrics.detection_scores(colour, albedo, tolerance=1).recall >= 0.8  # measured 1.0
    assert metrics.detection_scores(cues_run.edges, albedo, tolerance=1).recall < 0.2
    for cue in ("stereo", "texture"):
        assert metrics.detection_scores(boundary_map(*cues_run.lines[cue]), albedo, tolerance=1).recall < 0.2
    assert metrics.label_scores(cues_run.labels, cues_scene.labels, tolerance=1)[Label.ALBEDO].recall >= 0.8


@pytest.mark.xfail(strict=True, reason="measured at 256 x 256 (fast mean-field schedule), each boundary within "
                   "its scene's tolerance (Scene.tolerance: 1 px, the texture-only one 9 px, half its sparse side's "
                   "18-px blob spacing): the linear labels (vmcl.labelling, fitted to targets that reach as far) recall "
                   "the colour-only boundary (1.00) and the texture-only one (0.83; 0.67 and 0.90 on seeds 1 and 2), "
                   "but the depth-only one at 0.43 (0.38 and 0.47). The depth-only boundary is in the image, but the "
                   "matcher places it only to within 2 to 3 px where its census window fattens the plate over the "
                   "background, and the stereo MRF's lines (alpha 1, beta 0.25, chosen for their depth lines on the "
                   "other presets) recall it at 0.40 within 1 px (0.88 within 3 px)")
def test_integration_recalls_every_single_cue_boundary(cues_scene, cues_run):
    scores = metrics.label_scores(cues_run.labels, cues_scene.labels, tolerance=cues_scene.tolerance)
    assert min(scores[label].recall for label in (Label.DEPTH, Label.ALBEDO, Label.TEXTURE)) >= 0.8


@pytest.mark.xfail(strict=True, reason="measured F 0.75 within the scene's tolerance (0.66 and 0.77 on seeds 1 "
                   "and 2) with the linear labels: more than half of the depth-only boundary (30% of the boundary "
                   "pixels) is missed; see the recall test")
def test_integrated_discontinuities_f_at_least_0_8(cues_scene, cues_run):
    scores = metrics.detection_scores(cues_run.discontinuities, cues_scene.labels > 0, tolerance=cues_scene.tolerance)
    assert scores.f >= 0.8


# -- real data -------------------------------------------------------------------------------------

@pytest.mark.parametrize("name, bar", [("tsukuba", 0.10), ("venus", 0.06)])
def test_dense_disparity_on_middlebury(name, bar, datasets_root, machine):
    """The depth MRF restores the edge matches backfilled by the intensity matches (stereo.backfill)."""
    from vmcl.datasets import load_stereo

    pair = load_stereo(name, datasets_root)
    # No range given: the machine finds it from the images (vmcl.early.disparity_range).
    result = VisionMachine(Config(), machine=machine).run(pair.left, pair.right)
    scores = metrics.evaluate_disparity(result.disparity, pair.disparity, mask=pair.masks["nonocc"])
    # measured tsukuba 0.097, venus 0.051 (benchmarks/results/disparity_range.md; given the true range,
    # 0.075 and 0.051)
    assert scores.bad[1.0] < bar


@pytest.mark.parametrize("scale, dtype, noted", [(16, np.uint16, True), (257, np.uint16, False), (1, np.uint8, False),
                                                 (0.1, np.uint8, True)])
def test_an_integer_image_using_little_of_its_range_gets_a_note(scale, dtype, noted, machine):
    """12-bit data in uint16 (x 16) is read on uint16's full scale, so the machine sees a very dark image:
    the run says so, naming the image and the factor that would fill the range; full-range data gets no
    note, nor does an 8-bit image of ordinary brightness; a very dark 8-bit one does."""
    grey = np.clip(np.round(scenes.render(scenes.preset("blocks", shape=(64, 64)), seed=0).left.mean(axis=2) * 255),
                   1, 255)
    image = np.round(grey * scale).astype(dtype)
    notes = [n for n in VisionMachine(machine=machine).run(image).notes if n.startswith("left: its brightest pixel")]
    assert len(notes) == noted, notes
    if noted and dtype == np.uint16:
        assert "of uint16's 65535" in notes[0] and "if the data has 12 bits" in notes[0] and "(x 16.0037)" in notes[0]


def test_the_dark_image_note_gives_the_factor_that_fills_the_range():
    # A black image was told to scale by 128 (nothing scales 0), and 1-bit data by 128 (it needs 255).
    from vmcl.pipeline import range_note

    assert range_note(np.zeros((20, 20), np.uint8), "left") == "left: every pixel is 0 (a black image): the machine sees nothing in it"
    assert "if the data has 1 bit, scale it to the full range first (x 255)" in range_note(
        np.eye(20, dtype=np.uint8), "left")
    # A float image divided by 255 twice got no note while the same data as an integer image did.
    twice = np.linspace(0, 1, 400, dtype=np.float32).reshape(20, 20) / 255
    assert "its brightest pixel is 0.003922" in range_note(twice, "left") and "(x 255" in range_note(twice, "left")
    assert range_note(np.zeros((20, 20), np.float32), "left").startswith("left: no pixel is above 0")
    assert range_note(np.full((20, 20), 0.2, np.float32), "left") is None


def test_a_float_image_centred_on_zero_is_refused():
    # Brightness in [-0.5, 0.5] (a mean taken out) was read as a dark image on the [0, 1] scale, in silence.
    image = np.random.default_rng(0).random((32, 32)).astype(np.float32) - 0.5
    with pytest.raises(ValueError, match=r"left: float images hold brightness in \[0, 1\]"):
        VisionMachine().run(image)


def test_the_rule_labels_strength_is_zero_on_an_edge_they_label_none():
    # Without the image's probability the strength was 1 wherever the support map had a bit, the brightness
    # edges' included: an edge the cartoon labels none (no cue marks it) had full strength.
    image = np.full((64, 64), 0.3, np.float32)
    image[:, 32:] = 0.7
    config = Config.from_dict({"labels": {"method": "rule", "boundary_probability": False}})
    found = VisionMachine(config).run(image)
    assert (found.support != 0).sum() > 30 and not found.labels.any()
    assert not found.boundary_strength.any()


def test_settings_a_run_cannot_use_are_named_before_any_stage(tmp_path, small_scene):
    # A weights file without the run's set of inputs failed after every stage had run, naming no key; a
    # library folder that does not exist was refused without the key's name; an edge sigma too wide for
    # the image was refused as "sigma".
    import json

    shipped = json.loads((Path(__file__).parents[1] / "vmcl" / "labelling.json").read_text())
    shipped.pop("fitted")
    shipped["weights"] = {"image": shipped["weights"]["image"]}
    (tmp_path / "image_only.json").write_text(json.dumps(shipped))
    vm = VisionMachine(Config.from_dict({"labels": {"weights": str(tmp_path / "image_only.json")}}))
    stages = []
    with pytest.raises(ValueError, match=r"labels.weights \(.*image_only.json\): the labeller has no weights"):
        vm.run(small_scene.left, small_scene.right, progress=stages.append)
    assert stages == []
    with pytest.raises(ValueError, match="recognition.models: folder must be a directory"):
        VisionMachine(Config.from_dict({"recognition": {"models": str(tmp_path / "none")}}))
    with pytest.raises(ValueError, match=r"edges \(the \[edges\] settings on this image\): sigma must be at most"):
        VisionMachine(Config.from_dict({"edges": {"sigma": 1000.0}})).run(small_scene.left)


def test_an_image_no_enabled_cue_reads_is_named_in_the_notes(small_scene):
    # With stereo and motion off, a right image and a next frame were dropped without a word.
    config = Config.from_dict({"stereo": {"enabled": False}, "motion": {"enabled": False}})
    found = VisionMachine(config).run(small_scene.left, small_scene.right, small_scene.left)
    assert "right: given but not used: no cue that reads it is enabled" in found.notes
    assert "next: given but not used: no cue that reads it is enabled" in found.notes
    assert not any("given but not used" in n for n in VisionMachine().run(small_scene.left, small_scene.right).notes)


def test_every_listed_stage_is_reported_when_there_is_nothing_to_restore():
    # On a featureless pair the feedback pass was skipped: VisionMachine.stages listed it, but progress and
    # Result.stages never saw it (a progress bar one short).
    flat = np.full((64, 64), 0.5, np.float32)
    vm = VisionMachine(Config.from_dict({"stereo": {"feature_matches": True, "backfill": False}}))
    seen = []
    found = vm.run(flat, flat, progress=seen.append)
    listed = vm.stages(right=True, next=False, rgb=False)
    assert "feedback" in listed and list(found.stages) == listed and seen == listed


def test_a_config_with_a_byte_order_mark_is_read_and_one_nested_too_deeply_refused(tmp_path):
    # Notepad's UTF-8 starts with a byte-order mark, which was refused as invalid TOML; an array nested
    # 200,000 deep ended in a RecursionError.
    bom = tmp_path / "bom.toml"
    bom.write_bytes(b"\xef\xbb\xbf[stereo]\nd_max = 12\n")
    assert Config.from_toml(bom).stereo.d_max == 12
    deep = tmp_path / "deep.toml"
    deep.write_text("x = " + "[" * 200_000 + "]" * 200_000 + "\n")
    with pytest.raises(ValueError, match="deep.toml"):
        Config.from_toml(deep)


def test_a_config_path_that_is_not_a_path_or_is_a_folder_is_refused_as_input(tmp_path):
    # A number reached pathlib's bare TypeError and a folder a raw IsADirectoryError: neither an InputError,
    # which the README promises for every refusal.
    import re

    from vmcl.errors import InputTypeError, InputValueError

    with pytest.raises(InputTypeError, match=r"^path must be a str or an os\.PathLike, got int$"):
        Config.from_toml(5)
    with pytest.raises(InputValueError, match=f"^{re.escape(str(tmp_path))}: a folder, not a TOML file$"):
        Config.from_toml(tmp_path)
    with pytest.raises(FileNotFoundError):
        Config.from_toml(tmp_path / "missing.toml")


def test_a_left_image_of_one_brightness_gives_no_depth_or_motion():
    # Every matcher's winner on a blank image was its scan's first, confirmed by an equally blind check:
    # a disparity and a flow of 0 everywhere, restored as sure data, with no word.
    blank = np.full((64, 64), 128, np.uint8)
    found = VisionMachine().run(blank, blank, blank)
    assert found.disparity is None and found.flow is None
    # The raw fields hold no blind values either.
    assert np.isnan(found.raw_flow).all() and not found.half_occluded.any()
    red = np.zeros((64, 64, 3), np.uint8)  # one colour everywhere, though its channels differ
    red[..., 0] = 255
    assert VisionMachine().run(red, red).disparity is None
    assert "stereo: the left image has one brightness everywhere, so there is nothing to match: no data" in found.notes


@pytest.mark.parametrize("returned, match", [("none", "measure\\(\\) must return a vmcl.cues.Measurement, got NoneType"),
                                             ("host", "its Measurement's data must be a device array"),
                                             ("undeclared", r"its Measurement holds fields \['labels'\] that the cue")])
def test_a_registered_cue_that_measures_wrongly_is_named(small_scene, returned, match):
    # A cue of the user's that returned None, or host arrays, ended the run with a bare AttributeError or
    # TypeError, and an error of its own was said to come from its "[probe] settings", which do not exist.
    from vmcl.cues import CueModule, Measurement, register, unregister
    from vmcl.labels import Label

    class Probe(CueModule):
        name = "probe"
        label = Label.ORIENTATION

        def measure(self, run):
            if returned == "none":
                return None
            grey = np.ascontiguousarray(run.left.get().mean(axis=2), np.float32)
            if returned == "undeclared":  # Result's own labels: a TypeError when Result was made
                device = run.machine.to_device(grey)
                return Measurement(device, None, run.brightness, fields={"labels": device})
            return Measurement(grey, None, run.brightness)

    register(Probe())
    try:
        with pytest.raises(InputError, match=r"probe \(a registered cue\): " + match):
            VisionMachine().run(small_scene.left)
    finally:
        unregister("probe")


def test_a_file_setting_may_be_a_path():
    # A pathlib.Path, which the loaders the setting feeds take, was refused: "must be a string or None".
    from pathlib import Path

    from vmcl import labelling

    given = Config.from_dict({"labels": {"weights": Path(labelling.WEIGHTS_FILE)}})
    assert given.labels.weights == str(labelling.WEIGHTS_FILE)
    assert given == Config.from_dict({"labels": {"weights": str(labelling.WEIGHTS_FILE)}})


@pytest.mark.parametrize("section, key", [("stereo", "census_threshold"), ("stereo", "edge_gain"),
                                          ("grouping", "threshold"), ("colour", "threshold"),
                                          ("texture", "noise_factor")])
def test_a_setting_beyond_float32_is_refused_when_the_config_is_made(section, key):
    # Each reached the device as an infinity mid-run, with only NumPy's overflow warning.
    with pytest.raises(InputError, match=f"{section}.{key} must lie within float32's range"):
        Config.from_dict({section: {key: 1e308}})
    # An integer too large for a float (TOML holds any): math.isfinite raised OverflowError on it.
    with pytest.raises(InputError, match=f"{section}.{key} must lie within float32's range.*integer of 401 digits"):
        Config.from_dict({section: {key: 10**400}})


def test_the_recognition_section_sets_the_pose_and_the_candidate_budget(tmp_path, small_scene, monkeypatch):
    # `vmcl run --models` had no way to raise the budget, which a larger library shares more thinly.
    from vmcl import pipeline
    from vmcl.recognize import learn, save_model
    from vmcl.scenes import object_view

    with pytest.raises(ValueError, match="recognition.candidates must be"):
        Config.from_dict({"recognition": {"candidates": 0}})
    with pytest.raises(ValueError, match="recognition.transform"):
        Config.from_dict({"recognition": {"transform": "projective"}})
    folder = tmp_path / "library"
    folder.mkdir()
    save_model(learn("ell", [object_view("ell")[0]]), folder)
    seen = []
    monkeypatch.setattr(pipeline, "recognize", lambda *args, **kwargs: seen.append(kwargs) or [])
    config = Config.from_dict({"recognition": {"models": str(folder), "transform": "affine", "candidates": 4096}})
    VisionMachine(config).run(small_scene.left)
    assert seen and seen[0]["transform"] == "affine" and seen[0]["candidates"] == 4096


def test_a_noise_rule_that_leaves_no_edge_is_said():
    # The README's own scene ("cues", textured everywhere) gave no brightness edge, and nothing said so.
    from vmcl import scenes

    textured = scenes.render(scenes.preset("cues", shape=(128, 128)), seed=0, noise=0.01)
    found = VisionMachine(Config()).run(textured.left)
    assert not found.edges.any() and any("Canny found no brightness edge" in note for note in found.notes)
    given = VisionMachine(Config.from_dict({"edges": {"low_threshold": 0.02, "high_threshold": 0.05}})).run(textured.left)
    assert given.edges.any() and not any("Canny found no brightness edge" in note for note in given.notes)
    blocks = scenes.render(scenes.preset("blocks", shape=(128, 128)), seed=0, noise=0.01)
    assert not any("Canny found no" in note for note in VisionMachine(Config()).run(blocks.left).notes)
    # An image of one colour, or of colours of one brightness, has no brightness edge to find: no threshold
    # is to blame.
    red = np.zeros((64, 64, 3), np.float32)
    red[..., 0] = 1.0
    assert not any("Canny found no" in note for note in VisionMachine(Config()).run(red).notes)


def test_quantile_thresholds_need_a_threshold():
    # use_quantiles alone left the noise rule in charge and changed nothing, in silence.
    with pytest.raises(InputError, match="edges.use_quantiles = true needs edges.low_threshold or"):
        Config.from_dict({"edges": {"use_quantiles": True}})
    Config.from_dict({"edges": {"use_quantiles": True, "high_threshold": 0.9}})
