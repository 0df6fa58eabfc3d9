"""Energy bookkeeping of a DA run (a dataset of ``run_da``): the checks that say whether the scheme
created energy.

E(t) = Σ_i V_i (u_i²/2 + g z_i + g cosθ_i h_i/2) per unit density (and width): kinetic, potential of the
particle on the bed, and the hydrostatic potential of its own depth (the energy of the k = 1 pressure;
eqs 8–9 only add dissipation on top of it when k_a ≤ 1 ≤ k_p).

With deposition the deposit is bed (``deposition.deposit_as_bed``: −g cosθ ∂h_D/∂x in the momentum
balance), so it carries energy too, booked as the hydrostatic energy of the two layers,
∫ g cosθ (h + h_D)²/2 = ∫ g cosθ (h²/2 + h h_D + h_D²/2):

    E = Σ_i V_i (u_i²/2 + g z_i + g cosθ_i (h_i/2 + h_D(x_i))) + Σ_k V_D,k g (z_k + cosθ_k h_D,k/2)

over the particles i and the grid cells k (V_D,k the deposited volume of cell k, h_D the deposit depth
on the grid, linearly interpolated to the particles). Volume moved from a particle onto the grid at
its own place leaves E unchanged but for its kinetic energy (and eq 12's velocity loss), which is
dissipation; between depositions the deposit is a fixed bed, in whose potential V_i g cosθ h_D the
particles move. So E never rises with deposition either, up to the difference between the grid's
smoothed deposit and the kernel sum of the bed term (O(Δx_grid²)). With ``deposition.own_deposit:
exclude`` (the default) a particle is not pushed by the deposit it laid itself: E then also loses
the work that force would have done (negative for a particle moving away from its own trail), so a
rise of E is still energy the scheme made, but E is no longer an exact budget.

Two checks:

* **Coulomb ratio** W_min/ΔE: the basal friction work is no less than μ g Σ V_i Δx_i (Δx the horizontal
  displacement between the first and the last output, V_i the particle's final volume, never more than
  what it carried on the way; equality for blocks sliding forward only, more with the centripetal
  normal stress, backward motion, the earth-pressure dissipation or deposition), so
  W_min / (E_0 − E_end) ≤ 1 unless the scheme created energy;
* **largest rise** of E between two outputs, relative to E_0 − E_end: friction, the pressure switch and
  deposition only remove energy, so any rise above round-off is energy the scheme made.
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


def _deposit_energy(ds: xr.Dataset, xp: np.ndarray, V: np.ndarray, c: np.ndarray) -> np.ndarray:
    """The deposit's share of E(t): Σ_i V_i g cosθ_i h_D(x_i) + Σ_k V_D,k g (z_k + cosθ_k h_D,k/2)."""
    hd = ds.deposit_depth.values                      # (time, cell), bed-normal, per unit width
    if "x_particle" in ds and "bed_slope" in ds:      # a path: cells at the stations s
        xc = ds.s.values
        zc, cc = ds.z.values, np.cos(np.radians(ds.bed_slope.values))
        width = ds.width.values if "width" in ds else np.ones_like(xc)
    else:
        xc = ds.x_grid.values
        th = math.radians(float(ds.attrs["theta_deg"]))
        zc, cc, width = -xc * math.sin(th), np.full(xc.shape, math.cos(th)), np.ones_like(xc)
    dxg = float(ds.attrs["dx_grid"])
    vd = hd * width * dxg                              # deposited volume per cell
    cells = (vd * G * (zc + cc * hd / 2.0)).sum(axis=1)
    at_particles = np.stack([np.interp(xp[k], xc, hd[k], right=0.0) for k in range(hd.shape[0])])
    return cells + (V * G * c * at_particles).sum(axis=1)


def has_deposit(ds: xr.Dataset) -> bool:
    """True when the run deposited (its deposit then carries energy)."""
    return bool(ds.attrs.get("deposition", False)) and "deposit_depth" in ds and \
        float(ds.deposited_volume.max()) > 0.0


def energy_series(ds: xr.Dataset, with_deposit: bool = True) -> np.ndarray:
    """E(t) at every output (m⁴ s⁻² per unit density and width; m³ … on a constant slope), the
    deposit's share included (``with_deposit=False``: the particles' share alone)."""
    V, u, h, z, _, c = _particle_fields(ds)
    E = (V * (0.5 * u ** 2 + G * z + G * c * h / 2.0)).sum(axis=1)
    if with_deposit and has_deposit(ds):
        xp = ds.x_particle.values if "x_particle" in ds else ds.x.values
        E = E + _deposit_energy(ds, xp, V, c)
    return E


def coulomb_ratio(ds: xr.Dataset, mu: float, E: np.ndarray | None = None) -> float:
    """W_min / (E_0 − E_end) with W_min = μ g Σ V_i Δx_i (horizontal): ≤ 1 unless energy was created
    (E: :func:`energy_series`, computed when not given)."""
    V, _, _, _, xh, _ = _particle_fields(ds)
    E = energy_series(ds) if E is None else E
    w_min = G * mu * float((V[-1] * (xh[-1] - xh[0])).sum())
    return w_min / float(E[0] - E[-1])


def largest_rise(E: np.ndarray) -> tuple[float, int]:
    """(largest E(t_k+1) − E(t_k) over the outputs of the series E relative to E_0 − E_end (≤ 0 when E
    never rises), number of output intervals in which E rose by more than 1e-9 of E_0 − E_end)."""
    drop = float(E[0] - E[-1])
    d = np.diff(E) / drop
    return (float(d.max()) if d.size else 0.0), int(np.count_nonzero(d > 1e-9))


def energy_report(ds: xr.Dataset) -> dict:
    """The energy checks of a run, with or without deposition."""
    mu = math.tan(math.radians(float(ds.attrs.get("phi_basal_deg", 25.5))))
    E = energy_series(ds)
    rise, n = largest_rise(E)
    return {"coulomb_ratio": coulomb_ratio(ds, mu, E), "largest_rise": rise, "n_rises": n}
