"""The wheel holds every package: pyproject.toml's explicit package list names each folder of vmcl and
hardware that has an __init__.py (an editable install, which `make setup` makes, would hide a missing one)."""

import sys
from pathlib import Path

if sys.version_info >= (3, 11):
    import tomllib
else:
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[1]


def test_every_package_is_listed_for_the_wheel():
    listed = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    found = {".".join(init.parent.relative_to(ROOT).parts) for top in ("vmcl", "hardware")
             for init in (ROOT / top).rglob("__init__.py")}
    assert found - listed == set(), f"packages missing from pyproject.toml's list: {sorted(found - listed)}"
