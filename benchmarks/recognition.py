"""Recognition: rendered scenes of known identity and pose, OpenCV's real samples, and speed.

Run: python benchmarks/recognition.py [--data ../shared/datasets] [--out benchmarks/results/recognition.md]

- Test scenes (vmcl.scenes.recognition_scene, seeds 1000..1099, never looked at while developing): two
  library objects each among clutter, 30-50 % of each hidden; the library learned from
  vmcl.scenes.example_library (27 objects: one view of each flat one, five views 20 degrees apart of each
  solid one, seen in the scenes at any view between). Recognition rate, false detections per image and the
  pose's mean error at the model's corners (vmcl.metrics.recognition_scores: the corners the detection's
  view shows), at the decision threshold
  benchmarks/recognition_fit.py chose on training scenes (the default of vmcl.recognize.recognize); and the
  same scenes indexed by corners alone (arcs=False), what the arcs add, and with the other choice of the
  support required of a view's inner markings (none, or 0.1 where the default requires none); and the same
  scenes rendered as stereo pairs, occlusion explained by the depth machine's disparity (and by the true
  one, at the same threshold), at the threshold benchmarks/recognition_depth_fit.py chose on training
  scenes.
- OpenCV's samples: graf1 learned as a model and found in graf3 (a homography), its corners against the
  true homography H1to3p beside ORB + RANSAC and SIFT + RANSAC, configured as OpenCV's feature-homography
  tutorial does (ratio test 0.75, RANSAC reprojection threshold 5 px); box learned from box.png and found in
  box_in_scene.png, its corners beside SIFT + RANSAC's (there is no ground truth; the picture is written
  to benchmarks/results/recognition_box.png).
- Speed: a 512 x 384 scene against a 20-model library, the time recognize takes beyond the edges; the
  indexing vote, the distance transform and the support test on the device against the same steps in
  NumPy / SciPy (vmcl.recognize.vote_numpy, distance_transform_numpy, support_numpy); and the vote's time
  per image as the library grows from 10 to 1000 synthetic models (random polygons, their corners and
  boundary taken from their geometry).
"""

from __future__ import annotations

import argparse
import inspect
import math
import platform
import statistics
import sys
import time
from pathlib import Path

import cv2
import numpy as np

from vmcl.metrics import recognition_scores
from vmcl.pipeline import Config, VisionMachine
from vmcl.recognize import (
    Index,
    Library,
    Model,
    View,
    corner_pairs,
    distance_transform,
    distance_transform_numpy,
    image_features,
    learn,
    pair_keys,
    recognize,
    support,
    support_numpy,
    vote,
    vote_numpy,
)
from vmcl.recognize.recognition import MIN_SIGNIFICANCE, MIN_SIGNIFICANCE_DEPTH
from vmcl.scenes import OBJECTS, example_library, recognition_scene
from vmcl.stereo_evaluation import DEPTH_ONLY

ROOT = Path(__file__).resolve().parents[1]
TEST_SEEDS = range(1000, 1100)
DEFAULT_MIN_INNER = inspect.signature(recognize).parameters["min_inner"].default
OTHER_MIN_INNER = 0.1  # compared where the default requires no share: the least share the fit tries above 0
REPEATS = 5
GROWTH_ROUNDS = 21


def _timed(call, repeats: int = REPEATS) -> float:
    """Median wall ms of ``call`` over ``repeats`` runs, after one warm-up."""
    call()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        times.append((time.perf_counter() - start) * 1e3)
    return statistics.median(times)


def _scene_tally(library, learned, depth_of=None, **kwargs) -> tuple[list[tuple[str, bool, float]], int]:
    """Over the test scenes: every placed object's (name, found, pose error), and the false detections. With
    ``depth_of``, each scene is rendered as a stereo pair and recognised with ``depth_of(scene)`` as its
    disparity."""
    placed, false = [], 0
    for seed in TEST_SEEDS:
        scene = recognition_scene(seed=seed, stereo=depth_of is not None)
        depth = None if depth_of is None else depth_of(scene)
        scores = recognition_scores(recognize(scene.image, library, depth=depth, **kwargs), scene.placements, learned)
        false += scores.false
        placed += [(p.name, bool(found), error) for p, found, error in
                   zip(scene.placements, scores.found, scores.pose_error)]
    return placed, false


