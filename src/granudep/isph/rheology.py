"""μ(I) friction laws of the 2D runs and their well-posedness.

- eq (5) of the paper (Jop et al. 2006), written as the extended law of Barker & Gray (2017, eq 2.21)
  μ(I) = (μ_s I_0 + μ_2 I + μ_∞ I²)/(I_0 + I) (μ_∞ = 0: eq 5 exactly);
- the well-posedness test of the incompressible 2D equations (Barker et al. 2015; Barker & Gray
  2017, eq 3.9): with ν = I μ'(I)/μ(I), C(I) = 4ν² − 4ν + μ²(1 − ν/2)²; the equations are
  well posed where C < 0 and ill posed where C > 0 (there small perturbations grow the faster the
  shorter they are, which a discretisation shows as results that move under refinement);
- the partial regularisation of Barker & Gray (2017, eqs 6.3–6.4): below I_1^N, the low end of the
  well-posed band, μ(I) = sqrt(α / ln(A₋/I)) with A₋ = I_1^N exp(α (I_0 + I_1^N)²/(μ_s I_0 + μ_2 I_1^N
  + μ_∞ (I_1^N)²)²), continuous at I_1^N and well posed for every I < I_1^N.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from .operators import shear_rate


def mu_extended(i: np.ndarray | float, mu_s: float, mu_2: float, mu_inf: float, i0: float):
    """μ(I) = (μ_s I_0 + μ_2 I + μ_∞ I²)/(I_0 + I) (Barker & Gray 2017 eq 2.21; eq 5 for μ_∞ = 0)."""
    i = np.asarray(i, dtype=float)
    return (mu_s * i0 + mu_2 * i + mu_inf * i * i) / (i0 + i)


def well_posedness(i: np.ndarray | float, mu_s: float, mu_2: float, mu_inf: float, i0: float):
    """C(I) = 4ν² − 4ν + μ²(1 − ν/2)², ν = I μ'/μ (Barker & Gray 2017 eq 3.9): < 0 well posed."""
    i = np.asarray(i, dtype=float)
    mu = mu_extended(i, mu_s, mu_2, mu_inf, i0)
    dmu = ((mu_2 + 2.0 * mu_inf * i) * (i0 + i) - (mu_s * i0 + mu_2 * i + mu_inf * i * i)) / (i0 + i) ** 2
    nu = i * dmu / mu
    return 4.0 * nu * nu - 4.0 * nu + mu * mu * (1.0 - 0.5 * nu) ** 2


def ill_posed_bounds(mu_s: float, mu_2: float, mu_inf: float, i0: float) -> tuple[float, float]:
    """(I_1^N, I_2^N): the well-posed band of the unregularised law (nan, nan if there is none),
    by bisection on C(I) = 0 from a log grid of I in [1e-9, 1e3]."""
    grid = np.logspace(-9, 3, 4001)
    c = well_posedness(grid, mu_s, mu_2, mu_inf, i0)
    good = np.flatnonzero(c < 0.0)
    if good.size == 0:
        return float("nan"), float("nan")

    def root(a: float, b: float) -> float:
        ca = float(well_posedness(a, mu_s, mu_2, mu_inf, i0))
        for _ in range(200):
            m = math.sqrt(a * b)
            cm = float(well_posedness(m, mu_s, mu_2, mu_inf, i0))
            if (cm < 0.0) == (ca < 0.0):
                a, ca = m, cm
            else:
                b = m
        return math.sqrt(a * b)

    lo = root(grid[good[0] - 1], grid[good[0]]) if good[0] > 0 else float(grid[0])
    hi = root(grid[good[-1]], grid[good[-1] + 1]) if good[-1] < grid.size - 1 else float("inf")
    return lo, hi


def regularisation_constant(i_n1: float, mu_s: float, mu_2: float, mu_inf: float, i0: float,
                            alpha: float) -> float:
    """A₋ of Barker & Gray (2017, eq 6.4)."""
    m = mu_s * i0 + mu_2 * i_n1 + mu_inf * i_n1 * i_n1
    return i_n1 * math.exp(alpha * (i0 + i_n1) ** 2 / (m * m))


@njit(cache=True)
def friction(inertial, mu_s, mu_2, mu_inf, i0, i_n1, alpha, a_minus):
    """μ(I): the extended law above ``i_n1``; below it the partial regularisation
    sqrt(α / ln(A₋/I)) (``i_n1`` <= 0: no regularisation, eq 5 for every I)."""
    if i_n1 > 0.0 and inertial < i_n1:
        if inertial <= 0.0:
            return 0.0
        return math.sqrt(alpha / math.log(a_minus / inertial))
    return (mu_s * i0 + mu_2 * inertial + mu_inf * inertial * inertial) / (i0 + inertial)


@njit(cache=True)
def regularised_viscosity(grad, p, d, rho_s, law, bounds):
    """η = μ(I) p/|γ̇| with μ(I) from :func:`friction`, capped to bounds = (eta_min, eta_max); returns
    η, |γ̇| (|γ̇| from :func:`granudep.isph.operators.shear_rate`, as in ``mu_i_viscosity``).
    law = (mu_s, mu_2, mu_inf, i0, i_n1, alpha, a_minus): :func:`friction`'s constants."""
    mu_s, mu_2, mu_inf, i0, i_n1, alpha, a_minus = law
    eta_min, eta_max = bounds
    n = p.size
    eta = np.empty(n)
    gdot = np.empty(n)
    for i in range(n):
        gd = shear_rate(grad, i)
        gdot[i] = gd
        pi = max(p[i], 0.0)
        if pi <= 0.0:
            e = eta_min
        elif gd <= 0.0:
            e = eta_max
        else:
            inertial = gd * d / math.sqrt(pi / rho_s)
            e = friction(inertial, mu_s, mu_2, mu_inf, i0, i_n1, alpha, a_minus) * pi / gd
        eta[i] = min(max(e, eta_min), eta_max)
    return eta, gdot
