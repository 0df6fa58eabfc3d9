"""Small synthetic datasets shaped like the stage outputs (docs/data-contract.md).

Numbers are planted so tests know the exact answers: the 2D front moves at a constant speed until
``t_stop`` and then stays, so the shared flow-time definition returns ``t_stop`` exactly; DA scalars
are chosen as exact multiples of the reference values.
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
import xarray as xr

from granudep import cases
from granudep.io import provenance, var, write_netcdf

THRESH = 1.4e-3


def _attrs(ds, case, **attrs):
    provenance(ds, case=case, config_yaml="synthetic: true\n", command="synthetic test data")
    ds.attrs.update(attrs)
    return ds


def isph_run(case="T22-A70", L0=0.2, H0=0.14, theta=22.0, dx=0.01, runout=0.3, t_stop=1.0,
             t_end=1.6, dt=0.02) -> xr.Dataset:
    """A 2D run: a column stretched along the slope, front = L0 + runout·min(t/t_stop, 1)."""
    time = np.round(np.arange(0.0, t_end + dt / 2, dt), 10)
    front = L0 + runout * np.minimum(time / t_stop, 1.0)
    X, Y = np.meshgrid(np.arange(dx / 2, L0, dx), np.arange(dx / 2, H0, dx))
    X, Y = X.ravel(), Y.ravel()
    s = front / L0  # stretch factor
    x = X[None, :] * s[:, None]
    # surface sloping down towards the front, area-preserving on average
    y = Y[None, :] / s[:, None] * (1.5 - X[None, :] / L0)
    moving = (time < t_stop)[:, None]
    u = np.where(moving, X[None, :] / L0 * runout / t_stop, 0.0)
    u = u * np.clip(y / (0.3 * H0), 0.0, 1.0)  # slow base: a deposited layer
    v = np.zeros_like(u)
    p = 1550 * 9.81 * np.maximum(H0 / s[:, None] - y, 0)
    fs = (y > (H0 / s[:, None]) * (1.5 - X[None, :] / L0) - 1.5 * dx).astype(np.int8)
    ds = xr.Dataset(
        {"x": var(x, ("time", "particle"), "m", "down-slope position"),
         "y": var(y, ("time", "particle"), "m", "bed-normal position"),
         "u": var(u, ("time", "particle"), "m s-1", "down-slope velocity"),
         "v": var(v, ("time", "particle"), "m s-1", "bed-normal velocity"),
         "pressure": var(p, ("time", "particle"), "Pa", "pressure"),
         "viscosity": var(np.full_like(p, 0.1), ("time", "particle"), "Pa s", "viscosity"),
         "free_surface": var(fs, ("time", "particle"), "1", "free-surface flag"),
         "front_position": var(front, ("time",), "m", "front position from the back wall"),
         "kinetic_energy": var(np.where(time < t_stop, 1.0, 0.0), ("time",), "J m-1", "kinetic energy"),
         "final_front_position": var(front[-1], (), "m", "final front position"),
         "time_to_rest": var(t_stop, (), "s", "time to rest")},
        coords={"time": var(time, ("time",), "s", "time")})
    return _attrs(ds, case, theta_deg=theta, L0=L0, H0=H0, dx=dx, smoothing_length=1.3 * dx,
                  particle_volume=dx * dx, rho=1550.0, rho_s=2500.0, d=7e-4, mu_s=0.48, mu_2=0.6,
                  I0=0.279, front_depth_threshold=THRESH)


def da_run(case="1D-A70", deposition=True, final_runout_norm=1.8, flow_time=1.2, L0=0.2, H0=0.14,
           theta=22.0, n=40, nx=60, dt=0.02) -> xr.Dataset:
    """A DA run whose front reaches L0(1 + final_runout_norm) linearly at ``flow_time``, then stops."""
    t_end = flow_time * 1.4
    time = np.round(np.arange(0.0, t_end + dt / 2, dt), 10)
    runout = final_runout_norm * L0 * np.minimum(time / flow_time, 1.0)
    front = L0 + runout
    x_edges = np.linspace(0.0, L0 * (2 + final_runout_norm), nx + 1)
    xg = 0.5 * (x_edges[1:] + x_edges[:-1])
    hT = np.clip(H0 * L0 / front[:, None] * (1 - xg[None, :] / front[:, None]) * 2, 0, None)
    frac = np.clip(time / flow_time, 0, 1)[:, None] if deposition else np.zeros((time.size, 1))
    hD = hT * frac * 0.8
    h = hT - hD
    vol0 = H0 * L0
    dep_vol = vol0 * 0.8 * frac[:, 0]
    px = np.linspace(0.01, 1.0, n)[None, :] * front[:, None]
    tc = cases.characteristic_time(H0, math.radians(theta))
    ds = xr.Dataset(
        {"front_position": var(front, ("time",), "m", "front position from the back wall"),
         "runout": var(runout, ("time",), "m", "runout from the gate"),
         "flowing_volume": var(vol0 - dep_vol, ("time",), "m2", "flowing volume per unit width"),
         "deposited_volume": var(dep_vol, ("time",), "m2", "deposited volume per unit width"),
         "flow_depth": var(h, ("time", "x_grid"), "m", "flowing depth"),
         "deposit_depth": var(hD, ("time", "x_grid"), "m", "deposit depth"),
         "x": var(px, ("time", "particle"), "m", "particle position"),
         "u": var(np.gradient(px, time, axis=0), ("time", "particle"), "m s-1", "particle velocity"),
         "h": var(np.full_like(px, 0.01), ("time", "particle"), "m", "particle depth"),
         "volume": var(np.full_like(px, vol0 / n), ("time", "particle"), "m2", "particle volume"),
         "final_runout": var(runout[-1], (), "m", "final runout"),
         "final_runout_norm": var(final_runout_norm, (), "1", "final runout / L0"),
         "flow_time": var(flow_time, (), "s", "flow time"),
         "flow_time_norm": var(flow_time / tc, (), "1", "flow time / t_c")},
        coords={"time": var(time, ("time",), "s", "time"),
                "x_grid": var(xg, ("x_grid",), "m", "grid cell centre")})
    return _attrs(ds, case, theta_deg=theta, L0=L0, H0=H0, a=H0 / L0, deposition=int(deposition),
                  front_depth_threshold=THRESH, x_inf=float(front[-1]))


SECTION_TC = np.array([7.9, 8.1, 8.4, 8.8, 9.2, 9.6, 10.0, 10.4, 10.8, 11.0, 11.2])  # planted (t_s)_C
SECTION_RATE = 0.02  # planted d(h_D/H0)/dt_s


def sections(case="T22-A70", L0=0.2, H0=0.14, theta=22.0, x_inf=0.5, dx=0.004, t_end=4.0, nt=81):
    """Monitoring sections with h_D/H0 = rate·(t_s − (t_s)_C) after a planted onset."""
    tc = cases.characteristic_time(H0, math.radians(theta))
    time = np.linspace(0.0, t_end, nt)
    ts = time / tc
    xn = np.linspace(0.0, 1.0, 11)
    x = L0 + xn * (x_inf - L0)
    arrive = 1.0 + 2.0 * xn
    hT = H0 * np.where(ts[None, :] >= arrive[:, None], 0.15 + 0.2 * (1 - xn[:, None]), 0.0)
    hT[0] = np.maximum(hT[0], H0 * np.exp(-ts / 3))
    onset = SECTION_TC[:, None]  # planted onset, in t_s
    hD = np.clip(H0 * SECTION_RATE * (ts[None, :] - onset), 0.0, None)
    hD = np.minimum(hD, hT)
    h = hT - hD
    vel = np.where(hT > 0, 0.8 * np.exp(-0.25 * np.clip(ts[None, :] - arrive[:, None], 0, None)), 0.0)
    ds = xr.Dataset(
        {"velocity": var(vel, ("section", "time"), "m s-1", "depth-averaged velocity"),
         "flow_depth": var(h, ("section", "time"), "m", "flowing depth"),
         "deposit_depth": var(hD, ("section", "time"), "m", "deposit depth"),
         "total_depth": var(hT, ("section", "time"), "m", "total depth"),
         "momentum": var(h * vel, ("section", "time"), "m2 s-1", "depth-averaged momentum hu"),
         "free_surface_height": var(hT, ("section", "time"), "m", "free-surface height"),
         "interface_height": var(hD, ("section", "time"), "m", "F/D interface height")},
        coords={"x": var(x, ("section",), "m", "section position"),
                "x_norm": var(xn, ("section",), "1", "normalised section position [x]"),
                "time": var(time, ("time",), "s", "time"),
                "t_s": var(ts, ("time",), "1", "normalised time t/t_c")})
    return _attrs(ds, case, theta_deg=theta, L0=L0, H0=H0, dx=dx, x_inf=x_inf, width_factor=2.0)


def wm_sections(case="T22-A70", factors=(1, 2, 3, 4)):
    """monitor-wm-like output: momentum_norm (width_factor, section, time), planted deviations
    hu/p0·(1 + 0.01 (f − 2)) so the RMS from W_M = 2 dx is known; deceleration window; no rms
    variable (the figure computes it)."""
    base = sections(case)
    p0 = cases.momentum_scale(0.14, math.radians(22.0))
    m = base["momentum"].values / p0
    mom = np.stack([m * (1 + 0.01 * (f - 2)) for f in factors])
    ds = base.drop_vars(list(base.data_vars))
    ds = ds.assign_coords(width_factor=var(np.asarray(factors, float), ("width_factor",), "1", "W_M / dx"))
    ds["momentum_norm"] = var(mom, ("width_factor", "section", "time"), "1", "hu/p0 per width")
    ds["deceleration"] = var((m > 0).astype(np.int8), ("section", "time"), "1", "deceleration window")
    ds.attrs["wm_reference"] = 2.0
    return ds


def critical_table(case="T22-A70", theta=22.0, a=0.7, A=-0.03, B=0.05):
    xn = np.linspace(0.0, 1.0, 11)
    return pd.DataFrame({"case": case, "theta_deg": theta, "a": a, "x_norm": xn,
                         "t_s_critical": SECTION_TC, "t_s_critical_fit": SECTION_TC + 0.05,
                         "deposition_rate": SECTION_RATE, "r2": 0.99,
                         "momentum_critical_norm": A * xn + B})


def coefficients_table():
    rows = []
    for theta, base in ((16.0, 0.08), (22.0, 0.06)):
        for a in (0.35, 0.5, 0.7, 1.0):
            rows.append({"case": f"T{theta:.0f}-A{round(100 * a)}", "theta_deg": theta, "a": a,
                         "A": -0.05 / (1 + a), "B": base / (1 + a), "r2": 0.99})
    return pd.DataFrame(rows)


def save(ds: xr.Dataset, path) -> str:
    write_netcdf(ds, path)
    return str(path)