def _rate(placed: list[tuple[str, bool, float]], names: set[str]) -> float:
    hits = [found for name, found, _ in placed if name in names]
    return sum(hits) / max(len(hits), 1)


def scenes_section() -> list[str]:
    library, learned = example_library()
    kinds = {"flat": {o.name for o in OBJECTS if not o.solid}, "solid": {o.name for o in OBJECTS if o.solid}}
    placed, false = _scene_tally(library, learned)
    flat, solid = (sum(name in kinds[k] for name, _, _ in placed) for k in ("flat", "solid"))
    lines = ["## Rendered scenes (test seeds 1000..1099)", "",
             (f"{len(TEST_SEEDS)} scenes, {len(placed)} objects ({flat} flat, {solid} solid), each 30-50 % hidden, "
              "among clutter; 27 models learned from at most 5 views."), "",
             "| objects | recognition rate | pose error at the corners: mean px | median px | within 2 px |",
             "|---|---|---|---|---|"]
    for kind, label in (("flat", "flat (2-D)"), ("solid", "solid (3-D, views between the learned ones)")):
        e = np.array([error for name, found, error in placed if found and name in kinds[kind]])
        lines.append(f"| {label} | {_rate(placed, kinds[kind]):.3f} | "
                     f"{e.mean() if len(e) else float('nan'):.2f} | {np.median(e) if len(e) else float('nan'):.2f} | "
                     f"{(e <= 2).mean() if len(e) else float('nan'):.3f} |")
    every = kinds["flat"] | kinds["solid"]
    lines += [f"| all | {_rate(placed, every):.3f} | | | |", "",
              (f"False detections per image: {false / len(TEST_SEEDS):.3f} (bar: at most 0.1). Recognition rate bar: "
               "at least 0.9; pose error bar: at most 2 px."), "",
              ("The pose error is the mean distance from each of the object's visible corners that the detection's "
               "view shows to the nearest corner the pose carries there (vmcl.metrics.recognition_scores). A solid "
               "seen a degree or two past a learned view shows a sliver of a face that the view sees edge-on; that "
               "face's far corners are none of the view's, so no pose of the view can carry one there, and they are "
               "left out."), ""]
    # The arcs' share: the same scenes indexed by corners alone.
    curved = {o.name for o in OBJECTS if o.curved}
    alone, alone_false = _scene_tally(library, learned, arcs=False)
    lines += [("What the arcs add: the same scenes with corners alone indexed (`recognize(..., arcs=False)`), at the "
               "same threshold:"), "",
              "| indexing | flat, curved outlines | flat, polygons | solid | all | false detections per image |",
              "|---|---|---|---|---|---|"]
    for label, tally, wrong in (("corners and arcs", placed, false), ("corners only", alone, alone_false)):
        lines.append(f"| {label} | {_rate(tally, curved):.3f} | {_rate(tally, kinds['flat'] - curved):.3f} | "
                     f"{_rate(tally, kinds['solid']):.3f} | {_rate(tally, every):.3f} | {wrong / len(TEST_SEEDS):.3f} |")
    # The inner markings' share: the same scenes with the other choice (none required, or the least share
    # the fit tried where the default requires none).
    other = 0.0 if DEFAULT_MIN_INNER else OTHER_MIN_INNER
    compared, compared_false = _scene_tally(library, learned, min_inner=other)
    lines += ["", (f"What requiring a view's inner markings does: the same scenes at `recognize(..., min_inner={other:g})`, "
                   "at the same threshold:"), "",
              "| inner markings | flat | solid | all | false detections per image |", "|---|---|---|---|---|"]

    def inner_label(share: float) -> str:
        return f"at least {share:g} supported" if share else "not required"

    for label, tally, wrong in ((f"{inner_label(DEFAULT_MIN_INNER)} (the default)", placed, false),
                                (inner_label(other), compared, compared_false)):
        lines.append(f"| {label} | {_rate(tally, kinds['flat']):.3f} | {_rate(tally, kinds['solid']):.3f} | "
                     f"{_rate(tally, every):.3f} | {wrong / len(TEST_SEEDS):.3f} |")
    return lines + [""] + _stereo_lines(library, learned, kinds, placed, false)


