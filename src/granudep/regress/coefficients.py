"""Eq 36: (hu)_C/p0 = A [x] + B per case and the A/B tables over (a, θ) (Fig 13); their interpolation
is ``granudep.abtable``.

Which sections enter a case's fit: every section with a detected onset and a finite critical
momentum whose [x] lies in [fit_x_min, fit_x_max] (default [0, 1]: [x] = 0 and 1 are used when they
have an onset). Fewer than ``min_sections`` such sections → NaN A, B with a warning.
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
import xarray as xr

from .. import cases
from ..io import var
from ..progress import LOG
from .config import RegressConfig
from .critical import linear_fit

COLUMNS = ["case", "theta_deg", "a", "L0", "H0", "A", "B", "r2", "n_sections", "x_norm_used", "p0", "note"]


def coefficient_table(critical: pd.DataFrame, cfg: RegressConfig) -> pd.DataFrame:
    """One row per case: least-squares A (slope) and B (intercept) of (hu)_C/p0 vs [x], with R²."""
    rows = []
    for case, grp in critical.groupby("case", sort=False):
        first = grp.iloc[0]
        use = grp[np.isfinite(grp.t_s_critical) & np.isfinite(grp.momentum_critical_norm)
                  & (grp.x_norm >= cfg.fit_x_min - 1e-9) & (grp.x_norm <= cfg.fit_x_max + 1e-9)]
        note = ""
        if len(use) < cfg.min_sections:
            A = B = r2 = math.nan
            note = (f"only {len(use)} section(s) with a detected onset in [x] in "
                    f"[{cfg.fit_x_min}, {cfg.fit_x_max}] (need {cfg.min_sections}): A, B not fitted")
            LOG.warning("regress %s: %s", case, note)
        else:
            A, B, r2, _ = linear_fit(use.x_norm, use.momentum_critical_norm)
        if "run_complete" in grp and not bool(grp.run_complete.iloc[0]):
            extra = ("the 2D run did not reach rest: x_inf is not its final runout and later onsets are "
                     "missing; A, B are not meaningful")
            note = f"{note}; {extra}" if note else extra
            LOG.warning("regress %s: %s", case, extra)
        theta = math.radians(float(first.theta_deg))
        rows.append({"case": case, "theta_deg": float(first.theta_deg), "a": float(first.a),
                     "L0": float(first.L0), "H0": float(first.H0), "A": A, "B": B, "r2": r2,
                     "n_sections": int(len(use)),
                     "x_norm_used": ";".join(f"{v:g}" for v in use.x_norm),
                     "p0": cases.momentum_scale(float(first.H0), theta), "note": note})
    return pd.DataFrame(rows, columns=COLUMNS)


def coefficients_dataset(coeffs: pd.DataFrame) -> xr.Dataset:
    """The coefficient table as NetCDF: per case (dim ``case``) and on the (θ, a) grid (Fig 13)."""
    n = len(coeffs)
    ds = xr.Dataset(coords={"case": var(np.asarray(coeffs.case, dtype=str), ("case",), "1", "2D run (case name)")})
    for name, units, long_name in (
            ("theta_deg", "degree", "slope angle theta"), ("aspect_ratio", "1", "initial aspect ratio a = H0/L0"),
            ("L0", "m", "initial column length L0"), ("H0", "m", "initial column height H0"),
            ("A", "1", "slope A of (hu)_C/p0 = A [x] + B (eq 36)"),
            ("B", "1", "intercept B of (hu)_C/p0 = A [x] + B (eq 36)"),
            ("r2", "1", "coefficient of determination R^2 of the eq-36 fit"),
            ("n_sections", "1", "number of sections in the eq-36 fit"),
            ("p0", "m2 s-1", "momentum scale p0 = H0 sqrt(g H0 cos theta)")):
        dtype = np.int32 if name == "n_sections" else float
        col = "a" if name == "aspect_ratio" else name  # 'a' and 'A' may not differ only by case (CF 2.3)
        ds[name] = var(np.asarray(coeffs[col], dtype=dtype).reshape(n), ("case",), units, long_name)
    grid = coeffs[np.isfinite(coeffs.A) & np.isfinite(coeffs.B)].groupby(["theta_deg", "a"])[["A", "B", "r2"]].mean()
    thetas = np.unique(coeffs.theta_deg.astype(float))
    aspects = np.unique(coeffs.a.astype(float))
    ds = ds.assign_coords(
        theta_grid=var(thetas, ("theta_grid",), "degree", "slope angle of the coefficient grid"),
        aspect_ratio_grid=var(aspects, ("aspect_ratio_grid",), "1", "initial aspect ratio of the coefficient grid"))
    for name, long_name in (("A", "A on the (theta, a) grid (NaN: no case)"),
                            ("B", "B on the (theta, a) grid (NaN: no case)"),
                            ("r2", "R^2 on the (theta, a) grid (NaN: no case)")):
        arr = np.full((thetas.size, aspects.size), np.nan)
        for (th, a), row in grid.iterrows():
            arr[np.searchsorted(thetas, th), np.searchsorted(aspects, a)] = row[name]
        ds[f"{name}_grid"] = var(arr, ("theta_grid", "aspect_ratio_grid"), "1", long_name)
    return ds
