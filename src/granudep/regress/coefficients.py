"""Eq 36: (hu)_C/p0 = A [x] + B per case, the A/B tables over (a, θ) (Fig 13) and their interpolation.

Which sections enter a case's fit: every section with a detected onset and a finite critical
momentum whose [x] lies in [fit_x_min, fit_x_max] (default [0, 1]: [x] = 0 and 1 are used when they
have an onset). Fewer than ``min_sections`` such sections → NaN A, B with a warning.
"""
from __future__ import annotations

import math
import numbers
from pathlib import Path

import numpy as np
import pandas as pd
import xarray as xr

from .. import cases
from ..config import ConfigError
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


def _load_table(table) -> pd.DataFrame:
    if isinstance(table, pd.DataFrame):
        df = table
    else:
        path = Path(table)
        if not path.is_file():
            raise ConfigError(f"coefficients: file not found: {path}")
        df = pd.read_csv(path)
    missing = [c for c in ("a", "theta_deg", "A", "B") if c not in df.columns]
    if missing:
        raise ConfigError(f"coefficients: table lacks column(s) {missing} (need a, theta_deg, A, B)")
    df = df[np.isfinite(df.A.astype(float)) & np.isfinite(df.B.astype(float))]
    if df.empty:
        raise ConfigError("coefficients: no case with finite A and B in the table")
    return df.groupby(["theta_deg", "a"], as_index=False)[["A", "B"]].mean()


def _lin(x0, x1, y0, y1, x):
    return y0 if x1 == x0 else y0 + (y1 - y0) * (x - x0) / (x1 - x0)


def _along_a(rows: pd.DataFrame, a: float, extrapolate: bool):
    """Linear in a within one θ row (nodes sorted by a); the row's a-range bounds it."""
    av = rows.a.to_numpy(float)
    A = rows.A.to_numpy(float)
    B = rows.B.to_numpy(float)
    tol = 1e-9 * max(1.0, abs(a))  # a = H0/L0 in floating point (0.14/0.2 = 0.7000000000000001)
    if av[0] - tol <= a <= av[-1] + tol:
        a = min(max(a, av[0]), av[-1])
        return float(np.interp(a, av, A)), float(np.interp(a, av, B))
    if not extrapolate:
        return None
    if av.size == 1:
        return float(A[0]), float(B[0])
    i0, i1 = (0, 1) if a < av[0] else (av.size - 2, av.size - 1)
    return _lin(av[i0], av[i1], A[i0], A[i1], a), _lin(av[i0], av[i1], B[i0], B[i1], a)


def interpolate_ab(table, a: float, theta_deg: float, extrapolate: bool = False) -> tuple[float, float]:
    """A and B at (a, θ) from coefficients.csv (DataFrame or path).

    Linear in a within each θ of the table and linear in θ between the two bracketing θ values
    (the grid is irregular: each θ has its own set of a). Exact on table nodes. Outside the table
    (θ outside [θ_min, θ_max], or a outside the a-range of the bracketing θ rows) a ConfigError names
    the key and the allowed range, unless ``extrapolate=True`` (linear from the two nearest nodes;
    constant where a row has a single node).
    """
    if not (isinstance(a, numbers.Real) and math.isfinite(a) and a > 0):
        raise ConfigError(f"a: must be a finite number > 0 (got {a!r})")
    if not (isinstance(theta_deg, numbers.Real) and math.isfinite(theta_deg)):
        raise ConfigError(f"theta_deg: must be a finite number (got {theta_deg!r})")
    grid = _load_table(table).sort_values(["theta_deg", "a"])
    thetas = np.unique(grid.theta_deg.to_numpy(float))
    rows = {t: grid[grid.theta_deg == t] for t in thetas}

    def at(t):
        return _along_a(rows[t], a, extrapolate)

    exact = thetas[np.isclose(thetas, theta_deg, rtol=0, atol=1e-9)]
    if exact.size:
        bracket = [exact[0]]
    elif thetas[0] < theta_deg < thetas[-1]:
        i = int(np.searchsorted(thetas, theta_deg))
        bracket = [thetas[i - 1], thetas[i]]
    elif not extrapolate:
        raise ConfigError(f"theta_deg: {theta_deg} is outside the coefficient table's range "
                          f"[{thetas[0]:g}, {thetas[-1]:g}] degrees (pass extrapolate=True to extrapolate)")
    elif thetas.size == 1:
        bracket = [thetas[0]]
    else:
        bracket = [thetas[0], thetas[1]] if theta_deg < thetas[0] else [thetas[-2], thetas[-1]]
    values = [at(t) for t in bracket]
    if any(v is None for v in values):
        lo = max(float(rows[t].a.min()) for t in bracket)
        hi = min(float(rows[t].a.max()) for t in bracket)
        where = " and ".join(f"{t:g}" for t in bracket)
        if lo > hi:
            raise ConfigError(f"a: the coefficient table's theta_deg = {where} rows share no a-range "
                              f"(got a = {a}; pass extrapolate=True to extrapolate)")
        raise ConfigError(f"a: {a} is outside the coefficient table's range [{lo:g}, {hi:g}] at theta_deg = "
                          f"{where} (pass extrapolate=True to extrapolate)")
    if len(bracket) == 1:
        return values[0]
    (A0, B0), (A1, B1) = values
    t0, t1 = bracket
    return _lin(t0, t1, A0, A1, theta_deg), _lin(t0, t1, B0, B1, theta_deg)
