"""The μ(I) viscosity and the implicit viscous system of the ISPH scheme (numba).

η = μ(I) p/|γ̇| (eq 5 of the paper, capped to [η_min, η_max]) and the variable-viscosity Laplacian
with the pair viscosity η̄_ij (:func:`pair_viscosity`), assembled as a sparse system per velocity
component. Friction laws as formulas and their well-posedness: :mod:`granudep.isph.rheology`.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from .parallel import prange_kernel


from .operators import shear_rate


from .walls import SLIP_COULOMB, wall_beta


MEAN_HARMONIC, MEAN_GEOMETRIC, MEAN_ARITHMETIC, MEAN_STRESS = 0, 1, 2, 3
MEAN_CODES = {"harmonic": MEAN_HARMONIC, "geometric": MEAN_GEOMETRIC, "arithmetic": MEAN_ARITHMETIC,
              "stress": MEAN_STRESS}


@njit(cache=True, inline="always")
def pair_viscosity(ei, ej, gi, gj, mean):
    """Pair viscosity η̄_ij of the variable-viscosity Laplacian (gi, gj: shear rates |γ̇|).

    ``stress``: the pair's mean stress over its mean shear rate, (η_i γ̇_i + η_j γ̇_j)/(γ̇_i + γ̇_j);
    for a linear stress profile the pair flux then carries the midpoint stress.
    """
    if mean == MEAN_STRESS:
        g = gi + gj
        if g > 0.0:
            return (ei * gi + ej * gj) / g
        return 0.5 * (ei + ej)
    if mean == MEAN_HARMONIC:
        return 2.0 * ei * ej / (ei + ej + 1e-300)
    if mean == MEAN_GEOMETRIC:
        return math.sqrt(ei * ej)
    return 0.5 * (ei + ej)


@prange_kernel
def mu_i_viscosity(grad, p, d, rho_s, mu_s, mu_2, i0, eta_min, eta_max):
    """η = μ(I) p / |γ̇| capped to [eta_min, eta_max] (eqs 4–5); returns η and |γ̇|.

    |γ̇| = sqrt(2 D:D) with D = (∇u + ∇uᵀ)/2, i.e. sqrt(½ γ̇_ij γ̇_ij) with γ̇ = 2D: equals |du/dy|
    in simple shear (Jop et al. 2006). p is clipped at 0; I = |γ̇| d / sqrt(p/ρ_s).
    """
    n = p.size
    eta = np.empty(n)
    gdot = np.empty(n)
    for i in prange(n):
        gd = shear_rate(grad, i)
        gdot[i] = gd
        pi = max(p[i], 0.0)
        if pi <= 0.0:
            e = eta_min
        elif gd * eta_max <= mu_s * pi:
            e = eta_max  # below yield even at I = 0: quasi-rigid
        else:
            inertial = gd * d / math.sqrt(pi / rho_s)
            mu = mu_s + (mu_2 - mu_s) * inertial / (i0 + inertial)
            e = mu * pi / gd
        eta[i] = min(max(e, eta_min), eta_max)
    return eta, gdot


@prange_kernel
def assemble_viscous(pairs, nf, vol, pos, visc, walls, law, consts, mean, wall_ns):
    """Implicit viscous matrices A = I − Δt/ρ ∇·(η∇·) (Morris Laplacian, pair viscosity
    :func:`pair_viscosity`, ``rheology.pair_mean``: stress-weighted by default) as CSR; pos = (x, y),
    visc = (η, |γ̇|), law = (slip code, slip length) of the wall, consts = (dx, Δt, ρ, ε², Laplacian norm).

    Row i: (1 + Δt/ρ Σ_j c_ij + wall_i) u_i − Δt/ρ Σ_j c_ij u_j,
    c_ij = 2 η̄_ij V F_ij, F_ij = −r dW/dr/(r² + ε²) ≥ 0, η̄ = 2 η_i η_j/(η_i + η_j). Symmetric.
    The wall term acts on the tangential component only (the normal one is the pressure's job):
    wall_i = Δt/ρ Σ_w 2 η_i V F_iw β φ t_a², t = wall tangent, a = x (u matrix) or y (v matrix).
    Returns indptr, indices, data (diagonal first in each row, u matrix) and diag_v (v matrix).
    """
    x, y = pos
    eta, gdot = visc
    slip, slip_length = law
    dx, dt, rho, eps2, lap_norm = consts
    start, nbr, rr, gw = pairs.start, pairs.nbr, pairs.rr, pairs.gw
    wnx, wny, wc = walls.nx, walls.ny, walls.c
    indptr = np.zeros(nf + 1, np.int64)
    for i in prange(nf):
        cnt = 1
        for k in range(start[i], start[i + 1]):
            if nbr[k] < nf:
                cnt += 1
        indptr[i + 1] = cnt
    for i in range(nf):
        indptr[i + 1] += indptr[i]
    nnz = indptr[nf]
    indices = np.empty(nnz, np.int64)
    data = np.empty(nnz)
    diag_v = np.empty(nf)
    fac = dt / rho
    for i in prange(nf):
        pos = indptr[i]
        dpos = pos
        indices[pos] = i
        pos += 1
        diag = 1.0
        wu = 0.0
        wv = 0.0
        for k in range(start[i], start[i + 1]):
            j = nbr[k]
            r = rr[k]
            f = -gw[k] * r * r / (r * r + eps2) / lap_norm
            if j < nf:
                ebar = pair_viscosity(eta[i], eta[j], gdot[i], gdot[j], mean)
                cij = fac * 2.0 * ebar * vol * f
                indices[pos] = j
                data[pos] = -cij
                pos += 1
                diag += cij
            else:
                w = j - nf
                beta = wall_beta(x[i], y[i], wnx[w], wny[w], wc[w], x[j], y[j], slip, slip_length, dx)
                if slip == SLIP_COULOMB:
                    continue  # friction enters through coulomb_wall_drag
                cw = fac * 2.0 * eta[i] / wall_ns * vol * f * lap_norm * beta
                # tangent t = (-n_y, n_x)
                wu += cw * wny[w] * wny[w]
                wv += cw * wnx[w] * wnx[w]
        data[dpos] = diag + wu
        diag_v[i] = diag + wv
    return indptr, indices, data, diag_v
