"""The time loop of a 2D ISPH run: steps the solver (:class:`.stepper.IsphSolver`) to rest or t_end,
stores snapshots every ``output.dt_output``, applies the rest rule, reports progress and calls the
checkpoint hooks (:mod:`.checkpoint`)."""
from __future__ import annotations

import math
import time as _time
from dataclasses import dataclass, field

import numpy as np

from ..front import FRONT_MEASURE_DOC, front_from_profile, front_measures
from ..progress import Progress
from .config import IsphConfig
from .energy import potential_energy
from .errors import IsphBlowUp
from .heap import keep_freed_memory
from .linsolve import pin_blas_to_one_thread
from .profile import area_ratio, surface_profile
from .stepper import IsphSolver

#: energy terms stored per snapshot (J m-1), see :mod:`.energy`
ENERGY_TERMS = ("potential", "dissipated", "wall_friction", "projection", "shifting", "clamps", "outflow")


@dataclass
class Snapshots:
    time: list = field(default_factory=list)
    fields: dict = field(default_factory=lambda: {k: [] for k in
                                                  ("x", "y", "u", "v", "pressure", "viscosity", "free_surface")})
    front: list = field(default_factory=list)
    kinetic: list = field(default_factory=list)
    area: list = field(default_factory=list)
    max_speed: list = field(default_factory=list)
    steps: list = field(default_factory=list)
    energy: dict = field(default_factory=lambda: {k: [] for k in ENERGY_TERMS})
    fronts: dict = field(default_factory=lambda: {k: [] for k in FRONT_MEASURE_DOC})


def step_towards(dt: float, remaining: float) -> float:
    """Time step that lands on a target time ``remaining`` ahead without a sliver step: the last
    two steps before it share the remainder. A sliver (Δt → 0) would blow up the projection
    pressure, which scales like (ρ/Δt) ∇·u* (the divergence left in uⁿ divided by Δt): with the
    snapshot times cut into the CFL steps, T22-A70 at dx = 4 mm saw pressures 10³ ρ g H0 at the
    bed, which the μ(I) law (η = μ p/|γ̇|) and the Coulomb wall friction (μ_B p) then used."""
    if remaining <= dt * (1.0 + 1e-9):
        return remaining
    if remaining < 2.0 * dt:
        return 0.5 * remaining
    return dt


@dataclass
class RunState:
    """Everything the time loop of :func:`run` carries from one step to the next: the solver (particles,
    warm-start arrays, statistics, energy budget), the snapshots so far and the loop's counters. A
    checkpoint (:mod:`.checkpoint`) is this object pickled after a step; :func:`run` given it
    continues exactly where it stood."""
    solver: IsphSolver
    snaps: Snapshots
    next_out: float
    rest_since: float | None = None
    started: bool = False
    time_to_rest: float = float("nan")
    status: str = "t_end reached"
    done: bool = False


