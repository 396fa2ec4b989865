"""Fitted parameter files: what they were fitted on, and a check that they are what was fitted.

Seed section "Learning and parameter estimation". A configuration that ``vmcl fit`` learns is a TOML file
that :meth:`vmcl.pipeline.Config.from_toml` loads like any other, plus a ``[fitted]`` table that says
where it came from: the data (each example's name and one SHA-256 over their files), the vmcl version and
a hash of the learning code, the method, the date, and the SHA-256 of the parameter tables themselves.
The fitted JSON artefacts vmcl ships (the labelling weights, the probability-of-boundary model) carry the
same record as a ``"fitted"`` object (:func:`write_fitted_json`, :func:`check_fitted_json`), whose hash is
checked the same way (their version is recorded, not warned about: they ship with the code they fit).
Loading checks that hash (a file whose parameters, every table but ``[fitted]``, were edited by hand or
damaged is refused with a sentence saying so: drop the ``[fitted]`` table to keep the edit as one's own
configuration) and warns (:class:`FittedVersionWarning`) when the file was fitted by another vmcl version or
does not say by which. The record's ``entries_sha256``, the SHA-256 of every entry vmcl wrote (that one left
out; their order and layout do not count), covers the record too: a file whose record (what, data, converged, fixed ...) was edited is refused
likewise (files written before vmcl recorded it have their parameters checked alone). Comments are not
entries, and load; but before replacing a file vmcl compares its whole text with what vmcl wrote
(:func:`check_writable`), so a file with any edit (a comment, a key added to the record) is left as it is.
"""

from __future__ import annotations

import datetime
import hashlib
import json
import math
import os
import warnings
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from vmcl.errors import InputTypeError, InputValueError
from vmcl.output_folder import replace_file

__all__ = ["FITTED_BY", "FittedVersionWarning", "check_fitted", "check_fitted_json", "check_writable", "code_sha256",
           "config_sha256", "files_sha256", "fitted_record", "parameters_sha256", "toml_values", "with_data",
           "write_fitted", "write_fitted_json"]

FITTED_BY = "vmcl fit"
"""The ``[fitted]`` table's ``written_by``: the mark of a file vmcl wrote, which it may replace."""

_HEADER = "# Parameters learned by `vmcl fit`; [fitted] says from what. Load with vmcl run --config."
_ENTRIES_KEY = "entries_sha256"


class FittedVersionWarning(UserWarning):
    """A fitted file was fitted by another vmcl version, or does not say by which."""


def parameters_sha256(tables: Mapping[str, Any]) -> str:
    """SHA-256 of the parameter tables in a canonical form (JSON, sorted keys), the same before writing
    and after TOML reads them back."""
    text = json.dumps(tables, sort_keys=True, separators=(",", ":"), allow_nan=False)
    return hashlib.sha256(text.encode()).hexdigest()


def files_sha256(paths: Iterable[Path]) -> str:
    """One SHA-256 over files, in the order given: each file's name and bytes."""
    digest = hashlib.sha256()
    for path in paths:
        digest.update(Path(path).name.encode() + b"\0")
        digest.update(Path(path).read_bytes())
    return digest.hexdigest()


def config_sha256(settings: Mapping[str, Any]) -> str:
    """SHA-256 of a Config's settings (:meth:`vmcl.pipeline.Config.to_dict`, or part of it): values JSON
    cannot hold are taken by their repr."""
    if not isinstance(settings, Mapping):
        raise InputTypeError(f"settings must be a mapping of a Config's sections, got {type(settings).__name__}")
    return parameters_sha256(json.loads(json.dumps(settings, default=repr)))


def code_sha256(*modules: Any) -> str:
    """SHA-256 of the source files of ``modules`` (modules or paths): the learning code's version."""
    paths = [Path(m) if isinstance(m, (str, Path)) else Path(m.__file__) for m in modules]
    return files_sha256(paths)


