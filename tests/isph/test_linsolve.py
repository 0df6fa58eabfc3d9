"""Numba Jacobi-CG (granudep.isph.linsolve): the same iterates as scipy's cg, bit for bit.

Bitwise equality is the requirement (not a tolerance): the collapse amplifies solver-tolerance
differences (docs/model.md, "Linear solvers"), so anything less would change the runs.
"""
import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from granudep.isph.cg_dic import dic_diagonal, mic_diagonal, pcg_dic, pcg_dic_pair, split_triangles
from granudep.isph.cg_two_level import aggregate_nodes, coarse_matrix, pcg_two_level
from granudep.isph.linsolve import BREAKDOWN, NONFINITE, _two_level_apply, csr_matvec, pcg_jacobi, pcg_jacobi_pair
from granudep.isph.neighbours import build_neighbours


def _particle_matrix(n_side=24, shift=0.05, seed=0, diag_extra=None, radius=2.6, random_shift=True):
    """CSR like the ISPH kernels write it: per row the diagonal first, then the neighbours in
    neighbour-list order (unsorted); off-diagonal -w_ij (w > 0, symmetric), diagonal
    shift + Σ w (+ diag_extra: a second diagonal for the pair solve)."""
    rng = np.random.default_rng(seed)
    g = np.arange(n_side) * 1.0
    x, y = (a.ravel() + 0.2 * rng.standard_normal(n_side * n_side) for a in np.meshgrid(g, g))
    n = x.size
    start, nbr, rx, ry, rr = build_neighbours(x, y, n, radius, 0.0)
    w = (1.0 - rr / radius) ** 4  # symmetric: a function of the pair distance
    indptr = np.zeros(n + 1, np.int64)
    indptr[1:] = np.cumsum(np.diff(start) + 1)
    indices = np.empty(indptr[-1], np.int64)
    data = np.empty(indptr[-1])
    for i in range(n):  # test set-up only
        a, b = start[i], start[i + 1]
        indices[indptr[i]] = i
        indices[indptr[i] + 1:indptr[i + 1]] = nbr[a:b]
        data[indptr[i] + 1:indptr[i + 1]] = -w[a:b]
        data[indptr[i]] = (shift * (1.0 + rng.random()) if random_shift else shift) + w[a:b].sum()
    return indptr, indices, data


def _scipy_cg(indptr, indices, data, b, x0, rtol=1e-8, maxiter=1000):
    n = indptr.size - 1
    a = sp.csr_matrix((data, indices, indptr), shape=(n, n))
    dinv = 1.0 / data[indptr[:-1]]
    m = spla.LinearOperator((n, n), matvec=lambda z: dinv * z)
    it = [0]

    def cb(_):
        it[0] += 1
    x, info = spla.cg(a, b, x0=x0, rtol=rtol, atol=0.0, maxiter=maxiter, M=m, callback=cb)
    return x, it[0], info


def test_matrix_is_symmetric_with_diagonal_first():
    indptr, indices, data = _particle_matrix()
    n = indptr.size - 1
    a = sp.csr_matrix((data, indices, indptr), shape=(n, n))
    assert abs(a - a.T).max() == 0.0
    assert np.all(indices[indptr[:-1]] == np.arange(n))
    assert np.diff(indptr).min() >= 5  # neighbours beyond the diagonal (not a trivial matrix)


def test_matvec_equals_scipy_bitwise():
    indptr, indices, data = _particle_matrix()
    n = indptr.size - 1
    x = np.random.default_rng(3).standard_normal(n)
    out = np.empty(n)
    csr_matvec(indptr, indices, data, x, out)
    assert np.array_equal(out, sp.csr_matrix((data, indices, indptr), shape=(n, n)) @ x)


@pytest.mark.parametrize("shift, warm", [(0.05, False), (0.05, True), (1e-4, True), (1.0, False)])
def test_pcg_jacobi_reproduces_scipy_cg_bitwise(shift, warm):
    indptr, indices, data = _particle_matrix(shift=shift)
    n = indptr.size - 1
    rng = np.random.default_rng(7)
    b = rng.standard_normal(n)
    x0 = b + 0.1 * rng.standard_normal(n) if warm else np.zeros(n)
    xs, its, infos = _scipy_cg(indptr, indices, data, b, x0)
    x, it, info = pcg_jacobi(indptr, indices, data, b, x0, 1e-8, 0.0, 1000)
    assert infos == 0 and info == 0
    assert it == its and it > 10
    assert np.array_equal(x, xs)
    a = sp.csr_matrix((data, indices, indptr), shape=(n, n))
    assert np.linalg.norm(b - a @ x) < 1e-8 * np.linalg.norm(b)
    assert not np.shares_memory(x, x0) and np.array_equal(x0, x0)


