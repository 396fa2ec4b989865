"""The Machine: one OpenCL context and in-order queue standing in for the Connection Machine.

Seed section "Our computational engine: The Connection Machine". Each CM processor becomes one OpenCL
work-item; the host (the CM's front end) enqueues whole-field operations. The Machine owns what every
module shares: the device choice, the program and kernel caches (a kernels/*.cl file is built once per
set of -D defines), a pool of device buffers so repeated calls reuse memory, and optional per-kernel
timings.
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
import re
import sys
import tempfile
import threading
import warnings
from collections import defaultdict
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pyopencl as cl
import pyopencl.array as cl_array
import pyopencl.tools as cl_tools

# pyopencl's unbuilt program, which pyopencl.Program wraps (its one-argument form): built with exactly the
# options given, where Program.build adds its own include folder to them.
from pyopencl._cl import _Program as RawProgram
from pyopencl.characterize import has_src_build_cache

from vmcl.errors import InputTypeError, InputValueError

__all__ = [
    "CPU_GROUP",
    "INSTALL_HINT",
    "Machine",
    "NoOpenCLPlatformError",
    "default_machine",
    "kernel_source",
    "kernels_dir",
    "list_devices",
    "on_device",
]

CPU_GROUP = 64
"""Work-items per work-group, along the first dimension, of every launch on a CPU device that does not fix
its own (:meth:`Machine.launch`)."""

INSTALL_HINT = (
    "No OpenCL platform found. vmcl needs an OpenCL driver; on Debian or Ubuntu install PoCL with\n"
    "    sudo apt-get update && sudo apt-get install -y pocl-opencl-icd\n"
    "(or run `make setup`, which does it when run as root). Any vendor's OpenCL driver works too."
)

_MAX_LAYOUTS = 4096
_MAX_CONSTANTS = 256  # Machine.constant's tables before they are dropped and made again as needed
"""Array layouts :meth:`Machine.empty` keeps before starting over."""

_log = logging.getLogger(__name__)
# A library's records are the application's to show: without this, Python's last-resort handler would
# print WARNING records to the terminal of a user who never configured logging.
_log.addHandler(logging.NullHandler())

_DRIVER_NOTE = re.compile(r"changes the ABI|vector ABI|is a kernel, so overriding noinline attribute", re.IGNORECASE)
"""Build-log lines that are about the driver, not vmcl's source: PoCL's notes on AVX vector ABIs, which
depend on how the CPU and PoCL's own kernel library were built, and NVIDIA's notice (drivers from 550 on)
that a kernel may be inlined where it is called, printed for kernels that no other kernel calls. Logged at
DEBUG."""

_CLANG_SUMMARY = re.compile(rb"^\d+ (warnings?|errors?)( and \d+ errors?)? generated\.$")
"""The line clang inside PoCL prints straight to the process's stderr after a build with diagnostics."""

_STDERR_LOCK = threading.Lock()
"""File descriptor 2 belongs to the process: one build at a time may redirect it, whatever the Machine."""


class NoOpenCLPlatformError(RuntimeError):
    """Raised when no OpenCL platform or no matching device is available."""


def kernels_dir() -> Path:
    """The folder holding the OpenCL sources: inside an installed wheel, else the checkout's kernels/."""
    here = Path(__file__).resolve().parent
    for candidate in (here / "_kernels", here.parent / "kernels"):
        if (candidate / "vmcl.h").is_file():
            return candidate
    raise FileNotFoundError(f"vmcl's OpenCL kernels were not found in {here / '_kernels'} or {here.parent / 'kernels'}")


def _platforms() -> list[cl.Platform]:
    try:
        platforms = cl.get_platforms()
    except (cl.LogicError, cl.RuntimeError) as error:
        # pyopencl reports an absent ICD loader target as PLATFORM_NOT_FOUND_KHR.
        raise NoOpenCLPlatformError(f"{INSTALL_HINT}\n(OpenCL said: {error})") from None
    if not platforms:
        raise NoOpenCLPlatformError(INSTALL_HINT)
    return platforms


