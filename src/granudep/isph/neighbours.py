"""Cell-linked neighbour search (numba): a flat per-particle neighbour list rebuilt each step.

Rows are the fluid (granular) particles 0..nf-1; neighbours are any particle (fluid or wall)
within ``radius`` (= 2h, the Wendland C2 support). The list is CSR-like: the neighbours of fluid
particle i are ``nbr[start[i]:start[i+1]]`` with pair vectors ``rx = x_i - x_j``, ``ry`` and
distance ``r``. With ``period > 0`` the domain is periodic in x on [0, period) (minimum image).
"""
from __future__ import annotations

import numpy as np
from numba import njit, prange


from .parallel import prange_kernel


@njit(cache=True)
def _cells(x, y, cell, period, xmin, ymin, ncx, ncy):
    n = x.size
    cid = np.empty(n, np.int64)
    for k in range(n):
        cx = int((x[k] - xmin) / cell)
        if period > 0.0:
            cx = cx % ncx
        else:
            cx = min(max(cx, 0), ncx - 1)
        cy = min(max(int((y[k] - ymin) / cell), 0), ncy - 1)
        cid[k] = cx * ncy + cy
    counts = np.zeros(ncx * ncy + 1, np.int64)
    for k in range(n):
        counts[cid[k] + 1] += 1
    for c in range(ncx * ncy):
        counts[c + 1] += counts[c]
    order = np.empty(n, np.int64)
    fill = counts[:-1].copy()
    for k in range(n):
        order[fill[cid[k]]] = k
        fill[cid[k]] += 1
    return cid, counts, order


@njit(cache=True, inline="always")
def _minimum_image(ddx, period, half):
    """x separation under the periodic minimum-image convention (unchanged when period <= 0)."""
    if period > 0.0:
        if ddx > half:
            return ddx - period
        if ddx < -half:
            return ddx + period
    return ddx


@prange_kernel
def build_neighbours(x, y, nf, radius, period):
    """Neighbours within ``radius`` of each of the first ``nf`` particles (self excluded).

    Returns start (nf+1), nbr, rx, ry, r.
    """
    n = x.size
    if period > 0.0:
        xmin = 0.0
        ncx = max(int(period / radius), 1)
        cell_x = period / ncx
    else:
        xmin = x.min() - 1e-9
        cell_x = radius
        ncx = int((x.max() - xmin) / cell_x) + 1
    ymin = y.min() - 1e-9
    # cells are square with side >= radius; with periodicity the x side is period/ncx >= radius
    cell = cell_x
    ncy = int((y.max() - ymin) / cell) + 1
    cid, counts, order = _cells(x, y, cell, period, xmin, ymin, ncx, ncy)
    # positions in cell order: the candidates of a column of three cells are then one contiguous run
    xs = np.empty(n)
    ys = np.empty(n)
    for s in prange(n):
        xs[s] = x[order[s]]
        ys[s] = y[order[s]]
    r2max = radius * radius
    half = 0.5 * period
    # one distance search: the accepted neighbours of particle i go to its row of ``buf``, whose width
    # bounds any particle's neighbour count (all neighbours lie in the 3 x 3 block of cells); then
    # the CSR list is filled from ``buf`` in the same order
    width = 0
    for c in range(ncx * ncy):
        width = max(width, counts[c + 1] - counts[c])
    width *= 9
    # the rows are independent (parallel over particles, each writes its own row of ``buf`` and its
    # count); the offsets ``start`` are the serial prefix sum of the counts, then the rows are copied
    start = np.zeros(nf + 1, np.int64)
    buf = np.empty(nf * width, np.int32)
    for i in prange(nf):
        ci = cid[i] // ncy
        cj = cid[i] % ncy
        xi = x[i]
        yi = y[i]
        cnt = 0
        base = i * width
        for dxc in range(-1, 2):
            cx = ci + dxc
            if period > 0.0:
                if ncx < 3 and dxc != 0 and (ncx == 1 or dxc == 1):
                    continue  # avoid visiting the same column twice
                cx = cx % ncx
            elif cx < 0 or cx >= ncx:
                continue
            # cells (cx, cj - 1 .. cj + 1), in cell order (same visiting order as cell by cell)
            c0 = cx * ncy + max(cj - 1, 0)
            c1 = cx * ncy + min(cj + 1, ncy - 1)
            for s in range(counts[c0], counts[c1 + 1]):
                ddx = _minimum_image(xi - xs[s], period, half)
                ddy = yi - ys[s]
                if ddx * ddx + ddy * ddy < r2max:
                    j = order[s]
                    if j != i:
                        buf[base + cnt] = j
                        cnt += 1
        start[i + 1] = cnt
    for i in range(nf):
        start[i + 1] += start[i]
    m = start[nf]
    nbr = np.empty(m, np.int64)
    rx = np.empty(m)
    ry = np.empty(m)
    rr = np.empty(m)
    for i in prange(nf):
        k = start[i]
        for c in range(start[i + 1] - start[i]):
            j = buf[i * width + c]
            ddx = _minimum_image(x[i] - x[j], period, half)
            ddy = y[i] - y[j]
            nbr[k] = j
            rx[k] = ddx
            ry[k] = ddy
            rr[k] = np.sqrt(ddx * ddx + ddy * ddy)
            k += 1
    return start, nbr, rx, ry, rr
