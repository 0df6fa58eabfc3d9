"""Two-level CG: Jacobi plus an aggregation coarse space, on a CSR matrix (``cg_two_level``) or on
the matrix-free adjoint-pair PPE operator; the coarse correction and the CG loop it runs in are in
:mod:`.linsolve`."""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from .linsolve import BREAKDOWN, NONFINITE, _any_nonzero, _diag_first, _dot, _pcg_loop, _start, stop_threshold
# ------------------------------------------------------------------------------------------------
# Two-level CG: Jacobi plus an aggregation coarse space (``numerics.pressure_solver: cg_two_level``;
# the adjoint-pair PPE's solver, where incomplete Cholesky breaks down)
#
# M⁻¹ r = D⁻¹ r + P A_c⁻¹ Pᵀ r,  A_c = Pᵀ A P,  P the piecewise-constant prolongation of aggregates
# of the matrix graph (each root takes its whole row: ~65 nodes for the 2-ring adjoint-pair operator).
# The additive form is symmetric positive definite for any SPD A (A_c = PᵀAP is SPD for a P of full
# column rank), so plain CG applies. Jacobi alone leaves the smooth modes, whose number grows as
# 1/dx (T22-A70, adjoint-pair PPE: 79 / 143 / 184 iterations at 4 / 2 / 1.4 mm); the coarse space
# removes them: 54 / 52 / 54 iterations, 16.7 → 12.5, 82 → 38, 330 → 134 ms per solve (one core).
# ------------------------------------------------------------------------------------------------


@njit(cache=True)
def aggregate_rows(pa, ia, va, pb, ib, vb):
    """Aggregates of the matrix graph (standard aggregation, strength threshold 0), each row i given
    as the entries pa[i]:pa[i+1] of (ia, va) followed by pb[i]:pb[i+1] of (ib, vb): a CSR matrix
    (second part empty, :func:`aggregate_nodes`) or the two triangles of :func:`split_triangles`
    (the deflated SSOR-CG, :mod:`.deflation`). Pass 1 makes each node whose neighbourhood is still
    free the root of an aggregate holding its whole row; pass 2 joins each remaining node to the
    pass-1 aggregate it is most strongly coupled to; pass 3 makes new aggregates of what is left.
    Returns (aggregate of each node, number of aggregates)."""
    n = pa.size - 1
    agg = np.full(n, -1, np.int64)
    nc = 0
    for i in range(n):
        if agg[i] >= 0:
            continue
        free = True
        for q in range(pa[i], pa[i + 1]):
            if agg[ia[q]] >= 0:
                free = False
                break
        if free:
            for q in range(pb[i], pb[i + 1]):
                if agg[ib[q]] >= 0:
                    free = False
                    break
        if not free:
            continue
        for q in range(pa[i], pa[i + 1]):
            agg[ia[q]] = nc
        for q in range(pb[i], pb[i + 1]):
            agg[ib[q]] = nc
        agg[i] = nc
        nc += 1
    first = agg.copy()
    for i in range(n):
        if first[i] >= 0:
            continue
        best = -1
        strongest = 0.0
        for q in range(pa[i], pa[i + 1]):
            j = ia[q]
            if j != i and first[j] >= 0 and abs(va[q]) > strongest:
                strongest = abs(va[q])
                best = first[j]
        for q in range(pb[i], pb[i + 1]):
            j = ib[q]
            if j != i and first[j] >= 0 and abs(vb[q]) > strongest:
                strongest = abs(vb[q])
                best = first[j]
        agg[i] = best
    for i in range(n):
        if agg[i] < 0:
            agg[i] = nc
            for q in range(pa[i], pa[i + 1]):
                if agg[ia[q]] < 0:
                    agg[ia[q]] = nc
            for q in range(pb[i], pb[i + 1]):
                if agg[ib[q]] < 0:
                    agg[ib[q]] = nc
            nc += 1
    return agg, nc


