"""CG preconditioned with the diagonal incomplete Cholesky factorisation (``cg_dic``) or SSOR, with
Eisenstat's trick: one forward and one backward sweep per iteration, for one system, for the u and v
viscous systems in lock-step, or on the split triangles of a matrix assembled that way. The shared
pieces (dot products, the start of a recurrence, the stopping test) are in :mod:`.linsolve`."""
from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from .linsolve import (BREAKDOWN, NONFINITE, _any_nonzero, _dot, cg_advance, converged, csr_matvec,
                       search_direction, stop_threshold)
from .parallel import prange_kernel
# ------------------------------------------------------------------------------------------------
# CG preconditioned with the diagonal incomplete Cholesky factorisation (DIC), Eisenstat's trick
#
# A = L + D + Lᵀ; W = D̃ + L with D̃ chosen so that diag(W D̃⁻¹ Wᵀ) = diag(A):
# d̃_i = a_ii − Σ_{k<i} a_ik² / d̃_k (no fill-in: only the diagonal changes). M = W D̃⁻¹ Wᵀ.
# PCG on A with M equals CG on Â = W⁻¹ A W⁻ᵀ with the preconditioner D̃ (Â ≈ D̃⁻¹), and
# Â p = t + W⁻¹(p + K t), t = W⁻ᵀ p, K = D − 2 D̃ (Eisenstat 1981): one forward and one backward
# sweep over the off-diagonal entries per iteration, the cost of one matrix-vector product.
# Stopping rule (at least as strict as scipy's): ‖b − A x‖₂ < max(rtol ‖b‖₂, atol) for the
# true residual of the returned x, checked whenever the transformed residual predicts it.
# ------------------------------------------------------------------------------------------------
@njit(cache=True)
def split_triangles(indptr, indices, data):
    """Strict lower and upper parts of a CSR matrix (own CSR arrays) and its diagonal.

    For the sweeps: the indices are unsigned (uint64 row pointers, uint32 columns: numba then
    drops the negative-index wraparound test of every access) and each row is sorted, the lower
    part by ascending and the upper part by descending column, so that the entry that the
    triangular sweep computed last (the nearest row) comes last in the row and the running sum
    waits for it only at its end. Both together: the Eisenstat product of the T22-A150 PPE
    57 -> 35 us."""
    n = indptr.size - 1
    lp = np.zeros(n + 1, np.int64)
    up = np.zeros(n + 1, np.int64)
    diag = np.zeros(n)
    for i in range(n):
        cl = 0
        cu = 0
        for k in range(indptr[i], indptr[i + 1]):
            j = indices[k]
            cl += j < i
            cu += j > i
        lp[i + 1] = lp[i] + cl
        up[i + 1] = up[i] + cu
    li = np.empty(lp[n], np.uint32)
    lv = np.empty(lp[n])
    ui = np.empty(up[n], np.uint32)
    uv = np.empty(up[n])
    for i in range(n):
        a0 = lp[i]
        a = a0
        b0 = up[i]
        b = b0
        for k in range(indptr[i], indptr[i + 1]):
            j = indices[k]
            v = data[k]
            if j < i:  # insertion sort (the rows come nearly sorted from the neighbour search)
                m = a
                while m > a0 and li[m - 1] > j:
                    li[m] = li[m - 1]
                    lv[m] = lv[m - 1]
                    m -= 1
                li[m] = j
                lv[m] = v
                a += 1
            elif j > i:  # ascending here, reversed below
                m = b
                while m > b0 and ui[m - 1] > j:
                    ui[m] = ui[m - 1]
                    uv[m] = uv[m - 1]
                    m -= 1
                ui[m] = j
                uv[m] = v
                b += 1
            else:
                diag[i] += v
        b -= 1
        while b0 < b:
            ui[b0], ui[b] = ui[b], ui[b0]
            uv[b0], uv[b] = uv[b], uv[b0]
            b0 += 1
            b -= 1
    return lp.astype(np.uint64), li, lv, up.astype(np.uint64), ui, uv, diag


@njit(cache=True)
def _split_residual(lp, li, lv, up, ui, uv, diag, b, x, r):
    """r = b − A x with A = L + diag + U given by :func:`split_triangles`; returns ‖r‖₂."""
    for i in range(b.size):
        acc = diag[i] * x[i]
        for k in range(lp[i], lp[i + 1]):
            acc += lv[k] * x[li[k]]
        for k in range(up[i], up[i + 1]):
            acc += uv[k] * x[ui[k]]
        r[i] = b[i] - acc
    return math.sqrt(_dot(r, r))


