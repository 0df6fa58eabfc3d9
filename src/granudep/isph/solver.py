"""Projection ISPH driver: owns the particle state, the time loop, the linear solves and output.

One step (Cummins & Rudman 1999; Shao & Lo 2003; Lind et al. 2012), all per-particle work in the
numba kernels of :mod:`granudep.isph.operators`, :mod:`~granudep.isph.walls`,
:mod:`~granudep.isph.viscous`, :mod:`~granudep.isph.ppe`, :mod:`~granudep.isph.shifting`,
:mod:`~granudep.isph.projection`:

1. neighbour list (cell-linked, rebuilt every step), ∇·r, concentration, renormalisation;
   free-surface particles: ∇·r < ``free_surface_threshold``;
2. rheology from uⁿ, pⁿ: η = μ(I) p/|γ̇| capped at η_max (or Newtonian η);
3. predictor, implicit in the viscous stress: (I − Δt/ρ ∇·η∇) u* = uⁿ + Δt g − Δt/ρ G pⁿ (one
   sparse matrix, two right-hand sides), g = (g sin θ, −g cos θ); the previous pressure's gradient
   G pⁿ only with ``numerics.pressure_correction: incremental`` (the default with the adjoint pair;
   Goda 1979, van Kan 1986), so that the viscous stress and the wall friction act on a velocity the
   pressure already nearly balances;
4. projection (default ``numerics.projection: adjoint_pair``, :mod:`.projection`): PPE
   ((1 − ε) D Dᵀ + ε L_c) p = −ρ/Δt D u* (+ density-invariant source) over the granular and the
   wetted wall nodes, Dirichlet p_fs on the free surface, solved by SSOR-CG (``cg_dic``; two-level CG: ``cg_two_level``), for the velocity
   u* + Δt/ρ G pⁿ (incremental) or u*; corrector uⁿ⁺¹ = u* − Δt/ρ G (pⁿ⁺¹ − pⁿ) (or − Δt/ρ G pⁿ⁺¹),
   G = −Dᵀ, energy-stable. ``approximate`` (the earlier scheme): compact PPE
   Σ a_ij (p_i − p_j) = −ρ/Δt ∇·u*, mirror-pressure Neumann walls, renormalised difference gradient;
5. positions xⁿ⁺¹ = xⁿ + Δt uⁿ⁺¹ + δr (particle shifting).
"""
from __future__ import annotations

import math
import time as _time
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import NamedTuple

import numba
import numpy as np

from ..cases import G
from ..front import FRONT_MEASURE_DOC, front_from_profile, front_measures
from ..progress import LOG, Progress
from . import operators, ppe, shifting, viscous, walls
from .bed import bed_law
from .energy import EnergyBudget, kinetic_energy, potential_energy, pressure_work, viscous_dissipation
from .config import IsphConfig
from .rheology import ill_posed_bounds, regularisation_constant, regularised_viscosity
from .projection import (adjoint_divergence, adjoint_pair_geometry, adjoint_pair_projection, apply_gradient,
                         divergence_entries, wall_normal_acceleration)
from .errors import IsphBlowUp
from .linear_systems import LinearSystems
from .linsolve import pin_blas_to_one_thread
from .bundles import Pairs, WallSurface, pairs_of
from .heap import keep_freed_memory
from .setup import (Particles, build_particles, lattice_constants, reference_concentration,
                    reference_laplacian_sum)


#: the thread that builds the PPE geometry beside the predictor (:meth:`IsphSolver._start_ppe_geometry`),
#: started on first use; module-level, so that a pickled solver carries no thread
_PPE_THREAD: ThreadPoolExecutor | None = None


def _ppe_thread() -> ThreadPoolExecutor:
    global _PPE_THREAD
    if _PPE_THREAD is None:
        _PPE_THREAD = ThreadPoolExecutor(max_workers=1, thread_name_prefix="granudep-ppe")
    return _PPE_THREAD


class Geometry(NamedTuple):
    """Per-step geometry shared by the stages: concentration, ∇C, renormalisation matrices and their
    diagonal, wall contact (planes, columns) and detachment (None where no stage reads them)."""
    conc: np.ndarray
    gcx: np.ndarray
    gcy: np.ndarray
    lmat: np.ndarray
    mdiag: tuple
    contact: np.ndarray | None
    col: np.ndarray | None
    detached: np.ndarray | None


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


#: the per-particle state besides the positions, one row per granular particle: what the renumbering
#: (:meth:`IsphSolver._reorder`) permutes and the outflow (:meth:`IsphSolver._remove`) filters
PARTICLE_FIELDS = ("u", "v", "p", "eta", "gdot", "fs", "p_rheo", "visc_du", "visc_dv", "ids", "wall_an")

#: energy terms stored per snapshot (J m-1), see :mod:`.energy`
ENERGY_TERMS = ("potential", "dissipated", "wall_friction", "projection", "shifting", "clamps", "outflow")


@dataclass
class SolverStats:
    steps: int = 0
    wall_s: float = 0.0
    t_neigh: float = 0.0
    t_kern: float = 0.0
    t_visc: float = 0.0
    t_ppe: float = 0.0
    ppe_iters: int = 0
    visc_iters: int = 0
    clamped: int = 0
    fallbacks: int = 0
    walls_released: int = 0


