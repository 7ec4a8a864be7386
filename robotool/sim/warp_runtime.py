"""Warp, loaded quietly: the simulator's warp backend and the compiled kernels that run on the CPU share it."""

from __future__ import annotations

import functools
import os
import sys
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


_DTYPES = {np.dtype(np.float64): wp.float64, np.dtype(np.int32): wp.int32}


def cpu_view(values: np.ndarray) -> wp.array:
    """A Warp array on the CPU over a C-contiguous float64 or int32 numpy array's memory, without a copy (CPU launches
    run before they return, so the numpy array outlives the view's use; a kernel's writes land in it)."""
    if not values.flags.c_contiguous or values.dtype not in _DTYPES:
        raise ValueError(f"a kernel reads C-contiguous float64 or int32 arrays, not {values.dtype} {values.strides}")
    return wp.array(ptr=values.ctypes.data, dtype=_DTYPES[values.dtype], shape=values.shape, device="cpu")


def launch_on_cpu(kernel: Any, dim: int, *args: np.ndarray | int) -> None:
    """Run ``kernel`` on the CPU in ``dim`` threads, its array arguments numpy arrays viewed in place
    (:func:`cpu_view`)."""
    init_warp()
    inputs = [cpu_view(a) if isinstance(a, np.ndarray) else a for a in args]
    wp.launch(kernel, dim=dim, inputs=inputs, device="cpu")
