"""The step recipe of the projection ISPH: one time step as a short list of named stages, on the
particle state of :mod:`.state` (the time loop is :mod:`.run`).

One step (Cummins & Rudman 1999; Shao & Lo 2003; Lind et al. 2012), all per-particle work in the
numba kernels of :mod:`granudep.isph.operators`, :mod:`~granudep.isph.walls`,
:mod:`~granudep.isph.viscous`, :mod:`~granudep.isph.shifting`,
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
   G = −Dᵀ, energy-stable. ``approximate`` (the earlier scheme, in its own module :mod:`.approximate`): compact PPE
   Σ a_ij (p_i − p_j) = −ρ/Δt ∇·u*, mirror-pressure Neumann walls, renormalised difference gradient;
5. positions xⁿ⁺¹ = xⁿ + Δt uⁿ⁺¹ + δr (particle shifting).
"""
from __future__ import annotations

import math
import time as _time
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass
from typing import NamedTuple

import numba
import numpy as np

from ..cases import G
from . import approximate, operators, shifting, viscous, walls
from .bed import bed_law
from .bundles import Pairs, WallSurface, pairs_of
from .config import IsphConfig
from .energy import kinetic_energy, potential_energy, pressure_work, viscous_dissipation
from .errors import IsphBlowUp
from .heap import keep_freed_memory
from .linear_systems import LinearSystems
from .linsolve import pin_blas_to_one_thread
from .ppe_operator import apply_gradient, wall_normal_acceleration
from .projection import adjoint_pair_geometry, adjoint_pair_projection, divergence_entries
from .rheology import ill_posed_bounds, regularisation_constant, regularised_viscosity
from .setup import Particles, lattice_constants, reference_concentration, reference_laplacian_sum
from .state import ParticleState


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
    diagonal, and the wall contact (planes, columns; None where the bed law does not read it)."""
    conc: np.ndarray
    gcx: np.ndarray
    gcy: np.ndarray
    lmat: np.ndarray
    mdiag: tuple
    contact: np.ndarray | None
    col: np.ndarray | None


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


class IsphSolver(ParticleState):
    """The particle state with the scheme's constants and the step recipe for one configuration."""

    def __init__(self, cfg: IsphConfig, particles: Particles | None = None):
        pin_blas_to_one_thread()
        keep_freed_memory()
        c = cfg
        if c.numerics.pressure_solver.startswith("amg_"):
            from .amg import have_pyamg
            if not have_pyamg():
                raise ImportError(f"numerics.pressure_solver: {c.numerics.pressure_solver} needs the optional "
                                  "package pyamg (pip install pyamg, or the [amg] extra)")
        super().__init__(cfg, particles)
        th = c.theta
        self.h = c.h
        self.eps2 = 0.01 * self.h * self.h
        self.radius = 2.0 * self.h
        self.grad = None
        self.p_floor = (0.5 * self.rho * G * math.cos(th) * self.dx
                        if c.rheology.model == "mu_i" and c.rheology.pressure_floor == "half_layer" else 0.0)
        self.p_fs = 0.5 * self.rho * G * math.cos(th) * self.dx if c.numerics.free_surface_pressure == "half_layer" else 0.0
        self.c0 = reference_concentration(self.h, self.dx)
        lc = lattice_constants(c.numerics.h_factor, 0.01, c.wall_layers)
        self.slip = walls.SLIP_CODES[c.wall.slip]
        self.bed = bed_law(self.slip)
        # wall_ns: the no-slip wall stress norm (the stress-limited law's rigid bed); wall_norm: the
        # configured law's (a Navier wall: its slip length in dx), so that its stress is exact
        self.lap_norm, self.wall_ns = lc["lap"], lc["wall_ns"]
        self.wall_norm = self.bed.wall_norm(c, self.wall_ns)
        self.a_full = (reference_laplacian_sum(self.h, self.dx, self.eps2) / self.lap_norm
                       if c.numerics.kernel_completion else 0.0)
        self.mean = viscous.MEAN_CODES[c.rheology.pair_mean]
        planes = [(0.0, 1.0, 0.0)] + ([(1.0, 0.0, 0.0)] if c.geometry.back_wall else [])
        self.planes = np.array(planes, dtype=float)
        # extent of each wall along its tangent t = (-n_y, n_x): bed x in [0, L], back wall y >= 0
        self.plane_lo = np.array([-math.inf] + ([0.0] if c.geometry.back_wall else []))
        self.plane_hi = np.array([math.inf] + ([math.inf] if c.geometry.back_wall else []))
        self.u_eps = c.wall.stick_speed
        self.mu_wall = math.tan(math.radians(c.wall.phi_basal_deg))
        self.stats = SolverStats()
        self.linear = LinearSystems(self)
        self.visc_du = None                     # previous viscous increment (cg_dic warm start)
        self.visc_dv = None
        self.visc_dt = 0.0
        rh, m = c.rheology, c.material
        if rh.regularisation == "barker_gray_2017":
            i_n1 = ill_posed_bounds(m.mu_s, m.mu_2, rh.mu_inf, m.I0_standard)[0]
            self.reg = (i_n1, rh.alpha_reg,
                        regularisation_constant(i_n1, m.mu_s, m.mu_2, rh.mu_inf, m.I0_standard, rh.alpha_reg))
        else:
            self.reg = (0.0, rh.alpha_reg, 1.0)
        self.p_wall = None                      # adjoint_pair: wall-node pressures
        self.wall_dry = None                    # adjoint_pair: wall nodes held at p = 0 (released)
        self.wall_an = None                     # adjoint_pair: wall-normal reaction per particle and plane

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
        contact where the bed law reads it (else None)."""
        c = self.cfg
        nf, h = self.nf, self.h
        divr, conc, gcx, gcy, lmat, mdiag = operators.geometry_terms(nb, nf, h, self.vol)
        self.fs = divr < c.numerics.free_surface_threshold
        contact = col = None
        if self.bed.needs_contact(self):
            contact, col = walls.wall_contact(nb, nf, self.x, self.y, self.planes, self.dx, h,
                                              c.wall.cover_offset * self.dx)
        return Geometry(conc, gcx, gcy, lmat, mdiag, contact, col)

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
        if rh.model != "mu_i" and not self.bed.needs_velocity_gradient:
            return
        grad = operators.velocity_gradient(nb, nf, self.vol, (self.x, self.y), (self.u, self.v), geo.lmat, self.wall_surface,
                                           walls.gradient_slip_code(self.slip), c.wall.slip_length, self.dx)
        self.grad = grad  # uⁿ's gradient: a bed law may read it after the projection (:class:`.bed.NavierOverwrite`)
        if rh.model != "mu_i":
            return
        m = c.material
        if rh.regularisation == "none" and rh.mu_inf == 0.0:
            self.eta, self.gdot = viscous.mu_i_viscosity(grad, self.p_rheo, m.d, m.rho_s, m.mu_s, m.mu_2, m.I0_standard,
                                                         rh.eta_min, rh.eta_max)
        else:
            law = (m.mu_s, m.mu_2, rh.mu_inf, m.I0_standard, *self.reg)
            self.eta, self.gdot = regularised_viscosity(grad, self.p_rheo, m.d, m.rho_s, law, (rh.eta_min, rh.eta_max))

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
        indptr, indices, data, diag_v = viscous.assemble_viscous(
            nb, nf, self.vol, (self.x, self.y), (self.eta, self.gdot), self.wall_surface,
            (walls.viscous_slip_code(self.slip), c.wall.slip_length), (self.dx, dt, rho, self.eps2, self.lap_norm),
            self.mean, self.wall_norm)
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
        else:   # the study variant, kept in its own module (:mod:`.approximate`)
            approximate.project(self, nb, geo, lmat_p, us, vs, dt)

    def _shift_and_move(self, nb: Pairs, geo: Geometry, u_old, v_old, us, vs, dt: float) -> None:
        """Stage 5: particle shifting, the new positions, the wall clamps and their energy terms."""
        c = self.cfg
        nf, h = self.nf, self.h
        eb = self.energy
        ncx, ncy = operators.smoothed_gradient(nb, nf, h, geo.gcx, geo.gcy)
        alpha = (shifting.surface_band(nb, nf, self.fs, h, 2.0 * self.dx)
                 if c.numerics.shifting_surface == "band" else self.fs.astype(np.float64))
        sx, sy = shifting.shifting(nf, (geo.gcx, geo.gcy), (self.u, self.v), alpha, h, dt, c.numerics.shifting,
                                   self.dx, (ncx, ncy))
        eb.projection += pressure_work(self.m, u_old, v_old, us, vs, self.u, self.v)
        # a bed law that changes the new velocity (the authors' slip): its kinetic-energy change is
        # booked as the wall's work (dissipated when positive, created when negative)
        ke = self.bed.after_projection(self, nb)
        ke_new = kinetic_energy(self.m, self.u, self.v)
        if ke is not None:
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