class IsphSolver:
    """State + stepping for one configuration."""

    def __init__(self, cfg: IsphConfig, particles: Particles | None = None):
        pin_blas_to_one_thread()
        keep_freed_memory()
        self.cfg = cfg
        c = cfg
        if c.numerics.pressure_solver.startswith("amg_"):
            from .amg import have_pyamg
            if not have_pyamg():
                raise ImportError(f"numerics.pressure_solver: {c.numerics.pressure_solver} needs the optional "
                                  "package pyamg (pip install pyamg, or the [amg] extra)")
        self.parts = particles if particles is not None else build_particles(cfg)
        P = self.parts
        self.nf = P.nf
        self.x = P.x.copy()
        self.y = P.y.copy()
        nf = self.nf
        self.u = np.zeros(nf)
        self.v = np.zeros(nf)
        th = c.theta
        self.gx = G * math.sin(th)
        self.gy = -G * math.cos(th)
        self.rho = c.material.rho
        self.dx = c.numerics.dx
        self.h = c.h
        self.vol = self.dx * self.dx
        self.eps2 = 0.01 * self.h * self.h
        self.radius = 2.0 * self.h
        self.period = c.geometry.periodic_length
        # lithostatic initial pressure (used by the rheology of the first step only)
        self.p = np.maximum(self.rho * G * math.cos(th) * (c.geometry.H0 - self.y[:nf]), 0.0)
        self.eta = np.full(nf, c.rheology.eta_max if c.rheology.model == "mu_i" else c.rheology.viscosity)
        self.gdot = np.zeros(nf)
        self.grad = None
        self.p_floor = (0.5 * self.rho * G * math.cos(th) * self.dx
                        if c.rheology.model == "mu_i" and c.rheology.pressure_floor == "half_layer" else 0.0)
        self.p_fs = 0.5 * self.rho * G * math.cos(th) * self.dx if c.numerics.free_surface_pressure == "half_layer" else 0.0
        self.fs = np.zeros(nf, dtype=bool)
        self.c0 = reference_concentration(self.h, self.dx)
        lc = lattice_constants(c.numerics.h_factor, 0.01, c.wall_layers)
        # wall_ns: the no-slip wall stress norm (the stress-limited law's rigid bed); wall_norm: the
        # configured law's (a Navier wall: its slip length in dx), so that its stress is exact
        self.lap_norm, self.wall_ns = lc["lap"], lc["wall_ns"]
        self.wall_norm = (lattice_constants(c.numerics.h_factor, 0.01, c.wall_layers,
                                            c.wall.slip_length / c.numerics.dx)["wall_ns"]
                          if c.wall.slip == "navier" else self.wall_ns)
        self.a_full = (reference_laplacian_sum(self.h, self.dx, self.eps2) / self.lap_norm
                       if c.numerics.kernel_completion else 0.0)
        self.slip = walls.SLIP_CODES[c.wall.slip]
        self.bed = bed_law(self.slip)
        self.mean = viscous.MEAN_CODES[c.rheology.pair_mean]
        planes = [(0.0, 1.0, 0.0)] + ([(1.0, 0.0, 0.0)] if c.geometry.back_wall else [])
        self.planes = np.array(planes, dtype=float)
        # extent of each wall along its tangent t = (-n_y, n_x): bed x in [0, L], back wall y >= 0
        self.plane_lo = np.array([-math.inf] + ([0.0] if c.geometry.back_wall else []))
        self.plane_hi = np.array([math.inf] + ([math.inf] if c.geometry.back_wall else []))
        self.u_eps = c.wall.stick_speed
        self.mu_wall = math.tan(math.radians(c.wall.phi_basal_deg))
        self.t = 0.0
        self.step_no = 0
        self.stats = SolverStats()
        self.linear = LinearSystems(self)
        self.dt = 0.0
        # domain box for escape checks
        self.xmin = -0.5 * self.dx if c.geometry.back_wall else -math.inf
        self.xmax = c.domain_length if self.period <= 0 else math.inf
        self.ymin = -0.5 * self.dx
        self.ymax = c.geometry.H0 + max(1.0, 5.0 * c.geometry.H0)
        # downstream outflow: particles past x = xmax leave the computation (see _check); the
        # state arrays then hold the n_active particles still in the domain, ``ids`` their
        # original indices; snapshots keep all n0 particles (those gone frozen where they left)
        self.outflow = bool(c.geometry.outflow) and self.period <= 0
        self.n0 = nf
        self.ids = np.arange(nf)
        self.outflow_time = np.full(nf, np.nan)
        self.exit_x = np.full(nf, np.nan)
        self.exit_y = np.full(nf, np.nan)
        self.outflow_log: list[tuple] = []      # (particle, t, step, y, speed) per departure
        # particle renumbering (:meth:`_reorder`) every ``reorder_interval`` steps; ``permuted``:
        # the arrays are no longer in the original order (``ids`` maps them back)
        self.reorder_interval = c.numerics.reorder_interval
        self.x_origin = float(self.x.min()) - 0.5 * self.dx
        self.permuted = False
        self.visc_du = None                     # previous viscous increment (cg_dic warm start)
        self.visc_dv = None
        self.visc_dt = 0.0
        self.m = self.rho * self.vol
        rh, m = c.rheology, c.material
        if rh.regularisation == "barker_gray_2017":
            i_n1 = ill_posed_bounds(m.mu_s, m.mu_2, rh.mu_inf, m.I0_standard)[0]
            self.reg = (i_n1, rh.alpha_reg,
                        regularisation_constant(i_n1, m.mu_s, m.mu_2, rh.mu_inf, m.I0_standard, rh.alpha_reg))
        else:
            self.reg = (0.0, rh.alpha_reg, 1.0)
        self.energy = EnergyBudget(
            e0=potential_energy(self.m, self.x[:nf], self.y[:nf], self.gx, self.gy),
            e_ref=max(self.m * G * math.cos(th) * float(np.sum(self.y[:nf])), 1e-300))
        self.e_mech = self.energy.e0
        self.nf_at_energy = nf
        self.p_wall = None                      # adjoint_pair: wall-node pressures
        self.wall_dry = None                    # adjoint_pair: wall nodes held at p = 0 (released)
        self.wall_an = None                     # adjoint_pair: wall-normal reaction per particle and plane

    # ------------------------------------------------------------------------------------------
    @property
    def wall_surface(self) -> WallSurface:
        """The wall particles' surface normals and offsets (the bundle the kernels take)."""
        P = self.parts
        return WallSurface(P.wnx, P.wny, P.wc)

    @property
    def reaction_friction(self) -> bool:
        """Coulomb friction from the walls' normal reaction (wall.coulomb_normal: projection, or auto
        with the adjoint-pair projection, whose walls carry pressure); read from the config, so a
        solver given another config (a benchmark restart) follows it."""
        w, n = self.cfg.wall, self.cfg.numerics
        return w.coulomb_normal == "projection" or (w.coulomb_normal == "auto" and n.projection == "adjoint_pair")

    def gravity_step(self) -> float:
        """The step's gravity cap c sqrt(h/g): c = 0.125 with the adjoint pair, 0.25 otherwise."""
        c_g = 0.125 if self.cfg.numerics.projection == "adjoint_pair" else 0.25
        return c_g * math.sqrt(self.h / G)

    def density_relaxation(self, dt: float) -> float:
        """Weight γ of the density-invariant source −γ ρ/Δt² min(1 − C/C0, 0) in this step
        (``numerics.density_relaxation_form``): γ, or γ Δt/Δt_ref with Δt_ref the gravity cap."""
        n = self.cfg.numerics
        if n.density_relaxation_form == "per_time":
            return n.density_relaxation * min(dt / self.gravity_step(), 1.0)
        return n.density_relaxation

    def time_step(self) -> float:
        n = self.cfg.numerics
        umax = float(np.sqrt(np.max(self.u ** 2 + self.v ** 2))) if self.nf else 0.0
        # gravity-wave bound dt <= c sqrt(h/g): c = 0.25; the adjoint-pair projection needs
        # c = 0.125 (a Newtonian film at dx = 0.5 mm compacted by 14 % within 0.02 s at
        # c = 0.246 and stayed put at c = 0.12-0.18; the 1 mm film, c = 0.17, is stable)
        dt = min(n.dt_max, self.gravity_step())
        if umax > 0:
            dt = min(dt, n.cfl * self.h / umax)
        if not dt > 0.0:
            i = int(np.argmax(self.u ** 2 + self.v ** 2))
            raise IsphBlowUp(f"time step {dt:g} s (max speed {umax:g} m/s) at t={self.t:.5g} s, step {self.step_no}, "
                             f"particle {i} at (x, y) = ({self.x[i]:.4g}, {self.y[i]:.4g}) m")
        return dt

    def step(self, dt: float) -> None:
        """One time step (module doc): a recipe of named, timed stages. With ``numerics.threads_mode:
        overlap`` on more than one numba thread (``auto``: on exactly two), the step's kernels run their
        serial builds in this thread (numba's thread count is per thread) and the PPE geometry is built
        on a second one."""
        threads = numba.get_num_threads()
        mode = self.cfg.numerics.threads_mode
        if threads == 1 or mode == "prange" or (mode == "auto" and threads > 2):
            self._step(dt, False)
            return
        numba.set_num_threads(1)
        try:
            self._step(dt, True)
        finally:
            numba.set_num_threads(threads)

    def _step(self, dt: float, overlap: bool) -> None:
        t0 = _time.perf_counter()
        nb = self._neighbours()
        t1 = _time.perf_counter()
        geo = self._geometry(nb)
        self._rheology(nb, geo)
        t2 = _time.perf_counter()
        # free-surface particles: diagonal renormalisation only (1/M_xx, 1/M_yy); with one-sided
        # support the full inverse mixes the wall-normal pressure gradient into the tangential one
        lmat_p = operators.lmat_pressure(geo.lmat, self.fs, *geo.mdiag)
        dmat = self._divergence_matrix(nb, geo, lmat_p)
        gp_old = self._old_pressure_gradient(dmat)
        t_div = _time.perf_counter()
        ppe_geo = self._start_ppe_geometry(nb, dmat, overlap)
        us, vs = self._predictor(nb, geo, dt, gp_old)
        if gp_old is not None:
            # the projection sees the velocity without the old pressure impulse, so that it solves
            # for the whole pⁿ⁺¹ and uⁿ⁺¹ = u* − Δt/ρ G (pⁿ⁺¹ − pⁿ)
            us = us + dt / self.rho * gp_old[0]
            vs = vs + dt / self.rho * gp_old[1]
        t3 = _time.perf_counter()
        u_old, v_old = self.u, self.v
        self._projection(nb, geo, lmat_p, dmat, us, vs, dt, ppe_geo)
        t4 = _time.perf_counter()
        self._shift_and_move(nb, geo, u_old, v_old, us, vs, dt)
        t5 = _time.perf_counter()
        st = self.stats
        st.steps += 1
        st.t_neigh += t1 - t0
        st.t_kern += (t2 - t1) + (t5 - t4)
        st.t_visc += t3 - t_div
        st.t_ppe += (t4 - t3) + (t_div - t2)
        self.nf_at_energy = self.nf
        self._check()
        self._check_energy()

    def _neighbours(self) -> Pairs:
        """Stage 1a: the particle renumbering (every ``reorder_interval`` steps) and the neighbour list."""
        if self.reorder_interval and self.step_no % self.reorder_interval == 0:
            self._reorder()
        return pairs_of(self.x, self.y, self.nf, self.radius, self.period, self.h)

    def _geometry(self, nb: Pairs) -> Geometry:
        """Stage 1b: kernel values, ∇·r, concentration, renormalisation, free surface, and the wall
        contact where a stage reads it (else None)."""
        c = self.cfg
        nf, h = self.nf, self.h
        divr, conc, gcx, gcy, lmat, mdiag = operators.geometry_terms(nb, nf, h, self.vol)
        self.fs = divr < c.numerics.free_surface_threshold
        contact = col = detached = None
        if c.numerics.projection == "approximate" or (self.slip in walls.FRICTION_LAWS and not self.reaction_friction):
            # the wall contact is read only by the approximate projection (detachment) and by the
            # Coulomb drag from the contact pressure (:class:`.bed.FrictionWall` without the reaction)
            contact, col = walls.wall_contact(nb, nf, self.x, self.y, self.planes, self.dx, h,
                                              c.wall.cover_offset * self.dx)
            detached = walls.detached_from_walls(contact, 0.75 * self.dx)
        return Geometry(conc, gcx, gcy, lmat, mdiag, contact, col, detached)

    def _rheology(self, nb: Pairs, geo: Geometry) -> None:
        """Stage 2: the pressure the friction law sees (eq 5), η and |γ̇| from uⁿ, pⁿ."""
        c = self.cfg
        nf, h = self.nf, self.h
        rh = c.rheology
        # pressure seen by the friction law (eq 5): clipped below at the overburden of half a
        # particle layer, ρ g cosθ dx/2 (free-surface and thin-front particles keep friction)
        if rh.pressure_filter == "mls":
            p_seen = operators.mls_linear_average(nb, nf, h, self.p)
        elif rh.pressure_filter == "shepard":
            p_seen = operators.shepard_average(nb, nf, h, self.p)
        else:
            p_seen = self.p
        self.p_rheo = np.maximum(p_seen, self.p_floor)
        if rh.model != "mu_i" and self.slip != walls.SLIP_NAVIER_OVERWRITE:
            return
        grad = operators.velocity_gradient(nb, nf, self.vol, self.x, self.y, self.u, self.v, geo.lmat, self.wall_surface,
                                           walls.gradient_slip_code(self.slip), c.wall.slip_length, self.dx)
        self.grad = grad  # uⁿ's gradient: the authors' slip (navier_overwrite) reads it after the projection
        if rh.model != "mu_i":
            return
        m = c.material
        if rh.regularisation == "none" and rh.mu_inf == 0.0:
            self.eta, self.gdot = viscous.mu_i_viscosity(grad, self.p_rheo, m.d, m.rho_s, m.mu_s, m.mu_2, m.I0_standard,
                                                         rh.eta_min, rh.eta_max)
        else:
            self.eta, self.gdot = regularised_viscosity(grad, self.p_rheo, m.d, m.rho_s, m.mu_s, m.mu_2,
                                                        rh.mu_inf, m.I0_standard, *self.reg, rh.eta_min, rh.eta_max)

    @property
    def incremental(self) -> bool:
        """The predictor carries −Δt/ρ G pⁿ (``numerics.pressure_correction``; auto: with the adjoint pair)."""
        n = self.cfg.numerics
        return n.pressure_correction == "incremental" or (n.pressure_correction == "auto"
                                                          and n.projection == "adjoint_pair")

    def _divergence_matrix(self, nb: Pairs, geo: Geometry, lmat_p):
        """Stage 2b (adjoint pair): the divergence D in COO (:func:`projection.divergence_entries`),
        shared by the old pressure gradient and the projection; None with the approximate projection."""
        if self.cfg.numerics.projection != "adjoint_pair":
            return None
        return divergence_entries(nb, self.nf, self.vol, lmat_p, self.wall_surface)

    def _old_pressure_gradient(self, dmat):
        """G pⁿ = −Dᵀ pⁿ on the current geometry with the previous step's granular and wall pressures
        (incremental pressure correction); None when not incremental and at the first step (no wall
        pressures yet)."""
        if dmat is None or not self.incremental or self.p_wall is None:
            return None
        return apply_gradient(self.nf, *dmat, np.concatenate((self.p, self.p_wall)))

    def _predictor(self, nb: Pairs, geo: Geometry, dt: float, gp_old=None):
        """Stage 3: the predictor u*, implicit in the viscous stress, with the bed law's wall terms in its
        diagonals (:mod:`.bed`) and (``gp_old``, incremental) the old pressure impulse −Δt/ρ G pⁿ on its right-hand
        side; books the viscous and wall-friction dissipation. Returns (u*, v*)."""
        c = self.cfg
        nf, rho = self.nf, self.rho
        indptr, indices, data, diag_v = viscous.assemble_viscous(nb, nf, self.vol, self.x, self.y,
                                                                 self.eta, self.gdot, self.wall_surface,
                                                                 walls.viscous_slip_code(self.slip), c.wall.slip_length, self.dx, dt, rho, self.eps2,
                                                                 self.mean, self.lap_norm, self.wall_norm)
        diag_v, wall_du, wall_dv = self.bed.predictor_terms(self, nb, geo, dt, data, indptr, diag_v)
        # the velocity the viscous step starts from: uⁿ, less the old pressure impulse (incremental)
        u0, v0 = self.u, self.v
        if gp_old is not None:
            u0 = self.u - dt / rho * gp_old[0]
            v0 = self.v - dt / rho * gp_old[1]
        if c.numerics.viscous_solver == "direct":
            data_v = data.copy()
            data_v[indptr[:-1]] = diag_v
            us = self.linear.direct(indptr, indices, data, u0 + dt * self.gx, "viscous (u)")
            vs = self.linear.direct(indptr, indices, data_v, v0 + dt * self.gy, "viscous (v)")
        else:
            bu = u0 + dt * self.gx
            bv = v0 + dt * self.gy
            dic = c.numerics.viscous_solver == "cg_dic"
            xu0, xv0 = bu, bv
            if dic and self.visc_du is not None:
                # warm start: the right-hand side plus the previous step's viscous increment
                # u* − (uⁿ + Δt g) (∝ Δt, rescaled): T22-A150 u+v iterations 35 -> 29 per step
                # (``cg`` keeps the right-hand side, so that it still repeats scipy's iterates)
                f = dt / self.visc_dt
                xu0 = bu + f * self.visc_du
                xv0 = bv + f * self.visc_dv
            us, vs = self.linear.solve_cg_pair(indptr, indices, data, diag_v, bu, bv, xu0, xv0, dic=dic)
            self.visc_du = us - bu
            self.visc_dv = vs - bv
            self.visc_dt = dt
        eb = self.energy
        # the work of the viscous operator on u* (the old pressure impulse is the projection's, booked
        # there: its pressure work is taken on u* + Δt/ρ G pⁿ)
        eb.dissipated += viscous_dissipation(self.m, u0, v0, us, vs, dt, self.gx, self.gy)
        if wall_du is not None:
            # the wall's share: its diagonal increments times u*² (the drag's work)
            eb.wall_friction += self.m * float(np.dot(wall_du, us * us) + np.dot(wall_dv, vs * vs))
        return us, vs

    def _start_ppe_geometry(self, nb: Pairs, dmat, overlap: bool = False):
        """Stage 2c (adjoint pair): what the projection's PPE needs before u* is known
        (:func:`projection.adjoint_pair_geometry`: the L_c edges, the active set, the triangles). With
        ``overlap`` (:meth:`step`: ``numerics.threads_mode`` and the numba thread count)
        it is built on a second thread while the predictor runs (a Future; the two
        stages share no data and every kernel of both releases the GIL), else here; the same result
        bit for bit either way (``numerics.threads_mode``). None with the approximate projection."""
        if dmat is None:
            return None
        nf = self.nf
        nw = self.parts.wnx.size
        if self.p_wall is None or self.p_wall.size != nw:
            self.p_wall = np.zeros(nw)
        if self.wall_dry is None or self.wall_dry.size != nw:
            self.wall_dry = np.zeros(nw, dtype=bool)
        args = (nb, nf, nw, self.vol, self.fs, self.p_fs, self.eps2, self.lap_norm,
                self.cfg.numerics.projection_stabilisation, self.wall_dry, dmat, self.linear.ppe_form == "triangles")
        if overlap:
            return _ppe_thread().submit(adjoint_pair_geometry, *args)
        return adjoint_pair_geometry(*args)

    def _projection(self, nb: Pairs, geo: Geometry, lmat_p, dmat, us, vs, dt: float, ppe_geo=None) -> None:
        """Stage 4: the pressure projection of u* (adjoint pair or approximate): pⁿ⁺¹ and uⁿ⁺¹."""
        if self.cfg.numerics.projection == "adjoint_pair":
            if isinstance(ppe_geo, Future):
                ppe_geo = ppe_geo.result()
            self._project_adjoint_pair(nb, lmat_p, dmat, geo.conc, us, vs, dt, ppe_geo)
        else:
            self._project_approximate(nb, geo.lmat, lmat_p, geo.conc, us, vs, dt,
                                      geo.detached)

    def _shift_and_move(self, nb: Pairs, geo: Geometry, u_old, v_old, us, vs, dt: float) -> None:
        """Stage 5: particle shifting, the new positions, the wall clamps and their energy terms."""
        c = self.cfg
        nf, h = self.nf, self.h
        eb = self.energy
        ncx, ncy = operators.smoothed_gradient(nb, nf, h, geo.gcx, geo.gcy)
        alpha = (shifting.surface_band(nb, nf, self.fs, h, 2.0 * self.dx)
                 if c.numerics.shifting_surface == "band" else self.fs.astype(np.float64))
        sx, sy = shifting.shifting(nf, geo.gcx, geo.gcy, self.u, self.v, alpha, h, dt, c.numerics.shifting, self.dx,
                                   ncx, ncy)
        eb.projection += pressure_work(self.m, u_old, v_old, us, vs, self.u, self.v)
        overwrite = self.slip == walls.SLIP_NAVIER_OVERWRITE and self.grad is not None
        if overwrite:
            # the authors' slip overwrites the first layer's new velocity: its kinetic-energy change
            # is booked as the wall's work (dissipated when positive, created when negative)
            ke = kinetic_energy(self.m, self.u, self.v)
            walls.navier_overwrite(nb, nf, self.grad, self.u, self.v, self.wall_surface,
                                   walls.OVERWRITE_BAND * self.dx, c.wall.slip_length)
        ke_new = kinetic_energy(self.m, self.u, self.v)
        if overwrite:
            eb.wall_friction += ke - ke_new
            eb.dissipated += ke - ke_new
        eb.shifting += -self.m * (self.gx * float(np.sum(sx)) + self.gy * float(np.sum(sy)))
        self.x[:nf] += dt * self.u + sx
        self.y[:nf] += dt * self.v + sy
        if self.period > 0:
            self.x[:nf] %= self.period
        e_before = ke_new + potential_energy(self.m, self.x[:nf], self.y[:nf], self.gx, self.gy)
        n_clamped = walls.clamp_to_walls(nf, self.x, self.y, self.u, self.v, self.planes, 0.25 * self.dx,
                                         self.plane_lo, self.plane_hi)
        self.stats.clamped += n_clamped
        e_mech = e_before
        if n_clamped:
            e_mech = (kinetic_energy(self.m, self.u, self.v)
                      + potential_energy(self.m, self.x[:nf], self.y[:nf], self.gx, self.gy))
            eb.clamps += e_mech - e_before
        self.e_mech = e_mech
        self.t += dt
        self.step_no += 1

    def _project_approximate(self, nb: Pairs, lmat, lmat_p, conc, us, vs, dt, detached):
        """Approximate projection: compact-Laplacian PPE with mirror-pressure (Neumann) walls, the
        renormalised difference gradient in the corrector."""
        c = self.cfg
        nf, vol, rho = self.nf, self.vol, self.rho
        if c.numerics.ppe_divergence == "adjoint":
            div = adjoint_divergence(nb, nf, vol, us, vs, lmat_p)
        else:
            div = operators.divergence(nb, nf, vol, us, vs, lmat)
        unknown = np.full(nf, -1, np.int64)
        interior = ~self.fs
        n_unknown = int(interior.sum())
        unknown[interior] = np.arange(n_unknown)
        # free-surface Dirichlet value: p = 0 holds on the surface, which lies dx/2 beyond the centre
        # of a free-surface particle: p_fs = ρ g cosθ dx/2 (bed-normal hydrostatics), or 0
        p_new = np.where(self.fs, self.p_fs, 0.0)
        if n_unknown:
            pi, pj, pd, rhs = ppe.assemble_ppe(nb, nf, vol, unknown, n_unknown, p_new, div,
                                               us, vs, conc, self.c0, self.density_relaxation(dt), self.wall_surface, dt,
                                               rho, self.eps2, self.a_full, self.lap_norm)
            p_new[interior] = self.linear.solve_ppe(pi, pj, pd, rhs, self.p[interior])
        self.p = p_new
        gpx, gpy = operators.pressure_gradient(nb, nf, vol, self.p, us, vs, lmat_p, self.wall_surface,
                                               dt, rho, detached)
        self.u = us - dt / rho * gpx
        self.v = vs - dt / rho * gpy

    def _project_adjoint_pair(self, nb: Pairs, lmat_p, dmat, conc, us, vs, dt, ppe_geo=None):
        """Adjoint-pair projection (:func:`projection.adjoint_pair_projection`): G = −Dᵀ, walls carry
        pressure; the pressure cannot raise the kinetic energy except through the free-surface
        Dirichlet value and the density source (docs/model.md)."""
        c = self.cfg
        nf = self.nf
        nw = self.parts.wnx.size
        guess = np.concatenate((self.p, self.p_wall))      # p_wall, wall_dry: set in _start_ppe_geometry
        p, gpx, gpy, self.wall_dry, released = adjoint_pair_projection(
            nb, nf, nw, self.vol, lmat_p, self.wall_surface, self.fs, self.p_fs, us, vs, conc, self.c0,
            self.density_relaxation(dt), dt, self.rho, self.eps2, self.lap_norm,
            c.numerics.projection_stabilisation, guess, self.linear.solve_ppe, self.wall_dry,
            release=c.numerics.wall_release, entries=dmat,
            solve_free=self.linear.solve_ppe_free if self.linear.ppe_form != "csr" else None, free_form=self.linear.ppe_form,
            geometry=ppe_geo)
        self.stats.walls_released += released
        self.p = p[:nf]
        self.p_wall = p[nf:]
        if self.reaction_friction:
            self.wall_an = wall_normal_acceleration(nb, nf, self.vol, lmat_p, self.wall_surface, p, self.rho, self.planes)
        self.u = us - dt / self.rho * gpx
        self.v = vs - dt / self.rho * gpy

    def _check_energy(self) -> None:
        """Energy creation: (E_kin + E_pot + D + outflow − E_0)/E_ref above ``numerics.energy_limit``
        stops the run as a blow-up (naming the time, the step and the stage that gained most)."""
        eb = self.energy
        if self.period > 0:          # periodic layers: x wraps, E_pot is not defined
            return
        e_mech = self.e_mech if self.nf == self.nf_at_energy else self.mechanical_energy()
        excess = eb.residual(e_mech) / eb.e_ref
        if excess > eb.max_excess:
            eb.max_excess, eb.max_excess_time = excess, self.t
        if excess > self.cfg.numerics.energy_limit:
            stages = {"projection": eb.projection, "shifting": eb.shifting, "wall clamps": eb.clamps}
            worst = max(stages, key=stages.get)
            raise IsphBlowUp(f"energy rose above E_0 by {100 * excess:.2f} % of E_ref at t={self.t:.5f} s, "
                             f"step {self.step_no} (limit numerics.energy_limit = "
                             f"{100 * self.cfg.numerics.energy_limit:g} %; largest gain: {worst} "
                             f"{stages[worst] / eb.e_ref * 100:+.2f} %)")

    def mechanical_energy(self) -> float:
        """E_kin + E_pot of the particles in the domain."""
        nf = self.nf
        return (kinetic_energy(self.m, self.u, self.v)
                + potential_energy(self.m, self.x[:nf], self.y[:nf], self.gx, self.gy))

    def _take_rows(self, index) -> None:
        """Permute (an index array) or filter (a mask) every per-particle array of PARTICLE_FIELDS
        present with one row per granular particle (the positions are handled by the callers)."""
        nf = self.nf
        for name in PARTICLE_FIELDS:
            a = getattr(self, name, None)
            if a is not None and np.ndim(a) >= 1 and a.shape[0] == nf:
                setattr(self, name, a[index])

    def _reorder(self) -> None:
        """Renumber the granular particles in natural order: columns of width dx (down-slope), by
        height within a column, as the initial lattice is numbered. The flow mixes the numbering,
        which slows the (M)IC preconditioner, the triangular sweeps and the neighbour loops
        (T22-A70 at 4 mm, mid-run: 4.47 -> 3.68 ms per step with a renumbering every 10 steps);
        numbering by the 2h cells of the neighbour search instead doubled the PPE iterations.
        Every per-particle array is permuted; ``ids`` keeps the original index of each particle
        (outputs are written in that order, see :meth:`full`)."""
        nf = self.nf
        col = np.floor((self.x[:nf] - self.x_origin) / self.dx)
        perm = np.lexsort((self.y[:nf], col))
        if np.array_equal(perm, np.arange(nf)):
            return
        self.x[:nf] = self.x[:nf][perm]
        self.y[:nf] = self.y[:nf][perm]
        self._take_rows(perm)
        self.permuted = True

    def _check(self) -> None:
        """NaN anywhere, or a particle through the bed, back wall or top: IsphBlowUp. A finite
        particle past the downstream end of the bed (x > domain_length) with ``geometry.outflow``
        leaves through the outflow (:meth:`_remove`), which is not a failure."""
        nf = self.nf
        bad = ~(np.isfinite(self.u) & np.isfinite(self.v) & np.isfinite(self.p))
        if bad.any():
            k = int(np.flatnonzero(bad)[0])
            raise IsphBlowUp(f"non-finite velocity/pressure at t={self.t:.5f} s, step {self.step_no}, "
                             f"particle {int(self.ids[k])} at (x, y) = ({self.x[k]:.4f}, {self.y[k]:.4f}) m")
        x, y = self.x[:nf], self.y[:nf]
        inside_y = (y >= self.ymin) & (y <= self.ymax)
        if self.outflow:
            gone = (x > self.xmax) & np.isfinite(x) & inside_y
            if gone.any():
                self._remove(gone)
                nf = self.nf
                x, y = self.x[:nf], self.y[:nf]
        out = (x < self.xmin) | (x > self.xmax) | (y < self.ymin) | (y > self.ymax) | ~np.isfinite(x) | ~np.isfinite(y)
        if out.any():
            k = int(np.flatnonzero(out)[0])
            x, y = x.copy(), y.copy()
            k_id = int(self.ids[k])
            raise IsphBlowUp(f"particle {k_id} left the domain at t={self.t:.5f} s, step {self.step_no}: "
                             f"(x, y) = ({x[k]:.4f}, {y[k]:.4f}) m outside x in [{self.xmin:.4f}, {self.xmax:.4f}],"
                             f" y in [{self.ymin:.4f}, {self.ymax:.4f}]")

    def _remove(self, gone: np.ndarray) -> None:
        """Take the granular particles ``gone`` (mask over the active ones) out of the computation:
        they passed the downstream end of the bed. Their exit time and place are kept; the wall
        particles (stored after the granular ones) are untouched."""
        nf = self.nf
        idx = np.flatnonzero(gone)
        keep = ~gone
        orig = self.ids[idx]
        self.outflow_time[orig] = self.t
        self.exit_x[orig] = self.x[idx]
        self.exit_y[orig] = self.y[idx]
        speed = np.hypot(self.u[idx], self.v[idx])
        self.energy.outflow += (kinetic_energy(self.m, self.u[idx], self.v[idx])
                                + potential_energy(self.m, self.x[idx], self.y[idx], self.gx, self.gy))
        for k, i in enumerate(orig):
            self.outflow_log.append((int(i), self.t, self.step_no, float(self.y[idx[k]]), float(speed[k])))
            if len(self.outflow_log) <= 20:
                LOG.warning("isph %s: particle %d left through the downstream outflow (x = %.3f m) at t=%.5f s, "
                            "step %d, y = %.4f m, speed %.3f m/s", self.cfg.case, i, self.xmax, self.t,
                            self.step_no, self.y[idx[k]], speed[k])
            elif len(self.outflow_log) == 21:
                LOG.warning("isph %s: further outflow departures are counted, not logged", self.cfg.case)
        self.x = np.concatenate([self.x[:nf][keep], self.x[nf:]])
        self.y = np.concatenate([self.y[:nf][keep], self.y[nf:]])
        self._take_rows(keep)
        self.nf = int(keep.sum())

    def full(self, a: np.ndarray, fill: float = 0.0) -> np.ndarray:
        """A per-particle array of the active particles spread over all n0 original particles
        (``fill`` for those gone through the outflow)."""
        if self.nf == self.n0 and not self.permuted:
            return a
        out = np.full(self.n0, fill, dtype=a.dtype)
        out[self.ids] = a
        return out

    @property
    def n_outflow(self) -> int:
        return self.n0 - self.nf

    # ------------------------------------------------------------------------------------------
    def kinetic_energy(self) -> float:
        return float(0.5 * self.rho * self.vol * np.sum(self.u ** 2 + self.v ** 2))

    def mass_speed(self, front: float, measure: str = "rms") -> float:
        """Max or root-mean-square speed of the granular particles behind the front (x <= front)."""
        if self.nf == 0:
            return 0.0
        sel = self.x[:self.nf] <= front if math.isfinite(front) else np.ones(self.nf, bool)
        if not sel.any():
            sel = np.ones(self.nf, bool)
        sp2 = self.u[sel] ** 2 + self.v[sel] ** 2
        return float(np.sqrt(np.max(sp2) if measure == "max" else np.mean(sp2)))

    def max_speed(self) -> float:
        return float(np.sqrt(np.max(self.u ** 2 + self.v ** 2))) if self.nf else 0.0

    def front(self) -> float:
        """Front: granular particles binned into bed-parallel cells of width dx; cell depth =
        max y + dx/2 (0 if empty; gaps of <= 2 empty cells closed); then the shared front rule
        (first cell thinner than threshold)."""
        return front_position(self.x[:self.nf], self.y[:self.nf], self.dx, self.cfg.front_depth_threshold,
                              self.cfg.domain_length)


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


