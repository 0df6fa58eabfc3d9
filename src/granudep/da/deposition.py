"""Deposition set-up (eqs 34, 36): the A, B coefficients and the run-out x∞ in [x].

The deposition *rate* and the transfer of volume to the fixed grid happen inside the step kernel
(``step.drive_and_deposition`` with ``physics.alpha_coefficient`` / ``deposition_rate``). This module
resolves what the kernel needs before a run:

* A, B — ``paper``: Table 5 row of the case; ``user``: ``deposition.A``/``deposition.B``;
  ``computed``: ``granudep.abtable.interpolate_ab`` on a coefficients.csv;
* x∞ — ``user``: ``deposition.x_inf``; ``no-deposition``: the final front of the run without
  deposition; ``self-consistent`` (default): x∞ = x_front,final(x∞), solved by bracketing
  (Brent's method on g(x) = x_front,final(x) − x, bracket [x_front(x_nd), x_nd]), reporting the
  iterations and the final residual; where F jumps across the diagonal or no bracket exists, a
  documented fall-back gives x∞ and the warning is stored in the output (``x_inf_warning``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

from ..cases import table5
from ..config import ConfigError
from ..progress import LOG
from .errors import DARunError


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
        from ..abtable import interpolate_ab
    except ImportError as exc:  # the regression stage is not installed
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
    #: non-empty when the fixed point was not reached within x_inf_residual_tol and a documented
    #: fall-back rule gave x∞ (docs/paper-notes.md, "x∞ fall-back"); the run still completes
    warning: str = ""


def self_consistent(run, x_nodep: float, L0: float, tol: float, residual_tol: float, max_iter: int,
                    rec_nodep=None) -> XInfResult:
    """Solve x∞ = F(x∞), F(x) = final front of the deposition run with x∞ = x.

    F is non-increasing for A < 0 (a larger x∞ lowers [x], raises (hu)_C and deposits more), so
    g(x) = F(x) − x changes sign once. Bracket: g(x_nd) ≤ 0 at the no-deposition runout; its image
    F(x_nd) gives g ≥ 0 (else the bracket is widened towards L0). Brent's method then stops when the
    bracket is narrower than ``tol``. A plain fixed-point iteration x ← F(x) can lock into a 2-cycle
    here because F is decreasing: it is not used. Never raises for a missing fixed point: the fall-back
    rules (no bracket → x∞ = no-deposition runout; F jumps across the diagonal → the evaluated run
    closest to the sign change of F(x) − x) set ``XInfResult.warning``.
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
            # fall-back 1: no sign change of g between L0 and x_nd -> x∞ = the no-deposition runout
            warning = (f"x_inf: no bracket of the fixed point found (F(x) < x down to x = {lo:.4f} m); fall-back: "
                       f"x_inf = the no-deposition final front {hi:.5f} m")
            LOG.warning("%s", warning)
            return XInfResult(hi, cache[hi], "self-consistent", len(hx), abs(g(hi)) / max(hi - L0, 1e-12), hx, hf,
                              warning)
    warning = ""
    try:
        root = brentq(g, lo, hi, xtol=tol, maxiter=max_iter)
    except (RuntimeError, ValueError) as exc:
        root = None
        warning = f"x_inf: Brent's method stopped ({exc}); "
    # accept the evaluated point closest to a fixed point (the root itself is evaluated)
    if root is not None:
        F(root)
    best = min(cache, key=lambda x: abs(cache[x].final_front - x))
    residual = abs(cache[best].final_front - best) / (best - L0)
    if not math.isfinite(residual) or residual > residual_tol:
        # fall-back 2: F jumps across the diagonal (the final front is discontinuous in x∞). The sign
        # change of g = F(x) − x is then the generalised fixed point: below it F(x) > x, above it F(x) < x.
        # We keep the evaluated run closest to it and say so (docs/paper-notes.md, "x∞ fall-back").
        below = [x for x in cache if cache[x].final_front > x]
        above = [x for x in cache if cache[x].final_front <= x]
        jump = ""
        if below and above:
            xl, xh = max(below), min(above)
            jump = (f"F jumps from {cache[xl].final_front:.5f} m at x = {xl:.5f} m to {cache[xh].final_front:.5f} m at "
                    f"x = {xh:.5f} m ({1e3 * (xh - xl):.2f} mm apart); ")
        warning += (f"x_inf: no fixed point within x_inf_residual_tol = {residual_tol}: {jump}the final front is "
                    f"discontinuous in x_inf; fall-back: x_inf = {best:.5f} m, the evaluated run closest to the sign "
                    f"change of F(x) - x (residual {residual:.3g}, {len(hx)} runs)")
        LOG.warning("%s", warning)
    return XInfResult(best, cache[best], "self-consistent", len(hx), residual, hx, hf, warning)


def find_x_inf(dep, run_with, run_without, gate: float, case: str, origin: float = 0.0) -> XInfResult:
    """x∞ by ``deposition.x_inf_mode``, for a column and a path alike (coordinates from the back wall;
    ``origin``: the station of coordinate 0 on a path, where the user's x∞ is a station).

    ``run_with(x)``: the deposition run with x∞ = x (its record); ``run_without()``: the run without
    deposition. ``user``: the user's x∞; ``no-deposition``: the final front without deposition;
    ``self-consistent``: :func:`self_consistent` from there. ``gate``: the release end."""
    if dep.x_inf_mode == "user":
        x = dep.x_inf - origin
        return XInfResult(x, run_with(x), "user")
    x_nd = run_without().final_front
    if not math.isfinite(x_nd) or x_nd <= gate:
        raise DARunError(f"DA {case}: the no-deposition front ({x_nd + origin}) does not pass the release end; "
                         f"x_inf undefined")
    if dep.x_inf_mode == "no-deposition":
        return XInfResult(x_nd, run_with(x_nd), "no-deposition")
    xinf = self_consistent(run_with, x_nd, gate, dep.x_inf_tol, dep.x_inf_residual_tol, dep.x_inf_max_iter)
    LOG.info("DA %s: x_inf = %.5f m after %d runs, residual %.2e", case, xinf.x_inf + origin, xinf.iterations,
             xinf.residual)
    return xinf