def test_pcg_jacobi_maxiter_and_zero_rhs_match_scipy():
    indptr, indices, data = _particle_matrix(shift=1e-4)
    n = indptr.size - 1
    b = np.random.default_rng(1).standard_normal(n)
    xs, its, infos = _scipy_cg(indptr, indices, data, b, np.zeros(n), maxiter=5)
    x, it, info = pcg_jacobi(indptr, indices, data, b, np.zeros(n), 1e-8, 0.0, 5)
    assert infos == 5 and info == 5 and it == 5
    assert np.array_equal(x, xs)
    x, it, info = pcg_jacobi(indptr, indices, data, np.zeros(n), np.ones(n), 1e-8, 0.0, 1000)
    assert info == 0 and it == 0 and np.array_equal(x, np.zeros(n))


def test_pair_equals_two_single_solves_bitwise():
    indptr, indices, data = _particle_matrix(shift=0.05)
    n = indptr.size - 1
    rng = np.random.default_rng(11)
    diag_v = data[indptr[:-1]] + 0.3 * rng.random(n)  # v diagonal: same off-diagonal, more drag
    data_v = data.copy()
    data_v[indptr[:-1]] = diag_v
    bu, bv = rng.standard_normal(n), 0.01 * rng.standard_normal(n)
    xu, itu, infou, xv, itv, infov = pcg_jacobi_pair((indptr, indices, data), diag_v, bu, bu, bv, bv, 1e-8, 0.0, 1000)
    xu1, itu1, _ = _scipy_cg(indptr, indices, data, bu, bu)
    xv1, itv1, _ = _scipy_cg(indptr, indices, data_v, bv, bv)
    assert infou == 0 and infov == 0
    assert (itu, itv) == (itu1, itv1) and itu != itv  # the two recurrences stop on their own tests
    assert np.array_equal(xu, xu1) and np.array_equal(xv, xv1)
    # one side with a zero right-hand side, the other not converging in the allowed iterations
    xu, itu, infou, xv, itv, infov = pcg_jacobi_pair((indptr, indices, data), diag_v, np.zeros(n), bu, bv, bv,
                                                     1e-8, 0.0, 3)
    xv3, itv3, infov3 = _scipy_cg(indptr, indices, data_v, bv, bv, maxiter=3)
    assert (itu, infou) == (0, 0) and np.array_equal(xu, np.zeros(n))
    assert (itv, infov) == (3, 3) == (itv3, infov3) and np.array_equal(xv, xv3)


def test_pair_rejects_a_matrix_without_the_diagonal_first():
    indptr, indices, data = _particle_matrix(n_side=6)
    n = indptr.size - 1
    i0 = indptr[0]
    indices[[i0, i0 + 1]] = indices[[i0 + 1, i0]]
    data[[i0, i0 + 1]] = data[[i0 + 1, i0]]
    b = np.ones(n)
    with pytest.raises(ValueError, match="diagonal must be the first entry"):
        pcg_jacobi_pair((indptr, indices, data), np.ones(n), b, b, b, b, 1e-8, 0.0, 10)


# ---- DIC-preconditioned CG (cg_dic): a different iteration, judged on the true residual ----------
def test_dic_diagonal_matches_the_incomplete_factorisation():
    """diag(W D̃⁻¹ Wᵀ) = diag(A), W = D̃ + L, on the particle matrix (no fill-in)."""
    indptr, indices, data = _particle_matrix(n_side=10)
    n = indptr.size - 1
    lp, li, lv, up, ui, uv, diag = split_triangles(indptr, indices, data)
    dt, bad = dic_diagonal(lp, li, lv, diag)
    assert bad == -1
    lo = sp.csr_matrix((lv, li, lp), shape=(n, n))
    a = sp.csr_matrix((data, indices, indptr), shape=(n, n))
    assert abs(sp.csr_matrix((uv, ui, up), shape=(n, n)) - lo.T).max() == 0.0
    assert np.array_equal(diag, a.diagonal())
    w = lo + sp.diags(dt)
    m = (w @ sp.diags(1.0 / dt) @ w.T).toarray()
    assert np.allclose(np.diag(m), diag, rtol=1e-13, atol=0.0)
    assert np.all(dt > 0) and np.all(dt <= diag)
    # the sweeps want each lower row by ascending, each upper row by descending column
    assert all(np.all(np.diff(li[lp[i]:lp[i + 1]].astype(np.int64)) > 0) for i in range(n))
    assert all(np.all(np.diff(ui[up[i]:up[i + 1]].astype(np.int64)) < 0) for i in range(n))