def list_devices() -> list[cl.Device]:
    """Every OpenCL device of every platform, GPUs first, in platform order otherwise."""
    devices = [device for platform in _platforms() for device in platform.get_devices()]
    return sorted(devices, key=lambda d: 0 if d.type & cl.device_type.GPU else 1)


def _choose_device(device: cl.Device | str | int | None) -> cl.Device:
    if isinstance(device, cl.Device):
        return device
    if isinstance(device, (int, np.integer)) and not isinstance(device, (bool, np.bool_)):
        # An index as `vmcl info` numbers the devices, as the digits "1" give it (and MachinePlugin takes).
        if device < 0:
            raise InputValueError(f"device: an index must be >= 0, got {device}")
        device = str(int(device))
    if device is not None and not isinstance(device, str):
        raise InputTypeError(f"device must be a pyopencl.Device, a name substring, an index (as vmcl info lists the "
                             f"devices) or None, got {type(device).__name__}")
    wanted = device if device is not None else os.environ.get("VMCL_DEVICE") or None
    devices = list_devices()
    if not devices:
        raise NoOpenCLPlatformError(INSTALL_HINT)
    if wanted is None:
        return devices[0]
    source = "device" if device is not None else "the VMCL_DEVICE environment variable"
    if wanted.strip().isdigit():  # an index, as `vmcl info` lists the devices, not a part of a name ("1" of "avx512")
        index = int(wanted)
        if index >= len(devices):
            raise InputValueError(f"{source}: index {index} is outside the {len(devices)} OpenCL device(s) here "
                                  "(vmcl info lists them)")
        return devices[index]
    needle = wanted.lower()
    for candidate in devices:
        if needle in candidate.name.lower() or needle in candidate.platform.name.lower():
            return candidate
    names = ", ".join(f"{d.platform.name} / {d.name}" for d in devices)
    raise InputValueError(f"{source}: no OpenCL device matches {wanted!r}; available: {names}")


_BUILD_ATTEMPTS = 3  # builds of a program that lost a race for PoCL's cache files
_CACHE_RACE = "unable to rename temporary"  # PoCL's build log when another process took its cache file

_INCLUDE = re.compile(r'^[ \t]*#[ \t]*include[ \t]+"([^"]+)"[ \t]*$')


def kernel_source(family: str) -> str:
    """The OpenCL source of kernels/<family>.cl with its ``#include "x.h"`` lines replaced by those files.

    The build then needs no include path, so its source and options are the same wherever vmcl is
    installed, and so are the keys of PoCL's and pyopencl's kernel caches: a second checkout or a
    reinstall finds the kernels the first one built. ``#line`` directives keep the compiler's messages
    pointing at each file's own lines. A header is inlined once per program.
    """
    if not isinstance(family, str):
        raise InputTypeError(f"family must be the name of a kernel file (a str), got {type(family).__name__}")
    folder = kernels_dir()
    if "/" in family or "\\" in family or not (folder / f"{family}.cl").is_file():
        raise InputValueError(f"family {family!r} names no kernel file in {folder}")
    seen: set[str] = set()

    def expand(name: str) -> list[str]:
        lines = []
        for number, line in enumerate((folder / name).read_text().splitlines(), start=1):
            found = _INCLUDE.match(line)
            if found is None:
                lines.append(line)
                continue
            header = found.group(1)
            if header not in seen:
                seen.add(header)
                lines += [f'#line 1 "{header}"', *expand(header)]
            lines.append(f'#line {number + 1} "{name}"')
        return lines

    return "\n".join(expand(f"{family}.cl")) + "\n"


