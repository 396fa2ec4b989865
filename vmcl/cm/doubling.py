"""Distance doubling: pointer jumping on lists and rings, and connected components of binary fields.

Seed section "Powerful primitive operations" (Distance Doubling): every processor holds the address of
the next one; in each step it combines the value of the processor it points to and then points to that
processor's target, so after step k it knows the 2^k processors ahead. With max over the addresses
this finds the *principal* (the largest address) of every ring in O(log N) steps, and with plus the
distance of every node from it. "Edge detection" uses the same idea to bring Canny's hysteresis from
O(m) spreading activation down to O(log m).

References
----------
J. C. Wyllie, "The complexity of parallel computations", Cornell TR 79-387, 1979.
O. Playne and K. Hawick, "A new algorithm for parallel connected-component labelling on GPUs",
IEEE TPDS 29(6), 2018 (the union-find with pointer jumping used by :func:`label`).
L. He, Y. Chao and K. Suzuki, "A run-based two-scan labeling algorithm", IEEE TIP 17(5), 2008 (runs,
not pixels, as the elements of the union-find).
"""

from __future__ import annotations

import math
from typing import Literal, overload

import numpy as np
import pyopencl as cl
import pyopencl.array as cl_array

from vmcl.cm import reduce as _reduce
from vmcl.cm.core import (
    ArrayLike,
    bool_as_bytes,
    check_bool,
    check_choice,
    check_int,
    field,
    machine_for,
    result,
)
from vmcl.cm.scan import exclusive_sum_into
from vmcl.errors import InputValueError
from vmcl.machine import Machine

__all__ = ["LabelMethod", "label", "principal", "principal_from_predecessors", "rank"]

LabelMethod = Literal["doubling", "iterative"]
_CHECK_EVERY = 16  # spreading-activation passes between reads of the "changed" flag
_STEPS_PER_LAUNCH = 2  # doubling steps folded into one launch of principal_steps


def _steps(n: int) -> int:
    return max(1, math.ceil(math.log2(n))) if n > 1 else 0


def _pointers(next: ArrayLike, machine: Machine, *, lowest: int, name: str = "next") -> tuple[cl_array.Array, bool]:
    data, host = field(next, name, machine, ndims=(1,), dtypes=(np.int32,))
    n = data.size
    low, high = (int(_reduce.reduce(data, op, machine=machine).get()) for op in ("min", "max"))
    if low < lowest or high >= n:
        raise InputValueError(f"{name} must hold addresses in [{lowest}, {n - 1}], got values in [{low}, {high}]")
    return data, host


def _kernel(machine: Machine, name: str, *, op: int = 0, connectivity: int = 8, instance: int = 0) -> cl.Kernel:
    """A kernel of kernels/doubling.cl, always built with both of its defines (OP: 0 plus, 1 max;
    CONNECTIVITY), though each kernel reads at most one: kernels taken at the same values then share one
    build, as the list kernels and 8-connected labelling do (one program on a first run, not two)."""
    return machine.kernel_instance(instance, "doubling", name, OP=op, CONNECTIVITY=connectivity)


def _jump(machine: Machine, value: cl_array.Array, pointer: cl_array.Array, op: int) -> tuple:
    """ceil(log2 n) doubling steps; returns (value, pointer). The inputs are never written: the steps
    ping-pong between two pairs of pooled buffers."""
    n = value.size
    kernel = _kernel(machine, "jump_step", op=op)
    pairs = [(machine.empty(n, np.int32), machine.empty(n, np.int32)) for _ in range(2)]
    for step in range(_steps(n)):
        target = pairs[step % 2]
        machine.launch(kernel, (n,), value, pointer, target[0], target[1], np.int64(n))
        value, pointer = target
    return value, pointer


