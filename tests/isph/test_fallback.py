"""The linear solver never crashes a run: a CG breakdown (zero/negative curvature,
NaN, a ZeroDivisionError, no convergence) falls back to SuperLU for that step and is counted in
the run file (``linear_solver_fallbacks``)."""
import types

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from granudep.isph import linear_systems as linear_mod
from granudep.isph import stepper
from granudep.isph.api import run_isph
from granudep.isph.config import load_config
from granudep.isph.cg_dic import pcg_dic, pcg_dic_pair
from granudep.isph.linsolve import BREAKDOWN, NONFINITE, pcg_jacobi, pcg_jacobi_pair
from granudep.isph.errors import IsphBlowUp
from granudep.isph.stepper import IsphSolver

from test_linsolve import _particle_matrix


def _indefinite(f=0.9):
    """The particle matrix (graph Laplacian, no shift) with its diagonal scaled by f < 1: symmetric,
    positive diagonal, negative eigenvalues (lowest -0.085 for f = 0.9), nonsingular."""
    indptr, indices, data = _particle_matrix(shift=0.0)
    data = data.copy()
    data[indptr[:-1]] *= f
    return indptr, indices, data


def _dense(indptr, indices, data):
    n = indptr.size - 1
    return sp.csr_matrix((data, indices, indptr), shape=(n, n))


def test_planted_indefinite_matrix_is_a_reported_breakdown_not_an_exception():
    indptr, indices, data = _indefinite()
    n = indptr.size - 1
    assert np.linalg.eigvalsh(_dense(indptr, indices, data).toarray())[0] < -0.05  # really indefinite
    b = np.random.default_rng(0).standard_normal(n)
    x0 = np.zeros(n)
    for info in (pcg_jacobi(indptr, indices, data, b, x0, 1e-8, 0.0, 1000)[2],
                 pcg_dic(indptr, indices, data, b, x0, 1e-8, 0.0, 1000, 0.0)[2]):
        assert info == BREAKDOWN  # p·Ap <= 0 met inside the iteration
    assert pcg_dic(indptr, indices, data, b, x0, 1e-8, 0.0, 1000, 0.97)[2] == -1  # MIC pivot breakdown
    r = pcg_jacobi_pair((indptr, indices, data), data[indptr[:-1]] + 10.0, b, x0, b, x0, 1e-8, 0.0, 1000)
    assert r[2] == BREAKDOWN and r[5] == 0  # the u side broke down, the (definite) v side converged
    r = pcg_dic_pair((indptr, indices, data), data[indptr[:-1]] + 10.0, b, x0, b, x0, 1e-8, 0.0, 1000, 0.0)
    assert r[2] == BREAKDOWN and r[5] == 0


def test_zero_curvature_and_zero_diagonal_do_not_raise():
    # A = [[1, 2], [2, 1]] (eigenvalues 3, -1) with b on the -1 eigenvector: p·Ap < 0 at once;
    # before, the zero-diagonal and zero-curvature cases raised ZeroDivisionError
    indptr = np.array([0, 2, 4])
    indices = np.array([0, 1, 1, 0])
    data = np.array([1.0, 2.0, 1.0, 2.0])
    b = np.array([1.0, -1.0])
    x, it, info = pcg_jacobi(indptr, indices, data, b, np.zeros(2), 1e-8, 0.0, 100)
    assert (it, info) == (0, BREAKDOWN) and np.all(np.isfinite(x))
    zero_diag = np.array([0.0, 2.0, 1.0, 2.0])
    assert pcg_jacobi(indptr, indices, zero_diag, b, np.zeros(2), 1e-8, 0.0, 100)[2] == BREAKDOWN
    assert pcg_dic(indptr, indices, zero_diag, b, np.zeros(2), 1e-8, 0.0, 100)[2] == -1


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_non_finite_rhs_is_reported_at_once(bad):
    indptr, indices, data = _particle_matrix()
    n = indptr.size - 1
    b = np.ones(n)
    b[7] = bad
    x0 = np.zeros(n)
    assert pcg_jacobi(indptr, indices, data, b, x0, 1e-8, 0.0, 1000)[1:] == (0, NONFINITE)
    assert pcg_dic(indptr, indices, data, b, x0, 1e-8, 0.0, 1000, 0.97)[1:] == (0, NONFINITE)
    ok = np.ones(n)
    for pair in (pcg_jacobi_pair((indptr, indices, data), data[indptr[:-1]], b, x0, ok, x0, 1e-8, 0.0, 1000),
                 pcg_dic_pair((indptr, indices, data), data[indptr[:-1]], b, x0, ok, x0, 1e-8, 0.0, 1000, 0.97)):
        assert pair[2] == NONFINITE and pair[5] == 0 and np.all(np.isfinite(pair[3]))


def _solver():
    return IsphSolver(load_config("T22-A70", dx=0.01, t_end=0.05))


@pytest.mark.parametrize("method", ["cg_dic", "cg", "cg_two_level"])
def test_solver_falls_back_to_direct_on_an_indefinite_matrix(method):
    s = _solver()
    indptr, indices, data = _indefinite()
    n = indptr.size - 1
    b = np.random.default_rng(2).standard_normal(n)
    x = s.linear.solve_cg(indptr, indices, data, b, np.zeros(n), "ppe", solver=method)
    dic = method == "cg_dic"
    exact = spla.spsolve(_dense(indptr, indices, data).tocsc(), b)
    assert s.stats.fallbacks == 1
    assert np.abs(x - exact).max() < 1e-9 * np.abs(exact).max()
    xu, xv = s.linear.solve_cg_pair(indptr, indices, data, data[indptr[:-1]] + 10.0, b, b, b, b, dic=dic)
    assert s.stats.fallbacks == 2  # the u system only
    assert np.abs(xu - exact).max() < 1e-9 * np.abs(exact).max()


