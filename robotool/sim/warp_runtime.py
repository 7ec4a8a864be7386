"""Warp, loaded quietly: the simulator's warp backend and the compiled kernels that run on the CPU share it."""

from __future__ import annotations

import functools
import os
import sys
import threading
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
import warp as wp

from robotool.sim.backend import cuda_driver_found

if TYPE_CHECKING:  # the type checker cannot read Warp's kernel dialect: to it, kernel values are Any
    Floats: Any
    Floats2: Any
    Floats3: Any
    Ints: Any
    Float: Any
    Int: Any
    Vec3: Any
else:  # what Warp reads in a kernel's annotations and calls
    Floats, Floats2, Floats3 = (kind(dtype=wp.float64) for kind in (wp.array, wp.array2d, wp.array3d))
    Ints = wp.array(dtype=wp.int32)
    Float, Int, Vec3 = wp.float64, wp.int32, wp.vec3d


@functools.cache
def init_warp() -> None:
    """``wp.init()`` without its banner and per-module load messages; without a CUDA driver, the line Warp's native
    library prints about it is left out too (the command line says once that warp runs on the CPU)."""
    wp.config.log_level = wp.LOG_WARNING
    if cuda_driver_found():
        wp.init()
        return
    sys.stderr.flush()
    saved = os.dup(2)
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 2)
            wp.init()
    finally:
        os.dup2(saved, 2)
        os.close(saved)


_DTYPES: dict[np.dtype, Any] = {np.dtype(np.float64): wp.float64, np.dtype(np.int32): wp.int32}
_NUMPY: dict[Any, np.dtype] = {kind: dtype for dtype, kind in _DTYPES.items()}


def cpu_view(values: np.ndarray) -> wp.array:
    """A Warp array on the CPU over a C-contiguous float64 or int32 numpy array's memory, without a copy (CPU launches
    run before they return, so the numpy array outlives the view's use; a kernel's writes land in it)."""
    _check_layout(values)
    return wp.array(ptr=values.ctypes.data, dtype=_DTYPES[values.dtype], shape=values.shape, device="cpu")


def _check_layout(values: np.ndarray) -> None:
    if not values.flags.c_contiguous or values.dtype not in _DTYPES:
        raise ValueError(f"a kernel reads C-contiguous float64 or int32 arrays, not {values.dtype} {values.strides}")


@dataclass
class _Replay:
    """A kernel's launch recorded once (Warp's ``record_cmd``) and replayed with new arguments: each array argument is
    a C struct (its pointer, shape and strides, as Warp would build it) handed to the launch once and rewritten in
    place for every replay, not a ``wp.array`` packed anew on every launch (most of a small launch's time)."""

    launch: Any
    expected: list[tuple[int, np.dtype] | None]  # each argument's (ndim, dtype) when it is an array
    structs: list[Any]  # each array argument's C struct (None for the others)
    dim: int = -1  # the launch's number of threads, set when it changes
    written: list[Any] = field(default_factory=list)  # each argument as last written (a scalar, or shape and strides)
    held: list[Any] = field(default_factory=list)  # each array argument last written, kept alive: passed again, as is

    @classmethod
    def record(cls, kernel: Any, dim: int, args: tuple[np.ndarray | int | float, ...]) -> _Replay:
        inputs = [cpu_view(a) if isinstance(a, np.ndarray) else a for a in args]
        launch = wp.launch(kernel, dim=dim, inputs=inputs, device="cpu", record_cmd=True)
        expected = [
            (arg.type.ndim, _NUMPY[arg.type.dtype]) if wp.types.is_array(arg.type) else None for arg in kernel.adj.args
        ]
        structs = [  # of the type Warp packed for the argument (after the launch bounds)
            type(launch.params[1 + i])(ndim=e[0], shape=(0,) * e[0], strides=(0,) * e[0]) if e else None
            for i, e in enumerate(expected)
        ]
        for i, struct in enumerate(structs):
            if struct is not None:
                launch.set_param_at_index_from_ctype(i, struct)
        return cls(launch, expected, structs, written=[None] * len(expected), held=[None] * len(expected))

    def run(self, dim: int, args: tuple[np.ndarray | int | float, ...]) -> None:
        if len(args) != len(self.expected):
            raise TypeError(f"the kernel takes {len(self.expected)} arguments, not {len(args)}")
        written, held = self.written, self.held
        for i, (value, expected) in enumerate(zip(args, self.expected, strict=True)):
            if expected is None:
                if written[i] is None or written[i] != value:  # (Warp packs a scalar at some cost: only anew)
                    self.launch.set_param_at_index(i, value)
                    written[i] = value
                continue
            if value is held[i] and written[i] == (value.shape, value.strides):
                continue  # the array last written, alive since: its struct holds its pointer and layout
            if not isinstance(value, np.ndarray) or (value.ndim, value.dtype) != expected:
                got = f"{value.ndim}-d {value.dtype}" if isinstance(value, np.ndarray) else type(value).__name__
                raise ValueError(f"argument {i} must be a {expected[0]}-d {expected[1]} array, not {got}")
            _check_layout(value)
            struct = self.structs[i]
            struct.data = value.ctypes.data
            held[i] = value
            layout = (value.shape, value.strides)
            if written[i] != layout:
                struct.shape[: value.ndim] = value.shape
                struct.strides[: value.ndim] = value.strides
                written[i] = layout
        if dim != self.dim:
            self.launch.set_dim(dim)
            self.dim = dim
        self.launch.launch()


_replays = threading.local()  # per thread: a recorded launch's arguments are rewritten on every replay


def launch_on_cpu(kernel: Any, dim: int, *args: np.ndarray | int | float) -> None:
    """Run ``kernel`` on the CPU in ``dim`` threads, its array arguments numpy arrays viewed in place (C-contiguous,
    float64 or int32, of the dimensions the kernel declares): the first launch of a kernel in a thread is recorded,
    later ones replay it with their own arguments (:class:`_Replay`)."""
    init_warp()
    cache: dict[Any, _Replay] = _replays.__dict__.setdefault("by_kernel", {})
    replay = cache.get(kernel)
    if replay is None:
        replay = cache[kernel] = _Replay.record(kernel, dim, args)
    replay.run(dim, args)
