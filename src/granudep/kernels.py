"""2D SPH kernel shared by the ISPH solver and the monitoring-section analysis (eq 16).

Wendland C2 in 2D (Wendland 1995; Dehnen & Aly 2012), support radius 2h:
W(q) = α_d (1 − q/2)^4 (2q + 1),  q = r/h ≤ 2,  α_d = 7 / (4π h²).
The 1D Gaussian kernel of the DA model (eqs 23–24) lives in ``granudep.da.kernels``.
"""
from __future__ import annotations

import math

from numba import njit

SUPPORT = 2.0  # kernel support radius in units of h


@njit(cache=True, inline="always")
def wendland_w(r: float, h: float) -> float:
    """W(r, h) in 2D."""
    q = r / h
    if q >= 2.0:
        return 0.0
    t = 1.0 - 0.5 * q
    return 7.0 / (4.0 * math.pi * h * h) * t * t * t * t * (2.0 * q + 1.0)


@njit(cache=True, inline="always")
def wendland_dwdr(r: float, h: float) -> float:
    """dW/dr in 2D (≤ 0); ∇_i W_ij = dW/dr · (x_i − x_j)/r."""
    q = r / h
    if q >= 2.0:
        return 0.0
    t = 1.0 - 0.5 * q
    return 7.0 / (4.0 * math.pi * h * h * h) * (-5.0 * q) * t * t * t
