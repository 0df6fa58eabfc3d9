"""SSOR-CG with an aggregation deflation space for the adjoint-pair PPE.

The SSOR-preconditioned CG (:func:`linsolve.pcg_dic_split`, symmetric Gauss-Seidel in the Eisenstat
form) removes the rough part of the error in one pass over the matrix per iteration, but not the
smooth part, whose number of modes grows as 1/dx: 37 / 45 / 66 iterations on the captured T22-A150
PPE at 4 / 2 / 1 mm (3855 / 15 170 / 59 531 unknowns), 72 on T22-A70 at 1 mm. A coarse space of
aggregates (piecewise-constant prolongation P over aggregates of the matrix graph, each root taking
its whole two-ring row: ~70 unknowns per aggregate; ``linsolve.aggregate_rows``, the rule of the
two-level CG) takes the
smooth modes out; with it the iterations stay at 22-24 at every resolution (same systems: 24 / 22 /
22).

The preconditioner is the "adapted deflation" one of Tang, Nabben, Vuik & Erlangga (2009, J. Sci.
Comput. 39, 340; A-DEF2): z = (I − Q A) S⁻¹ r, Q = P A_c⁻¹ Pᵀ, A_c = Pᵀ A P (exact, dense Cholesky),
S = (D + L) D⁻¹ (D + U) the symmetric Gauss-Seidel matrix, with the start x₀ = x_g + Q (b − A x_g)
(Pᵀ r₀ = 0, kept by every iteration), which makes it a symmetric positive definite preconditioner
on the iterates' subspace; its iterations equal those of the symmetric two-level cycle (coarse,
SGS, coarse) at one coarse solve per iteration instead of two. Its cost per iteration stays close
to one pass over the matrix:

- S⁻¹ r: a forward sweep w = (D + L)⁻¹ r and a backward sweep y = (D + U)⁻¹ D w;
- A y = L y + D w (since U y = D w − D y): L y is scattered from the backward sweep's rows while
  they are in cache ((L y)_j += U_kj y_k once y_k is known), so the upper triangle is read once;
- Q A y: restriction, the coarse solve (two dense triangular solves of n_c² / 2), prolongation; and
  A Q A y = (A P) (A_c⁻¹ Pᵀ A y) with the n × n_c matrix A P (~3-4 entries per row), so that
  A z = A y − A Q A y needs no product with A, and q = A p follows from p = z + β p_old as
  q = A z + β q_old.

Same stopping test as :func:`cg_dic.pcg_dic_split`: ‖b − A x‖ < max(atol, rtol ‖b‖) for the
true residual, checked once the recurrence's residual passes it (a failed check restarts the
iteration from the true residual). Same return convention. The set-up (aggregation, A P, A_c and its
Cholesky factor) is done on every call: the matrix changes every step. Above ``COARSE_MAX``
aggregates the dense coarse factor would cost more than it saves (n_c³ / 3 flops); the solve is
then :func:`linsolve.pcg_dic_split`'s (no deflation).

Cost (one thread, docs/performance.md): an iteration is 1.5-1.65x an Eisenstat SSOR iteration
(the scatter, the coarse correction, A P) and the set-up ~5 sweeps (aggregation, A P, A_c, its
factor). Through T22-A70 runs the solve is 0-30 % slower at 7k unknowns (2 mm: 29-52 SSOR iterations
against 17-27), 0-28 % faster at 14.5k (1.4 mm: 35-69 against 17-27) and about twice as fast at 28k
(1 mm: 64-72 against 18-19); ``numerics.deflation_min_unknowns`` (12 000) picks it from there on.

Results: the same operator and stopping test as the SSOR-CG, so the solutions agree within the
solver tolerance (not bit for bit); the runout check is in docs/performance.md.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from .cg_dic import _split_residual, pcg_dic_split
from .cg_two_level import aggregate_rows, coarse_factor
from .linsolve import BREAKDOWN, NONFINITE, _dot, coarse_solve, converged, stop_threshold

#: above this many aggregates the dense coarse Cholesky (n_c³ / 3 flops per step) is not set up
#: and the solve falls back to the SSOR-CG without deflation (~170 000 unknowns at ~70 per aggregate)
COARSE_MAX = 2500


@njit(cache=True, inline="always")
def _sum_by_aggregate(ptr, idx, val, i, agg, mark, lst, acc, cnt):
    """Add row i's entries ptr[i]:ptr[i+1] into the dense accumulator ``acc`` by aggregate, listing
    each aggregate met for the first time in row i (without a branch); returns the list's length."""
    for k in range(ptr[i], ptr[i + 1]):
        c = agg[idx[k]]
        lst[cnt] = c
        cnt += mark[c] != i
        mark[c] = i
        acc[c] += val[k]
    return cnt