def _log_build(family: str, defines: tuple, build_log: str) -> None:
    """Log a build's compiler output on "vmcl.machine": vmcl's own warnings at WARNING, driver notes at DEBUG.

    Nothing reaches the terminal unless the application configures logging; a developer sees both with
    ``logging.basicConfig(level=logging.DEBUG)``. Each build logs once: programs are cached per Machine,
    and PoCL keeps the log with its cached binaries, so a cache hit logs the same as the first build.
    """
    lines = [line for line in build_log.splitlines() if line.strip()]
    notes = [line for line in lines if _DRIVER_NOTE.search(line)]
    own = [line for line in lines if not _DRIVER_NOTE.search(line)]
    where = f"kernels/{family}.cl with {dict(defines)}"
    if own:
        _log.warning("compiler output building %s:\n%s", where, "\n".join(own))
    if notes:
        _log.debug("driver notes building %s:\n%s", where, "\n".join(notes))


@contextlib.contextmanager
def _clang_stderr_to_log():
    """Keep clang's "N warnings generated." off the terminal: PoCL's clang writes it to file descriptor 2.

    PoCL hands clang's diagnostics to the build log, but clang's own summary line goes straight to the
    process's stderr, bypassing Python, for any build with a diagnostic (PoCL's AVX notes count as one).
    Passing -w would silence it, but also empty the build log that :func:`_log_build` reports from, so
    instead fd 2 points at a temporary file for the build: the summary lines go to DEBUG, anything else
    that arrived meanwhile (not clang's, e.g. another thread's) is written back to stderr.
    """
    with _STDERR_LOCK, tempfile.TemporaryFile() as capture:
        try:
            sys.stderr.flush()
            saved = os.dup(2)
        except (OSError, ValueError, AttributeError):  # no fd 2 or no sys.stderr: nothing reaches a terminal
            yield
            return
        os.dup2(capture.fileno(), 2)
        try:
            yield
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            capture.seek(0)
            others = []
            for line in capture.read().splitlines(keepends=True):
                if _CLANG_SUMMARY.match(line.strip()):
                    _log.debug("clang: %s", line.strip().decode(errors="replace"))
                else:
                    others.append(line)
            if others:
                os.write(2, b"".join(others))


def device_memory(x: cl_array.Array) -> cl.MemoryObjectHolder:
    """The memory object under ``x``, a non-empty array from :meth:`Machine.empty`, for the
    ``cl.enqueue_*`` calls that take one (pyopencl types ``base_data`` as memory, SVM pointer or None)."""
    memory = x.base_data
    # The Machine's pool hands out PooledBuffers, which are memory objects; only an empty array has none.
    assert isinstance(memory, cl.MemoryObjectHolder), f"no device memory under an array of shape {x.shape}"
    return memory