@njit(cache=True)
def dic_diagonal(lp, li, lv, diag):
    """d̃_i = a_ii − Σ_{k<i} a_ik² / d̃_k. Returns (d̃, i) with i the first row with a pivot that
    is not positive (the factorisation broke down: A not positive definite enough), else -1."""
    n = diag.size
    dt = np.empty(n)
    for i in range(n):
        s = diag[i]
        for k in range(lp[i], lp[i + 1]):
            s -= lv[k] * lv[k] / dt[li[k]]
        if not s > 0.0:
            return dt, i
        dt[i] = s
    return dt, -1


@njit(cache=True)
def mic_diagonal(lp, li, lv, up, uv, diag, alpha):
    """Modified incomplete Cholesky (MIC(0)) pivots with relaxation ``alpha``: besides the diagonal
    of M = W D̃⁻¹ Wᵀ, the fill-in that IC(0) drops is lumped onto it (a fraction alpha of it), so
    that the row sums of M match those of A for alpha = 1 (Gustafsson 1978):
    d̃_i = a_ii − Σ_{k<i} (a_ik/d̃_k) [(1 − alpha) a_ki + alpha Σ_{j>k} a_kj].
    alpha = 0 is :func:`dic_diagonal` (bit for bit: it is called). Safeguard (Bridson 2015): a pivot
    below a quarter of a_ii takes the plain DIC value of its row instead, which keeps M positive
    definite and well scaled near (almost) singular rows. Any positive d̃ gives an SPD M, so the
    CG converges to the same solution whatever alpha; alpha only moves the iteration count
    (T22-A150 PPE: 62 -> 30 iterations with alpha = 0.97). Returns (d̃, first breakdown row or -1)."""
    if alpha == 0.0:
        return dic_diagonal(lp, li, lv, diag)
    n = diag.size
    usum = np.empty(n)
    for k in range(n):
        acc = 0.0
        for m in range(up[k], up[k + 1]):
            acc += uv[m]
        usum[k] = acc
    dt = np.empty(n)
    for i in range(n):
        s = diag[i]
        sd = diag[i]
        for k in range(lp[i], lp[i + 1]):
            kk = li[k]
            a = lv[k]
            f = a / dt[kk]
            s -= f * ((1.0 - alpha) * a + alpha * usum[kk])
            sd -= f * a
        if not s >= 0.25 * diag[i]:
            s = sd
        if not s > 0.0:
            return dt, i
        dt[i] = s
    return dt, -1


@njit(cache=True)
def ssor_diagonal(diag, omega=1.0):
    """SSOR pivots (``mic = -omega < 0`` in :func:`pcg_dic`): d̃ = diag(A)/ω, M ∝ (D/ω + L) (D/ω)⁻¹
    (D/ω + U); ω = 1 is the symmetric Gauss-Seidel preconditioner. SPD for any SPD A and 0 < ω < 2
    (no factorisation, no breakdown for a positive diagonal). For the adjoint-pair PPE, where
    incomplete Cholesky breaks down. Returns (d̃, first row with a diagonal that is not
    positive, or -1)."""
    dt = diag / omega
    for i in range(diag.size):
        if not diag[i] > 0.0:
            return dt, i
    return dt, -1


@njit(cache=True)
def _lower_solve(lp, li, lv, dinv, s, out):
    """out = (D̃ + L)⁻¹ s (dinv = 1/d̃)."""
    for i in range(s.size):
        acc = s[i]
        for k in range(lp[i], lp[i + 1]):
            acc -= lv[k] * out[li[k]]
        out[i] = acc * dinv[i]


@njit(cache=True)
def _upper_solve(up, ui, uv, dinv, s, out):
    """out = (D̃ + U)⁻¹ s (U = Lᵀ)."""
    for i in range(s.size - 1, -1, -1):
        acc = s[i]
        for k in range(up[i], up[i + 1]):
            acc -= uv[k] * out[ui[k]]
        out[i] = acc * dinv[i]


