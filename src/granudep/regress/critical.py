"""Per-section onset of deposition, deposition rate and critical DA momentum (Section 4.2, Figs 9, 11).

Rules (docs/model.md, "Monitoring sections and regression"):

* onset (t_s)_C: the last upward crossing of h_D = ε (ε = onset_depth_factor·dx, default half a
  particle spacing), i.e. the first time after which h_D stays ≥ ε until the end of the record,
  interpolated linearly between the bracketing samples; dips below ε whose surrounding samples above ε lie
  ≤ onset_max_gap apart (t_s) are bridged. An empty section (NaN) counts as h_D = 0.
  No onset when the deposit does not persist to the end, or when h_D ≥ ε from the first sample.
* growth phase: from the first sample after the crossing to the first sample with
  h_D ≥ growth_end_fraction·h_D(end); least-squares line h_D/H0 = (S_D)_s t_s + b over it, so
  (S_D)_s = sqrt(1/(g H0 cos θ)) dh_D/dt; the Fig-9 intercept (t_s)_C,fit = −b/(S_D)_s.
* critical DA momentum (hu)_C/p0: hu/p0 linearly interpolated in t_s at the onset (t_s)_C.
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
import xarray as xr

from .. import cases
from ..config import ConfigError
from .config import RegressConfig


def linear_fit(x, y):
    """Least-squares y = slope·x + intercept over finite pairs: (slope, intercept, R², n).

    R² = 1 − SS_res/SS_tot (NaN when fewer than 2 points or y is constant up to round-off)."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    ok = np.isfinite(x) & np.isfinite(y)
    x, y = x[ok], y[ok]
    n = int(x.size)
    if n < 2 or np.ptp(x) == 0:
        return math.nan, math.nan, math.nan, n
    slope, intercept = np.polyfit(x, y, 1)
    ss_tot = float(np.sum((y - y.mean()) ** 2))
    ss_res = float(np.sum((y - (slope * x + intercept)) ** 2))
    tiny = n * (1e-12 * float(np.max(np.abs(y)))) ** 2  # constant y up to round-off: R² undefined
    r2 = 1.0 - ss_res / ss_tot if ss_tot > tiny else math.nan
    return float(slope), float(intercept), r2, n


def onset_time(t_s, h_D, eps: float, max_gap: float = 0.0):
    """Last upward crossing of h_D = eps: (t_C, i, status), i = first sample of the final run of
    h_D ≥ eps; (nan, −1, reason) when there is none.

    Gaps (runs of h_D < eps) between two runs above eps whose surrounding above-eps samples are at
    most ``max_gap`` apart (in t_s) are bridged: a momentary re-mobilisation of a deposit does not
    reset its onset."""
    t_s = np.asarray(t_s, dtype=float)
    hd = np.nan_to_num(np.asarray(h_D, dtype=float), nan=0.0)
    if hd.size == 0:
        return math.nan, -1, "empty record"
    above = hd >= eps
    if not above[-1]:
        return math.nan, -1, "no deposit at the end of the record"
    below = np.flatnonzero(~above)
    if below.size == 0:
        return math.nan, -1, "deposited from the first record"
    i = int(below[-1]) + 1
    while True:
        gap_end = i - 1
        earlier_above = np.flatnonzero(above[:gap_end])
        if earlier_above.size == 0:
            break
        gap_start = int(earlier_above[-1]) + 1
        if t_s[i] - t_s[gap_start - 1] > max_gap:  # time between the above-eps samples around the gap
            break
        earlier_below = np.flatnonzero(~above[:gap_start])
        if earlier_below.size == 0:
            return math.nan, -1, "deposited from the first record"
        i = int(earlier_below[-1]) + 1
    h0, h1 = hd[i - 1], hd[i]
    frac = (eps - h0) / (h1 - h0) if h1 > h0 else 1.0
    return float(t_s[i - 1] + frac * (t_s[i] - t_s[i - 1])), i, "ok"


