"""The approximate projection (``numerics.projection: approximate``), kept apart: the default step
(``adjoint_pair``, :mod:`granudep.isph.projection`) never calls this module.

It is the earlier scheme, neither energy-stable nor convergent (docs/model.md): a compact-Laplacian PPE
Σ_j a_ij (p_i − p_j) = −ρ/Δt ∇·u* over the particles off the free surface (:func:`assemble_ppe`),
mirror-pressure (Neumann) walls, and the renormalised difference gradient in the corrector
(:func:`pressure_gradient`), which lets particles that lost wall contact (:func:`walls.wall_contact`,
:func:`walls.detached_from_walls`) ignore the wall. Kept as a study variant; :func:`project` is the
stage the stepper calls in its place.
"""
from __future__ import annotations

import numpy as np
from numba import prange

from . import operators, walls
from .parallel import prange_kernel
from .projection import adjoint_divergence


def project(s, nb, geo, lmat_p, us, vs, dt: float) -> None:
    """The projection stage with the approximate projection on the solver state ``s``
    (:class:`.stepper.IsphSolver`): pⁿ⁺¹ and uⁿ⁺¹ from u*."""
    c = s.cfg
    nf, vol, rho = s.nf, s.vol, s.rho
    if c.numerics.ppe_divergence == "adjoint":
        div = adjoint_divergence(nb, nf, vol, us, vs, lmat_p)
    else:
        div = operators.divergence(nb, nf, vol, us, vs, geo.lmat)
    unknown = np.full(nf, -1, np.int64)
    interior = ~s.fs
    n_unknown = int(interior.sum())
    unknown[interior] = np.arange(n_unknown)
    # free-surface Dirichlet value: p = 0 holds on the surface, which lies dx/2 beyond the centre
    # of a free-surface particle: p_fs = ρ g cosθ dx/2 (bed-normal hydrostatics), or 0
    p_new = np.where(s.fs, s.p_fs, 0.0)
    if n_unknown:
        pi, pj, pd, rhs = assemble_ppe(nb, nf, vol, (unknown, n_unknown), p_new, div, (us, vs),
                                       (geo.conc, s.c0, s.density_relaxation(dt)), s.wall_surface,
                                       (dt, rho, s.eps2, s.a_full, s.lap_norm))
        p_new[interior] = s.linear.solve_ppe(pi, pj, pd, rhs, s.p[interior])
    s.p = p_new
    contact = geo.contact
    if contact is None:   # the bed law did not need it: the wall contact of this step's positions
        contact, _ = walls.wall_contact(nb, nf, s.x, s.y, s.planes, s.dx, s.h, c.wall.cover_offset * s.dx)
    detached = walls.detached_from_walls(contact, 0.75 * s.dx)
    gpx, gpy = pressure_gradient(nb, nf, vol, s.p, (us, vs), lmat_p, s.wall_surface, dt, rho, detached)
    s.u = us - dt / rho * gpx
    s.v = vs - dt / rho * gpy


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


@prange_kernel
def pressure_gradient(pairs, nf, vol, p, vel, lmat, walls, dt, rho, detached):
    """Renormalised ∇p_i = L_i Σ_j V (p_j − p_i) ∇_i W_ij; wall neighbours use the mirror pressure
    (which reads the predicted velocities vel = (u*, v*)).

    ``detached`` particles (first layer over a wall but farther than 0.75 dx from it) ignore the
    wall: with the renormalisation the mirror pressure would otherwise hold them at any height
    within the kernel support (2h), hovering without contact."""
    us, vs = vel
    start, nbr, rx, ry, gw = pairs.start, pairs.nbr, pairs.rx, pairs.ry, pairs.gw
    wnx, wny = walls.nx, walls.ny
    gpx = np.zeros(nf)
    gpy = np.zeros(nf)
    for i in prange(nf):
        ax = 0.0
        ay = 0.0
        for k in range(start[i], start[i + 1]):
            j = nbr[k]
            g = gw[k]
            if j < nf:
                dp = p[j] - p[i]
            else:
                if detached[i]:
                    continue
                w = j - nf
                nx = wnx[w]
                ny = wny[w]
                gn = rho / dt * min(us[i] * nx + vs[i] * ny, 0.0)
                dp = -gn * (nx * rx[k] + ny * ry[k])
            ax += vol * dp * g * rx[k]
            ay += vol * dp * g * ry[k]
        gpx[i] = lmat[i, 0] * ax + lmat[i, 1] * ay
        gpy[i] = lmat[i, 2] * ax + lmat[i, 3] * ay
    return gpx, gpy
