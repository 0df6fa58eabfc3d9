"""The fast adjoint-pair PPE paths against the assembled matrix and dense NumPy:
the matrix-free operator (``numerics.ppe_operator: matrix_free``), the PPE assembled as its two
triangles for the SSOR-CG (``numerics.pressure_solver: cg_ssor``), their solvers against SuperLU,
and the configuration errors."""
import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from granudep.config import ConfigError
from granudep.isph import ppe_operator as po
from granudep.isph import projection as pj
from granudep.isph.config import load_config
from granudep.isph.cg_dic import pcg_dic, pcg_dic_split, split_triangles
from granudep.isph.cg_two_level import (free_coarse_matrix, free_aggregates, free_diagonal, free_matvec,
                                        pcg_two_level, pcg_two_level_free)

import test_projection as tp


def _system(stab=0.3, seed=5):
    """The walled cloud's PPE: D in COO, L_c edges, a few Dirichlet particles and the dry walls
    known (known values random), a random node right-hand side; plus the dense operator."""
    c = tp._walled_cloud()
    nf, nw = c["nf"], c["nw"]
    n = nf + nw
    rows, cols, cx, cy = tp._coo(c)
    ei, ej, ea = pj.compact_laplacian_edges(c["pairs"], nf, c["dx"] ** 2, 0.01 * c["h"] ** 2, 1.0)
    dxm, dym = tp._naive_d(c)
    lc = np.zeros((n, n))
    for i, j, a in zip(ei, ej, ea):
        lc[i, i] += a
        lc[j, j] += a
        lc[i, j] -= a
        lc[j, i] -= a
    full = (1.0 - stab) * (dxm @ dxm.T + dym @ dym.T) + stab * lc
    known = np.zeros(n, bool)
    known[:5] = True
    known[nf:] = ~(np.abs(dxm[nf:]).sum(1) > 0)
    unknown = np.full(n, -1, np.int64)
    unk = np.flatnonzero(~known)
    unknown[unk] = np.arange(unk.size)
    p = np.where(known, np.random.default_rng(seed).normal(size=n), 0.0)
    b = np.random.default_rng(seed + 1).normal(size=n)
    args = (po.PPESystem(n, rows, cols, cx, cy, nf, ei, ej, ea, stab, unknown, unk.size), p, b)
    return args, full[np.ix_(unk, unk)], b[unk] - full[np.ix_(unk, np.flatnonzero(known))] @ p[known]


@pytest.mark.parametrize("stab", [0.0, 0.01, 0.3])
def test_matrix_free_operator_is_the_dense_product_and_its_rhs_the_assembled_one(stab):
    args, dense, rhs_ref = _system(stab)
    op, rhs = po.matrix_free_ppe(*args)
    nf = args[0].nf
    m = rhs.size
    scale = np.abs(dense).max()
    assert np.allclose(rhs, rhs_ref, atol=1e-10 * np.abs(rhs_ref).max())
    rng = np.random.default_rng(1)
    for _ in range(3):
        x = rng.normal(size=m)
        out = np.empty(m)
        free_matvec(op, x, np.empty(nf), np.empty(nf), out)
        assert np.allclose(out, dense @ x, atol=1e-12 * scale * np.abs(x).sum())
    assert np.allclose(free_diagonal(op), np.diag(dense), atol=1e-13 * scale)
    # the coarse matrix of any aggregation is Pᵀ A P
    for coarse_max in (1000, 3):
        agg, nc = free_aggregates(op, coarse_max)
        assert agg.min() == 0 and agg.max() == nc - 1
        pm = np.zeros((m, nc))
        pm[np.arange(m), agg] = 1.0
        assert np.allclose(free_coarse_matrix(op, agg, nc), pm.T @ dense @ pm, atol=1e-12 * scale * m)
    # and the assembled CSR holds the same matrix
    indptr, indices, data, rhs_a = po.assemble_adjoint_ppe(*args)
    assert np.allclose(sp.csr_matrix((data, indices, indptr)).toarray(), dense, atol=1e-12 * scale)


@pytest.mark.parametrize("stab", [0.0, 0.01, 0.3])
def test_triangles_are_the_split_of_the_assembled_matrix(stab):
    args, dense, rhs_ref = _system(stab)
    tri, rhs = po.assemble_adjoint_triangles(*args)
    indptr, indices, data, rhs_a = po.assemble_adjoint_ppe(*args)
    ref = split_triangles(indptr, indices, data)
    scale = np.abs(dense).max()
    for name, got, want in zip(("lp", "li", "lv", "up", "ui", "uv", "diag"), tri, ref):
        assert got.dtype == want.dtype, name
        if got.dtype.kind == "u":
            assert np.array_equal(got, want), name       # same pattern, same order in each row
        else:
            assert np.allclose(got, want, atol=1e-13 * scale), name
    assert np.allclose(rhs, rhs_a, atol=1e-12 * np.abs(rhs_a).max())