def test_mic_diagonal_matches_the_row_sums():
    """MIC(0), alpha = 1: the row sums of W D̃⁻¹ Wᵀ are those of A; alpha = 0 is DIC bit for bit."""
    indptr, indices, data = _particle_matrix(n_side=10, shift=0.05)
    n = indptr.size - 1
    lp, li, lv, up, ui, uv, diag = split_triangles(indptr, indices, data)
    d0, bad0 = mic_diagonal(lp, li, lv, up, uv, diag, 0.0)
    assert bad0 == -1 and np.array_equal(d0, dic_diagonal(lp, li, lv, diag)[0])
    d1, bad = mic_diagonal(lp, li, lv, up, uv, diag, 1.0)
    assert bad == -1 and np.all(d1 > 0) and np.all(d1 < d0 * (1 + 1e-12))
    a = sp.csr_matrix((data, indices, indptr), shape=(n, n))
    w = sp.csr_matrix((lv, li, lp), shape=(n, n)) + sp.diags(d1)
    m = (w @ sp.diags(1.0 / d1) @ w.T).toarray()
    safe = d1 >= 0.25 * diag  # rows where the safeguard did not take the DIC pivot
    assert safe.mean() > 0.9
    rows = np.flatnonzero(safe)
    assert np.allclose(m.sum(axis=1)[rows], np.asarray(a.sum(axis=1)).ravel()[rows], rtol=0.0,
                       atol=1e-12 * diag.max())


@pytest.mark.parametrize("shift", [0.05, 1e-4])
def test_mic_converges_to_the_same_solution_in_fewer_iterations(shift):
    indptr, indices, data = _particle_matrix(shift=shift)
    n = indptr.size - 1
    b = np.random.default_rng(3).standard_normal(n)
    a = sp.csr_matrix((data, indices, indptr), shape=(n, n))
    x0, it0, info0 = pcg_dic(indptr, indices, data, b, np.zeros(n), 1e-8, 0.0, 1000)
    x1, it1, info1 = pcg_dic(indptr, indices, data, b, np.zeros(n), 1e-8, 0.0, 1000, 0.97)
    assert info0 == info1 == 0 and it1 < it0
    for x in (x0, x1):
        assert np.linalg.norm(b - a @ x) < 1e-8 * np.linalg.norm(b)


@pytest.mark.parametrize("shift, warm", [(0.05, False), (0.05, True), (1e-4, True)])
def test_pcg_dic_meets_the_true_residual_test_in_fewer_iterations(shift, warm):
    indptr, indices, data = _particle_matrix(shift=shift)
    n = indptr.size - 1
    rng = np.random.default_rng(7)
    b = rng.standard_normal(n)
    x0 = b + 0.1 * rng.standard_normal(n) if warm else np.zeros(n)
    a = sp.csr_matrix((data, indices, indptr), shape=(n, n))
    _, it_j, _ = pcg_jacobi(indptr, indices, data, b, x0, 1e-8, 0.0, 1000)
    x, it, info = pcg_dic(indptr, indices, data, b, x0, 1e-8, 0.0, 1000)
    assert info == 0
    assert np.linalg.norm(b - a @ x) < 1e-8 * np.linalg.norm(b)  # scipy's rule, on the true residual
    assert it < 0.6 * it_j  # the preconditioner pays (2.5x fewer on the ISPH PPE)
    exact = spla.spsolve(a.tocsc(), b)
    # error <= cond * residual; cond of these matrices < 1e4 (shift 1e-4: < 1e5)
    assert np.abs(x - exact).max() < 1e-8 * 1e5 * np.abs(exact).max()
    x2, it2, info2 = pcg_dic(indptr, indices, data, b, x0, 1e-11, 0.0, 1000)
    assert info2 == 0 and it2 > it
    assert np.linalg.norm(b - a @ x2) < 1e-11 * np.linalg.norm(b)


