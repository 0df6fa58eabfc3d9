"""DA SPH along a path profile: the driver of ``step.advance`` on a bed table.

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
from dataclasses import dataclass, field

import numpy as np

from ..front import MAIN_RUN_FRACTION, main_run_front
from .path import N_TABLE, T_A, T_B, T_COS, T_DWIDTH, T_KACT, T_KAPPA, T_KPASS, T_SIN, T_WIDTH
from .solver import (AT_REST, ESCAPED, F_K, F_ND, F_U, F_V, F_V0, MAX_STEPS, N_FIELDS, NONFINITE, RUNNING,  # noqa: F401
                     grid_depth, grid_spacing, particle_depths, smooth_deposit, smoothing_length, step_params)
from .step import (D_DEFICIT, D_LIFT, D_WHERE, E_H, E_T, E_U, advance, deposit_smoothing_length,  # noqa: F401
                   mark_envelopes, own_trail)

# time_step 'relative': |u| Δt <= CFL · GEOMETRY_STEP · σ (σ the path's smoothing length)
GEOMETRY_STEP = 0.25


# ----------------------------------------------------------------------------------------------
# Python driver
# ----------------------------------------------------------------------------------------------

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


@dataclass
class PathRecord:
    """What a path run produced, at the output times (particle arrays indexed by particle id)."""
    time: list = field(default_factory=list)
    x: list = field(default_factory=list)
    u: list = field(default_factory=list)
    h: list = field(default_factory=list)
    volume: list = field(default_factory=list)
    flow_depth: list = field(default_factory=list)
    deposit_depth: list = field(default_factory=list)
    deposited_volume: list = field(default_factory=list)
    front: list = field(default_factory=list)
    smoothing_length: list = field(default_factory=list)
    time_step: list = field(default_factory=list)
    steps: list = field(default_factory=list)
    x_edges: np.ndarray | None = None
    envelopes: np.ndarray | None = None
    diag: np.ndarray | None = None
    status: int = RUNNING
    message: str = ""
    n_steps: int = 0
    x_inf: float = float("nan")
    A: float = float("nan")
    B: float = float("nan")
    final_deposit_volume: np.ndarray | None = None

    @property
    def final_front(self) -> float:
        return float(self.front[-1]) if self.front else float("nan")


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


def _grid(setup: PathSetup, dxg: float):
    ng = int(math.ceil(setup.xi_end / dxg))
    edges = np.arange(ng + 1) * dxg
    centres = (np.arange(ng) + 0.5) * dxg
    width = setup.bed.at("width", centres + setup.origin)
    return ng, edges, centres, width


def path_params(cfg, setup: PathSetup, phys, centripetal: bool):
    """The constant-θ ``StepParams`` with the path's stations, gate, scale and options."""
    from ..cases import momentum_scale
    dep = cfg.deposition
    return step_params(cfg, phys, grid_spacing(cfg, setup.dx0, phys.deposition))._replace(
        x_min=0.0, x_max=float(setup.xi_end), L0=float(setup.xi_gate),
        x_inf=float(phys.x_inf) if phys.deposition else float(setup.xi_gate) + 1.0,
        momentum_scale=(float(momentum_scale(setup.H0, setup.theta_release)) if dep.coefficient_units == "normalised"
                        else 1.0),
        origin=float(setup.origin), ds=float(setup.bed.ds), centripetal=bool(centripetal),
        has_width=bool(setup.bed.has_width), dt_relative=cfg.geometry.path.time_step == "relative",
        geometry_step=GEOMETRY_STEP * setup.bed.sigma if math.isfinite(setup.bed.sigma) else 1e300)


def path_front(edges, depth, thr, width, fraction: float = MAIN_RUN_FRACTION) -> float:
    """Front on a path: ``front.main_run_front`` (the farthest down-slope contiguous run holding at
    least ``fraction`` of the material above threshold), with the channel width."""
    return main_run_front(edges, depth, thr, width, fraction)


def _record(rec, cfg, setup, x, F, order, dep, t, L, dt, steps, dxg, ng, width_c, thr):
    n = x.shape[0]
    qc = cfg.numerics.kernel_support
    wall = cfg.geometry.back_wall
    h = particle_depths(x, F[F_V], L, qc, wall) / setup.bed.at("width", x + setup.origin)
    for name, vals in (("x", x), ("u", F[F_U]), ("h", h), ("volume", F[F_V])):
        arr = np.empty(n)
        arr[order] = vals
        getattr(rec, name).append(arr)
    flow = grid_depth(x, F[F_V], L, qc, wall, dxg, ng) / width_c
    depo = smooth_deposit(dep, deposit_smoothing_length(L, dxg), qc, dxg) / width_c
    rec.flow_depth.append(flow)
    rec.deposit_depth.append(depo)
    rec.deposited_volume.append(float(np.sum(dep)))
    rec.front.append(path_front(rec.x_edges, flow + depo, thr, width_c))
    rec.time.append(t)
    rec.smoothing_length.append(L)
    rec.time_step.append(dt)
    rec.steps.append(steps)


