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

The recurrence itself is written once and shared by every CG of granudep (here, :mod:`.cg_dic`,
:mod:`.cg_two_level`, :mod:`.deflation`): :func:`stop_threshold` and :func:`converged` (the stopping
test), :func:`search_direction` (p = z or β p + z) and :func:`cg_advance` (x += α p, r −= α q). The
Jacobi and two-level CG, on a CSR matrix or on the matrix-free PPE operator, are one loop,
:func:`_pcg_loop`.

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


@njit(cache=True, inline="always")
def stop_threshold(b_norm, rtol, atol):
    """The stopping test every CG of granudep shares: stop once ‖r‖₂ < max(rtol ‖b‖₂, atol) (scipy's)."""
    return max(atol, rtol * b_norm)


@njit(cache=True, inline="always")
def converged(residual_norm, thresh):
    """The stopping decision every CG of granudep takes, on a residual norm (recursive, transformed
    or true) against :func:`stop_threshold`'s threshold."""
    return residual_norm < thresh


@njit(cache=True, inline="always")
def search_direction(p, z, rho, rho_prev, first):
    """The CG recurrence's new search direction: p = z at the first iteration, else p = β p + z with
    β = ρ/ρ_prev (ρ = r·M⁻¹r), in place."""
    if first:
        p[:] = z
    else:
        beta = rho / rho_prev
        for i in range(p.size):
            p[i] = p[i] * beta + z[i]


@njit(cache=True, inline="always")
def cg_advance(x, r, p, q, alpha):
    """The CG recurrence's step: x += α p, r −= α q (q = A p), in place."""
    for i in range(x.size):
        x[i] += alpha * p[i]
        r[i] -= alpha * q[i]


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
    thresh = stop_threshold(bnrm2, rtol, atol)
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
    return _pcg_loop((indptr, indices, data), None, x, r, dinv, thresh, maxiter,
                     (no_coarse, no_coarse, np.empty(0, np.int64)), True)


@prange_kernel
def _pcg_loop(A, free, x, r, dinv, thresh, maxiter, coarse, blas_dot):
    """The CG iteration from the initial state (x, r) on A = (indptr, indices, data) in CSR (``free``
    None), or on the matrix-free PPE operator ``free`` (A then not read; :func:`ppe_operator.matrix_free_operator`,
    applied as :func:`cg_two_level.free_matvec` does, each of its two gathers row-parallel):
    preconditioner z = D⁻¹ r, plus the coarse correction P A_c⁻¹ Pᵀ r when coarse = (lc, lct, agg) has a
    non-empty ``lc`` (the Cholesky factor of A_c, :func:`pcg_two_level`); dot products by ``np.dot``
    (``blas_dot``: scipy's iterates bit for bit) or :func:`_dot`. The product A p runs over the rows in
    parallel (``prange``), each row summed as :func:`csr_matvec` does, so the iterates do not depend on
    the thread count. Returns (x, iterations, info) as :func:`pcg_jacobi`."""
    lc, lct, agg = coarse
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
        if converged(math.sqrt(rr), thresh):
            return x, it, 0
        if nc > 0:
            _two_level_apply(lc, lct, agg, dinv, r, z, rc, yc)
        else:
            for i in range(n):
                z[i] = dinv[i] * r[i]
        rho = np.dot(r, z) if blas_dot else _dot(r, z)
        if not rho > 0.0:
            return x, it, BREAKDOWN  # r·M⁻¹r <= 0 (or NaN): the preconditioner not positive
        search_direction(p, z, rho, rho_prev, it == 0)
        if free is None:
            indptr, indices, data = A
            for i in prange(n):             # q = A p (csr_matvec, row-parallel)
                s = 0.0
                for k in range(indptr[i], indptr[i + 1]):
                    s += data[k] * p[indices[k]]
                q[i] = s
        else:
            wd, rptr, rcol, rx, ry, cptr, crow, ccx, ccy, lptr, lcol, lval = free
            nfp = cptr.size - 1
            gx = np.empty(nfp)
            gy = np.empty(nfp)
            for i in prange(nfp):           # D_Uᵀ p, by particle
                sx = 0.0
                sy = 0.0
                for k in range(cptr[i], cptr[i + 1]):
                    pr = p[crow[k]]
                    sx += ccx[k] * pr
                    sy += ccy[k] * pr
                gx[i] = sx
                gy[i] = sy
            for i in prange(n):             # q = wd D_U (D_Uᵀ p) + ε L_c p, by row
                s = 0.0
                for k in range(rptr[i], rptr[i + 1]):
                    c = rcol[k]
                    s += rx[k] * gx[c] + ry[k] * gy[c]
                t = 0.0
                for k in range(lptr[i], lptr[i + 1]):
                    t += lval[k] * p[lcol[k]]
                q[i] = wd * s + t
        pq = np.dot(p, q) if blas_dot else _dot(p, q)
        if not pq > 0.0:
            return x, it, BREAKDOWN  # zero/negative curvature: A singular or indefinite
        alpha = rho / pq
        cg_advance(x, r, p, q, alpha)
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
def pcg_jacobi_pair(A, diag_v, bu, xu0, bv, xv0, rtol, atol, maxiter):
    """Two Jacobi-CG solves, A_u x_u = b_u and A_v x_v = b_v, in lock-step (see module doc);
    A = (indptr, indices, data): A_u in CSR, diagonal first in each row, A_v = A_u with ``diag_v``.

    Returns (x_u, iterations_u, info_u, x_v, iterations_v, info_v)."""
    indptr, indices, data = A
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
    thv = stop_threshold(bnv, rtol, atol)
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
        if run_u and converged(math.sqrt(np.dot(ru, ru)), thu):
            run_u = False
            it_u = it
        if run_v and converged(math.sqrt(np.dot(rv, rv)), thv):
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
            search_direction(pu, zu, rho, rho_u, it == 0)
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
            search_direction(pv, zv, rho, rho_v, it == 0)
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
            cg_advance(xu, ru, pu, qu, rho_u / pq)
        if run_v:
            pq = np.dot(pv, qv)
            if not pq > 0.0:
                run_v = False
                it_v = it
                info_v = BREAKDOWN
        if run_v:
            cg_advance(xv, rv, pv, qv, rho_v / pq)
    else:
        if run_u:
            it_u = maxiter
            info_u = maxiter
        if run_v:
            it_v = maxiter
            info_v = maxiter
    return xu, it_u, info_u, xv, it_v, info_v


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