def test_pcg_dic_edge_cases():
    indptr, indices, data = _particle_matrix(shift=1e-4)
    n = indptr.size - 1
    b = np.random.default_rng(1).standard_normal(n)
    x, it, info = pcg_dic(indptr, indices, data, np.zeros(n), np.ones(n), 1e-8, 0.0, 1000)
    assert (it, info) == (0, 0) and np.array_equal(x, np.zeros(n))
    exact = spla.spsolve(sp.csr_matrix((data, indices, indptr), shape=(n, n)).tocsc(), b)
    x, it, info = pcg_dic(indptr, indices, data, b, exact, 1e-8, 0.0, 1000)  # already converged
    assert (it, info) == (0, 0) and np.array_equal(x, exact)
    x, it, info = pcg_dic(indptr, indices, data, b, np.zeros(n), 1e-8, 0.0, 3)
    assert (it, info) == (3, 3) and np.all(np.isfinite(x))
    bad = data.copy()
    bad[indptr[5]] = -1.0  # negative diagonal: not positive definite
    x0 = np.full(n, 2.0)
    x, it, info = pcg_dic(indptr, indices, bad, b, x0, 1e-8, 0.0, 1000)
    assert (it, info) == (0, -1) and np.array_equal(x, x0)


def test_cg_dic_run_agrees_with_direct_like_cg():
    """Short T22-A70 collapse (dx = 1 cm, 0.1 s): cg_dic and cg both follow the direct solve; the
    difference of each from it is solver-tolerance noise amplified by the flow (measured max KE
    difference / max KE: cg 6.3e-5, cg_dic 5.8e-5; bound 2e-4 for both)."""
    from granudep.isph.api import run_isph
    runs = {s: run_isph("T22-A70", dx=0.01, t_end=0.1, **{"numerics.pressure_solver": s,
                                                          "numerics.viscous_solver": s})
            for s in ("direct", "cg", "cg_dic")}
    ke = {s: ds.kinetic_energy.values for s, ds in runs.items()}
    scale = np.abs(ke["direct"]).max()
    d_cg = np.abs(ke["cg"] - ke["direct"]).max() / scale
    d_dic = np.abs(ke["cg_dic"] - ke["direct"]).max() / scale
    assert d_cg < 2e-4 and d_dic < 2e-4
    assert np.array_equal(runs["cg_dic"].front_position.values, runs["direct"].front_position.values)


def test_dic_pair_equals_two_single_dic_solves_bitwise():
    indptr, indices, data = _particle_matrix(shift=0.05)
    n = indptr.size - 1
    rng = np.random.default_rng(11)
    diag_v = data[indptr[:-1]] + 0.3 * rng.random(n)
    data_v = data.copy()
    data_v[indptr[:-1]] = diag_v
    bu, bv = rng.standard_normal(n), 0.01 * rng.standard_normal(n)
    xu, itu, infou, xv, itv, infov = pcg_dic_pair((indptr, indices, data), diag_v, bu, bu, bv, bv, 1e-8, 0.0, 1000)
    xu1, itu1, infou1 = pcg_dic(indptr, indices, data, bu, bu, 1e-8, 0.0, 1000)
    xv1, itv1, infov1 = pcg_dic(indptr, indices, data_v, bv, bv, 1e-8, 0.0, 1000)
    assert (infou, infov, infou1, infov1) == (0, 0, 0, 0)
    assert (itu, itv) == (itu1, itv1) and itu != itv and itu > 3
    assert np.array_equal(xu, xu1) and np.array_equal(xv, xv1)
    xu, itu, infou, xv, itv, infov = pcg_dic_pair((indptr, indices, data), diag_v, bu, bu, bv, bv, 1e-8, 0.0, 1000,
                                                  0.97)
    xu2, itu2, _ = pcg_dic(indptr, indices, data, bu, bu, 1e-8, 0.0, 1000, 0.97)
    xv2, itv2, _ = pcg_dic(indptr, indices, data_v, bv, bv, 1e-8, 0.0, 1000, 0.97)
    assert (itu, itv) == (itu2, itv2) and np.array_equal(xu, xu2) and np.array_equal(xv, xv2)
    # zero right-hand side on one side; maxiter on the other; breakdown (negative diagonal) on v
    xu, itu, infou, xv, itv, infov = pcg_dic_pair((indptr, indices, data), diag_v, np.zeros(n), bu, bv, bv,
                                                  1e-8, 0.0, 2)
    xv2, itv2, infov2 = pcg_dic(indptr, indices, data_v, bv, bv, 1e-8, 0.0, 2)
    assert (itu, infou) == (0, 0) and np.array_equal(xu, np.zeros(n))
    assert (itv, infov) == (2, 2) == (itv2, infov2) and np.array_equal(xv, xv2)
    bad_v = diag_v.copy()
    bad_v[3] = -1.0
    xu, itu, infou, xv, itv, infov = pcg_dic_pair((indptr, indices, data), bad_v, bu, bu, bv, bv, 1e-8, 0.0, 1000)
    assert infov == -1 and np.array_equal(xv, bv)
    assert (itu, infou) == (itu1, 0) and np.array_equal(xu, xu1)


