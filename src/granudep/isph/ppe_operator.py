"""The PPE operator of the adjoint-pair projection, ((1 − ε) D Dᵀ + ε L_c) p = rhs over the granular
and the wetted wall nodes (:mod:`.projection` builds D and L_c): its right-hand side
(:func:`ppe_rhs`), and the operator in each form a linear solver takes: assembled as CSR
(:func:`assemble_adjoint_ppe`), as its triangles (:func:`assemble_adjoint_triangles`) or applied
without a matrix (:func:`matrix_free_ppe`); plus the divergence D, the gradient G = −Dᵀ and the
walls' normal reaction they imply.
"""
from __future__ import annotations

import numpy as np
from numba import get_num_threads, njit, prange

from typing import NamedTuple

from .parallel import prange_kernel


class PPESystem(NamedTuple):
    """What every form of the adjoint-pair PPE is built from (:mod:`.projection` makes it): the
    divergence D as COO entries (node row, particle column, x and y coefficients) over the n nodes
    (nf particles, then wall nodes), the edges of the stabilising Laplacian L_c (ei, ej, weight ea),
    its weight ε, and the unknowns' numbering (``unknown[node]``, −1 for a known node)."""
    n: int
    rows: np.ndarray
    cols: np.ndarray
    cx: np.ndarray
    cy: np.ndarray
    nf: int
    ei: np.ndarray
    ej: np.ndarray
    ea: np.ndarray
    stab: float
    unknown: np.ndarray
    n_unknown: int


@njit(cache=True, nogil=True)
def ppe_rhs(system, p, b):
    """The right-hand side of the PPE on the unknowns, b_U − (1 − ε) D_U (D_Kᵀ p_K) − ε (L_c p_K)_U,
    for the matrix-free operator and the triangles (each row's D_U sum in D's COO order)."""
    n, rows, cols, cx, cy, nf, ei, ej, ea, stab, unknown, n_unknown = system
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
def _product_rows(a0, a1, g, wd, stab, unknown, p, b, work, out):
    """Gustavson's row-by-row product for the unknown rows among nodes a0..a1−1, written from 0 into
    out = (indices, data, rowlen, rhs) (diagonal first, then the columns in the order they are met);
    work = (slot, acc, lst): ``slot`` (−1 on entry and on return) maps a node to its place in the
    row's accumulator ``acc``, ``lst`` lists the row's nodes. Returns the number of entries written."""
    slot, acc, lst = work
    indices, data, rowlen, rhs = out
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


def assemble_adjoint_ppe(system, p, b):
    """CSR (diagonal first) of ((1 − ε) D Dᵀ + ε L_c) restricted to the unknown nodes and its right-hand side
    b_U − A_UK p_K (Gustavson's row-by-row product, :func:`_product_rows`).

    ``system`` (:class:`PPESystem`): D in COO (:func:`divergence_entries`), the edges of L_c and
    ``unknown[node]``, the unknown's index or −1 (known, value ``p[node]``), the unknowns numbered in
    node order. The nodes are split into one contiguous block per numba thread (``prange``); each row
    is computed alone, in the same order whatever the blocks, so the result does not depend on the
    thread count (bit for bit)."""
    return _assemble_blocks(system, p, b, max(1, min(get_num_threads(), system.n)))


@prange_kernel
def _assemble_blocks(system, p, b, nblock):
    """:func:`assemble_adjoint_ppe` over ``nblock`` contiguous blocks of nodes, one per ``prange`` iteration."""
    n, rows, cols, cx, cy, nf, ei, ej, ea, stab, unknown, n_unknown = system
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
        counts[c] = _product_rows(edges[c], edges[c + 1], g, wd, stab, unknown, p, b, (slot, acc, lst),
                                  (ind, dat, rowlen, rhs))
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
def matrix_free_operator(system):
    """The operator ((1 − ε) D Dᵀ + ε L_c) restricted to the unknown nodes, unassembled (the matrix
    of :func:`assemble_adjoint_ppe`; its right-hand side is :func:`ppe_rhs`'s).

    Returns op = (wd, rptr, rcol, rx, ry, cptr, crow, ccx, ccy, lptr, lcol, lval): D_U by
    unknown row (columns: particles) and by particle (rows: unknown indices), both CSR, wd = 1 − ε;
    ε L_c restricted to the unknowns by row with its diagonal first (``lval`` holds ε a_e; the
    diagonal sums the edges to known nodes too). See :func:`cg_two_level.free_matvec`."""
    n, rows, cols, cx, cy, nf, ei, ej, ea, stab, unknown, n_unknown = system
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
def matrix_free_ppe(system, p, b):
    """(op, rhs): :func:`matrix_free_operator` and :func:`ppe_rhs` (the same system as
    :func:`assemble_adjoint_ppe`)."""
    return (matrix_free_operator(system),
            ppe_rhs(system, p, b))


@njit(cache=True)
def assemble_adjoint_triangles(system, p, b):
    """(triangles, rhs): :func:`adjoint_triangles` and :func:`ppe_rhs`."""
    return (adjoint_triangles(system),
            ppe_rhs(system, p, b))


@njit(cache=True, nogil=True)
def adjoint_triangles(system):
    """The matrix of :func:`assemble_adjoint_ppe` as its strict lower and upper triangles and its
    diagonal, in :func:`cg_dic.split_triangles`' layout (uint64 row pointers, uint32 columns, the
    lower rows by ascending and the upper rows by descending column); for the SSOR-preconditioned
    CG (``numerics.pressure_solver: cg_ssor``, :func:`cg_dic.pcg_dic_split`). It does not depend on
    the right-hand side, so it can be built before u* is known (:func:`adjoint_pair_geometry`).

    Only the upper triangle is computed (the product is symmetric): row a takes, for each particle
    i of its D_U row, the nodes b > a of column i (the columns sorted by node, each entered at a head that
    only moves forward as a grows),
    plus its L_c entries b > a; the lower triangle is its transpose. Half the multiply-adds of the
    row-by-row product and no CSR to split. Returns (lp, li, lv, up, ui, uv, diag)."""
    n, rows, cols, cx, cy, nf, ei, ej, ea, stab, unknown, n_unknown = system
    op = matrix_free_operator(system)
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
