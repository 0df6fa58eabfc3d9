"""Synthetic, contract-shaped 2D run files for the monitor/regress tests (ISPH contract, docs/data-contract.md).

A run is a particle lattice (spacing dx, bed at y = 0, first row at dx/2) with planted velocities:
the lowest ``m`` rows of a column are at rest (deposited), the rows above move at ``u_flow``.
"""
from __future__ import annotations

import numpy as np
import xarray as xr

from granudep import cases
from granudep.io import provenance, var


def lattice(x_lo: float, x_hi: float, n_rows: int, dx: float):
    """Particle centres of a strip [x_lo, x_hi] × [0, n_rows·dx] (centres at (i + ½) dx)."""
    nx = int(round((x_hi - x_lo) / dx))
    X, Y = np.meshgrid(x_lo + (np.arange(nx) + 0.5) * dx, (np.arange(n_rows) + 0.5) * dx, indexing="ij")
    return X.ravel(), Y.ravel()


def free_surface_flags(x, y, dx):
    """1 for the highest particle of each lattice column (enough for a flat synthetic strip)."""
    col = np.round(x / dx - 0.5).astype(int)
    col -= col.min()
    top = np.full(col.max() + 1, -np.inf)
    np.maximum.at(top, col, y)
    return (np.abs(y - top[col]) < 1e-9 * dx + 1e-15).astype(np.int8)


def planted_frame(x, y, dx, m_deposit, u_flow, v_flow=0.0):
    """Velocities: rows below m_deposit·dx at rest, rows above move at (u_flow, v_flow)."""
    moving = y > m_deposit * dx
    u = np.where(moving, u_flow, 0.0)
    v = np.where(moving, v_flow, 0.0)
    return u, v


def make_run(frames, *, dx=0.004, h_ratio=1.3, L0=0.2, H0=0.14, theta_deg=22.0, x_inf=0.6,
             case="SYN-A70", times=None, free_surface=None):
    """Contract-shaped run Dataset from a list of frames (x, y, u, v) with equal particle counts."""
    nt = len(frames)
    X = np.stack([f[0] for f in frames])
    Y = np.stack([f[1] for f in frames])
    U = np.stack([f[2] for f in frames])
    V = np.stack([f[3] for f in frames])
    if free_surface is None:
        FS = np.stack([free_surface_flags(X[i], Y[i], dx) for i in range(nt)])
    else:
        FS = np.asarray(free_surface, dtype=np.int8)
    t = np.arange(nt) * 0.05 if times is None else np.asarray(times, dtype=float)
    dims = ("time", "particle")
    ds = xr.Dataset(
        {"x": var(X, dims, "m", "down-slope position"), "y": var(Y, dims, "m", "bed-normal position"),
         "u": var(U, dims, "m s-1", "down-slope velocity"), "v": var(V, dims, "m s-1", "bed-normal velocity"),
         "pressure": var(np.zeros_like(X), dims, "Pa", "pressure"),
         "viscosity": var(np.zeros_like(X), dims, "Pa s", "effective viscosity"),
         "free_surface": var(FS, dims, "1", "free-surface flag"),
         "front_position": var(np.full(nt, x_inf), ("time",), "m", "front position"),
         "kinetic_energy": var(np.zeros(nt), ("time",), "J m-1", "kinetic energy"),
         "final_front_position": var(x_inf, (), "m", "final front position"),
         "final_front_v99": var(x_inf, (), "m", "final 1 % volume front (the monitor's x_inf by default)"),
         "time_to_rest": var(t[-1], (), "s", "time to rest")},
        coords={"time": var(t, ("time",), "s", "time")})
    mat = cases.material("glass_beads")
    ds.attrs.update(theta_deg=theta_deg, L0=L0, H0=H0, dx=dx, smoothing_length=h_ratio * dx,
                    particle_volume=dx * dx, rho=mat["rho"], rho_s=mat["rho_s"], d=mat["d"],
                    mu_s=0.48, mu_2=0.73, I0=0.279, front_depth_threshold=2 * mat["d"])
    provenance(ds, case=case, config_yaml="synthetic: true\n", command="tests")
    return ds


def strip_run(*, n_rows=15, m_deposit=6, u_flow=0.5, dx=0.004, x_lo=0.18, x_hi=0.62, jitter=0.0,
              seed=0, **kw):
    """One-frame run: a strip over all sections with a planted F/D interface at m_deposit·dx."""
    x, y = lattice(x_lo, x_hi, n_rows, dx)
    fs = free_surface_flags(x, y, dx)
    if jitter:
        rng = np.random.default_rng(seed)
        x = x + rng.uniform(-jitter, jitter, x.size) * dx
        y = np.maximum(y + rng.uniform(-jitter, jitter, y.size) * dx, 0.05 * dx)
    u, v = planted_frame(x, y, dx, m_deposit, u_flow)
    return make_run([(x, y, u, v)], dx=dx, free_surface=fs[None], **kw)


def ramp_run(*, n_rows=15, dx=0.004, t_onset=0.5, rows_per_s=20.0, t_end=1.0, dt=0.02, u0=1.0,
             x_lo=0.18, x_hi=0.62, **kw):
    """A run whose deposit grows by ``rows_per_s`` lattice rows per second after ``t_onset`` and
    whose flowing layer slows linearly from u0 (a synthetic deceleration with deposition)."""
    x, y = lattice(x_lo, x_hi, n_rows, dx)
    times = np.arange(0.0, t_end + 0.5 * dt, dt)
    frames = []
    for t in times:
        m = int(np.floor(max(t - t_onset, 0.0) * rows_per_s + 1e-9)) if t >= t_onset else 0
        m = min(m, n_rows)
        u_flow = max(u0 * (1.0 - t / (1.2 * t_end)), 0.2)
        frames.append((x, y, *planted_frame(x, y, dx, m, u_flow)))
    return make_run(frames, dx=dx, times=times, **kw)