def check_fitted(values: dict[str, Any], source: str) -> dict[str, Any]:
    """A loaded configuration without its ``[fitted]`` table, once the table's hash is checked.

    Parameters
    ----------
    values : dict
        The TOML file's tables.
    source : str
        The file's name, for the messages.

    Raises
    ------
    InputValueError
        The table lacks its hash, the parameters differ from those fitted, or (where the record holds its
        ``entries_sha256``) any entry, the record's own included, differs from what vmcl wrote.
    """
    from vmcl import __version__

    if not isinstance(values, Mapping):
        raise InputTypeError(f"values must be the mapping of a TOML file's tables, got {type(values).__name__}")
    rest = {key: value for key, value in values.items() if key != "fitted"}
    fitted = values.get("fitted")
    if fitted is None:
        return rest
    _check_hash(rest, fitted, source, "the [fitted] table", "configuration")
    _check_entries(values, source, "the [fitted] table", "configuration")
    version = fitted.get("vmcl")
    if version != __version__:
        by = (f"was fitted by vmcl {version}" if version is not None else
              "does not say which vmcl version fitted it (its [fitted] table has no vmcl entry)")
        warnings.warn(f"{source} {by}, this is vmcl {__version__}: its parameters may not suit this version's "
                      "modules", FittedVersionWarning, stacklevel=3)
    return rest


def write_fitted(path: str | Path, tables: Mapping[str, Any], provenance: Mapping[str, Any]) -> Path:
    """Write parameter tables and their ``[fitted]`` table as TOML, replacing only a file vmcl fitted.

    Parameters
    ----------
    path : str or Path
        A new file, or one an earlier ``vmcl fit`` wrote (anything else is refused, untouched).
    tables : mapping
        Nested tables of numbers and strings (e.g. ``{"mrf": {"stereo": {...}}}``; NumPy scalars and tuples
        are written as :func:`toml_values` gives them).
    provenance : mapping
        The ``[fitted]`` entries besides those this adds (written_by, vmcl, date, parameters_sha256).

    Returns
    -------
    Path
        The file written (written beside it first, then moved into place).
    """
    target = check_writable(path)
    # Plain values first: the hashes are of what the file will hold, as TOML reads it back.
    tables = toml_values(tables)
    text = _sealed_text(toml_values({**tables, "fitted": fitted_record(tables, provenance)}), json_file=False)
    replace_file(target, lambda stream: stream.write(text.encode("utf-8")))
    return target


def _text(values: Mapping[str, Any], *, json_file: bool) -> str:
    """The text vmcl writes for a fitted file's ``values``: so that one read back can be told unedited by
    rendering it again."""
    if json_file:
        return json.dumps(values, indent=1, allow_nan=False) + "\n"
    return "\n".join([_HEADER, "", *_toml_tables(toml_values(values), ())]) + "\n"


def toml_values(value: Any, where: str = "") -> Any:
    """``value`` in the types a fitted TOML file holds: mappings as dicts, tuples and lists as lists, NumPy
    scalars as Python's, bools, ints, finite floats and strings as they are.

    Parameters
    ----------
    value : Any
        A fitted file's tables, or one of their values.
    where : str
        ``value``'s dotted key, which the refusal names ("" for a file's tables).

    Raises
    ------
    InputValueError
        A value TOML cannot hold (None, a float that is not finite, any other type), named by its key.
    """
    if not isinstance(where, str):
        raise InputTypeError(f"where must be a str, got {type(where).__name__}")
    if isinstance(value, Mapping):
        return {key: toml_values(item, f"{where}.{key}" if where else str(key)) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [toml_values(item, where) for item in value]
    if isinstance(value, np.generic):
        value = value.item()
    if value is None:
        raise InputValueError(f"{where or 'value'} is None, which a TOML file cannot hold")
    if not isinstance(value, (bool, int, float, str)):
        raise InputValueError(f"{where or 'value'} is {type(value).__name__} {value!r}, which a TOML file cannot hold")
    if isinstance(value, float) and not math.isfinite(value):
        raise InputValueError(f"{where or 'value'} must be finite to be written as a fitted value, got {value}")
    return value


def _entries_sha256(values: Mapping[str, Any]) -> str:
    """SHA-256 of every entry of ``values``, its record's ``entries_sha256`` left out, in the canonical form
    of :func:`parameters_sha256`: the order of the entries and the way they are written do not count
    (:func:`check_writable` compares the text itself)."""
    record = {key: value for key, value in values["fitted"].items() if key != _ENTRIES_KEY}
    return parameters_sha256({**values, "fitted": record})


def _sealed_text(values: Mapping[str, Any], *, json_file: bool) -> str:
    """The text of ``values`` with its record's ``entries_sha256``, so that an edit to the record is seen too."""
    record = {**values["fitted"], _ENTRIES_KEY: _entries_sha256(values)}
    return _text({**values, "fitted": record}, json_file=json_file)


def _check_entries(values: Mapping[str, Any], source: str, where: str, own: str) -> None:
    """Refuse a fitted file whose entries, record and all, are not those vmcl wrote (by its ``entries_sha256``;
    a file written before vmcl recorded one has its parameters checked alone)."""
    recorded = values["fitted"].get(_ENTRIES_KEY)
    if recorded is None:
        return
    try:
        found = _entries_sha256(values)
    except (TypeError, ValueError):  # entries vmcl never writes (a TOML date, NaN): not what was written
        found = None
    if found != recorded:
        raise InputValueError(f"{source}: its entries, {where} among them, differ from those `vmcl fit` wrote (their SHA-256 "
                              f"does not match the {_ENTRIES_KEY} of {where}): edited or damaged since; remove "
                              f"{where} to use it as your own {own}")


def fitted_record(parameters: Mapping[str, Any], provenance: Mapping[str, Any]) -> dict[str, Any]:
    """What a fitted file says of itself: written by ``vmcl fit``, the vmcl version, the date,
    ``provenance`` (what it was fitted on, by what code) and the SHA-256 of ``parameters``.

    ``provenance`` may give its own ``date`` (when the fit ran), which then stands.
    """
    from vmcl import __version__

    if not isinstance(provenance, Mapping):
        raise InputTypeError(f"provenance must be a mapping, got {type(provenance).__name__}")
    # The marks vmcl reads back (who wrote it, which version, what it hashed) are its own, whatever
    # provenance says.
    return {"date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"), **provenance,
            "written_by": FITTED_BY, "vmcl": __version__, "parameters_sha256": parameters_sha256(parameters)}