def rank(next: ArrayLike, *, machine: Machine | None = None) -> tuple[ArrayLike, ArrayLike]:
    """List ranking: each node's distance to the tail of its list, and that tail.

    Parameters
    ----------
    next : int32 array (n,)
        next[i] is the node after i, or -1 where i is a tail. Lists must not contain cycles: a host
        array with one is refused (a device array's result is not read back for that check).

    Returns
    -------
    rank : int32 (n,)
        Number of ``next`` steps from i to its tail (0 at tails).
    tail : int32 (n,)
        The tail of i's list.
    """
    machine = machine_for(machine)
    data, host = _pointers(next, machine, lowest=-1)
    n = data.size
    pointer, distance = machine.empty(n, np.int32), machine.empty(n, np.int32)
    machine.launch(_kernel(machine, "list_init"), (n,), data, pointer, distance, np.int64(n))
    distance, tail = _jump(machine, distance, pointer, 0)
    if host:
        # On a cycle the jumps end on a node that is not a tail: its ranks would be wrong, not an error.
        ends = tail.get()
        caught = np.flatnonzero(np.asarray(next)[ends] != -1)
        if len(caught):
            raise InputValueError(f"next must form lists that end (next = -1), not cycles: node {int(caught[0])} "
                                  "never reaches a tail")
        return distance.get(), ends
    return distance, tail


def principal(next: ArrayLike, *, keys: ArrayLike | None = None, check: bool = True,
              machine: Machine | None = None) -> tuple[ArrayLike, ArrayLike]:
    """The principal (largest address, or largest key) of every ring, and each node's distance from it.

    Parameters
    ----------
    next : int32 array (n,)
        A permutation: next[i] is the node after i, so the nodes form disjoint rings.
    keys : int32 array (n,), optional
        Distinct values that rank the nodes: the principal of a ring is its node of largest key. Default:
        the addresses themselves (the paper's principal). Keys let a caller choose which node of a ring
        is its principal (vmcl.group.curves makes a curve's endpoint the principal of its ring).
    check : bool
        Check ``next``: its addresses in range, and for a host array that it is a permutation (a device
        array's is not read back for that); False skips the checks for a device array the caller's own
        kernel built (a wrong one then gives wrong answers, not an error).

    Returns
    -------
    principal : int32 (n,)
        The largest address (or key) in i's ring.
    distance : int32 (n,)
        Number of ``next`` steps from the principal to i (0 at the principal).
    """
    machine = machine_for(machine)
    data, key, host = _rings(next, "next", keys, check, machine)
    prev = machine.empty(data.size, np.int32)
    machine.launch(_kernel(machine, "ring_init"), (data.size,), data, prev, np.int64(data.size))
    top, distance = _principal_steps(machine, prev, key)
    return result(top, host), result(distance, host)


def principal_from_predecessors(prev: ArrayLike, *, keys: ArrayLike | None = None, check: bool = True,
                                machine: Machine | None = None) -> tuple[ArrayLike, ArrayLike]:
    """:func:`principal` of the rings given backwards: prev[i] is the node *before* i.

    The doubling walks the rings backwards, so a kernel that builds rings can write each node's
    predecessor and save :func:`principal` its first pass, which inverts ``next``. Same parameters (with
    ``prev`` for ``next``) and results: the distance still counts the steps forwards from the principal.

    Examples
    --------
    >>> import numpy as np
    >>> top, distance = principal_from_predecessors(np.array([2, 0, 1], np.int32))  # the ring 0 -> 1 -> 2 -> 0
    >>> top.tolist(), distance.tolist()
    ([2, 2, 2], [1, 2, 0])
    """
    machine = machine_for(machine)
    data, key, host = _rings(prev, "prev", keys, check, machine)
    top, distance = _principal_steps(machine, data, key)
    return result(top, host), result(distance, host)