def _stereo_lines(library, learned, kinds, placed, false) -> list[str]:
    """The test scenes rendered as stereo pairs (their left views are the scenes above): occlusion explained
    by the depth machine's disparity, and by the scenes' true disparity at the same threshold."""
    vm = VisionMachine(Config.from_dict(DEPTH_ONLY))
    measured, measured_false = _scene_tally(library, learned, lambda scene: vm.run(scene.image, scene.right).disparity)
    true, true_false = _scene_tally(library, learned, lambda scene: scene.disparity)
    every = kinds["flat"] | kinds["solid"]
    lines = ["## The same scenes as stereo pairs", "",
             ("The test scenes rendered as stereo pairs (`recognition_scene(..., stereo=True)`: each layer flat at its "
              "disparity, nearer as it is painted later; the left views are the scenes above). The disparity explains "
              "occlusion (`recognize(..., depth=...)`): the model points a nearer surface hides leave an object's "
              "coverage, at the threshold benchmarks/recognition_depth_fit.py chose on the training scenes "
              f"(min_significance {MIN_SIGNIFICANCE_DEPTH:g}; {MIN_SIGNIFICANCE:g} on the image alone). The true "
              "disparity is not a method, and the threshold was chosen with the machine's, not with it."), "",
             ("| disparity | flat | solid | all | false detections per image | pose error at the corners, mean px: "
              "flat | solid |"), "|---|---|---|---|---|---|---|"]

    def mean_error(tally, names) -> float:
        errors = [error for name, found, error in tally if found and name in names]
        return float(np.mean(errors)) if errors else float("nan")

    for label, tally, wrong in (("none (the image alone)", placed, false),
                                ("the depth machine's (vmcl defaults, depth only)", measured, measured_false),
                                ("the scene's true disparity (same threshold)", true, true_false)):
        lines.append(f"| {label} | {_rate(tally, kinds['flat']):.3f} | {_rate(tally, kinds['solid']):.3f} | "
                     f"{_rate(tally, every):.3f} | {wrong / len(TEST_SEEDS):.3f} | "
                     f"{mean_error(tally, kinds['flat']):.2f} | {mean_error(tally, kinds['solid']):.2f} |")
    return lines + ["", ("Bars (the depth machine's disparity): recognition rate at least 0.9: "
                         f"{'met' if _rate(measured, every) >= 0.9 else 'NOT met'}; false detections per image at "
                         f"most 0.1: {'met' if measured_false / len(TEST_SEEDS) <= 0.1 else 'NOT met'}; pose error "
                         "at most 2 px, flat and solid: "
                         f"{'met' if max(mean_error(measured, kinds[k]) for k in kinds) <= 2 else 'NOT met'}."), ""]


def _corners_error(h: np.ndarray, truth: np.ndarray, shape: tuple[int, int]) -> float:
    height, width = shape
    corners = np.array([[0, 0], [width - 1, 0], [width - 1, height - 1], [0, height - 1]], np.float64)
    a = cv2.perspectiveTransform(corners[None], h)[0]
    b = cv2.perspectiveTransform(corners[None], truth)[0]
    return float(np.hypot(*(a - b).T).mean())


def _feature_homography(detector, norm: int, model: np.ndarray, scene: np.ndarray) -> np.ndarray | None:
    """OpenCV's feature-homography tutorial: matches passing Lowe's ratio test 0.75, RANSAC at 5 px."""
    k1, d1 = detector.detectAndCompute(model, None)
    k2, d2 = detector.detectAndCompute(scene, None)
    if d1 is None or d2 is None:
        return None
    good = [m for m, n in (p for p in cv2.BFMatcher(norm).knnMatch(d1, d2, k=2) if len(p) == 2)
            if m.distance < 0.75 * n.distance]
    if len(good) < 4:
        return None
    src = np.float32([k1[m.queryIdx].pt for m in good])
    dst = np.float32([k2[m.trainIdx].pt for m in good])
    h, _ = cv2.findHomography(src, dst, cv2.RANSAC, 5.0)
    return h