@pytest.mark.parametrize("stab", [0.0, 0.01, 0.3])
def test_the_rhs_is_the_dense_one_and_the_csr_assembly_s(stab):
    """ppe_rhs (the right-hand side of the triangles and of the matrix-free operator, computed once
    u* is known) is b_U − A_UK p_K of the dense operator, known pressures included, and agrees with
    the CSR product's own right-hand side (a separate code path)."""
    args, dense, rhs_ref = _system(stab)
    assert np.abs(args[-2]).max() > 0                 # the known pressures are not all zero
    rhs = po.ppe_rhs(*args)
    assert np.allclose(rhs, rhs_ref, atol=1e-10 * np.abs(rhs_ref).max())
    assert np.allclose(rhs, po.assemble_adjoint_ppe(*args)[3], atol=1e-12 * np.abs(rhs_ref).max())


def test_fast_ppe_solvers_agree_with_superlu_within_the_cg_tolerance():
    args, dense, rhs_ref = _system(0.01)
    indptr, indices, data, rhs = po.assemble_adjoint_ppe(*args)
    a = sp.csr_matrix((data, indices, indptr)).tocsc()
    exact = spla.spsolve(a, rhs)
    rtol = 1e-10
    x0 = np.zeros(rhs.size)
    op, rhs_f = po.matrix_free_ppe(*args)
    tri, rhs_t = po.assemble_adjoint_triangles(*args)
    sols = {"two_level": pcg_two_level(indptr, indices, data, rhs, x0, rtol, 0.0, 1000),
            "free": pcg_two_level_free(op, rhs_f, x0, rtol, 0.0, 1000),
            "free_two_stage": pcg_two_level_free(op, rhs_f, x0, rtol, 0.0, 1000, 3),
            "ssor_csr": pcg_dic(indptr, indices, data, rhs, x0, rtol, 0.0, 1000, -1.0),
            "ssor_triangles": pcg_dic_split(tri, rhs_t, x0, rtol, 0.0, 1000, -1.0)}
    for name, (x, it, info) in sols.items():
        assert info == 0 and it > 0, name
        # the stopping test holds for the true residual of the assembled matrix
        assert np.linalg.norm(rhs - a @ x) <= 1.01 * rtol * np.linalg.norm(rhs), name
        assert np.linalg.norm(x - exact) <= 1e-5 * np.linalg.norm(exact), name
    # warm start from the solution: nothing to do
    x, it, info = pcg_two_level_free(op, rhs_f, exact, 1e-8, 0.0, 1000)
    assert info == 0 and it <= 1
    # SSOR on the triangles is the CSR path, split, bit for bit
    assert np.array_equal(sols["ssor_csr"][0], pcg_dic_split(split_triangles(indptr, indices, data), rhs, x0, rtol,
                                                             0.0, 1000, -1.0)[0])


def test_fast_ppe_solvers_report_breakdown_and_zero_rhs():
    args, dense, rhs_ref = _system(0.01)
    op, rhs = po.matrix_free_ppe(*args)
    x0 = np.zeros(rhs.size)
    x, it, info = pcg_two_level_free(op, np.zeros_like(rhs), x0, 1e-8, 0.0, 100)
    assert info == 0 and it == 0 and not x.any()
    bad = rhs.copy()
    bad[0] = np.nan
    assert pcg_two_level_free(op, bad, x0, 1e-8, 0.0, 100)[2] < 0
    tri, rhs_t = po.assemble_adjoint_triangles(*args)
    assert pcg_dic_split(tri, bad, x0, 1e-8, 0.0, 100, -1.0)[2] < 0
    neg = list(tri)
    neg[6] = -neg[6]                                  # a negative diagonal: the SSOR pivots refuse it
    assert pcg_dic_split(tuple(neg), rhs_t, x0, 1e-8, 0.0, 100, -1.0)[2] == -1


def test_config_errors_name_the_key_and_the_allowed_values():
    with pytest.raises(ConfigError, match=r"^numerics.ppe_operator: must be one of"):
        load_config("T22-A70", **{"numerics.ppe_operator": "sparse"})
    for solver in ("cg_ssor", "cg_dic"):
        with pytest.raises(ConfigError, match=r"^numerics.ppe_operator: matrix_free needs"):
            load_config("T22-A70", **{"numerics.ppe_operator": "matrix_free", "numerics.pressure_solver": solver})
    with pytest.raises(ConfigError, match=r"^numerics.ppe_operator: matrix_free needs"):
        load_config("T22-A70", **{"numerics.ppe_operator": "matrix_free", "numerics.projection": "approximate",
                                  "numerics.pressure_solver": "cg_two_level"})
    assert load_config("T22-A70", **{"numerics.ppe_operator": "matrix_free",
                                     "numerics.pressure_solver": "cg_two_level"}).numerics.ppe_operator == "matrix_free"
    with pytest.raises(ConfigError, match=r"^numerics.pressure_solver: must be one of"):
        load_config("T22-A70", **{"numerics.pressure_solver": "ssor"})
    cfg = load_config("T22-A70", **{"numerics.pressure_solver": "cg_ssor"})
    assert cfg.numerics.pressure_solver == "cg_ssor"
