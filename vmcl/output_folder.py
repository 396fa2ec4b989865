"""Output folders vmcl writes: only its own files, replaced whole or not at all.

vmcl writes only its own files. An output folder must be a new folder, an empty one, or a previous vmcl
output, which vmcl knows by the file :data:`MARKER` listing the files it wrote there; anything else is
refused before any work starts. The files are written into a hidden folder beside the output and moved
into place only when all are written; replacing a previous output touches only the files it lists, and
puts them back if the move fails or is interrupted part way. A new folder gets the mode the umask
gives; an existing one keeps its own. Single files vmcl owns (a model, a fitted configuration) are
replaced the same way (:func:`replace_file`).
"""

from __future__ import annotations

import contextlib
import os
import secrets
import shutil
import socket
import struct
import zipfile
from collections.abc import Callable, Iterator, Sequence
from glob import escape as glob_escape
from pathlib import Path
from typing import BinaryIO

from vmcl.errors import InputTypeError, InputValueError

__all__ = ["MARKER", "is_whole", "output_folder", "refuse_names_present", "replace_file"]

MARKER = ".vmcl-output"
"""The file that marks a folder as a vmcl output: the names of the files vmcl wrote there, one a line."""

_MARKER_HEADER = "# Written by vmcl: the files it wrote here, which its next run into this folder replaces.\n"


@contextlib.contextmanager
def output_folder(out: Path) -> Iterator[Path]:
    """A hidden folder beside ``out`` to write into; its files replace ``out``'s when the block succeeds.

    ``out`` is checked at once (before the run that fills it): it must be new, empty or a previous vmcl
    output (see the module's docstring), and its parent writable. The hidden folder and any parent
    folders made for ``out`` vanish if the block fails or is interrupted; those of runs into ``out`` on this
    machine that were killed where they stood (SIGKILL) are removed first.
    """
    out = out.resolve()  # the hidden folders go beside the real folder, on its file system
    _previous_output(out)
    _remove_stale_partials(out)
    missing = [folder for folder in (out.parent, *out.parent.parents) if not folder.exists()]
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        work = _hidden_folder(out, "partial")
    except OSError as error:
        _remove_empty(missing)
        raise InputValueError(f"--out {out}: cannot write into {out.parent} ({error.strerror})") from None
    if out.is_dir() and not os.access(out, os.W_OK | os.X_OK):
        _remove_empty([work, *missing])
        raise InputValueError(f"--out {out}: the folder is not writable")
    done = False
    try:
        yield work
        _move_in(work, out)
        done = True
    finally:
        shutil.rmtree(work, ignore_errors=True)
        if not done:
            _remove_empty(missing)


def _previous_output(out: Path) -> list[str]:
    """The files a previous vmcl output at ``out`` holds ([] for a new or empty folder); refuses others."""
    if not out.exists():
        return []
    if not out.is_dir():
        raise InputValueError(f"--out {out} exists and is not a folder")
    try:
        present = {entry.name for entry in out.iterdir()}
    except OSError as error:
        raise InputValueError(f"--out {out}: cannot list the folder ({error.strerror})") from None
    if not present:
        return []
    if MARKER not in present:
        raise InputValueError(f"--out {out} is not empty and is not a vmcl output (it has no {MARKER}); vmcl writes "
                       "only its own files: name a new or empty folder")
    listed = _listed(out)
    foreign = sorted(present - set(listed) - {MARKER})
    if foreign:
        shown = ", ".join(foreign[:3]) + (f" and {len(foreign) - 3} more" if len(foreign) > 3 else "")
        raise InputValueError(f"--out {out} holds files vmcl did not write ({shown}); vmcl replaces only its own "
                       "output: move them away or name another folder")
    return sorted(set(listed) & present)


