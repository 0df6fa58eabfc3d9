"""Configuration of a 2D ISPH run: validated dataclasses built from a case name, YAML or dict.

Sections (YAML keys): ``case``, ``geometry``, ``material``, ``rheology``, ``wall``, ``numerics``,
``output``. Every field is range-checked by :func:`granudep.config.build`; cross-field checks are in
``validate``. Overrides follow the one rule of every stage (:func:`granudep.config.overrides_mapping`):
a section mapping, a dotted key (``numerics.dx``) or, when unique, a bare name (``dx``).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

from ..cases import characteristic_time, check_case_name, material as table2_material, table1, table5
from ..config import ConfigError, build, config_data, param

_GB = table2_material("glass_beads")


@dataclass(frozen=True)
class Geometry:
    theta_deg: float = param(22.0, ge=0.0, lt=60.0, unit="deg", doc="slope angle")
    L0: float = param(0.2, gt=0.0, le=5.0, unit="m", doc="column length (gate at x = L0)")
    H0: float = param(0.14, gt=0.0, le=5.0, unit="m", doc="column height")
    domain_length: float | None = param(None, gt=0.0, unit="m",
                                        doc="bed length from the back wall; null = L0 + max(4 m, 20 H0)")
    back_wall: bool = param(True, doc="rigid wall at x = 0 (column collapse); false for periodic layers")
    periodic_length: float = param(0.0, ge=0.0, unit="m",
                                   doc="> 0: periodic in x with this period (layer tests; no back wall)")
    outflow: bool = param(True, doc="the bed ends at x = domain_length in an open outflow: particles that pass "
                                    "it leave the computation (counted, timed); false = a blow-up")

    def validate(self, prefix: str) -> None:
        p = f"{prefix}." if prefix else ""
        if self.domain_length is not None and self.domain_length <= self.L0:
            raise ConfigError(f"{p}domain_length: must be > L0 = {self.L0} (got {self.domain_length})")
        if self.periodic_length > 0 and self.back_wall:
            raise ConfigError(f"{p}back_wall: must be false when periodic_length > 0 (got true)")
        if self.periodic_length > 0 and abs(self.periodic_length - self.L0) > 1e-12:
            raise ConfigError(f"{p}periodic_length: must equal L0 = {self.L0} for a periodic layer "
                              f"(got {self.periodic_length})")


@dataclass(frozen=True)
class Material:
    d: float = param(_GB["d"], gt=0.0, lt=0.1, unit="m", doc="grain diameter (Table 2)")
    rho_s: float = param(_GB["rho_s"], gt=0.0, unit="kg m-3", doc="grain density (Table 2)")
    rho: float = param(_GB["rho"], gt=0.0, unit="kg m-3", doc="bulk density of the continuum (Table 2)")
    phi_internal_deg: float = param(_GB["phi_internal_deg"], gt=0.0, lt=90.0, unit="deg", was="phi_deg",
                                    doc="internal friction angle phi_I; mu_s from it by material.mu_s_form")
    mu_2: float = param(0.73, gt=0.0, unit="1", doc="limiting friction at large I (paper: 'mu_s ~ 0.73')")
    I0: float = param(0.279, gt=0.0, unit="1", doc="inertial-number scale (Ionescu et al. 2015), for the I of "
                                                   "material.inertial_number")
    mu_s_form: str = param("tan_phi", choices=("tan_phi", "sin_phi"),
                           doc="static friction of the mu(I) law: tan_phi (mu_s = tan phi_I, the paper's text, "
                               "Section 2.1) or sin_phi (mu_s = sin phi_I, the Drucker-Prager plane-strain match "
                               "of the authors' published code, Nikooei-Data Granularmaterial3, after Ionescu et al. "
                               "2015: 0.4305 against 0.4770 at 25.5 deg)")
    inertial_number: str = param("standard", choices=("standard", "doubled"),
                                 doc="inertial number of eq 4: standard, I = |gamma_dot| d / sqrt(p/rho_s) (the "
                                     "paper's text), or doubled, I = 2 |gamma_dot| d / sqrt(p/rho_s) (the authors' "
                                     "published code; with I0 = 0.279 it is the standard law with I0 = 0.1395)")

    @property
    def mu_s(self) -> float:
        """μ_s of the μ(I) law (``mu_s_form``)."""
        phi = math.radians(self.phi_internal_deg)
        return math.sin(phi) if self.mu_s_form == "sin_phi" else math.tan(phi)

    @property
    def I0_standard(self) -> float:
        """I0 of the law written with the standard inertial number: μ(I) with I doubled and I0 is
        μ(I) with the standard I and I0/2 (``inertial_number``)."""
        return 0.5 * self.I0 if self.inertial_number == "doubled" else self.I0

    def validate(self, prefix: str) -> None:
        p = f"{prefix}." if prefix else ""
        if self.mu_2 <= self.mu_s:
            raise ConfigError(f"{p}mu_2: must be > mu_s = {self.mu_s_form.replace('_', '(')}_internal_deg) = "
                              f"{self.mu_s:.4f} (got {self.mu_2})")
        if self.rho > self.rho_s:
            raise ConfigError(f"{p}rho: must be <= rho_s = {self.rho_s} (got {self.rho})")


@dataclass(frozen=True)
class Rheology:
    model: str = param("mu_i", choices=("mu_i", "newtonian"), doc="mu(I) (eqs 4-5) or constant viscosity")
    viscosity: float = param(1.0, gt=0.0, unit="Pa s", doc="Newtonian dynamic viscosity (model = newtonian)")
    eta_max: float = param(5.0e3, gt=0.0, unit="Pa s",
                           doc="viscosity cap of the regularised Drucker-Prager/mu(I) law (quasi-rigid state)")
    pair_mean: str = param("stress", choices=("harmonic", "geometric", "arithmetic", "stress"),
                           doc="pair viscosity of the implicit viscous Laplacian")
    eta_min: float = param(1.0e-3, ge=0.0, unit="Pa s", doc="viscosity floor (p -> 0 at the free surface)")
    pressure_floor: str = param("half_layer", choices=("half_layer", "none"),
                                doc="pressure seen by the friction law clipped below at rho g cos(theta) dx/2 "
                                    "(half_layer: thin fronts keep their friction) or at 0 (none)")
    pressure_filter: str = param("none", choices=("none", "shepard", "mls"),
                                 doc="pressure seen by the friction law (eq 5): each particle's own (none), its "
                                     "kernel (Shepard) average over the granular neighbours (shepard), or the "
                                     "kernel-weighted linear least-squares fit there (mls: exact for linear "
                                     "pressures at walls and free surfaces); the filters remove the layer-to-layer "
                                     "mode that the adjoint-pair pressure gradient barely sees")
    regularisation: str = param("none", choices=("none", "barker_gray_2017"),
                                doc="mu(I) below the well-posed band: the paper's law (none), or the partial "
                                    "regularisation of Barker & Gray (2017, eq 6.3), well posed for every I")
    alpha_reg: float = param(1.9, gt=0.0, le=10.0, unit="1",
                             doc="alpha of the Barker & Gray (2017) regularisation (their value 1.9)")
    mu_inf: float = param(0.0, ge=0.0, le=1.0, unit="1",
                          doc="mu_inf of the extended law (mu_s I0 + mu_2 I + mu_inf I^2)/(I0 + I); 0 = eq 5 exactly "
                              "(Barker & Gray 2017 use 0.05, which makes the law well posed at high I)")

    def validate(self, prefix: str) -> None:
        p = f"{prefix}." if prefix else ""
        if self.eta_min >= self.eta_max:
            raise ConfigError(f"{p}eta_min: must be < eta_max = {self.eta_max} (got {self.eta_min})")


@dataclass(frozen=True)
class Wall:
    slip: str = param("navier", choices=("no_slip", "navier", "navier_overwrite", "free_slip", "coulomb", "mu_w_i",
                                         "stress_limited"),
                      doc="bed law (basal and back wall). navier (default): the paper's basal slip velocity "
                          "(Section 4.1, after Nikooei & Manzari 2020), a Navier slip u_s = slip_length (I - n n).gamma_dot.n "
                          "(the authors' published code), as a wall stress eta u_1/(d_1 + slip_length) on the first "
                          "layer in the implicit viscous step; no_slip (u_w = 0: a rough bed); navier_overwrite (the "
                          "authors' discrete form: the first layer's velocity replaced by slip_length (I - n n).gamma_dot.n "
                          "after the projection, explicit; unstable for slip_length > 2 dx); free_slip; coulomb (friction "
                          "tan phi_B times the walls' normal stress on the first layer); mu_w_i (the bulk mu(I) law at the "
                          "wall, I_w from the slip speed sheared over slip_shear_length); stress_limited (no slip while the "
                          "wall shear stress stays below tan phi_B p_w, Coulomb sliding beyond). docs/model.md, 'Bed law "
                          "and basal slip'")
    slip_length: float = param(0.018, ge=0.0, le=1.0, unit="m",
                               doc="Navier slip length L_s (slip = navier, navier_overwrite): 0.018 m, the only value the "
                                   "authors published (Nikooei-Data projection.cpp, 'Ls'); the value of the paper's "
                                   "glass-bead runs is not published")
    slip_shear_length: float | None = param(None, gt=0.0, unit="m",
                                            doc="slip = mu_w_i: length over which the slip speed shears, "
                                                "I_w = (|u_slip|/l) d / sqrt(p_w/rho_s); null = material.d "
                                                "(one grain: the slip is the shear of the basal grain layer)")
    phi_basal_deg: float = param(_GB["phi_internal_deg"], gt=0.0, lt=90.0, unit="deg", was="phi_wall_deg",
                                 doc="Coulomb wall friction angle phi_B (slip = coulomb, stress_limited)")
    bed_stress: str = param("bed", choices=("bed", "centre", "hydrostatic", "wall"),
                            doc="slip = no_slip, navier with mu(I): the viscous wall stress of the first layer at "
                                "the bed's normal stress (bed: eta_i p_w/p_i, p_w = rho a_n dx from the walls' "
                                "reaction, never below p_i) or at the particle centre (centre: a sheet "
                                "one particle thick holds half its weight and slides on). The bed stress needs the "
                                "walls' reaction (numerics.projection: adjoint_pair); with the approximate projection "
                                "the centre stress is used. hydrostatic: the first layer's pressure extrapolated to "
                                "the wall, p_i + rho g_n d_i (a diagnostic). wall: mu(I) evaluated "
                                "at the wall itself, p_w = rho a_n dx and the wall's own shear rate rho dx (k_i/eta_i) "
                                "|u_t| (best on layers >= 10 particles, no better on 2-4-particle sheets)")
    stick_speed: float = param(1.0e-4, gt=0.0, unit="m s-1",
                               doc="Coulomb regularisation: below this tangential speed the wall friction is a stiff drag")
    contact_length: str = param("voronoi", choices=("voronoi", "dx"),
                                doc="bed length carried by a contact particle in the Coulomb friction: "
                                    "half the spacing to its contact neighbours (voronoi) or dx")
    cover_offset: float = param(0.5, gt=0.0, le=2.0, unit="dx",
                                doc="a particle is not in wall contact when another lies below it within "
                                    "this tangential offset (in dx)")
    coulomb_normal: str = param("auto", choices=("auto", "contact", "projection"),
                                doc="normal stress of the Coulomb friction (slip = coulomb): the contact "
                                    "pressure of the first particle layer (PPE pressure or column weight, "
                                    "on the bed length each contact particle carries), or the walls' normal "
                                    "reaction on each particle from the previous projection (needs "
                                    "numerics.projection: adjoint_pair, whose walls carry pressure); auto: "
                                    "projection with adjoint_pair, contact with the approximate projection")
    layers: int = param(0, ge=0, le=8, doc="wall particle layers; 0 = enough to cover the kernel support 2h")


@dataclass(frozen=True)
class Numerics:
    dx: float = param(0.004, gt=0.0, le=0.1, unit="m", doc="initial particle spacing")
    h_factor: float = param(1.3, ge=1.0, le=2.0, unit="1", doc="smoothing length h = h_factor dx")
    cfl: float = param(0.2, gt=0.0, le=0.5, unit="1", doc="dt <= cfl h / max|u|")
    dt_max: float = param(2.0e-3, gt=0.0, unit="s", doc="upper bound of the time step")
    t_end: float | None = param(None, gt=0.0, unit="s", doc="end time; null = 30 t_c (t_c = sqrt(H0/(g cos theta)))")
    free_surface_threshold: float = param(1.6, gt=0.0, lt=2.0, unit="1",
                                          doc="div r below this marks a free-surface particle (p = 0)")
    shifting: float = param(2.0, ge=0.0, le=10.0, unit="1",
                            doc="particle shifting coefficient A in D = A h |u| dt (0 = off)")
    shifting_surface: str = param("band", choices=("surface", "band"),
                                  doc="where the shift loses its part normal to the free surface: on the "
                                      "free-surface particles only (surface), or also, weighted by "
                                      "min(1, sum W_ij / W(2 dx)) over free-surface neighbours j, just below them (band)")
    density_relaxation: float = param(0.02, ge=0.0, le=1.0, unit="1",
                                      doc="weight of the density-invariant source (1 - C_i/C0)/dt^2 in the PPE")
    density_relaxation_form: str = param("per_time", choices=("per_step", "per_time"),
                                         doc="per_step: the source removes the fraction density_relaxation of the "
                                             "compression 1 - C/C0 in every step (its rate per unit time grows as "
                                             "1/dt); per_time: the fraction density_relaxation dt/dt_ref, dt_ref = "
                                             "the gravity cap of the step (0.125 or 0.25 sqrt(h/g)): the same rate "
                                             "per unit time at any dt")
    free_surface_pressure: str = param("half_layer", choices=("half_layer", "zero"),
                                       doc="Dirichlet value on free-surface particles: rho g cos(theta) dx/2 or 0")
    ppe_divergence: str = param("renormalised", choices=("renormalised", "adjoint"),
                                doc="divergence of the PPE source: the renormalised divergence (exact for linear "
                                    "fields), or the negative adjoint of the corrector's pressure gradient "
                                    "(energy-consistent projection, isph/projection.py)")
    projection: str = param("adjoint_pair", choices=("approximate", "adjoint_pair"),
                            doc="pressure projection: the approximate projection (compact-Laplacian PPE, "
                                "renormalised difference gradient, mirror-pressure walls), or the adjoint pair "
                                "(corrector gradient G = -D^T of the renormalised divergence D, PPE "
                                "((1 - eps) D D^T + eps L_c) p, wall particles carrying pressure: energy-stable, "
                                "isph/projection.py)")
    pressure_correction: str = param("auto", choices=("auto", "incremental", "non_incremental"),
                                     doc="the predictor carries the previous step's pressure gradient "
                                         "(incremental: u* = u^n + dt g - dt/rho G p^n + viscous, the projection "
                                         "then applies G (p^{n+1} - p^n); Goda 1979, van Kan 1986) or none "
                                         "(non_incremental, Chorin 1968: the viscous stress and the wall friction "
                                         "act on a velocity not yet balanced by the pressure, a first-order "
                                         "splitting error that measured 5.5 % of the T22-A70 runout between cfl "
                                         "0.1 and 0.3); auto: incremental with numerics.projection: adjoint_pair, "
                                         "non_incremental with the approximate projection")
    projection_stabilisation: float = param(0.01, ge=0.0, le=0.5, unit="1",
                                            doc="adjoint_pair: PPE operator (1 - eps) D D^T + eps L_c; the compact "
                                                "Laplacian L_c removes the checkerboard null space of D D^T; "
                                                "energy-stable for eps <= 1/2")
    wall_release: bool = param(True, doc="adjoint_pair: a wall node whose pressure comes out negative (it would "
                                         "pull the flow) is held at p = 0 from the next step until the flow "
                                         "presses into it again")
    kernel_completion: bool = param(True, doc="PPE: missing neighbours next to the free surface count as p = 0")
    pressure_solver: str = param("cg_dic", choices=("direct", "cg", "cg_dic", "cg_two_level", "cg_ssor", "amg_sa",
                                                     "amg_rs"),
                                 doc="PPE: SuperLU factorisation, Jacobi-preconditioned CG (warm start; scipy's "
                                     "iterates bit for bit), CG with diagonal incomplete Cholesky (Eisenstat; "
                                     "~2.5x fewer iterations, ~2x faster, true-residual stopping test; with "
                                     "projection adjoint_pair, where incomplete Cholesky breaks down, cg_dic "
                                     "means cg_ssor), two-level CG (Jacobi + "
                                     "an aggregation coarse space; "
                                     "dx-independent iterations), or CG "
                                     "preconditioned by an algebraic-multigrid V-cycle (pyamg, optional package: "
                                     "smoothed aggregation or Ruge-Stuben; N-independent iterations but slower "
                                     "at 3.7k-60k particles, see docs/performance.md); cg_ssor: CG with the "
                                     "symmetric Gauss-Seidel (SSOR, omega = 1) preconditioner in Eisenstat form, "
                                     "which never breaks down (adjoint-pair PPE at 4 mm: 47 -> 29 iterations; "
                                     "docs/performance.md)")
    deflation_min_unknowns: int = param(12_000, ge=0, unit="unknowns",
                                        doc="adjoint_pair PPE with cg_dic / cg_ssor: from this many unknowns "
                                            "on, the SSOR-CG is deflated by an aggregation coarse space "
                                            "(A-DEF2, isph/deflation.py: 17-27 iterations at every dx instead "
                                            "of 29-72). Measured through T22-A70 runs (docs/performance.md): at "
                                            "7k unknowns (2 mm) 0-30 % slower, at 14.5k (1.4 mm) 0-28 % "
                                            "faster, at 28k (1 mm) ~2x faster, so the 4 mm runs and the "
                                            "7000-particle 2 mm columns keep the plain SSOR-CG; same "
                                            "operator and stopping test: the solution agrees within "
                                            "solver_rtol; 0 = always")
    ppe_operator: str = param("assembled", choices=("assembled", "matrix_free"),
                              doc="adjoint_pair PPE with the two-level CG (pressure_solver "
                                  "cg_two_level): the matrix assembled as the product (1 - eps) D D^T + eps L_c "
                                  "(CSR), or applied unassembled as D (D^T x) + eps L_c x (the same operator; "
                                  "no product to form, each iteration dearer; docs/performance.md)")
    viscous_solver: str = param("cg_dic", choices=("direct", "cg", "cg_dic"),
                                doc="implicit viscous step: SuperLU, Jacobi-preconditioned CG (u and v in lock-step) "
                                    "or DIC-preconditioned CG, warm-started from the right-hand side")
    solver_rtol: float = param(1.0e-8, gt=0.0, lt=1.0, unit="1", doc="CG relative residual tolerance")
    ic_modification: float = param(0.97, ge=0.0, le=1.0, unit="1",
                                   doc="cg_dic: relaxation of the modified incomplete Cholesky preconditioner "
                                       "(0 = plain DIC; 0.97: T22-A150 PPE 62 -> 30 iterations); the solution and "
                                       "the stopping test do not depend on it")
    reorder_interval: int = param(10, ge=0, unit="steps",
                                  doc="renumber the granular particles in natural order (columns of width dx, "
                                      "by height) every this many steps: faster solves and neighbour loops; "
                                      "0 = never (the numbering of the initial lattice, as before); outputs keep "
                                      "the original particle index")
    threads_mode: str = param("auto", choices=("auto", "overlap", "prange"),
                              doc="with more than one numba thread (NUMBA_NUM_THREADS): overlap = the "
                                  "adjoint-pair PPE's geometry (L_c, active set, the triangles) is built on "
                                  "a second thread while the predictor runs, every kernel in its serial "
                                  "build (two threads busy); prange = the per-particle kernels' numba "
                                  "parallel builds, no overlap; auto = overlap on exactly two threads, "
                                  "prange on more. Bit for bit the same results; on 2 cores overlap "
                                  "measured 11-30 % faster per step than one thread at 3750-60000 "
                                  "particles, prange slower at 3750 (docs/performance.md; more "
                                  "than two threads not measured). One thread: no effect")
    seed: int = param(0, ge=0, le=2**31 - 1, unit="1",
                      doc="ensemble member: 0 = the unperturbed lattice; k > 0 moves every grain particle's "
                          "initial position by jitter dx N(0, 1) per coordinate, drawn from numpy's "
                          "default_rng(k) (bit for bit the same for the same k), clipped to the lattice's extent")
    jitter: float = param(0.01, ge=0.0, le=0.1, unit="1",
                          doc="standard deviation of the initial position perturbation of a member seed > 0, in dx")
    max_steps: int = param(2_000_000, gt=0, doc="hard cap on the number of time steps")
    energy_limit: float = param(0.01, gt=0.0, le=10.0, unit="1",
                                doc="stop the run (as a blow-up) when E_kin + E_pot + dissipated rises above "
                                    "E_0 by more than this share of E_ref = m g cos(theta) sum y(0)")


@dataclass(frozen=True)
class Output:
    dt_output: float = param(0.01, gt=0.0, unit="s", was="interval", doc="interval between stored snapshots")
    front_depth_threshold: float | None = param(None, gt=0.0, unit="m",
                                                doc="front: first cell thinner than this; null = 2 d")
    rest_speed: float = param(0.1, gt=0.0, unit="m s-1",
                              doc="at rest when the speed (rest_measure) of the particles behind the front < "
                                  "rest_speed (default: the paper's flow/deposit speed 0.1 m/s) ...")
    rest_measure: str = param("max", choices=("max", "rms"),
                              doc="... taking the max over all particles (every particle deposited) or the rms "
                                  "speed of those behind the front ...")
    rest_duration: float = param(0.1, gt=0.0, unit="s", doc="... for this long")
    stop_at_rest: bool = param(True, doc="end the run once at rest")
    progress_every_s: float = param(5.0, gt=0.0, unit="s", was="progress_s", doc="wall seconds between progress lines")


@dataclass(frozen=True)
class IsphConfig:
    case: str = param("user", doc="case name (output file name)")
    geometry: Geometry = field(default_factory=Geometry)
    material: Material = field(default_factory=Material)
    rheology: Rheology = field(default_factory=Rheology)
    wall: Wall = field(default_factory=Wall)
    numerics: Numerics = field(default_factory=Numerics)
    output: Output = field(default_factory=Output)

    def validate(self, prefix: str) -> None:
        check_case_name(self.case)
        g, n = self.geometry, self.numerics
        _check_paper_identity(self)
        if g.periodic_length == 0:
            # a column on a bed comes to rest only if the slope is below the friction angles
            limits = [(self.material.phi_internal_deg, "material.phi_internal_deg")]
            if self.wall.slip in ("coulomb", "stress_limited"):
                limits.append((self.wall.phi_basal_deg, "wall.phi_basal_deg"))
            phi, key = min(limits)
            if g.theta_deg >= phi:
                raise ConfigError(f"geometry.theta_deg: must be < {key} = {phi} for a column on a bed "
                                  f"(no rest is possible on a slope steeper than the friction angle; "
                                  f"got {g.theta_deg})")
        if self.wall.slip in ("navier", "navier_overwrite") and not self.wall.slip_length > 0:
            raise ConfigError(f"wall.slip_length: must be > 0 for wall.slip: {self.wall.slip} (got "
                              f"{self.wall.slip_length}); a wall without slip is wall.slip: no_slip")
        if self.wall.slip == "navier_overwrite" and self.wall.slip_length > 2.0 * n.dx:
            raise ConfigError(f"wall.slip_length: must be <= 2 dx = {2.0 * n.dx:g} m for wall.slip: navier_overwrite "
                              f"(got {self.wall.slip_length}): the explicit overwrite amplifies the first layer's "
                              f"velocity beyond that and the run blows up (docs/model.md); use wall.slip: navier")
        reaction = self.wall.coulomb_normal == "projection" or (self.wall.coulomb_normal == "auto"
                                                                and n.projection == "adjoint_pair")
        if self.wall.slip in ("mu_w_i", "stress_limited") and not reaction:
            raise ConfigError(f"wall.slip: {self.wall.slip} needs the walls' normal reaction (numerics.projection: "
                              f"adjoint_pair with wall.coulomb_normal: auto or projection; got "
                              f"{n.projection} / {self.wall.coulomb_normal})")
        if self.wall.coulomb_normal == "projection" and n.projection != "adjoint_pair":  # auto: never
            raise ConfigError("wall.coulomb_normal: projection needs numerics.projection: adjoint_pair (walls "
                              f"carrying pressure; got numerics.projection: {n.projection})")
        if n.pressure_correction == "incremental" and n.projection != "adjoint_pair":  # auto: never
            raise ConfigError("numerics.pressure_correction: incremental needs numerics.projection: adjoint_pair "
                              f"(got numerics.projection: {n.projection}); use auto or non_incremental")
        if n.ppe_operator == "matrix_free" and (n.projection != "adjoint_pair"
                                                or n.pressure_solver != "cg_two_level"):
            raise ConfigError("numerics.ppe_operator: matrix_free needs numerics.projection: adjoint_pair and "
                              "numerics.pressure_solver: cg_two_level (got "
                              f"{n.projection} / {n.pressure_solver})")
        if g.L0 < 2 * n.dx or g.H0 < 2 * n.dx:
            raise ConfigError(f"numerics.dx: must be <= min(L0, H0)/2 = {min(g.L0, g.H0) / 2} (got {n.dx})")
        npart = (g.L0 / n.dx) * (g.H0 / n.dx)
        if npart > 400_000:
            raise ConfigError(f"numerics.dx: gives {npart:.0f} particles (> 400000); must be >= "
                              f"{math.sqrt(g.L0 * g.H0 / 400_000):.4g}")
        if g.periodic_length > 0 and g.periodic_length < 3 * 2 * n.h_factor * n.dx:
            raise ConfigError(f"geometry.periodic_length: must be >= 6 h = {6 * n.h_factor * n.dx:.4g} "
                              f"(got {g.periodic_length})")

    # derived quantities ------------------------------------------------------------------
    @property
    def theta(self) -> float:
        return math.radians(self.geometry.theta_deg)

    @property
    def h(self) -> float:
        return self.numerics.h_factor * self.numerics.dx

    @property
    def t_c(self) -> float:
        return characteristic_time(self.geometry.H0, self.theta)

    @property
    def t_end(self) -> float:
        return self.numerics.t_end if self.numerics.t_end is not None else 30.0 * self.t_c

    @property
    def domain_length(self) -> float:
        g = self.geometry
        if g.periodic_length > 0:
            return g.periodic_length
        return g.domain_length if g.domain_length is not None else g.L0 + max(4.0, 20.0 * g.H0)

    @property
    def front_depth_threshold(self) -> float:
        t = self.output.front_depth_threshold
        return t if t is not None else 2.0 * self.material.d

    @property
    def wall_shear_length(self) -> float:
        """ℓ of the wall inertial number (``wall.slip_shear_length``; default one grain, d)."""
        ls = self.wall.slip_shear_length
        return ls if ls is not None else self.material.d

    @property
    def wall_friction(self) -> float:
        return math.tan(math.radians(self.wall.phi_basal_deg))

    @property
    def wall_layers(self) -> int:
        if self.wall.layers:
            return self.wall.layers
        return int(math.ceil(2.0 * self.numerics.h_factor))


# --- named cases -------------------------------------------------------------------------------
EXTRA_CASES = {"T22-A30": "1D-A30", "T22-A45": "1D-A45", "T22-A124": "1D-A124"}


def case_names() -> list[str]:
    return list(table1().case_id) + list(EXTRA_CASES)


def case_geometry(name: str) -> dict:
    """theta_deg, L0, H0 of a named case (Table 1, or a Table 5 geometry at 22 deg).

    Table 5 rounds H0 (1D-A45: 0.113 m); we use H0 = a L0 (0.1125 m), the contract's value.
    """
    t1 = table1()
    row = t1[t1.case_id == name]
    if not row.empty:
        r = row.iloc[0]
        return {"theta_deg": float(r.theta_deg), "L0": float(r.L0_m), "H0": float(r.H0_m)}
    if name in EXTRA_CASES:
        t5 = table5()
        r = t5[t5.case_id == EXTRA_CASES[name]].iloc[0]
        return {"theta_deg": float(r.theta_deg), "L0": float(r.L0_m), "H0": round(float(r.a) * float(r.L0_m), 6)}
    raise ConfigError(f"case: unknown case {name!r} (allowed: {', '.join(case_names())}, or a YAML file)")


#: material keys that choose how the friction law reads the material, not the material itself: a paper
#: case keeps its name under either convention (a study of the paper's model, not another material)
MODEL_CONVENTIONS = ("mu_s_form", "inertial_number")


def _check_paper_identity(cfg: "IsphConfig") -> None:
    """A paper case name stands for the paper's geometry and material: a run that changes either
    must carry its own name (it would be written to results/isph/{case}.nc labelled as the paper's)."""
    if cfg.case not in case_names():
        return
    ref_geo = case_geometry(cfg.case)
    changed = [(f"geometry.{k}", getattr(cfg.geometry, k), v) for k, v in ref_geo.items()
               if not math.isclose(getattr(cfg.geometry, k), v, rel_tol=1e-9, abs_tol=1e-12)]
    for sec, obj, ref in (("material", cfg.material, Material()), ("wall", cfg.wall, Wall())):
        keys = ([f.name for f in dataclasses.fields(ref) if f.name not in MODEL_CONVENTIONS] if sec == "material"
                else ["phi_basal_deg"])
        changed += [(f"{sec}.{k}", getattr(obj, k), getattr(ref, k)) for k in keys
                    if getattr(obj, k) != getattr(ref, k)]
    if changed:
        key, got, ref = changed[0]
        raise ConfigError(f"{key}: {got} changes the paper case {cfg.case!r} (its value: {ref}); a run with its "
                          f"own geometry or material needs its own name (case: my-{cfg.case}, "
                          f"letters, digits, '_' and '-')")


def _paper_case(name: str) -> dict | None:
    return {"geometry": case_geometry(name)} if name in case_names() else None


def load_config(case_or_config: Any, **overrides) -> IsphConfig:
    """Case name, YAML path, mapping or IsphConfig (+ overrides) -> validated IsphConfig.

    The one loader and override rule of every stage (:func:`granudep.config.config_data`): a YAML or
    mapping naming a paper case inherits its geometry unless it sets one.
    """
    return build(IsphConfig, config_data(IsphConfig, case_or_config, overrides, paper_case=_paper_case,
                                         case_mapping=lambda name: {"case": name, "geometry": case_geometry(name)},
                                         example="dx, t_end, theta_deg"))
