"""Energy bookkeeping of a DA run (a dataset of ``run_da``): the checks that say whether the scheme
created energy.

E(t) = Σ_i V_i (u_i²/2 + g z_i + g cosθ_i h_i/2) per unit density (and width): kinetic, potential of the
particle on the bed, and the hydrostatic potential of its own depth (the energy of the k = 1 pressure;
eqs 8–9 only add dissipation on top of it when k_a ≤ 1 ≤ k_p). Without deposition two checks:

* **Coulomb ratio** W_min/ΔE: the basal friction work is no less than μ g Σ V_i Δx_i (Δx the horizontal
  displacement between the first and the last output; equality for blocks sliding forward only, more
  with the centripetal normal stress, backward motion or the earth-pressure dissipation), so
  W_min / (E_0 − E_end) ≤ 1 unless the scheme created energy;
* **largest rise** of E between two outputs, relative to E_0 − E_end: friction and the pressure switch
  only remove energy, so any rise above round-off is energy the scheme made.

With deposition the deposited volume leaves the particles (its energy is not tracked), so only runs
without deposition are checked.
"""
from __future__ import annotations

import math

import numpy as np
import xarray as xr

from ..cases import G


def _particle_fields(ds: xr.Dataset):
    """(V, u, h, z, x_horizontal, cosθ) per output and particle, for a constant slope or a path."""
    V, u, h = ds.volume.values, ds.u.values, ds.h.values
    if "x_particle" in ds and "bed_slope" in ds:          # a path: stations s, bed z(s), x(s), θ(s)
        s, zb, xb = ds.s.values, ds.z.values, ds.x.values
        sp = ds.x_particle.values
        th = np.radians(np.interp(sp, s, ds.bed_slope.values))
        z, xh = np.interp(sp, s, zb), np.interp(sp, s, xb)
    else:
        th = np.full(V.shape, math.radians(float(ds.attrs["theta_deg"])))
        xp = ds.x.values if ds.x.dims == ("time", "particle") else ds.x_particle.values
        z, xh = -xp * np.sin(th), xp * np.cos(th)
    return V, u, h, z, xh, np.cos(th)


def energy_series(ds: xr.Dataset) -> np.ndarray:
    """E(t) at every output (m⁴ s⁻² per unit density and width; m³ … on a constant slope)."""
    V, u, h, z, _, c = _particle_fields(ds)
    return (V * (0.5 * u ** 2 + G * z + G * c * h / 2.0)).sum(axis=1)


def coulomb_ratio(ds: xr.Dataset, mu: float) -> float:
    """W_min / (E_0 − E_end) with W_min = μ g Σ V_i Δx_i (horizontal): ≤ 1 unless energy was created."""
    V, _, _, _, xh, _ = _particle_fields(ds)
    E = energy_series(ds)
    w_min = G * mu * float((V[-1] * (xh[-1] - xh[0])).sum())
    return w_min / float(E[0] - E[-1])


def largest_rise(ds: xr.Dataset) -> tuple[float, int]:
    """(largest E(t_k+1) − E(t_k) over the outputs relative to E_0 − E_end (≤ 0 when E never rises),
    number of output intervals in which E rose by more than 1e-9 of E_0 − E_end)."""
    E = energy_series(ds)
    drop = float(E[0] - E[-1])
    d = np.diff(E) / drop
    return (float(d.max()) if d.size else 0.0), int(np.count_nonzero(d > 1e-9))


def energy_report(ds: xr.Dataset) -> dict:
    """The energy checks of a run without deposition (NaN with deposition)."""
    if bool(ds.attrs.get("deposition", False)):
        return {"coulomb_ratio": float("nan"), "largest_rise": float("nan"), "n_rises": -1}
    mu = math.tan(math.radians(float(ds.attrs.get("phi_basal_deg", 25.5))))
    rise, n = largest_rise(ds)
    return {"coulomb_ratio": coulomb_ratio(ds, mu), "largest_rise": rise, "n_rises": n}
