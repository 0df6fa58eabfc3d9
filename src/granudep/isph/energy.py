"""Mechanical energy budget of an ISPH run (per unit width, J m⁻¹).

    E_kin + E_pot + D = E_0 − (numerical dissipation) + (numerical creation)

- E_kin = ½ m Σ |u|², E_pot = −m Σ g·r with g = (g sin θ, −g cos θ) in the slope frame (datum: the
  bed and the back wall), m = ρ Δx² per particle;
- D: the cumulative physical dissipation of the viscous predictor, read off the assembled system
  A u* = uⁿ + Δt g itself: ΔD = m Σ u*·(uⁿ + Δt g − u*) = m Σ u*·(A − I) u* ≥ 0. (A − I)/Δt is the
  discrete viscous operator plus the wall friction, so ΔD is exactly the work the discrete stress and
  the wall traction take out in that step (μ(I), Newtonian, Coulomb or no-slip walls alike);
- what the scheme adds or removes beyond that is kept per stage, so a gain can be traced:
  the projection (the work of the pressure impulse on the mid-step velocity, zero in the continuum),
  the shifting (the potential energy of the shift δr, which
  moves particles without changing their velocity), the wall clamps, the time integration (the
  rest), and the energy carried out through the outflow.

The relative measures are taken of E_ref = m g cos θ Σ y_i(0) (the column's bed-normal potential
energy; = E_0 at θ = 0 with the bed as datum), which is positive for any column, whereas E_0 itself
depends on the datum and can be negative on a slope.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def kinetic_energy(m: float, u: np.ndarray, v: np.ndarray) -> float:
    """E_kin = ½ m Σ (u² + v²)."""
    return float(0.5 * m * (np.dot(u, u) + np.dot(v, v)))


def potential_energy(m: float, x: np.ndarray, y: np.ndarray, gx: float, gy: float) -> float:
    """E_pot = −m Σ (g_x x + g_y y) (slope frame; datum x = 0, y = 0)."""
    return float(-m * (gx * np.sum(x) + gy * np.sum(y)))


def viscous_dissipation(m: float, u_n, v_n, us, vs, dt: float, gx: float, gy: float) -> float:
    """ΔD = m Σ u*·(uⁿ + Δt g − u*): the work of the discrete viscous stress and wall traction
    in one implicit predictor step (≥ 0 for a positive semi-definite operator)."""
    return float(m * (np.dot(us, u_n + dt * gx - us) + np.dot(vs, v_n + dt * gy - vs)))


def pressure_work(m: float, u_n, v_n, us, vs, u_new, v_new) -> float:
    """Work of the projection's pressure impulse on the mid-step velocity ū = (uⁿ + uⁿ⁺¹)/2:
    W_p = −Δt V Σ ū·∇p = m Σ ū·(uⁿ⁺¹ − u*). The positions advance with uⁿ⁺¹, so this is the
    pressure's share of E_kin + E_pot; a hydrostatic column at rest gives 0 (ū = 0), and an
    incompressible flow with p = 0 on its free surface and impermeable walls gives 0 in the
    continuum (∫ p ∇·u − ∮ p u·n). A positive sum is energy the pressure created."""
    return float(0.5 * m * (np.dot(u_n + u_new, u_new - us) + np.dot(v_n + v_new, v_new - vs)))


@dataclass
class EnergyBudget:
    """Cumulative energy terms of a run (J m⁻¹)."""
    e0: float = 0.0             # E_kin + E_pot at t = 0
    e_ref: float = 1.0          # scale of the relative measures, m g cosθ Σ y(0)
    dissipated: float = 0.0     # Σ ΔD (physical: viscous stress + wall traction)
    wall_friction: float = 0.0  # the Coulomb wall traction's share of ``dissipated``
    projection: float = 0.0     # Σ W_p, the pressure work on the mid-step velocity (0 in the continuum)
    shifting: float = 0.0       # Σ −m g·δr (potential energy moved by particle shifting)
    clamps: float = 0.0         # Σ energy change of the wall clamps
    outflow: float = 0.0        # E_kin + E_pot of the particles that left through the outflow
    max_excess: float = 0.0     # max over steps of (E_kin + E_pot + D + outflow − E_0) / E_ref
    max_excess_time: float = 0.0

    def residual(self, e_mech: float) -> float:
        """E_mech + D + outflow − E_0 for E_mech = E_kin + E_pot: > 0 is energy the scheme created."""
        return e_mech + self.dissipated + self.outflow - self.e0