def growth_fit(t_s, h_D_norm, i_onset: int, end_fraction: float, min_points: int):
    """Fit h_D/H0 over the growth phase: ((S_D)_s, (t_s)_C,fit, R², n)."""
    t_s = np.asarray(t_s, dtype=float)
    hd = np.nan_to_num(np.asarray(h_D_norm, dtype=float), nan=0.0)
    if i_onset < 0:
        return math.nan, math.nan, math.nan, 0
    final = hd[-1]
    reach = np.flatnonzero(hd[i_onset:] >= end_fraction * final)
    j = hd.size - 1 if reach.size == 0 else i_onset + int(reach[0])
    sl = slice(i_onset, j + 1)
    keep = hd[sl] > 0  # samples inside a bridged gap (no deposit) stay out of the fit
    slope, intercept, r2, n = linear_fit(t_s[sl][keep], hd[sl][keep])
    if n < min_points or not slope > 0:
        return math.nan, math.nan, math.nan, n
    t_fit = -intercept / slope
    # The Fig-9 intercept is a reading of the onset: it must fall inside the record, before the end
    # of the fitted growth phase. A nearly flat fit extrapolates to absurd times (seen: t_s = -429).
    if not (t_s[0] <= t_fit <= t_s[j]):
        t_fit = math.nan
    return slope, t_fit, r2, n


def value_at(t_s, series, t: float) -> float:
    """``series`` linearly interpolated at ``t`` over its finite samples (NaN outside them)."""
    t_s = np.asarray(t_s, dtype=float)
    series = np.asarray(series, dtype=float)
    ok = np.isfinite(series) & np.isfinite(t_s)
    if not math.isfinite(t) or ok.sum() == 0:
        return math.nan
    ts, ys = t_s[ok], series[ok]
    if t < ts[0] or t > ts[-1]:
        return math.nan
    return float(np.interp(t, ts, ys))


REQUIRED = ("deposit_depth", "momentum")
REQUIRED_ATTRS = ("theta_deg", "L0", "H0", "dx", "x_inf")


def _attr(ds: xr.Dataset, name: str) -> float:
    if name not in ds.attrs:
        raise ConfigError(f"sections.attrs.{name}: required attribute is missing "
                          f"(case {ds.attrs.get('case', '?')})")
    return float(ds.attrs[name])


def critical_table(ds: xr.Dataset, cfg: RegressConfig) -> pd.DataFrame:
    """One row per section: onset, growth-phase rate and fit intercept, critical DA momentum."""
    for name in REQUIRED:
        if name not in ds.variables:
            raise ConfigError(f"sections.{name}: required variable is missing (case {ds.attrs.get('case', '?')})")
    g = {k: _attr(ds, k) for k in REQUIRED_ATTRS}
    theta = math.radians(g["theta_deg"])
    t_c = cases.characteristic_time(g["H0"], theta)
    p0 = cases.momentum_scale(g["H0"], theta)
    t_s = np.asarray(ds["time"].values, dtype=float) / t_c
    hd = np.asarray(ds["deposit_depth"].transpose("section", "time").values, dtype=float)
    mom = np.asarray(ds["momentum"].transpose("section", "time").values, dtype=float) / p0
    eps = cfg.onset_depth_factor * g["dx"]
    complete = bool(int(ds.attrs.get("run_complete", 1)))
    rows = []
    for k in range(hd.shape[0]):
        t_crit, i0, status = onset_time(t_s, hd[k], eps, cfg.onset_max_gap)
        rate, t_fit, r2, n = growth_fit(t_s, hd[k] / g["H0"], i0, cfg.growth_end_fraction, cfg.min_fit_points)
        m_crit = value_at(t_s, mom[k], t_crit)
        rows.append({
            "case": str(ds.attrs.get("case", "run")), "theta_deg": g["theta_deg"],
            "a": round(g["H0"] / g["L0"], 6), "L0": g["L0"], "H0": g["H0"], "dx": g["dx"],
            "x_inf": g["x_inf"], "section": k, "x": float(ds["x"].values[k]),
            "x_norm": round(float(ds["x_norm"].values[k]), 10),
            "t_s_critical": t_crit, "t_s_critical_fit": t_fit, "deposition_rate": rate, "r2": r2,
            "n_fit": n, "momentum_critical_norm": m_crit, "momentum_critical": m_crit * p0,
            "t_c": t_c, "p0": p0, "status": status, "run_complete": complete,
        })
    return pd.DataFrame(rows)