class Machine:
    """An OpenCL device with a context, an in-order queue, program/kernel caches and a buffer pool.

    Parameters
    ----------
    device : pyopencl.Device, str or int, optional
        The device, a case-insensitive substring of its platform or device name, or its index among
        :func:`list_devices` (``1`` or the digits ``"1"``: as ``vmcl info`` numbers them). Default: the ``VMCL_DEVICE``
        environment variable (the same), else the first device, GPUs before CPUs.
    profile : bool
        Record the device time of every kernel launched through :meth:`launch`; see :meth:`timings`.
    local_size : int, optional
        Work-group size along the first dimension for every launch that does not fix its own (the
        global size is rounded up to a multiple; kernels ignore the extra work-items). Default: on CPU
        devices :data:`CPU_GROUP` (PoCL compiles a kernel once per work-group size, so a size that does
        not follow the image's lets a new image size reuse every kernel built), elsewhere the driver's
        choice. Results never depend on it; tests use it to prove that.

    Attributes
    ----------
    is_cpu : bool
        Whether the device is a CPU.
    compute_units : int
        The device's compute units.
    vector_width : int
        Elements each work-item of a vectorised kernel handles (its ``VEC`` define): 16 on CPUs, whose
        SIMD lanes then see contiguous loads, 1 on GPUs, whose work-items are the lanes.
    build_options : tuple of str
        Options every program is built with, before its defines (read-only):
        ``-cl-fp32-correctly-rounded-divide-sqrt`` where the device offers it, so that ``/`` and ``sqrt``
        are correctly rounded, as NumPy's float32 ones are (NVIDIA's default division is within 2 ulp, and
        the edge matcher's score ties then broke otherwise than its NumPy oracle's). ``native_*``
        functions, other built-ins and contracted multiply-adds may still differ between devices.

    Notes
    -----
    Programs are compiled on first use, never at construction, and cached per (file, defines).

    On PoCL a Machine is safe to share between threads. A pyopencl kernel object holds its arguments until
    the next launch sets them, so setting them and enqueueing happen under one lock, as do the
    allocations from the buffer pool; each call's scratch buffers are its own. Work from several
    threads is serialised on the one in-order queue, so threads add no speed on one device: for that,
    use one Machine per thread (each with its own queue) or one process per device.

    On NVIDIA's OpenCL (driver 580, an H200), six threads sharing one Machine ended the process with a
    segmentation fault in a worker thread of the driver's library, while another thread released an event
    (tests/test_threads.py); the cause is not isolated. There, give each thread its own Machine, passed as
    ``machine=`` to every call (module functions otherwise share :func:`default_machine`).
    """

    def __init__(self, device: cl.Device | str | int | None = None, *, profile: bool = False,
                 local_size: int | None = None) -> None:
        if local_size is not None and (not isinstance(local_size, int) or local_size < 1):
            raise InputValueError(f"local_size must be a positive integer or None, got {local_size!r}")
        self.device = _choose_device(device)
        self.context = cl.Context([self.device])
        # Without profiling the queue takes pyopencl's default properties (0): its stub types the
        # argument as an enum that has no member for "none" at run time.
        self.queue = (cl.CommandQueue(self.context, properties=cl.command_queue_properties.PROFILING_ENABLE)
                      if profile else cl.CommandQueue(self.context))
        self.profile = profile
        self.local_size = local_size
        self.pool = cl_tools.MemoryPool(cl_tools.ImmediateAllocator(self.queue))
        self._programs: dict[tuple, cl.Program] = {}
        self._kernels: dict[tuple, cl.Kernel] = {}
        # The machine's own kernels -> argument index -> (dtype, bytes) of the scalar each holds.
        self._scalar_args: dict[cl.Kernel, dict[int, tuple]] = {}
        # Profiling: each launch's kernel name, the bytes of the buffers it was given, and its event.
        self._events: list[tuple[str, int, cl.Event]] = []
        self._layouts: dict[tuple, tuple] = {}  # (shape, dtype) -> (shape, dtype, strides, size) for empty()
        self._constants: dict[Any, cl_array.Array] = {}  # constant()'s tables
        self._lock = threading.Lock()
        # Held while a launch sets a kernel object's arguments and enqueues it, and while the pool
        # allocates: both mutate state that every thread using this Machine shares.
        self._launch_lock = threading.RLock()
        self.is_cpu = bool(self.device.type & cl.device_type.CPU)
        self.compute_units = self.device.max_compute_units
        self.vector_width = 16 if self.is_cpu else 1
        exact = bool(self.device.single_fp_config & cl.device_fp_config.CORRECTLY_ROUNDED_DIVIDE_SQRT)
        self._build_options: tuple[str, ...] = ("-cl-fp32-correctly-rounded-divide-sqrt",) if exact else ()

    def __repr__(self) -> str:
        return f"Machine({self.device.platform.name} / {self.device.name})"

    @property
    def build_options(self) -> tuple[str, ...]:
        # Read-only: the programs cached by defines alone were all built with these.
        return self._build_options

    # -- programs and kernels -------------------------------------------------------------------

    def program(self, family: str, **defines: Any) -> cl.Program:
        """The built program of kernels/<family>.cl for these -D defines (built once, then cached)."""
        key = (family, tuple(sorted(defines.items())))
        with self._lock:
            program = self._programs.get(key)
            if program is None:
                source = kernel_source(family)
                options = [*self.build_options, *(f"-D{name}={value}" for name, value in key[1])]
                with warnings.catch_warnings(record=True) as caught, _clang_stderr_to_log():
                    # pyopencl only says "non-empty compiler output" here; the log itself is read below.
                    warnings.simplefilter("always")
                    program = self._build(source, options)
                for warning in caught:
                    if not issubclass(warning.category, cl.CompilerWarning):
                        # Another thread's warning, caught only because catch_warnings is process-wide.
                        warnings.warn_explicit(warning.message, warning.category, warning.filename, warning.lineno)
                _log_build(family, key[1], program.get_build_info(self.device, cl.program_build_info.LOG))
                self._programs[key] = program
        return program

    def _build(self, source: str, options: list[str]) -> cl.Program:
        """The program of ``source`` built for this device with exactly ``options`` where the driver keeps
        its own cache of builds (PoCL, NVIDIA): pyopencl's Program.build adds "-I <its install folder>",
        which the driver's cache key then holds, and a second install (another virtual environment, a
        checkout) would build every kernel again. Elsewhere pyopencl's build, with its own binary cache."""
        for attempt in range(_BUILD_ATTEMPTS):
            try:
                if not has_src_build_cache(self.device):
                    return cl.Program(self.context, source).build(options=options)
                raw = RawProgram(self.context, source)
                raw.build(" ".join(options).encode(), [self.device])  # a failure's error holds the build log
                return cl.Program(raw)
            except cl.Error as error:
                # Processes that build one program at once into PoCL's shared cache race for its files ("unable
                # to rename temporary ..."): the loser's build fails, though its source is sound. Built again,
                # it finds the winner's binary.
                if _CACHE_RACE not in str(error) or attempt == _BUILD_ATTEMPTS - 1:
                    raise
        raise AssertionError("unreachable")

    def kernel(self, family: str, name: str, **defines: Any) -> cl.Kernel:
        """A cached kernel object: fetched from its program once per (family, name, defines). Launch it
        with :meth:`launch` (see :meth:`kernel_instance`)."""
        return self.kernel_instance(0, family, name, **defines)

    def kernel_instance(self, instance: int, family: str, name: str, **defines: Any) -> cl.Kernel:
        """Instance ``instance`` of a kernel: separate kernel objects of one kernel (0 is :meth:`kernel`'s),
        each holding its own arguments. A caller that launches a kernel with a few fixed sets of scalars
        (a step of each span) gives each set its instance, and :meth:`launch` then sets none of them
        again (see ``_set_arguments``).

        Launch the machine's kernels through :meth:`launch` only: it remembers the scalars each holds,
        and a kernel's arguments set elsewhere (``set_arg``, calling it) would leave that record wrong."""
        key = (family, name, tuple(sorted(defines.items())), instance)
        kernel = self._kernels.get(key)
        if kernel is None:
            made = cl.Kernel(self.program(family, **defines), name)
            with self._launch_lock:  # two threads may make one kernel: one of them is kept, and only it known
                kernel = self._kernels.setdefault(key, made)
                if kernel is made:
                    self._scalar_args[kernel] = {}
        return kernel

    def launch(self, kernel: cl.Kernel, global_size: tuple[int, ...], *args: Any,
               local_size: tuple[int, ...] | None = None) -> cl.Event:
        """Enqueue ``kernel`` over ``global_size`` work-items; device arrays are passed by their buffer.

        With a local size (the call's, else the Machine's), the global size is rounded up to a multiple
        of it; every vmcl kernel checks its ids against the field's bounds, so the extra work-items idle.
        A global size with a zero dimension launches nothing (its arguments are not set either): the
        returned event is a marker in the queue's order.
        """
        values = []
        buffer_bytes = 0
        for a in args:
            if isinstance(a, cl_array.Array):
                if a.offset:
                    # base_data is the whole buffer: a view's offset would be silently lost.
                    raise InputValueError("device arrays passed to kernels must not be views with an offset; "
                                          "copy the view")
                values.append(a.base_data)
                buffer_bytes += a.nbytes
            else:
                values.append(a)
                if isinstance(a, cl.MemoryObjectHolder):
                    buffer_bytes += a.size
        if local_size is None and self.local_size is not None:
            local_size = (self.local_size,) + (1,) * (len(global_size) - 1)
        elif local_size is None and self.is_cpu:
            local_size = (CPU_GROUP,) + (1,) * (len(global_size) - 1)
        if local_size is not None:
            global_size = tuple(-(-g // size) * size for g, size in zip(global_size, local_size))
        if 0 in global_size:
            # An empty range has no work-item to run; PoCL 3.1 aborts the whole process on one (OpenCL 3.0
            # allows it), so it never reaches the driver. The marker orders like the launch would have.
            return cl.enqueue_marker(self.queue)
        with self._launch_lock:
            scalars = self._scalar_args.get(kernel)
            if scalars is None:  # a kernel of the caller's own making
                # pyopencl's KernelArg omits MemoryObjectHolder, yet a pooled array's base_data is a
                # PooledBuffer (one), which kernels take as they take a Buffer.
                event = kernel(self.queue, global_size, local_size, *values)  # type: ignore[arg-type]
            else:
                self._set_arguments(kernel, scalars, values)
                event = cl.enqueue_nd_range_kernel(self.queue, kernel, global_size, local_size)
        if self.profile:
            self._events.append((kernel.function_name, buffer_bytes, event))
        return event

    @staticmethod
    def _set_arguments(kernel: cl.Kernel, scalars: dict[int, tuple], values: list[Any]) -> None:
        """Set a machine kernel's arguments, skipping scalars it already holds.

        PoCL takes about 9 us to set one scalar argument (a buffer, 0.1 us), so a launch of ten scalars
        cost more host time than most kernels take to run; a kernel object keeps its arguments between
        launches, and the sizes and flags of a stage seldom change. Scalars are compared by type and
        bytes (0.0 and -0.0 differ; a NaN equals itself).
        """
        for index, value in enumerate(values):
            if isinstance(value, np.generic):
                held = (value.dtype, value.tobytes())
                if scalars.get(index) == held:
                    continue
                kernel.set_arg(index, value)
                scalars[index] = held
            else:
                kernel.set_arg(index, value)  # type: ignore[arg-type]
                scalars.pop(index, None)

    def row_local_size(self, global_size: tuple[int, ...]) -> tuple[int, ...] | None:
        """The work-group shape for a launch whose first dimension runs along image rows.

        On CPU devices, :data:`CPU_GROUP` work-items along the row whatever the image's width: on PoCL
        they ran row kernels faster than the driver's own choice (binomial filter, motion), and one size
        is one build. Elsewhere, or when the Machine fixes ``local_size``, None (the driver's or the
        Machine's choice).
        """
        if not self.is_cpu or self.local_size is not None:
            return None
        return (CPU_GROUP,) + (1,) * (len(global_size) - 1)

    # -- memory -----------------------------------------------------------------------------------

    def empty(self, shape: tuple[int, ...] | int, dtype: Any) -> cl_array.Array:
        """An uninitialised C-contiguous device array from the pool (memory of freed arrays is reused).

        Built through pyopencl's fast constructor with the shape checked and the strides computed here:
        its general one spends host time on NumPy checks for every array, and a Canny or stereo
        call makes dozens, on a host thread that shares the CPU with the device's.
        """
        dims = (shape,) if isinstance(shape, (int, float, np.integer, np.floating)) else tuple(shape)
        # Only plain-int shapes are looked up: 5.0 == 5 as a dict key, and a float must still be refused.
        layout = self._layouts.get((dims, dtype)) if all(type(n) is int for n in dims) else None
        if layout is None:
            if not all(isinstance(n, (int, np.integer)) and not isinstance(n, bool) and n >= 0 for n in dims):
                raise InputValueError(f"invalid shape {dims}: dimensions must be integers >= 0")
            dims = tuple(int(n) for n in dims)
            item = np.dtype(dtype)
            strides, step = [], item.itemsize
            for n in reversed(dims):
                strides.append(step)
                step *= max(1, n)
            if len(self._layouts) >= _MAX_LAYOUTS:  # images of ever new sizes must not grow it forever
                self._layouts.clear()
            layout = self._layouts[(dims, dtype)] = (dims, item, tuple(reversed(strides)), math.prod(dims))
        dims, dtype, strides, size = layout
        with self._launch_lock:
            return cl_array.Array(None, dims, dtype, allocator=self.pool, strides=strides, _fast=True,
                                  _size=size, _context=self.context, _queue=self.queue)

    def full(self, shape: tuple[int, ...] | int, dtype: Any, value: Any) -> cl_array.Array:
        """A device array from the pool with every element ``value``, filled on the queue (nothing waits)."""
        return self.fill(self.empty(shape, dtype), value)

    def fill(self, array: cl_array.Array, value: Any) -> cl_array.Array:
        """Set every element of a device array from :meth:`empty` to ``value``, on the queue; returns it.

        A view with an offset is refused (as :meth:`launch` refuses one), and so is a value its dtype cannot
        hold exactly (2.5 for int32, 300 for uint8): nothing is silently rounded or wrapped.
        """
        if not isinstance(array, cl_array.Array):
            raise InputTypeError(f"array must be a pyopencl.array.Array, got {type(array).__name__}")
        if array.offset or not array.flags.c_contiguous:
            raise InputValueError("array must be a whole C-contiguous device array, not a view; copy the view")
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            try:
                held = array.dtype.type(value)
            except (TypeError, ValueError, OverflowError) as error:
                raise InputValueError(f"value {value!r} cannot be held by the array's dtype {array.dtype}") from error
        if not (held == value or (array.dtype.kind == "f" and np.isnan(held) and np.isnan(value))):
            raise InputValueError(f"value {value!r} cannot be held exactly by the array's dtype {array.dtype}")
        if array.size:
            cl.enqueue_fill_buffer(self.queue, device_memory(array), held, 0, array.nbytes)
        return array

    def require_memory(self, what: str, total: int, largest: int | None = None) -> None:
        """Refuse, before anything is allocated, work that this device cannot hold.

        ``total`` is the bytes the call keeps on the device at once, ``largest`` its largest single
        buffer (default: ``total``). A driver reports an oversized request late and obscurely (an
        allocation failure mid-call, or a host swapping), so callers that size buffers from their
        arguments check here first and name what does fit.
        """
        largest = total if largest is None else largest
        limit_total, limit_one = self.device.global_mem_size, self.device.max_mem_alloc_size
        if total > limit_total or largest > limit_one:
            mib = 2**20
            raise InputValueError(
                f"{what} needs {total / mib:,.0f} MiB of device memory (largest buffer {largest / mib:,.0f} MiB); "
                f"{self.device.name} has {limit_total / mib:,.0f} MiB, at most {limit_one / mib:,.0f} MiB per buffer")

    def to_device(self, array: np.ndarray) -> cl_array.Array:
        """Copy a host array to a pooled device array (C order, the machine's own byte order: the kernels
        read native numbers, and a big-endian array's values are kept, not its bytes)."""
        array = np.ascontiguousarray(array)
        if not array.dtype.isnative:
            array = array.astype(array.dtype.newbyteorder("="))
        device_array = self.empty(array.shape, array.dtype)
        device_array.set(array, queue=self.queue)
        return device_array

    def constant(self, key: Any, make: Callable[[], np.ndarray]) -> cl_array.Array:
        """A read-only table on the device (filter taps, weights, look-up tables): ``make()``'s array,
        uploaded once per ``key`` for this machine's life. An upload waits for the queue to drain, which a
        stage whose fields stay on the device must not do on every call. Keys name their caller's module
        first, e.g. ("vmcl.group.curves", "tangent weights", smoothing); nothing may write a table.
        """
        table = self._constants.get(key)  # one look-up: another thread may clear the tables meanwhile
        if table is None:
            if len(self._constants) >= _MAX_CONSTANTS:  # a sweep over ever new settings must not grow it forever
                self._constants.clear()
            table = self._constants[key] = self.to_device(make())
        return table

    def read_into(self, out: np.ndarray, array: cl_array.Array, *, offset: int = 0) -> cl.Event | None:
        """Queue a copy of ``out.size`` elements of device ``array`` from element ``offset`` into the host
        array ``out`` (C-contiguous, of ``array``'s item size), without waiting: the event says when it is
        done (None when there was nothing to copy). Slicing a device array and reading the view costs
        several times the copy itself (pyopencl builds the view on the host).
        """
        if not out.flags.c_contiguous or out.itemsize != array.dtype.itemsize:
            raise InputValueError(f"out must be C-contiguous with items of {array.dtype.itemsize} bytes")
        if not array.flags.c_contiguous:
            raise InputValueError("array must be C-contiguous (a strided view's elements are not consecutive)")
        if offset < 0 or offset + out.size > array.size:
            raise InputValueError(f"elements {offset}..{offset + out.size} lie outside an array of {array.size}")
        if out.size == 0:
            return None
        # pyopencl's overloads type a read's source as Buffer; a pooled array's memory is one.
        return cl.enqueue_copy(self.queue, out, device_memory(array),  # type: ignore[call-overload]
                               src_offset=offset * out.itemsize + array.offset, is_blocking=False)

    def finish(self) -> None:
        self.queue.finish()

    # -- timings --------------------------------------------------------------------------------

    def timings(self, *, reset: bool = True) -> dict[str, dict[str, float]]:
        """Per-kernel device time since the last reset: {name: {"calls": n, "total_ms": t, "mean_ms": m,
        "bytes": b}}, b the bytes of the buffers its launches were given, summed over the launches (each
        buffer counted once per launch: the traffic of a kernel that reads and writes each of its buffers
        once, and a lower bound for one that reads a buffer more than once from beyond its caches; a
        device array counts its own size, a raw buffer its allocation's).

        Only available with ``profile=True``; waits for the queue to drain.
        """
        if not self.profile:
            raise RuntimeError("timings() needs a Machine created with profile=True")
        self.queue.finish()
        totals: dict[str, list[float]] = defaultdict(lambda: [0, 0.0, 0])
        for name, buffer_bytes, event in self._events:
            entry = totals[name]
            entry[0] += 1
            entry[1] += (event.profile.end - event.profile.start) * 1e-6
            entry[2] += buffer_bytes
        if reset:
            self._events.clear()
        return {name: {"calls": n, "total_ms": t, "mean_ms": t / n, "bytes": b}
                for name, (n, t, b) in sorted(totals.items())}

    def kernel_families(self) -> dict[str, str]:
        """The kernels this machine has made, by name: the kernels/<family>.cl each comes from (several
        families joined by "/" when they share a name)."""
        found: dict[str, set[str]] = defaultdict(set)
        with self._launch_lock:  # kernels are added under it, from any thread
            keys = list(self._kernels)
        for family, name, *_ in keys:
            found[name].add(family)
        return {name: "/".join(sorted(families)) for name, families in sorted(found.items())}


_default: Machine | None = None
_default_lock = threading.Lock()


def default_machine() -> Machine:
    """The process-wide Machine, created on first use (so importing vmcl compiles nothing)."""
    global _default
    with _default_lock:
        if _default is None:
            _default = Machine()
        return _default


def on_device(array: np.ndarray | cl_array.Array) -> cl_array.Array:
    """``array``, typed as the device array it is.

    vmcl's modules return host arrays for host input and device arrays for device input, and their
    result types say "either". A caller that gave device input (the pipeline and its cues) narrows the
    result with this; a host array here is a defect in vmcl, hence TypeError rather than an InputError.
    """
    if not isinstance(array, cl_array.Array):
        raise TypeError(f"expected a device array, got {type(array).__name__}")
    return array
