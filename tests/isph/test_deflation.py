"""Deflated SSOR-CG (granudep.isph.deflation): each kernel against a plain NumPy/SciPy
reference, the solver against the direct solve and the SSOR-CG it deflates."""
import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from granudep.isph.deflation import _sgs_with_product, coarse_operators, pcg_ssor_deflated
from granudep.isph.cg_dic import pcg_dic_split, split_triangles
from granudep.isph.cg_two_level import aggregate_nodes, aggregate_rows, coarse_factor
from granudep.isph.linsolve import BREAKDOWN, NONFINITE

from test_linsolve import _particle_matrix


def _wide(n_side=30, shift=1e-3, seed=3):
    """A 2-ring-like SPD particle matrix (support 5.2 spacings, as the adjoint-pair PPE's D Dᵀ), as
    CSR and as the triangles the PPE assembly gives the solver."""
    indptr, indices, data = _particle_matrix(n_side, shift, seed, radius=5.2, random_shift=False)
    n = indptr.size - 1
    a = sp.csr_matrix((data, indices, indptr), shape=(n, n))
    return a, split_triangles(indptr, indices, data)


def _prolongation(agg, nc):
    n = agg.size
    return sp.csr_matrix((np.ones(n), (np.arange(n), agg)), shape=(n, nc))


def test_aggregates_of_the_triangles_are_those_of_the_csr_matrix():
    """aggregate_rows on the two triangles (diagonal left out) gives the aggregates of the CSR matrix
    (diagonal first, neighbours unsorted; random weights: no ties in pass 2), a coarse space."""
    indptr, indices, data = _particle_matrix(24, 1e-3, 5, radius=5.2, random_shift=False)
    rng = np.random.default_rng(0)
    n = indptr.size - 1
    a = sp.csr_matrix((data, indices, indptr), shape=(n, n))
    noise = sp.triu(a, 1).tocoo()
    noise.data = noise.data * (1.0 + 0.1 * rng.random(noise.data.size))   # still symmetric
    a = (sp.diags(a.diagonal()) + noise + noise.T).tocsr()
    agg_ref, nc_ref = aggregate_nodes(a.indptr.astype(np.int64), a.indices.astype(np.int64), a.data)
    agg, nc = aggregate_rows(*split_triangles(a.indptr.astype(np.int64), a.indices.astype(np.int64), a.data)[:6])
    assert nc == nc_ref and np.array_equal(agg, agg_ref)
    assert np.unique(agg).size == nc and nc < n / 10


def test_coarse_operators_are_a_p_and_the_galerkin_product():
    a, tri = _wide(n_side=20)
    agg, nc = aggregate_rows(*tri[:6])
    app, api, apv, ac = coarse_operators(*tri, agg, nc)
    p = _prolongation(agg, nc)
    ap = sp.csr_matrix((apv, api, app), shape=(a.shape[0], nc))
    assert np.allclose(ap.toarray(), (a @ p).toarray(), rtol=1e-13, atol=1e-13)
    assert np.allclose(ac, (p.T @ a @ p).toarray(), rtol=1e-12, atol=1e-12)
    assert np.all(np.diff(app) >= 1) and api.size < 8 * a.shape[0]   # the own aggregate, a few others


def test_sweeps_give_the_ssor_inverse_and_its_product_with_a():
    a, tri = _wide(n_side=16)
    n = a.shape[0]
    lp, li, lv, up, ui, uv, diag = tri
    r = np.random.default_rng(2).normal(size=n)
    w, y, ay = np.empty(n), np.empty(n), np.empty(n)
    _sgs_with_product(tri, 1.0 / diag, r, w, y, ay)
    lower = sp.tril(a, -1).toarray()
    d = np.diag(diag)
    s = (d + lower) @ np.linalg.inv(d) @ (d + lower.T)          # symmetric Gauss-Seidel matrix
    assert np.allclose(y, np.linalg.solve(s, r), rtol=1e-10, atol=1e-12 * np.abs(y).max())
    assert np.allclose(ay, a @ y, rtol=1e-10, atol=1e-12 * np.abs(ay).max())


