"""Numba Jacobi-preconditioned conjugate gradients on the CSR arrays of the ISPH kernels.

The iteration is the one of ``scipy.sparse.linalg.cg`` with ``M = diag(A)⁻¹`` (scipy 1.17,
``_isolve/iterative.py``), operation for operation, so that it returns the same iterates, bit for
bit: the residual r = b − A x₀ (r = b when x₀ = 0), the stopping test ‖r‖₂ < max(rtol ‖b‖₂, atol)
at the top of each iteration, z = D⁻¹ r, ρ = r·z, p = β p + z, q = A p, α = ρ/(p·q),
x += α p, r −= α q. The dot products go through ``np.dot`` (BLAS ddot, the same routine numpy's
``dot`` and ``linalg.norm`` use; bitwise equality checked in tests/isph/test_linsolve.py); the CSR
product sums each row in storage order from 0, as scipy's ``csr_matvec`` does. Why bit-for-bit:
the collapse amplifies differences at the solver tolerance (T22-A70 at dx = 1 cm: the kinetic
energy at t = 1 s moves by 26 % between solver_rtol 1e-8 and 1e-10, see docs/paper-notes.md),
so a solver that only agrees "to within the tolerance" would not reproduce the existing runs.

:func:`pcg_jacobi_pair` solves the two implicit viscous systems (u and v) in lock-step: the
matrices share the off-diagonal entries and differ on the diagonal (stored first in each row, as
the kernels write it), so each sweep over the off-diagonal entries serves both products. Each of
the two recurrences is exactly the single-system one (each stops on its own test).

Return convention: (x, iterations, info) with info = 0 on convergence, ``maxiter`` otherwise
(scipy's), and x = b when ‖b‖ = 0.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit


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
    """Initial state of one recurrence: x, r, dinv, the stopping threshold and ‖b‖ == 0."""
    n = b.size
    bnrm2 = math.sqrt(np.dot(b, b))
    thresh = max(atol, rtol * bnrm2)
    x = x0.copy()
    r = np.empty(n)
    if bnrm2 == 0.0:
        return b.copy(), r, np.empty(n), thresh, True
    if _any_nonzero(x):
        csr_matvec(indptr, indices, data, x, r)
        for i in range(n):
            r[i] = b[i] - r[i]
    else:
        r[:] = b
    dinv = np.empty(n)
    for i in range(n):
        dinv[i] = 1.0 / diag[i]
    return x, r, dinv, thresh, False


@njit(cache=True)
def _diag_first(indptr, indices, data):
    n = indptr.size - 1
    d = np.empty(n)
    for i in range(n):
        d[i] = data[indptr[i]]
    return d


@njit(cache=True)
def pcg_jacobi(indptr, indices, data, b, x0, rtol, atol, maxiter):
    """Solve A x = b (A symmetric positive definite, CSR, diagonal stored first in each row)."""
    n = b.size
    x, r, dinv, thresh, zero = _start(indptr, indices, data, _diag_first(indptr, indices, data), b, x0, rtol, atol)
    if zero:
        return x, 0, 0
    z = np.empty(n)
    p = np.empty(n)
    q = np.empty(n)
    rho_prev = 1.0
    for it in range(maxiter):
        if math.sqrt(np.dot(r, r)) < thresh:
            return x, it, 0
        for i in range(n):
            z[i] = dinv[i] * r[i]
        rho = np.dot(r, z)
        if it > 0:
            beta = rho / rho_prev
            for i in range(n):
                p[i] = p[i] * beta + z[i]
        else:
            p[:] = z
        csr_matvec(indptr, indices, data, p, q)
        alpha = rho / np.dot(p, q)
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
    xu, ru, dinvu, thu, zero_u = _start(indptr, indices, data, diag_u, bu, xu0, rtol, atol)
    # A_v x for the initial residual: the pair product with the u side switched off
    xv = xv0.copy()
    bnv = math.sqrt(np.dot(bv, bv))
    thv = max(atol, rtol * bnv)
    zero_v = bnv == 0.0
    rv = np.empty(n)
    dinvv = np.empty(n)
    if zero_v:
        xv = bv.copy()
    else:
        if _any_nonzero(xv):
            _pair_matvec(indptr, indices, data, diag_v, xv, xv, rv, rv, False, True)
            for i in range(n):
                rv[i] = bv[i] - rv[i]
        else:
            rv[:] = bv
        for i in range(n):
            dinvv[i] = 1.0 / diag_v[i]
    zu = np.empty(n)
    zv = np.empty(n)
    pu = np.empty(n)
    pv = np.empty(n)
    qu = np.empty(n)
    qv = np.empty(n)
    run_u = not zero_u
    run_v = not zero_v
    it_u = 0
    it_v = 0
    info_u = 0
    info_v = 0
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
            if it > 0:
                beta = rho / rho_v
                for i in range(n):
                    pv[i] = pv[i] * beta + zv[i]
            else:
                pv[:] = zv
            rho_v = rho
        _pair_matvec(indptr, indices, data, diag_v, pu, pv, qu, qv, run_u, run_v)
        if run_u:
            alpha = rho_u / np.dot(pu, qu)
            for i in range(n):
                xu[i] += alpha * pu[i]
                ru[i] -= alpha * qu[i]
        if run_v:
            alpha = rho_v / np.dot(pv, qv)
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