def test_dic_two_threads_equals_the_pair_bitwise():
    """pcg_dic_two (u and v as two pcg_dic solves, one per thread) gives the pair's results bit for bit."""
    from granudep.isph.cg_dic import pcg_dic_two
    indptr, indices, data = _particle_matrix(shift=0.05)
    n = indptr.size - 1
    rng = np.random.default_rng(12)
    diag_v = data[indptr[:-1]] + 0.3 * rng.random(n)
    bu, bv = rng.standard_normal(n), 0.01 * rng.standard_normal(n)
    a = pcg_dic_pair((indptr, indices, data), diag_v, bu, bu, bv, bv, 1e-8, 0.0, 1000, 0.97)
    b = pcg_dic_two((indptr, indices, data), diag_v, bu, bu, bv, bv, 1e-8, 0.0, 1000, 0.97)
    assert a[1] > 3 and a[2] == a[5] == 0
    for p, q in zip(a, b):
        assert np.array_equal(p, q)
    bad_v = diag_v.copy()
    bad_v[3] = -1.0  # breakdown on the v side only
    a = pcg_dic_pair((indptr, indices, data), bad_v, bu, bu, bv, bv, 1e-8, 0.0, 1000, 0.0)
    b = pcg_dic_two((indptr, indices, data), bad_v, bu, bu, bv, bv, 1e-8, 0.0, 1000, 0.0)
    assert a[5] == b[5] == -1 and a[2] == b[2] == 0 and np.array_equal(a[0], b[0])


def test_dot_is_blas_up_to_10000_then_a_fixed_order_sum():
    """(M)IC-CG inner products: BLAS ddot (bit for bit) up to DOT_BLAS_MAX entries; above it (where
    OpenBLAS would thread the sum) eight interleaved serial partial sums, added pairwise."""
    from granudep.isph.linsolve import DOT_BLAS_MAX, _dot
    rng = np.random.default_rng(5)
    a, b = rng.standard_normal(DOT_BLAS_MAX), rng.standard_normal(DOT_BLAS_MAX)
    assert _dot(a, b) == np.dot(a, b)
    n = DOT_BLAS_MAX + 13
    a, b = rng.standard_normal(n), rng.standard_normal(n)
    s = [0.0] * 8
    m = n - n % 8
    for i in range(m):  # reference, test only
        s[i % 8] += a[i] * b[i]
    for i in range(m, n):
        s[0] += a[i] * b[i]
    ref = ((s[0] + s[1]) + (s[2] + s[3])) + ((s[4] + s[5]) + (s[6] + s[7]))
    assert _dot(a, b) == ref
    assert abs(ref - np.dot(a, b)) < 1e-12 * np.abs(a * b).sum()


# --- two-level CG (Jacobi + aggregation coarse space) ---------------------------------------------

def _wide_matrix(n_side=40, shift=1e-3, seed=3):
    """A 2-ring-like SPD particle matrix (support 5.2 spacings, as the adjoint-pair PPE's D Dᵀ)."""
    return _particle_matrix(n_side, shift, seed, radius=5.2, random_shift=False)


def test_aggregates_cover_every_node_once_and_are_connected():
    indptr, indices, data = _wide_matrix()
    n = indptr.size - 1
    agg, nc = aggregate_nodes(indptr, indices, data)
    assert agg.min() == 0 and agg.max() == nc - 1
    assert np.unique(agg).size == nc                 # no empty aggregate: P has full column rank
    assert nc < n / 10                               # a coarse space, not a copy
    for i in range(n):                               # every node couples to another node of its aggregate
        nb = indices[indptr[i] + 1:indptr[i + 1]]
        if (agg == agg[i]).sum() > 1:
            assert np.any(agg[nb] == agg[i])