@pytest.mark.parametrize("warm", [False, True])
def test_deflated_cg_meets_the_true_residual_test(warm):
    a, tri = _wide()
    n = a.shape[0]
    rng = np.random.default_rng(1)
    b = rng.normal(size=n)
    x_ref = spla.spsolve(a.tocsc(), b)
    x0 = x_ref + 0.01 * rng.normal(size=n) if warm else np.zeros(n)
    x, it, info = pcg_ssor_deflated(tri, b, x0, 1e-10, 0.0, 2000)
    assert info == 0 and it > 0
    assert np.linalg.norm(b - a @ x) < 1e-10 * np.linalg.norm(b)
    assert np.allclose(x, x_ref, rtol=1e-6, atol=1e-8 * np.abs(x_ref).max())


def test_deflation_takes_out_the_growth_of_the_ssor_iterations():
    """Doubling the lattice side (4x the nodes): the SSOR-CG's iterations grow by about sqrt(2)
    (the smooth modes), the deflated CG's by less than a fifth and stay below half the SSOR-CG's
    (measured 50 -> 71 and 21 -> 24)."""
    its = {}
    for side in (30, 60):
        a, tri = _wide(n_side=side)
        n = a.shape[0]
        b = np.random.default_rng(1).normal(size=n)
        its[side] = (pcg_ssor_deflated(tri, b, np.zeros(n), 1e-10, 0.0, 3000)[1],
                     pcg_dic_split(tri, b, np.zeros(n), 1e-10, 0.0, 3000, -1.0)[1])
    assert its[60][1] > 1.3 * its[30][1]
    assert its[60][0] < 1.2 * its[30][0]
    assert its[60][0] < 0.5 * its[60][1]


def test_the_preconditioned_operator_is_symmetric_on_the_deflated_subspace():
    """A-DEF2: z = (I − Q A) S⁻¹ r. On residuals with Pᵀ r = 0 (the iteration keeps them so),
    r₁ · z(r₂) = r₂ · z(r₁), and r · z(r) > 0."""
    a, tri = _wide(n_side=12)
    n = a.shape[0]
    lp, li, lv, up, ui, uv, diag = tri
    agg, nc = aggregate_rows(*tri[:6])
    p = _prolongation(agg, nc).toarray()
    ad = a.toarray()
    q = p @ np.linalg.solve(p.T @ ad @ p, p.T)
    lower = sp.tril(a, -1).toarray()
    d = np.diag(diag)
    sinv = np.linalg.inv((d + lower) @ np.linalg.inv(d) @ (d + lower.T))
    m = (np.eye(n) - q @ ad) @ sinv
    proj = np.eye(n) - ad @ q                       # residuals with Pᵀ r = 0
    rng = np.random.default_rng(4)
    r1, r2 = proj @ rng.normal(size=n), proj @ rng.normal(size=n)
    assert abs(p.T @ r1).max() < 1e-10 * abs(r1).max()
    assert abs(r1 @ m @ r2 - r2 @ m @ r1) < 1e-10 * abs(r1 @ m @ r2)
    assert r1 @ m @ r1 > 0 and r2 @ m @ r2 > 0


def test_coarse_factor_refuses_a_matrix_that_is_not_positive_definite():
    """Reported (the solvers return BREAKDOWN and the caller falls back), never raised."""
    assert coarse_factor(np.array([[1.0, 2.0], [2.0, 1.0]]))[2] is False
    assert coarse_factor(np.array([[-1.0, 0.0], [0.0, 1.0]]))[2] is False
    assert coarse_factor(np.array([[2.0, 1.0], [1.0, 2.0]]))[2] is True