def initial_path_state(setup: PathSetup):
    n = setup.x0.size
    x = setup.x0.copy()
    F = np.zeros((N_FIELDS, n))
    F[F_V] = setup.V0
    F[F_V0] = F[F_V]
    F[F_K] = 0.0  # the released mass starts in the active state: clipped to k_a at the first stage
    F[F_ND] = 1.0 / setup.dx0
    return x, F, np.arange(n, dtype=np.int64)


def simulate_path(cfg, setup: PathSetup, phys, tab: np.ndarray, label: str = "", progress=None, init=None,
                  centripetal: bool | None = None) -> PathRecord:
    """Run one DA simulation along the path to rest (or t_end); a failure stops the run and the
    record keeps what was written, with ``status`` and ``message`` (time, step, particle, station)."""
    from .solver import custom_state
    cent = cfg.geometry.path.centripetal if centripetal is None else centripetal
    if init is None:
        x, F, order = initial_path_state(setup)
    else:
        x, F, order = custom_state(*init)
    prm = path_params(cfg, setup, phys, cent)
    dxg = prm.dx_grid
    ng, edges, centres, width_c = _grid(setup, dxg)
    dep = np.zeros(ng)
    depb = np.zeros(ng)
    binv = 1.0 / width_c
    env = np.zeros((3, ng))
    env[E_T] = np.inf
    diag = np.zeros(3)
    own = own_trail(x.shape[0], prm.deposition and prm.deposit_as_bed and not prm.own_deposit)
    rec = PathRecord(x_edges=edges, x_inf=phys.x_inf, A=phys.A, B=phys.B, envelopes=env, diag=diag)
    thr = cfg.front_threshold
    L = smoothing_length(F, prm)
    # the release itself: depth and arrival time 0 in its cells
    h0 = particle_depths(x, F[F_V], L, cfg.numerics.kernel_support, cfg.geometry.back_wall)
    h0 = h0 / setup.bed.at("width", x + setup.origin)
    mark_envelopes(env, x, x, h0, F[F_U], F[F_V], 0.0, dxg, thr)
    _record(rec, cfg, setup, x, F, order, dep, 0.0, L, 0.0, 0, dxg, ng, width_c, thr)
    t, steps = 0.0, 0
    dt_out, t_end = cfg.output.dt_output, cfg.numerics.t_end
    k = 1
    while True:
        t_target = min(k * dt_out, t_end)
        t, steps, status, where, L, dt = advance(x, F, order, dep, depb, binv, env, diag, t, t_target, prm, tab,
                                                 steps, own)
        if status in (RUNNING, AT_REST):
            _record(rec, cfg, setup, x, F, order, dep, t, L, dt, steps, dxg, ng, width_c, thr)
        if progress is not None:
            progress(lambda: f"DA path {label}: t = {t:.3f} s, step {steps}, front s = "
                             f"{rec.front[-1] + setup.origin:.3f} m, L_s = {L:.3g} m, dt = {dt:.2e} s")
        if status == AT_REST:
            rec.status, rec.message = AT_REST, f"at rest at t = {t:.4f} s after {steps} steps"
            break
        if status in (NONFINITE, ESCAPED, MAX_STEPS):
            xs = np.empty_like(x)
            xs[order] = x
            where_txt = "" if where < 0 else f" particle {where} at s = {xs[where] + setup.origin:.4f} m"
            what = {NONFINITE: "non-finite velocity or position",
                    ESCAPED: f"a particle left the path (s outside [{setup.origin:.4g}, {setup.bed.length:.4g}] m;"
                             f" extend the path CSV)",
                    MAX_STEPS: f"numerics.max_steps = {cfg.numerics.max_steps} reached"}[status]
            rec.status = status
            rec.message = f"DA path run {label} stopped at t = {t:.5f} s, step {steps}: {what}{where_txt}"
            break
        if t >= t_end:
            rec.status, rec.message = RUNNING, f"not at rest at numerics.t_end = {t_end} s"
            break
        k += 1
    rec.n_steps = steps
    rec.final_deposit_volume = dep.copy()
    return rec