def is_whole(out: Path) -> bool:
    """Whether ``out`` holds a whole vmcl output: its :data:`MARKER`, every file the marker lists, and each
    listed NumPy archive (``.npz``) with its whole directory of members, each within the file (a file
    deleted, emptied or cut short since vmcl wrote it is not to be trusted). The members' contents are not
    read: vmcl writes each file whole or not at all (:func:`replace_file`), and a batch resuming over many
    items read every byte of every one of them."""
    if not (out / MARKER).is_file():
        return False
    try:
        names = _listed(out)
        for name in names:
            if not (out / name).is_file():
                return False
            if name.endswith(".npz") and not _members_in_place(out / name):
                return False
    except (InputValueError, OSError, zipfile.BadZipFile, EOFError, ValueError):
        return False
    return True


def _members_in_place(path: Path) -> bool:
    """Whether a zip archive (an ``.npz``) has its directory (at its end: a file cut short has none) and each
    member's own header where the directory places it, with the member's data before the file's end."""
    size = path.stat().st_size
    with zipfile.ZipFile(path) as archive, path.open("rb") as raw:
        for info in archive.infolist():
            raw.seek(info.header_offset)
            header = raw.read(30)
            if len(header) < 30 or header[:4] != b"PK\x03\x04":
                return False
            name_length, extra_length = struct.unpack("<HH", header[26:30])
            if info.header_offset + 30 + name_length + extra_length + info.compress_size > size:
                return False
    return True


def _listed(out: Path) -> list[str]:
    """The file names :data:`MARKER` lists, each a plain file of ``out``'s (vmcl writes no others)."""
    try:
        lines = (out / MARKER).read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError) as error:
        raise InputValueError(f"--out {out}: cannot read its {MARKER} ({error})") from None
    names = [line for line in lines if line and not line.startswith("#")]
    for name in names:
        if name in (".", "..") or name.startswith(MARKER) or "/" in name or os.sep in name or (out / name).is_dir():
            raise InputValueError(f"--out {out}: its {MARKER} lists {name!r}, which is not a file vmcl writes")
    return names


def refuse_names_present(folder: Path, ours: Callable[[str], bool], what: str) -> None:
    """Refuse (InputValueError) to write ``what`` into ``folder`` when it already holds an entry whose name
    ``ours`` claims: vmcl never overwrites a file it did not write, and a link of such a name, even one to
    nothing, would be written through to its target. A folder that does not exist yet (or is no folder:
    the caller's own making of it says so) holds nothing."""
    if not isinstance(folder, (str, os.PathLike)):
        raise InputTypeError(f"folder must be a path, got {type(folder).__name__}")
    # vmcl's names are lower case; a name that is one of them but for its case is the same file where the file
    # system ignores case (macOS, Windows), and refused everywhere alike.
    try:
        taken = sorted(entry.name for entry in Path(folder).iterdir() if ours(entry.name) or ours(entry.name.lower()))
    except (FileNotFoundError, NotADirectoryError):
        return
    if taken:
        shown = ", ".join(taken[:3]) + (f" and {len(taken) - 3} more" if len(taken) > 3 else "")
        raise InputValueError(f"folder {folder} already holds {shown}; write {what} into a new or empty folder "
                              "(the vmcl command replaces its own previous output)")


def replace_file(target: Path, write: Callable[[BinaryIO], object]) -> None:
    """Write ``target`` whole or not at all: ``write`` fills a new hidden file beside it (created
    exclusively, with the umask's mode, so no other file is touched), which is then moved over ``target``.
    A reader never sees half a file; a failed or interrupted write leaves the old one and removes only the
    file it created."""
    while True:
        partial = target.parent / f".{target.name}.{secrets.token_hex(4)}.partial"
        try:
            stream = open(partial, "xb")  # noqa: SIM115 - closed below, before the move
            break
        except FileExistsError:
            continue
    try:
        with stream:
            write(stream)
        os.replace(partial, target)
    except BaseException:
        partial.unlink(missing_ok=True)
        raise


