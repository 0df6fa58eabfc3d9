"""The ISPH solver pins the BLAS its numba kernels call to one thread (linsolve.pin_blas_to_one_thread)."""
import threadpoolctl

from granudep.isph.config import load_config
from granudep.isph.solver import IsphSolver


def test_solver_runs_blas_on_one_thread():
    IsphSolver(load_config("T22-A70", **{"numerics.dx": 0.02}))
    blas = [d for d in threadpoolctl.threadpool_info() if d["user_api"] == "blas"]
    assert blas, "no BLAS library loaded"
    assert all(d["num_threads"] == 1 for d in blas), blas