def front_position(x: np.ndarray, y: np.ndarray, dx: float, threshold: float, length: float) -> float:
    edges, depth = surface_profile(x, y, dx, length)
    return front_from_profile(edges, depth, threshold)


def area_ratio(x: np.ndarray, y: np.ndarray, dx: float, length: float) -> float:
    """Area under the binned surface profile / (N dx²): the bulk-volume conservation measure of the
    run (1 = the particles fill exactly their volume; < 1 = the mass compressed or particles
    clumped). Each particle carries dx², so mass is conserved by construction; this is the error
    of the incompressibility constraint (thin layers, where every particle is a free-surface
    particle without a pressure equation, are where it is lost)."""
    if x.size == 0:
        return float("nan")
    edges, depth = surface_profile(x, y, dx, length)
    return float(depth.sum() * dx / (x.size * dx * dx))


def surface_profile(x: np.ndarray, y: np.ndarray, dx: float, length: float):
    """Bed cells of width dx (edges) and the depth of the granular mass in each: max y + dx/2."""
    ncell = int(math.ceil(length / dx)) + 1
    edges = np.arange(ncell + 1) * dx
    idx = np.clip((x / dx).astype(np.int64), 0, ncell - 1)
    depth = np.zeros(ncell)
    np.maximum.at(depth, idx, y + 0.5 * dx)
    # close gaps of at most two empty cells (2 dx < the kernel support 2h: the particles on either
    # side still interact): a thin deposit one or two particles thick has such gaps, which moved the
    # front of T22-A70 at dx = 8 mm back and forth between 0.55 and 1.11 m after rest
    left = np.maximum(np.concatenate([[0.0], depth[:-1]]), np.concatenate([[0.0, 0.0], depth[:-2]]))
    right = np.maximum(np.concatenate([depth[1:], [0.0]]), np.concatenate([depth[2:], [0.0, 0.0]]))
    depth = np.where(depth > 0.0, depth, np.minimum(left, right))
    return edges, depth


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