def _homography_xml(path: Path) -> np.ndarray:
    """The 3 x 3 matrix of an OpenCV storage file's first node (read as XML: OpenCV 5's reader refuses it)."""
    from xml.etree import ElementTree

    node = next(iter(ElementTree.parse(path).getroot()))
    return np.array(node.findtext("data").split(), float).reshape(3, 3)


def _read_grey(path: Path) -> np.ndarray:
    image = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
    if image is None:
        raise SystemExit(f"cannot read {path}")
    return image


def samples_section(data: Path) -> list[str]:
    folder = data / "opencv_samples"
    graf1, graf3 = _read_grey(folder / "graf1.png"), _read_grey(folder / "graf3.png")
    truth = _homography_xml(folder / "H1to3p.xml")
    library = Library([learn("graf", [graf1])])
    lines = ["## OpenCV's samples", "", ("graf1 -> graf3: the mean error (px) at graf1's four image corners against "
                                         "the true homography H1to3p."), "",
             "| method | mean corner error px | time ms |", "|---|---|---|"]
    start = time.perf_counter()
    found = recognize(graf3, library, transform="homography")
    ms = (time.perf_counter() - start) * 1e3
    ours = f"{_corners_error(found[0].transform, truth, graf1.shape):.1f}" if found else "not found"
    lines.append(f"| vmcl (learn graf1, recognize in graf3, homography) | {ours} | {ms:.0f} |")
    for name, detector, norm in (("ORB + RANSAC", cv2.ORB_create(nfeatures=2000), cv2.NORM_HAMMING),
                                 ("SIFT + RANSAC", cv2.SIFT_create(), cv2.NORM_L2)):
        start = time.perf_counter()
        h = _feature_homography(detector, norm, graf1, graf3)
        ms = (time.perf_counter() - start) * 1e3
        error = _corners_error(h, truth, graf1.shape) if h is not None else float("nan")
        lines.append(f"| {name} | {error:.1f} | {ms:.0f} |")
    box, scene = _read_grey(folder / "box.png"), _read_grey(folder / "box_in_scene.png")
    library = Library([learn("box", [box])])
    box_corners = np.array([[0, 0], [box.shape[1] - 1, 0], [box.shape[1] - 1, box.shape[0] - 1], [0, box.shape[0] - 1]],
                           np.float64)
    rows = []
    picture = cv2.cvtColor(scene, cv2.COLOR_GRAY2BGR)
    sift = _feature_homography(cv2.SIFT_create(), cv2.NORM_L2, box, scene)
    sift_corners = cv2.perspectiveTransform(box_corners[None], sift)[0] if sift is not None else None
    # The same search with graf1 learned into the library beside the box: whether a model is found should
    # not depend on what else the library holds.
    crowded = Library([*library.models, learn("graf", [_read_grey(folder / "graf1.png")])])
    for transform, models in (("similarity", library), ("affine", library), ("homography", library),
                              ("homography", crowded)):
        label = transform if models is library else f"{transform}, graf1 also in the library"
        found = [d for d in recognize(scene, models, transform=transform) if d.name == "box"]
        if not found:
            rows.append(f"| vmcl ({label}) | not found | |")
            continue
        corners = found[0].locate(box_corners)
        gap = np.hypot(*(corners - sift_corners).T).mean() if sift_corners is not None else float("nan")
        rows.append(f"| vmcl ({label}) | {_fmt(corners)} | {gap:.1f} |")
        if transform == "homography" and models is library:
            cv2.polylines(picture, [np.round(corners).astype(np.int32)], True, (0, 200, 0), 2)
    if sift_corners is not None:
        rows.append(f"| SIFT + RANSAC | {_fmt(sift_corners)} | 0 |")
        cv2.polylines(picture, [np.round(sift_corners).astype(np.int32)], True, (0, 0, 220), 1)
    cv2.imwrite(str(ROOT / "benchmarks" / "results" / "recognition_box.png"), picture)
    lines += ["", ("box.png found in box_in_scene.png: its corners (clockwise from the top left of box.png) and "
                   "their mean distance from SIFT + RANSAC's (no ground truth). The picture "
                   "(results/recognition_box.png) draws vmcl's homography in green, SIFT's in red."), "",
              "| method | corners (x, y) | mean px from SIFT's |", "|---|---|---|", *rows, ""]
    return lines


