"""The README's benchmark tables are what benchmarks/readme.py generates from benchmarks/results.

A benchmark re-run without `python benchmarks/readme.py` afterwards leaves the README quoting old figures;
this fails the suite until the tables are regenerated.
"""

import importlib.util
import shutil
import sys
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[1] / "benchmarks" / "readme.py"


@pytest.fixture(scope="module")
def generator():
    # benchmarks/ is a folder of scripts, not a package: load the script by its path. dataclasses look the
    # module up in sys.modules while the class bodies run, so it is registered before executing.
    spec = importlib.util.spec_from_file_location("benchmarks_readme", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    try:
        spec.loader.exec_module(module)
        yield module
    finally:
        del sys.modules[spec.name]


@pytest.fixture
def results_copy(generator, tmp_path: Path) -> Path:
    return Path(shutil.copytree(generator.RESULTS, tmp_path / "results"))


def test_readme_tables_match_the_results_files(generator):
    diff = generator.difference()
    assert not diff, f"README.md is stale: run `python benchmarks/readme.py`\n{diff}"


def test_a_changed_figure_in_a_results_file_is_noticed(generator, results_copy: Path):
    stereo = results_copy / "stereo.md"
    lines = stereo.read_text().splitlines()
    row = next(i for i, line in enumerate(lines)
               if line.startswith("| middlebury_stereo_v2eval/teddy | vmcl (dense, MRF) | nonocc |"))
    cells = lines[row].split("|")
    cells[5] = " 99.9 "  # the bad 1 column
    lines[row] = "|".join(cells)
    stereo.write_text("\n".join(lines) + "\n")
    added = [line for line in generator.difference(results_dir=results_copy).splitlines()
             if line.startswith("+") and not line.startswith("+++")]
    assert len(added) == 1 and "/ 99.9 /" in added[0], added


def test_a_renamed_row_fails_loudly(generator, results_copy: Path):
    motion = results_copy / "motion.md"
    motion.write_text(motion.read_text().replace("| mean of the 5 Middlebury pairs |", "| average |"))
    with pytest.raises(LookupError, match="mean of the 5 Middlebury pairs"):
        generator.generated_block(results_copy)


def test_a_readme_without_markers_is_refused(generator):
    with pytest.raises(LookupError, match="markers"):
        generator.rewritten("# no markers here\n", generator.generated_block())


def test_check_exits_1_with_a_diff_when_stale(generator, tmp_path: Path, monkeypatch, capsys):
    import re

    readme = generator.README.read_text()
    fps = re.search(r"\((\d+\.\d+) fps;", readme)
    assert fps is not None, "the pipeline row's frames per second moved: update this test"
    stale = tmp_path / "README.md"
    stale.write_text(readme.replace(fps.group(0), "(0.01 fps;"))
    monkeypatch.setattr(generator, "README", stale)
    assert generator.main(["--check"]) == 1
    removed = [line for line in capsys.readouterr().out.splitlines()
               if line.startswith("-") and not line.startswith("---")]
    assert len(removed) == 1 and "(0.01 fps;" in removed[0]
    assert stale.read_text().count("(0.01 fps;") == 1, "--check must not write"
