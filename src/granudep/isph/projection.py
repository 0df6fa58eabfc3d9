"""Energy-consistent projection (issue 11): the PPE divergence as the negative adjoint of the
pressure gradient that the corrector applies.

The corrector applies G p_i = L_i Σ_j V (p_j − p_i) ∇_i W_ij (renormalised, :func:`physics.pressure_gradient`;
the wall neighbours add a term that does not depend on p). Its pressure work on a velocity field u
is −Δt V Σ_i u_i·(G p)_i. With the divergence of the PPE source taken as D = −Gᵀ,

    D u_k = V Σ_j g_kj [ u_k·(L_k r_kj) + u_j·(L_j r_kj) ],   r_kj = x_k − x_j, ∇_k W_kj = g_kj r_kj,

the identity Σ_i u_i·(G p)_i = −Σ_k p_k (D u)_k holds exactly (summed over every granular particle),
so the pressure work of the projection is Δt V p·D u* = Δt² V/ρ p·(L_PPE p) plus the wall and
Dirichlet terms: ≤ 0 for the negative semi-definite compact Laplacian of the PPE. With the
renormalised divergence (not the adjoint) that identity fails, and the water dam break gains
energy through the pressure (+20 % of E_ref by t = 0.4 s at dx = 4 mm).

For a linear field u = u_k + A (x − x_k) on a lattice D u_k = tr A; in general
D u_k = tr A + u_k·(L_k + L̄_j) Σ_j V ∇_k W_kj + …: on a support cut by a wall that term measures the
velocity normal to the wall, but on a disordered cloud Σ_j V ∇_k W_kj ≠ 0 and a uniform translation
reads as divergence of order |u| × disorder / h (tests/isph/test_projection.py). That zero-order
inconsistency is why this option damps the water dam break (−58 % of E_ref by t = 0.4 s at dx = 4 mm
instead of +20 %) and is not the default (docs/paper-notes.md, "Energy budget").
"""
from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def adjoint_divergence(start, nbr, rx, ry, gw, nf, vol, u, v, lmat):
    """D u_k = −(Gᵀ u)_k for the renormalised pressure gradient with matrices ``lmat`` (rows
    L0 L1 / L2 L3, the ones the corrector uses); granular neighbours only."""
    div = np.zeros(nf)
    for k in range(nf):
        s = 0.0
        lk0 = lmat[k, 0]
        lk1 = lmat[k, 1]
        lk2 = lmat[k, 2]
        lk3 = lmat[k, 3]
        for q in range(start[k], start[k + 1]):
            j = nbr[q]
            if j >= nf:
                continue
            x = rx[q]
            y = ry[q]
            # u_k·(L_k r) + u_j·(L_j r)
            a = u[k] * (lk0 * x + lk1 * y) + v[k] * (lk2 * x + lk3 * y)
            b = u[j] * (lmat[j, 0] * x + lmat[j, 1] * y) + v[j] * (lmat[j, 2] * x + lmat[j, 3] * y)
            s += gw[q] * (a + b)
        div[k] = vol * s
    return div

