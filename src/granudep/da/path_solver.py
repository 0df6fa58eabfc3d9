"""DA SPH along a path profile: the path's run constants, bed table, grid and release; the time
loop is ``driver.run``, shared with the constant-slope model.

The particles move along the bed; their coordinate ξ = s − s_origin is the station along the
smoothed path (``da/path.py``) from the back wall (s_origin = start of the release) or, without a
wall, from the first point of the path. Every step is the constant-θ scheme — the same kernel,
``step.advance``, with its stages — with the slope quantities read per particle from the bed
table (linear interpolation in s; a constant slope is a table of two equal stations) and the
curved-bed terms of
Savage & Hutter (1991):

    du/dt = g sinθ(s) − k g cosθ(s) ∂h/∂s − g cosθ(s) ∂h_D/∂s − sgn(u) tanφ_B N⁺,
    N = g cosθ(s) + κ(s) u²,  N⁺ = max(N, 0)   (``physics.bed_normal_acceleration``)

(the centripetal term only in the normal stress, as in S&H 1991; earth pressure as in eqs 8–9).
Where N < 0 (a convex break taken faster than √(g cosθ/|κ|)) the mass would leave the bed:
free flight is not modelled, friction is zero there, and every clipped particle-stage is counted
(``diag``; the output reports the count, the largest deficit and where).

Width b(s): particles carry volume (m³; m² per unit width without a width column); the SPH sum
of eq 20 gives the cross-section A = Σ V_j W_ij, the depth is h = A/b and the pressure gradient
∂h/∂s = (∂A/∂s − h db/ds)/b (``physics.depth_from_area`` / ``depth_gradient_from_area``), so the
pressure force per unit mass is −k g cosθ ∂h/∂s as in a rectangular channel of slowly varying
width. The deposit is kept as volume per grid cell (conserved) and as volume/b (its depth × Δs,
for the bed term). With b ≡ 1, θ constant and κ = 0 every operation reduces to
the constant-θ run bit for bit (tested).

Time step (``geometry.path.time_step``): ``absolute`` is eq 32 as in the constant-θ model,
Δt = CFL L_s / max(|u|, √(g h)). ``relative`` (default on a path) drops the advection speed, which
no Lagrangian scheme needs for stability (particles carry their state; Monaghan's SPH CFL uses
the wave speed and the relative velocity of neighbours): Δt = CFL L_s / max(√(g h) + min(L_s |∂u/∂s|, 2 max|u|)),
plus |u| Δt ≤ CFL · ¼ σ so that a step never jumps over the bed's changes of slope (σ: the path
smoothing length). Measured effect in docs/paper-notes.md ("DA on a path profile").

Friction is integrated like the other forces (Heun): the predictor's budget is N⁺(stage 1) tanφ_B Δt,
the corrector's ½ Δt tanφ_B (N⁺₁ + N⁺₂); for a constant N this is the constant-θ budget exactly.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .driver import DARecord, Track, run
from .path import N_TABLE, T_A, T_B, T_COS, T_DWIDTH, T_KACT, T_KAPPA, T_KPASS, T_SIN, T_WIDTH
from .solver import custom_state, grid_spacing, released_state, step_params
from ..cases import momentum_scale

# time_step 'relative': |u| Δt <= CFL · GEOMETRY_STEP · σ (σ the path's smoothing length)
GEOMETRY_STEP = 0.25


@dataclass(frozen=True)
class PathSetup:
    """A run's bed and release, resolved once (stations s in m along the bed from the first point)."""
    bed: object            # path.Bed
    origin: float          # s of ξ = 0 (back wall, or the first point without a wall)
    s_start: float         # release from s_start ...
    s_end: float           # ... to s_end (the "gate")
    L0: float              # release length s_end − s_start
    H0: float              # release depth (column) or mean depth (polygon), bed-normal
    theta_release: float   # rad: the release zone's slope (chord)
    x0: np.ndarray         # initial ξ of the particles
    V0: np.ndarray         # initial particle volumes (m³; m² per unit width without width)
    dx0: float             # initial particle spacing

    @property
    def xi_gate(self) -> float:
        return self.s_end - self.origin

    @property
    def xi_end(self) -> float:
        return self.bed.length - self.origin


