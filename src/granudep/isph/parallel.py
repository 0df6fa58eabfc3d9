"""The per-particle kernels' two builds: parallel (numba ``prange``) and serial, chosen per call.

Every kernel decorated with :func:`prange_kernel` is compiled on first use in the build the current
thread count asks for: ``parallel=True`` when numba runs more than one thread, a plain ``njit``
otherwise. A parallel build on one thread still hands every ``prange`` region to the threading
layer's worker and waits for it (workqueue: a condition-variable round trip, two futex calls and two
context switches per region). Measured (2 mm Bagnold layer, 80 particles, one thread): 3.5 ms per
step, 40 % of it system time in futex calls, against the few hundred microseconds of work. Each
``prange`` iteration writes only its own row (no reductions, ``PARALLEL`` below), so both builds
give the same results bit for bit (``tests/isph/test_threads.py``).

The serial build is compiled from a copy of the function with its own qualified name, so the two
builds keep separate on-disk caches (numba keys a cache file by module and qualified name).
"""
from __future__ import annotations

import functools
import types

import numba
from numba import njit

# numba parallel options of the per-particle kernels: the prange loops only (numpy=False: array
# allocations and reductions such as np.zeros or x.min() stay serial instead of each becoming a
# parallel region of its own; every region costs a wake-up of the worker threads, and on a loaded
# machine a wait for a time slice)
PARALLEL = {"prange": True, "numpy": False, "comprehension": False, "setitem": False, "reduction": False,
            "inplace_binop": False, "stencil": False, "fusion": False}

SERIAL_SUFFIX = "__serial"


def _renamed_copy(fn, suffix: str):
    """The same code object under another qualified name (its own numba cache index)."""
    g = types.FunctionType(fn.__code__, fn.__globals__, fn.__name__, fn.__defaults__, fn.__closure__)
    g.__qualname__ = fn.__qualname__ + suffix
    g.__module__ = fn.__module__
    g.__doc__ = fn.__doc__
    g.__kwdefaults__ = fn.__kwdefaults__
    return g


class PrangeKernel:
    """A ``prange`` kernel callable from Python: ``serial`` when ``numba.get_num_threads() == 1``,
    else ``parallel``. Both are ``cache=True`` dispatchers, compiled lazily (a one-thread run
    compiles only the serial build)."""

    def __init__(self, fn):
        self.py_func = fn
        # nogil: the predictor's kernels run while a second Python thread builds the PPE geometry
        # (solver._start_ppe_geometry)
        self.parallel = njit(cache=True, nogil=True, parallel=PARALLEL)(fn)
        self.serial = njit(cache=True, nogil=True)(_renamed_copy(fn, SERIAL_SUFFIX))
        functools.update_wrapper(self, fn)

    def build(self, threads: int | None = None):
        """The dispatcher a call with ``threads`` (default: numba's current count) uses."""
        n = numba.get_num_threads() if threads is None else threads
        return self.serial if n == 1 else self.parallel

    def __call__(self, *args):
        if numba.get_num_threads() == 1:
            return self.serial(*args)
        return self.parallel(*args)


def prange_kernel(fn) -> PrangeKernel:
    """Decorator for the per-particle kernels (see the module doc)."""
    return PrangeKernel(fn)
