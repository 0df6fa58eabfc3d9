"""Front position and flow time, defined once so 2D and DA runs are compared like with like.

Front (both models): walk down-slope from the main mass over a depth profile on a grid and stop
at the first cell whose depth is below ``threshold`` (default in configs: 2 grain diameters,
the thinnest layer that is still a continuous granular flow). Isolated particles or cells ahead
of a gap do not set the front. The front is the down-slope edge of the last cell above threshold.

Flow time: the first time after which the front advances by less than ``tol`` in total
(i.e. x_front(t_end) − x_front(t) < tol); the run must have reached rest for this to be the
paper's "time when the flow comes to rest".
"""
from __future__ import annotations

import numpy as np


def front_from_profile(x_edges: np.ndarray, depth: np.ndarray, threshold: float, start: int | None = None) -> float:
    """Down-slope edge of the contiguous run of cells with depth ≥ threshold.

    x_edges: cell edges (n+1, increasing); depth: per-cell depth (n); start: index of a cell inside
    the main mass (default: the cell of maximum depth). Returns NaN if no cell reaches threshold.
    """
    depth = np.asarray(depth, dtype=float)
    above = depth >= threshold
    if not above.any():
        return float("nan")
    i = int(np.argmax(depth)) if start is None else int(start)
    if not above[i]:
        i = int(np.flatnonzero(above)[0])
    gaps = np.flatnonzero(~above[i:])
    last = (len(depth) - 1) if gaps.size == 0 else i + gaps[0] - 1
    return float(x_edges[last + 1])


def flow_time(time: np.ndarray, front: np.ndarray, tol: float) -> float:
    """First time after which the front moves less than ``tol`` (m) until the end of the record."""
    time = np.asarray(time, dtype=float)
    front = np.asarray(front, dtype=float)
    ok = np.isfinite(front)
    time, front = time[ok], front[ok]
    if time.size == 0:
        return float("nan")
    remaining = np.maximum.accumulate(front[::-1])[::-1]  # furthest front from t onward
    moving = (front[-1] - front) >= tol
    moving |= (remaining - front) >= tol
    idx = np.flatnonzero(moving)
    return float(time[0] if idx.size == 0 else time[min(idx[-1] + 1, time.size - 1)])