def _rings(pointers: ArrayLike, name: str, keys: ArrayLike | None, check: bool,
           machine: Machine) -> tuple[cl_array.Array, cl_array.Array, bool]:
    """The ring pointers and the keys on the device, checked, and whether the pointers came from the host."""
    if not check_bool(check, "check") and isinstance(pointers, cl_array.Array):
        data, host = field(pointers, name, machine, ndims=(1,), dtypes=(np.int32,))
    else:
        data, host = _pointers(pointers, machine, lowest=0, name=name)
    if host and np.bincount(np.asarray(pointers), minlength=data.size).max() != 1:
        raise InputValueError(f"{name} must be a permutation (every node the {'successor' if name == 'next' else 'predecessor'} "
                              "of exactly one node) to form rings")
    n = data.size
    if keys is None:
        return data, machine.to_device(np.arange(n, dtype=np.int32)), host
    key, key_host = field(keys, "keys", machine, ndims=(1,), dtypes=(np.int32,))
    if key.size != n:
        raise InputValueError(f"keys must have one value per node ({n}), got {key.size}")
    if key_host and np.unique(np.asarray(keys)).size != n:
        raise InputValueError("keys must be distinct")
    return data, key, host


def _principal_steps(machine: Machine, prev: cl_array.Array, key: cl_array.Array) -> tuple[cl_array.Array, cl_array.Array]:
    """ceil(log2 n) doubling steps backwards from every node as its own window's largest key, at distance
    0: each node carries the largest key it has seen and how far behind it lies, so the principal and the
    distances come from the same steps. The inputs are never written."""
    n = prev.size
    steps = _steps(n)
    if steps == 0:  # at most one node: its own principal
        return key.copy(), machine.full(n, np.int32, 0)
    buffers = [[machine.empty(n, np.int32) for _ in range(3)] for _ in range(2)]
    # The first launch reads the keys as the largest and 0 as the distance (first), so nothing sets them up.
    top, distance, k, launches = key, key, 0, 0
    while k < steps:
        # Several steps per launch (the same result as one at a time, in a fraction of the launches).
        now = min(_STEPS_PER_LAUNCH, steps - k)
        target = buffers[launches % 2]
        # A kernel object per first step keeps its scalars set from one call to the next.
        kernel = _kernel(machine, "principal_steps", instance=k)
        machine.launch(kernel, (n,), top, distance, prev, *target, np.int32(1 << k), np.int32(now), np.int32(k == 0),
                       np.int64(n))
        top, distance, prev = target
        k, launches = k + now, launches + 1
    return top, distance


@overload
def label(mask: np.ndarray, *, connectivity: int = 8, relabel: bool = False, method: LabelMethod = "doubling",
          machine: Machine | None = None) -> np.ndarray: ...
@overload
def label(mask: cl_array.Array, *, connectivity: int = 8, relabel: bool = False,
          method: LabelMethod = "doubling", machine: Machine | None = None) -> cl_array.Array: ...
def label(mask: ArrayLike, *, connectivity: int = 8, relabel: bool = False, method: LabelMethod = "doubling",
          machine: Machine | None = None) -> ArrayLike:
    """Connected-component labels of a binary field.

    Parameters
    ----------
    mask : 2-D array, bool or uint8 (non-zero is foreground)
    connectivity : {4, 8}
    relabel : bool
        False: each pixel gets the largest flat address (y * W + x) in its component, the paper's
        principal, and background gets -1. True: components are numbered 1..k in the order of their
        principals' addresses, background 0.
    method : {"doubling", "iterative"}
        "doubling" (default): union-find over the rows' runs (horizontal stretches of foreground,
        numbered in raster order) in which every pointer leads to a larger run; merges follow
        pointers to the roots and link the smaller root under the larger (integer compare-and-swap
        where work-items share trees), so a component's root is its last run, and a last pass gives
        every pixel the last address of its run's root: three passes whatever the field's shape.
        "iterative": the paper's O(m) spreading activation, every pixel taking the largest label
        among its neighbours until nothing changes (m = the longest path inside a component); the
        flag is read back every 16 passes.
    machine : vmcl.Machine, optional

    Returns
    -------
    int32 labels of the mask's shape. Both methods give identical labels.
    """
    machine = machine_for(machine)
    data, host = field(bool_as_bytes(mask), "mask", machine, ndims=(2,), dtypes=(np.uint8,))
    if check_int(connectivity, "connectivity") not in (4, 8):
        raise InputValueError(f"connectivity must be 4 or 8, got {connectivity!r}")
    connectivity = int(connectivity)
    method = check_choice(method, "method", ("doubling", "iterative"))
    relabel = check_bool(relabel, "relabel")
    if data.size >= 2**31:
        raise InputValueError(f"mask must have fewer than 2**31 pixels, got shape {data.shape}")
    n = data.size
    labels = machine.empty(data.shape, np.int32)
    if method == "doubling":
        _union_runs(machine, data, labels, connectivity)
    else:
        machine.launch(_kernel(machine, "label_init", connectivity=connectivity), (n,), data, labels,
                       np.int64(n))
        labels = _propagate(machine, labels, connectivity)
    if relabel:
        labels = _relabel(machine, labels)
    return result(labels, host)


