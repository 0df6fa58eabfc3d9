"""The pressure Poisson system of the approximate projection (``numerics.projection: approximate``;
numba). The adjoint-pair projection, the default, is :mod:`granudep.isph.projection`.
"""
from __future__ import annotations

import numpy as np
from numba import prange

from .parallel import prange_kernel


@prange_kernel
def assemble_ppe(pairs, nf, vol, unknowns, p_dir, div, vel, density, walls, consts):
    """PPE Σ_j a_ij (p_i − p_j) = −(ρ/Δt) ∇·u* − γ ρ/Δt² min(1 − C_i/C0, 0) over the unknown
    (non-free-surface) particles; a_ij = 2 V F_ij (Cummins & Rudman 1999 Laplacian). Free-surface
    neighbours have their Dirichlet value ``p_dir``; wall neighbours use the mirror pressure (Neumann), which moves to the RHS.
    Kernel completion: where the support is truncated (next to the free surface) the missing
    neighbours are taken at p = 0, i.e. diag += max(a_full − Σ_j a_ij, 0) with a_full the
    full-lattice sum (``a_full`` <= 0 switches this off).
    Symmetric positive definite whenever every cluster touches a free surface.
    unknowns = (unknown[particle], their number); vel = (u*, v*); density = (C, C0, γ);
    consts = (Δt, ρ, ε², a_full, Laplacian norm)."""
    unknown, n_unknown = unknowns
    us, vs = vel
    conc, c0, relax = density
    dt, rho, eps2, a_full, lap_norm = consts
    start, nbr, rx, ry, rr, gw = pairs.start, pairs.nbr, pairs.rx, pairs.ry, pairs.rr, pairs.gw
    wnx, wny = walls.nx, walls.ny
    indptr = np.zeros(n_unknown + 1, np.int64)
    for i in prange(nf):
        row = unknown[i]
        if row < 0:
            continue
        cnt = 1
        for k in range(start[i], start[i + 1]):
            j = nbr[k]
            if j < nf and unknown[j] >= 0:
                cnt += 1
        indptr[row + 1] = cnt
    for r in range(n_unknown):
        indptr[r + 1] += indptr[r]
    nnz = indptr[n_unknown]
    indices = np.empty(nnz, np.int64)
    data = np.empty(nnz)
    rhs = np.zeros(n_unknown)
    for i in prange(nf):
        row = unknown[i]
        if row < 0:
            continue
        pos = indptr[row]
        dpos = pos
        indices[pos] = row
        pos += 1
        diag = 0.0
        asum = 0.0
        b = -rho / dt * div[i] - relax * rho / (dt * dt) * min(1.0 - conc[i] / c0, 0.0)
        for k in range(start[i], start[i + 1]):
            j = nbr[k]
            r = rr[k]
            a = 2.0 * vol * (-gw[k]) * r * r / (r * r + eps2) / lap_norm
            asum += a
            if j < nf:
                diag += a
                if unknown[j] >= 0:
                    indices[pos] = unknown[j]
                    data[pos] = -a
                    pos += 1
                else:
                    b += a * p_dir[j]
            else:
                w = j - nf
                nx = wnx[w]
                ny = wny[w]
                gn = rho / dt * min(us[i] * nx + vs[i] * ny, 0.0)
                # p_i - p_w = G (n·r_iw)
                b -= a * gn * (nx * rx[k] + ny * ry[k])
        if a_full > 0.0:
            diag += max(a_full - asum, 0.0)
        data[dpos] = diag
        rhs[row] = b
    return indptr, indices, data, rhs