@njit(cache=True)
def _eisenstat_product(T, dinv, kd, p, t, w, q):
    """q = Â p = t + W⁻¹(p + K t), t = W⁻ᵀ p (w: work array for W⁻¹(p + K t)); T = the strict
    triangles (lp, li, lv, up, ui, uv)."""
    lp, li, lv, up, ui, uv = T
    _upper_solve(up, ui, uv, dinv, p, t)
    for i in range(p.size):
        acc = p[i] + kd[i] * t[i]
        for k in range(lp[i], lp[i + 1]):
            acc -= lv[k] * w[li[k]]
        w[i] = acc * dinv[i]
        q[i] = w[i] + t[i]


@njit(cache=True)
def _residual(indptr, indices, data, b, x, r):
    csr_matvec(indptr, indices, data, x, r)
    for i in range(b.size):
        r[i] = b[i] - r[i]
    return math.sqrt(_dot(r, r))


@njit(cache=True)
def pcg_dic(indptr, indices, data, b, x0, rtol, atol, maxiter, mic=0.0):
    """Solve A x = b (A symmetric positive definite, CSR, any entry order) by DIC-preconditioned
    CG (Eisenstat form, see above), warm-started from x0. Returns (x, iterations, info), info = -1
    when the incomplete factorisation breaks down (non-positive pivot; x = x0). ``mic < 0``: SSOR
    pivots (:func:`ssor_diagonal`) instead of incomplete Cholesky."""
    if math.sqrt(_dot(b, b)) == 0.0:
        return b.copy(), 0, 0
    if not math.isfinite(_dot(b, b)):
        return x0.copy(), 0, NONFINITE
    return pcg_dic_split(split_triangles(indptr, indices, data), b, x0, rtol, atol, maxiter, mic)


@njit(cache=True)
def pcg_dic_split(tri, b, x0, rtol, atol, maxiter, mic=0.0):
    """:func:`pcg_dic` on a matrix given as its two triangles and diagonal, tri = (lp, li, lv, up, ui,
    uv, diag) (:func:`split_triangles`' layout; e.g. the adjoint-pair PPE assembled that way,
    :func:`ppe_operator.assemble_adjoint_triangles`)."""
    lp, li, lv, up, ui, uv, diag = tri
    T = (lp, li, lv, up, ui, uv)
    n = b.size
    thresh = stop_threshold(math.sqrt(_dot(b, b)), rtol, atol)
    x = x0.copy()
    r = np.empty(n)
    if math.sqrt(_dot(b, b)) == 0.0:
        return b.copy(), 0, 0
    if not math.isfinite(_dot(b, b)):
        return x, 0, NONFINITE
    if _any_nonzero(x):
        nr = _split_residual(lp, li, lv, up, ui, uv, diag, b, x, r)
    else:
        r[:] = b
        nr = math.sqrt(_dot(r, r))
    if converged(nr, thresh):
        return x, 0, 0
    dt, bad = ssor_diagonal(diag, -mic) if mic < 0.0 else mic_diagonal(lp, li, lv, up, uv, diag, mic)
    if bad >= 0:
        return x, 0, -1  # breakdown: the caller falls back to a direct solve
    kd = np.empty(n)
    dinv = np.empty(n)
    for i in range(n):
        kd[i] = diag[i] - 2.0 * dt[i]
        dinv[i] = 1.0 / dt[i]
    rh = np.empty(n)  # transformed residual W⁻¹ r of the correction e (x = x0 + W⁻ᵀ ê)
    _lower_solve(lp, li, lv, dinv, r, rh)
    eh = np.zeros(n)
    z = np.empty(n)
    p = np.empty(n)
    q = np.empty(n)
    t = np.empty(n)
    s = np.empty(n)
    e = np.empty(n)
    xt = np.empty(n)
    nrh0 = math.sqrt(_dot(rh, rh))
    if not (nrh0 > 0.0 and math.isfinite(nr)):
        return x, 0, BREAKDOWN
    scale = nr / nrh0  # ‖r‖ / ‖r̂‖, refreshed at every true-residual check
    rho_prev = 1.0
    for it in range(maxiter):
        for i in range(n):
            z[i] = dt[i] * rh[i]
        rho = _dot(rh, z)
        if not rho > 0.0:
            break  # breakdown (below)
        search_direction(p, z, rho, rho_prev, it == 0)
        _eisenstat_product(T, dinv, kd, p, t, s, q)
        pq = _dot(p, q)
        if not pq > 0.0:
            break  # zero/negative curvature (or NaN): A singular or indefinite
        cg_advance(eh, rh, p, q, rho / pq)
        rho_prev = rho
        nrh = math.sqrt(_dot(rh, rh))
        if converged(scale * nrh, thresh):
            _upper_solve(up, ui, uv, dinv, eh, e)
            for i in range(n):
                xt[i] = x[i] + e[i]
            nr = _split_residual(lp, li, lv, up, ui, uv, diag, b, xt, r)
            if converged(nr, thresh):
                return xt, it + 1, 0
            scale = nr / max(nrh, 1e-300)
    else:
        _upper_solve(up, ui, uv, dinv, eh, e)
        for i in range(n):
            x[i] += e[i]
        return x, maxiter, maxiter
    return x, it, BREAKDOWN


