"""Plain-NumPy twins of the DA step (the STUMPY ``tests/naive.py`` model): dense all-pairs
matrices, no windows, no pair buffer, no sorting, formulas written out from the paper's
equations — slow and obviously right. ``step`` takes one RK2 step exactly as documented in
``granudep.da.step`` (stage list in its module docstring) and is compared with the numba kernel.
"""
from __future__ import annotations

import math

import numpy as np

from granudep.da.path import T_A, T_B, T_COS, T_DWIDTH, T_KACT, T_KAPPA, T_KPASS, T_SIN, T_WIDTH


def kernel(r, L, qc):
    """W (eq 23, truncated smoothly and renormalised) and eq 24's −∂W/∂x_i for r = x_i − x_j."""
    ec = math.exp(-qc * qc)
    norm = 1.0 / (L * (math.sqrt(math.pi) * math.erf(qc) - 2.0 * qc * ec * (1.0 + 2.0 * qc * qc / 3.0)))
    q2 = (r / L) ** 2
    inside = q2 < qc * qc
    e = np.exp(-q2)
    W = np.where(inside, norm * (e - ec * (1.0 + qc * qc - q2)), 0.0)
    gW = np.where(inside, 2.0 * norm / L ** 2 * r * (e - ec), 0.0)
    return W, gW


def with_ghosts(x, u, V, L, qc, wall):
    """Particles plus their mirror images −x (velocity −u) for x < q_c L at a wall; index of the
    real particle each image belongs to."""
    idx = np.arange(x.size)
    if wall:
        g = x < qc * L
        return (np.concatenate([-x[g], x]), np.concatenate([-u[g], u]), np.concatenate([V[g], V]),
                np.concatenate([idx[g], idx]))
    return x, u, V, idx


def fields(x, u, V, L, qc, wall):
    """Eq 20 depth h, number density, eqs 21–22 ∂h/∂x, eqs 28–29 ∂u/∂x (sign corrected), XSPH sum."""
    xs, us, Vs, own = with_ghosts(x, u, V, L, qc, wall)
    r = x[:, None] - xs[None, :]
    W, gW = kernel(r, L, qc)
    full = (Vs > 0.0)[None, :]
    h = np.sum(np.where(full, Vs * W, 0.0), axis=1)
    nd = np.sum(np.where(full, W, 0.0), axis=1)
    hs = h[own]
    shep = np.sum(np.where(full & (hs > 0.0)[None, :], Vs / np.where(hs > 0, hs, 1.0) * W, 0.0), axis=1)
    dh = -np.sum(np.where(full, Vs * gW, 0.0), axis=1) / np.maximum(shep, 0.5)
    dU = us[None, :] - u[:, None]
    num = np.sum(np.where(full, Vs * dU * gW, 0.0), axis=1)
    den = -np.sum(np.where(full, Vs * r * gW, 0.0), axis=1)
    du = np.where(den != 0.0, num / np.where(den != 0.0, den, 1.0), 0.0)
    xsph = np.sum(np.where(full, 2.0 * Vs / (h[:, None] + hs[None, :]) * dU * W, 0.0), axis=1)
    empty = V <= 0.0
    dh[empty] = du[empty] = xsph[empty] = 0.0
    return h, nd, dh, du, xsph


def symmetric_pressure(x, V, L, qc, wall, k):
    """−Σ_j V_j ½(k_i + k_j) ∇W_ij / max(Σ_j V_j/h_j W_ij, ½) and the |∇W|-weighted mean of ½(k_i + k_j),
    dense, with the mirror images (which carry their particle's k)."""
    xs, _, Vs, own = with_ghosts(x, np.zeros_like(x), V, L, qc, wall)
    r = x[:, None] - xs[None, :]
    W, gW = kernel(r, L, qc)
    full = (Vs > 0.0)[None, :]
    h = np.sum(np.where(full, Vs * W, 0.0), axis=1)
    hs = h[own]
    shep = np.sum(np.where(full & (hs > 0.0)[None, :], Vs / np.where(hs > 0, hs, 1.0) * W, 0.0), axis=1)
    kij = 0.5 * (k[:, None] + k[own][None, :])
    kdA = -np.sum(np.where(full, Vs * kij * gW, 0.0), axis=1) / np.maximum(shep, 0.5)
    a = np.where(full, Vs * np.abs(gW), 0.0)
    ws = a.sum(axis=1)
    kbar = np.where(ws > 0, (a * kij).sum(axis=1) / np.where(ws > 0, ws, 1.0), k)
    kdA[V <= 0.0] = 0.0
    return kdA, kbar