def run(cfg: IsphConfig, on_snapshot=None, progress: Progress | None = None, solver: IsphSolver | None = None,
        checkpoint=None):
    """Advance to rest or t_end, storing snapshots every ``output.dt_output``.

    Returns (solver, snapshots, status, time_to_rest). Raises IsphBlowUp with the partial
    snapshots attached (``exc.snapshots``) on NaN or escape. ``checkpoint``
    (:class:`.checkpoint.IsphCheckpointer`): its ``resume()`` gives a :class:`RunState` to continue,
    its ``after_step(state, at_output)`` is called after every step (it writes the checkpoint file
    when due, and at an output time when SIGTERM/SIGINT asked for a stop).
    """
    out = cfg.output
    pin_blas_to_one_thread()     # also for a solver unpickled from a checkpoint (no __init__)
    keep_freed_memory()
    st = checkpoint.resume() if checkpoint is not None else None
    resumed = st is not None
    if st is None:
        st = RunState(solver if solver is not None else IsphSolver(cfg), Snapshots(), out.dt_output)
    s, snaps = st.solver, st.snaps
    t_end = cfg.t_end
    progress = progress or Progress(out.progress_every_s)
    tol = 1e-9

    def snap():
        # every snapshot holds all n0 particles: those gone through the outflow sit where they left
        # (x = domain length) at rest, with p = 0 and free_surface = 1
        nf = s.nf
        snaps.time.append(s.t)
        f = snaps.fields
        xs, ys = s.x[:nf], s.y[:nf]
        if nf < s.n0 or s.permuted:
            xs = s.exit_x.copy()
            xs[s.ids] = s.x[:nf]
            ys = s.exit_y.copy()
            ys[s.ids] = s.y[:nf]
        f["x"].append(xs.astype(np.float32))
        f["y"].append(ys.astype(np.float32))
        f["u"].append(s.full(s.u).astype(np.float32))
        f["v"].append(s.full(s.v).astype(np.float32))
        f["pressure"].append(s.full(s.p).astype(np.float32))
        f["viscosity"].append(s.full(s.eta).astype(np.float32))
        f["free_surface"].append(s.full(s.fs, True).astype(np.int8))
        edges, depth = surface_profile(s.x[:nf], s.y[:nf], s.dx, cfg.domain_length)
        snaps.front.append(front_from_profile(edges, depth, cfg.front_depth_threshold))
        for k, val in front_measures(edges, depth, cfg.material.d).items():
            snaps.fronts[k].append(val)
        snaps.kinetic.append(s.kinetic_energy())
        eb = s.energy
        e_pot = potential_energy(s.m, s.x[:nf], s.y[:nf], s.gx, s.gy) if s.period <= 0 else float("nan")
        for k, val in (("potential", e_pot), ("dissipated", eb.dissipated), ("wall_friction", eb.wall_friction),
                       ("projection", eb.projection),
                       ("shifting", eb.shifting), ("clamps", eb.clamps), ("outflow", eb.outflow)):
            snaps.energy[k].append(val)
        snaps.area.append(area_ratio(s.x[:nf], s.y[:nf], s.dx, cfg.domain_length))
        snaps.max_speed.append(s.max_speed())
        snaps.steps.append(s.step_no)
        if on_snapshot is not None:
            on_snapshot(s, snaps)

    def message():
        el = max(s.stats.wall_s, 1e-9)
        return (f"isph {cfg.case}: t={s.t:.4f} s ({s.t / cfg.t_c:.2f} t_c), steps={s.step_no}, "
                f"{s.step_no / el:.1f} steps/s, dt={s.dt:.2e} s, front={snaps.front[-1] if snaps.front else float('nan'):.4f} m, "
                f"KE={s.kinetic_energy():.3e} J/m, max|u|={s.max_speed():.3e} m/s")

    if not resumed:
        snap()
    wall0 = _time.perf_counter() - s.stats.wall_s  # a restart goes on counting the wall time
    try:
        while not st.done and s.t < t_end - tol:
            if s.step_no >= cfg.numerics.max_steps:
                st.status = f"max_steps ({cfg.numerics.max_steps}) reached"
                break
            if s.nf == 0:
                st.status = "every particle left through the outflow"
                break
            dt = s.time_step()
            dt = step_towards(dt, min(st.next_out, t_end) - s.t)
            s.dt = dt
            s.step(dt)
            s.stats.wall_s = _time.perf_counter() - wall0
            at_output = s.t >= st.next_out - tol
            if at_output:
                snap()
                st.next_out += out.dt_output
                # rest: the max speed of all granular particles (every particle deposited), or the
                # rms speed of those behind the front (a gap of one empty dx cell in a thin deposit
                # moves the front back, so the max is taken over all particles)
                vmax = s.mass_speed(math.inf if out.rest_measure == "max" else snaps.front[-1], out.rest_measure)
                # the flow has started once the mass moves faster than the rest speed (a slow
                # flat collapse never reaches 10x it: that rule put every such rest at 5 t_c)
                if vmax > out.rest_speed or s.t > 5.0 * cfg.t_c:
                    st.started = True
                if st.started and vmax < out.rest_speed:
                    if st.rest_since is None:
                        st.rest_since = s.t
                else:
                    st.rest_since = None
                if st.rest_since is not None and s.t - st.rest_since >= out.rest_duration - tol:
                    st.time_to_rest = st.rest_since
                    if out.stop_at_rest:
                        st.status = "at rest"
                        st.done = True
            if checkpoint is not None:
                checkpoint.after_step(st, at_output)
            if at_output:
                progress(message)  # raises the stage's interruption when SIGTERM/SIGINT asked for a stop
    except IsphBlowUp as exc:
        s.stats.wall_s = _time.perf_counter() - wall0
        exc.snapshots = snaps
        exc.solver = s
        raise
    s.stats.wall_s = _time.perf_counter() - wall0
    status, time_to_rest, rest_since = st.status, st.time_to_rest, st.rest_since
    if math.isnan(time_to_rest) and rest_since is not None and s.t - rest_since >= out.rest_duration - tol:
        time_to_rest = rest_since
    if status != "at rest" and not math.isnan(time_to_rest):
        status = "at rest"
    progress(message, final=True)
    return s, snaps, status, time_to_rest