def with_data(data: str, provenance: Mapping[str, Any] | None) -> dict[str, Any]:
    """A fitted artefact's provenance: ``provenance`` (None: nothing more) with ``data``, what it was
    fitted on, unless ``provenance`` names its own."""
    if provenance is not None and not isinstance(provenance, Mapping):
        raise InputTypeError(f"provenance must be a mapping or None, got {type(provenance).__name__}")
    return {"data": data, **(provenance or {})}


def write_fitted_json(path: str | os.PathLike, parameters: Mapping[str, Any], provenance: Mapping[str, Any]) -> Path:
    """Write a fitted JSON artefact (the labelling weights, a boundary model): ``parameters`` and a
    ``"fitted"`` object (:func:`fitted_record`), replacing only a file vmcl fitted.

    Parameters
    ----------
    path : str or Path
        A new file, or one an earlier fit wrote (anything else is refused, untouched).
    parameters : mapping
        The artefact's entries, JSON-able (lists and numbers, no NaN).
    provenance : mapping
        What it was fitted on (``data``, ``data_sha256``, ``code_sha256`` ...).

    Returns
    -------
    Path
        The file written (written beside it first, then moved into place).
    """
    if not isinstance(parameters, Mapping):
        raise InputTypeError(f"parameters must be a mapping, got {type(parameters).__name__}")
    if "fitted" in parameters:
        raise InputValueError("parameters must not have a 'fitted' entry: the record is added here")
    target = check_writable(path)
    try:
        text = _sealed_text({**parameters, "fitted": fitted_record(parameters, provenance)}, json_file=True)
    except (TypeError, ValueError) as error:
        raise InputValueError(f"parameters and provenance must be plain JSON values (numbers, strings, lists, "
                              f"mappings; no NaN): {error}") from None
    replace_file(target, lambda stream: stream.write(text.encode("utf-8")))
    return target


def check_fitted_json(data: Mapping[str, Any], source: str) -> dict[str, Any] | None:
    """The ``"fitted"`` record of a loaded JSON artefact, once checked against its other entries; None for
    a file without one (the user's own, used as it is).

    Raises
    ------
    InputValueError
        The record lacks its hash, or the entries differ from those fitted (edited or damaged).
    """
    if not isinstance(data, Mapping):
        raise InputTypeError(f"data must be the mapping of a JSON file's entries, got {type(data).__name__}")
    record = data.get("fitted")
    if record is None:
        return None
    _check_hash({key: value for key, value in data.items() if key != "fitted"}, record, source,
                "its 'fitted' record", "file")
    _check_entries(data, source, "its 'fitted' record", "file")
    return dict(record)