def _hidden_folder(out: Path, kind: str) -> Path:
    """A new hidden folder beside ``out``, made with the umask's mode (mkdtemp's would be 0700), named with
    this machine and process (so that a later run can tell one a killed run left behind)."""
    while True:
        folder = out.parent / f".{out.name}.{kind}-{_owner()}-{secrets.token_hex(4)}"
        try:
            folder.mkdir()
            return folder
        except FileExistsError:
            continue


def _owner() -> str:
    """This machine's name and this process's id, as hidden folders are named with them."""
    return f"{''.join(c if c.isalnum() else '_' for c in socket.gethostname())}.{os.getpid()}"


def _remove_stale_partials(out: Path) -> None:
    """Remove the partial folders beside ``out`` that a run on this machine left when it was killed where it
    stood (SIGKILL: no handler runs): each names its machine and process, and the process is gone. Another
    machine's (a shared file system) or a live process's are left alone, and so is every other folder."""
    host = _owner().rsplit(".", 1)[0]
    for folder in out.parent.glob(f".{glob_escape(out.name)}.partial-{glob_escape(host)}.*-*"):
        pid = folder.name[len(f".{out.name}.partial-{host}."):].split("-", 1)[0]
        if not pid.isdigit() or not folder.is_dir() or folder.is_symlink():
            continue
        try:
            os.kill(int(pid), 0)
        except ProcessLookupError:
            shutil.rmtree(folder, ignore_errors=True)
        except (PermissionError, OverflowError):  # alive under another user, or no pid at all
            continue


def _remove_empty(folders: Sequence[Path]) -> None:
    """Remove these folders, nearest first, while they are empty (those made for a run that failed)."""
    for folder in folders:
        try:
            folder.rmdir()
        except OSError:
            return


def _write_marker(path: Path, names: Sequence[str]) -> None:
    path.write_text(_MARKER_HEADER + "".join(f"{name}\n" for name in sorted(names)), encoding="utf-8")


def _move_in(work: Path, out: Path) -> None:
    """Put ``work``'s files in ``out``: a rename of the folder if ``out`` is new, else file by file.

    File by file, the marker first lists the old and new files together, so that every state on the way
    is a vmcl output the next run would take; the old files are moved aside, the new ones in, and the old
    ones deleted only at the end. On any error or interrupt the moves are undone from what is on disk
    (a rename may have completed just before an interrupt arrived).
    """
    new = sorted(entry.name for entry in work.iterdir())
    if not out.exists():
        _write_marker(work / MARKER, new)
        os.replace(work, out)
        return
    previous = _previous_output(out)  # again: the folder may have changed during the run
    old_marker = (out / MARKER).read_bytes() if (out / MARKER).exists() else None
    aside = _hidden_folder(out, "old")
    try:
        _write_marker(aside / f"{MARKER}.both", sorted(set(previous) | set(new)))
        os.replace(aside / f"{MARKER}.both", out / MARKER)
        for name in previous:
            os.replace(out / name, aside / name)
        for name in new:
            os.replace(work / name, out / name)
        _write_marker(aside / f"{MARKER}.new", new)
        os.replace(aside / f"{MARKER}.new", out / MARKER)
    except BaseException:
        _undo_move_in(work, out, aside, previous, new, old_marker)
        raise
    shutil.rmtree(aside)


def _undo_move_in(work: Path, out: Path, aside: Path, previous: Sequence[str], new: Sequence[str],
                  old_marker: bytes | None) -> None:
    """Put the previous output back as it was; ``aside`` is removed only once it holds none of it."""
    for name in new:
        if (out / name).exists() and not (work / name).exists():
            os.replace(out / name, work / name)
    for name in previous:
        if (aside / name).exists():
            os.replace(aside / name, out / name)
    if old_marker is None:
        (out / MARKER).unlink(missing_ok=True)
    else:
        (aside / f"{MARKER}.old").write_bytes(old_marker)
        os.replace(aside / f"{MARKER}.old", out / MARKER)
    shutil.rmtree(aside)