def deposit_slope(x, V, depb, dxg, L, qc, wall):
    """∂h_D/∂x at the particles from the cell volumes (/width) at the cell centres, mirrored at a wall."""
    c = (np.arange(depb.size) + 0.5) * dxg
    _, gW = kernel(x[:, None] - c[None, :], L, qc)
    s = gW @ depb
    if wall:
        _, gM = kernel(x[:, None] + c[None, :], L, qc)
        s = s + np.where(x < qc * L, gM @ depb, 0.0)
    return np.where(V > 0.0, -s, 0.0)


def bed(tab, s, p):
    """Bed table rows at stations s (linear, held at the ends)."""
    st = np.arange(tab.shape[1]) * p.ds
    return {row: np.interp(s, st, tab[row]) for row in (T_SIN, T_COS, T_KAPPA, T_WIDTH, T_DWIDTH, T_KACT, T_KPASS,
                                                        T_A, T_B)}


def stage(x, u, V, L, tab, p, depb, dxg, k_state=None):
    """One evaluation: depth, slopes and the per-particle bed quantities; ``k_state``: the strained
    k of each particle (``earth_pressure_switch`` 'strain') instead of the sign switch."""
    area, nd, dA, du, xsph = fields(x, u, V, L, p.kernel_support, p.back_wall)
    b = bed(tab, x + p.origin, p)
    h = area / b[T_WIDTH]
    dh = (dA - h * b[T_DWIDTH]) / b[T_WIDTH]
    gs, gc = p.g * b[T_SIN], p.g * b[T_COS]
    N = np.maximum(p.g * b[T_COS] + (b[T_KAPPA] if p.centripetal else 0.0) * u * u, 0.0)
    fc = p.tan_phi_basal * N
    k = np.where(du >= 0.0, b[T_KACT], b[T_KPASS]) if k_state is None else k_state
    if p.k_symmetric:   # pair form: k-weighted area gradient with ½(k_i + k_j) inside the sum
        kdA, kbar = symmetric_pressure(x, V, L, p.kernel_support, p.back_wall, k)
        dh = (kdA - kbar * h * b[T_DWIDTH]) / b[T_WIDTH]
        k = np.ones_like(k)
    # the deposit is known per grid cell: its kernel is never narrower than a cell
    gb = (deposit_slope(x, V, depb, dxg, max(L, dxg), p.kernel_support, p.back_wall) if p.deposition and p.deposit_as_bed
          else np.zeros_like(x))
    a = gs - k * gc * dh - gc * gb
    live = V > 0.0
    return dict(h=h, nd=nd, dh=dh, du=du, xsph=xsph, fc=np.where(live, fc, 0.0), a=np.where(live, a, 0.0), b=b)


def coulomb(ustar, budget):
    return np.where(ustar > budget, ustar - budget, np.where(ustar < -budget, ustar + budget, 0.0))


def strained(k0, du, dt, b, p):
    """k after the strain −∂u/∂x Δt: k0 − (k_p − k_a)/ε_k ∂u/∂x Δt within [k_a, k_p] (b: bed rows)."""
    return np.clip(k0 - (b[T_KPASS] - b[T_KACT]) * p.k_strain * du * dt, b[T_KACT], b[T_KPASS])