def _fmt(corners: np.ndarray) -> str:
    return " ".join(f"({x:.0f}, {y:.0f})" for x, y in corners)


def _synthetic_view(rng: np.random.Generator) -> View:
    """A random polygon's view from its geometry: its vertices as corners, its outline as the boundary."""
    k = int(rng.integers(5, 10))
    angles = np.sort(rng.uniform(0, 2 * math.pi, k))
    radii = rng.uniform(25, 45, k)
    vertices = np.stack([radii * np.cos(angles), radii * np.sin(angles)], 1) + 100
    before, after = np.roll(vertices, 1, axis=0) - vertices, np.roll(vertices, -1, axis=0) - vertices
    a, b = np.arctan2(before[:, 1], before[:, 0]), np.arctan2(after[:, 1], after[:, 0])
    opening = np.abs(np.angle(np.exp(1j * (b - a))))
    bisector = np.angle(np.exp(1j * a) + np.exp(1j * b))
    points, tangent = [], []
    for p, q in zip(vertices, np.roll(vertices, -1, axis=0)):
        n = max(int(np.hypot(*(q - p)) / 2), 1)
        t = np.linspace(0, 1, n, endpoint=False)[:, None]
        points.append(p + t * (q - p))
        tangent.append(np.full(n, math.atan2(q[1] - p[1], q[0] - p[0])))
    boundary = np.concatenate(points)
    centre = boundary.mean(axis=0)
    return View(vertices, bisector, opening, boundary, np.concatenate(tangent), centre,
                float(np.sqrt(((boundary - centre) ** 2).sum(axis=1).mean())), (200, 200), 2.0 * len(boundary))


