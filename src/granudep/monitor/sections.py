"""Monitoring-section kernels: eq 15 (section velocity), eq 16 (F/D interface), eq 17 (depths).

Pure functions and ``@njit`` kernels only (the neighbour search is the solver's); the time loop and the output live in ``api.py``.

Conventions (slope-aligned frame of the ISPH output: x down-slope along the bed, y bed-normal,
bed at y = 0; particle centres sit half a spacing Δx inside the material they represent):

* a particle belongs to section k if |x − x_k| ≤ W_M/2 (W_M = width_factor·Δx);
* deposited: |v| = sqrt(u² + v²) < critical_speed, otherwise flowing;
* eq 16 with the sign that gives +2 under full support:
  (∇·r)_i = −Σ_{j deposited} V_j r_ij dW/dr(r_ij), V_j = particle_volume, Wendland C2 with the
  run's smoothing length; with ``mirror`` the images (x_j, −y_j) of the deposited particles count
  too (the rigid bed is at rest, and the run carries no wall particles);
* F/D interface particle: deposited, (∇·r)_i < threshold, not flagged ``free_surface`` and lying
  below the highest flowing particle of its section (so the top of a deposit that is itself the
  free surface is never an interface);
* Y_bed = 0; Y_F = highest particle centre + Δx/2;
  Y_F/D = mean interface-particle centre + Δx/2 (the top edge of the interface layer);
* eq 17 without 1/cos θ (y is already bed-normal): h = Y_F − Y_F/D, h_D = Y_F/D − Y_bed,
  h_T = h + h_D.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..isph.neighbours import build_neighbours
from ..kernels import wendland_dwdr

#: how the interface height of a section was obtained (variable ``interface_source``)
SOURCE_EMPTY = -1        # no particle in the section: every depth is NaN
SOURCE_NO_DEPOSIT = 0    # no deposited particle: h_D = 0, h = h_T
SOURCE_EQ16 = 1          # F/D interface particles found by eq 16
SOURCE_FALLBACK = 2      # deposited and flowing particles but no eq-16 interface particle:
                         # top of the deposited particles below the lowest flowing one (or the bed)
SOURCE_ALL_DEPOSITED = 3  # no flowing particle: h = 0, h_D = h_T

SOURCE_MEANINGS = ("-1 empty section, 0 no deposited particle, 1 eq 16 interface particles, "
                   "2 fallback: top of deposited particles below the lowest flowing particle, "
                   "3 fully deposited")


def section_centres(L0: float, x_inf: float, n_sections: int = 11) -> np.ndarray:
    """x_M = L0 + k (x∞ − L0)/(n − 1), k = 0 … n − 1 (Section 3: 11 sections, L0 to x∞)."""
    return L0 + (x_inf - L0) * np.arange(n_sections) / (n_sections - 1)


def divr_deposited(x, y, deposited, volume, h, mirror):
    """Eq 16 for every particle, summed over deposited neighbours only (support 2h).

    x, y: positions (NaN = absent particle → NaN result); deposited: bool mask; volume: V_j = m/ρ;
    h: smoothing length; mirror: add the images (x_j, −y_j) of deposited particles below the bed.
    The neighbours come from the solver's own search (:func:`granudep.isph.neighbours.build_neighbours`),
    run with every present particle as a row and the deposited particles (and their images) as the
    only sources that count.
    """
    x = np.asarray(x, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    out = np.full(x.size, np.nan)
    present = np.flatnonzero(np.isfinite(x) & np.isfinite(y))
    if present.size == 0:
        return out
    xa, ya = x[present], y[present]
    source = np.asarray(deposited, dtype=bool)[present]
    if mirror:
        xa = np.concatenate([xa, xa[source]])
        ya = np.concatenate([ya, -ya[source]])
        source = np.concatenate([source, np.ones(int(source.sum()), dtype=bool)])
    start, nbr, _, _, rr = build_neighbours(xa, ya, present.size, 2.0 * h, 0.0)
    out[present] = _divr_from_sources(start, nbr, rr, source, present.size, volume, h)
    return out


@njit(cache=True)
def _divr_from_sources(start, nbr, rr, source, n, volume, h):
    """−Σ_{j source} V r_ij dW/dr(r_ij) over each row's neighbour list (eq 16)."""
    out = np.zeros(n)
    for i in range(n):
        acc = 0.0
        for k in range(start[i], start[i + 1]):
            if source[nbr[k]]:
                r = rr[k]
                acc -= volume * r * wendland_dwdr(r, h)
        out[i] = acc
    return out