def _union_runs(machine: Machine, mask: cl_array.Array, labels: cl_array.Array, connectivity: int) -> None:
    """Writes the "doubling" labels of ``mask`` into ``labels``: runs found and merged per strip, strip
    borders merged, then every pixel given its run's root's last address."""
    height, width = mask.shape
    # Row y's runs take the run indices y * slots onwards; a row has at most ceil(W / 2) runs, and the
    # kernel that finds them writes one int past their bounds.
    slots = width // 2 + 1
    # Raw pooled buffers: the kernels alone see them, and making a pyopencl Array costs host time on
    # every call.
    int32 = np.dtype(np.int32).itemsize
    bounds, counts, parent, run_label = (machine.pool.allocate(size * int32) for size in
                                         (2 * height * slots, height, height * slots, height * slots))
    # CPUs get a few tall strips (each labelled serially, like a sequential labeller); GPUs get one
    # row per strip, so every row is a work-item.
    rows = max(1, math.ceil(height / (machine.compute_units * 8))) if machine.is_cpu else 1
    strips = math.ceil(height / rows)
    sizes = np.int64(width), np.int64(height)
    machine.launch(_kernel(machine, "label_strips", connectivity=connectivity), (strips,),
                   mask, bounds, counts, parent, *sizes, np.int64(rows), np.int64(slots), local_size=(1,))
    if strips > 1:
        machine.launch(_kernel(machine, "label_merge_strips", connectivity=connectivity),
                       (strips - 1,), bounds, counts, parent, *sizes, np.int64(rows), np.int64(slots))
    machine.launch(_kernel(machine, "label_flatten", connectivity=connectivity), (height,),
                   mask, bounds, counts, parent, run_label, labels, *sizes, np.int64(slots))


def _propagate(machine: Machine, labels: cl_array.Array, connectivity: int) -> cl_array.Array:
    height, width = labels.shape
    kernel = _kernel(machine, "propagate_step", connectivity=connectivity)
    spare = machine.empty(labels.shape, np.int32)
    changed = machine.empty(1, np.int32)
    zero = np.zeros(1, np.int32)
    while True:
        changed.set(zero, queue=machine.queue)
        for _ in range(_CHECK_EVERY):
            machine.launch(kernel, (width, height), labels, spare, changed, np.int64(width), np.int64(height))
            labels, spare = spare, labels
        if not changed.get(queue=machine.queue)[0]:
            return labels


def _relabel(machine: Machine, labels: cl_array.Array) -> cl_array.Array:
    n = labels.size
    roots, ids, out = (machine.empty(labels.shape, np.int32) for _ in range(3))
    machine.launch(_kernel(machine, "mark_roots"), (n,), labels, roots, np.int64(n))
    exclusive_sum_into(machine, roots.reshape(n), ids.reshape(n))
    machine.launch(_kernel(machine, "relabel"), (n,), labels, ids, out, np.int64(n))
    return out