@njit(cache=True)
def aggregate_nodes(indptr, indices, data):
    """:func:`aggregate_rows` of a CSR matrix."""
    return aggregate_rows(indptr, indices, data, np.zeros(indptr.size, np.int64), indices[:0], data[:0])


@njit(cache=True)
def coarse_matrix(indptr, indices, data, agg, nc):
    """A_c = Pᵀ A P (dense) for the piecewise-constant prolongation of the aggregates ``agg``."""
    ac = np.zeros((nc, nc))
    for i in range(indptr.size - 1):
        ai = agg[i]
        for q in range(indptr[i], indptr[i + 1]):
            ac[ai, agg[indices[q]]] += data[q]
    return ac


@njit(cache=True)
def coarse_factor(ac):
    """Cholesky factor L of A_c and Lᵀ (both C-ordered, rows contiguous for :func:`coarse_solve`),
    and whether A_c is positive definite (a non-positive or NaN diagonal or pivot: not; reported,
    never raised)."""
    nc = ac.shape[0]
    for i in range(nc):                  # Cholesky needs a positive diagonal at least
        if not ac[i, i] > 0.0:
            return ac, ac, False
    try:
        lc = np.linalg.cholesky(ac)      # LAPACK potrf; raises on a non-positive pivot
    except Exception:                    # noqa: BLE001 (numba catches no narrower class)
        return ac, ac, False
    for i in range(nc):
        if not lc[i, i] > 0.0:           # NaN pivots
            return lc, lc, False
    return lc, np.ascontiguousarray(lc.T), True


def pcg_two_level(indptr, indices, data, b, x0, rtol, atol, maxiter):
    """Solve A x = b (SPD, CSR, diagonal first) by CG preconditioned with Jacobi plus the
    aggregation coarse space above (set up from A on every call). Same stopping test, return
    convention and breakdown checks as :func:`pcg_jacobi`; a coarse matrix that is not positive
    definite (A not SPD) returns ``BREAKDOWN``. Dot products through :func:`_dot`."""
    x, r, dinv, thresh, zero, status = _start(indptr, indices, data, _diag_first(indptr, indices, data), b, x0,
                                              rtol, atol)
    if zero:
        return x, 0, 0
    if status != 0:
        return x, 0, status
    agg, lc, lct, ok = _two_level_setup(indptr, indices, data)
    if not ok:
        return x, 0, BREAKDOWN
    return _pcg_loop((indptr, indices, data), None, x, r, dinv, thresh, maxiter, (lc, lct, agg), False)


@njit(cache=True)
def _two_level_setup(indptr, indices, data):
    """The aggregates, the Cholesky factor L of A_c and Lᵀ (C-ordered), and whether A_c is positive
    definite (a non-positive diagonal or pivot, or NaN: not)."""
    agg, nc = aggregate_nodes(indptr, indices, data)
    lc, lct, ok = coarse_factor(coarse_matrix(indptr, indices, data, agg, nc))
    return agg, lc, lct, ok


# ------------------------------------------------------------------------------------------------
# Two-level CG on the matrix-free adjoint-pair PPE (``numerics.ppe_operator: matrix_free``)
#
# The operator is :func:`ppe_operator.matrix_free_ppe`'s op = (wd, D_U by row, D_U by particle, ε L_c);
# A x = wd D_U (D_Uᵀ x) + ε L_c x, both products as gathers (D_Uᵀ x by particle, then D_U by row),
# each output entry written by one prange iteration (no reductions: the same iterates on any number
# of threads). The preconditioner is the additive two-level one of :func:`pcg_two_level` (Jacobi +
# P A_c⁻¹ Pᵀ, exact A_c = Pᵀ A P) with the aggregates taken on the graph of L_c (one ring: ~19
# nodes per aggregate) instead of that of A (two rings: ~70), and, above FREE_COARSE_MAX aggregates,
# those aggregated again on their own graph. On T22-A150 at 4 mm, cold start: 57 iterations with
# either aggregation (the A-graph one: 57), 63 with the second stage.
# ------------------------------------------------------------------------------------------------

