"""Stage package: isph.

The per-particle kernels run in parallel (numba ``prange``, ``NUMBA_NUM_THREADS`` threads). Numba's
threading layer defaults here to ``workqueue`` (unless ``NUMBA_THREADING_LAYER`` is set): the OpenMP
layer, which numba picks first when libgomp is present, spin-waits between parallel regions, and
on a loaded machine (T22-A150 at 4 mm, 2 threads, load average 11 on 2 cores) that made a step
16x slower (885 vs 57 ms/step with workqueue; 51 ms on one thread). On one thread the kernels run
their serial builds and no threading layer is involved (``parallel.py``).
"""
import os as _os

if "NUMBA_THREADING_LAYER" not in _os.environ:
    from numba import config as _config
    _config.THREADING_LAYER = "workqueue"