@njit(cache=True)
def section_reduce(x, y, vx, deposited, interface_candidate, x0, spacing, half_width, n_sections):
    """Per-section sums over the particles with |x − x_k| ≤ half_width, x_k = x0 + k·spacing.

    Returns a (n_sections, 11) array with columns
    0 count, 1 Σ v_x, 2 max y, 3 n deposited, 4 n flowing, 5 max y flowing, 6 min y flowing,
    7 Σ y of interface particles, 8 n interface particles, 9 max y of deposited particles below the
    lowest flowing one (−inf if none), 10 Σ v_x of the flowing particles. Interface particles are candidates lying below the highest
    flowing particle of the section (column 5).
    """
    out = np.zeros((n_sections, 11))
    for k in range(n_sections):
        out[k, 2] = -np.inf
        out[k, 5] = -np.inf
        out[k, 6] = np.inf
        out[k, 9] = -np.inf
    eps = 1e-12 * max(abs(spacing), half_width)
    for p in range(2):
        for i in range(x.size):
            if not (math.isfinite(x[i]) and math.isfinite(y[i]) and math.isfinite(vx[i])):
                continue
            klo = int(math.ceil((x[i] - half_width - eps - x0) / spacing))
            khi = int(math.floor((x[i] + half_width + eps - x0) / spacing))
            for k in range(max(klo, 0), min(khi, n_sections - 1) + 1):
                if abs(x[i] - (x0 + k * spacing)) > half_width + eps:
                    continue
                if p == 0:
                    out[k, 0] += 1.0
                    out[k, 1] += vx[i]
                    out[k, 2] = max(out[k, 2], y[i])
                    if deposited[i]:
                        out[k, 3] += 1.0
                    else:
                        out[k, 4] += 1.0
                        out[k, 10] += vx[i]
                        out[k, 5] = max(out[k, 5], y[i])
                        out[k, 6] = min(out[k, 6], y[i])
                elif deposited[i]:
                    if interface_candidate[i] and y[i] < out[k, 5]:
                        out[k, 7] += y[i]
                        out[k, 8] += 1.0
                    if y[i] < out[k, 6]:
                        out[k, 9] = max(out[k, 9], y[i])
    return out


def depths_from_sums(sums: np.ndarray, dx: float, y_bed: float = 0.0) -> dict:
    """Eq 15 and eq 17 from the per-section sums of :func:`section_reduce` (vectorised numpy).

    Returns arrays (n_sections) velocity, flowing_velocity, free_surface_height, interface_height,
    total_depth, flow_depth, deposit_depth, interface_source, n_particles, n_deposited, n_interface.
    """
    count, svx, ytop, ndep, nflow = sums[:, 0], sums[:, 1], sums[:, 2], sums[:, 3], sums[:, 4]
    niface = sums[:, 8]
    empty = count == 0
    with np.errstate(invalid="ignore", divide="ignore"):
        velocity = np.where(empty, np.nan, svx / np.where(empty, 1, count))
        flowing_velocity = np.where(nflow > 0, sums[:, 10] / np.where(nflow > 0, nflow, 1), np.nan)
        y_f = np.where(empty, np.nan, ytop + 0.5 * dx)
        y_iface = np.where(niface > 0, sums[:, 7] / np.where(niface > 0, niface, 1) + 0.5 * dx, np.nan)
        y_below = np.where(np.isfinite(sums[:, 9]), sums[:, 9] + 0.5 * dx, y_bed)
    source = np.select([empty, ndep == 0, nflow == 0, niface > 0],
                       [SOURCE_EMPTY, SOURCE_NO_DEPOSIT, SOURCE_ALL_DEPOSITED, SOURCE_EQ16],
                       SOURCE_FALLBACK).astype(np.int8)
    y_fd = np.select([source == SOURCE_EMPTY, source == SOURCE_NO_DEPOSIT, source == SOURCE_ALL_DEPOSITED,
                      source == SOURCE_EQ16], [np.nan, y_bed, y_f, y_iface], y_below)
    y_fd = np.clip(y_fd, y_bed, y_f)
    return {
        "velocity": velocity,
        "flowing_velocity": flowing_velocity,
        "free_surface_height": y_f,
        "interface_height": y_fd,
        "total_depth": y_f - y_bed,
        "flow_depth": y_f - y_fd,
        "deposit_depth": y_fd - y_bed,
        "interface_source": source,
        "n_particles": count.astype(np.int32),
        "n_deposited": ndep.astype(np.int32),
        "n_interface": niface.astype(np.int32),
    }
