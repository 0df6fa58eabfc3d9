"""Deposition set-up (eqs 34, 36): the A, B coefficients and the run-out x∞ in [x].

The deposition *rate* and the transfer of volume to the fixed grid happen inside the step kernel
(``solver.advance`` with ``physics.alpha_coefficient`` / ``deposition_rate``). This module
resolves what the kernel needs before a run:

* A, B — ``paper``: Table 5 row of the case; ``user``: ``deposition.A``/``deposition.B``;
  ``computed``: ``granudep.regress.coefficients.interpolate_ab`` on a coefficients.csv;
* x∞ — ``user``: ``deposition.x_inf``; ``no-deposition``: the final front of the run without
  deposition; ``self-consistent`` (default): x∞ = x_front,final(x∞), solved by bracketing
  (Brent's method on g(x) = x_front,final(x) − x, bracket [x_front(x_nd), x_nd]), reporting the
  iterations and the final residual and failing loudly if no fixed point is found.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

from ..cases import table5
from ..config import ConfigError
from ..progress import LOG


def coefficients(cfg) -> tuple[float, float, str]:
    """(A, B, description of their source) for the configured ``deposition.ab_source``."""
    dep = cfg.deposition
    if dep.ab_source == "user":
        return float(dep.A), float(dep.B), "user (deposition.A, deposition.B)"
    if dep.ab_source == "paper":
        t5 = table5()
        row = t5[t5.case_id == cfg.case]
        if row.empty:
            raise ConfigError(f"deposition.ab_source: 'paper' needs a Table 5 case name as `case` (got {cfg.case!r})")
        return float(row.iloc[0].A), float(row.iloc[0].B), f"paper (Table 5, {cfg.case})"
    try:
        from ..regress.coefficients import interpolate_ab
    except ImportError as exc:  # engineer C's stage not installed/built yet
        raise ConfigError(f"deposition.ab_source: 'computed' needs granudep.regress.coefficients "
                          f"(not importable: {exc}); use 'paper' or 'user'") from None
    a = cfg.geometry.H0 / cfg.geometry.L0
    A, B = interpolate_ab(dep.coefficients, a, cfg.geometry.theta_deg)
    return float(A), float(B), f"computed ({dep.coefficients}, a = {a:.4g}, theta = {cfg.geometry.theta_deg:g} deg)"


@dataclass
class XInfResult:
    """The outcome of the x∞ search: the run at the accepted x∞ and the iteration history."""
    x_inf: float
    record: object
    mode: str
    iterations: int = 0
    residual: float = 0.0  # |x_front,final(x∞) − x∞| / (x∞ − L0)
    history_x: list = field(default_factory=list)
    history_front: list = field(default_factory=list)


def self_consistent(run, x_nodep: float, L0: float, tol: float, residual_tol: float, max_iter: int,
                    rec_nodep=None) -> XInfResult:
    """Solve x∞ = F(x∞), F(x) = final front of the deposition run with x∞ = x.

    F is non-increasing for A < 0 (a larger x∞ lowers [x], raises (hu)_C and deposits more), so
    g(x) = F(x) − x changes sign once. Bracket: g(x_nd) ≤ 0 at the no-deposition runout; its image
    F(x_nd) gives g ≥ 0 (else the bracket is widened towards L0). Brent's method then stops when the
    bracket is narrower than ``tol``. A plain fixed-point iteration x ← F(x) can lock into a 2-cycle
    here because F is decreasing: it is not used. Raises RuntimeError if no fixed point is found.
    """
    from scipy.optimize import brentq

    cache: dict[float, object] = {}
    hx, hf = [], []

    def F(x):
        if x not in cache:
            rec = run(x)
            cache[x] = rec
            hx.append(x)
            hf.append(rec.final_front)
            LOG.info("x_inf iteration %d: x_inf = %.5f m -> final front %.5f m", len(hx), x, rec.final_front)
        return cache[x].final_front

    def g(x):
        return F(x) - x

    hi = x_nodep
    if g(hi) >= 0.0:
        rec = cache[hi]
        return XInfResult(hi, rec, "self-consistent", len(hx), abs(g(hi)) / max(hi - L0, 1e-12), hx, hf)
    lo = F(hi)
    tries = 0
    while g(lo) < 0.0:
        tries += 1
        lo = L0 + 0.5 * (lo - L0)
        if tries > 6 or lo - L0 < tol:
            raise RuntimeError(f"x_inf self-consistent iteration: no bracket found (g < 0 down to x = {lo:.4f} m); "
                               f"use deposition.x_inf_mode 'no-deposition' or 'user'")
    try:
        root = brentq(g, lo, hi, xtol=tol, maxiter=max_iter)
    except (RuntimeError, ValueError) as exc:
        raise RuntimeError(f"x_inf self-consistent iteration did not converge in {max_iter} iterations "
                           f"(deposition.x_inf_max_iter): {exc}") from None
    # accept the evaluated point closest to a fixed point (the root itself is evaluated)
    F(root)
    best = min(cache, key=lambda x: abs(cache[x].final_front - x))
    residual = abs(cache[best].final_front - best) / (best - L0)
    if not math.isfinite(residual) or residual > residual_tol:
        raise RuntimeError(
            f"x_inf self-consistent iteration: best residual |x_front - x_inf|/(x_inf - L0) = {residual:.3g} "
            f"> deposition.x_inf_residual_tol = {residual_tol} after {len(hx)} runs (x_inf = {best:.5f} m); "
            f"the final front jumps across the fixed point: refine output.dx_grid or numerics.n_particles")
    return XInfResult(best, cache[best], "self-consistent", len(hx), residual, hx, hf)