def speed_section() -> list[str]:
    names = tuple(o.name for o in OBJECTS[:20])
    library, _ = example_library(names)
    scene = recognition_scene((384, 512), library=names, seed=1000)
    features = image_features(scene.image)
    edge_ms = _timed(lambda: image_features(scene.image))
    total_ms = _timed(lambda: recognize(scene.image, library))
    beyond = _timed(lambda: recognize(features, library))
    index = Index.build(library)
    pairs = corner_pairs(features.corners)
    args = (index, features.corners, features.bisector, features.opening, pairs)
    vote_ms, vote_np_ms = _timed(lambda: vote(*args)), _timed(lambda: vote_numpy(*args))
    dt_ms = _timed(lambda: distance_transform(features.edges))
    dt_np_ms = _timed(lambda: distance_transform_numpy(features.edges))
    nearest = distance_transform(features.edges).nearest
    found = vote(*args)
    views = library.views()
    chosen = found.views[:128]
    points = np.concatenate([views[v][2].points for v in chosen])
    tangents = np.concatenate([views[v][2].tangent for v in chosen])
    sizes = np.array([len(views[v][2].points) for v in chosen])
    ranges = np.stack([np.cumsum(sizes) - sizes, np.cumsum(sizes)], 1)
    transforms = found.matrices()[:128]
    sargs = (nearest, features.tangent_map, points, tangents, ranges, transforms)
    support_ms, support_np_ms = _timed(lambda: support(*sargs)), _timed(lambda: support_numpy(*sargs))
    lines = ["## Speed", "", (f"A 512 x 384 scene (seed 1000) against a 20-model library ({len(index)} table "
                              f"entries), median of {REPEATS} runs on this machine's OpenCL device (PoCL on the CPU)."),
             "",
             "| step | ms |", "|---|---|", f"| edges, curves and corners (image_features) | {edge_ms:.0f} |",
             f"| recognize from the image | {total_ms:.0f} |",
             f"| recognize beyond the features (selection, indexing, verification) | {beyond:.0f} |", "",
             (f"Kernels against the same steps in NumPy / SciPy ({len(pairs)} corner pairs; {len(chosen)} "
              f"candidates, {len(points)} model points):"), "", "| step | device ms | NumPy ms | ratio |", "|---|---|---|---|",
             f"| indexing vote (both passes) | {vote_ms:.2f} | {vote_np_ms:.2f} | {vote_np_ms / vote_ms:.1f} |",
             f"| distance transform | {dt_ms:.2f} | {dt_np_ms:.2f} | {dt_np_ms / dt_ms:.1f} |",
             f"| support test | {support_ms:.2f} | {support_np_ms:.2f} | {support_np_ms / support_ms:.1f} |", ""]
    rng = np.random.default_rng(7)
    synthetic = [Model(f"polygon {i}", (_synthetic_view(rng),), ("synthetic",)) for i in range(1000)]
    sizes = (10, 30, 100, 300, 1000)
    grown = {size: Index.build(Library(synthetic[:size])) for size in sizes}
    times: dict[int, list[float]] = {size: [] for size in sizes}
    for size in sizes:  # a warm-up call each (kernels built, the table on the device)
        vote(grown[size], features.corners, features.bisector, features.opening, pairs)
    for _ in range(GROWTH_ROUNDS):  # the sizes in alternation, so that the machine's drifting load meets each alike
        for size in sizes:
            start = time.perf_counter()
            vote(grown[size], features.corners, features.bisector, features.opening, pairs)
            times[size].append((time.perf_counter() - start) * 1e3)
    medians = {size: statistics.median(times[size]) for size in sizes}
    lines += [(f"The vote's time per image as the library grows (synthetic models; the same scene's corner pairs; "
               f"the sizes in alternation, medians of {GROWTH_ROUNDS} rounds):"), "",
              ("| models | table entries | entries the lookups meet | vote ms | ratio to 10 models | "
               "sqrt of the size ratio |"), "|---|---|---|---|---|---|"]
    keys = pair_keys(features.corners, features.bisector, features.opening, pairs)
    for size in sizes:
        met = int((grown[size].offsets[keys + 1] - grown[size].offsets[keys]).sum())
        lines.append(f"| {size} | {len(grown[size])} | {met} | {medians[size]:.2f} | "
                     f"{medians[size] / medians[10]:.2f} | {math.sqrt(size / 10):.2f} |")
    ratio = medians[1000] / medians[10]
    lines += ["", (f"Bar (the time at 1000 models at most the square root of the size ratio, 10x the time at 10): "
                   f"{ratio:.2f}x, {'met' if ratio <= 10 else 'NOT met'}. The vote's work grows with the entries "
                   "its lookups meet, about as the table does; what keeps the ratio down is how little each "
                   "entry costs beside the call's fixed costs (launches and transfers), not an index that meets "
                   "fewer entries.")]
    lines.append("")
    return lines


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default=str(ROOT.parent / "shared" / "datasets"))
    parser.add_argument("--out", default=str(ROOT / "benchmarks" / "results" / "recognition.md"))
    args = parser.parse_args()
    start = time.perf_counter()
    body = scenes_section() + samples_section(Path(args.data)) + speed_section()
    head = ["# Recognition", "", (f"`python benchmarks/recognition.py` on {platform.node() or 'this machine'} "
                                  f"({time.strftime('%Y-%m-%d')}), {time.perf_counter() - start:.0f} s; no GPU was "
                                  "lent, so every figure is PoCL on the CPU."), ""]
    Path(args.out).write_text("\n".join(head + body))
    print("\n".join(head + body))
    return 0


if __name__ == "__main__":
    sys.exit(main())
