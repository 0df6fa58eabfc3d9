"""Energy-consistent projection: the PPE divergence as the negative adjoint of the
pressure gradient that the corrector applies.

The corrector applies G p_i = L_i Σ_j V (p_j − p_i) ∇_i W_ij (renormalised, :func:`operators.pressure_gradient`;
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
from numba import get_num_threads, njit, prange

from .parallel import prange_kernel


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
            tri = adjoint_triangles(n, rows, cols, cx, cy, nf, ei, ej, ea, stab, unknown, unk.size)
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


@njit(cache=True, nogil=True)
def ppe_rhs(n, rows, cols, cx, cy, nf, ei, ej, ea, stab, unknown, n_unknown, p, b):
    """The right-hand side of the PPE on the unknowns, b_U − (1 − ε) D_U (D_Kᵀ p_K) − ε (L_c p_K)_U,
    for the matrix-free operator and the triangles (each row's D_U sum in D's COO order)."""
    wd = 1.0 - stab
    rhs = np.empty(n_unknown)
    for a in range(n):
        if unknown[a] >= 0:
            rhs[unknown[a]] = b[a]
    for e in range(ei.size):
        a = unknown[ei[e]]
        c = unknown[ej[e]]
        w = stab * ea[e]
        if a >= 0 and c < 0:
            rhs[a] += w * p[ej[e]]
        if c >= 0 and a < 0:
            rhs[c] += w * p[ei[e]]
    gx = np.zeros(nf)
    gy = np.zeros(nf)
    known = False
    for q in range(rows.size):
        a = rows[q]
        if unknown[a] < 0 and p[a] != 0.0:
            gx[cols[q]] += cx[q] * p[a]
            gy[cols[q]] += cy[q] * p[a]
            known = True
    if known:
        s = np.zeros(n_unknown)
        for q in range(rows.size):
            r = unknown[rows[q]]
            if r >= 0:
                s[r] += cx[q] * gx[cols[q]] + cy[q] * gy[cols[q]]
        for r in range(n_unknown):
            rhs[r] -= wd * s[r]
    return rhs


def adjoint_pair_projection(pairs, nf, nw, vol, lmat, walls, fs, p_fs, us, vs, conc, c0, relax, dt, rho, eps2,
                            lap_norm, stab, guess, solve, wall_dry, max_passes=1, release=True, entries=None,
                            solve_free=None, free_form="free", geometry=None):
    """Solve ((1 − ε) D Dᵀ + ε L_c) p = −(ρ/Δt) D u* + s on the interior granular and the wetted wall nodes
    (free-surface particles: p = ``p_fs``; dry or pulling walls: p = 0) and return the node
    pressures (nf + nw), the corrector's G p = −Dᵀ p (x and y), the wall nodes to keep dry at the
    next step and the number of wall nodes released in this one.

    ``s``: the density-invariant source −γ ρ/Δt² min(1 − C/C0, 0) on granular rows (as in
    :func:`ppe.assemble_ppe`); ``solve(indptr, indices, data, rhs, guess)``: the PPE solver.
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
        if solve_free is not None:
            if k == 0 and triangles:
                op = geometry.triangles      # built before u* was known (it does not depend on it)
            else:
                # the triangles again for a changed active set, or the matrix-free operator
                # (numerics.ppe_operator): the same operator applied as D_U (D_Uᵀ x) + ε L_c x
                build = adjoint_triangles if triangles else matrix_free_operator
                op = build(n, rows, cols, cx, cy, nf, ei, ej, ea, stab, unknown, unk.size)
            rhs = ppe_rhs(n, rows, cols, cx, cy, nf, ei, ej, ea, stab, unknown, unk.size, p, b)
            p[unk] = solve_free(op, rhs, guess[unk], _csr_builder(n, rows, cols, cx, cy, nf, ei, ej, ea, stab,
                                                                   unknown, unk.size, p.copy(), b))
        else:
            indptr, indices, data, rhs = assemble_adjoint_ppe(n, rows, cols, cx, cy, nf, ei, ej, ea, stab, unknown,
                                                              unk.size, p, b)
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


