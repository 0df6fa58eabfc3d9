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


#: share of the material above threshold a contiguous run must hold to count as a main run
MAIN_RUN_FRACTION = 0.01


def main_run_front(x_edges: np.ndarray, depth: np.ndarray, threshold: float, width=1.0,
                   fraction: float = MAIN_RUN_FRACTION) -> float:
    """:func:`front_from_profile` started in the farthest down-slope contiguous run of cells with
    depth ≥ threshold that holds at least ``fraction`` of the material above threshold (depth ×
    width × cell length). The runout of a DA run: material left in the release zone can be deeper
    than the deposit down-slope and separated from it by a trough just below the threshold, and the
    walk from the deepest cell would then stop in the release zone."""
    depth = np.asarray(depth, dtype=float)
    above = depth >= threshold
    if not above.any():
        return float("nan")
    vol = depth * width * np.diff(x_edges)
    starts = np.flatnonzero(above & ~np.concatenate([[False], above[:-1]]))
    ends = np.flatnonzero(above & ~np.concatenate([above[1:], [False]]))
    runs = np.array([vol[a:b + 1].sum() for a, b in zip(starts, ends)])
    main = np.flatnonzero(runs >= fraction * runs.sum())
    return front_from_profile(x_edges, depth, threshold, start=int(starts[main[-1]]))


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


# ---------------------------------------------------------------------------------------------
# Robust front measures: the same four numbers for 2D and DA depth profiles
# ---------------------------------------------------------------------------------------------
#: thickness of the second attached front, m (independent of the grain size and of dx)
FRONT_FIXED_THICKNESS = 0.005
#: share of the deposit's area (volume per unit width) allowed beyond the volume front
FRONT_VOLUME_SHARE = 0.01


def volume_front(x_edges: np.ndarray, depth: np.ndarray, share: float = FRONT_VOLUME_SHARE) -> float:
    """The point beyond which ``share`` of the profile's area lies (area = ∫ depth dx, the volume per
    unit width). The depth is taken as constant in each cell, so the point is linear inside the cell
    where the cumulative area crosses (1 − share) of the total. NaN for an empty profile.

    Unlike a thickness threshold it does not depend on how thin the leading sheet is: a sheet of
    any thickness moves it only as far as its volume carries it."""
    depth = np.asarray(depth, dtype=float)
    x_edges = np.asarray(x_edges, dtype=float)
    area = depth * np.diff(x_edges)
    total = float(area.sum())
    if not total > 0.0:
        return float("nan")
    cum = np.concatenate([[0.0], np.cumsum(area)])
    target = (1.0 - share) * total
    k = int(np.searchsorted(cum, target, side="left"))      # cum[k-1] < target <= cum[k]
    k = min(max(k, 1), depth.size)
    a = area[k - 1]
    frac = 0.0 if a <= 0.0 else (target - cum[k - 1]) / a
    return float(x_edges[k - 1] + frac * (x_edges[k] - x_edges[k - 1]))


def tail_extent(x_edges: np.ndarray, depth: np.ndarray) -> float:
    """Down-slope edge of the attached mass at any thickness (the thin-tail extent): the front rule
    with a zero threshold. Grows under refinement for a local μ(I) continuum (a thinner sheet can
    still flow at finer Δx), so it is reported, never used as the converged runout."""
    depth = np.asarray(depth, dtype=float)
    return front_from_profile(x_edges, depth, np.nextafter(0.0, 1.0))


def front_measures(x_edges: np.ndarray, depth: np.ndarray, d: float,
                   fixed: float = FRONT_FIXED_THICKNESS, share: float = FRONT_VOLUME_SHARE) -> dict:
    """The robust front measures of one depth profile, by name:

    - ``front_2d``: attached front at a thickness of 2 grain diameters (the default front);
    - ``front_5mm``: attached front at a fixed thickness ``fixed`` (5 mm);
    - ``front_v99``: the point beyond which ``share`` (1 %) of the volume lies;
    - ``front_tail``: the attached mass at any thickness (thin tail; not a converged quantity).
    """
    return {
        "front_2d": front_from_profile(x_edges, depth, 2.0 * d),
        "front_5mm": front_from_profile(x_edges, depth, fixed),
        "front_v99": volume_front(x_edges, depth, share),
        "front_tail": tail_extent(x_edges, depth),
    }


#: long names of the measures, for the output files
FRONT_MEASURE_DOC = {
    "front_2d": "attached front: first bed cell, walking down-slope from the deepest cell, thinner than 2 d",
    "front_5mm": "attached front at a fixed 5 mm thickness (same rule as front_2d)",
    "front_v99": "point beyond which 1 % of the deposit's area (volume per unit width) lies",
    "front_tail": "attached mass at any thickness (thin-tail extent; grows under refinement, not a converged measure)",
}
