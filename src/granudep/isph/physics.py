"""Per-particle physics of the projection ISPH scheme (numba kernels; no Python loops).

All loops run over the fluid (granular) particles i = 0..nf-1 and their neighbour list
(:mod:`granudep.isph.neighbours`); wall particles are j >= nf. Pair vector r_ij = x_i - x_j,
∇_i W_ij = (dW/dr / r) r_ij with the shared 2D Wendland C2 kernel (support 2h). Every particle has
volume V = dx² (incompressible continuum).

Walls are layers of fixed particles. Each wall particle carries the plane of its wall surface
(unit normal n into the fluid, offset c: n·x = c on the surface). Per fluid–wall pair:

* pressure (mirror/Neumann): p_w = p_i − G_i (n·r_iw), G_i = (ρ/Δt) min(u*_i·n, 0): the wall
  supports the normal momentum the predictor pushes into it and never pulls (separation allowed);
* velocity (viscous stress and strain rate): the tangential wall velocity is extrapolated
  u_w,t = (1 − β) u_i,t with Morris et al. (1997) β = min(1.5, (d_i + d_w)/(d_i + b)); b is the
  Navier slip length (0: no slip); free slip: β = 0. No-slip/Navier wall terms are divided by the
  lattice constant ``wall_ns`` (0.71 for h = 1.3 dx) so that a linear shear profile feels the wall
  stress η du/dy. Coulomb (default): no viscous wall term (β = 0); the wall friction μ_B p_w is a
  contact drag on the first particle layer (:func:`coulomb_wall_drag`).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ..kernels import wendland_dwdr, wendland_w
from .parallel import prange_kernel

SLIP_NO, SLIP_NAVIER, SLIP_FREE, SLIP_COULOMB = 0, 1, 2, 3
SLIP_CODES = {"no_slip": SLIP_NO, "navier": SLIP_NAVIER, "free_slip": SLIP_FREE, "coulomb": SLIP_COULOMB}


@njit(cache=True, inline="always")
def wall_beta_linear(xi, yi, nx, ny, c, xw, yw, slip, slip_length, dx):
    """β of the linear extrapolation u_w = u_i (b − d_w)/(d_i + b) (no cap; d_i floored at dx/4):
    u_i − u_w = β u_i for the tangential component (velocity gradient of the rheology)."""
    if slip == SLIP_FREE:
        return 0.0
    di = max(nx * xi + ny * yi - c, 0.25 * dx)
    dw = max(c - (nx * xw + ny * yw), 0.0)
    b = slip_length if slip == SLIP_NAVIER else 0.0
    return (di + dw) / (di + b)


@njit(cache=True, inline="always")
def wall_beta(xi, yi, nx, ny, c, xw, yw, slip, slip_length, dx):
    """Morris wall-velocity factor β (u_i − u_w = β u_i for the tangential component): the linear
    extrapolation capped at 1.5 (Morris et al. 1997; viscous operator)."""
    return min(1.5, wall_beta_linear(xi, yi, nx, ny, c, xw, yw, slip, slip_length, dx))


@prange_kernel
def pair_kernel(rr, h):
    """W(r_ij) and (dW/dr)/r (0 at r < 1e-12 h) of every pair of the neighbour list, once per step for
    all the kernels below (each evaluated them again: 0.13 ms per kernel and step at 75k pairs).
    The same expressions in the same order as :func:`wendland_w` and :func:`wendland_dwdr`: bit for bit."""
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
def shepard_average(start, nbr, wk, nf, h, f):
    """Kernel (Shepard) average f̄_i = (W(0) f_i + Σ_j W_ij f_j)/(W(0) + Σ_j W_ij) over the granular
    neighbours j of each granular particle i (wall particles left out)."""
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
def mls_linear_average(start, nbr, rx, ry, wk, nf, h, f):
    """Value at each granular particle of the kernel-weighted least-squares linear fit
    f ≈ a + b·(x_j − x_i) over the particle and its granular neighbours (moving least squares of
    order 1): exact for linear fields, also where the support is cut by the free surface or a wall,
    and a low-pass filter for the rest (a layer-to-layer alternation is averaged out). Where the
    3 × 3 moment matrix is singular to round-off (fewer than three neighbours in general position),
    the Shepard average. ``rx, ry``: x_i − x_j of each pair."""
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
def geometry_terms(start, nbr, rx, ry, rr, wk, gw, nf, h, vol):
    """∇·r (free-surface detector, Lee et al. 2008), concentration C = Σ V W (self included),
    ∇C (shifting, normals) and the inverse renormalisation matrix L (Bonet & Lok 1999)."""
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
def velocity_gradient(start, nbr, rx, ry, rr, gw, nf, h, vol, x, y, u, v, lmat, p, eta,
                      wnx, wny, wc, slip, slip_length, mu_wall, dx, gx, gy, rho, eta_max, wall_ns, wall_k):
    """Renormalised ∇u (rows: du/dx, du/dy, dv/dx, dv/dy); wall neighbours carry the extrapolated
    wall velocity (normal component = u_i's, tangential (1 − βφ) u_i,t)."""
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
                # (with the cap, the bed shear rate of the Bagnold test read 44 1/s instead of 84)
                beta = wall_beta_linear(x[i], y[i], nx, ny, wc[w], x[j], y[j], slip, slip_length, dx)
                if slip == SLIP_COULOMB:
                    beta = 0.0  # the granular particle slides on the wall; friction is a contact force
                un = u[i] * nx + v[i] * ny
                # u_w - u_i = -β u_t
                du = -beta * (u[i] - un * nx)
                dv = -beta * (v[i] - un * ny)
            gx = vol * g * rx[k]
            gy = vol * g * ry[k]
            a0 += du * gx
            a1 += du * gy
            a2 += dv * gx
            a3 += dv * gy
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
def assemble_viscous(start, nbr, rx, ry, rr, gw, nf, h, vol, x, y, u, v, p, eta, gdot, wnx, wny, wc,
                     slip, slip_length, mu_wall, dx, dt, rho, eps2, mean, gx, gy, eta_max, lap_norm, wall_ns,
                     wall_k):
    """Implicit viscous matrices A = I − Δt/ρ ∇·(η∇·) (Morris Laplacian, pair viscosity
    :func:`pair_viscosity`, ``rheology.pair_mean``: stress-weighted by default) as CSR.

    Row i: (1 + Δt/ρ Σ_j c_ij + wall_i) u_i − Δt/ρ Σ_j c_ij u_j,
    c_ij = 2 η̄_ij V F_ij, F_ij = −r dW/dr/(r² + ε²) ≥ 0, η̄ = 2 η_i η_j/(η_i + η_j). Symmetric.
    The wall term acts on the tangential component only (the normal one is the pressure's job):
    wall_i = Δt/ρ Σ_w 2 η_i V F_iw β φ t_a², t = wall tangent, a = x (u matrix) or y (v matrix).
    Returns indptr, indices, data (diagonal first in each row, u matrix) and diag_v (v matrix).
    """
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


@prange_kernel
def wall_contact(start, nbr, nf, x, y, planes, dx, h, cover):
    """Per particle and wall plane (n, c): distance d = n·x − c if the particle is the first layer
    over that wall (d < 2h and no granular particle between it and the wall, i.e. none with
    d_j < d − dx/2 within a tangential offset ``cover``), else +inf; and the height of the granular
    column over a contact particle (largest d_j of the neighbours within a tangential offset dx/2,
    + dx/2), from which the contact pressure of thin flows is estimated. With ``cover`` = dx/2
    (default) the two rules agree: every particle's weight is either in the column of the contact
    particle below it or carried by its own contact (with ``cover`` = dx, particles offset by
    dx/2..dx from the one below were in neither, and thin flows lost up to half their friction)."""
    npl = planes.shape[0]
    dist = np.full((nf, npl), np.inf)
    col = np.zeros((nf, npl))
    for i in prange(nf):
        for q in range(npl):
            nx = planes[q, 0]
            ny = planes[q, 1]
            d = nx * x[i] + ny * y[i] - planes[q, 2]
            if d >= 2.0 * h:
                continue
            covered = False
            for k in range(start[i], start[i + 1]):
                j = nbr[k]
                if j >= nf:
                    continue
                dj = nx * x[j] + ny * y[j] - planes[q, 2]
                if dj < d - 0.5 * dx:
                    off = abs(-ny * (x[i] - x[j]) + nx * (y[i] - y[j]))
                    if off < cover:
                        covered = True
                        break
            if not covered:
                dist[i, q] = d
                top = d
                count = 1
                for k in range(start[i], start[i + 1]):
                    j = nbr[k]
                    if j >= nf:
                        continue
                    dj = nx * x[j] + ny * y[j] - planes[q, 2]
                    if dj > d - 0.5 * dx and abs(-ny * (x[i] - x[j]) + nx * (y[i] - y[j])) < 0.5 * dx:
                        count += 1
                        if dj > top:
                            top = dj
                # height of the column: to its top particle, or its particle count times dx where
                # free-surface particles (no pressure between them) have piled up closer than dx
                col[i, q] = max(top + 0.5 * dx, count * dx)
    return dist, col


@prange_kernel
def detached_from_walls(contact, limit):
    """Particles whose nearest wall contact (:func:`wall_contact`) is finite but farther than
    ``limit`` (numpy's min over the short axis of ``contact`` cost 0.12 ms per call)."""
    n, npl = contact.shape
    out = np.zeros(n, np.bool_)
    for i in prange(n):
        m = np.inf
        for q in range(npl):
            m = min(m, contact[i, q])
        out[i] = m > limit and np.isfinite(m)
    return out


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
def contact_length(start, nbr, nf, x, y, contact, planes, dx):
    """Wall length carried by each contact particle (Voronoi cell along the wall): half the distance
    to the nearest contact particle of the same wall on either side (dx/2 on a side without one
    within the neighbour list), clipped to [dx/2, 2 dx] in total. On the initial lattice this is dx;
    in a flow the first layer stretches along the bed (median spacing 1.12 dx in T22-A70 at 4 mm)
    and a fixed dx per particle loses that fraction of the basal friction."""
    npl = planes.shape[0]
    length = np.zeros((nf, npl))
    for i in prange(nf):
        for q in range(npl):
            if not contact[i, q] < np.inf:
                continue
            nx = planes[q, 0]
            ny = planes[q, 1]
            ti = -ny * x[i] + nx * y[i]
            lo = -np.inf
            hi = np.inf
            for k in range(start[i], start[i + 1]):
                j = nbr[k]
                if j >= nf or not contact[j, q] < np.inf:
                    continue
                tj = -ny * x[j] + nx * y[j] - ti
                if tj > 0.0 and tj < hi:
                    hi = tj
                elif tj <= 0.0 and tj > lo:
                    lo = tj
            a = 0.5 * hi if hi < np.inf else 0.5 * dx
            b = -0.5 * lo if lo > -np.inf else 0.5 * dx
            length[i, q] = min(max(a + b, 0.5 * dx), 2.0 * dx)
    return length


@prange_kernel
def coulomb_wall_drag(nf, u, v, p, contact, col, planes, mu_wall, gx, gy, rho, dx, dt, u_eps, diag_u, diag_v,
                      length):
    """Coulomb wall friction as an implicit drag on the first particle layer (slip = coulomb).

    For a particle in contact with wall plane (n, c) (:func:`wall_contact`), the traction μ_B p_w
    on its bed area dx, with the contact pressure p_w = max(p_i + g_n ρ dx/2, g_n ρ h_col) (PPE pressure
    extrapolated to the wall, or the weight of the column h_col above the particle where that is
    larger: in flows a few particles thick all particles are free-surface particles with Dirichlet
    pressure), g_n = max(−g·n, 0), gives
    the acceleration −μ_B p_w l/(ρ dx²) u_t/|u_t| (l: wall length carried by the particle,
    :func:`contact_length`; dx on the lattice), regularised as the drag k u_t,
    k = μ_B p_w l/(ρ dx² max(|u_t|, u_eps)), added implicitly to the diagonal of the tangential
    component. It sticks (static friction up to μ_B p_w) when |u_t| < u_eps.
    """
    for i in prange(nf):
        for q in range(planes.shape[0]):
            if not contact[i, q] < np.inf:
                continue
            nx = planes[q, 0]
            ny = planes[q, 1]
            gn = max(-(gx * nx + gy * ny), 0.0)
            pw = max(max(p[i], 0.0) + rho * gn * 0.5 * dx, rho * gn * col[i, q])
            un = u[i] * nx + v[i] * ny
            utx = u[i] - un * nx
            uty = v[i] - un * ny
            ut = math.sqrt(utx * utx + uty * uty)
            # traction μ_B p_w on the wall length l_i carried by the particle (volume dx²), but never
            # less than μ_B times the weight of its own column, ρ g_n h_col dx: clumped contact
            # particles (spacing < dx) carry less bed length than their weight needs, and a cluster of
            # three with 2.14 dx of bed between them accelerated down a 22° bed (+0.57 m/s²) instead
            # of stopping (-0.66 m/s²)
            load = max(pw * length[i, q], rho * gn * col[i, q] * dx)
            kd = mu_wall * load / (rho * dx * dx * max(ut, u_eps))
            # tangent t = (-n_y, n_x)
            diag_u[i] += dt * kd * ny * ny
            diag_v[i] += dt * kd * nx * nx


@prange_kernel
def coulomb_drag_from_reaction(nf, u, v, a_n, planes, mu_wall, dt, u_eps, diag_u, diag_v):
    """Coulomb wall friction from the walls' normal reaction (``wall.coulomb_normal: projection``):
    the tangential deceleration μ_B max(a_n, 0) u_t/|u_t| of each particle, a_n its acceleration
    along the wall normal from the wall terms of the previous projection
    (:func:`projection.wall_normal_acceleration`), regularised below ``u_eps`` as in
    :func:`coulomb_wall_drag` and added implicitly to the diagonal of the tangential component."""
    for i in prange(nf):
        for q in range(planes.shape[0]):
            an = a_n[i, q]
            if not an > 0.0:
                continue
            nx = planes[q, 0]
            ny = planes[q, 1]
            un = u[i] * nx + v[i] * ny
            utx = u[i] - un * nx
            uty = v[i] - un * ny
            ut = math.sqrt(utx * utx + uty * uty)
            kd = mu_wall * an / max(ut, u_eps)
            diag_u[i] += dt * kd * ny * ny
            diag_v[i] += dt * kd * nx * nx


@prange_kernel
def divergence(start, nbr, rx, ry, rr, gw, nf, h, vol, u, v, lmat):
    """∇·u_i = tr(L_i Σ_j V (u_j − u_i) ⊗ ∇_i W_ij) over granular neighbours (walls enter through
    the pressure Neumann condition, not here). With the renormalisation L (identity where the
    support is too sparse) the divergence of any linear velocity field is exact, also with a
    one-sided support: without it a sheared top layer showed ∇·u ~ γ̇ (≈ 40 1/s) on particles that
    the ∇·r test had just flagged interior, and the projection answered with pressure spikes of
    10³–10⁴ Pa that launched particles (Bagnold test, θ = 30°)."""
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
def assemble_ppe(start, nbr, rx, ry, rr, gw, nf, h, vol, unknown, n_unknown, p_dir, div, us, vs, conc, c0,
                 relax, wnx, wny, dt, rho, eps2, a_full, lap_norm):
    """PPE Σ_j a_ij (p_i − p_j) = −(ρ/Δt) ∇·u* − γ ρ/Δt² min(1 − C_i/C0, 0) over the unknown
    (non-free-surface) particles; a_ij = 2 V F_ij (Cummins & Rudman 1999 Laplacian). Free-surface
    neighbours have their Dirichlet value ``p_dir``; wall neighbours use the mirror pressure (Neumann), which moves to the RHS.
    Kernel completion: where the support is truncated (next to the free surface) the missing
    neighbours are taken at p = 0, i.e. diag += max(a_full − Σ_j a_ij, 0) with a_full the
    full-lattice sum (``a_full`` <= 0 switches this off).
    Symmetric positive definite whenever every cluster touches a free surface."""
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
def pressure_gradient(start, nbr, rx, ry, rr, gw, nf, h, vol, p, us, vs, lmat, wnx, wny, dt, rho, detached):
    """Renormalised ∇p_i = L_i Σ_j V (p_j − p_i) ∇_i W_ij; wall neighbours use the mirror pressure.

    ``detached`` particles (first layer over a wall but farther than 0.75 dx from it) ignore the
    wall: with the renormalisation the mirror pressure would otherwise hold them at any height
    within the kernel support (2h), hovering without contact."""
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


@prange_kernel
def smoothed_gradient(start, nbr, wk, nf, h, vol, gx, gy):
    """Kernel (Shepard) average of a granular particle field's gradient over each support: the
    surface normal of the shifting. The raw ∇C of a free-surface particle points at the nearest
    clump of surface particles (no pressure acts between them), so projecting the shift onto the
    tangent of that "normal" removed exactly the de-clumping part of the shift; clumps of 2–3
    surface particles within 0.1 dx formed in the Bagnold test and ended in pressure spikes."""
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


@prange_kernel
def surface_band(start, nbr, wk, nf, fs, h, r_ref):
    """Weight α ∈ [0, 1] of the bed-normal part of the shift that is removed (Lind et al. 2012):
    1 on free-surface particles, Σ_{j free-surface} W_ij / W(r_ref) (at most 1) below them. Below the
    surface the truncated support gives ∇C a normal part that pushed the second layer up into the
    surface layer at every step (Bagnold layer: top layer 0.25 dx low, pressure ≈ ρ g cosθ 0.15 dx low
    throughout). With r_ref = 2 dx the second and third layers of a lattice get α = 1 and the weight
    goes to 0 with W at the edge of the support (2.6 dx), so it is continuous in the positions (a
    0/1 band switched by a neighbour crossing the support radius turns round-off into different
    runs)."""
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
def shifting(nf, gcx, gcy, u, v, alpha, h, dt, coeff, dx, ncx, ncy):
    """Fickian particle shifting δr = −A h |u| Δt ∇C (Skillen et al. 2013; Lind et al. 2012);
    the fraction ``alpha`` of the part normal to the free surface is removed (1 on free-surface
    particles: they keep only the tangential part); |δr| <= min(0.1 dx, |u| Δt/2). Zero at rest."""
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


@prange_kernel
def clamp_to_walls(nf, x, y, u, v, planes, dmin, lo, hi):
    """Safeguard against wall penetration: a particle closer than ``dmin`` to a wall plane (within
    the wall's extent [lo, hi] along it) is put back at ``dmin`` and loses its velocity into the
    wall. Returns the number of particles moved (reported in the run statistics)."""
    moved = 0
    for i in prange(nf):
        for q in range(planes.shape[0]):
            nx = planes[q, 0]
            ny = planes[q, 1]
            along = -ny * x[i] + nx * y[i]
            if along < lo[q] or along > hi[q]:
                continue
            d = nx * x[i] + ny * y[i] - planes[q, 2]
            if d < dmin:
                x[i] += (dmin - d) * nx
                y[i] += (dmin - d) * ny
                un = u[i] * nx + v[i] * ny
                if un < 0.0:
                    u[i] -= un * nx
                    v[i] -= un * ny
                moved += 1
    return moved