def test_coarse_matrix_is_the_galerkin_product():
    indptr, indices, data = _wide_matrix(n_side=16)
    n = indptr.size - 1
    agg, nc = aggregate_nodes(indptr, indices, data)
    a = sp.csr_matrix((data, indices, indptr), shape=(n, n)).toarray()
    p = np.zeros((n, nc))
    p[np.arange(n), agg] = 1.0
    assert np.allclose(coarse_matrix(indptr, indices, data, agg, nc), p.T @ a @ p, rtol=1e-13, atol=1e-13)


def test_two_level_preconditioner_is_symmetric_positive_definite():
    indptr, indices, data = _wide_matrix(n_side=14)
    n = indptr.size - 1
    agg, nc = aggregate_nodes(indptr, indices, data)
    lc = np.linalg.cholesky(coarse_matrix(indptr, indices, data, agg, nc))
    dinv = 1.0 / data[indptr[:-1]]
    m = np.zeros((n, n))
    z, rc, yc = np.empty(n), np.empty(nc), np.empty(nc)
    for k in range(n):
        e = np.zeros(n)
        e[k] = 1.0
        _two_level_apply(lc, np.ascontiguousarray(lc.T), agg, dinv, e, z, rc, yc)
        m[:, k] = z
    p = np.zeros((n, nc))
    p[np.arange(n), agg] = 1.0
    a = sp.csr_matrix((data, indices, indptr), shape=(n, n)).toarray()
    assert np.allclose(m, np.diag(dinv) + p @ np.linalg.solve(p.T @ a @ p, p.T), rtol=1e-10, atol=1e-12)
    assert np.allclose(m, m.T, atol=1e-12 * np.abs(m).max())
    assert np.linalg.eigvalsh(0.5 * (m + m.T)).min() > 0.0


@pytest.mark.parametrize("warm", [False, True])
def test_two_level_cg_meets_the_true_residual_test(warm):
    indptr, indices, data = _wide_matrix()
    n = indptr.size - 1
    rng = np.random.default_rng(1)
    b = rng.normal(size=n)
    a = sp.csr_matrix((data, indices, indptr), shape=(n, n))
    x_ref = spla.spsolve(a.tocsc(), b)
    x0 = x_ref + 0.01 * rng.normal(size=n) if warm else np.zeros(n)
    x, it, info = pcg_two_level(indptr, indices, data, b, x0, 1e-10, 0.0, 2000)
    assert info == 0 and it > 0
    assert np.linalg.norm(b - a @ x) < 1e-10 * np.linalg.norm(b)
    assert np.allclose(x, x_ref, rtol=1e-6, atol=1e-8 * np.abs(x_ref).max())


def test_two_level_iterations_barely_grow_with_the_problem_size():
    """Doubling the lattice side (4x the nodes): Jacobi-CG's iterations double (the smooth modes),
    the two-level CG's grow by less than a third (measured 88 -> 165 and 55 -> 64)."""
    its = {}
    for side in (30, 60):
        indptr, indices, data = _wide_matrix(n_side=side)
        n = indptr.size - 1
        b = np.random.default_rng(1).normal(size=n)
        its[side] = (pcg_two_level(indptr, indices, data, b, np.zeros(n), 1e-10, 0.0, 3000)[1],
                     pcg_jacobi(indptr, indices, data, b, np.zeros(n), 1e-10, 0.0, 3000)[1])
    assert its[60][1] > 1.6 * its[30][1]
    assert its[60][0] < 1.3 * its[30][0]
    assert its[60][0] < 0.5 * its[60][1]


def test_two_level_cg_edge_cases():
    indptr, indices, data = _wide_matrix(n_side=10)
    n = indptr.size - 1
    x, it, info = pcg_two_level(indptr, indices, data, np.zeros(n), np.ones(n), 1e-8, 0.0, 100)
    assert it == 0 and info == 0 and not x.any()
    b = np.ones(n)
    b[3] = np.nan
    assert pcg_two_level(indptr, indices, data, b, np.zeros(n), 1e-8, 0.0, 100)[2] == NONFINITE
    # a negative-definite matrix: breakdown reported, never raised
    assert pcg_two_level(indptr, indices, -data, np.ones(n), np.zeros(n), 1e-8, 0.0, 100)[2] == BREAKDOWN
    # not converged within maxiter: maxiter returned
    assert pcg_two_level(indptr, indices, data, np.ones(n), np.zeros(n), 1e-14, 0.0, 2)[1:] == (2, 2)
