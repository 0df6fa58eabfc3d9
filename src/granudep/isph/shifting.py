"""Particle shifting (numba): the free-surface band and the shifting displacement with its
velocity correction.
"""
from __future__ import annotations

import math

import numpy as np
from numba import prange

from ..kernels import wendland_w


from .parallel import prange_kernel


@prange_kernel
def surface_band(pairs, nf, fs, h, r_ref):
    """Weight α ∈ [0, 1] of the bed-normal part of the shift that is removed (Lind et al. 2012):
    1 on free-surface particles, Σ_{j free-surface} W_ij / W(r_ref) (at most 1) below them, where the
    truncated support gives ∇C a normal part (docs/model.md, "Kernel design notes"). With r_ref = 2 dx the second and third layers of a lattice get α = 1 and the weight
    goes to 0 with W at the edge of the support (2.6 dx), so it is continuous in the positions (a
    0/1 band switched by a neighbour crossing the support radius turns round-off into different
    runs)."""
    start, nbr, wk = pairs.start, pairs.nbr, pairs.wk
    alpha = np.zeros(nf)
    w_ref = wendland_w(r_ref, h)
    for i in prange(nf):
        if fs[i]:
            alpha[i] = 1.0
            continue
        a = 0.0
        for k in range(start[i], start[i + 1]):
            j = nbr[k]
            if j < nf and fs[j]:
                a += wk[k]
        alpha[i] = min(a / w_ref, 1.0)
    return alpha


@prange_kernel
def shifting(nf, gc, vel, alpha, h, dt, coeff, dx, nc):
    """Fickian particle shifting δr = −A h |u| Δt ∇C (Skillen et al. 2013; Lind et al. 2012), with
    gc = (∂C/∂x, ∂C/∂y) and vel = (u, v); the fraction ``alpha`` of the part normal to the free
    surface (normal nc = (n_x, n_y)) is removed (1 on free-surface particles: they keep only the
    tangential part); |δr| <= min(0.1 dx, |u| Δt/2). Zero at rest."""
    gcx, gcy = gc
    u, v = vel
    ncx, ncy = nc
    sx = np.zeros(nf)
    sy = np.zeros(nf)
    if coeff <= 0.0:
        return sx, sy
    for i in prange(nf):
        speed = math.sqrt(u[i] * u[i] + v[i] * v[i])
        dcoef = coeff * h * speed * dt
        ax = -dcoef * gcx[i]
        ay = -dcoef * gcy[i]
        if alpha[i] > 0.0:
            gn = math.sqrt(ncx[i] * ncx[i] + ncy[i] * ncy[i])
            if gn > 0.0:
                nx = ncx[i] / gn
                ny = ncy[i] / gn
                dn = alpha[i] * (ax * nx + ay * ny)
                ax -= dn * nx
                ay -= dn * ny
        mag = math.sqrt(ax * ax + ay * ay)
        # at most 0.1 dx, and at most half the particle's own displacement |u| Δt: a larger shift
        # can cancel the advection, and a particle whose shift holds it in place against its
        # velocity keeps that (then spurious) velocity indefinitely (seen at the bed of a
        # deposit: v = −0.15 m/s, position fixed)
        lim = min(0.1 * dx, 0.5 * speed * dt)
        if mag > lim:
            ax *= lim / mag
            ay *= lim / mag
        sx[i] = ax
        sy[i] = ay
    return sx, sy
