"""The bundles the ISPH kernels take: one home for the pair list and one for the wall
surface, instead of five to seven loose arrays per kernel call.

Both are ``NamedTuple`` s of arrays: numba passes them to ``njit(cache=True)`` and ``prange`` kernels
as tuples (the fields are read at the top of each kernel, so the arithmetic is the one of the loose
arrays, bit for bit). The solver builds :class:`Pairs` once per step (:func:`pairs_of`) and
:class:`WallSurface` once per run (the wall particles do not move).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .neighbours import build_neighbours
from .operators import pair_kernel


class Pairs(NamedTuple):
    """The step's neighbour list (:func:`neighbours.build_neighbours`) and the kernel on it:
    CSR rows of the granular particles (``start``, length nf + 1), neighbour indices ``nbr``
    (granular < nf ≤ wall), pair vectors r_ij = x_i − x_j (``rx``, ``ry``), distances ``rr``, the
    Wendland kernel W_ij (``wk``) and (dW/dr)/r (``gw``) per pair (:func:`operators.pair_kernel`)."""
    start: np.ndarray
    nbr: np.ndarray
    rx: np.ndarray
    ry: np.ndarray
    rr: np.ndarray
    wk: np.ndarray
    gw: np.ndarray


class WallSurface(NamedTuple):
    """Per wall particle: the unit normal of the wall surface into the granular domain (``nx``,
    ``ny``) and its offset ``c`` (n·x = c on the surface)."""
    nx: np.ndarray
    ny: np.ndarray
    c: np.ndarray


def pairs_of(x, y, nf: int, radius: float, period: float, h: float) -> Pairs:
    """The neighbour list of the nf granular particles (walls after them in x, y) within ``radius``
    (x periodic over ``period`` when > 0) and the kernel of smoothing length h on it."""
    start, nbr, rx, ry, rr = build_neighbours(x, y, nf, radius, period)
    wk, gw = pair_kernel(rr, h)
    return Pairs(start, nbr, rx, ry, rr, wk, gw)
