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
def earth_pressure_strained(k_old: float, dudx: float, dt: float, k_act: float, k_pass: float,
                            inv_strain: float) -> float:
    """k of eqs 8–9 carried as a state that follows the strain (Hungr 1995; McDougall & Hungr 2004):
    dk = −(k_p − k_a)/ε_k ∂u/∂x dt, kept within [k_a, k_p] (``inv_strain`` = 1/ε_k). Sustained
    stretching reaches k_a and sustained compression k_p after a strain ε_k, as eqs 8–9 say; a pile
    whose ∂u/∂x only jitters about zero keeps its k instead of flipping between k_a and k_p."""
    k = k_old - (k_pass - k_act) * inv_strain * dudx * dt
    return min(max(k, k_act), k_pass)


@njit(cache=True, inline="always")
def earth_pressure_wave_factor(k_act: float, k_pass: float, inv_strain: float) -> float:
    """c²/(g h) of the strained earth pressure: P = k g h²/2 with dk = (k_p − k_a)/ε_k dh/h gives
    dP/dh = g h (k + (k_p − k_a)/(2 ε_k)); bounded by its value at k = k_p."""
    return k_pass + 0.5 * (k_pass - k_act) * inv_strain


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
def driving_acceleration(g_sin: float, k: float, g_cos: float, dhdx: float, dhD_dx: float) -> float:
    """Friction-free du/dt of eqs 11/27 (with the deposit as bed): g sinθ − k g cosθ ∂h/∂x − g cosθ ∂h_D/∂x."""
    return g_sin - k * g_cos * dhdx - g_cos * dhD_dx


@njit(cache=True, inline="always")
def momentum_rate(h: float, u: float, a_net: float, dudx: float) -> float:
    """d|hu|/dt of eq 34 along the particle: sgn(u) h du/dt − |u| h ∂u/∂x (dh/dt = −h ∂u/∂x);
    h |du/dt| for a particle at rest (it can only start to move)."""
    if u != 0.0:
        return math.copysign(1.0, u) * h * a_net - abs(u) * h * dudx
    return h * abs(a_net)


@njit(cache=True, inline="always")
def deposited_fraction(s_d: float, dt: float, h: float) -> float:
    """Fraction of a particle's volume deposited this step, −S_D Δt / h (S_D ≤ 0), at most 1."""
    return min(1.0, -s_d * dt / h)


@njit(cache=True, inline="always")
def deposition_velocity_loss(g: float, tan_phi_i: float, fraction: float, dt: float) -> float:
    """Velocity loss this step from eq 12, u S_D = g Δh_D tan φ_I per unit depth (eq 27):
    g tan φ_I (Δh_D / h) Δt with Δh_D / h the deposited fraction; a Coulomb-type budget (m/s)."""
    return g * tan_phi_i * fraction * dt


@njit(cache=True, inline="always")
def heun_friction_budget(dt: float, friction_1: float, friction_2: float) -> float:
    """Coulomb budget (m/s) of the corrector: ½ Δt (F₁ + F₂) of the friction decelerations of both
    stages (Heun); = F Δt exactly for a constant F."""
    return 0.5 * dt * (friction_1 + friction_2)


@njit(cache=True, inline="always")
def wave_speed_absolute(u: float, h: float, g: float) -> float:
    """Signal speed of eq 32: max(|u|, √(g h))."""
    return max(abs(u), math.sqrt(g * h))


@njit(cache=True, inline="always")
def wave_speed_relative(h: float, g: float, L: float, dudx: float, cap: float) -> float:
    """Lagrangian signal speed √(g h) + L |∂u/∂x|, the relative velocity across the support capped
    at ``cap`` (2 max|u|; an isolated or nearly emptied particle can have an ill-conditioned ∂u/∂x)."""
    r = L * abs(dudx)
    if not r <= cap:
        r = cap
    return math.sqrt(g * h) + r


# ----------------------------------------------------------------------------------------------
# on a path profile (da/path_solver.py): curved bed after Savage & Hutter (1991), width
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