def test_solver_nan_rhs_falls_back_and_the_nan_then_stops_the_run(monkeypatch, tmp_path):
    """A NaN in the PPE right-hand side at step 3: counted fallback, the direct solve's NaN pressure
    stops the run as a blow-up (not a crash) with the partial output written."""
    real = stepper.approximate.assemble_ppe
    calls = [0]

    def planted(*a):
        pi, pj, pd, rhs = real(*a)
        calls[0] += 1
        if calls[0] == 3:
            rhs = rhs.copy()
            rhs[len(rhs) // 2] = np.nan
        return pi, pj, pd, rhs
    monkeypatch.setattr(stepper.approximate, "assemble_ppe", planted)
    out = tmp_path / "nan.nc"
    with pytest.raises(IsphBlowUp, match="non-finite"):
        run_isph("T22-A70", output=out, dx=0.01, t_end=0.05, **{"numerics.projection": "approximate"})
    import xarray as xr
    ds = xr.open_dataset(tmp_path / "nan.failed.nc")
    assert ds.attrs["status"].startswith("failed: non-finite")
    assert ds.attrs["linear_solver_fallbacks"] == 1


@pytest.mark.parametrize("projection, cg, solver", [("approximate", "pcg_dic", "cg_dic"),
                                                    ("adjoint_pair", "pcg_ssor_deflated", "cg_dic"),
                                                    ("adjoint_pair", "pcg_two_level", "cg_two_level"),
                                                    ("adjoint_pair/matrix_free", "pcg_two_level_free", "cg_two_level")])
@pytest.mark.parametrize("mode", ["breakdown", "raise", "nan"])
def test_run_survives_a_cg_failure_and_counts_it(monkeypatch, mode, projection, cg, solver):
    """The PPE CG fails once (planted: a breakdown code, a ZeroDivisionError or a NaN solution) at
    step 4: the step is solved by SuperLU and the run goes on; the output counts one fallback."""
    real = getattr(linear_mod, cg)
    calls = [0]

    def planted(*a):
        calls[0] += 1
        if calls[0] == 4:
            if mode == "raise":
                raise ZeroDivisionError("division by zero")
            x, it, info = real(*a)
            if mode == "nan":
                return np.full_like(x, np.nan), it, 0
            return x, it, BREAKDOWN
        return real(*a)
    monkeypatch.setattr(linear_mod, cg, planted)
    projection, _, operator = projection.partition("/")
    ds = run_isph("T22-A70", dx=0.01, t_end=0.05, **{"numerics.projection": projection,
                                                     "numerics.pressure_solver": solver,
                                                     "numerics.ppe_operator": operator or "assembled"})
    assert not ds.attrs["status"].startswith("failed")
    assert ds.attrs["linear_solver_fallbacks"] == 1
    assert ds.attrs["n_steps"] > 4 and calls[0] > 4
    assert np.isfinite(ds.pressure.values).all()


def test_singular_direct_solve_is_a_blow_up_not_a_crash():
    s = _solver()
    indptr = np.array([0, 2, 4])
    indices = np.array([0, 1, 1, 0])
    data = np.array([1.0, 1.0, 1.0, 1.0])  # [[1, 1], [1, 1]]: exactly singular
    with pytest.raises(IsphBlowUp, match="direct solver failed"):
        s.linear.solve_cg(indptr, indices, data, np.array([1.0, 0.0]), np.zeros(2), "ppe", solver="cg_dic")
    assert s.stats.fallbacks == 1


def test_amg_pressure_solver_runs_and_agrees_with_cg_dic():
    """numerics.pressure_solver amg_sa / amg_rs (pyamg): a short collapse without fallbacks, pressure
    within the round-off spread of the default at t = 0.02 s (the trajectories differ at solver
    tolerance, see docs/model.md "Linear solvers")."""
    pytest.importorskip("pyamg")
    ref = run_isph("T22-A70", dx=0.01, t_end=0.02)
    for m in ("amg_sa", "amg_rs"):
        ds = run_isph("T22-A70", dx=0.01, t_end=0.02, **{"numerics.pressure_solver": m})
        assert ds.attrs["linear_solver_fallbacks"] == 0 and ds.attrs["ppe_iterations"] > 0
        assert ds.attrs["ppe_iterations"] < ref.attrs["ppe_iterations"]  # fewer (but costlier) iterations
        p, q = ds.pressure.values[-1], ref.pressure.values[-1]
        assert np.abs(p - q).max() < 1e-3 * np.abs(q).max()


def test_amg_without_pyamg_is_a_clear_error(monkeypatch):
    from granudep.isph import amg
    monkeypatch.setattr(amg, "have_pyamg", lambda: False)
    with pytest.raises(ImportError, match="pyamg"):
        IsphSolver(load_config("T22-A70", dx=0.01, **{"numerics.pressure_solver": "amg_sa"}))


def test_every_cg_pressure_solver_name_has_a_registry_entry():
    """The names numerics.pressure_solver accepts and the CG registry agree: a CG name the config
    allows but the registry lacks would fail at the first solve, not at the edge."""
    import dataclasses
    from granudep.isph.config import Numerics
    from granudep.isph.linear_systems import CG_SOLVERS, ppe_solver_name
    choices = next(f for f in dataclasses.fields(Numerics) if f.name == "pressure_solver").metadata["choices"]
    cg_names = [c for c in choices if c != "direct" and not c.startswith("amg_")]
    assert cg_names and set(cg_names) <= set(CG_SOLVERS)
    for projection in ("adjoint_pair", "approximate"):
        for c in cg_names:
            num = types.SimpleNamespace(pressure_solver=c, projection=projection)
            assert ppe_solver_name(num) in CG_SOLVERS