@njit(cache=True)
def coo_to_csr(rows, n):
    """Row pointers and the permutation that sorts COO entries by row (stable counting sort)."""
    ptr = np.zeros(n + 1, np.int64)
    for r in rows:
        ptr[r + 1] += 1
    for r in range(n):
        ptr[r + 1] += ptr[r]
    fill = ptr[:-1].copy()
    perm = np.empty(rows.size, np.int64)
    for q in range(rows.size):
        r = rows[q]
        perm[fill[r]] = q
        fill[r] += 1
    return ptr, perm


@njit(cache=True)
def _gather_products(n, rows, cols, cx, cy, nf, ei, ej, ea):
    """D by node (rows) and by particle (columns), and L_c by node (both directions of each edge),
    as contiguous CSR-like arrays (column indices int32) for :func:`assemble_adjoint_ppe`."""
    rptr, rperm = coo_to_csr(rows, n)
    cptr, cperm = coo_to_csr(cols, nf)
    r_col = cols[rperm].astype(np.int32)
    r_x = cx[rperm]
    r_y = cy[rperm]
    c_row = rows[cperm].astype(np.int32)
    c_x = cx[cperm]
    c_y = cy[cperm]
    ne = ei.size
    lrows = np.empty(2 * ne, np.int64)
    lrows[:ne] = ei
    lrows[ne:] = ej
    lptr, lperm = coo_to_csr(lrows, n)
    l_col = np.empty(2 * ne, np.int32)
    l_val = np.empty(2 * ne)
    for q in range(2 * ne):
        e = lperm[q]
        if e < ne:
            l_col[q] = ej[e]
            l_val[q] = ea[e]
        else:
            l_col[q] = ei[e - ne]
            l_val[q] = ea[e - ne]
    return rptr, r_col, r_x, r_y, cptr, c_row, c_x, c_y, lptr, l_col, l_val


@njit(cache=True)
def _row_bounds(a0, a1, rptr, r_col, cptr, lptr, unknown):
    """Upper bounds of the entries of the unknown rows among nodes a0..a1−1: their total and the
    largest of one row."""
    total = 0
    largest = 0
    for a in range(a0, a1):
        if unknown[a] < 0:
            continue
        m = 1 + lptr[a + 1] - lptr[a]
        for q in range(rptr[a], rptr[a + 1]):
            i = r_col[q]
            m += cptr[i + 1] - cptr[i]
        total += m
        largest = max(largest, m)
    return total, largest


@njit(cache=True)
def _product_rows(a0, a1, g, wd, stab, unknown, p, b, slot, acc, lst, indices, data, rowlen, rhs):
    """Gustavson's row-by-row product for the unknown rows among nodes a0..a1−1, written from 0 into
    ``indices``/``data`` (diagonal first, then the columns in the order they are met); ``slot``
    (−1 on entry and on return) maps a node to its place in the row's accumulator ``acc``.
    Returns the number of entries written."""
    rptr, r_col, r_x, r_y, cptr, c_row, c_x, c_y, lptr, l_col, l_val = g
    pos = 0
    for a in range(a0, a1):
        ra = unknown[a]
        if ra < 0:
            continue
        m = 1
        slot[a] = 0
        lst[0] = a
        acc[0] = 0.0
        for q in range(rptr[a], rptr[a + 1]):
            i = r_col[q]
            ax = r_x[q]
            ay = r_y[q]
            for t in range(cptr[i], cptr[i + 1]):
                bn = c_row[t]
                s = slot[bn]
                if s < 0:
                    s = m
                    slot[bn] = m
                    lst[m] = bn
                    acc[m] = 0.0
                    m += 1
                acc[s] += wd * (ax * c_x[t] + ay * c_y[t])
        for q in range(lptr[a], lptr[a + 1]):
            bn = l_col[q]
            w = stab * l_val[q]
            s = slot[bn]
            if s < 0:
                s = m
                slot[bn] = m
                lst[m] = bn
                acc[m] = 0.0
                m += 1
            acc[s] -= w
            acc[0] += w
        start_pos = pos
        indices[pos] = ra
        data[pos] = acc[0]
        pos += 1
        ba = b[a]
        for t in range(1, m):
            bn = lst[t]
            rb = unknown[bn]
            if rb >= 0:
                indices[pos] = rb
                data[pos] = acc[t]
                pos += 1
            else:
                ba -= acc[t] * p[bn]
        rhs[ra] = ba
        rowlen[ra] = pos - start_pos
        for t in range(m):
            slot[lst[t]] = -1
    return pos