@njit(cache=True)
def coarse_operators(lp, li, lv, up, ui, uv, diag, agg, nc):
    """A P (CSR, n × n_c: row i summed over each aggregate) and A_c = Pᵀ A P (dense). One pass over
    the triangles; a row's few distinct aggregates (3-4 on average: the aggregates are as wide as
    the rows) are summed in a dense accumulator (as the triangle assembly's product does)."""
    n = diag.size
    acc = np.zeros(nc)
    mark = np.full(nc, -1, np.int64)
    lst = np.empty(nc + 1, np.int64)
    cap = lp[n] + up[n] + n              # a row has at most its own entries' aggregates
    api = np.empty(cap, np.int64)
    apv = np.empty(cap)
    app = np.zeros(n + 1, np.int64)
    t0 = 0
    for i in range(n):
        c = agg[i]
        lst[0] = c
        mark[c] = i
        acc[c] += diag[i]
        cnt = _sum_by_aggregate(lp, li, lv, i, agg, mark, lst, acc, 1)
        cnt = _sum_by_aggregate(up, ui, uv, i, agg, mark, lst, acc, cnt)
        for t in range(cnt):
            c = lst[t]
            api[t0 + t] = c
            apv[t0 + t] = acc[c]
            acc[c] = 0.0
        t0 += cnt
        app[i + 1] = t0
    ac = np.zeros((nc, nc))
    for i in range(n):
        a = agg[i]
        for t in range(app[i], app[i + 1]):
            ac[a, api[t]] += apv[t]
    return app, api[:t0], apv[:t0], ac


@njit(cache=True)
def _deflate_start(lc, lct, agg, app, api, apv, x, r, rc, yc):
    """x ← x + Q r, r ← r − A Q r (then Pᵀ r = 0); returns ‖r‖."""
    rc[:] = 0.0
    for i in range(r.size):
        rc[agg[i]] += r[i]
    coarse_solve(lc, lct, rc, yc)
    for i in range(r.size):
        x[i] += rc[agg[i]]
        s = 0.0
        for t in range(app[i], app[i + 1]):
            s += apv[t] * rc[api[t]]
        r[i] -= s
    return math.sqrt(_dot(r, r))


@njit(cache=True)
def _sgs_with_product(tri, dinv, r, w, y, ay):
    """y = S⁻¹ r (symmetric Gauss-Seidel: w = (D + L)⁻¹ r, y = (D + U)⁻¹ D w) and ay = A y = L y + D w,
    L y scattered from the backward sweep's rows (one read of each triangle); tri = (lp, li, lv, up,
    ui, uv, diag)."""
    lp, li, lv, up, ui, uv, diag = tri
    n = r.size
    for i in range(n):
        acc = r[i]
        for k in range(lp[i], lp[i + 1]):
            acc -= lv[k] * w[li[k]]
        wi = acc * dinv[i]
        w[i] = wi
        ay[i] = diag[i] * wi
    for i in range(n - 1, -1, -1):
        acc = 0.0
        for k in range(up[i], up[i + 1]):
            acc += uv[k] * y[ui[k]]
        yi = w[i] - acc * dinv[i]
        y[i] = yi
        for k in range(up[i], up[i + 1]):
            ay[ui[k]] += uv[k] * yi