FREE_COARSE_MAX = 200


@njit(cache=True)
def free_diagonal(op):
    """diag(A) of the matrix-free operator."""
    wd, rptr, rcol, rx, ry, cptr, crow, ccx, ccy, lptr, lcol, lval = op
    m = rptr.size - 1
    d = np.empty(m)
    for r in range(m):
        s = 0.0
        for k in range(rptr[r], rptr[r + 1]):
            s += rx[k] * rx[k] + ry[k] * ry[k]
        d[r] = wd * s + lval[lptr[r]]
    return d


@njit(cache=True)
def free_matvec(op, x, gx, gy, out):
    """out = A x for the matrix-free operator (gx, gy: work arrays, one entry per particle)."""
    wd, rptr, rcol, rx, ry, cptr, crow, ccx, ccy, lptr, lcol, lval = op
    for i in range(cptr.size - 1):
        sx = 0.0
        sy = 0.0
        for k in range(cptr[i], cptr[i + 1]):
            xr = x[crow[k]]
            sx += ccx[k] * xr
            sy += ccy[k] * xr
        gx[i] = sx
        gy[i] = sy
    for r in range(rptr.size - 1):
        s = 0.0
        for k in range(rptr[r], rptr[r + 1]):
            c = rcol[k]
            s += rx[k] * gx[c] + ry[k] * gy[c]
        t = 0.0
        for k in range(lptr[r], lptr[r + 1]):
            t += lval[k] * x[lcol[k]]
        out[r] = wd * s + t


@njit(cache=True)
def _coarse_graph(lptr, lcol, lval, agg, nc):
    """CSR (diagonal first) of Pᵀ |L| P: the graph of the aggregates, for a second aggregation."""
    m = lptr.size - 1
    mptr = np.zeros(nc + 1, np.int64)
    for i in range(m):
        mptr[agg[i] + 1] += 1
    for g in range(nc):
        mptr[g + 1] += mptr[g]
    mem = np.empty(m, np.int64)
    fill = mptr[:-1].copy()
    for i in range(m):
        mem[fill[agg[i]]] = i
        fill[agg[i]] += 1
    slot = np.full(nc, -1, np.int64)
    lst = np.empty(nc, np.int64)
    acc = np.empty(nc)
    indptr = np.zeros(nc + 1, np.int64)
    ind = []
    dat = []
    for g in range(nc):
        cnt = 1
        slot[g] = 0
        lst[0] = g
        acc[0] = 0.0
        for t in range(mptr[g], mptr[g + 1]):
            a = mem[t]
            for k in range(lptr[a], lptr[a + 1]):
                h = agg[lcol[k]]
                s = slot[h]
                if s < 0:
                    s = cnt
                    slot[h] = cnt
                    lst[cnt] = h
                    acc[cnt] = 0.0
                    cnt += 1
                acc[s] += abs(lval[k])
        for t in range(cnt):
            ind.append(lst[t])
            dat.append(acc[t])
            slot[lst[t]] = -1
        indptr[g + 1] = indptr[g] + cnt
    return indptr, np.array(ind, dtype=np.int64), np.array(dat)


@njit(cache=True)
def free_aggregates(op, coarse_max):
    """Aggregates of the unknowns on the graph of L_c (:func:`aggregate_nodes`), aggregated once
    more on their own graph when there are more than ``coarse_max``. Returns (agg, nc)."""
    lptr, lcol, lval = op[9], op[10], op[11]
    agg, nc = aggregate_nodes(lptr, lcol, lval)
    if nc > coarse_max:
        gp, gi, gd = _coarse_graph(lptr, lcol, lval, agg, nc)
        agg2, nc2 = aggregate_nodes(gp, gi, gd)
        for i in range(agg.size):
            agg[i] = agg2[agg[i]]
        nc = nc2
    return agg, nc


