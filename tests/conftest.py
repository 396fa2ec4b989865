"""Shared pytest fixtures."""

from pathlib import Path

import pytest


@pytest.fixture(scope="session")
def datasets_root() -> Path:
    """The third-party evaluation data at ../shared/datasets, or a skip when this checkout lacks it."""
    root = (Path(__file__).resolve().parents[1] / ".." / "shared" / "datasets").resolve()
    if not root.is_dir():
        pytest.skip(f"evaluation data not found at {root} (see the README's data section)")
    return root
