"""SPH operators of the ISPH scheme (numba): kernel values, renormalisation, gradients, divergence.

All loops run over the fluid (granular) particles i = 0..nf-1 and their neighbour list
(:mod:`granudep.isph.neighbours`); wall particles are j >= nf. Pair vector r_ij = x_i - x_j,
∇_i W_ij = (dW/dr / r) r_ij with the shared 2D Wendland C2 kernel (support 2h). Every particle has
volume V = dx² (incompressible continuum). Walls enter through :mod:`granudep.isph.walls`.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ..kernels import wendland_w


from .parallel import prange_kernel


from .walls import SLIP_COULOMB, wall_beta_linear


@prange_kernel
def pair_kernel(rr, h):
    """W(r_ij) and (dW/dr)/r (0 at r < 1e-12 h) of every pair of the neighbour list, once per step for
    all the kernels below (:class:`bundles.Pairs`). The same expressions in the same order as :func:`wendland_w` and :func:`wendland_dwdr`: bit for bit."""
    n = rr.size
    w = np.empty(n)
    gw = np.empty(n)
    cw = 7.0 / (4.0 * math.pi * h * h)
    cg = 7.0 / (4.0 * math.pi * h * h * h)
    rmin = 1e-12 * h
    for k in prange(n):
        r = rr[k]
        q = r / h
        t = 1.0 - 0.5 * q
        inside = q < 2.0
        w[k] = cw * t * t * t * t * (2.0 * q + 1.0) if inside else 0.0
        gw[k] = (cg * (-5.0 * q) * t * t * t) / r if (inside and r >= rmin) else 0.0
    return w, gw


@prange_kernel
def shepard_average(pairs, nf, h, f):
    """Kernel (Shepard) average f̄_i = (W(0) f_i + Σ_j W_ij f_j)/(W(0) + Σ_j W_ij) over the granular
    neighbours j of each granular particle i (wall particles left out)."""
    start, nbr, wk = pairs.start, pairs.nbr, pairs.wk
    w0 = 7.0 / (4.0 * math.pi * h * h)
    out = np.empty(nf)
    for i in prange(nf):
        s = w0 * f[i]
        sw = w0
        for q in range(start[i], start[i + 1]):
            j = nbr[q]
            if j < nf:
                s += wk[q] * f[j]
                sw += wk[q]
        out[i] = s / sw
    return out


@prange_kernel
def mls_linear_average(pairs, nf, h, f):
    """Value at each granular particle of the kernel-weighted least-squares linear fit
    f ≈ a + b·(x_j − x_i) over the particle and its granular neighbours (moving least squares of
    order 1): exact for linear fields, also where the support is cut by the free surface or a wall,
    and a low-pass filter for the rest (a layer-to-layer alternation is averaged out). Where the
    3 × 3 moment matrix is singular to round-off (fewer than three neighbours in general position),
    the Shepard average. ``rx, ry``: x_i − x_j of each pair."""
    start, nbr, rx, ry, wk = pairs.start, pairs.nbr, pairs.rx, pairs.ry, pairs.wk
    w0 = 7.0 / (4.0 * math.pi * h * h)
    out = np.empty(nf)
    for i in prange(nf):
        m00 = w0
        m01 = 0.0
        m02 = 0.0
        m11 = 0.0
        m12 = 0.0
        m22 = 0.0
        b0 = w0 * f[i]
        b1 = 0.0
        b2 = 0.0
        for q in range(start[i], start[i + 1]):
            j = nbr[q]
            if j >= nf:
                continue
            w = wk[q]
            x = -rx[q] / h
            y = -ry[q] / h
            m00 += w
            m01 += w * x
            m02 += w * y
            m11 += w * x * x
            m12 += w * x * y
            m22 += w * y * y
            b0 += w * f[j]
            b1 += w * f[j] * x
            b2 += w * f[j] * y
        # a = first component of M⁻¹ b (Cramer: cofactors of the first column)
        c00 = m11 * m22 - m12 * m12
        c01 = m02 * m12 - m01 * m22
        c02 = m01 * m12 - m02 * m11
        det = m00 * c00 + m01 * c01 + m02 * c02
        if det > 1e-10 * m00 * m00 * m00:
            out[i] = (c00 * b0 + c01 * b1 + c02 * b2) / det
        else:
            out[i] = b0 / m00
    return out


@prange_kernel
def geometry_terms(pairs, nf, h, vol):
    """∇·r (free-surface detector, Lee et al. 2008), concentration C = Σ V W (self included),
    ∇C (shifting, normals) and the inverse renormalisation matrix L (Bonet & Lok 1999)."""
    start, rx, ry, rr, wk, gw = pairs.start, pairs.rx, pairs.ry, pairs.rr, pairs.wk, pairs.gw
    divr = np.zeros(nf)
    conc = np.zeros(nf)
    gcx = np.zeros(nf)
    gcy = np.zeros(nf)
    lmat = np.zeros((nf, 4))
    m_xx = np.zeros(nf)
    m_yy = np.zeros(nf)
    w0 = wendland_w(0.0, h)
    for i in prange(nf):
        s_div = 0.0
        s_c = vol * w0
        sx = 0.0
        sy = 0.0
        mxx = 0.0
        mxy = 0.0
        myy = 0.0
        for k in range(start[i], start[i + 1]):
            r = rr[k]
            g = gw[k]
            s_div -= vol * g * r * r
            s_c += vol * wk[k]
            sx += vol * g * rx[k]
            sy += vol * g * ry[k]
            # M_ab = Σ V (x_j - x_i)_a ∇_b W = -Σ V g r_a r_b
            mxx -= vol * g * rx[k] * rx[k]
            mxy -= vol * g * rx[k] * ry[k]
            myy -= vol * g * ry[k] * ry[k]
        divr[i] = s_div
        conc[i] = s_c
        gcx[i] = sx
        gcy[i] = sy
        m_xx[i] = mxx
        m_yy[i] = myy
        det = mxx * myy - mxy * mxy
        # renormalise only where the support is at least about half full (det M ≈ 1 for a full
        # support, 0.5 next to a flat surface); sparse neighbourhoods would amplify noise
        if det > 0.4 and mxx > 0.4 and myy > 0.4:
            lmat[i, 0] = myy / det
            lmat[i, 1] = -mxy / det
            lmat[i, 2] = -mxy / det
            lmat[i, 3] = mxx / det
        else:
            lmat[i, 0] = 1.0
            lmat[i, 3] = 1.0
    return divr, conc, gcx, gcy, lmat, (m_xx, m_yy)


@prange_kernel
def lmat_pressure(lmat, fs, mxx, myy):
    """Renormalisation of the pressure gradient: ``lmat``, except on free-surface particles,
    where only the diagonal is renormalised (1/M_xx, 1/M_yy where both > 0.4, else none)."""
    out = lmat.copy()
    for i in prange(fs.size):
        if fs[i]:
            out[i, 1] = 0.0
            out[i, 2] = 0.0
            if mxx[i] > 0.4 and myy[i] > 0.4:
                out[i, 0] = 1.0 / mxx[i]
                out[i, 3] = 1.0 / myy[i]
            else:
                out[i, 0] = 1.0
                out[i, 3] = 1.0
    return out


@prange_kernel
def velocity_gradient(pairs, nf, vol, pos, vel, lmat, walls, slip, slip_length, dx):
    """Renormalised ∇u (rows: du/dx, du/dy, dv/dx, dv/dy) at the positions pos = (x, y) from the
    velocities vel = (u, v); wall neighbours carry the extrapolated wall velocity (normal
    component = u_i's, tangential (1 − βφ) u_i,t)."""
    x, y = pos
    u, v = vel
    start, nbr, rx, ry, gw = pairs.start, pairs.nbr, pairs.rx, pairs.ry, pairs.gw
    wnx, wny, wc = walls.nx, walls.ny, walls.c
    grad = np.zeros((nf, 4))
    for i in prange(nf):
        a0 = 0.0
        a1 = 0.0
        a2 = 0.0
        a3 = 0.0
        for k in range(start[i], start[i + 1]):
            j = nbr[k]
            g = gw[k]
            if j < nf:
                du = u[j] - u[i]
                dv = v[j] - v[i]
            else:
                w = j - nf
                nx = wnx[w]
                ny = wny[w]
                # linear extrapolation to the wall particle, not capped at Morris's β = 1.5: the
                # renormalised gradient is then exact for a linear profile through the wall value
                # (docs/model.md, "Kernel design notes")
                beta = wall_beta_linear(x[i], y[i], nx, ny, wc[w], x[j], y[j], slip, slip_length, dx)
                if slip == SLIP_COULOMB:
                    beta = 0.0  # the granular particle slides on the wall; friction is a contact force
                un = u[i] * nx + v[i] * ny
                # u_w - u_i = -β u_t
                du = -beta * (u[i] - un * nx)
                dv = -beta * (v[i] - un * ny)
            wx = vol * g * rx[k]
            wy = vol * g * ry[k]
            a0 += du * wx
            a1 += du * wy
            a2 += dv * wx
            a3 += dv * wy
        l0 = lmat[i, 0]
        l1 = lmat[i, 1]
        l2 = lmat[i, 2]
        l3 = lmat[i, 3]
        # corrected gradient row vector: g_corr = L g  (L symmetric)
        grad[i, 0] = l0 * a0 + l1 * a1
        grad[i, 1] = l2 * a0 + l3 * a1
        grad[i, 2] = l0 * a2 + l1 * a3
        grad[i, 3] = l2 * a2 + l3 * a3
    return grad


@njit(cache=True, inline="always")
def shear_rate(grad, i):
    """|γ̇| = sqrt(2 D:D), D = (∇u + ∇uᵀ)/2, from row i of the velocity gradient (du/dx, du/dy,
    dv/dx, dv/dy): |du/dy| in simple shear (Jop et al. 2006)."""
    dxx = grad[i, 0]
    dyy = grad[i, 3]
    dxy = 0.5 * (grad[i, 1] + grad[i, 2])
    return math.sqrt(2.0 * (dxx * dxx + dyy * dyy + 2.0 * dxy * dxy))


@prange_kernel
def divergence(pairs, nf, vol, u, v, lmat):
    """∇·u_i = tr(L_i Σ_j V (u_j − u_i) ⊗ ∇_i W_ij) over granular neighbours (walls enter through
    the pressure Neumann condition, not here). With the renormalisation L (identity where the
    support is too sparse) the divergence of any linear velocity field is exact, also with a
    one-sided support (why it matters: docs/model.md, "Kernel design notes")."""
    start, nbr, rx, ry, gw = pairs.start, pairs.nbr, pairs.rx, pairs.ry, pairs.gw
    div = np.zeros(nf)
    for i in prange(nf):
        axx = 0.0
        axy = 0.0
        ayx = 0.0
        ayy = 0.0
        for k in range(start[i], start[i + 1]):
            j = nbr[k]
            if j < nf:
                g = vol * gw[k]
                du = u[j] - u[i]
                dv = v[j] - v[i]
                axx += du * g * rx[k]
                axy += du * g * ry[k]
                ayx += dv * g * rx[k]
                ayy += dv * g * ry[k]
        # du/dx = L_0 a_xx + L_1 a_xy ; dv/dy = L_2 a_yx + L_3 a_yy
        div[i] = lmat[i, 0] * axx + lmat[i, 1] * axy + lmat[i, 2] * ayx + lmat[i, 3] * ayy
    return div


@prange_kernel
def smoothed_gradient(pairs, nf, h, gx, gy):
    """Kernel (Shepard) average of a granular particle field's gradient over each support: the
    surface normal of the shifting (rather than the raw ∇C, which points at the nearest clump of
    surface particles: docs/model.md, "Kernel design notes")."""
    start, nbr, wk = pairs.start, pairs.nbr, pairs.wk
    sx = np.zeros(nf)
    sy = np.zeros(nf)
    w0 = wendland_w(0.0, h)
    for i in prange(nf):
        ax = w0 * gx[i]
        ay = w0 * gy[i]
        ws = w0
        for k in range(start[i], start[i + 1]):
            j = nbr[k]
            if j < nf:
                w = wk[k]
                ax += w * gx[j]
                ay += w * gy[j]
                ws += w
        sx[i] = ax / ws
        sy[i] = ay / ws
    return sx, sy