def step(x, u, V, V0, nd_prev, dep, depb, binv, p, tab, k_state=None):
    """One RK2 step of the DA model from sorted (x, u); returns the new state and Δt (and the new
    strained k when ``k_state`` is given: Heun mean of the two stages' ∂u/∂x)."""
    live = V > 0.0
    strain = k_state is not None
    if p.L_fixed > 0:
        L = p.L_fixed
    else:
        ok = live & (nd_prev > 0.0)
        w = (V / V0)[ok] if p.smoothing_volume else np.ones(ok.sum())
        L = p.smoothing_B * w.sum() / (w * nd_prev[ok]).sum()
    wf = np.ones_like(x)
    k1 = None
    if strain:
        b1 = bed(tab, x + p.origin, p)
        k1 = np.where(live, np.clip(k_state, b1[T_KACT], b1[T_KPASS]), k_state)
        wf = b1[T_KPASS] + 0.5 * (b1[T_KPASS] - b1[T_KACT]) * p.k_strain
    s1 = stage(x, u, V, L, tab, p, depb, p.dx_grid, k1)
    h = s1["h"]
    hw = h * wf                                   # c²/g of the time step
    if p.dt_relative:
        wmax = np.max(np.abs(u[live]))
        c = np.sqrt(p.g * hw) + np.minimum(L * np.abs(s1["du"]), 2.0 * wmax)
        dt = p.cfl * L / c[live].max()
        if wmax * dt > p.cfl * p.geometry_step:
            dt = p.cfl * p.geometry_step / wmax
    else:
        dt = p.cfl * L / np.maximum(np.abs(u), np.sqrt(p.g * hw))[live].max()
    # stage 1: deposition (eqs 14, 34, 36) and the eq 12 loss
    a1, fc1 = s1["a"], s1["fc"]
    an = np.where(u > 0, a1 - fc1, np.where(u < 0, a1 + fc1, np.where(a1 > fc1, a1 - fc1,
                                                                        np.where(a1 < -fc1, a1 + fc1, 0.0))))
    dhu = np.where(u != 0.0, np.sign(u) * h * an - np.abs(u) * h * s1["du"], h * np.abs(an))
    fr = np.zeros_like(x)
    if p.deposition:
        xn_ = (x - p.L0) / (p.x_inf - p.L0)
        if p.clamp_x:
            xn_ = np.clip(xn_, 0.0, 1.0)
        huc = p.momentum_scale * (s1["b"][T_A] * xn_ + s1["b"][T_B])
        hu = np.abs(u) * h
        dec = live & (h > 0) & (huc > 0) & (hu < huc) & (dhu < 0)
        dec &= np.abs(s1["b"][T_SIN]) <= p.deposit_max_tan * s1["b"][T_COS]   # no deposit steeper than φ_B
        alpha = np.where(dec, (huc - hu) / np.where(huc > 0, huc, 1.0), 0.0)
        sd = alpha * dhu / np.maximum(np.abs(u), p.u_min)
        fr = np.where(dec, np.minimum(1.0, -sd * dt / np.where(h > 0, h, 1.0)), 0.0)
    loss = p.g * p.tan_phi_internal * fr * dt if p.eq12 else 0.0 * fr
    # predictor
    ut = np.where(live, coulomb(u + dt * a1, fc1 * dt + loss), 0.0)
    xt = np.where(live, x + dt * u, x)
    if p.back_wall:
        xt = np.abs(xt)
    k2 = None
    if strain:
        k2 = np.where(live, strained(k1, s1["du"], dt, bed(tab, xt + p.origin, p), p), k1)
    s2 = stage(xt, ut, V, L, tab, p, depb, p.dx_grid, k2)
    un = coulomb(u + 0.5 * dt * (a1 + s2["a"]), 0.5 * dt * (fc1 + s2["fc"]) + loss)
    xn = x + dt * (0.5 * (u + un) + p.xsph_delta * s2["xsph"])
    if p.back_wall:
        back = xn < 0.0
        xn = np.abs(xn)
        un = np.where(back & (un < 0), 0.0, un)
    un = np.where(live, un, 0.0)
    xn = np.where(live, xn, x)
    kn = np.where(live, strained(k1, 0.5 * s1["du"] + 0.5 * s2["du"], dt, bed(tab, xn + p.origin, p), p), k1) \
        if strain else None
    # deposition onto the grid (linear weights to the two nearest cell centres)
    dep, depb = dep.copy(), depb.copy()
    Vn = V.copy()
    for i in np.flatnonzero(live & (fr > 0)):
        dv = fr[i] * V[i]
        rest = V[i] - dv
        if rest < p.min_volume_fraction * V0[i]:
            dv, rest, un[i] = V[i], 0.0, 0.0
        Vn[i] = rest
        sg = xn[i] / p.dx_grid - 0.5
        k = int(math.floor(sg))
        ng = dep.size
        if k < 0:
            parts = [(0, dv)]
        elif k >= ng - 1:
            parts = [(ng - 1, dv)]
        else:
            parts = [(k, dv * (1 - (sg - k))), (k + 1, dv * (sg - k))]
        for kk, v in parts:
            dep[kk] += v
            depb[kk] += v * binv[kk]
    if strain:
        return xn, un, Vn, dep, depb, s1["h"], dt, L, fr, kn
    return xn, un, Vn, dep, depb, s1["h"], dt, L, fr
