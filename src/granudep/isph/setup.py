"""Initial particle sets: the granular column (or layer) and the fixed wall-particle layers."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .config import IsphConfig
from ..kernels import wendland_dwdr, wendland_w


@dataclass
class Particles:
    x: np.ndarray          # all particles, granular first then walls
    y: np.ndarray
    nf: int                # number of granular particles
    wnx: np.ndarray        # wall-surface unit normal (into the granular domain), per wall particle
    wny: np.ndarray
    wc: np.ndarray         # wall-surface offset: n·x = c on the surface


def lattice(x0: float, x1: float, y0: float, y1: float, dx: float) -> tuple[np.ndarray, np.ndarray]:
    """Square lattice of spacing dx filling [x0,x1]×[y0,y1] with cell-centred points."""
    nx = max(int(round((x1 - x0) / dx)), 1)
    ny = max(int(round((y1 - y0) / dx)), 1)
    xs = x0 + (np.arange(nx) + 0.5) * dx
    ys = y0 + (np.arange(ny) + 0.5) * dx
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    return X.ravel(), Y.ravel()


def perturbed(x: np.ndarray, y: np.ndarray, dx: float, seed: int, jitter: float) -> tuple[np.ndarray, np.ndarray]:
    """An ensemble member's initial positions: the lattice (seed 0) or, for seed k > 0, every position
    moved by ``jitter`` dx N(0, 1) per coordinate from ``numpy.random.default_rng(k)``, clipped to
    the lattice's own extent (no particle starts in a wall or beyond the column)."""
    if seed == 0 or jitter == 0.0:
        return x, y
    rng = np.random.default_rng(seed)
    px = np.clip(x + jitter * dx * rng.standard_normal(x.size), x.min(), x.max())
    py = np.clip(y + jitter * dx * rng.standard_normal(y.size), y.min(), y.max())
    return px, py


def build_particles(cfg: IsphConfig) -> Particles:
    """Column [0,L0]×[0,H0] (or a periodic layer of height H0) plus bed and back-wall layers."""
    g, dx = cfg.geometry, cfg.numerics.dx
    nl = cfg.wall_layers
    fx, fy = perturbed(*lattice(0.0, g.L0, 0.0, g.H0, dx), dx, cfg.numerics.seed, cfg.numerics.jitter)
    walls_x, walls_y, nxs, nys, cs = [], [], [], [], []

    def add(px, py, nx, ny, c):
        walls_x.append(px)
        walls_y.append(py)
        nxs.append(np.full(px.size, nx))
        nys.append(np.full(px.size, ny))
        cs.append(np.full(px.size, c))

    length = cfg.domain_length
    # bed: layers below y = 0
    bx, by = lattice(0.0, length if g.periodic_length > 0 else length + nl * dx, -nl * dx, 0.0, dx)
    add(bx, by, 0.0, 1.0, 0.0)
    if g.back_wall:
        top = g.H0 + 3.0 * dx
        wx, wy = lattice(-nl * dx, 0.0, 0.0, top, dx)
        add(wx, wy, 1.0, 0.0, 0.0)
        cx, cy = lattice(-nl * dx, 0.0, -nl * dx, 0.0, dx)
        s = 1.0 / math.sqrt(2.0)
        add(cx, cy, s, s, 0.0)
    wx = np.concatenate(walls_x)
    wy = np.concatenate(walls_y)
    return Particles(x=np.concatenate([fx, wx]), y=np.concatenate([fy, wy]), nf=fx.size,
                     wnx=np.concatenate(nxs), wny=np.concatenate(nys), wc=np.concatenate(cs))


def reference_concentration(h: float, dx: float) -> float:
    """C0 = Σ_j V W(r_ij) on a full square lattice (self included): the 'incompressible' value."""
    n = int(math.ceil(2.0 * h / dx)) + 1
    k = np.arange(-n, n + 1) * dx
    X, Y = np.meshgrid(k, k)
    r = np.hypot(X, Y).ravel()
    return float(sum(wendland_w(float(ri), h) for ri in r) * dx * dx)


def reference_laplacian_sum(h: float, dx: float, eps2: float) -> float:
    """Σ_j 2 V F_ij on a full square lattice: the PPE diagonal of a particle with full support."""
    n = int(math.ceil(2.0 * h / dx)) + 1
    k = np.arange(-n, n + 1) * dx
    X, Y = np.meshgrid(k, k)
    r = np.hypot(X, Y).ravel()
    r = r[r > 0]
    return float(sum(2.0 * dx * dx * (-wendland_dwdr(float(ri), h)) * ri / (ri * ri + eps2) for ri in r))


def lattice_constants(h_factor: float, eps_factor: float, layers: int, slip_length: float = 0.0) -> dict:
    """Discrete moments of the Morris/Cummins Laplacian on the initial square lattice (dx = 1).

    * ``lap``: Σ_j V F_ij y_ij² (continuum value 1; 0.963 for h = 1.3 dx): the Laplacian
      coefficients are divided by it, so that the discrete operator is exact for quadratic fields;
    * ``wall_ns``: Σ_layers (d_i + b) Σ_w V F_iw β_iw (continuum 1): wall shear stress of the Morris
      extrapolation (β capped at 1.5) for the linear profile u = y + b of a Navier wall with slip
      length b = ``slip_length`` (in dx; 0 = no slip); wall terms are divided by it, so that the
      discrete wall stress of that profile is η du/dy whatever b. The cap acts on the first layer
      only when b < dx: normalised by the no-slip sum (0.71 for h = 1.3 dx), a Navier wall with
      b ≥ dx had 1.35 times its stress, i.e. an effective slip length (d_1 + b)/1.35 − d_1 ≈ 0.73 b.
    """
    h = h_factor
    eps2 = eps_factor * h * h
    n = int(math.ceil(2.0 * h)) + 2
    k = np.arange(-n, n + 1, dtype=float)
    X, Y = np.meshgrid(k, k)
    r = np.hypot(X, Y).ravel()
    yy = Y.ravel()
    m = r > 0
    F = np.array([-wendland_dwdr(float(ri), h) * ri / (ri * ri + eps2) for ri in r[m]])
    lap = float(np.sum(F * yy[m] ** 2))
    wall_ns = 0.0
    for layer in range(int(math.ceil(2.0 * h)) + 1):
        yi = layer + 0.5
        s_layer = 0.0
        for xw in k:
            for lw in range(layers):
                yw = -(lw + 0.5)
                rr = math.hypot(xw, yi - yw)
                if rr >= 2.0 * h:
                    continue
                f = -wendland_dwdr(rr, h) * rr / (rr * rr + eps2)
                s_layer += 2.0 * f * min(1.5, (yi - yw) / (yi + slip_length))
        wall_ns += (yi + slip_length) * s_layer
    return {"lap": lap, "wall_ns": wall_ns}