@njit(cache=True)
def _pair_eisenstat_product(T, dinv, kd, p, t, w, q):
    """:func:`_eisenstat_product` for the u and v systems in one pair of sweeps (shared
    off-diagonal entries; per side the same operations in the same order): row 0 of each (2, n)
    array is u's, row 1 v's."""
    lp, li, lv, up, ui, uv = T
    dinv_u, dinv_v, kd_u, kd_v = dinv[0], dinv[1], kd[0], kd[1]
    pu, pv, tu, tv, wu, wv, qu, qv = p[0], p[1], t[0], t[1], w[0], w[1], q[0], q[1]
    n = pu.size
    for i in range(n - 1, -1, -1):
        au = pu[i]
        av = pv[i]
        for k in range(up[i], up[i + 1]):
            a = uv[k]
            j = ui[k]
            au -= a * tu[j]
            av -= a * tv[j]
        tu[i] = au * dinv_u[i]
        tv[i] = av * dinv_v[i]
    for i in range(n):
        au = pu[i] + kd_u[i] * tu[i]
        av = pv[i] + kd_v[i] * tv[i]
        for k in range(lp[i], lp[i + 1]):
            a = lv[k]
            j = li[k]
            au -= a * wu[j]
            av -= a * wv[j]
        wu[i] = au * dinv_u[i]
        qu[i] = wu[i] + tu[i]
        wv[i] = av * dinv_v[i]
        qv[i] = wv[i] + tv[i]


