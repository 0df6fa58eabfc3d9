"""DA SPH on a constant slope θ (Sections 2.3–2.4, Fig 4): the run constants, the bed table and the
initial column of a constant-slope run; the time loop is ``driver.run``, shared with the path model.

The step is ``step.advance`` (the SPH sums are in ``sph.py``, the per-particle formulas in
``physics.py``); a constant slope is a bed table of two equal stations. Per step:

1. sort particles by x (insertion sort), smoothing length L_s from eq 25 (generalised: B over the
   mean particle number density Σ_j W_ij, which equals eq 25 for equal volumes and stays finite as
   deposition empties particles) or fixed;
2. stage 1 at (x^n, u^n): depth eq 20 (with mirror ghosts at the back wall), depth gradient
   eqs 21–22, velocity divergence eqs 28–29 (sign of eq 29 corrected), XSPH sum eq 33;
   driving acceleration g sinθ − k g cosθ ∂h/∂x (eqs 11/27, k from eqs 8–9);
   deposition rate (eqs 14, 34, 36) and the eq 12 momentum loss;
3. Δt from eq 32 (CFL);
4. predictor ũ = u^n + Δt a^n (Coulomb-limited), x̃ = x^n + Δt u^n;
5. stage 2 at (x̃, ũ): a^{n+1};
6. RK2 eqs 30–31: u^{n+1} = u^n + Δt/2 (a^n + a^{n+1}) with Coulomb friction applied as a
   velocity budget that stops but never reverses; XSPH correction eq 33; x^{n+1} = x^n + Δt/2 (u^n + u^{n+1});
7. deposition: the volume fraction −S_D Δt / h leaves each particle into the fixed grid (linear
   weights to the two nearest cells), so flowing + deposited volume is conserved to round-off.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .path import N_TABLE, T_A, T_B, T_COS, T_KACT, T_KPASS, T_SIN, T_WIDTH
from .driver import DARecord, Track, run
from .sph import F_K, F_ND, F_U, F_V, F_V0, N_FIELDS
from .step import StepParams
from ..cases import G


@dataclass(frozen=True)
class Physics:
    """Run-level constants resolved from the config (radians, k coefficients, A/B, x∞)."""
    k_active: float
    k_passive: float
    deposition: bool
    A: float = 0.0
    B: float = 0.0
    x_inf: float = float("nan")


def grid_spacing(cfg, release_spacing: float, deposition: bool) -> float:
    """Cell of the fixed grid (deposit, profiles, front): ``output.dx_grid``, but with deposition never
    coarser than the smoothing length at release (B × the release spacing, or the fixed L_s). The
    deposit lives on this grid and acts as bed; with a cell coarser than the particles' kernel the
    deposit is smoothed over the cell, the flow over L_s, and the model changes with N (1D-A70 with
    deposition at N = 8000: 2.525 m on the 1 mm grid, 2.494 m on 0.25 mm, the L_s at release; at
    N = 4000 2.483 / 2.4835 m on 1 / 0.5 mm). Without deposition the grid only reads the profiles."""
    num = cfg.numerics
    L = num.L_s if num.smoothing == "fixed" else num.smoothing_B * release_spacing
    return min(cfg.output.dx_grid, L) if deposition else cfg.output.dx_grid


def column_grid_spacing(cfg, phys: Physics) -> float:
    """:func:`grid_spacing` of a column of n equal particles over L0."""
    return grid_spacing(cfg, cfg.geometry.L0 / cfg.numerics.n_particles, phys.deposition)


def step_params(cfg, phys: Physics, dx_grid: float | None = None) -> StepParams:
    """The run constants the numba stages read (``step.StepParams``), for a constant slope."""
    num, dep, mat = cfg.numerics, cfg.deposition, cfg.material
    return StepParams(
        g=float(G), cfl=float(num.cfl), xsph_delta=float(num.xsph_delta), kernel_support=float(num.kernel_support),
        smoothing_B=float(num.smoothing_B), L_fixed=float(num.L_s) if num.smoothing == "fixed" else 0.0,
        smoothing_volume=num.smoothing_weight == "volume",
        back_wall=bool(cfg.geometry.back_wall), x_min=-math.inf, x_max=float(cfg.geometry.domain_end),
        u_rest=float(num.u_rest), max_steps=int(num.max_steps),
        deposition=bool(phys.deposition), deposit_as_bed=bool(dep.deposit_as_bed),
        eq12=dep.momentum_term == "eq12", clamp_x=bool(dep.clamp_x),
        momentum_scale=float(cfg.p0) if dep.coefficient_units == "normalised" else 1.0,
        L0=float(cfg.geometry.L0),
        x_inf=float(phys.x_inf) if phys.deposition else float(cfg.geometry.L0) + 1.0,
        u_min=float(dep.u_min), tan_phi_internal=math.tan(math.radians(mat.phi_internal_deg)),
        tan_phi_basal=math.tan(math.radians(mat.phi_basal_deg)) if num.basal_friction else 0.0,
        min_volume_fraction=float(dep.min_volume_fraction),
        dx_grid=float(column_grid_spacing(cfg, phys) if dx_grid is None else dx_grid),
        origin=0.0, ds=float(cfg.geometry.domain_end), centripetal=False, has_width=False, dt_relative=False,
        geometry_step=math.inf, front_threshold=float(cfg.front_threshold),
        own_deposit=dep.own_deposit == "include",
        deposit_max_tan=math.tan(math.radians(mat.phi_basal_deg)) if dep.steep_bed == "no_deposit" else math.inf,
        k_symmetric=num.earth_pressure_switch in ("symmetric", "strain") and num.earth_pressure != "one",
        k_strain=1.0 / num.earth_pressure_strain if num.earth_pressure_switch == "strain" and num.earth_pressure != "one"
        else 0.0)


def constant_bed_table(theta: float, phys: Physics) -> np.ndarray:
    """The bed table of a constant slope: two equal stations (``step.table_at`` returns their value
    exactly), sinθ, cosθ, no curvature, width 1, k and A, B of the run."""
    tab = np.zeros((N_TABLE, 2))
    tab[T_SIN] = math.sin(theta)
    tab[T_COS] = math.cos(theta)
    tab[T_WIDTH] = 1.0
    tab[T_KACT] = phys.k_active
    tab[T_KPASS] = phys.k_passive
    tab[T_A] = phys.A
    tab[T_B] = phys.B
    return tab


def released_state(x, volume, number_density: float):
    """A released mass at rest: particles at x (sorted) with their volumes and the number density of
    their lattice (1/spacing), so the first L_s is B / number density (eq 25). It starts in the
    active state (k clipped to k_a at the first stage)."""
    n = x.shape[0]
    F = np.zeros((N_FIELDS, n))
    F[F_V] = volume
    F[F_V0] = F[F_V]
    F[F_K] = 0.0
    F[F_ND] = number_density
    return x, F, np.arange(n, dtype=np.int64)


def initial_state(cfg):
    """The column [0, L0] × [0, H0]: n equal particles at the centres of n equal cells."""
    n = cfg.numerics.n_particles
    dx = cfg.geometry.L0 / n
    return released_state((np.arange(n) + 0.5) * dx, cfg.geometry.H0 * dx, 1.0 / dx)


def custom_state(x, volume, u):
    """Any initial particle set (sorted positions x, volumes, velocities): for analytic checks."""
    x = np.array(x, dtype=float)
    x, F, order = released_state(x, volume, (x.shape[0] - 1) / (x[-1] - x[0]))
    F[F_U] = u
    return x, F, order


def column_track(cfg, dxg: float) -> Track:
    """The grid of a column run: cells of ``dxg`` from the back wall x = 0 to ``geometry.x_max``."""
    return Track(dx_grid=dxg, n_cells=int(math.ceil(cfg.geometry.domain_end / dxg)),
                 escaped=f"a particle left the domain (x > x_max = {cfg.geometry.domain_end:.4g} m; raise geometry.x_max)")


def simulate(cfg, phys: Physics, label: str = "", progress=None, init=None, checkpoint=None) -> DARecord:
    """Run one DA simulation on a constant slope to rest (or t_end) and return its record
    (``driver.run``: a failure stops the run, the record keeps what was written). ``init``: any
    initial particle set (x, volume, u) instead of the column; ``checkpoint``: see ``driver.run``."""
    track = column_track(cfg, column_grid_spacing(cfg, phys))
    prm = step_params(cfg, phys, track.dx_grid)
    state = initial_state(cfg) if init is None else custom_state(*init)
    return run(cfg, track, prm, constant_bed_table(cfg.theta, phys), state, phys, label, progress, checkpoint)
