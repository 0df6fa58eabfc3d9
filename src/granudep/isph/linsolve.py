"""Numba conjugate gradients on the CSR arrays of the ISPH kernels: Jacobi-preconditioned
(``cg``, the default: scipy's iterates bit for bit) and DIC-preconditioned (``cg_dic``, below).

The iteration is the one of ``scipy.sparse.linalg.cg`` with ``M = diag(A)⁻¹`` (scipy 1.17,
``_isolve/iterative.py``), operation for operation, so that it returns the same iterates, bit for
bit: the residual r = b − A x₀ (r = b when x₀ = 0), the stopping test ‖r‖₂ < max(rtol ‖b‖₂, atol)
at the top of each iteration, z = D⁻¹ r, ρ = r·z, p = β p + z, q = A p, α = ρ/(p·q),
x += α p, r −= α q. The dot products go through ``np.dot`` (BLAS ddot, the same routine numpy's
``dot`` and ``linalg.norm`` use; bitwise equality checked in tests/isph/test_linsolve.py); the CSR
product sums each row in storage order from 0, as scipy's ``csr_matvec`` does. Why bit-for-bit:
the collapse amplifies differences at the solver tolerance (T22-A70 at dx = 1 cm: the kinetic
energy at t = 1 s moves by 26 % between solver_rtol 1e-8 and 1e-10, see docs/model.md),
so a solver that only agrees "to within the tolerance" would not reproduce the existing runs.

:func:`pcg_jacobi_pair` solves the two implicit viscous systems (u and v) in lock-step: the
matrices share the off-diagonal entries and differ on the diagonal (stored first in each row, as
the kernels write it), so each sweep over the off-diagonal entries serves both products. Each of
the two recurrences is exactly the single-system one (each stops on its own test).

Return convention: (x, iterations, info) with info = 0 on convergence, ``maxiter`` otherwise
(scipy's), and x = b when ‖b‖ = 0. Breakdowns never raise: info = -1 for a
non-positive incomplete-Cholesky pivot, ``BREAKDOWN`` (-2) for a curvature p·Ap that is not
positive (zero, negative or NaN: A singular or indefinite), a zero or non-positive ρ = r·z or a
zero diagonal, and ``NONFINITE`` (-3) for a right-hand side with NaN/inf; x is then the last
finite iterate (or x0). The caller (``linear_systems.LinearSystems.solve_cg``) falls back to the direct solver.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from .parallel import prange_kernel

BREAKDOWN = -2
NONFINITE = -3


# OpenBLAS (scipy's, which numba's np.dot calls) splits a ddot over its own threads above this size
# (kernel/x86_64/ddot.c: n > 10000): the sum then depends on the OpenBLAS thread count, and on a
# loaded machine every such call waits for the second thread (T22-A150 at 2 mm, one numba thread:
# viscous + PPE 139 -> 1529 ms/step with OpenBLAS at its default 2 threads vs 1 thread).
DOT_BLAS_MAX = 10000


_BLAS_PINNED = False


def pin_blas_to_one_thread() -> None:
    """Run the BLAS that the numba kernels call (``np.dot`` → scipy's OpenBLAS ddot) on one thread,
    for the whole process, once.

    OpenBLAS splits a ddot over its threads once the vectors exceed 10 000 entries: every CG
    iteration (three dot products) then wakes and synchronises the BLAS threads, which compete with
    the numba ``prange`` threads and with the other jobs of ``snakemake -j2``. Measured on this 2-core
    machine (T22-A70 at dx = 1.4 mm, 14 504 PPE unknowns, adjoint-pair PPE, the other core busy):
    Jacobi-CG 13.2 ns per nonzero and iteration with two BLAS threads against 4.8 with one, the
    whole run 1 → 2 steps/s; below 10 000 unknowns nothing changes. (The (M)IC-CG already avoids
    BLAS above that size, :func:`_dot`; the Jacobi-CG keeps ``np.dot`` for scipy's iterates.) It also makes the partial sums
    of the dot products (hence the trajectories, which amplify round-off) independent of the
    machine's core count. The numba kernels are the parallel layer (``NUMBA_NUM_THREADS``)."""
    global _BLAS_PINNED
    if _BLAS_PINNED:
        return
    import scipy.linalg.cython_blas  # noqa: F401 -- the BLAS numba's np.dot calls: load it before limiting
    from threadpoolctl import threadpool_limits
    threadpool_limits(limits=1, user_api="blas")
    _BLAS_PINNED = True


@njit(cache=True)
def _dot(a, b):
    """a·b for the (M)IC-CG: BLAS ddot (np.dot) up to DOT_BLAS_MAX entries, so that the runs of up
    to ~10 000 particles (dx = 4 mm) keep their iterates bit for bit; above, a serial sum in a
    fixed order (8 interleaved partial sums, added pairwise), the same on any machine and thread
    count, never waiting for BLAS threads."""
    n = a.size
    if n <= DOT_BLAS_MAX:
        return np.dot(a, b)
    s0 = 0.0
    s1 = 0.0
    s2 = 0.0
    s3 = 0.0
    s4 = 0.0
    s5 = 0.0
    s6 = 0.0
    s7 = 0.0
    m = n - n % 8
    for i in range(0, m, 8):
        s0 += a[i] * b[i]
        s1 += a[i + 1] * b[i + 1]
        s2 += a[i + 2] * b[i + 2]
        s3 += a[i + 3] * b[i + 3]
        s4 += a[i + 4] * b[i + 4]
        s5 += a[i + 5] * b[i + 5]
        s6 += a[i + 6] * b[i + 6]
        s7 += a[i + 7] * b[i + 7]
    for i in range(m, n):
        s0 += a[i] * b[i]
    return ((s0 + s1) + (s2 + s3)) + ((s4 + s5) + (s6 + s7))


@njit(cache=True)
def csr_matvec(indptr, indices, data, x, out):
    """out = A x (row sums in storage order, from 0)."""
    n = indptr.size - 1
    for i in range(n):
        s = 0.0
        for k in range(indptr[i], indptr[i + 1]):
            s += data[k] * x[indices[k]]
        out[i] = s


@njit(cache=True)
def _any_nonzero(x):
    for i in range(x.size):
        if x[i] != 0.0:
            return True
    return False


@njit(cache=True)
def _start(indptr, indices, data, diag, b, x0, rtol, atol):
    """Initial state of one recurrence: x, r, dinv, the stopping threshold, ‖b‖ == 0 and a status
    (0, ``NONFINITE`` for a NaN/inf right-hand side, ``BREAKDOWN`` for a zero diagonal)."""
    n = b.size
    bnrm2 = math.sqrt(np.dot(b, b))
    thresh = max(atol, rtol * bnrm2)
    x = x0.copy()
    r = np.empty(n)
    if bnrm2 == 0.0:
        return b.copy(), r, np.empty(n), thresh, True, 0
    if not math.isfinite(bnrm2):
        return x, r, np.empty(n), thresh, False, NONFINITE
    if _any_nonzero(x):
        csr_matvec(indptr, indices, data, x, r)
        for i in range(n):
            r[i] = b[i] - r[i]
    else:
        r[:] = b
    dinv = np.empty(n)
    for i in range(n):
        if diag[i] == 0.0:
            return x, r, dinv, thresh, False, BREAKDOWN
        dinv[i] = 1.0 / diag[i]
    return x, r, dinv, thresh, False, 0


@njit(cache=True)
def _diag_first(indptr, indices, data):
    n = indptr.size - 1
    d = np.empty(n)
    for i in range(n):
        d[i] = data[indptr[i]]
    return d


def pcg_jacobi(indptr, indices, data, b, x0, rtol, atol, maxiter):
    """Solve A x = b (A symmetric positive definite, CSR, diagonal stored first in each row)."""
    x, r, dinv, thresh, zero, status = _start(indptr, indices, data, _diag_first(indptr, indices, data), b, x0,
                                              rtol, atol)
    if zero:
        return x, 0, 0
    if status != 0:
        return x, 0, status
    no_coarse = np.empty((0, 0))
    return _pcg_loop(indptr, indices, data, x, r, dinv, thresh, maxiter, no_coarse, no_coarse,
                     np.empty(0, np.int64), True)


@prange_kernel
def _pcg_loop(indptr, indices, data, x, r, dinv, thresh, maxiter, lc, lct, agg, blas_dot):
    """The CG iteration from the initial state (x, r): preconditioner z = D⁻¹ r, plus the coarse
    correction P A_c⁻¹ Pᵀ r when ``lc`` (the Cholesky factor of A_c, :func:`pcg_two_level`) is not
    empty; dot products by ``np.dot`` (``blas_dot``: scipy's iterates bit for bit) or :func:`_dot`.
    The product A p runs over the rows in parallel (``prange``), each row summed as
    :func:`csr_matvec` does, so the iterates do not depend on the thread count.
    Returns (x, iterations, info) as :func:`pcg_jacobi`."""
    n = x.size
    nc = lc.shape[0]
    z = np.empty(n)
    p = np.empty(n)
    q = np.empty(n)
    rc = np.empty(nc)
    yc = np.empty(nc)
    rho_prev = 1.0
    for it in range(maxiter):
        rr = np.dot(r, r) if blas_dot else _dot(r, r)
        if math.sqrt(rr) < thresh:
            return x, it, 0
        if nc > 0:
            _two_level_apply(lc, lct, agg, dinv, r, z, rc, yc)
        else:
            for i in range(n):
                z[i] = dinv[i] * r[i]
        rho = np.dot(r, z) if blas_dot else _dot(r, z)
        if not rho > 0.0:
            return x, it, BREAKDOWN  # r·M⁻¹r <= 0 (or NaN): the preconditioner not positive
        if it > 0:
            beta = rho / rho_prev
            for i in range(n):
                p[i] = p[i] * beta + z[i]
        else:
            p[:] = z
        for i in prange(n):                 # q = A p (csr_matvec, row-parallel)
            s = 0.0
            for k in range(indptr[i], indptr[i + 1]):
                s += data[k] * p[indices[k]]
            q[i] = s
        pq = np.dot(p, q) if blas_dot else _dot(p, q)
        if not pq > 0.0:
            return x, it, BREAKDOWN  # zero/negative curvature: A singular or indefinite
        alpha = rho / pq
        for i in range(n):
            x[i] += alpha * p[i]
            r[i] -= alpha * q[i]
        rho_prev = rho
    return x, maxiter, maxiter


@njit(cache=True)
def _pair_matvec(indptr, indices, data, diag_v, pu, pv, qu, qv, do_u, do_v):
    """qu = A_u pu and qv = A_v pv in one sweep; A_v = A_u with the diagonal (first entry of each
    row) replaced by diag_v. Same summation order as :func:`csr_matvec` on either matrix."""
    n = indptr.size - 1
    for i in range(n):
        k0 = indptr[i]
        su = 0.0
        sv = 0.0
        if do_u:
            su += data[k0] * pu[indices[k0]]
        if do_v:
            sv += diag_v[i] * pv[indices[k0]]
        for k in range(k0 + 1, indptr[i + 1]):
            a = data[k]
            j = indices[k]
            if do_u:
                su += a * pu[j]
            if do_v:
                sv += a * pv[j]
        qu[i] = su
        qv[i] = sv


@njit(cache=True)
def pcg_jacobi_pair(indptr, indices, data, diag_v, bu, xu0, bv, xv0, rtol, atol, maxiter):
    """Two Jacobi-CG solves, A_u x_u = b_u and A_v x_v = b_v, in lock-step (see module doc).

    Returns (x_u, iterations_u, info_u, x_v, iterations_v, info_v)."""
    n = bu.size
    for i in range(n):
        if indices[indptr[i]] != i:
            raise ValueError("pcg_jacobi_pair: the diagonal must be the first entry of each row")
    diag_u = _diag_first(indptr, indices, data)
    xu, ru, dinvu, thu, zero_u, info_u = _start(indptr, indices, data, diag_u, bu, xu0, rtol, atol)
    info_v = 0
    # A_v x for the initial residual: the pair product with the u side switched off
    xv = xv0.copy()
    bnv = math.sqrt(np.dot(bv, bv))
    thv = max(atol, rtol * bnv)
    zero_v = bnv == 0.0
    rv = np.empty(n)
    dinvv = np.empty(n)
    if zero_v:
        xv = bv.copy()
    elif not math.isfinite(bnv):
        info_v = NONFINITE
    else:
        if _any_nonzero(xv):
            _pair_matvec(indptr, indices, data, diag_v, xv, xv, rv, rv, False, True)
            for i in range(n):
                rv[i] = bv[i] - rv[i]
        else:
            rv[:] = bv
        for i in range(n):
            if diag_v[i] == 0.0:
                info_v = BREAKDOWN
                break
            dinvv[i] = 1.0 / diag_v[i]
    zu = np.empty(n)
    zv = np.empty(n)
    pu = np.empty(n)
    pv = np.empty(n)
    qu = np.empty(n)
    qv = np.empty(n)
    run_u = not zero_u and info_u == 0
    run_v = not zero_v and info_v == 0
    it_u = 0
    it_v = 0
    rho_u = 1.0
    rho_v = 1.0
    for it in range(maxiter):
        if run_u and math.sqrt(np.dot(ru, ru)) < thu:
            run_u = False
            it_u = it
        if run_v and math.sqrt(np.dot(rv, rv)) < thv:
            run_v = False
            it_v = it
        if not (run_u or run_v):
            break
        if run_u:
            for i in range(n):
                zu[i] = dinvu[i] * ru[i]
            rho = np.dot(ru, zu)
            if not rho > 0.0:
                run_u = False
                it_u = it
                info_u = BREAKDOWN
        if run_u:
            if it > 0:
                beta = rho / rho_u
                for i in range(n):
                    pu[i] = pu[i] * beta + zu[i]
            else:
                pu[:] = zu
            rho_u = rho
        if run_v:
            for i in range(n):
                zv[i] = dinvv[i] * rv[i]
            rho = np.dot(rv, zv)
            if not rho > 0.0:
                run_v = False
                it_v = it
                info_v = BREAKDOWN
        if run_v:
            if it > 0:
                beta = rho / rho_v
                for i in range(n):
                    pv[i] = pv[i] * beta + zv[i]
            else:
                pv[:] = zv
            rho_v = rho
        if not (run_u or run_v):
            break
        _pair_matvec(indptr, indices, data, diag_v, pu, pv, qu, qv, run_u, run_v)
        if run_u:
            pq = np.dot(pu, qu)
            if not pq > 0.0:
                run_u = False
                it_u = it
                info_u = BREAKDOWN
        if run_u:
            alpha = rho_u / pq
            for i in range(n):
                xu[i] += alpha * pu[i]
                ru[i] -= alpha * qu[i]
        if run_v:
            pq = np.dot(pv, qv)
            if not pq > 0.0:
                run_v = False
                it_v = it
                info_v = BREAKDOWN
        if run_v:
            alpha = rho_v / pq
            for i in range(n):
                xv[i] += alpha * pv[i]
                rv[i] -= alpha * qv[i]
    else:
        if run_u:
            it_u = maxiter
            info_u = maxiter
        if run_v:
            it_v = maxiter
            info_v = maxiter
    return xu, it_u, info_u, xv, it_v, info_v


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
def _eisenstat_product(lp, li, lv, up, ui, uv, dinv, kd, p, t, w, q):
    """q = Â p = t + W⁻¹(p + K t), t = W⁻ᵀ p (w: work array for W⁻¹(p + K t))."""
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
    lp, li, lv, up, ui, uv, diag = split_triangles(indptr, indices, data)
    return pcg_dic_split(lp, li, lv, up, ui, uv, diag, b, x0, rtol, atol, maxiter, mic)


@njit(cache=True)
def pcg_dic_split(lp, li, lv, up, ui, uv, diag, b, x0, rtol, atol, maxiter, mic=0.0):
    """:func:`pcg_dic` on a matrix given as its two triangles and diagonal (:func:`split_triangles`'
    layout; e.g. the adjoint-pair PPE assembled that way, :func:`ppe_operator.assemble_adjoint_triangles`)."""
    n = b.size
    thresh = max(atol, rtol * math.sqrt(_dot(b, b)))
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
    if nr < thresh:
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
        if it > 0:
            beta = rho / rho_prev
            for i in range(n):
                p[i] = p[i] * beta + z[i]
        else:
            p[:] = z
        _eisenstat_product(lp, li, lv, up, ui, uv, dinv, kd, p, t, s, q)
        pq = _dot(p, q)
        if not pq > 0.0:
            break  # zero/negative curvature (or NaN): A singular or indefinite
        alpha = rho / pq
        for i in range(n):
            eh[i] += alpha * p[i]
            rh[i] -= alpha * q[i]
        rho_prev = rho
        nrh = math.sqrt(_dot(rh, rh))
        if scale * nrh < thresh:
            _upper_solve(up, ui, uv, dinv, eh, e)
            for i in range(n):
                xt[i] = x[i] + e[i]
            nr = _split_residual(lp, li, lv, up, ui, uv, diag, b, xt, r)
            if nr < thresh:
                return xt, it + 1, 0
            scale = nr / max(nrh, 1e-300)
    else:
        _upper_solve(up, ui, uv, dinv, eh, e)
        for i in range(n):
            x[i] += e[i]
        return x, maxiter, maxiter
    return x, it, BREAKDOWN


@njit(cache=True)
def _pair_eisenstat_product(lp, li, lv, up, ui, uv, dinv_u, dinv_v, kd_u, kd_v, pu, pv, tu, tv, wu, wv, qu, qv):
    """:func:`_eisenstat_product` for the u and v systems in one pair of sweeps (shared
    off-diagonal entries; per side the same operations in the same order)."""
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
def pcg_dic_pair(indptr, indices, data, diag_v, bu, xu0, bv, xv0, rtol, atol, maxiter, mic=0.0):
    """:func:`pcg_dic` on the u and v viscous systems in lock-step (A_v = A_u with diagonal
    ``diag_v``; diagonal first in each row): each side gives the same result as its own
    :func:`pcg_dic` call, bit for bit, with one traversal of the off-diagonal entries per
    iteration for both. Returns (x_u, iterations_u, info_u, x_v, iterations_v, info_v)."""
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
        thresh[s] = max(atol, rtol * math.sqrt(_dot(b, b)))
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
        if not nr < thresh[s]:
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
            if it > 0:
                beta = rho[s] / rho_prev[s]
                for i in range(n):
                    p[s, i] = p[s, i] * beta + z[i]
            else:
                p[s, :] = z
        _pair_eisenstat_product(lp, li, lv, up, ui, uv, dinv[0], dinv[1], kd[0], kd[1], p[0], p[1], t[0], t[1],
                                w[0], w[1], q[0], q[1])
        for s in range(2):
            if not run[s]:
                continue
            pq = _dot(p[s], q[s])
            if not pq > 0.0:
                run[s] = False
                its[s] = it
                infos[s] = BREAKDOWN  # zero/negative curvature (or NaN)
                continue
            alpha = rho[s] / pq
            for i in range(n):
                eh[s, i] += alpha * p[s, i]
                rh[s, i] -= alpha * q[s, i]
            rho_prev[s] = rho[s]
            nrh = math.sqrt(_dot(rh[s], rh[s]))
            if scale[s] * nrh < thresh[s]:
                _upper_solve(up, ui, uv, dinv[s], eh[s], e)
                for i in range(n):
                    xt[i] = xs[s][i] + e[i]
                nr = _split_residual(lp, li, lv, up, ui, uv, diags[s], bs[s], xt, r[s])
                if nr < thresh[s]:
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
def pcg_dic_two(indptr, indices, data, diag_v, bu, xu0, bv, xv0, rtol, atol, maxiter, mic=0.0):
    """The u and v viscous systems of :func:`pcg_dic_pair` as two independent :func:`pcg_dic` solves,
    one per thread (prange over the two systems): the same results bit for bit as the pair (each
    side of the pair is its own pcg_dic, see its doc) on any number of threads, in about half the
    time on two. Returns (x_u, iterations_u, info_u, x_v, iterations_v, info_v)."""
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
def _two_level_apply(lc, lct, agg, dinv, r, z, rc, yc):
    """z = D⁻¹ r + P A_c⁻¹ Pᵀ r with A_c = L Lᵀ (``lc`` = L, ``lct`` = Lᵀ, both C-ordered)."""
    rc[:] = 0.0
    for i in range(r.size):
        rc[agg[i]] += r[i]
    coarse_solve(lc, lct, rc, yc)
    for i in range(r.size):
        z[i] = dinv[i] * r[i] + rc[agg[i]]


@njit(cache=True)
def coarse_solve(lc, lct, rc, yc):
    """rc ← A_c⁻¹ rc with A_c = L Lᵀ (``lc`` = L, ``lct`` = Lᵀ, both C-ordered; yc: work)."""
    nc = rc.size
    for i in range(nc):                  # L y = rc
        s = rc[i]
        for j in range(i):
            s -= lc[i, j] * yc[j]
        yc[i] = s / lc[i, i]
    for i in range(nc - 1, -1, -1):      # Lᵀ c = y
        s = yc[i]
        for j in range(i + 1, nc):
            s -= lct[i, j] * rc[j]
        rc[i] = s / lct[i, i]


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
    return _pcg_loop(indptr, indices, data, x, r, dinv, thresh, maxiter, lc, lct, agg, False)


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


@prange_kernel
def _pcg_free_loop(op, x, r, dinv, thresh, maxiter, lc, lct, agg):
    """:func:`_pcg_loop` (two-level, fixed-order dot products) with A p applied matrix-free
    (:func:`free_matvec`, each of its two gathers row-parallel)."""
    wd, rptr, rcol, rx, ry, cptr, crow, ccx, ccy, lptr, lcol, lval = op
    n = x.size
    nfp = cptr.size - 1
    nc = lc.shape[0]
    z = np.empty(n)
    p = np.empty(n)
    q = np.empty(n)
    gx = np.empty(nfp)
    gy = np.empty(nfp)
    rc = np.empty(nc)
    yc = np.empty(nc)
    rho_prev = 1.0
    for it in range(maxiter):
        rr = _dot(r, r)
        if math.sqrt(rr) < thresh:
            return x, it, 0
        _two_level_apply(lc, lct, agg, dinv, r, z, rc, yc)
        rho = _dot(r, z)
        if not rho > 0.0:
            return x, it, BREAKDOWN
        if it > 0:
            beta = rho / rho_prev
            for i in range(n):
                p[i] = p[i] * beta + z[i]
        else:
            p[:] = z
        for i in prange(nfp):               # D_Uᵀ p, by particle
            sx = 0.0
            sy = 0.0
            for k in range(cptr[i], cptr[i + 1]):
                pr = p[crow[k]]
                sx += ccx[k] * pr
                sy += ccy[k] * pr
            gx[i] = sx
            gy[i] = sy
        for i in prange(n):                 # q = wd D_U (D_Uᵀ p) + ε L_c p, by row
            s = 0.0
            for k in range(rptr[i], rptr[i + 1]):
                c = rcol[k]
                s += rx[k] * gx[c] + ry[k] * gy[c]
            t = 0.0
            for k in range(lptr[i], lptr[i + 1]):
                t += lval[k] * p[lcol[k]]
            q[i] = wd * s + t
        pq = _dot(p, q)
        if not pq > 0.0:
            return x, it, BREAKDOWN
        alpha = rho / pq
        for i in range(n):
            x[i] += alpha * p[i]
            r[i] -= alpha * q[i]
        rho_prev = rho
    return x, maxiter, maxiter


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
    thresh = max(atol, rtol * bnrm2)
    r = b.copy()
    if _any_nonzero(x):
        ax = np.empty(n)
        free_matvec(op, x, np.empty(op[5].size - 1), np.empty(op[5].size - 1), ax)
        r -= ax
    dinv, agg, lc, lct, status = _free_setup(op, coarse_max)
    if status != 0:
        return x, 0, status
    return _pcg_free_loop(op, x, r, dinv, thresh, maxiter, lc, lct, agg)
