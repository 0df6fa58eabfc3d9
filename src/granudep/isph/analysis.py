"""Post-processing of ISPH runs: the initial failure plane of the column (Section 4.2.2)."""
from __future__ import annotations

import math

import numpy as np
import xarray as xr


def failure_plane_angle(ds: xr.Dataset, t_norm: float = 1.0, v_crit: float = 0.1) -> dict:
    """Inclination (from the bed) of the surface separating moving and static column particles.

    At t = t_norm t_c the particles faster than ``v_crit`` (the paper's 0.1 m/s flow/deposit
    threshold, Section 2.2) are 'moving'. In bands of initial height y0 in [0.1, 0.9] H0, the
    failure surface position is the smallest initial x0 of a moving particle; a straight line
    x0 = c − y0 cot(θ_F) fitted through the band points gives θ_F (Rankine: 45° + φ/2).
    """
    tc = float(ds.attrs["t_c"])
    k = int(np.argmin(np.abs(ds.time.values - t_norm * tc)))
    x0 = ds.x.isel(time=0).values.astype(float)
    y0 = ds.y.isel(time=0).values.astype(float)
    sp = np.hypot(ds.u.isel(time=k).values, ds.v.isel(time=k).values)
    H0, dx = float(ds.attrs["H0"]), float(ds.attrs["dx"])
    moving = sp > v_crit
    ys, xs = [], []
    for lo in np.arange(0.1 * H0, 0.9 * H0, dx):
        band = (y0 >= lo) & (y0 < lo + dx) & moving
        if band.any():
            ys.append(float(np.mean(y0[band])))
            xs.append(float(np.min(x0[band])))
    if len(ys) < 3:
        return {"angle_deg": float("nan"), "time": float(ds.time[k]), "points": 0}
    slope, _ = np.polyfit(ys, xs, 1)  # dx0/dy0 = -cot(theta_F)
    angle = math.degrees(math.atan2(1.0, -slope)) if slope < 0 else float("nan")
    return {"angle_deg": angle, "time": float(ds.time[k]), "points": len(ys)}
