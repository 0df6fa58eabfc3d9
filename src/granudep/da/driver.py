"""The one DA time loop: a column on a constant slope and a run along a path profile are the same
driver on a different :class:`Track`.

The physics of a step is ``step.advance`` (its stages in ``step.py``, the SPH sums in ``sph.py``,
the per-particle formulas in ``physics.py``); what the bed looks like reaches it as data (the bed
table and ``StepParams``). What differs between a column and a path is only where the particles run:
the fixed grid that holds the deposit and reads the profiles and the front, the channel width on
it, and how a place is named in a message (x from the back wall, or the station s along the bed).
That is a :class:`Track`; ``solver.column_track`` and ``path_solver.path_track`` build one.

Every output time the driver appends the particle states, the depth profiles on the grid and the
front to one :class:`DARecord`. A failure (non-finite state, a particle leaving the track, the step
limit) stops the run: the record keeps every output written so far, with ``status`` and
``message`` saying when, at which step and where.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..front import main_run_front
from .sph import F_U, F_V, grid_depth, particle_depths
from .step import (AT_REST, E_T, ESCAPED, MAX_STEPS, NONFINITE, RUNNING, advance, deposit_smoothing_length,
                   mark_envelopes, own_trail, smoothing_length)


@dataclass
class DARecord:
    """Everything a run produced, at the output times (particle arrays indexed by particle id)."""
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
    envelopes: np.ndarray | None = None     # (3, cells): max depth, max |u|, arrival time (a path)
    diag: np.ndarray | None = None          # lift-off count, largest deficit, where (a path)
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


@dataclass(frozen=True)
class Track:
    """Where the particles run: the fixed grid (cells of ``dx_grid`` from coordinate 0), the channel
    width on it, and how a place on it is named."""
    dx_grid: float
    n_cells: int
    width_cells: np.ndarray | None = None             # width per cell; None: unit width (a column)
    width_at: Callable[[np.ndarray], np.ndarray] | None = None   # width at particle coordinates
    origin: float = 0.0                               # name of coordinate 0 (the station of the back wall)
    coordinate: str = "x"                             # how a place is named in messages
    name: str = "DA"                                  # "DA" or "DA path", in progress and stop messages
    escaped: str = "a particle left the domain"       # the stop message when one does
    envelopes: bool = False                           # keep along-track envelopes (max depth, speed, arrival)

    @property
    def edges(self) -> np.ndarray:
        return np.arange(self.n_cells + 1) * self.dx_grid


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


def record_output(rec: DARecord, cfg, track: Track, x, F, order, dep, t, L, dt, steps) -> None:
    """Append one output time: particle states by id, flow and deposit depth on the grid, the front."""
    n = x.shape[0]
    qc = cfg.numerics.kernel_support
    wall = cfg.geometry.back_wall
    dxg = track.dx_grid
    h = particle_depths(x, F[F_V], L, qc, wall)
    if track.width_at is not None:
        h = h / track.width_at(x)
    for name, vals in (("x", x), ("u", F[F_U]), ("h", h), ("volume", F[F_V])):
        arr = np.empty(n)
        arr[order] = vals
        getattr(rec, name).append(arr)
    flow = grid_depth(x, F[F_V], L, qc, wall, dxg, track.n_cells)
    depo = smooth_deposit(dep, deposit_smoothing_length(L, dxg), qc, dxg)
    width = 1.0
    if track.width_cells is not None:
        width = track.width_cells
        flow, depo = flow / width, depo / width
    rec.flow_depth.append(flow)
    rec.deposit_depth.append(depo)
    rec.deposited_volume.append(float(np.sum(dep)))
    rec.front.append(main_run_front(rec.x_edges, flow + depo, cfg.front_threshold, width))
    rec.time.append(t)
    rec.smoothing_length.append(L)
    rec.time_step.append(dt)
    rec.steps.append(steps)


def new_record(track: Track, phys) -> DARecord:
    env = np.zeros((3, track.n_cells if track.envelopes else 0))
    env[E_T] = np.inf
    return DARecord(x_edges=track.edges, x_inf=phys.x_inf, A=phys.A, B=phys.B, envelopes=env, diag=np.zeros(3))


def run(cfg, track: Track, prm, tab, state, phys, label: str = "", progress=None, checkpoint=None) -> DARecord:
    """Run one DA simulation from ``state`` = (x, F, order) to rest (or ``numerics.t_end``).

    ``checkpoint`` (``da.checkpoint``): its ``resume()`` gives the state to continue from (or None),
    and ``at_output(state_fn)`` is called after every output time."""
    resumed = checkpoint.resume() if checkpoint is not None else None
    if resumed is not None:  # continue exactly where the checkpointed run stood after output k - 1
        x, F, order, dep, rec, t, steps, k, own = resumed
    else:
        x, F, order = state
        dep = np.zeros(track.n_cells)
        own = own_trail(x.shape[0], prm.deposition and prm.deposit_as_bed and not prm.own_deposit)
        rec = new_record(track, phys)
        L = smoothing_length(F, prm)
        if track.envelopes:  # the release itself: its depth and arrival time 0 in its cells
            h0 = particle_depths(x, F[F_V], L, cfg.numerics.kernel_support, cfg.geometry.back_wall)
            if track.width_at is not None:
                h0 = h0 / track.width_at(x)
            mark_envelopes(rec.envelopes, x, x, h0, F[F_U], F[F_V], 0.0, track.dx_grid, cfg.front_threshold)
        record_output(rec, cfg, track, x, F, order, dep, 0.0, L, 0.0, 0)
        t, steps, k = 0.0, 0, 1
    if track.width_cells is not None:   # deposit per cell and per unit width (the bed term)
        depb, binv = np.zeros(track.n_cells), 1.0 / track.width_cells
    else:
        depb, binv = dep, _NO_CELLS
    dt_out, t_end = cfg.output.dt_output, cfg.numerics.t_end
    while True:
        t_target = min(k * dt_out, t_end)
        t, steps, status, where, L, dt = advance((x, F, order), (dep, depb, binv, own), (rec.envelopes, rec.diag),
                                                 t, t_target, prm, tab, steps)
        if status in (RUNNING, AT_REST):
            record_output(rec, cfg, track, x, F, order, dep, t, L, dt, steps)
        if progress is not None:
            progress(lambda: f"{track.name} {label}: t = {t:.3f} s, step {steps}, front {track.coordinate} = "
                             f"{rec.front[-1] + track.origin:.4f} m, L_s = {L * 1e3:.3g} mm, dt = {dt:.2e} s")
        if status == AT_REST:
            rec.status, rec.message = AT_REST, f"at rest at t = {t:.4f} s after {steps} steps"
            break
        if status in (NONFINITE, ESCAPED, MAX_STEPS):
            xs = np.empty_like(x)
            xs[order] = x
            where_txt = "" if where < 0 else f" particle {where} at {track.coordinate} = {xs[where] + track.origin:.4f} m"
            what = {NONFINITE: "non-finite velocity or position", ESCAPED: track.escaped,
                    MAX_STEPS: f"numerics.max_steps = {cfg.numerics.max_steps} reached"}[status]
            rec.status = status
            rec.message = f"{track.name} run {label} stopped at t = {t:.5f} s, step {steps}: {what}{where_txt}"
            break
        if t >= t_end:
            rec.status, rec.message = RUNNING, f"not at rest at numerics.t_end = {t_end} s"
            break
        k += 1
        if checkpoint is not None:
            checkpoint.at_output(lambda: (x, F, order, dep, rec, t, steps, k, own))
    rec.n_steps = steps
    rec.final_deposit_volume = dep.copy()
    return rec


_NO_CELLS = np.zeros(0)