def _check_hash(rest: Mapping[str, Any], record: Any, source: str, where: str, own: str) -> None:
    """Refuse a fitted file whose entries other than the record (``rest``) are not those it hashed."""
    if not isinstance(record, Mapping) or not isinstance(record.get("parameters_sha256"), str):
        raise InputValueError(f"{source}: {where} has no parameters_sha256, so what was fitted cannot be checked")
    try:
        found = parameters_sha256(rest)
    except (TypeError, ValueError):  # entries JSON cannot hold: not what was fitted
        found = None
    if found != record["parameters_sha256"]:
        raise InputValueError(f"{source}: its parameters differ from those fitted (their SHA-256 does not match "
                              f"the parameters_sha256 of {where}): edited or damaged since `vmcl fit` wrote it; "
                              f"remove {where} to use it as your own {own}")


def check_writable(path: str | os.PathLike) -> Path:
    """``path`` as a Path, if :func:`write_fitted` or :func:`write_fitted_json` may write it: a new file in an
    existing folder, or a plain, writable file ``vmcl fit`` wrote and nobody edited since: its text exactly
    what vmcl wrote, parameters, record, comments and all (checked before any fitting, so that a refusal
    costs no work).

    Raises
    ------
    InputValueError
        The file exists and is someone else's, or was edited since vmcl wrote it, or is a link or read-only;
        or its folder does not exist.
    """
    if not isinstance(path, (str, os.PathLike)):
        raise InputTypeError(f"path must be a str or a path, got {type(path).__name__}")
    target = Path(path)
    if not target.parent.is_dir():
        raise InputValueError(f"{target}: its folder {target.parent} does not exist")
    if target.is_symlink():
        raise InputValueError(f"{target} is a link: vmcl replaces only plain files it wrote; choose a new name")
    if not target.exists():
        return target
    written = _written_by_vmcl(target)
    if written is None:
        raise InputValueError(f"{target} exists and is not a file `vmcl fit` wrote: choose a new name")
    if not written:
        raise InputValueError(f"{target} was written by `vmcl fit` and edited since: vmcl would lose the edit; move "
                              "it away or choose a new name")
    # By its mode, not by access(): a user who made the file read-only meant it, even for root.
    if not target.stat().st_mode & 0o222 or not os.access(target, os.W_OK):
        raise InputValueError(f"{target} is read-only: vmcl leaves it as it is; choose a new name")
    return target


def _written_by_vmcl(path: Path) -> bool | None:
    """True for a file vmcl fit wrote whose text is still the text vmcl wrote (its record matching its
    parameters), False for one edited since, None for anyone else's."""
    from vmcl.pipeline import tomllib

    try:
        text = path.read_text(encoding="utf-8")
        values = json.loads(text) if path.suffix == ".json" else tomllib.loads(text)
    except (OSError, UnicodeDecodeError, ValueError):  # JSON's and TOML's decode errors are ValueErrors
        return None
    if not isinstance(values, Mapping):
        return None
    fitted = values.get("fitted")
    if not (isinstance(fitted, Mapping) and fitted.get("written_by") == FITTED_BY):
        return None
    try:
        with warnings.catch_warnings():  # another version's fit is still vmcl's own file
            warnings.simplefilter("ignore")
            (check_fitted_json if path.suffix == ".json" else check_fitted)(dict(values), str(path))
    except (InputTypeError, InputValueError):
        return False
    # The hash covers the parameters alone: a note, a comment or a changed record would be lost in silence.
    try:
        return _text(values, json_file=path.suffix == ".json") == text
    except (TypeError, ValueError):  # values vmcl never writes (TOML dates, NaN): not its text
        return False


def _toml_tables(tables: Mapping[str, Any], prefix: tuple[str, ...]) -> list[str]:
    scalars = {k: v for k, v in tables.items() if not isinstance(v, Mapping)}
    out = []
    if scalars and prefix:
        out.append(f"[{'.'.join(prefix)}]")
        out += [f"{key} = {_toml_value(value)}" for key, value in scalars.items()]
        out.append("")
    for key, value in tables.items():
        if isinstance(value, Mapping):
            out += _toml_tables(value, (*prefix, key))
    return out


def _toml_value(value: Any) -> str:
    """A value :func:`toml_values` gave, in TOML's syntax (which values a file holds is decided there)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return json.dumps(value)  # a TOML basic string: JSON's escapes are TOML's
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    return repr(value)  # an int, or a finite float
