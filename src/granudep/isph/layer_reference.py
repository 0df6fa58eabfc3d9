"""A converged 1D reference for uniform μ(I) layers on an incline.

A layer of thickness h, infinite and uniform down-slope, no-slip bed, stress-free surface, obeys

    ρ ∂u/∂t = ρ g sin θ + ∂τ/∂y,    τ = η ∂u/∂y,    η = min(μ(I) p / |γ̇|, η_max),
    p = ρ g cos θ (h − y),          I = d |γ̇| / sqrt(p / ρ_s),   μ(I) = μ_s + (μ_2 − μ_s) I / (I_0 + I)

(the same regularised μ(I) law as the 2D solver, :mod:`granudep.isph.rheology`). Below the static
friction (tan θ < μ_s) every shearing layer decelerates and stops in a finite time; above it (tan θ
between μ_s and μ_2) it tends to Bagnold's profile. Neither transient has a closed form, so this module
solves the 1D problem with finite volumes fine enough to be converged (cell centres at (j + ½) Δ,
viscosity on the faces from the face's own shear rate and pressure, the bed face at the bed's normal
stress with γ̇ = u_0/(Δ/2); backward Euler with Picard iterations on η). It is the reference of the
decelerating-layer check (:func:`granudep.isph.verification.decelerating_layer`) and of
``benchmarks/decelerating_layer.py``, which measure how the 2D solver and Basilisk treat the bed of
sheets a few particles (cells) thick — the regime of the T22 fronts.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.linalg import solve_banded

G = 9.81


@dataclass(frozen=True)
class LayerMaterial:
    """μ(I) material of the layer (SI); defaults: the glass beads of Table 2 as the 2D solver has them."""
    rho: float = 1550.0
    rho_s: float = 2500.0
    d: float = 0.7e-3
    mu_s: float = math.tan(math.radians(25.5))
    mu_2: float = 0.73
    i0: float = 0.279
    eta_max: float = 5.0e3
    #: viscosity floor (Pa s); 0 as in the 2D solver (whose 1e-3 Pa s floor never acts here). Basilisk's
    #: granular.h floors η at ρ D sqrt(g D) = 0.13 Pa s: set it to read its thin layers
    eta_min: float = 0.0

    @classmethod
    def from_config(cls, cfg) -> "LayerMaterial":
        m = cfg.material
        return cls(m.rho, m.rho_s, m.d, m.mu_s, m.mu_2, m.I0_standard, cfg.rheology.eta_max)


def face_pressure(h: float, n_cells: int, theta: float, rho: float) -> np.ndarray:
    """Lithostatic pressure ρ g cos θ (h − y_f) on the n faces below each cell (face 0: the bed)."""
    yf = np.arange(n_cells) * (h / n_cells)
    return rho * G * math.cos(theta) * (h - yf)


def face_viscosity(gdot: np.ndarray, p: np.ndarray, mat: LayerMaterial) -> np.ndarray:
    """η = min(μ(I) p / |γ̇|, η_max) on each face (regularised μ(I), the 2D solver's law)."""
    ag = np.maximum(np.abs(gdot), 1e-12)
    inert = mat.d * ag / np.sqrt(np.maximum(p, 1e-300) / mat.rho_s)
    mu = mat.mu_s + (mat.mu_2 - mat.mu_s) * inert / (mat.i0 + inert)
    return np.clip(mu * p / ag, mat.eta_min, mat.eta_max)


def face_shear_rate(u: np.ndarray, dy: float) -> np.ndarray:
    """∂u/∂y on the faces below each cell: the bed face from u = 0 at y = 0 (one-sided, Δ/2)."""
    g = np.empty_like(u)
    g[0] = 2.0 * u[0] / dy
    g[1:] = (u[1:] - u[:-1]) / dy
    return g


def bagnold_initial(y: np.ndarray, h: float, mean_speed: float) -> np.ndarray:
    """Bagnold's profile shape 1 − (1 − y/h)^{3/2}, scaled to a given mean speed."""
    s = 1.0 - (1.0 - np.clip(y, 0.0, h) / h) ** 1.5
    return s * (mean_speed / float(np.mean(s)))


@dataclass
class LayerHistory:
    t: np.ndarray            # output times (s)
    mean_speed: np.ndarray   # depth-averaged speed at t (m/s)
    surface_speed: np.ndarray
    t_stop: float            # first time the mean speed falls below stop_speed (s); NaN if never
    u: np.ndarray            # final profile at the cell centres
    y: np.ndarray


def uniform_layer(h: float, theta_deg: float, mean_speed: float = 1.0, n_cells: int = 80, t_end: float = 1.2,
                  dt: float = 2.0e-4, out_every: float = 0.05, stop_speed: float = 0.01,
                  mat: LayerMaterial | None = None, initial: str = "bagnold") -> LayerHistory:
    """Transient of a uniform μ(I) layer launched with a Bagnold-shaped (``initial='bagnold'``) or
    plug (``'plug'``) profile of the given mean speed: backward Euler, Picard on the face viscosities
    (to 1e-10 m/s), tridiagonal solve per iteration. Returns the mean and surface speeds every
    ``out_every`` s and the stop time (mean speed < ``stop_speed``)."""
    if not (h > 0.0 and n_cells >= 2 and dt > 0.0 and t_end > 0.0):
        raise ValueError("uniform_layer: need h > 0, n_cells >= 2, dt > 0, t_end > 0")
    mat = mat or LayerMaterial()
    th = math.radians(theta_deg)
    dy = h / n_cells
    y = (np.arange(n_cells) + 0.5) * dy
    pf = face_pressure(h, n_cells, th, mat.rho)
    u = bagnold_initial(y, h, mean_speed) if initial == "bagnold" else np.full(n_cells, float(mean_speed))
    ts, ms, ss = [0.0], [float(np.mean(u))], [float(u[-1])]
    t, t_stop = 0.0, math.nan
    n_steps = int(round(t_end / dt))
    every = max(1, int(round(out_every / dt)))
    ab = np.zeros((3, n_cells))
    for n in range(1, n_steps + 1):
        un = u.copy()
        for it in range(60):
            a = face_viscosity(face_shear_rate(u, dy), pf, mat) / dy**2
            diag = mat.rho / dt + a
            diag[0] += a[0]                  # the bed face: u_ghost = −u_0
            diag[:-1] += a[1:]
            ab[1] = diag
            ab[0, 1:] = -a[1:]
            ab[2, :-1] = -a[1:]
            unew = solve_banded((1, 1), ab, mat.rho * un / dt + mat.rho * G * math.sin(th))
            done = float(np.max(np.abs(unew - u))) < 1e-10
            u = unew if it < 20 else 0.5 * (u + unew)
            if done:
                break
        t = n * dt
        if math.isnan(t_stop) and float(np.mean(u)) < stop_speed:
            t_stop = t
        if n % every == 0:
            ts.append(t)
            ms.append(float(np.mean(u)))
            ss.append(float(u[-1]))
    return LayerHistory(np.array(ts), np.array(ms), np.array(ss), t_stop, u, y)
