"""The device state of one restoration: data, weights, field, line process, clique costs; one sweep.

Seed section "Algorithms: Deterministic and stochastic". Every solver (annealing, MPM, mean field, ICM)
is a schedule of the same sweep: the line sites at their four colours, then f at the two checkerboard
colours (kernels/mrf.cl documents the coding), each phase one launch of one work-item per site. A sweep
is enqueued back to back; nothing is read back until the solver has finished.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pyopencl as cl
import pyopencl.array as cl_array
from pyopencl import cltypes

from vmcl.cm import reduce as cm_reduce
from vmcl.machine import Machine
from vmcl.mrf.energy import EnergyModel, resolve_levels

__all__ = ["MODES", "SWEEP_ORDER", "Lattice", "philox_key"]

MODES = {"sample": 0, "icm": 1, "mean": 2}
# (phase, colour): the line sites' four colours, then f at the checkerboard's two colours. Lines go first
# so that the first sweep sees the data's jumps before the smoothing of f has flattened them.
SWEEP_ORDER = (("lines", 0), ("lines", 1), ("lines", 2), ("lines", 3), ("f", 0), ("f", 1))
# Kernels of kernels/mrf.cl that read no KIND, NLEVELS or MODE (at most NCOMP): every lattice of a
# component count takes them from one build, the smooth kind's for ICM. A pipeline frame restores both
# kinds, so on its first run they are compiled once per NCOMP, and the constant kind's preparation
# (built before its levels are known) is no program of its own.
_NCOMP_ONLY = frozenset({"prepare", "fill_step", "start_from", "line_costs", "near_rows", "near_columns",
                         "set_value", "scale_and_threshold", "unpad"})


def philox_key(seed: int) -> np.ndarray:
    """The Philox key of a 64-bit seed: (low word, high word)."""
    # pyopencl generates the make_* constructors at import time and its annotations declare only the
    # vector dtypes (cltypes.uint2), not the constructors.
    return cltypes.make_uint2(seed & 0xFFFFFFFF, seed >> 32)  # type: ignore[attr-defined]


class Lattice:
    """Device buffers of a restoration and the kernels that update them.

    Parameters
    ----------
    machine : Machine
    data : device array, float32, (H, W) or (H, W, C)
    confidence : device float32 (H, W) or None
    edges : device uint8 (H, W) or None
    kind : {"smooth", "constant"}
    model : EnergyModel
    start : device array of the data's shape, float32, or None
        A warm start: f begins there wherever it holds a value (else at the filled data; where no datum
        has a weight, at the start's own values, filled the same way).

    Attributes
    ----------
    strongest : float
        The largest weight alpha * confidence of a datum: 0 where the data hold no value with a positive
        confidence (nothing to restore), infinite where the product overflowed float32.
    begins : bool
        Whether f holds a value everywhere: the data have a weight somewhere, or the start a finite pixel.
    """

    def __init__(self, machine: Machine, data: cl_array.Array, confidence: cl_array.Array | None,
                 edges: cl_array.Array | None, kind: str, model: EnergyModel,
                 start: cl_array.Array | None = None) -> None:
        self.machine = machine
        self.model = model
        self.kind = kind
        self.height, self.width = data.shape[:2]
        self.ncomp = 1 if data.ndim == 2 else data.shape[2]
        self.n = self.height * self.width
        self.grid = (self.width, self.height)
        # Colour launches: sixteen sites of the colour per work-item, as vector lanes (kernels/mrf.cl, SITES).
        self.group_grid = (((self.width + 1) // 2 + 15) // 16, self.height)
        self.dims = (np.int64(self.width), np.int64(self.height))
        shape = data.shape
        empty = machine.empty
        self.g, self.f = empty(shape, np.float32), empty(shape, np.float32)
        self.w = empty((self.height, self.width), np.float32)
        self.lh, self.lv = empty(self.n, np.float32), empty(self.n, np.float32)
        self.bh, self.bv = empty(self.n, np.float32), empty(self.n, np.float32)
        self.table = machine.to_device(model.vertex_table().astype(np.float32))
        self.parallel = np.float32(model.beta * model.prior.parallel)
        self.kappa = np.float32(model.kappa)
        self.nlevels = 1
        self.levels = machine.to_device(np.zeros(1, np.float32))
        self._prepare(data, confidence)
        self.strongest = float(cm_reduce.reduce(self.w, "max", machine=machine).get())
        self.begins = self.strongest > 0
        if kind == "constant":
            # The levels span the data's values with a weight: the filled data, before any start, whose
            # fill takes means of them. Where none has a weight, all of the data's finite values.
            low, high = cm_reduce.extremes(self.f if self.begins else data, machine=machine)
        if start is not None:
            machine.launch(self.kernel("start_from"), self.grid, start, self.f, *self.dims)
            if not self.begins:
                # No datum filled f: the start's own values fill its gaps, as the data's would have.
                scratch = self.f.copy(queue=machine.queue)
                self._fill(scratch)
                self.begins = not np.isnan(cm_reduce.extremes(self.f, machine=machine)[0])
        if kind == "constant":
            if np.isnan(low):  # the data hold no finite value at all: the start's span, if it has one
                low, high = cm_reduce.extremes(self.f, machine=machine)
            levels = resolve_levels(model, low, high)
            self.nlevels = int(levels.size)
            self.levels = machine.to_device(levels)
            machine.launch(self.kernel("quantise"), self.grid, self.f, self.levels, *self.dims)
        self.f_start = self.f.copy(queue=machine.queue)
        near = self.bh  # read only with require_edge and edges; any buffer stands in otherwise
        if model.require_edge and edges is not None:
            near = self._near_edges(edges, model.edge_radius)
        machine.launch(self.kernel("line_costs"), self.grid, edges, np.int32(edges is not None),
                       np.float32(model.beta * model.prior.line), np.float32(model.beta * model.edge_gain),
                       np.int32(model.require_edge), near, self.bh, self.bv, *self.dims)
        self.reset()

    @staticmethod
    def memory(shape: tuple[int, ...], kind: str, model: EnergyModel, *, confidence: bool, edges: bool,
               start: bool, solver_words: tuple[int, ...] = ()) -> tuple[int, int]:
        """The device bytes a lattice of the data's ``shape`` holds at once, and its largest buffer, for
        :meth:`vmcl.Machine.require_memory`: the inputs on the device (the data, and the confidence,
        edges and start where given), the lattice's own buffers, the buffers read back at the end, and a
        solver's, given as float32 words per site (``solver_words``, one entry per buffer)."""
        height, width = shape[:2]
        n = height * width
        ncomp = 1 if len(shape) == 2 else shape[2]
        field_bytes = 4 * n * ncomp
        # data, g, f, f_start and the preparation's scratch; w; lh, lv, bh, bv; the site energies read back
        total = 5 * field_bytes + 4 * n + 16 * n + 4 * n
        total += 4 * n * confidence + n * edges + field_bytes * start + 2 * n  # + the public line fields
        if model.require_edge and edges:
            total += 5 * n  # the row distances and the near map of _near_edges
        total += sum(4 * n * words for words in solver_words)
        return total, max(field_bytes, 4 * n, *(4 * n * words for words in solver_words))

    def kernel(self, name: str, mode: str = "icm") -> Any:
        if name in _NCOMP_ONLY:
            return self.machine.kernel("mrf", name, NCOMP=self.ncomp, KIND=0, NLEVELS=1, MODE=MODES["icm"])
        return self.machine.kernel("mrf", name, NCOMP=self.ncomp, KIND=int(self.kind == "constant"),
                                   NLEVELS=self.nlevels, MODE=MODES[mode])

    def _prepare(self, data: cl_array.Array, confidence: cl_array.Array | None) -> None:
        """Clean data and weights, and the starting field: the data, its gaps filled by a jump fill."""
        scratch = self.machine.empty(data.shape, np.float32)
        self.machine.launch(self.kernel("prepare"), self.grid, data, confidence, np.int32(confidence is not None),
                            np.float32(self.model.alpha), self.g, self.w, scratch, *self.dims)
        self._fill(scratch)

    def _fill(self, scratch: cl_array.Array) -> None:
        """f from ``scratch`` (NaN where empty, overwritten) by the jump fill: every empty pixel takes
        the mean of filled ones nearby; all stay empty where none is filled."""
        fill = self.kernel("fill_step")
        source, target = scratch, self.f
        steps = 1 + int(np.ceil(np.log2(max(self.height, self.width))))
        for k in range(steps):
            self.machine.launch(fill, self.grid, source, target, np.int64(1 << k), *self.dims)
            source, target = target, source
        if source is not self.f:
            self.copy(self.f, source)

    def _near_edges(self, edges: cl_array.Array, radius: int) -> cl_array.Array:
        """uint8 (H, W): 1 where an edge pixel lies within Chebyshev distance ``radius``. The square is
        separable, so two passes (along each row, then each column) find it in O(H W) for any radius,
        where scanning each pixel's square costs (2 radius + 1)**2."""
        distance = self.machine.empty((self.height, self.width), np.int32)
        near = self.machine.empty((self.height, self.width), np.uint8)
        self.machine.launch(self.kernel("near_rows"), (self.height,), edges, distance, *self.dims)
        self.machine.launch(self.kernel("near_columns"), (self.width,), distance, np.int64(radius), near,
                            *self.dims)
        return near

    def copy(self, target: cl_array.Array, source: cl_array.Array) -> None:
        # pyopencl's annotations take only a Buffer here, but enqueue_copy copies between any
        # MemoryObjectHolder buffers, such as the PooledBuffer that Machine.empty allocates.
        cl.enqueue_copy(self.machine.queue, target.data, source.data,  # type: ignore[arg-type]
                        byte_count=source.nbytes)

    def set_value(self, array: cl_array.Array, value: float) -> None:
        self.machine.launch(self.kernel("set_value"), (array.size,), array, np.float32(value),
                            np.int64(array.size))

    def reset(self) -> None:
        """Back to the start: f from the filled data, no lines."""
        self.copy(self.f, self.f_start)
        self.set_value(self.lh, 0.0)
        self.set_value(self.lv, 0.0)

    def sweep(self, mode: str, temperature: float, index: int, key: np.ndarray,
              order: tuple[tuple[str, int], ...] = SWEEP_ORDER, q: cl_array.Array | None = None) -> None:
        """Enqueue one sweep: every site once, colour by colour in ``order``.

        ``mode`` is "sample" (heat bath at ``temperature``), "icm" (conditional modes) or "mean" (mean
        field at ``temperature``; the constant kind then updates the level distributions ``q``).
        ``index`` numbers the sweep in the random stream.
        """
        temperature = np.float32(temperature)
        index = np.uint32(index)
        f_kernel = self.kernel("q_update" if q is not None else "f_update", mode)
        lines = self.kernel("line_update", mode)
        for phase, colour in order:
            if phase == "f" and q is not None:
                self.machine.launch(f_kernel, self.group_grid, q, self.g, self.w, self.lh, self.lv, self.levels,
                                    self.kappa, temperature, np.int32(colour), *self.dims)
            elif phase == "f":
                self.machine.launch(f_kernel, self.group_grid, self.f, self.g, self.w, self.lh, self.lv, self.levels,
                                    self.kappa, temperature, index, key, np.int32(colour), *self.dims)
            else:
                self.machine.launch(lines, self.group_grid, self.lh, self.lv, self.f, q, self.bh, self.bv,
                                    self.table, self.parallel, self.kappa, temperature, index, key,
                                    np.int32(colour), *self.dims)

    def site_energy(self) -> cl_array.Array:
        """Each pixel's share of U(f, l) (lines read as on where non-zero), float32 (H, W)."""
        out = self.machine.empty((self.height, self.width), np.float32)
        self.machine.launch(self.kernel("site_energy"), self.grid, self.f, self.g, self.w, self.lh, self.lv,
                            self.bh, self.bv, self.table, self.parallel, self.kappa, out, *self.dims)
        return out

    def energy(self) -> float:
        """U(f, l), summed in a fixed order with compensation (one scalar read back)."""
        return float(cm_reduce.reduce(self.site_energy(), "sum", machine=self.machine).get())

    def lines(self) -> tuple[cl_array.Array, cl_array.Array]:
        """The line process in the public shapes: uint8 (H, W - 1) and (H - 1, W)."""
        line_h = self.machine.empty((self.height, self.width - 1), np.uint8)
        line_v = self.machine.empty((self.height - 1, self.width), np.uint8)
        self.machine.launch(self.kernel("unpad"), self.grid, self.lh, self.lv, line_h, line_v, *self.dims)
        return line_h, line_v
