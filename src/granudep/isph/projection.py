"""Energy-consistent projection: the PPE divergence as the negative adjoint of the
pressure gradient that the corrector applies.

The corrector applies G p_i = L_i Σ_j V (p_j − p_i) ∇_i W_ij (renormalised, :func:`approximate.pressure_gradient`;
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
instead of +20 %) and is not the default (docs/model.md, "Energy-stable projection").
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from .ppe_operator import (PPESystem, adjoint_triangles, apply_divergence, apply_gradient, assemble_adjoint_ppe,
                           matrix_free_operator, ppe_rhs)


@njit(cache=True)
def adjoint_divergence(pairs, nf, vol, u, v, lmat):
    """D u_k = −(Gᵀ u)_k for the renormalised pressure gradient with matrices ``lmat`` (rows
    L0 L1 / L2 L3, the ones the corrector uses); granular neighbours only."""
    start, nbr, rx, ry, gw = pairs.start, pairs.nbr, pairs.rx, pairs.ry, pairs.gw
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



# ------------------------------------------------------------------------------------------------
# Adjoint-pair projection with pressure-carrying walls (``numerics.projection: adjoint_pair``)
#
# Pressure nodes: the granular particles 0..nf-1 and the wall particles nf..nf+nw-1. The divergence
#
#   D u_k = Σ_j V g_kj (u_j − u_k)·(L_k r_kj) − Σ_w V g_kw (u_k·n_w)(n_w·L_k r_kw)   (granular k)
#   D u_w = Σ_j V g_wj (u_j·n_w)(n_w·r_wj)             (wall node w, surface normal n_w)
#
# is the renormalised divergence (exact for linear fields on a full support; with the wall nodes in
# the sum the support of a particle next to a wall is full, as its L already assumes). The
# corrector's gradient is its negative adjoint G = −Dᵀ:
#
#   G p_i = Σ_j V g_ij (p_i L_i + p_j L_j) r_ij + Σ_w V g_iw [p_i n_w·(L_i r_iw) + p_w n_w·r_iw] n_w,
#
# the momentum-conserving symmetric form with renormalisation; the walls see and push only the
# wall-normal velocity (a wall that also held the tangential stretching of the flow along it took
# 36 % of E_ref out of the water dam break by t = 0.4 s at dx = 8 mm). With p = 0 on the Dirichlet nodes
# Σ_i u_i·(G p)_i = −Σ_k p_k (D u)_k exactly, so the kinetic energy change of the projection
# u = u* − Δt/ρ G p with  ((1 − ε) D Dᵀ + ε L_c) p = −(ρ/Δt) D u*  is
#
#   ΔE_kin = −m (Δt/ρ)² [ (½ − ε) |Dᵀ p|² + ε p·L_c p ] ≤ 0   for 0 ≤ ε ≤ ½
#
# (with a free-surface Dirichlet value p_fs ≠ 0, ``numerics.free_surface_pressure: half_layer``, and
# the density-invariant source the work of those two terms adds to it: +0.16 % of E_ref in a flat
# quartz collapse at 2 mm; the water dam break never rose above E_0)
#
# (L_c: the compact Cummins–Rudman Laplacian, positive semi-definite; it removes the checkerboard
# null space of D Dᵀ, which a 2-ring operator has on any lattice). Both operators approximate −∇²
# for smooth pressures, so the blend projects a smooth load in full; the additive form
# D Dᵀ + ε L_c under-projected it by 1/(1 + ε): a Newtonian film sank at 0.6 mm/s with its bed
# pressure 12 % low, ε = 0.1). The wall nodes' pressure is
# an unknown like any other: the wall pushes exactly as hard as the no-penetration constraint
# D u_w = 0 needs; a wall node whose solved pressure is negative (the flow leaves the wall) is set
# to p = 0 and the system solved again (the wall never pulls).
# ------------------------------------------------------------------------------------------------


@njit(cache=True)
def divergence_entries(pairs, nf, vol, lmat, walls):
    """COO entries (row node, column particle, x and y coefficients) of D above, with the wall
    terms restricted to the wall-normal velocity (n: the wall particle's surface normal): a wall
    constrains penetration only, never the tangential stretching of the flow along it."""
    start, nbr, rx, ry, gw = pairs.start, pairs.nbr, pairs.rx, pairs.ry, pairs.gw
    wnx, wny = walls.nx, walls.ny
    nnz = 0
    for k in range(nf):
        nnz += 1 + start[k + 1] - start[k]
    rows = np.empty(nnz, np.int64)
    cols = np.empty(nnz, np.int64)
    cx = np.empty(nnz)
    cy = np.empty(nnz)
    pos = 0
    for k in range(nf):
        l0 = lmat[k, 0]
        l1 = lmat[k, 1]
        l2 = lmat[k, 2]
        l3 = lmat[k, 3]
        sx = 0.0
        sy = 0.0
        for q in range(start[k], start[k + 1]):
            j = nbr[q]
            g = vol * gw[q]
            x = rx[q]
            y = ry[q]
            ax = g * (l0 * x + l1 * y)
            ay = g * (l2 * x + l3 * y)
            if j < nf:
                sx -= ax
                sy -= ay
                rows[pos] = k
                cols[pos] = j
                cx[pos] = ax
                cy[pos] = ay
            else:
                w = j - nf
                nx = wnx[w]
                ny = wny[w]
                # the particle's own row: (0 − u_k·n) n·(L_k r_kw)
                an = nx * ax + ny * ay
                sx -= an * nx
                sy -= an * ny
                # the wall node's row: V g_wk (u_k·n)(n·r_wk), r_wk = −r_kw
                bn = -g * (nx * x + ny * y)
                rows[pos] = j
                cols[pos] = k
                cx[pos] = bn * nx
                cy[pos] = bn * ny
            pos += 1
        rows[pos] = k
        cols[pos] = k
        cx[pos] = sx
        cy[pos] = sy
        pos += 1
    return rows, cols, cx, cy


@njit(cache=True, nogil=True)
def compact_laplacian_edges(pairs, nf, vol, eps2, lap_norm):
    """Edges (i, j, a_ij) of the compact Laplacian L_c = Σ_e a_e (e_i − e_j)(e_i − e_j)ᵀ over the
    granular pairs (each once) and the granular–wall pairs; a_ij = 2 V F_ij r²/(r² + ε²)/lap_norm
    (the PPE's Cummins & Rudman weights)."""
    start, nbr, rr, gw = pairs.start, pairs.nbr, pairs.rr, pairs.gw
    n = 0
    for i in range(nf):
        for q in range(start[i], start[i + 1]):
            j = nbr[q]
            if j > i:
                n += 1
    ei = np.empty(n, np.int64)
    ej = np.empty(n, np.int64)
    ea = np.empty(n)
    pos = 0
    for i in range(nf):
        for q in range(start[i], start[i + 1]):
            j = nbr[q]
            if j > i:
                r = rr[q]
                ei[pos] = i
                ej[pos] = j
                ea[pos] = 2.0 * vol * (-gw[q]) * r * r / (r * r + eps2) / lap_norm
                pos += 1
    return ei, ej, ea


class PairGeometry(NamedTuple):
    """What :func:`adjoint_pair_projection`'s first pass needs that does not depend on u*
    (:func:`adjoint_pair_geometry`)."""
    ei: np.ndarray          # L_c edges (compact_laplacian_edges)
    ej: np.ndarray
    ea: np.ndarray
    wetted: np.ndarray      # wall nodes with a granular neighbour
    active: np.ndarray      # the first pass's unknown nodes
    p: np.ndarray           # the known pressures (free surface), zero elsewhere
    triangles: tuple | None  # the first pass's PPE as its triangles (assemble_adjoint_triangles), or None


def adjoint_pair_geometry(pairs, nf, nw, vol, fs, p_fs, eps2, lap_norm, stab, wall_dry, entries, triangles):
    """The part of :func:`adjoint_pair_projection`'s first pass that does not depend on u*: the L_c
    edges, the wetted walls and the active set, the known pressures and, with ``triangles``, the PPE
    matrix as its triangles (its right-hand side is :func:`ppe_rhs`'s once u* is known). The solver
    runs it beside the predictor on a second thread when numba has two (bit for bit the same)."""
    rows = entries[0]
    n = nf + nw
    ei, ej, ea = compact_laplacian_edges(pairs, nf, vol, eps2, lap_norm)
    wetted = np.zeros(nw, dtype=np.bool_)
    wetted[np.unique(rows[rows >= nf] - nf)] = True
    active = np.empty(n, dtype=np.bool_)
    active[:nf] = ~fs
    active[nf:] = wetted & ~wall_dry
    p = np.zeros(n)
    p[:nf] = np.where(fs, p_fs, 0.0)
    tri = None
    if triangles:
        unknown, unk = _numbering(active)
        if unk.size:
            rows, cols, cx, cy = entries
            tri = adjoint_triangles(PPESystem(n, rows, cols, cx, cy, nf, ei, ej, ea, stab, unknown, unk.size))
    return PairGeometry(ei, ej, ea, wetted, active, p, tri)


def _numbering(active):
    """unknown[node] (the unknown's index, −1 for a known node) and the unknown nodes."""
    unknown = np.full(active.size, -1, np.int64)
    unk = np.flatnonzero(active)
    unknown[unk] = np.arange(unk.size)
    return unknown, unk


def _csr_builder(*args):
    """``assemble()`` for the matrix-free solvers' direct fallback: the CSR of these
    :func:`assemble_adjoint_ppe` arguments, built only when called."""
    return lambda: assemble_adjoint_ppe(*args)[:3]




def adjoint_pair_projection(pairs, nf, nw, vol, lmat, walls, fs, p_fs, us, vs, conc, c0, relax, dt, rho, eps2,
                            lap_norm, stab, guess, solve, wall_dry, max_passes=1, release=True, entries=None,
                            solve_free=None, free_form="free", geometry=None):
    """Solve ((1 − ε) D Dᵀ + ε L_c) p = −(ρ/Δt) D u* + s on the interior granular and the wetted wall nodes
    (free-surface particles: p = ``p_fs``; dry or pulling walls: p = 0) and return the node
    pressures (nf + nw), the corrector's G p = −Dᵀ p (x and y), the wall nodes to keep dry at the
    next step and the number of wall nodes released in this one.

    ``s``: the density-invariant source −γ ρ/Δt² min(1 − C/C0, 0) on granular rows (as in
    :func:`approximate.assemble_ppe`); ``solve(indptr, indices, data, rhs, guess)``: the PPE solver.
    Walls, a lagged active set: a wall node that pulls (p < 0) is released, held at p = 0 until the
    flow presses into it again (D u < 0 there after a projection); within a step up to
    ``max_passes`` solves release walls, the last solve is used as it is (a wall may pull for that
    one step: the energy identity holds for the system actually solved). ``entries``: D in COO
    (:func:`divergence_entries` of these arguments) when the caller has it already. ``solve_free``:
    when given, the matrix is never assembled: ``solve_free(op, rhs, guess, assemble)`` gets the
    operator of :func:`matrix_free_ppe` (``assemble()`` returns the CSR, for a direct fallback), or
    with ``free_form="triangles"`` the triangles of :func:`assemble_adjoint_triangles`. ``geometry``:
    :func:`adjoint_pair_geometry` of these arguments when the caller has it already (computed beside
    the predictor)."""
    n = nf + nw
    rows, cols, cx, cy = (entries if entries is not None else divergence_entries(pairs, nf, vol, lmat, walls))
    triangles = solve_free is not None and free_form == "triangles"
    if geometry is None:
        geometry = adjoint_pair_geometry(pairs, nf, nw, vol, fs, p_fs, eps2, lap_norm, stab, wall_dry,
                                         (rows, cols, cx, cy), triangles)
    ei, ej, ea, wetted = geometry.ei, geometry.ej, geometry.ea, geometry.wetted
    active = geometry.active.copy()
    p = geometry.p.copy()
    b = -(rho / dt) * apply_divergence(n, rows, cols, cx, cy, us, vs)
    b[:nf] -= relax * rho / (dt * dt) * np.minimum(1.0 - conc / c0, 0.0)
    released = 0
    pull = np.zeros(0, np.int64)
    for k in range(max_passes):
        unknown, unk = _numbering(active)
        if unk.size == 0:
            break
        p[unk] = 0.0
        system = PPESystem(n, rows, cols, cx, cy, nf, ei, ej, ea, stab, unknown, unk.size)
        if solve_free is not None:
            if k == 0 and triangles:
                op = geometry.triangles      # built before u* was known (it does not depend on it)
            else:
                # the triangles again for a changed active set, or the matrix-free operator
                # (numerics.ppe_operator): the same operator applied as D_U (D_Uᵀ x) + ε L_c x
                build = adjoint_triangles if triangles else matrix_free_operator
                op = build(system)
            rhs = ppe_rhs(system, p, b)
            p[unk] = solve_free(op, rhs, guess[unk], _csr_builder(system, p.copy(), b))
        else:
            indptr, indices, data, rhs = assemble_adjoint_ppe(system, p, b)
            p[unk] = solve(indptr, indices, data, rhs, guess[unk])
        pull = unk[(unk >= nf) & (p[unk] < 0.0)] if release else np.zeros(0, np.int64)
        released += int(pull.size)
        if pull.size == 0 or k == max_passes - 1:
            # the last solve is kept as it is, pulling walls included: the pressure then solves the
            # system it was computed for and the energy identity holds; they are dry from the next step
            break
        active[pull] = False
        p[pull] = 0.0
    gpx, gpy = apply_gradient(nf, rows, cols, cx, cy, p)
    # walls that stay dry: released ones, unless the corrected flow presses into them
    dry = wetted & ~active[nf:]
    dry[pull - nf] = True
    if dry.any():
        du = apply_divergence(n, rows, cols, cx, cy, us - dt / rho * gpx, vs - dt / rho * gpy)[nf:]
        dry &= du >= 0.0
    return p, gpx, gpy, dry, released
