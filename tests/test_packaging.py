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


def test_every_data_file_of_the_packages_ships_in_the_wheel():
    data = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["package-data"]
    for top in ("vmcl", "hardware"):
        for found in (ROOT / top).rglob("*.json"):
            package = ".".join(found.parent.relative_to(ROOT).parts)
            assert found.name in data.get(package, []), f"{found.relative_to(ROOT)} is not in pyproject's package-data"
