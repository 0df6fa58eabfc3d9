"""Walls of the ISPH scheme: wall-velocity extrapolation, contact, Coulomb friction, clamps (numba).

Walls are layers of fixed particles. Each wall particle carries the plane of its wall surface
(unit normal n into the fluid, offset c: n·x = c on the surface). Per fluid–wall pair:

* pressure (approximate projection, mirror/Neumann): p_w = p_i − G_i (n·r_iw),
  G_i = (ρ/Δt) min(u*_i·n, 0): the wall supports the normal momentum the predictor pushes into it
  and never pulls (separation allowed); with the adjoint pair the wall particles are pressure nodes
  (:mod:`granudep.isph.projection`);
* velocity (viscous stress and strain rate): the tangential wall velocity is extrapolated
  u_w,t = (1 − β) u_i,t with Morris et al. (1997) β = min(1.5, (d_i + d_w)/(d_i + b)); b is the
  Navier slip length (0: no slip); free slip: β = 0. The no-slip/Navier wall terms are divided by the
  lattice sum ``wall_ns`` of the law's own linear profile u = y + b (:func:`setup.lattice_constants`:
  0.71 for no slip with h = 1.3 dx), so that the first layer feels the Navier wall stress
  η u_1/(d_1 + b) for any b: the slip length is in metres and converges with dx (Newtonian film,
  :func:`verification.navier_film`). Friction laws (coulomb, mu_w_i, stress_limited): no viscous
  wall term (β = 0); the wall traction is a drag on the first particle layer
  (:func:`coulomb_drag_from_reaction` and the others below). ``navier_overwrite``: the authors'
  explicit form, the first layer's velocity replaced after the projection (:func:`navier_overwrite`).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from .parallel import prange_kernel


SLIP_NO, SLIP_NAVIER, SLIP_FREE, SLIP_COULOMB, SLIP_MU_W_I, SLIP_STRESS, SLIP_NAVIER_OVERWRITE = 0, 1, 2, 3, 4, 5, 6
SLIP_CODES = {"no_slip": SLIP_NO, "navier": SLIP_NAVIER, "free_slip": SLIP_FREE, "coulomb": SLIP_COULOMB,
              "mu_w_i": SLIP_MU_W_I, "stress_limited": SLIP_STRESS, "navier_overwrite": SLIP_NAVIER_OVERWRITE}
#: navier_overwrite: the band, in dx, of the nearest wall particle within which a granular particle's
#: velocity is replaced: the authors' h/2.2 with their h = 2.6 dx, i.e. the first particle layer
OVERWRITE_BAND = 2.6 / 2.2
# bed laws whose wall traction is a friction drag on the first particle layer (no viscous wall term
# in the implicit viscous matrix; :func:`coulomb_drag_from_reaction`, :func:`mu_w_i_drag_from_reaction`,
# :func:`stress_limited_drag`)
FRICTION_LAWS = (SLIP_COULOMB, SLIP_MU_W_I, SLIP_STRESS)


def viscous_slip_code(slip: int) -> int:
    """The slip code the implicit viscous matrix is assembled with: the friction laws add their wall
    traction to its diagonal afterwards (assembled as ``coulomb``: no viscous wall term)."""
    return SLIP_COULOMB if slip in FRICTION_LAWS else slip


def gradient_slip_code(slip: int) -> int:
    """The slip code of the wall velocity in the rheology's velocity gradient: the sliding friction
    laws (coulomb, mu_w_i) see no wall shear (β = 0, the layer slides, its friction is a contact
    force); the stress-limited law sees the rigid bed (u_w = 0, as no_slip), whose shear it caps."""
    if slip == SLIP_STRESS:
        return SLIP_NO
    return SLIP_COULOMB if slip == SLIP_MU_W_I else slip


@njit(cache=True, inline="always")
def tangential_speed(u, v, nx, ny):
    """|u_t|: the speed along a wall of unit normal n."""
    un = u * nx + v * ny
    utx = u - un * nx
    uty = v - un * ny
    return math.sqrt(utx * utx + uty * uty)


@njit(cache=True)
def navier_overwrite(pairs, nf, grad, u, v, walls, band, slip_length):
    """The authors' slip as they wrote it (``wall.slip: navier_overwrite``; Nikooei & Manzari 2020,
    public code ``projection.cpp``, "Partial-Slip BC"): after the projection, a granular particle
    whose nearest wall particle lies within ``band`` gets the velocity L_s (I − n⊗n)·γ̇·n, γ̇ = ∇u + ∇uᵀ
    its strain rate at the start of the step (explicit), n the normal of that wall particle; its
    normal component is zero. The gradient and the viscous wall term see a wall at rest (no slip), as
    the authors' wall particles are. Overwrites u, v in place; returns the number of particles set."""
    start, nbr, rr = pairs.start, pairs.nbr, pairs.rr
    wnx, wny = walls.nx, walls.ny
    count = 0
    for i in range(nf):
        best = band
        w_best = -1
        for k in range(start[i], start[i + 1]):
            j = nbr[k]
            if j >= nf and rr[k] < best:
                best = rr[k]
                w_best = j - nf
        if w_best < 0:
            continue
        nx = wnx[w_best]
        ny = wny[w_best]
        ux, uy, vx, vy = grad[i, 0], grad[i, 1], grad[i, 2], grad[i, 3]
        # (γ̇·n) with γ̇ = ∇u + ∇uᵀ, then its tangential part along t = (−n_y, n_x)
        gx = 2.0 * ux * nx + (uy + vx) * ny
        gy = (uy + vx) * nx + 2.0 * vy * ny
        s = -ny * gx + nx * gy
        u[i] = -slip_length * s * ny
        v[i] = slip_length * s * nx
        count += 1
    return count


