"""What a fitted TOML file holds (vmcl.fitted.toml_values): the one check that `vmcl fit`'s tables and the
file writer share, so that a setting the file cannot hold is refused by its key before any fitting."""

import math

import numpy as np
import pytest

from vmcl import fitted
from vmcl.errors import InputValueError


def test_numpy_scalars_and_tuples_become_plain_toml_values():
    values = fitted.toml_values({"stereo": {"window": np.int64(5), "sigma": np.float32(0.5), "on": np.bool_(True),
                                            "range": (0, 16), "name": "x"}})
    assert values == {"stereo": {"window": 5, "sigma": 0.5, "on": True, "range": [0, 16], "name": "x"}}
    assert [type(v) for v in values["stereo"].values()] == [int, float, bool, list, str]


@pytest.mark.parametrize("value, message", [(None, "stereo.window is None"), (math.inf, "stereo.window must be finite"),
                                            (object(), "stereo.window is object")])
def test_a_value_toml_cannot_hold_is_refused_by_its_key(value, message):
    with pytest.raises(InputValueError, match=message):
        fitted.toml_values({"stereo": {"window": value}})


def test_the_writer_writes_numpy_values_as_plain_ones(tmp_path):
    # The writer hashes and renders what toml_values gives: a NumPy integer failed in the hash, not JSON's.
    path = fitted.write_fitted(tmp_path / "x.toml", {"mrf": {"stereo": {"alpha": 0.5}}}, {"sites": (np.int64(3), 4)})
    assert "sites = [3, 4]" in path.read_text()