def bed_table(setup: PathSetup, k_active, k_passive, A, B) -> np.ndarray:
    """The (N_TABLE, ns) table the kernel interpolates; k, A, B scalars or arrays over the stations."""
    bed = setup.bed
    ns = bed.s.size
    tab = np.empty((N_TABLE, ns))
    tab[T_SIN] = np.sin(bed.theta) if getattr(bed, "sin", None) is None else bed.sin
    tab[T_COS] = np.cos(bed.theta) if getattr(bed, "cos", None) is None else bed.cos
    tab[T_KAPPA] = bed.kappa
    tab[T_WIDTH] = bed.width
    tab[T_DWIDTH] = bed.dwidth
    tab[T_KACT] = k_active
    tab[T_KPASS] = k_passive
    tab[T_A] = A
    tab[T_B] = B
    return tab


def path_track(setup: PathSetup, dxg: float) -> Track:
    """The grid of a path run: cells of ``dxg`` in ξ from the origin to the end of the path, the
    channel width at their centres and at the particles; places named by their station s."""
    ng = int(math.ceil(setup.xi_end / dxg))
    centres = (np.arange(ng) + 0.5) * dxg
    bed, o = setup.bed, setup.origin
    return Track(dx_grid=dxg, n_cells=ng, width_cells=bed.at("width", centres + o),
                 width_at=lambda x: bed.at("width", x + o), origin=float(o), coordinate="s", name="DA path",
                 escaped=f"a particle left the path (s outside [{o:.4g}, {bed.length:.4g}] m; extend the path CSV)",
                 envelopes=True)


def path_params(cfg, setup: PathSetup, phys, centripetal: bool):
    """The constant-θ ``StepParams`` with the path's stations, gate, scale and options."""
    dep = cfg.deposition
    return step_params(cfg, phys, grid_spacing(cfg, setup.dx0, phys.deposition))._replace(
        x_min=0.0, x_max=float(setup.xi_end), L0=float(setup.xi_gate),
        x_inf=float(phys.x_inf) if phys.deposition else float(setup.xi_gate) + 1.0,
        momentum_scale=(float(momentum_scale(setup.H0, setup.theta_release)) if dep.coefficient_units == "normalised"
                        else 1.0),
        origin=float(setup.origin), ds=float(setup.bed.ds), centripetal=bool(centripetal),
        has_width=bool(setup.bed.has_width), dt_relative=cfg.geometry.path.time_step == "relative",
        geometry_step=GEOMETRY_STEP * setup.bed.sigma if math.isfinite(setup.bed.sigma) else 1e300)


def initial_path_state(setup: PathSetup):
    """The release of the path (``solver.released_state`` at the set-up's stations and volumes)."""
    return released_state(setup.x0.copy(), setup.V0, 1.0 / setup.dx0)


def simulate_path(cfg, setup: PathSetup, phys, tab: np.ndarray, label: str = "", progress=None, init=None,
                  centripetal: bool | None = None) -> DARecord:
    """Run one DA simulation along the path to rest (or t_end) (``driver.run``: a failure stops the
    run, the record keeps what was written, with ``status`` and ``message``: time, step, particle,
    station). ``init``: any initial particle set (ξ, volume, u) instead of the release."""
    cent = cfg.geometry.path.centripetal if centripetal is None else centripetal
    prm = path_params(cfg, setup, phys, cent)
    state = initial_path_state(setup) if init is None else custom_state(*init)
    return run(cfg, path_track(setup, prm.dx_grid), prm, tab, state, phys, label, progress)
