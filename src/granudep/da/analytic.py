"""Exact solutions the DA solver is checked against (verification.py, tests/da).

All in the slope-aligned frame (x down-slope), depth h bed-normal, g = 9.81 m/s².

* Ritter (1892): dam break on a flat frictionless bed, k = 1.
* Mangeney et al. (2000): dam break on an incline with Coulomb friction, k = 1; the flat-bed limit
  gives Kerswell's (2005) stop distance 2 H0/μ.
* Savage & Hutter (1989): parabolic cap, a finite mass spreading on an incline with Coulomb
  friction and a constant k, in the frame of its centre of mass.
* Coulomb block: a uniform slab on an incline (no depth gradient) moves and stops as a block.
* Coulomb block on a curved bed (``exact_energy_line``): with and without the centripetal term.
* ``tip_half_volume``: the point behind the exact h = 0 tip beyond which half a particle's volume
  lies — where the SPH front particle sits (compare like with like).
"""
from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp

from ..cases import G


def ritter_depth(x, t: float, x0: float, H0: float, g: float = G):
    """Ritter depth at time t > 0 for a dam at x0 (reservoir x < x0 of depth H0)."""
    return mangeney_depth(x, t, x0, H0, 0.0, 0.0, g)


def ritter_front(t: float, x0: float, H0: float, g: float = G) -> float:
    return x0 + 2.0 * math.sqrt(g * H0) * t


def mangeney_m(theta: float, delta: float, g: float = G) -> float:
    """m = g sin θ − g cos θ tan δ (radians)."""
    return g * math.sin(theta) - g * math.cos(theta) * math.tan(delta)


def mangeney_depth(x, t: float, x0: float, H0: float, theta: float, delta: float, g: float = G):
    """Mangeney et al. (2000): h = (2 c0 t − (x − x0) + ½ m t²)² / (9 g cosθ t²) inside the fan,
    H0 behind it (reservoir moving with acceleration m), 0 ahead of the front."""
    x = np.asarray(x, dtype=float)
    gc = g * math.cos(theta)
    c0 = math.sqrt(gc * H0)
    m = mangeney_m(theta, delta, g)
    xi = (x - x0 - 0.5 * m * t * t) / t
    h = (2.0 * c0 - xi) ** 2 / (9.0 * gc)
    h = np.where(xi <= -c0, H0, h)
    return np.where(xi >= 2.0 * c0, 0.0, h)


def mangeney_front(t: float, x0: float, H0: float, theta: float, delta: float, g: float = G) -> float:
    c0 = math.sqrt(g * math.cos(theta) * H0)
    return x0 + 2.0 * c0 * t + 0.5 * mangeney_m(theta, delta, g) * t * t


def tip_half_volume(front: float, t: float, volume: float, theta: float = 0.0, g: float = G) -> float:
    """Position behind the exact front (fan solutions: h = ζ²/(9 g cosθ t²), ζ = distance behind
    the front) beyond which the volume ``volume``/2 lies: front − (27 g cosθ t² V/2)^(1/3)."""
    return front - (13.5 * g * math.cos(theta) * t * t * volume) ** (1.0 / 3.0)


def kerswell_stop_distance(H0: float, mu: float) -> float:
    """Kerswell (2005): a dam break on a flat bed with friction μ runs out 2 H0/μ beyond the gate
    (front velocity 2 c0 − μ g t reaches zero at t* = 2 c0/(μ g))."""
    return 2.0 * H0 / mu


def kerswell_stop_time(H0: float, mu: float, g: float = G) -> float:
    return 2.0 * math.sqrt(g * H0) / (mu * g)


def savage_hutter_cap(t_eval, half_length0: float, volume: float, theta: float, delta: float, k: float,
                      g: float = G):
    """Parabolic cap h = h0 (1 − ξ²/ℓ²), ξ = x − x_c, h0 = 3V/(4ℓ), released from rest:
    ℓ'' = (3/2) k g cosθ V / ℓ², x_c'' = m. Returns (ℓ(t), x_c(t) − x_c(0), h0(t)) arrays."""
    c = 1.5 * k * g * math.cos(theta) * volume
    sol = solve_ivp(lambda _t, y: [y[1], c / (y[0] * y[0])], (0.0, float(np.max(t_eval))),
                    [half_length0, 0.0], t_eval=np.asarray(t_eval, dtype=float), rtol=1e-11, atol=1e-13)
    ell = sol.y[0]
    shift = 0.5 * mangeney_m(theta, delta, g) * np.asarray(t_eval) ** 2
    return ell, shift, 0.75 * volume / ell


def coulomb_block(t, u0: float, theta: float, delta: float, g: float = G):
    """A uniform slab (no depth gradient) with initial velocity u0 ≥ 0: (x(t) − x(0), u(t));
    it decelerates at m < 0 and stops at t* = u0/|m| (never reverses)."""
    t = np.asarray(t, dtype=float)
    m = mangeney_m(theta, delta, g)
    if m >= 0.0:
        return u0 * t + 0.5 * m * t * t, u0 + m * t
    ts = u0 / -m
    tt = np.minimum(t, ts)
    return u0 * tt + 0.5 * m * tt * tt, np.where(t < ts, u0 + m * t, 0.0)


def exact_energy_line(s, theta, kappa, mu: float, s0: float, u0: float = 0.0, centripetal: bool = True,
                      g: float = G):
    """Speed u(s) of a Coulomb block (friction μ) sliding down a curved bed from station s0 with
    speed u0: with E = u²/2, dE/ds = g sinθ − μ (g cosθ + κ u²) (κ term only if ``centripetal``),
    a linear ODE solved exactly by the integrating factor e^{2μK}, K(s) = ∫κ ds:
    E(s) = e^{−2μK(s)} [E0 + ∫_{s0}^{s} g (sinθ − μ cosθ) e^{2μK} ds'] (trapezoid/Simpson on the
    given stations). Without the κ term this is the energy line: E = E0 + g (z0 − z) − μ g (x − x0),
    and a block from rest stops where the drop over the horizontal distance is tan α = μ.
    Returns (s, u) from s0 to the stop (u = 0 there; the stop found by linear interpolation)."""
    from scipy.integrate import cumulative_simpson
    s_all = np.asarray(s, dtype=float)
    keep = s_all > s0
    s = np.concatenate([[s0], s_all[keep]])
    theta = np.concatenate([[np.interp(s0, s_all, theta)], np.asarray(theta)[keep]])
    kappa = np.concatenate([[np.interp(s0, s_all, kappa)], np.asarray(kappa)[keep]])
    K = cumulative_simpson(kappa, x=s, initial=0.0) if centripetal else np.zeros_like(s)
    src = g * (np.sin(theta) - mu * np.cos(theta)) * np.exp(2.0 * mu * K)
    E = np.exp(-2.0 * mu * K) * (0.5 * u0 * u0 + cumulative_simpson(src, x=s, initial=0.0))
    neg = np.flatnonzero(E[1:] <= 0.0) + 1
    if neg.size:
        j = int(neg[0])
        s_stop = s[j - 1] + (s[j] - s[j - 1]) * E[j - 1] / (E[j - 1] - E[j])
        s = np.concatenate([s[:j], [s_stop]])
        E = np.concatenate([E[:j], [0.0]])
    return s, np.sqrt(np.maximum(2.0 * E, 0.0))
