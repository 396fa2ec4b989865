"""Distance doubling: list ranking, ring principals, and connected components against scipy."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import ndimage

from vmcl.cm.doubling import label, principal, principal_from_predecessors, rank
from vmcl.errors import InputValueError
from vmcl.patterns import spiral

STRUCTURE = {4: ndimage.generate_binary_structure(2, 1), 8: ndimage.generate_binary_structure(2, 2)}


def _lists(rng, n, count):
    """Random disjoint lists over 0..n-1: next pointers, and the rank and tail of every node."""
    order = rng.permutation(n)
    cuts = np.sort(rng.choice(np.arange(1, n), size=min(count, n) - 1, replace=False)) if n > 1 else []
    nxt, ranks, tails = np.full(n, -1, np.int32), np.zeros(n, np.int32), np.zeros(n, np.int32)
    for piece in np.split(order, cuts):
        nxt[piece[:-1]] = piece[1:]
        ranks[piece] = np.arange(len(piece))[::-1]
        tails[piece] = piece[-1]
    return nxt, ranks, tails


def _rings(rng, n, count):
    nxt, _, _ = _lists(rng, n, count)
    heads = np.setdiff1d(np.arange(n), nxt[nxt >= 0])
    tails = np.flatnonzero(nxt < 0)
    ring_of_tail = {}
    for head in heads:  # close every list into a ring: tail -> head
        node = head
        while nxt[node] >= 0:
            node = nxt[node]
        ring_of_tail[node] = head
    for tail in tails:
        nxt[tail] = ring_of_tail[tail]
    expected_principal, expected_distance = np.zeros(n, np.int32), np.zeros(n, np.int32)
    for head in heads:
        members = [head]
        while nxt[members[-1]] != head:
            members.append(nxt[members[-1]])
        top = members.index(max(members))
        members = members[top:] + members[:top]
        expected_principal[members] = members[0]
        expected_distance[members] = np.arange(len(members))
    return nxt, expected_principal, expected_distance


@pytest.mark.parametrize("n, count", [(1, 1), (2, 1), (17, 3), (1000, 1), (5000, 40)])
def test_list_ranking(n, count, machine):
    nxt, ranks, tails = _lists(np.random.default_rng(n), n, count)
    got_rank, got_tail = rank(nxt, machine=machine)
    np.testing.assert_array_equal(got_rank, ranks)
    np.testing.assert_array_equal(got_tail, tails)


@pytest.mark.parametrize("nxt", [[1, 2, 2], [1, 2, 0], [-1, 2, 1]])
def test_list_ranking_refuses_a_cycle_naming_next(nxt, machine):
    # A self-loop at the end, a whole cycle, and a list beside a cycle: the jumps would give wrong ranks.
    with pytest.raises(InputValueError, match="next must form lists that end"):
        rank(np.array(nxt, np.int32), machine=machine)


@pytest.mark.parametrize("n, count", [(1, 1), (2, 1), (8, 1), (999, 1), (5000, 37)])
def test_ring_principal_and_distance(n, count, machine, machine_with_local_size):
    nxt, expected_principal, expected_distance = _rings(np.random.default_rng(n + 1), n, count)
    for m in (machine, machine_with_local_size):
        got_principal, got_distance = principal(nxt, machine=m)
        np.testing.assert_array_equal(got_principal, expected_principal)
        np.testing.assert_array_equal(got_distance, expected_distance)


@pytest.mark.parametrize("n, count", [(1, 1), (2, 1), (8, 1), (999, 1), (5000, 37)])
def test_principal_from_predecessors_matches_the_rings_given_forwards(n, count, machine):
    rng = np.random.default_rng(n + 2)
    nxt, expected_principal, expected_distance = _rings(rng, n, count)
    prev = np.empty(n, np.int32)
    prev[nxt] = np.arange(n, dtype=np.int32)
    got_principal, got_distance = principal_from_predecessors(prev, machine=machine)
    np.testing.assert_array_equal(got_principal, expected_principal)
    np.testing.assert_array_equal(got_distance, expected_distance)
    # With keys, on the device and unchecked as a kernel's own rings are: the largest key's node leads.
    keys = rng.permutation(n).astype(np.int32)
    forwards = principal(nxt, keys=keys, machine=machine)
    backwards = principal_from_predecessors(machine.to_device(prev), keys=machine.to_device(keys), check=False,
                                            machine=machine)
    for want, got in zip(forwards, backwards):
        np.testing.assert_array_equal(got.get(), want)


def _check_labels(mask, connectivity, labels):
    reference, count = ndimage.label(mask, STRUCTURE[connectivity])
    flat = reference.ravel()
    assert np.all((labels.ravel() < 0) == (flat == 0))
    maxima = ndimage.maximum(np.arange(mask.size), flat, index=np.arange(1, count + 1)).astype(np.int64)
    np.testing.assert_array_equal(labels.ravel()[flat > 0], maxima[flat[flat > 0] - 1])


@settings(max_examples=40, deadline=None)
@given(height=st.integers(1, 60), width=st.integers(1, 60), density=st.sampled_from([0.2, 0.5, 0.6, 0.9]),
       connectivity=st.sampled_from([4, 8]), seed=st.integers(0, 2**31))
def test_label_is_the_max_address_of_each_component(height, width, density, connectivity, seed, machine):
    mask = np.random.default_rng(seed).random((height, width)) < density
    doubled = label(mask, connectivity=connectivity, machine=machine)
    _check_labels(mask, connectivity, doubled)
    np.testing.assert_array_equal(label(mask, connectivity=connectivity, method="iterative", machine=machine),
                                  doubled)


@pytest.mark.parametrize("connectivity", [4, 8])
@pytest.mark.parametrize("height, width", [(1, 1), (1, 63), (63, 1), (70, 129), (130, 64)])
def test_rows_with_the_most_runs(height, width, connectivity, machine):
    """Checkerboards and stripes fill rows with runs of one pixel, ceil(width / 2) of them, which is as
    many as a row can hold: diagonal chains with 8-connectivity, isolated pixels or lines with 4."""
    y, x = np.mgrid[:height, :width]
    for mask in ((x + y) % 2 == 0, (x + y) % 2 == 1, x % 2 == 0, y % 2 == 0):
        _check_labels(mask, connectivity, label(mask, connectivity=connectivity, machine=machine))


@pytest.mark.parametrize("connectivity", [4, 8])
def test_any_non_zero_value_is_foreground(connectivity, machine):
    rng = np.random.default_rng(11)
    mask = rng.random((64, 48)) < 0.6
    values = np.where(mask, rng.integers(1, 256, mask.shape), 0).astype(np.uint8)
    np.testing.assert_array_equal(label(values, connectivity=connectivity, machine=machine),
                                  label(mask, connectivity=connectivity, machine=machine))
    _check_labels(mask, connectivity, label(values, connectivity=connectivity, machine=machine))


@pytest.mark.parametrize("connectivity", [4, 8])
def test_relabel_numbers_components_by_principal(connectivity, machine):
    mask = np.random.default_rng(7).random((300, 211)) < 0.55
    principals = label(mask, connectivity=connectivity, machine=machine)
    numbered = label(mask, connectivity=connectivity, relabel=True, machine=machine)
    order = np.unique(principals[principals >= 0])
    expected = np.zeros(mask.shape, np.int32)
    expected[principals >= 0] = np.searchsorted(order, principals[principals >= 0]) + 1
    np.testing.assert_array_equal(numbered, expected)


@pytest.mark.parametrize("corridor", [1, 3])
def test_spiral_is_one_component(corridor, machine):
    mask = spiral(256, corridor=corridor)
    _reference, count = ndimage.label(mask, STRUCTURE[4])
    assert count == 1 and mask.sum() > 256**2 // 3
    _check_labels(mask, 4, label(mask, connectivity=4, machine=machine))
    small = spiral(40, corridor=corridor)
    np.testing.assert_array_equal(label(small, connectivity=4, method="iterative", machine=machine),
                                  label(small, connectivity=4, machine=machine))


def test_large_random_field_and_repeatability(machine, machine_with_local_size):
    mask = np.random.default_rng(8).random((2048, 2048)) < 0.5
    labels = label(mask, machine=machine)
    _check_labels(mask, 8, labels)
    np.testing.assert_array_equal(label(mask, machine=machine), labels)
    small = mask[:200, :333]
    np.testing.assert_array_equal(label(small, machine=machine_with_local_size), label(small, machine=machine))


@pytest.mark.parametrize("call, error, match", [
    (lambda m: rank(np.array([1, 5], np.int32), machine=m), ValueError, r"next must hold addresses in \[-1, 1\]"),
    (lambda m: principal(np.array([1, 1], np.int32), machine=m), ValueError, "permutation"),
    (lambda m: principal(np.array([-1, 0], np.int32), machine=m), ValueError, "next must hold addresses"),
    (lambda m: principal_from_predecessors(np.array([0, 0], np.int32), machine=m), ValueError,
     "prev must be a permutation .every node the predecessor"),
    (lambda m: principal_from_predecessors(np.array([2, 0], np.int32), machine=m), ValueError,
     "prev must hold addresses"),
    (lambda m: principal_from_predecessors(np.array([1, 0], np.int32), keys=np.array([3, 3], np.int32), machine=m),
     ValueError, "keys must be distinct"),
    (lambda m: rank(np.zeros(0, np.int32), machine=m), ValueError, "next must not be empty"),
    (lambda m: label(np.zeros((3, 3), bool), connectivity=6, machine=m), ValueError, "connectivity must be 4 or 8"),
    (lambda m: label(np.zeros(3, bool), machine=m), ValueError, "mask must have 2 dimensions"),
    (lambda m: label(np.zeros((3, 3), np.float32), machine=m), TypeError, "mask must have dtype"),
    (lambda m: label(np.zeros((3, 3), bool), method="fast", machine=m), ValueError, "method must be"),
])
def test_bad_input_is_named(call, error, match, machine):
    with pytest.raises(error, match=match):
        call(machine)


@pytest.mark.parametrize("kwargs, error, match", [
    ({"relabel": "no"}, TypeError, "relabel must be a bool"),
    ({"relabel": 0}, TypeError, "relabel must be a bool"),
    ({"relabel": None}, TypeError, "relabel must be a bool"),
    ({"connectivity": 8.0}, TypeError, "connectivity must be an integer"),
    ({"connectivity": "8"}, TypeError, "connectivity must be an integer"),
    ({"method": ["doubling"]}, TypeError, "method must be one of"),
])
def test_label_refuses_arguments_by_type(kwargs, error, match, machine):
    """relabel="no" used to relabel (a non-empty string is true) and connectivity=8.0 to compile."""
    from vmcl.errors import InputError

    with pytest.raises(error, match=match) as raised:
        label(np.eye(4, dtype=bool), machine=machine, **kwargs)
    assert isinstance(raised.value, InputError)