def assemble_adjoint_ppe(n, rows, cols, cx, cy, nf, ei, ej, ea, stab, unknown, n_unknown, p, b):
    """CSR (diagonal first) of ((1 − ε) D Dᵀ + ε L_c) restricted to the unknown nodes and its right-hand side
    b_U − A_UK p_K (Gustavson's row-by-row product, :func:`_product_rows`).

    ``rows, cols, cx, cy``: D in COO (:func:`divergence_entries`); ``ei, ej, ea``: the edges of L_c;
    ``unknown[node]``: the unknown's index or −1 (known, value ``p[node]``), the unknowns numbered in
    node order. The nodes are split into one contiguous block per numba thread (``prange``); each row
    is computed alone, in the same order whatever the blocks, so the result does not depend on the
    thread count (bit for bit)."""
    return _assemble_blocks(n, rows, cols, cx, cy, nf, ei, ej, ea, stab, unknown, n_unknown, p, b,
                            max(1, min(get_num_threads(), n)))


@prange_kernel
def _assemble_blocks(n, rows, cols, cx, cy, nf, ei, ej, ea, stab, unknown, n_unknown, p, b, nblock):
    """:func:`assemble_adjoint_ppe` over ``nblock`` contiguous blocks of nodes, one per ``prange`` iteration."""
    expect = 0
    for a in range(n):
        if unknown[a] >= 0:
            if unknown[a] != expect:
                raise ValueError("assemble_adjoint_ppe: unknowns must be numbered in node order")
            expect += 1
    g = _gather_products(n, rows, cols, cx, cy, nf, ei, ej, ea)
    rptr, r_col, cptr, lptr = g[0], g[1], g[4], g[8]
    wd = 1.0 - stab
    rowlen = np.zeros(n_unknown, np.int64)
    rhs = np.zeros(n_unknown)
    edges = np.empty(nblock + 1, np.int64)
    for c in range(nblock + 1):
        edges[c] = (n * c) // nblock
    counts = np.zeros(nblock, np.int64)
    block_indices = [np.empty(0, np.int32) for _ in range(nblock)]
    block_data = [np.empty(0) for _ in range(nblock)]
    for c in prange(nblock):
        total, largest = _row_bounds(edges[c], edges[c + 1], rptr, r_col, cptr, lptr, unknown)
        ind = np.empty(total, np.int32)
        dat = np.empty(total)
        slot = np.full(n, -1, np.int32)
        acc = np.empty(largest)
        lst = np.empty(largest, np.int32)
        counts[c] = _product_rows(edges[c], edges[c + 1], g, wd, stab, unknown, p, b, slot, acc, lst, ind, dat,
                                  rowlen, rhs)
        block_indices[c] = ind
        block_data[c] = dat
    indptr = np.zeros(n_unknown + 1, np.int64)
    for r in range(n_unknown):
        indptr[r + 1] = indptr[r] + rowlen[r]
    # the blocks hold consecutive rows in node order, which is the unknown order
    indices = np.empty(indptr[n_unknown], np.int64)
    data = np.empty(indptr[n_unknown])
    off = 0
    for c in range(nblock):
        e = counts[c]
        indices[off:off + e] = block_indices[c][:e]
        data[off:off + e] = block_data[c][:e]
        off += e
    return indptr, indices, data, rhs


@njit(cache=True)
def apply_divergence(n, rows, cols, cx, cy, u, v):
    """D u at every node from the COO entries."""
    out = np.zeros(n)
    for q in range(rows.size):
        out[rows[q]] += cx[q] * u[cols[q]] + cy[q] * v[cols[q]]
    return out