@njit(cache=True, nogil=True)
def pcg_dic_pair(A, diag_v, bu, xu0, bv, xv0, rtol, atol, maxiter, mic=0.0):
    """:func:`pcg_dic` on the u and v viscous systems in lock-step (A = (indptr, indices, data): A_u
    in CSR, diagonal first in each row; A_v = A_u with diagonal ``diag_v``): each side gives the same
    result as its own :func:`pcg_dic` call, bit for bit, with one traversal of the off-diagonal
    entries per iteration for both. Returns (x_u, iterations_u, info_u, x_v, iterations_v, info_v)."""
    indptr, indices, data = A
    n = bu.size
    for i in range(n):
        if indices[indptr[i]] != i:
            raise ValueError("pcg_dic_pair: the diagonal must be the first entry of each row")
    bs = (bu, bv)
    xs = (xu0.copy(), xv0.copy())
    its = np.zeros(2, np.int64)
    infos = np.zeros(2, np.int64)
    run = np.zeros(2, np.bool_)
    thresh = np.zeros(2)
    r = np.empty((2, n))
    out = [bu.copy(), bv.copy()]
    lp, li, lv, up, ui, uv, diag_u = split_triangles(indptr, indices, data)
    diags = (diag_u, diag_v)
    for s in range(2):
        b = bs[s]
        thresh[s] = stop_threshold(math.sqrt(_dot(b, b)), rtol, atol)
        if math.sqrt(_dot(b, b)) == 0.0:
            out[s] = b.copy()
            continue
        if not math.isfinite(_dot(b, b)):
            out[s] = xs[s].copy()
            infos[s] = NONFINITE
            continue
        if _any_nonzero(xs[s]):
            nr = _split_residual(lp, li, lv, up, ui, uv, diags[s], b, xs[s], r[s])
        else:
            r[s, :] = b
            nr = math.sqrt(_dot(r[s], r[s]))
        out[s] = xs[s].copy()
        if not converged(nr, thresh[s]):
            run[s] = True
    if not (run[0] or run[1]):
        return out[0], 0, 0, out[1], 0, 0
    dts = (mic_diagonal(lp, li, lv, up, uv, diag_u, mic), mic_diagonal(lp, li, lv, up, uv, diag_v, mic))
    dinv = np.ones((2, n))
    kd = np.zeros((2, n))
    for s in range(2):
        dt, bad = dts[s]
        if run[s] and bad >= 0:
            run[s] = False
            infos[s] = -1  # breakdown: x = x0, the caller falls back to a direct solve
            continue
        if run[s]:
            for i in range(n):
                kd[s, i] = diags[s][i] - 2.0 * dt[i]
                dinv[s, i] = 1.0 / dt[i]
    rh = np.zeros((2, n))
    eh = np.zeros((2, n))
    z = np.empty(n)
    p = np.zeros((2, n))
    q = np.zeros((2, n))
    t = np.zeros((2, n))
    w = np.zeros((2, n))
    e = np.empty(n)
    xt = np.empty(n)
    scale = np.ones(2)
    rho_prev = np.ones(2)
    for s in range(2):
        if run[s]:
            _lower_solve(lp, li, lv, dinv[s], r[s], rh[s])
            nrh0 = math.sqrt(_dot(rh[s], rh[s]))
            nr0 = math.sqrt(_dot(r[s], r[s]))
            if nrh0 > 0.0 and math.isfinite(nr0):
                scale[s] = nr0 / nrh0
            else:
                run[s] = False
                infos[s] = BREAKDOWN
    rho = np.zeros(2)
    for it in range(maxiter):
        if not (run[0] or run[1]):
            break
        for s in range(2):
            if not run[s]:
                continue
            dt = dts[s][0]
            for i in range(n):
                z[i] = dt[i] * rh[s, i]
            rho[s] = _dot(rh[s], z)
            if not rho[s] > 0.0:
                run[s] = False
                its[s] = it
                infos[s] = BREAKDOWN
                continue
            search_direction(p[s], z, rho[s], rho_prev[s], it == 0)
        _pair_eisenstat_product((lp, li, lv, up, ui, uv), dinv, kd, p, t, w, q)
        for s in range(2):
            if not run[s]:
                continue
            pq = _dot(p[s], q[s])
            if not pq > 0.0:
                run[s] = False
                its[s] = it
                infos[s] = BREAKDOWN  # zero/negative curvature (or NaN)
                continue
            cg_advance(eh[s], rh[s], p[s], q[s], rho[s] / pq)
            rho_prev[s] = rho[s]
            nrh = math.sqrt(_dot(rh[s], rh[s]))
            if converged(scale[s] * nrh, thresh[s]):
                _upper_solve(up, ui, uv, dinv[s], eh[s], e)
                for i in range(n):
                    xt[i] = xs[s][i] + e[i]
                nr = _split_residual(lp, li, lv, up, ui, uv, diags[s], bs[s], xt, r[s])
                if converged(nr, thresh[s]):
                    out[s] = xt.copy()
                    its[s] = it + 1
                    run[s] = False
                else:
                    scale[s] = nr / max(nrh, 1e-300)
    for s in range(2):
        if run[s]:
            _upper_solve(up, ui, uv, dinv[s], eh[s], e)
            for i in range(n):
                out[s][i] = xs[s][i] + e[i]
            its[s] = maxiter
            infos[s] = maxiter
    return out[0], its[0], infos[0], out[1], its[1], infos[1]


@prange_kernel
def pcg_dic_two(A, diag_v, bu, xu0, bv, xv0, rtol, atol, maxiter, mic=0.0):
    """The u and v viscous systems of :func:`pcg_dic_pair` (same A, diag_v) as two independent
    :func:`pcg_dic` solves, one per thread (prange over the two systems): the same results bit for
    bit as the pair (each side of the pair is its own pcg_dic, see its doc) on any number of
    threads, in about half the time on two. Returns (x_u, iterations_u, info_u, x_v, iterations_v, info_v)."""
    indptr, indices, data = A
    n = bu.size
    for i in range(n):
        if indices[indptr[i]] != i:
            raise ValueError("pcg_dic_two: the diagonal must be the first entry of each row")
    data_v = data.copy()
    for i in range(n):
        data_v[indptr[i]] = diag_v[i]
    xs = np.empty((2, n))
    its = np.zeros(2, np.int64)
    infos = np.zeros(2, np.int64)
    for s in prange(2):
        if s == 0:
            x, it, info = pcg_dic(indptr, indices, data, bu, xu0, rtol, atol, maxiter, mic)
        else:
            x, it, info = pcg_dic(indptr, indices, data_v, bv, xv0, rtol, atol, maxiter, mic)
        xs[s, :] = x
        its[s] = it
        infos[s] = info
    return xs[0].copy(), its[0], infos[0], xs[1].copy(), its[1], infos[1]
