"""Algebraic-multigrid preconditioned CG for the PPE (pyamg, optional: ``pip install pyamg``).

``numerics.pressure_solver: amg_sa`` (smoothed aggregation) or ``amg_rs`` (classical Ruge–Stüben):
a fresh hierarchy every step (the matrix pattern changes every step: the neighbour list is rebuilt
and the free-surface set, i.e. the unknowns, moves), one V-cycle per CG iteration, warm start from
the previous pressure, and the same stopping test as ``cg_dic``: the true residual
‖b − A x‖₂ < rtol ‖b‖₂ of the returned x. Measured against ``cg_dic`` (MIC(0)-CG) on T22-A150 PPE
systems at 3.5k–57k unknowns (docs/model.md, "Linear solvers: AMG"): the
iteration count is nearly independent of N (8–11), but the hierarchy set-up alone costs more than
the whole MIC-CG solve at every size measured, so it is not the default.
Return convention of :mod:`.linsolve`: (x, iterations, info), info 0 on convergence,
``maxiter`` when not converged, ``NONFINITE`` for a NaN/inf right-hand side.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .linsolve import NONFINITE


def have_pyamg() -> bool:
    try:
        import pyamg  # noqa: F401
    except ImportError:
        return False
    return True


def amg_pcg(indptr, indices, data, b, x0, rtol, maxiter=200, method="sa"):
    import pyamg
    n = b.size
    bn = float(np.linalg.norm(b))
    if bn == 0.0:
        return b.copy(), 0, 0
    if not np.isfinite(bn):
        return x0.copy(), 0, NONFINITE
    a = sp.csr_matrix((data, indices, indptr), shape=(n, n)).sorted_indices()
    if method == "sa":
        ml = pyamg.smoothed_aggregation_solver(a, symmetry="symmetric", max_coarse=200)
    else:
        ml = pyamg.ruge_stuben_solver(a, max_coarse=200)
    res: list = []
    x = ml.solve(b, x0=x0, tol=rtol, accel="cg", maxiter=maxiter, residuals=res)
    it = max(len(res) - 1, 0)
    rn = float(np.linalg.norm(b - a @ x))
    return x, it, 0 if rn < rtol * bn else maxiter