@njit(cache=True, inline="always")
def wall_beta_linear(xi, yi, nx, ny, c, xw, yw, slip, slip_length, dx):
    """β of the linear extrapolation u_w = u_i (b − d_w)/(d_i + b) (no cap; d_i floored at dx/4):
    u_i − u_w = β u_i for the tangential component (velocity gradient of the rheology)."""
    if slip == SLIP_FREE:
        return 0.0
    if slip == SLIP_NAVIER_OVERWRITE:
        return 1.0  # the authors' wall particles: at rest (u_w = 0), not extrapolated
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
def wall_contact(pairs, nf, x, y, planes, dx, h, cover):
    """Per particle and wall plane (n, c): distance d = n·x − c if the particle is the first layer
    over that wall (d < 2h and no granular particle between it and the wall, i.e. none with
    d_j < d − dx/2 within a tangential offset ``cover``), else +inf; and the height of the granular
    column over a contact particle (largest d_j of the neighbours within a tangential offset dx/2,
    + dx/2), from which the contact pressure of thin flows is estimated. With ``cover`` = dx/2
    (default) the two rules agree: every particle's weight is either in the column of the contact
    particle below it or carried by its own contact (with ``cover`` = dx, particles offset by
    dx/2..dx from the one below were in neither, and thin flows lost up to half their friction)."""
    start, nbr = pairs.start, pairs.nbr
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
def contact_length(pairs, nf, x, y, contact, planes, dx):
    """Wall length carried by each contact particle (Voronoi cell along the wall): half the distance
    to the nearest contact particle of the same wall on either side (dx/2 on a side without one
    within the neighbour list), clipped to [dx/2, 2 dx] in total. On the initial lattice this is dx;
    in a flow the first layer stretches along the bed (docs/model.md, "Kernel design notes")."""
    start, nbr = pairs.start, pairs.nbr
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
def coulomb_wall_drag(nf, vel, p, contact, col, planes, g, consts, diag, length):
    """Coulomb wall friction as an implicit drag on the first particle layer (slip = coulomb);
    vel = (u, v), g = (g_x, g_y), consts = (μ_B, ρ, dx, Δt, u_eps), diag = (diag_u, diag_v) the
    viscous diagonals it adds to.

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
    u, v = vel
    gx, gy = g
    mu_wall, rho, dx, dt, u_eps = consts
    diag_u, diag_v = diag
    for i in prange(nf):
        for q in range(planes.shape[0]):
            if not contact[i, q] < np.inf:
                continue
            nx = planes[q, 0]
            ny = planes[q, 1]
            gn = max(-(gx * nx + gy * ny), 0.0)
            pw = max(max(p[i], 0.0) + rho * gn * 0.5 * dx, rho * gn * col[i, q])
            ut = tangential_speed(u[i], v[i], nx, ny)
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
            ut = tangential_speed(u[i], v[i], nx, ny)
            kd = mu_wall * an / max(ut, u_eps)
            diag_u[i] += dt * kd * ny * ny
            diag_v[i] += dt * kd * nx * nx


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


@njit(cache=True, inline="always")
def wall_inertial_number(ut, pw, rho_s, shear_length, d):
    """Inertial number of the slip at a rigid rough bed (eq 4's I applied at the wall):
    I_w = (|u_t|/ℓ) d / sqrt(p_w/ρ_s), the slip velocity sheared over ℓ (one grain, ℓ = d, by default)."""
    if pw <= 0.0:
        return np.inf
    return ut / shear_length * d / math.sqrt(pw / rho_s)


@njit(cache=True, inline="always")
def wall_friction_mu_i(iw, mu_s, mu_2, i0):
    """μ_w(I_w) = μ_s + (μ_2 − μ_s)/(I0/I_w + 1) (eq 4, the bulk law at the wall); μ_2 as I_w → ∞."""
    if not iw < np.inf:
        return mu_2
    return mu_s + (mu_2 - mu_s) * iw / (i0 + iw)


@prange_kernel
def mu_w_i_drag_from_reaction(nf, vel, a_n, planes, law, consts, diag):
    """Rate-dependent wall friction μ_w(I_w) (``wall.slip: mu_w_i``; vel = (u, v), law = (μ_s, μ_2,
    I0, d, ρ_s), consts = (ρ, dx, shear length, Δt, u_eps), diag = (diag_u, diag_v)): as
    :func:`coulomb_drag_from_reaction` with the coefficient μ_w(I_w) of :func:`wall_friction_mu_i` in
    place of tan φ_B. The normal stress p_w = ρ a_n dx is the walls' reaction a_n (per unit mass)
    carried on a bed length dx by the particle's volume dx²; I_w from the particle's tangential speed
    at the start of the step (lagged: μ_w explicit, the drag implicit). Dissipative: the drag
    coefficient is ≥ 0. At rest I_w → 0 and μ_w → μ_s: the static limit is the bulk's."""
    u, v = vel
    mu_s, mu_2, i0, d, rho_s = law
    rho, dx, shear_length, dt, u_eps = consts
    diag_u, diag_v = diag
    for i in prange(nf):
        for q in range(planes.shape[0]):
            an = a_n[i, q]
            if not an > 0.0:
                continue
            nx = planes[q, 0]
            ny = planes[q, 1]
            ut = tangential_speed(u[i], v[i], nx, ny)
            iw = wall_inertial_number(ut, rho * an * dx, rho_s, shear_length, d)
            kd = wall_friction_mu_i(iw, mu_s, mu_2, i0) * an / max(ut, u_eps)
            diag_u[i] += dt * kd * ny * ny
            diag_v[i] += dt * kd * nx * nx


@prange_kernel
def viscous_wall_drag(pairs, nf, pos, eta, walls, planes, law, consts, wall_ns):
    """Per particle and wall plane (positions pos = (x, y); law = (slip code, slip length);
    consts = (dx, ρ, V, ε², Laplacian norm)), the drag coefficient k (1/s) of the viscous wall term of
    :func:`viscous.assemble_viscous` (its diagonal gets Δt k t_a² on the tangential component):
    k = Σ_w 2 η_i V F_iw β / (ρ wall_ns) over the wall particles w of that plane, β of
    :func:`wall_beta` for ``slip`` (no_slip or navier). Used to book the no-slip/Navier wall's share
    of the dissipation and by :func:`stress_limited_drag`."""
    x, y = pos
    slip, slip_length = law
    dx, rho, vol, eps2, lap_norm = consts
    start, nbr, rr, gw = pairs.start, pairs.nbr, pairs.rr, pairs.gw
    wnx, wny, wc = walls.nx, walls.ny, walls.c
    npl = planes.shape[0]
    kns = np.zeros((nf, npl))
    for i in prange(nf):
        for k in range(start[i], start[i + 1]):
            j = nbr[k]
            if j < nf:
                continue
            w = j - nf
            q = 0
            best = -2.0
            for qq in range(npl):  # the plane of this wall particle: the one with its normal
                dot = wnx[w] * planes[qq, 0] + wny[w] * planes[qq, 1]
                if dot > best:
                    best = dot
                    q = qq
            r = rr[k]
            f = -gw[k] * r * r / (r * r + eps2)
            beta = wall_beta(x[i], y[i], wnx[w], wny[w], wc[w], x[j], y[j], slip, slip_length, dx)
            kns[i, q] += 2.0 * eta[i] / wall_ns * vol * f * beta / rho
    return kns


@prange_kernel
def stress_limited_drag(nf, vel, kns, p_rheo, a_n, planes, consts, diag):
    """Stress-limited slip (``wall.slip: stress_limited``; vel = (u, v), consts = (μ_B, dx, Δt, ρ,
    u_eps), diag = (diag_u, diag_v); our reading of the paper's Section 4.1
    "slip velocity ... calculated based on the stress field"): the bed holds the first layer with the
    no-slip viscous wall stress η ∂u/∂n (drag coefficient ``kns`` per plane, the no-slip wall term
    of :func:`viscous_wall_drag`) as long as that stress stays below the Coulomb limit μ_B p_w;
    beyond it the particle slips and the wall carries μ_B p_w (drag μ_B a_n/|u_t|, as
    :func:`coulomb_drag_from_reaction`). Per particle and plane the diagonal gets
    Δt min(k_ns, μ_B a_n/max(|u_t|, u_eps)) on the tangential component; a particle the wall does not
    press on (a_n ≤ 0) is free to slide and to separate. Dissipative (coefficients ≥ 0).

    The wall stress is the μ(I) stress at the bed, not at the particle's centre: k_ns p_w/p_i with
    p_w = ρ a_n dx the walls' normal stress (p_i: the pressure the rheology saw). With η_i alone a
    sheet one particle thick (p_i = ρ g cosθ dx/2, the half-layer floor) got half the basal friction
    it needs (μ/2 < tan 22°) and slid on: at dx = 8 mm T22-A70 sent 163 particles 4 m down the bed."""
    u, v = vel
    mu_wall, dx, dt, rho, u_eps = consts
    diag_u, diag_v = diag
    for i in prange(nf):
        for q in range(planes.shape[0]):
            an = a_n[i, q]
            if not an > 0.0 or kns[i, q] <= 0.0:
                continue
            k_ns = kns[i, q] * max(rho * an * dx / max(p_rheo[i], 1e-300), 1.0)
            nx = planes[q, 0]
            ny = planes[q, 1]
            ut = tangential_speed(u[i], v[i], nx, ny)
            kd = min(k_ns, mu_wall * an / max(ut, u_eps))
            diag_u[i] += dt * kd * ny * ny
            diag_v[i] += dt * kd * nx * nx