@njit(cache=True)
def apply_gradient(nf, rows, cols, cx, cy, p):
    """G p = −Dᵀ p on the granular particles."""
    gx = np.zeros(nf)
    gy = np.zeros(nf)
    for q in range(rows.size):
        c = cols[q]
        pr = p[rows[q]]
        gx[c] -= cx[q] * pr
        gy[c] -= cy[q] * pr
    return gx, gy


@njit(cache=True)
def wall_normal_acceleration(pairs, nf, vol, lmat, walls, p, rho, planes):
    """Acceleration of each granular particle along each wall plane's normal that the walls' pressure
    terms of G p = −Dᵀ p apply (the wall reaction of the adjoint-pair projection):

        a_n,iq = −(1/ρ) Σ_{w ∈ plane q} V g_iw [p_i n·(L_i r_iw) + p_w n·r_iw]

    (``p``: node pressures, granular then wall). Summed over the particles it is the wall's normal
    reaction, whatever the resolution; the Coulomb friction of ``wall.coulomb_normal: projection``
    is μ_B times it."""
    start, nbr, rx, ry, gw = pairs.start, pairs.nbr, pairs.rx, pairs.ry, pairs.gw
    wnx, wny = walls.nx, walls.ny
    npl = planes.shape[0]
    out = np.zeros((nf, npl))
    for i in range(nf):
        l0 = lmat[i, 0]
        l1 = lmat[i, 1]
        l2 = lmat[i, 2]
        l3 = lmat[i, 3]
        for q in range(start[i], start[i + 1]):
            j = nbr[q]
            if j < nf:
                continue
            w = j - nf
            nx = wnx[w]
            ny = wny[w]
            x = rx[q]
            y = ry[q]
            g = vol * gw[q]
            an = nx * (l0 * x + l1 * y) + ny * (l2 * x + l3 * y)
            f = -g * (p[i] * an + p[j] * (nx * x + ny * y)) / rho
            for k in range(npl):
                if abs(planes[k, 0] - nx) < 1e-9 and abs(planes[k, 1] - ny) < 1e-9:
                    out[i, k] += f
                    break
    return out


# ------------------------------------------------------------------------------------------------
# Matrix-free PPE (``numerics.ppe_operator: matrix_free``): the assembled product D Dᵀ has
# ~63 entries per row and its Gustavson assembly cost as much as ~40 products with it (T22-A150,
# 3750 particles). Applied as D_U (D_Uᵀ x) + ε L_c x it is the same matrix (the same sums in another
# order: products agree to ~1e-15 relative, tests/isph/test_ppe_free.py) from ~19 D entries and ~18
# L_c entries per row, built in one counting-sort pass.
# ------------------------------------------------------------------------------------------------


