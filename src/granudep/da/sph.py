"""SPH operators of the DA model (eqs 20–25, 28–29, 33): depth, gradients, XSPH sum, grid sums.

Each operator is an ``@njit(cache=True)`` function over the sorted particles and their index windows
(``neighbours.py``); the Gaussian is ``kernels.gauss_w_e`` / ``gauss_gradw_e`` everywhere. The time
stepping that calls them is ``da/step.py``.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from .kernels import gauss_gradw_e, gauss_w, gauss_w_e, kernel_norm
from .neighbours import build_extended, count_ghosts, windows

# rows of the per-particle state matrix F (sorted order; x is kept separately)
F_U, F_V, F_V0, F_ND, F_H, F_K = 0, 1, 2, 3, 4, 5
N_FIELDS = 6

# rows of a stage matrix S (one per stage of the step, sorted order): what the operators give at the
# stage's positions. S_H depth (eq 20; an area until ``step.bed_terms`` divides by the width), S_ND
# number density, S_DH ∂h/∂s (eqs 21–22; k-weighted in pair form), S_DU ∂u/∂s (eqs 28–29), S_XS the
# XSPH sum (eq 33), S_GB −∂h_D/∂s (deposit as bed), S_GS g sinθ, S_GC g cosθ, S_FC the friction
# deceleration, S_K the k that multiplies S_DH, S_KB the pair-mean k of the width term.
S_H, S_ND, S_DH, S_DU, S_XS, S_GB, S_GS, S_GC, S_FC, S_K, S_KB = range(11)
N_STAGE = 11

# The neighbour window W of a stage: the extended arrays (mirror ghosts first, then the particles)
# of positions xe, velocities ue, volumes Ve, depths he, and each real particle's window [lo, hi)
# into them; a tuple so that the passes take one argument for it (``new_window``).

# fast-math for the pair passes WITHOUT 'reassoc': re-associated (vectorised) sums depend on the
# alignment of the pair buffer and made two identical runs differ in the last bit.
FASTMATH = {"nsz", "arcp", "contract", "afn"}

# the Shepard sum of eq 22 is floored: a nearly emptied particle (deposition) at the edge of a full
# particle's kernel has Σ V_j/h_j W_ij ≪ 1, and dividing by it gave accelerations of ~100 m/s² that
# shot such particles out of the domain. Full or half support gives Σ ≈ 1 or ≥ 0.5: unaffected.
SHEPARD_FLOOR = 0.5


@njit(cache=True)
def new_window(n):
    """The neighbour window W of n particles (room for n ghosts)."""
    return (np.empty(2 * n), np.zeros(2 * n), np.empty(2 * n), np.empty(2 * n), np.empty(n, np.int64),
            np.empty(n, np.int64))


@njit(cache=True)
def new_stage(n):
    """A stage matrix S of n particles (``S_*`` rows): the deposit term 0 and k̄ 1 until set."""
    S = np.empty((N_STAGE, n))
    S[S_GB] = 0.0
    S[S_KB] = 1.0
    return S


@njit(cache=True, fastmath=FASTMATH)
def depth_pass(W, m, n, kn, h, nd, E):
    """Eq 20, h_i = Σ_j V_j W_ij, and the number density Σ_j W_ij over particles with volume.
    Stores e^{−q²} of every pair in E (the windows of i = 0, 1, … one after the other) so the
    gradient pass needs no second exponential.

    Each exponential is evaluated once per pair of real particles: for j < i the value stored in
    j's window is reused (q² of (i, j) and (j, i) are the same floating-point number, so the
    results are bit for bit those of one exponential per ordered pair, at half the cost).
    W: the window (``new_window``), m ghosts first; kn = (L, kernel norm, q_c)."""
    xe, _, Ve, _, lo, hi = W
    L, norm, qc = kn
    qc2 = qc * qc
    ec = math.exp(-qc2)
    off = np.empty(n, np.int64)
    p = 0
    for i in range(n):
        off[i] = p
        ki = m + i
        xi = xe[ki]
        s = 0.0
        c = 0.0
        for j in range(lo[i], hi[i]):
            q2 = ((xi - xe[j]) / L) ** 2
            jr = j - m
            if jr >= 0 and jr < i and ki < hi[jr]:
                e = E[off[jr] + ki - lo[jr]]
            else:
                e = math.exp(-q2) if q2 < qc2 else 0.0
            E[p] = e
            p += 1
            vj = Ve[j]
            if vj > 0.0 and e > 0.0:
                w = gauss_w_e(e, q2, norm, qc2, ec)
                s += vj * w
                c += w
        h[i] = s
        nd[i] = c


@njit(cache=True, fastmath=FASTMATH)
def gradient_pass(W, m, n, kn, E, dhdx, dudx, xsph):
    """Eqs 21–22 (∂h/∂x), eqs 28–29 (∂u/∂x, eq 29's sign corrected) and the XSPH sum of eq 33.

    With eq 24's ∇W_ij = 2 r_ij/L² W'_ij = −∂W_ij/∂x_i (r_ij = x_i − x_j, ``kernels.gauss_gradw``):
    ∂h/∂x_i = Σ V_j B1 ∇W_ij, B1 = −[Σ V_j/h_j W_ij]⁻¹ (as printed);
    ∂u/∂x_i = Σ V_j (u_j − u_i) B2 ∇W_ij, B2 = +[Σ V_j (x_j − x_i) ∇W_ij]⁻¹ (printed with a minus,
    which returns −∂u/∂x). Both are exact for linear fields where the kernel support is full; B2 is
    exact for a linear u everywhere. E holds e^{−q²} of every pair from ``depth_pass``.
    """
    xe, ue, Ve, he, lo, hi = W
    L, norm, qc = kn
    qc2 = qc * qc
    ec = math.exp(-qc2)
    g2 = 2.0 * norm / (L * L)
    p = 0
    for i in range(n):
        k = m + i
        if Ve[k] <= 0.0:
            dhdx[i] = 0.0
            dudx[i] = 0.0
            xsph[i] = 0.0
            p += hi[i] - lo[i]
            continue
        xi = xe[k]
        ui = ue[k]
        hi_ = he[k]
        shep = 0.0
        gh = 0.0
        num = 0.0
        den = 0.0
        xs = 0.0
        for j in range(lo[i], hi[i]):
            e = E[p]
            p += 1
            vj = Ve[j]
            if vj <= 0.0 or e == 0.0:
                continue
            r = xi - xe[j]
            q2 = (r / L) ** 2
            w = gauss_w_e(e, q2, norm, qc2, ec)
            gw = gauss_gradw_e(g2, r, e, ec)
            hj = he[j]
            if hj > 0.0:
                shep += vj / hj * w
            gh += vj * gw
            du = ue[j] - ui
            num += vj * du * gw
            den -= vj * r * gw
            xs += 2.0 * vj / (hi_ + hj) * du * w
        dhdx[i] = -gh / max(shep, SHEPARD_FLOOR)
        dudx[i] = num / den if den != 0.0 else 0.0
        xsph[i] = xs


@njit(cache=True)
def evaluate_into(x, u, V, L, qc, wall, W, S, E):
    """Depth (eq 20), gradients (eqs 21–22, 28–29) and XSPH sum (eq 33) of all particles at
    positions x (sorted) and velocities u, into the rows S_H, S_ND, S_DH, S_DU, S_XS of the stage
    matrix S; W: the neighbour window it fills (``new_window``). ``E`` is the pair buffer: grown
    (and returned) when the pairs do not fit, so a kernel that keeps the returned buffer allocates
    it once per call of ``step.advance`` instead of twice per step."""
    xe, ue, Ve, he, lo, hi = W
    h, nd = S[S_H], S[S_ND]
    n = x.shape[0]
    radius = qc * L
    norm = kernel_norm(L, qc)
    m = count_ghosts(x, radius, wall)
    build_extended(x, u, V, m, xe, ue, Ve)
    ne = m + n
    windows(xe, m, ne, radius, lo, hi)
    npairs = 0
    for i in range(n):
        npairs += hi[i] - lo[i]
    if E.shape[0] < npairs:
        E = np.empty(npairs + npairs // 4)
    kn = (L, norm, qc)
    depth_pass(W, m, n, kn, h, nd, E)
    for k in range(m):
        he[k] = h[m - 1 - k]
    for i in range(n):
        he[m + i] = h[i]
    gradient_pass(W, m, n, kn, E, S[S_DH], S[S_DU], S[S_XS])
    return E


@njit(cache=True, fastmath=FASTMATH)
def symmetric_pressure_pass(W, ke, m, n, kn, E, kdh, kbar):
    """The earth-pressure gradient in symmetric (pair) form: kdh_i = −Σ_j V_j ½(k_i + k_j) ∇W_ij / S_i
    with S_i = max(Σ_j V_j/h_j W_ij, SHEPARD_FLOOR), i.e. ∂h/∂x of ``gradient_pass`` (eqs 21–22) with
    the pair's mean k inside the sum, and kbar_i = Σ V_j ½(k_i + k_j) |∇W_ij| / Σ V_j |∇W_ij| (the k of
    the particle's own width term; k_i for an isolated particle).

    ½(k_i + k_j) is symmetric, so (with S ≈ 1 inside the flow) the pair forces are equal and opposite;
    it is the SPH form of −(1/h) ∂(k g cosθ h²/2)/∂x with P/h² = k g cosθ/2. With S = 1 and a fixed
    L_s the rate of E = Σ V (u²/2 + g z + g cosθ h/2) it gives is −(g cosθ/2) Σ_i V_i (k_i − 1) dh_i/dt,
    never positive when k_i ≥ 1 where dh_i/dt > 0 (∂u/∂x_i < 0: k_p) and k_i ≤ 1 where it is < 0 (k_a).
    ke: k of the extended particles (ghosts first); E: e^{−q²} of every pair from ``depth_pass``."""
    xe, _, Ve, he, lo, hi = W
    L, norm, qc = kn
    qc2 = qc * qc
    ec = math.exp(-qc2)
    g2 = 2.0 * norm / (L * L)
    p = 0
    for i in range(n):
        k = m + i
        if Ve[k] <= 0.0:
            kdh[i] = 0.0
            kbar[i] = ke[k]
            p += hi[i] - lo[i]
            continue
        xi = xe[k]
        ki = ke[k]
        shep = 0.0
        gh = 0.0
        wsum = 0.0
        ksum = 0.0
        for j in range(lo[i], hi[i]):
            e = E[p]
            p += 1
            vj = Ve[j]
            if vj <= 0.0 or e == 0.0:
                continue
            r = xi - xe[j]
            q2 = (r / L) ** 2
            w = gauss_w_e(e, q2, norm, qc2, ec)
            gw = gauss_gradw_e(g2, r, e, ec)
            hj = he[j]
            if hj > 0.0:
                shep += vj / hj * w
            kij = 0.5 * (ki + ke[j])
            gh += vj * kij * gw
            a = vj * abs(gw)
            wsum += a
            ksum += a * kij
        kdh[i] = -gh / max(shep, SHEPARD_FLOOR)
        kbar[i] = ksum / wsum if wsum > 0.0 else ki


@njit(cache=True)
def symmetric_pressure_gradient(x, L, qc, wall, W, E, k, ke, S):
    """``symmetric_pressure_pass`` over the window W and pair buffer E that ``evaluate_into`` just
    filled for the same positions x; k: each real particle's k (a ghost takes its mirror
    particle's). Outputs: the rows S_DH (k-weighted ∂h/∂s) and S_KB (k̄) of S; ke: work array (≥ ghosts + n)."""
    n = x.shape[0]
    m = count_ghosts(x, qc * L, wall)
    for g in range(m):
        ke[g] = k[m - 1 - g]
    for i in range(n):
        ke[m + i] = k[i]
    symmetric_pressure_pass(W, ke, m, n, (L, kernel_norm(L, qc), qc), E, S[S_DH], S[S_KB])


@njit(cache=True)
def evaluate(x, u, V, L, qc, wall):
    """``evaluate_into`` with a window, stage matrix and pair buffer of its own; returns the stage matrix."""
    S = new_stage(x.shape[0])
    evaluate_into(x, u, V, L, qc, wall, new_window(x.shape[0]), S, np.empty(0))
    return S


@njit(cache=True)
def particle_depths(x, V, L, qc, wall):
    """Eq 20 at the (sorted) particle positions."""
    n = x.shape[0]
    W = new_window(n)
    xe, ue, Ve, _, lo, hi = W
    h = np.empty(n)
    nd = np.empty(n)
    radius = qc * L
    m = count_ghosts(x, radius, wall)
    build_extended(x, np.zeros(n), V, m, xe, ue, Ve)
    windows(xe, m, m + n, radius, lo, hi)
    npairs = 0
    for i in range(n):
        npairs += hi[i] - lo[i]
    depth_pass(W, m, n, (L, kernel_norm(L, qc), qc), h, nd, np.empty(npairs))
    return h


@njit(cache=True)
def grid_depth(x, V, L, qc, wall, dxg, ng):
    """Eq 20 evaluated at the cell centres (k + ½) dxg of the fixed grid (scatter, window per particle)."""
    out = np.zeros(ng)
    norm = kernel_norm(L, qc)
    radius = qc * L
    for j in range(x.shape[0]):
        vj = V[j]
        if vj <= 0.0:
            continue
        for mirror in range(2):
            if mirror == 1 and (not wall or x[j] >= radius):
                continue
            xj = x[j] if mirror == 0 else -x[j]
            k0 = max(0, int(math.floor((xj - radius) / dxg)))
            k1 = min(ng - 1, int(math.floor((xj + radius) / dxg)) + 1)
            for k in range(k0, k1 + 1):
                out[k] += vj * gauss_w((k + 0.5) * dxg - xj, L, norm, qc)
    return out


@njit(cache=True, inline="always")
def deposit_to_grid(dep, xp, dv, dxg):
    """Put volume dv at position xp onto the grid: linear weights to the two nearest cell centres."""
    ng = dep.shape[0]
    s = xp / dxg - 0.5
    k = int(math.floor(s))
    if k < 0:
        dep[0] += dv
    elif k >= ng - 1:
        dep[ng - 1] += dv
    else:
        w = s - k
        a = dv * (1.0 - w)
        dep[k] += a
        dep[k + 1] += dv - a


@njit(cache=True, inline="always")
def _deposit_cells_gradient(s, dep, xi, sign, k0, k1, c):
    """s + Σ_k dep_k ∇W(x_i − sign·x_k) over the cells k0 … k1 (sign −1: the mirror images at the
    wall); c = (cell, L, q_c², e^{−q_c²}, 2 norm/L²)."""
    dxg, L, qc2, ec, g2 = c
    for k in range(k0, k1 + 1):
        if dep[k] == 0.0:
            continue
        r = xi - sign * (k + 0.5) * dxg
        q2 = (r / L) ** 2
        if q2 < qc2:
            s += gauss_gradw_e(dep[k] * g2, r, math.exp(-q2), ec)
    return s


@njit(cache=True)
def deposit_gradient(x, V, dep, dxg, L, qc, wall, out):
    """∂h_D/∂x at the particles: the deposit (cell depths dep/dxg at the cell centres) smoothed with
    the same kernel, ∂/∂x_i Σ_k h_D,k Δx W(x_i − x_k), mirrored at the wall like the particles."""
    ng = dep.shape[0]
    norm = kernel_norm(L, qc)
    radius = qc * L
    qc2 = qc * qc
    ec = math.exp(-qc2)
    g2 = 2.0 * norm / (L * L)
    c = (dxg, L, qc2, ec, g2)
    for i in range(x.shape[0]):
        out[i] = 0.0
        if V[i] <= 0.0:
            continue
        xi = x[i]
        k0 = max(0, int(math.floor((xi - radius) / dxg)))
        k1 = min(ng - 1, int(math.floor((xi + radius) / dxg)) + 1)
        s = _deposit_cells_gradient(0.0, dep, xi, 1.0, k0, k1, c)
        if wall and xi < radius:
            k1 = min(ng - 1, int(math.floor((radius - xi) / dxg)) + 1)
            s = _deposit_cells_gradient(s, dep, xi, -1.0, 0, k1, c)
        out[i] = -s
