"""vmcl.sequence_output: the sequence writer writes only its own files."""

import re

import pytest

from vmcl.errors import InputError
from vmcl.sequence_output import SequenceWriter


@pytest.mark.parametrize("name", ["fields_000000.npz", "fields_000041.npz", "sequence.md", "cartoon.mp4"])
def test_a_folder_holding_a_name_it_writes_is_refused_before_anything_is_written(tmp_path, name):
    (tmp_path / name).write_bytes(b"the user's own")
    with pytest.raises(InputError, match=re.escape(f"folder {tmp_path} already holds {name}")):
        SequenceWriter(tmp_path, fps=5.0, title="t")
    assert [p.name for p in tmp_path.iterdir()] == [name] and (tmp_path / name).read_bytes() == b"the user's own"


def test_a_link_to_nothing_is_a_name_taken_and_other_files_are_left_to_be(tmp_path):
    elsewhere = tmp_path.parent / f"{tmp_path.name}-elsewhere.md"
    (tmp_path / "sequence.md").symlink_to(elsewhere)
    with pytest.raises(InputError, match="already holds sequence.md"):
        SequenceWriter(tmp_path, fps=5.0, title="t")
    (tmp_path / "sequence.md").unlink()
    for name in ("fields.npz", "fields_1.npz", "notes.md", "holiday.mp4"):  # none of them its own
        (tmp_path / name).write_bytes(b"the user's own")
    writer = SequenceWriter(tmp_path, fps=5.0, title="t")
    writer.close()  # no frame: only the summary
    assert (tmp_path / "sequence.md").read_text(encoding="utf-8").startswith("# t\n")
    assert not elsewhere.exists()
