"""Small pure functions for the DA physics: earth pressure, Coulomb friction, deposition.

Each function computes one quantity; the solver's step kernel calls them. Python-level helpers
(``earth_pressure_coefficients``) run once per run and refuse impossible angle combinations.
"""
from __future__ import annotations

import math

from numba import njit

from ..config import ConfigError


def earth_pressure_coefficients(mode: str, phi_internal: float, phi_basal: float, theta: float) -> tuple[float, float]:
    """(k_active, k_passive) for ∂u/∂x ≥ 0 and < 0 (angles in radians).

    ``paper``: eqs 8–9 as printed, with the slope θ under the root;
    ``savage_hutter``: Savage & Hutter (1989), the basal friction angle φ_B in place of θ;
    ``one``: k = 1 (hydrostatic; Ritter and Mangeney checks).
    """
    if mode == "one":
        return 1.0, 1.0
    if mode == "paper":
        angle, key = theta, "geometry.theta_deg"
    elif mode == "savage_hutter":
        angle, key = phi_basal, "material.phi_basal_deg"
    else:
        raise ConfigError(f"numerics.earth_pressure: must be one of ['paper', 'savage_hutter', 'one'] (got {mode!r})")
    c2 = math.cos(phi_internal) ** 2
    disc = 1.0 - c2 * (1.0 + math.tan(angle) ** 2)
    if disc < -1e-12:
        raise ConfigError(
            f"{key}: must be <= material.phi_internal_deg = {math.degrees(phi_internal):.6g} for "
            f"numerics.earth_pressure {mode!r}: eqs 8-9 have no real value (got {math.degrees(angle):.6g})")
    root = math.sqrt(max(disc, 0.0))
    return 2.0 / c2 * (1.0 - root) - 1.0, 2.0 / c2 * (1.0 + root) - 1.0


@njit(cache=True, inline="always")
def earth_pressure(dudx: float, k_act: float, k_pass: float) -> float:
    """k of eqs 8–9: active where the flow stretches (∂u/∂x ≥ 0), passive where it compresses."""
    return k_act if dudx >= 0.0 else k_pass


@njit(cache=True, inline="always")
def coulomb_update(u_star: float, friction_dv: float) -> float:
    """Apply a Coulomb resistance worth ``friction_dv`` (≥ 0, m/s this step) to the friction-free
    velocity ``u_star``: it reduces |u| and stops the particle, never reverses it."""
    if u_star > friction_dv:
        return u_star - friction_dv
    if u_star < -friction_dv:
        return u_star + friction_dv
    return 0.0


@njit(cache=True, inline="always")
def net_acceleration(a_drive: float, u: float, friction: float) -> float:
    """du/dt including Coulomb friction (magnitude ``friction``) for a particle with velocity u;
    a particle at rest stays at rest while |a_drive| ≤ friction."""
    if u > 0.0:
        return a_drive - friction
    if u < 0.0:
        return a_drive + friction
    if a_drive > friction:
        return a_drive - friction
    if a_drive < -friction:
        return a_drive + friction
    return 0.0


@njit(cache=True, inline="always")
def critical_momentum(x: float, L0: float, x_inf: float, A: float, B: float, scale: float, clamp: bool) -> float:
    """(hu)_C = scale · (A [x] + B), eq 36, [x] = (x − L0)/(x∞ − L0) (clamped to [0, 1] if asked);
    scale = p0 for normalised coefficients, 1 for dimensional ones."""
    s = (x - L0) / (x_inf - L0)
    if clamp:
        if s < 0.0:
            s = 0.0
        elif s > 1.0:
            s = 1.0
    return scale * (A * s + B)


@njit(cache=True, inline="always")
def alpha_coefficient(hu: float, hu_c: float, dhu_dt: float) -> float:
    """α of eq 34 (hu = |h u|, the momentum magnitude): 0 above the critical momentum or while the
    momentum grows; ((hu)_C − hu)/(hu)_C below it while it decays. Within [0, 1]."""
    if hu_c <= 0.0 or hu >= hu_c or dhu_dt >= 0.0:
        return 0.0
    return (hu_c - hu) / hu_c


@njit(cache=True, inline="always")
def deposition_rate(alpha: float, dhu_dt: float, u: float, u_min: float) -> float:
    """S_D of eq 14 (≤ 0, m/s): α d|hu|/dt / |u|, with |u| regularised to max(|u|, u_min) — the
    printed form is singular as u → 0 (docs/paper-notes.md)."""
    return alpha * dhu_dt / max(abs(u), u_min)


@njit(cache=True, inline="always")
def deposition_momentum_dv(removed_depth: float, h: float, g: float, tan_phi_i: float) -> float:
    """Velocity loss this step from eq 12: u S_D = g Δh_D tan φ_I, divided by h (eq 27):
    g tan φ_I Δh_D / h · Δt / Δt  → returned per unit time (m/s²); Δh_D = |S_D| Δt."""
    if h <= 0.0:
        return 0.0
    return g * tan_phi_i * removed_depth / h


# ----------------------------------------------------------------------------------------------
# on a path profile (issue 16; da/path_solver.py): curved bed after Savage & Hutter (1991), width
# ----------------------------------------------------------------------------------------------

@njit(cache=True, inline="always")
def bed_normal_acceleration(g: float, cos_theta: float, kappa: float, u: float) -> float:
    """N = g cosθ + κ u² (m/s²): the basal normal stress per unit mass and depth, ξ/(ρh), on a
    bed of curvature κ (> 0 concave: the slope eases and the flow is pressed onto the bed;
    Savage & Hutter 1991). May be negative on a convex break: the caller clips it at 0."""
    return g * cos_theta + kappa * u * u


@njit(cache=True, inline="always")
def depth_from_area(area: float, width: float) -> float:
    """h = A/b: depth from the SPH cross-section A = Σ V_j W_ij (eq 20 with volumes) in a channel
    of width b (b = 1 and V per unit width without a width column)."""
    return area / width


@njit(cache=True, inline="always")
def depth_gradient_from_area(darea: float, h: float, width: float, dwidth: float) -> float:
    """∂h/∂s = (∂A/∂s − h db/ds)/b, the depth gradient the earth-pressure term needs
    (−k g cosθ ∂h/∂s per unit mass in a rectangular channel of slowly varying width)."""
    return (darea - h * dwidth) / width

