"""Neighbour search in 1D: particles kept sorted by position, one index window per particle.

Particles are re-sorted every step by an insertion sort (O(N) when nearly sorted, which they are
between steps); the neighbours of particle i are the contiguous index range [lo_i, hi_i) of the
sorted array whose positions lie within the kernel support. Never an all-pairs loop.

The back wall at x = 0 is a mirror: particles closer to the wall than the support get a ghost at
−x with the same volume and opposite velocity (``build_extended``).
"""
from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def insertion_sort(x, arrays, order):
    """Sort ``x`` ascending in place, applying the same permutation to the rows of ``arrays``
    (2D float array, one row per field) and to ``order`` (int ids). Stable."""
    n = x.shape[0]
    m = arrays.shape[0]
    tmp = np.empty(m)
    for i in range(1, n):
        xi = x[i]
        if x[i - 1] <= xi:
            continue
        for k in range(m):
            tmp[k] = arrays[k, i]
        oi = order[i]
        j = i - 1
        while j >= 0 and x[j] > xi:
            x[j + 1] = x[j]
            for k in range(m):
                arrays[k, j + 1] = arrays[k, j]
            order[j + 1] = order[j]
            j -= 1
        x[j + 1] = xi
        for k in range(m):
            arrays[k, j + 1] = tmp[k]
        order[j + 1] = oi


@njit(cache=True)
def count_ghosts(x, radius, wall):
    """Number of (sorted, x ≥ 0) particles within ``radius`` of the wall (0 if no wall)."""
    if not wall:
        return 0
    m = 0
    n = x.shape[0]
    while m < n and x[m] < radius:
        m += 1
    return m


@njit(cache=True)
def build_extended(x, u, V, m, xe, ue, Ve):
    """Fill the extended arrays: m mirror ghosts (ascending) followed by the n real particles."""
    n = x.shape[0]
    for k in range(m):
        j = m - 1 - k
        xe[k] = -x[j]
        ue[k] = -u[j]
        Ve[k] = V[j]
    for i in range(n):
        xe[m + i] = x[i]
        ue[m + i] = u[i]
        Ve[m + i] = V[i]


@njit(cache=True)
def windows(xe, first, ne, radius, lo, hi):
    """For each real particle i (extended index first + i, ascending positions), the index window
    [lo[i], hi[i]) of extended particles with |x_j − x_i| ≤ radius (two-pointer sweep)."""
    a = 0
    b = 0
    for k in range(first, ne):
        xi = xe[k]
        while a < ne and xe[a] < xi - radius:
            a += 1
        if b < k + 1:
            b = k + 1
        while b < ne and xe[b] <= xi + radius:
            b += 1
        lo[k - first] = a
        hi[k - first] = b
