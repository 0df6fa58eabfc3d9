"""The linear systems of an ISPH step and how each is solved: one object per run
(:class:`LinearSystems`), asked by the solver for the pressure (PPE) and the viscous (u, v) solves.

* the PPE solver a user names (``numerics.pressure_solver``) is resolved in one place,
  :func:`ppe_solver_name` (``cg_dic`` runs as ``cg_ssor`` on the adjoint pair, whose operator has no
  incomplete Cholesky), and the CG that runs for each name comes from one registry, ``CG_SOLVERS``;
* one fallback rule for every CG: a breakdown, an exception, a non-finite solution or no convergence
  in 1000 iterations gives a SuperLU solve of the same system, counted in ``stats.fallbacks``
  (:meth:`LinearSystems.fallback`, :meth:`LinearSystems.why`); a singular direct solve is a blow-up.

The CG kernels are in :mod:`.linsolve`, :mod:`.deflation` and :mod:`.amg`. The owner (the solver) gives
``cfg``, ``stats``, ``t`` and ``step_no`` (read at each call: a restart may replace them).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..progress import LOG
from .deflation import pcg_ssor_deflated
from .errors import IsphBlowUp
from .cg_dic import pcg_dic, pcg_dic_pair
from .cg_two_level import pcg_two_level, pcg_two_level_free
from .linsolve import BREAKDOWN, NONFINITE, pcg_jacobi, pcg_jacobi_pair
from .amg import amg_pcg

def _cg_jacobi(indptr, indices, data, rhs, guess, rtol, numerics):
    return pcg_jacobi(indptr, indices, data, rhs, guess, rtol, 0.0, 1000)


def _cg_dic(indptr, indices, data, rhs, guess, rtol, numerics):
    return pcg_dic(indptr, indices, data, rhs, guess, rtol, 0.0, 1000, numerics.ic_modification)


def _cg_ssor(indptr, indices, data, rhs, guess, rtol, numerics):
    return pcg_dic(indptr, indices, data, rhs, guess, rtol, 0.0, 1000, -1.0)


def _cg_two_level(indptr, indices, data, rhs, guess, rtol, numerics):
    return pcg_two_level(indptr, indices, data, rhs, guess, rtol, 0.0, 1000)


#: the CG that runs for each assembled-system solver name (``numerics.pressure_solver`` after
#: :func:`ppe_solver_name`): f(indptr, indices, data, rhs, guess, rtol, numerics) -> (x, iterations,
#: info) with info 0 on convergence (the :mod:`.linsolve` return convention). A new solver is one
#: such function, one line here and its name in ``numerics.pressure_solver``'s choices.
CG_SOLVERS = {"cg": _cg_jacobi, "cg_dic": _cg_dic, "cg_ssor": _cg_ssor, "cg_two_level": _cg_two_level}


def ppe_solver_name(numerics) -> str:
    """The PPE solver that runs for ``numerics.pressure_solver``: ``cg_dic`` becomes ``cg_ssor`` with the
    adjoint-pair projection (its operator (1 − ε) D Dᵀ + ε L_c has positive off-diagonal entries, and
    incomplete Cholesky meets non-positive pivots on it); every other name runs as named."""
    if numerics.pressure_solver == "cg_dic" and numerics.projection == "adjoint_pair":
        return "cg_ssor"
    return numerics.pressure_solver


def _solve_direct(indptr, indices, data, rhss):
    n = indptr.size - 1
    # symmetric matrices: the CSR arrays are also the CSC arrays
    # SuperLU needs sorted row indices (the kernels put the diagonal first); sorted_indices()
    # works on a copy so the caller's arrays stay in kernel order
    a = sp.csc_matrix((data, indices, indptr), shape=(n, n)).sorted_indices()
    lu = spla.splu(a, permc_spec="MMD_AT_PLUS_A")
    return [lu.solve(b) for b in rhss]


class LinearSystems:
    """The PPE and viscous solves of one run, with the fallback to SuperLU (see the module)."""

    def __init__(self, owner):
        self.owner = owner

    def solve_ppe(self, indptr, indices, data, rhs, guess):
        if self.owner.cfg.numerics.pressure_solver == "direct":
            return self.direct(indptr, indices, data, rhs, "ppe")
        if self.owner.cfg.numerics.pressure_solver.startswith("amg_"):
            return self.solve_amg(indptr, indices, data, rhs, guess)
        # the adjoint-pair operator (1 − ε) D Dᵀ + ε L_c is only semi-definite up to ε L_c and has
        # positive off-diagonal entries: incomplete Cholesky (modified or not) meets non-positive
        # pivots on it (Newtonian film, ε = 0.01: every step); its preconditioned solver is the
        # two-level CG (Jacobi + aggregation coarse space, iterations independent of dx)
        return self.solve_cg(indptr, indices, data, rhs, guess, "ppe", solver=ppe_solver_name(self.owner.cfg.numerics))

    @property
    def ppe_form(self) -> str:
        """How the adjoint-pair PPE reaches its solver: ``csr`` (assembled), ``free`` (matrix-free,
        ``numerics.ppe_operator``) or ``triangles`` (``cg_ssor``: the SSOR sweeps' two triangles)."""
        n = self.owner.cfg.numerics
        if ppe_solver_name(n) == "cg_ssor":
            return "triangles"
        return "free" if n.ppe_operator == "matrix_free" else "csr"

    def solve_ppe_free(self, op, rhs, guess, assemble):
        """The adjoint-pair PPE as a matrix-free operator (two-level CG) or as its two triangles
        (SSOR-CG, deflated by an aggregation coarse space from ``numerics.deflation_min_unknowns``
        unknowns on: :mod:`.deflation`); the assembled matrix by SuperLU if it fails (:meth:`solve_cg`)."""
        rtol = self.owner.cfg.numerics.solver_rtol
        try:
            if self.ppe_form == "triangles":     # op = (lp, li, lv, up, ui, uv, diag)
                sol, it, info = pcg_ssor_deflated(op, rhs, guess, rtol, 0.0, 1000,
                                                  self.owner.cfg.numerics.deflation_min_unknowns)
            else:
                sol, it, info = pcg_two_level_free(op, rhs, guess, rtol, 0.0, 1000)
        except (ZeroDivisionError, FloatingPointError, np.linalg.LinAlgError) as exc:
            sol, it, info = guess, 0, BREAKDOWN
            LOG.warning("isph %s: ppe CG raised %r", self.owner.cfg.case, exc)
        self.owner.stats.ppe_iters += it
        why = self.why(info, sol)
        if why is not None:
            return self.fallback(*assemble(), rhs, "ppe", why)
        return sol

    def direct(self, indptr, indices, data, rhs, kind):
        """SuperLU; a singular matrix stops the run as a blow-up (partial output kept)."""
        try:
            return _solve_direct(indptr, indices, data, [rhs])[0]
        except (RuntimeError, ValueError, ZeroDivisionError) as exc:
            raise IsphBlowUp(f"{kind} linear system: direct solver failed ({exc}) at t={self.owner.t:.5f} s, "
                             f"step {self.owner.step_no}") from exc

    def fallback(self, indptr, indices, data, rhs, kind, why):
        """Direct solve of a system whose CG broke down or did not converge,
        counted in ``stats.fallbacks`` (run file attribute ``linear_solver_fallbacks``)."""
        self.owner.stats.fallbacks += 1
        if self.owner.stats.fallbacks <= 10:
            LOG.warning("isph %s: %s CG %s at t=%.5f s, step %d: direct solve for this step", self.owner.cfg.case, kind,
                        why, self.owner.t, self.owner.step_no)
        return self.direct(indptr, indices, data, rhs, kind)

    @staticmethod
    def why(info, sol):
        if info == NONFINITE:
            return "right-hand side not finite"
        if info == BREAKDOWN:
            return "breakdown (zero/negative curvature or NaN)"
        if info == -1:
            return "incomplete Cholesky breakdown (non-positive pivot)"
        if info > 0:
            return f"not converged in {info} iterations"
        if not np.isfinite(sol).all():
            return "returned a non-finite solution"
        return None

    def solve_amg(self, indptr, indices, data, rhs, guess):
        """AMG-preconditioned CG (:mod:`.amg`, pyamg), with the direct fallback of :meth:`solve_cg`."""
        try:
            sol, it, info = amg_pcg(indptr, indices, data, rhs, guess, self.owner.cfg.numerics.solver_rtol, 200,
                                    self.owner.cfg.numerics.pressure_solver[4:])
        except (ArithmeticError, ValueError, RuntimeError) as exc:
            sol, it, info = guess, 0, BREAKDOWN
            LOG.warning("isph %s: ppe AMG raised %r", self.owner.cfg.case, exc)
        self.owner.stats.ppe_iters += it
        why = self.why(info, sol)
        if why is not None:
            return self.fallback(indptr, indices, data, rhs, "ppe", why)
        return sol

    def solve_cg(self, indptr, indices, data, rhs, guess, kind, solver="cg"):
        """The CG of ``CG_SOLVERS[solver]`` (``cg``: Jacobi, scipy's iterates bit for bit; ``cg_dic``,
        ``cg_ssor``: Eisenstat; ``cg_two_level``: Jacobi + aggregation coarse space), warm-started;
        SuperLU if it breaks down, raises, returns a non-finite solution or does not converge in 1000
        iterations."""
        num = self.owner.cfg.numerics
        try:
            sol, it, info = CG_SOLVERS[solver](indptr, indices, data, rhs, guess, num.solver_rtol, num)
        except (ZeroDivisionError, FloatingPointError, np.linalg.LinAlgError) as exc:
            sol, it, info = guess, 0, BREAKDOWN
            LOG.warning("isph %s: %s CG raised %r", self.owner.cfg.case, kind, exc)
        if kind == "ppe":
            self.owner.stats.ppe_iters += it
        else:
            self.owner.stats.visc_iters += it
        why = self.why(info, sol)
        if why is not None:
            return self.fallback(indptr, indices, data, rhs, kind, why)
        return sol

    def solve_cg_pair(self, indptr, indices, data, diag_v, bu, bv, xu0, xv0, dic=False):
        """The u and v viscous systems (same off-diagonal, own diagonals) by Jacobi- or DIC-CG in
        lock-step, warm-started from xu0, xv0; SuperLU for one that does not converge."""
        rtol = self.owner.cfg.numerics.solver_rtol
        try:
            if dic:
                xu, itu, infou, xv, itv, infov = pcg_dic_pair((indptr, indices, data), diag_v, bu, xu0, bv, xv0, rtol,
                                                              0.0, 1000, self.owner.cfg.numerics.ic_modification)
            else:
                xu, itu, infou, xv, itv, infov = pcg_jacobi_pair((indptr, indices, data), diag_v, bu, xu0, bv, xv0,
                                                                 rtol, 0.0, 1000)
        except (ZeroDivisionError, FloatingPointError) as exc:
            xu, itu, infou, xv, itv, infov = xu0, 0, BREAKDOWN, xv0, 0, BREAKDOWN
            LOG.warning("isph %s: viscous CG raised %r", self.owner.cfg.case, exc)
        self.owner.stats.visc_iters += itu + itv
        why = self.why(infou, xu)
        if why is not None:
            xu = self.fallback(indptr, indices, data, bu, "viscous (u)", why)
        why = self.why(infov, xv)
        if why is not None:
            data_v = data.copy()
            data_v[indptr[:-1]] = diag_v
            xv = self.fallback(indptr, indices, data_v, bv, "viscous (v)", why)
        return xu, xv