@njit(cache=True)
def pcg_ssor_deflated(tri, b, x0, rtol, atol, maxiter, min_unknowns=0):
    """Solve A x = b (A SPD given as its triangles and diagonal, tri = (lp, li, lv, up, ui, uv, diag),
    :func:`linsolve.split_triangles`' layout) by SSOR-CG with the aggregation deflation space (module docstring), warm-started from
    x0. Returns (x, iterations, info) as :func:`linsolve.pcg_dic_split`: info 0 converged,
    ``maxiter`` not, ``BREAKDOWN`` for a coarse matrix that is not positive definite, a non-positive
    diagonal or curvature, ``NONFINITE`` for a right-hand side with NaN/inf. Below ``min_unknowns``
    unknowns (``numerics.deflation_min_unknowns``: there the set-up costs more than the iterations
    it saves) and above ``COARSE_MAX`` aggregates it is :func:`linsolve.pcg_dic_split`'s SSOR-CG."""
    if b.size < min_unknowns:
        return pcg_dic_split(tri, b, x0, rtol, atol, maxiter, -1.0)
    lp, li, lv, up, ui, uv, diag = tri
    n = b.size
    nb = math.sqrt(_dot(b, b))
    if nb == 0.0:
        return b.copy(), 0, 0
    if not math.isfinite(nb):
        return x0.copy(), 0, NONFINITE
    for i in range(n):
        if not diag[i] > 0.0:
            return x0.copy(), 0, BREAKDOWN
    agg, nc = aggregate_rows(lp, li, lv, up, ui, uv)
    if nc > COARSE_MAX:
        return pcg_dic_split(tri, b, x0, rtol, atol, maxiter, -1.0)
    app, api, apv, ac = coarse_operators(lp, li, lv, up, ui, uv, diag, agg, nc)
    lc, lct, ok = coarse_factor(ac)
    if not ok:
        return x0.copy(), 0, BREAKDOWN
    thresh = stop_threshold(nb, rtol, atol)
    dinv = 1.0 / diag
    x = x0.copy()
    r = np.empty(n)
    nr = _split_residual(lp, li, lv, up, ui, uv, diag, b, x, r)
    if converged(nr, thresh):
        return x, 0, 0
    rc = np.empty(nc)
    yc = np.empty(nc)
    w = np.empty(n)
    y = np.empty(n)
    ay = np.empty(n)
    p = np.zeros(n)
    q = np.zeros(n)
    _deflate_start(lc, lct, agg, app, api, apv, x, r, rc, yc)
    rho_prev = 1.0
    first = True
    for it in range(maxiter):
        _sgs_with_product(tri, dinv, r, w, y, ay)
        rc[:] = 0.0                              # e = A_c⁻¹ Pᵀ A y
        for i in range(n):
            rc[agg[i]] += ay[i]
        coarse_solve(lc, lct, rc, yc)
        rho = 0.0
        for i in range(n):                       # z = y − P e (in y), A z = A y − (A P) e (in ay), ρ = r·z
            zi = y[i] - rc[agg[i]]
            y[i] = zi
            s = 0.0
            for t in range(app[i], app[i + 1]):
                s += apv[t] * rc[api[t]]
            ay[i] -= s
            rho += r[i] * zi
        if not rho > 0.0:
            return x, it, BREAKDOWN
        beta = 0.0 if first else rho / rho_prev
        first = False
        pq = 0.0
        for i in range(n):                       # p = z + β p, q = A p = A z + β q, p·q
            pi = y[i] + beta * p[i]
            qi = ay[i] + beta * q[i]
            p[i] = pi
            q[i] = qi
            pq += pi * qi
        if not pq > 0.0:
            return x, it, BREAKDOWN
        alpha = rho / pq
        rr = 0.0
        for i in range(n):
            x[i] += alpha * p[i]
            ri = r[i] - alpha * q[i]
            r[i] = ri
            rr += ri * ri
        rho_prev = rho
        if converged(math.sqrt(rr), thresh):
            nr = _split_residual(lp, li, lv, up, ui, uv, diag, b, x, r)
            if converged(nr, thresh):
                return x, it + 1, 0
            _deflate_start(lc, lct, agg, app, api, apv, x, r, rc, yc)   # restart from the true residual
            first = True
    return x, maxiter, maxiter
