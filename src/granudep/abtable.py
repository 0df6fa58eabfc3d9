"""The A/B table of eq 36 over (a, θ) and its interpolation: what a DA run reads when its A, B come
from a coefficients.csv of ``granudep regress`` (``deposition.ab_source: computed``).

It sits below both the regression (which writes the table) and the DA model (which reads it), so
that the model does not import the regression stage.
"""
from __future__ import annotations

import math
import numbers
from pathlib import Path

import numpy as np
import pandas as pd

from .config import ConfigError


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
