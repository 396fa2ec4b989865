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


@pytest.fixture(scope="session")
def machine():
    """The Machine the tests run on: VMCL_DEVICE picks the device, as it does for users."""
    from vmcl import default_machine

    return default_machine()


@pytest.fixture(scope="session", params=[1, 7, 64])
def machine_with_local_size(request):
    """Machines that force odd work-group sizes: results must not depend on them."""
    from vmcl import Machine

    return Machine(local_size=request.param)