@njit(cache=True, nogil=True)
def matrix_free_operator(n, rows, cols, cx, cy, nf, ei, ej, ea, stab, unknown, n_unknown):
    """The operator ((1 − ε) D Dᵀ + ε L_c) restricted to the unknown nodes, unassembled (the matrix
    of :func:`assemble_adjoint_ppe`; its right-hand side is :func:`ppe_rhs`'s).

    Returns op = (wd, rptr, rcol, rx, ry, cptr, crow, ccx, ccy, lptr, lcol, lval): D_U by
    unknown row (columns: particles) and by particle (rows: unknown indices), both CSR, wd = 1 − ε;
    ε L_c restricted to the unknowns by row with its diagonal first (``lval`` holds ε a_e; the
    diagonal sums the edges to known nodes too). See :func:`linsolve.free_matvec`."""
    wd = 1.0 - stab
    # D_U by unknown row and by particle
    rptr = np.zeros(n_unknown + 1, np.int64)
    cptr = np.zeros(nf + 1, np.int64)
    for q in range(rows.size):
        r = unknown[rows[q]]
        if r >= 0:
            rptr[r + 1] += 1
            cptr[cols[q] + 1] += 1
    for r in range(n_unknown):
        rptr[r + 1] += rptr[r]
    for i in range(nf):
        cptr[i + 1] += cptr[i]
    m = rptr[n_unknown]
    rcol = np.empty(m, np.int32)
    rx = np.empty(m)
    ry = np.empty(m)
    crow = np.empty(m, np.int32)
    ccx = np.empty(m)
    ccy = np.empty(m)
    rf = rptr[:-1].copy()
    cf = cptr[:-1].copy()
    for q in range(rows.size):
        r = unknown[rows[q]]
        if r >= 0:
            k = rf[r]
            rcol[k] = cols[q]
            rx[k] = cx[q]
            ry[k] = cy[q]
            rf[r] += 1
            i = cols[q]
            k = cf[i]
            crow[k] = r
            ccx[k] = cx[q]
            ccy[k] = cy[q]
            cf[i] += 1
    # ε L_c on the unknowns: diagonal first, then the unknown neighbours
    lptr = np.zeros(n_unknown + 1, np.int64)
    for e in range(ei.size):
        a = unknown[ei[e]]
        c = unknown[ej[e]]
        if a >= 0 and c >= 0:
            lptr[a + 1] += 1
            lptr[c + 1] += 1
    for r in range(n_unknown):
        lptr[r + 1] += lptr[r] + 1
    lcol = np.empty(lptr[n_unknown], np.int32)
    lval = np.zeros(lptr[n_unknown])
    lf = lptr[:-1] + 1
    for r in range(n_unknown):
        lcol[lptr[r]] = r
    for e in range(ei.size):
        a = unknown[ei[e]]
        c = unknown[ej[e]]
        w = stab * ea[e]
        if a >= 0:
            lval[lptr[a]] += w
            if c >= 0:
                lcol[lf[a]] = c
                lval[lf[a]] = -w
                lf[a] += 1
        if c >= 0:
            lval[lptr[c]] += w
            if a >= 0:
                lcol[lf[c]] = a
                lval[lf[c]] = -w
                lf[c] += 1
    return (wd, rptr, rcol, rx, ry, cptr, crow, ccx, ccy, lptr, lcol, lval)


@njit(cache=True)
def matrix_free_ppe(n, rows, cols, cx, cy, nf, ei, ej, ea, stab, unknown, n_unknown, p, b):
    """(op, rhs): :func:`matrix_free_operator` and :func:`ppe_rhs` (the same system as
    :func:`assemble_adjoint_ppe`)."""
    return (matrix_free_operator(n, rows, cols, cx, cy, nf, ei, ej, ea, stab, unknown, n_unknown),
            ppe_rhs(n, rows, cols, cx, cy, nf, ei, ej, ea, stab, unknown, n_unknown, p, b))


@njit(cache=True)
def assemble_adjoint_triangles(n, rows, cols, cx, cy, nf, ei, ej, ea, stab, unknown, n_unknown, p, b):
    """(triangles, rhs): :func:`adjoint_triangles` and :func:`ppe_rhs`."""
    return (adjoint_triangles(n, rows, cols, cx, cy, nf, ei, ej, ea, stab, unknown, n_unknown),
            ppe_rhs(n, rows, cols, cx, cy, nf, ei, ej, ea, stab, unknown, n_unknown, p, b))


