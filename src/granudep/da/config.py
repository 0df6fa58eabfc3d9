"""Configuration of the 1D depth-averaged (DA) SPH model: frozen dataclasses built once at the edge.

Angles are degrees here (``*_deg``), radians inside the solver. A run is described by
``DAConfig``; :func:`resolve` builds it from a Table 5 case name, a YAML path or a dict, plus
overrides, and checks every key and range before any work starts (one-line ``ConfigError``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal, Mapping

from ..cases import check_case_name, material, momentum_scale, table5
from ..config import ConfigError, build, config_data, merge, param
from .path import PathGeometry, anchor_path_file

_GLASS = material("glass_beads")


@dataclass(frozen=True)
class Geometry:
    L0: float = param(0.2, gt=0.0, unit="m", doc="column length along the slope (gate at x = L0)")
    H0: float = param(0.14, gt=0.0, unit="m", doc="column height (bed-normal)")
    theta_deg: float = param(22.0, ge=0.0, lt=90.0, unit="deg", doc="slope angle")
    x_max: float | None = param(None, gt=0.0, unit="m",
                                doc="end of the domain and deposit grid; null: L0 + 60 H0")
    back_wall: bool = param(True, doc="mirror (ghost) wall at x = 0 holding the column")
    path: PathGeometry | None = param(None, doc="a slope profile (granudep.da.path); with it theta_deg and x_max "
                                                "are not used (the bed and its end come from the path)")

    def validate(self, prefix: str) -> None:
        p = f"{prefix}." if prefix else ""
        if self.x_max is not None and self.x_max <= self.L0:
            raise ConfigError(f"{p}x_max: must be > L0 = {self.L0} (got {self.x_max})")

    @property
    def domain_end(self) -> float:
        return self.x_max if self.x_max is not None else self.L0 + 60.0 * self.H0


@dataclass(frozen=True)
class Material:
    name: str = param("glass_beads", doc="label only")
    d: float = param(_GLASS["d"], gt=0.0, unit="m", doc="grain diameter (sets the front threshold 2 d)")
    rho: float = param(_GLASS["rho"], gt=0.0, unit="kg m-3", doc="bulk density (cancels out of the DA equations)")
    phi_internal_deg: float = param(25.5, gt=0.0, lt=90.0, unit="deg", doc="internal friction angle φ_I")
    phi_basal_deg: float = param(25.5, ge=0.0, lt=90.0, unit="deg", doc="basal friction angle φ_B")


@dataclass(frozen=True)
class Numerics:
    n_particles: int = param(1000, ge=20, le=200000, doc="particles in the initial column")
    smoothing: Literal["eq25", "fixed"] = param("eq25", doc="eq 25 variable L_s, or a fixed L_s")
    smoothing_B: float = param(10.0, gt=0.0, le=500.0, doc="B of eq 25 (L_s = B x mean spacing; paper: 50)")
    smoothing_weight: Literal["count", "volume"] = param(
        "volume", doc="eq 25's mean number density weighted by the fraction of its released volume each "
                      "particle still carries (volume, default: particles emptied by eq 34 stop setting L_s, so "
                      "their clusters cannot shrink it; the deposition ladders converge in N with it), or over "
                      "the particles (count); the two are identical without deposition")
    L_s: float | None = param(None, gt=0.0, unit="m", doc="fixed smoothing length (smoothing: fixed)")
    kernel_support: float = param(3.0, ge=2.0, le=6.0, doc="Gaussian cut-off in units of L_s (paper: 2)")
    cfl: float = param(0.5, gt=0.0, le=1.0, doc="CFL number of eq 32 (paper: 0 < CFL <= 1, value not given)")
    xsph_delta: float = param(0.05, ge=0.0, le=0.5, doc="δ of the XSPH correction eq 33")
    earth_pressure: Literal["paper", "savage_hutter", "one"] = param(
        "paper", doc="k: eqs 8-9 with θ (paper), with φ_B (Savage-Hutter), or k = 1")
    earth_pressure_switch: Literal["strain", "particle", "symmetric"] = param(
        "strain", doc="how the active/passive k of eqs 8-9 enters the momentum balance. strain (default): k is a "
                      "particle state that follows the along-slope strain (Hungr 1995), dk = -(k_p - k_a)/"
                      "earth_pressure_strain ∂u/∂s dt within [k_a, k_p], in the pair form "
                      "g cosθ Σ_j V_j ½(k_i + k_j) ∇W_ij (the SPH form of -(1/h) ∂(k g cosθ h²/2)/∂s); sustained "
                      "stretching or compression reaches eqs 8-9, a pile whose ∂u/∂s jitters keeps its k, and the "
                      "time step includes the wave speed of that stiffness. particle: -k_i g cosθ ∂h/∂s_i with k_i "
                      "from the sign of the particle's own ∂u/∂s (eq 11 read literally; creates energy on piles "
                      "coming to rest above N = 2000-4000). symmetric: the pair form with that sign switch (piles "
                      "never reach numerics.u_rest; creates energy on 1D-A70 at N = 8000). "
                      "docs/da-engineer-scale.md has the measurements. No effect with earth_pressure 'one'")
    earth_pressure_strain: float = param(
        0.05, gt=0.0, le=1.0, doc="ε_k of earth_pressure_switch 'strain': the along-slope strain (Δh/h) that takes "
                                  "k from k_a to k_p (a few per cent: the wall movement that mobilises passive "
                                  "pressure in sand; docs/da-engineer-scale.md has the sensitivity)")
    basal_friction: bool = param(True, doc="Coulomb basal friction tan φ_B (off for the Ritter check)")
    t_end: float = param(20.0, gt=0.0, unit="s", doc="hard stop if the flow has not come to rest")
    u_rest: float = param(1e-4, gt=0.0, unit="m s-1", doc="at rest when every |u| is below this")
    max_steps: int = param(5_000_000, ge=1)

    def validate(self, prefix: str) -> None:
        p = f"{prefix}." if prefix else ""
        if self.smoothing == "fixed" and self.L_s is None:
            raise ConfigError(f"{p}L_s: required (> 0, m) when {p}smoothing is 'fixed'")


@dataclass(frozen=True)
class Deposition:
    enabled: bool = param(True, doc="deposition source term (eqs 12, 14, 34, 36)")
    ab_source: Literal["paper", "computed", "user"] = param(
        "paper", doc="A, B from Table 5 (paper), from a coefficients.csv (computed), or A/B keys (user)")
    A: float | None = param(None, doc="slope A of eq 36 (ab_source user)")
    B: float | None = param(None, doc="intercept B of eq 36 (ab_source user)")
    coefficients: str | None = param(None, doc="coefficients.csv of `granudep regress` (ab_source computed)")
    coefficient_units: Literal["normalised", "dimensional"] = param(
        "normalised", doc="(hu)_C = p0 (A[x] + B) (eq 36 as printed) or A[x] + B in m2/s")
    x_inf_mode: Literal["self-consistent", "no-deposition", "user"] = param("self-consistent")
    x_inf: float | None = param(None, gt=0.0, unit="m", doc="x∞ for x_inf_mode user (from the back wall)")
    x_inf_tol: float = param(5e-3, gt=0.0, unit="m", doc="bracket width at which the x∞ iteration stops")
    x_inf_residual_tol: float = param(0.02, gt=0.0, le=1.0,
                                      doc="max |x_front(x∞) − x∞| / (x∞ − L0) accepted")
    x_inf_max_iter: int = param(30, ge=1, le=200)
    clamp_x: bool = param(True, doc="clamp [x] to [0, 1], the range eq 36 was fitted on")
    u_min: float = param(0.1, gt=0.0, unit="m s-1",
                         doc="regularises 1/u of eq 14: S_D = α d(hu)/dt / max(|u|, u_min)")
    momentum_term: Literal["eq12", "none"] = param(
        "eq12", doc="deposition momentum loss g tanφ_I Δh_D / h (eq 12) or none")
    deposit_as_bed: bool = param(True, doc="the deposit is bed topography: -g cosθ ∂h_D/∂x in the momentum "
                                          "equation (not in eq 11; without it deposition digs holes in h)")
    own_deposit: Literal["exclude", "include"] = param(
        "exclude", doc="the bed term at a particle leaves out the deposit that particle laid itself (exclude: a "
                       "particle is not pushed by its own trail) or counts it (include: the earlier behaviour)")
    steep_bed: Literal["no_deposit", "deposit"] = param(
        "no_deposit", doc="where |tanθ| > tan φ_B no deposit can rest (Coulomb statics): no deposition there "
                          "(no_deposit), or deposition on any slope (deposit: the earlier behaviour)")
    min_volume_fraction: float = param(1e-6, gt=0.0, lt=1.0,
                                       doc="a particle below this fraction of its initial volume deposits entirely")

    def validate(self, prefix: str) -> None:
        p = f"{prefix}." if prefix else ""
        if self.ab_source == "user" and (self.A is None or self.B is None):
            raise ConfigError(f"{p}A: {p}A and {p}B are required (numbers) when {p}ab_source is 'user'")
        if self.ab_source == "computed" and not self.coefficients:
            raise ConfigError(f"{p}coefficients: a coefficients.csv path is required when {p}ab_source is 'computed'")
        if self.x_inf_mode == "user" and self.x_inf is None:
            raise ConfigError(f"{p}x_inf: required (m, > L0) when {p}x_inf_mode is 'user'")


@dataclass(frozen=True)
class Output:
    dt_output: float = param(0.02, gt=0.0, unit="s", doc="interval between stored states")
    dx_grid: float = param(1e-3, gt=0.0, unit="m", doc="cell size of the fixed grid (profiles, deposit, front); "
                           "with deposition at most the smoothing length at release (B x release spacing), "
                           "so that the deposit is resolved as the particles are (da.solver.grid_spacing)")
    front_depth_threshold: float | None = param(None, gt=0.0, unit="m", doc="front threshold; null: 2 d")
    flow_time_tolerance: float = param(1e-3, gt=0.0, unit="m", doc="front advance below which the flow is at rest")
    progress_every_s: float = param(5.0, gt=0.0, unit="s", doc="wall seconds between progress lines")


@dataclass(frozen=True)
class DAConfig:
    case: str = param("user", doc="case name (file names): Table 5 name or [A-Za-z0-9_-]+")
    geometry: Geometry = field(default_factory=Geometry)
    material: Material = field(default_factory=Material)
    numerics: Numerics = field(default_factory=Numerics)
    deposition: Deposition = field(default_factory=Deposition)
    output: Output = field(default_factory=Output)

    def validate(self, prefix: str) -> None:
        check_case_name(self.case)
        g, m, d = self.geometry, self.material, self.deposition
        if d.x_inf_mode == "user" and d.x_inf is not None and d.x_inf <= g.L0:
            raise ConfigError(f"deposition.x_inf: must be > geometry.L0 = {g.L0} (got {d.x_inf})")
        if self.numerics.earth_pressure == "paper" and g.theta_deg > m.phi_internal_deg:
            raise ConfigError(
                f"geometry.theta_deg: must be <= material.phi_internal_deg = {m.phi_internal_deg} for "
                f"numerics.earth_pressure 'paper' (eqs 8-9 have no real value; got {g.theta_deg})")
        if self.numerics.earth_pressure == "savage_hutter" and m.phi_basal_deg > m.phi_internal_deg:
            raise ConfigError(
                f"material.phi_basal_deg: must be <= material.phi_internal_deg = {m.phi_internal_deg} for "
                f"numerics.earth_pressure 'savage_hutter' (no real k; got {m.phi_basal_deg})")
        if self.numerics.earth_pressure in ("paper", "savage_hutter") and self.numerics.basal_friction \
                and g.theta_deg >= m.phi_basal_deg:
            raise ConfigError(
                f"geometry.theta_deg: must be < material.phi_basal_deg = {m.phi_basal_deg} (a flow on a slope "
                f"steeper than the basal friction angle never comes to rest; got {g.theta_deg})")
        if d.x_inf is not None and d.x_inf_mode != "user":
            raise ConfigError(f"deposition.x_inf: used only with deposition.x_inf_mode 'user' "
                              f"(got x_inf = {d.x_inf} with x_inf_mode {d.x_inf_mode!r}; set both)")
        if self.case in set(table5().case_id):
            ref = case_mapping(self.case)
            for sec in ("geometry", "material"):
                for k, v in ref[sec].items():
                    got = getattr(getattr(self, sec), k)
                    if not math.isclose(got, v, rel_tol=1e-9, abs_tol=1e-12):
                        raise ConfigError(
                            f"{sec}.{k}: {got} changes the paper case {self.case!r} (Table 5: {v}); a run with "
                            f"its own geometry or material needs its own name (case: my-{self.case}) and "
                            f"deposition.ab_source 'computed' or 'user' (Table 5's A, B are for its geometry)")
        if d.enabled and d.ab_source == "paper" and self.case not in set(table5().case_id):
            raise ConfigError(
                f"deposition.ab_source: 'paper' needs a Table 5 case (one of {', '.join(table5().case_id)}) "
                f"as `case` (got {self.case!r}); use 'user' with deposition.A and deposition.B")

    # derived quantities -------------------------------------------------------------
    @property
    def theta(self) -> float:
        return math.radians(self.geometry.theta_deg)

    @property
    def front_threshold(self) -> float:
        t = self.output.front_depth_threshold
        return 2.0 * self.material.d if t is None else t

    @property
    def p0(self) -> float:
        return momentum_scale(self.geometry.H0, self.theta)


def case_mapping(name: str) -> dict:
    """Config mapping of a Table 5 case (geometry, friction angles, the paper's A and B)."""
    t5 = table5()
    row = t5[t5.case_id == name]
    if row.empty:
        raise ConfigError(f"case: unknown DA case {name!r} (allowed: {', '.join(t5.case_id)}, or a YAML path)")
    r = row.iloc[0]
    return {"case": name,
            "geometry": {"L0": float(r.L0_m), "H0": float(r.H0_m), "theta_deg": float(r.theta_deg)},
            "material": {"phi_internal_deg": float(r.phi_internal_deg), "phi_basal_deg": float(r.phi_basal_deg)}}


def _paper_case(name: str) -> dict | None:
    return case_mapping(name) if name in set(table5().case_id) else None


def resolve(case_or_config: str | Path | Mapping | DAConfig, deposition: bool | Mapping | None = None,
            **overrides) -> DAConfig:
    """Build the validated ``DAConfig`` from a case name, YAML path or mapping plus overrides.

    The one loader and override rule of every stage (:func:`granudep.config.config_data`);
    ``deposition`` (true/false or the section's mapping) is merged last.
    """
    data = config_data(DAConfig, case_or_config, overrides, paper_case=_paper_case, case_mapping=case_mapping,
                       on_file=anchor_path_file, example="n_particles, cfl, x_inf_mode")
    if isinstance(deposition, Mapping):  # run_da(..., deposition={"ab_source": "user", ...}): the section
        data = merge(data, {"deposition": {"enabled": True, **dict(deposition)}})
    elif deposition is not None:
        if not isinstance(deposition, (bool, int)) or isinstance(deposition, float):
            raise ConfigError(f"deposition: must be true/false or a mapping of deposition keys "
                              f"(got {type(deposition).__name__} {deposition!r})")
        data = merge(data, {"deposition": {"enabled": bool(deposition)}})
    return build(DAConfig, data)
