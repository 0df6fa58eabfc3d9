"""DA SPH on a constant slope θ (Sections 2.3–2.4, Fig 4): the Python driver.

The step is ``step.advance`` (shared with the path model, ``path_solver``; the SPH sums are in
``sph.py``, the per-particle formulas in ``physics.py``); a constant slope is a bed table of two
equal stations. Per step:

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
from dataclasses import dataclass, field

import numpy as np

from .path import N_TABLE, T_A, T_B, T_COS, T_KACT, T_KPASS, T_SIN, T_WIDTH
from .sph import (F_H, F_K, F_ND, F_U, F_V, F_V0, N_FIELDS, deposit_gradient, evaluate, grid_depth,  # noqa: F401
                  particle_depths)
from .step import (AT_REST, ESCAPED, MAX_STEPS, NONFINITE, RUNNING, StepParams, advance, deposit_smoothing_length,
                   own_trail, smoothing_length)


# ----------------------------------------------------------------------------------------------
# Python driver
# ----------------------------------------------------------------------------------------------

@dataclass
class RunRecord:
    """Everything a run produced, at the output times (arrays indexed by particle id)."""
    time: list = field(default_factory=list)
    x: list = field(default_factory=list)
    u: list = field(default_factory=list)
    h: list = field(default_factory=list)
    volume: list = field(default_factory=list)
    flow_depth: list = field(default_factory=list)
    deposit_depth: list = field(default_factory=list)
    front: list = field(default_factory=list)
    smoothing_length: list = field(default_factory=list)
    time_step: list = field(default_factory=list)
    steps: list = field(default_factory=list)
    x_edges: np.ndarray | None = None
    status: int = RUNNING
    message: str = ""
    n_steps: int = 0
    x_inf: float = float("nan")
    A: float = float("nan")
    B: float = float("nan")

    @property
    def final_front(self) -> float:
        return float(self.front[-1]) if self.front else float("nan")


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
    from ..cases import G
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


def run_kernel(x, F, order, dep, t, t_target, p: StepParams, tab, nsteps, own):
    """``step.advance`` for a constant slope (no width, no envelopes, no lift-off)."""
    return advance(x, F, order, dep, dep, _NO_CELLS, _NO_ENVELOPES, np.zeros(3), t, t_target, p, tab, nsteps, own)


_NO_CELLS = np.zeros(0)
_NO_ENVELOPES = np.zeros((3, 0))


def initial_state(cfg):
    """The column [0, L0] × [0, H0]: n equal particles at the centres of n equal cells."""
    n = cfg.numerics.n_particles
    dx = cfg.geometry.L0 / n
    x = (np.arange(n) + 0.5) * dx
    F = np.zeros((N_FIELDS, n))
    F[F_V] = cfg.geometry.H0 * dx
    F[F_V0] = F[F_V]
    F[F_K] = 0.0  # the released mass starts in the active state: clipped to k_a at the first stage
    F[F_ND] = 1.0 / dx  # number density of the lattice: first L_s = B dx (eq 25)
    order = np.arange(n, dtype=np.int64)
    return x, F, order


def custom_state(x, volume, u):
    """Any initial particle set (sorted positions x, volumes, velocities): for analytic checks."""
    x = np.array(x, dtype=float)
    n = x.shape[0]
    F = np.zeros((N_FIELDS, n))
    F[F_V] = volume
    F[F_V0] = volume
    F[F_U] = u
    F[F_K] = 0.0  # active state, as the released column
    F[F_ND] = (n - 1) / (x[-1] - x[0])
    return x, F, np.arange(n, dtype=np.int64)


def _grid(cfg, dxg: float):
    ng = int(math.ceil(cfg.geometry.domain_end / dxg))
    return dxg, ng, np.arange(ng + 1) * dxg


def smooth_deposit(dep: np.ndarray, L: float, qc: float, dxg: float) -> np.ndarray:
    """Deposit depth h_D on the grid as an SPH estimate (eq 20 applied to deposited volume).

    ``dep`` holds the deposited volume per cell, put there at the depositing particle's position.
    Where the tip's particles are farther apart than the grid cells, that leaves empty cells
    between them: h + h_D then dips below the front threshold and the front jumps back although
    the material is still there (seen: 1D-A124 front 23 → 17 L0, and x∞ iterations that jump
    across the fixed point). The flow depth is a kernel estimate with smoothing length L_s, so the
    deposit is smoothed with the same Gaussian (cut at qc L_s, weights normalised on the grid) and
    reflected at the back wall x = 0: the deposited volume is conserved to round-off.
    """
    m = max(1, int(math.ceil(qc * L / dxg)))
    offs = np.arange(-m, m + 1) * dxg
    w = np.exp(-(offs / L) ** 2)
    w /= w.sum()
    padded = np.concatenate([dep[:m][::-1], dep, np.zeros(m)])
    return np.convolve(padded, w, mode="valid")[: dep.shape[0]] / dxg


def _record(rec, cfg, x, F, order, dep, t, L, dt, steps, dxg, ng, thr):
    from ..front import main_run_front
    n = x.shape[0]
    qc = cfg.numerics.kernel_support
    wall = cfg.geometry.back_wall
    h = particle_depths(x, F[F_V], L, qc, wall)
    for name, vals in (("x", x), ("u", F[F_U]), ("h", h), ("volume", F[F_V])):
        arr = np.empty(n)
        arr[order] = vals
        getattr(rec, name).append(arr)
    flow = grid_depth(x, F[F_V], L, qc, wall, dxg, ng)
    depo = smooth_deposit(dep, deposit_smoothing_length(L, dxg), qc, dxg)
    rec.flow_depth.append(flow)
    rec.deposit_depth.append(depo.copy())
    rec.front.append(main_run_front(rec.x_edges, flow + depo, thr))
    rec.time.append(t)
    rec.smoothing_length.append(L)
    rec.time_step.append(dt)
    rec.steps.append(steps)


def simulate(cfg, phys: Physics, label: str = "", progress=None, init=None, checkpoint=None) -> RunRecord:
    """Run one DA simulation to rest (or t_end) and return its record.

    A failure (non-finite state, particle leaving the domain, step limit) stops the run: the record
    keeps every output written so far, with ``status`` and ``message`` saying when, at which step
    and where. ``checkpoint`` (``da.checkpoint``): its ``resume()`` gives the state to continue
    from (or None), and ``at_output(state_fn)`` is called after every output time.
    """
    dxg, ng, edges = _grid(cfg, column_grid_spacing(cfg, phys))
    prm = step_params(cfg, phys, dxg)
    tab = constant_bed_table(cfg.theta, phys)
    thr = cfg.front_threshold
    dt_out, t_end = cfg.output.dt_output, cfg.numerics.t_end
    state = checkpoint.resume() if checkpoint is not None else None
    if state is not None:  # continue exactly where the checkpointed run stood after output k - 1
        x, F, order, dep, rec, t, steps, k, own = state
    else:
        x, F, order = initial_state(cfg) if init is None else custom_state(*init)
        dep = np.zeros(ng)
        own = own_trail(x.shape[0], prm.deposition and prm.deposit_as_bed and not prm.own_deposit)
        rec = RunRecord(x_edges=edges, x_inf=phys.x_inf, A=phys.A, B=phys.B)
        L = smoothing_length(F, prm)
        _record(rec, cfg, x, F, order, dep, 0.0, L, 0.0, 0, dxg, ng, thr)
        t, steps = 0.0, 0
        k = 1
    while True:
        t_target = min(k * dt_out, t_end)
        t, steps, status, where, L, dt = run_kernel(x, F, order, dep, t, t_target, prm, tab, steps, own)
        if status in (RUNNING, AT_REST):
            _record(rec, cfg, x, F, order, dep, t, L, dt, steps, dxg, ng, thr)
        if progress is not None:
            progress(lambda: f"DA {label}: t = {t:.3f} s, step {steps}, front {rec.front[-1]:.4f} m, "
                             f"L_s = {L * 1e3:.2f} mm, dt = {dt:.2e} s")
        if status == AT_REST:
            rec.status, rec.message = AT_REST, f"at rest at t = {t:.4f} s after {steps} steps"
            break
        if status == NONFINITE or status == ESCAPED or status == MAX_STEPS:
            xs = np.empty_like(x)
            xs[order] = x
            where_txt = "" if where < 0 else f" particle {where} at x = {xs[where]:.4f} m"
            what = {NONFINITE: "non-finite velocity or position",
                    ESCAPED: f"a particle left the domain (x > x_max = {cfg.geometry.domain_end:.4g} m;"
                             f" raise geometry.x_max)",
                    MAX_STEPS: f"numerics.max_steps = {cfg.numerics.max_steps} reached"}[status]
            rec.status = status
            rec.message = f"DA run {label} stopped at t = {t:.5f} s, step {steps}: {what}{where_txt}"
            break
        if t >= t_end:
            rec.status, rec.message = RUNNING, f"not at rest at numerics.t_end = {t_end} s"
            break
        k += 1
        if checkpoint is not None:
            checkpoint.at_output(lambda: (x, F, order, dep, rec, t, steps, k, own))
    rec.n_steps = steps
    return rec