@njit(cache=True)
def free_coarse_matrix(op, agg, nc):
    """A_c = Pᵀ A P (dense) of the matrix-free operator: wd (PᵀD_U)(PᵀD_U)ᵀ by particle (each
    column of D_U summed per aggregate, then its outer product) plus Pᵀ (ε L_c) P."""
    wd, rptr, rcol, rx, ry, cptr, crow, ccx, ccy, lptr, lcol, lval = op
    ac = np.zeros((nc, nc))
    for r in range(lptr.size - 1):
        ar = agg[r]
        for k in range(lptr[r], lptr[r + 1]):
            ac[ar, agg[lcol[k]]] += lval[k]
    width = 0
    for i in range(cptr.size - 1):
        width = max(width, cptr[i + 1] - cptr[i])
    gl = np.empty(width, np.int64)
    sx = np.empty(width)
    sy = np.empty(width)
    for i in range(cptr.size - 1):
        cnt = 0
        for k in range(cptr[i], cptr[i + 1]):
            g = agg[crow[k]]
            s = -1
            for t in range(cnt):
                if gl[t] == g:
                    s = t
                    break
            if s < 0:
                s = cnt
                gl[cnt] = g
                sx[cnt] = 0.0
                sy[cnt] = 0.0
                cnt += 1
            sx[s] += ccx[k]
            sy[s] += ccy[k]
        for s in range(cnt):
            for t in range(cnt):
                ac[gl[s], gl[t]] += wd * (sx[s] * sx[t] + sy[s] * sy[t])
    return ac


@njit(cache=True)
def _free_setup(op, coarse_max):
    """dinv, aggregates, the Cholesky factor of A_c and its transpose, and a status (0, or
    ``BREAKDOWN`` for a non-positive diagonal or a coarse matrix not positive definite)."""
    d = free_diagonal(op)
    m = d.size
    dinv = np.empty(m)
    for i in range(m):
        if not d[i] > 0.0:
            return dinv, np.zeros(m, np.int64), np.empty((0, 0)), np.empty((0, 0)), BREAKDOWN
        dinv[i] = 1.0 / d[i]
    agg, nc = free_aggregates(op, coarse_max)
    lc, lct, ok = coarse_factor(free_coarse_matrix(op, agg, nc))
    return dinv, agg, lc, lct, 0 if ok else BREAKDOWN


def pcg_two_level_free(op, b, x0, rtol, atol, maxiter, coarse_max=FREE_COARSE_MAX):
    """Solve A x = b for the matrix-free PPE operator ``op`` (:func:`ppe_operator.matrix_free_ppe`)
    by the two-level CG above, warm-started from x0. Same stopping test (‖r‖ < max(rtol ‖b‖, atol),
    recursive residual), return convention and breakdown codes as :func:`pcg_two_level`."""
    n = b.size
    bnrm2 = math.sqrt(_dot(b, b))
    if bnrm2 == 0.0:
        return b.copy(), 0, 0
    x = np.array(x0, dtype=np.float64)
    if not math.isfinite(bnrm2):
        return x, 0, NONFINITE
    thresh = stop_threshold(bnrm2, rtol, atol)
    r = b.copy()
    if _any_nonzero(x):
        ax = np.empty(n)
        free_matvec(op, x, np.empty(op[5].size - 1), np.empty(op[5].size - 1), ax)
        r -= ax
    dinv, agg, lc, lct, status = _free_setup(op, coarse_max)
    if status != 0:
        return x, 0, status
    no_csr = (np.zeros(1, np.int64), np.zeros(0, np.int64), np.zeros(0))   # not read: A is ``op``
    return _pcg_loop(no_csr, op, x, r, dinv, thresh, maxiter, (lc, lct, agg), False)