def test_deflated_cg_edge_cases():
    a, tri = _wide(n_side=10)
    n = a.shape[0]
    x, it, info = pcg_ssor_deflated(tri, np.zeros(n), np.ones(n), 1e-8, 0.0, 100)
    assert it == 0 and info == 0 and not x.any()
    b = np.ones(n)
    b[3] = np.nan
    assert pcg_ssor_deflated(tri, b, np.zeros(n), 1e-8, 0.0, 100)[2] == NONFINITE
    lp, li, lv, up, ui, uv, diag = tri
    assert pcg_ssor_deflated((lp, li, -lv, up, ui, -uv, -diag), np.ones(n), np.zeros(n), 1e-8, 0.0, 100)[2] == BREAKDOWN
    x_ref = spla.spsolve(a.tocsc(), np.ones(n))
    assert pcg_ssor_deflated(tri, np.ones(n), x_ref, 1e-8, 0.0, 100)[1] == 0     # already converged
    assert pcg_ssor_deflated(tri, np.ones(n), np.zeros(n), 1e-15, 0.0, 2)[1:] == (2, 2)


def test_below_the_threshold_it_is_the_ssor_cg_bit_for_bit():
    a, tri = _wide(n_side=20)
    n = a.shape[0]
    b = np.random.default_rng(3).normal(size=n)
    below = pcg_ssor_deflated(tri, b, np.zeros(n), 1e-10, 0.0, 500, n + 1)
    ssor = pcg_dic_split(tri, b, np.zeros(n), 1e-10, 0.0, 500, -1.0)
    assert np.array_equal(below[0], ssor[0]) and below[1:] == ssor[1:]
    at = pcg_ssor_deflated(tri, b, np.zeros(n), 1e-10, 0.0, 500, n)      # from the threshold on: deflated
    assert at[2] == 0 and at[1] < ssor[1]


def test_too_many_aggregates_falls_back_to_the_ssor_cg():
    """Above COARSE_MAX aggregates (here a diagonal matrix: one aggregate per node) the solve is
    the SSOR-CG's, bit for bit."""
    n = 3000
    diag = np.linspace(1.0, 2.0, n)
    z = np.zeros(n + 1, np.int64)
    tri = (z, np.empty(0, np.uint32), np.empty(0), z.copy(), np.empty(0, np.uint32), np.empty(0), diag)
    b = np.random.default_rng(0).normal(size=n)
    xd = pcg_ssor_deflated(tri, b, np.zeros(n), 1e-10, 0.0, 100)
    xs = pcg_dic_split(tri, b, np.zeros(n), 1e-10, 0.0, 100, -1.0)
    assert np.array_equal(xd[0], xs[0]) and xd[1:] == xs[1:]


def test_solver_uses_the_deflated_cg_from_the_threshold_on():
    """A short T22-A70 collapse (dx = 1 cm): deflation_min_unknowns = 0 (deflated on every step)
    follows the SSOR-CG run within the solver tolerance amplified by the flow (as the cg / cg_dic
    comparison of test_linsolve does), in fewer PPE iterations."""
    from granudep.isph.config import load_config
    from granudep.isph.stepper import IsphSolver
    out = {}
    for name, k in (("ssor", 10 ** 9), ("deflated", 0)):
        s = IsphSolver(load_config("T22-A70", dx=0.01, **{"numerics.deflation_min_unknowns": k}))
        ke = []
        for _ in range(60):
            dt = s.time_step()
            s.dt = dt
            s.step(dt)
            ke.append(s.kinetic_energy())
        out[name] = (np.array(ke), s.stats.ppe_iters, s.stats.fallbacks)
    assert out["deflated"][2] == 0 and out["ssor"][2] == 0
    assert out["deflated"][1] < out["ssor"][1]
    scale = out["ssor"][0].max()
    assert np.abs(out["deflated"][0] - out["ssor"][0]).max() < 2e-4 * scale


def test_negative_threshold_is_refused_before_any_work():
    from granudep.isph.config import ConfigError, load_config
    with pytest.raises(ConfigError, match="deflation_min_unknowns"):
        load_config("T22-A70", **{"numerics.deflation_min_unknowns": -1})