@njit(cache=True, nogil=True)
def adjoint_triangles(n, rows, cols, cx, cy, nf, ei, ej, ea, stab, unknown, n_unknown):
    """The matrix of :func:`assemble_adjoint_ppe` as its strict lower and upper triangles and its
    diagonal, in :func:`linsolve.split_triangles`' layout (uint64 row pointers, uint32 columns, the
    lower rows by ascending and the upper rows by descending column); for the SSOR-preconditioned
    CG (``numerics.pressure_solver: cg_ssor``, :func:`linsolve.pcg_dic_split`). It does not depend on
    the right-hand side, so it can be built before u* is known (:func:`adjoint_pair_geometry`).

    Only the upper triangle is computed (the product is symmetric): row a takes, for each particle
    i of its D_U row, the nodes b > a of column i (the columns sorted by node, each entered at a head that
    only moves forward as a grows),
    plus its L_c entries b > a; the lower triangle is its transpose. Half the multiply-adds of the
    row-by-row product and no CSR to split. Returns (lp, li, lv, up, ui, uv, diag)."""
    op = matrix_free_operator(n, rows, cols, cx, cy, nf, ei, ej, ea, stab, unknown, n_unknown)
    wd, rptr, rcol, rx, ry, cptr, crow, ccx, ccy, lptr, lcol, lval = op
    m = n_unknown
    # each column by ascending node (insertion sort: the columns come nearly sorted)
    for i in range(nf):
        c0 = cptr[i]
        for t in range(c0 + 1, cptr[i + 1]):
            r = crow[t]
            vx = ccx[t]
            vy = ccy[t]
            u = t
            while u > c0 and crow[u - 1] > r:
                crow[u] = crow[u - 1]
                ccx[u] = ccx[u - 1]
                ccy[u] = ccy[u - 1]
                u -= 1
            crow[u] = r
            ccx[u] = vx
            ccy[u] = vy
    diag = np.empty(m)
    up = np.zeros(m + 1, np.int64)
    # a dense accumulator over the unknowns, zero between rows, and the row's distinct columns
    # listed without a branch (``mark[c] == a`` once c is listed for row a): one dependent load per
    # multiply-add instead of the slot map's two, no unpredictable first-visit branch
    mark = np.full(m, -1, np.int64)
    acc = np.zeros(m)
    # the part of column i below the diagonal of row a starts at head[i]: rows ascend, so the head
    # only moves forward (instead of scanning each column from its end)
    head = cptr[:-1].copy()
    # bounds: a row meets at most the entries of its particles' columns and its L_c row
    total = 0
    cap = 1
    for a in range(m):
        e = lptr[a + 1] - lptr[a]
        for k in range(rptr[a], rptr[a + 1]):
            e += cptr[rcol[k] + 1] - cptr[rcol[k]]
        total += e
        cap = max(cap, e)
    lst = np.empty(cap + 1, np.int32)
    ui = np.empty(max(1, total // 2 + m), np.uint32)
    uv = np.empty(ui.size)
    pos = 0
    for a in range(m):
        cnt = 0
        d = 0.0
        for k in range(rptr[a], rptr[a + 1]):
            i = rcol[k]
            ax = rx[k]
            ay = ry[k]
            d += ax * ax + ay * ay
            t0 = head[i]
            t1 = cptr[i + 1]
            while t0 < t1 and crow[t0] <= a:
                t0 += 1
            head[i] = t0
            for t in range(t0, t1):
                c = crow[t]
                lst[cnt] = c
                cnt += mark[c] != a
                mark[c] = a
                acc[c] += wd * (ax * ccx[t] + ay * ccy[t])
        diag[a] = wd * d + lval[lptr[a]]
        for k in range(lptr[a] + 1, lptr[a + 1]):
            c = lcol[k]
            if c > a:
                lst[cnt] = c
                cnt += mark[c] != a
                mark[c] = a
                acc[c] += lval[k]
        for t in range(cnt):            # in the order met (sorted by the transpositions below)
            c = lst[t]
            ui[pos + t] = c
            uv[pos + t] = acc[c]
            acc[c] = 0.0
        pos += cnt
        up[a + 1] = pos
    # the lower triangle: the transpose (rows visited in ascending order: each lower row by ascending
    # column); then the upper one again as the transpose of the lower, its rows visited in descending
    # order (each upper row by descending column). Two counting sorts instead of sorting every row.
    lp = np.zeros(m + 1, np.int64)
    for k in range(pos):
        lp[ui[k] + 1] += 1
    for a in range(m):
        lp[a + 1] += lp[a]
    li = np.empty(pos, np.uint32)
    lv = np.empty(pos)
    fill = lp[:-1].copy()
    for a in range(m):
        for k in range(up[a], up[a + 1]):
            c = ui[k]
            li[fill[c]] = a
            lv[fill[c]] = uv[k]
            fill[c] += 1
    fill[:] = up[:-1]
    for c in range(m - 1, -1, -1):
        for k in range(lp[c], lp[c + 1]):
            a = li[k]
            ui[fill[a]] = c
            uv[fill[a]] = lv[k]
            fill[a] += 1
    return lp.astype(np.uint64), li, lv, up.astype(np.uint64), ui[:pos], uv[:pos], diag
