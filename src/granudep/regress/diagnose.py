"""Why is R² of eq 36 low, and why do A, B jump across a? One refit per choice.

For every case, eq 36 ((hu)_C/p0 = A[x] + B) is refitted with one choice of the method changed at a
time, from the same monitoring sections:

* ``baseline``: the regression as run (rule onset, hu = h·u, [x] ∈ [0, 1]);
* ``no gate``: without the gate section [x] = 0 (at the gate the column's initially static block
  is counted as deposit; its onset is the end of the collapse, not a deposition front);
* ``interior``: [x] ∈ [0.1, 0.9] (neither the gate nor the last section near the thin front);
* ``fit onset``: (hu)_C read at the Fig-9 fit intercept (t_s)_C,fit instead of the rule onset;
* ``onset 1 dx``: rule onset at h_D = 1 Δx instead of 0.5 Δx (critical-point detection);
* ``flowing u``: u = mean v_x of the *flowing* particles only (|v| ≥ 0.1 m/s, the velocity threshold)
  instead of eq 15's mean over all particles;
* ``h_T u``: the depth-integrated momentum h_T·u (no F/D split);
* ``x_inf v99``: [x] renormalised with x∞ = the 2D run's 1 % volume front instead of its 2 d front
  (section placement: the thin tail sets x∞);
* ``W_M = k dx``: hu/p0 from the W_M sensitivity file at the same onset (k = 1, 3, 4).
* ``paper t_C`` (the cases of Table 3): (hu)_C read at the paper's critical times on the sections
  nearest [x] = 0.2, 0.4, 0.6, 0.8; the note gives the baseline's A, B on the same four sections.
  Not a reading of eq 36 but an attribution test: how much of the difference in A, B comes from
  *when* the momentum is read (our critical times against Table 3's) rather than from the momentum.

Beside A, B, R²: the mean and range of the fitted (hu)_C/p0 (a small range next to the RMS residual
means a line in [x] has little to explain) and ``x_norm_zero`` = −B/A, where the line crosses zero.

Each row gives A, B, R² of the line, R² of a quadratic in [x] (how much a curve would explain), the
RMS residual of the line and the number of sections. The residuals of every case's baseline are
returned for the Fig 12 residual plot.
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
import xarray as xr

from .. import cases
from ..progress import LOG
from .config import RegressConfig
from .critical import growth_fit, linear_fit, onset_time, value_at
from ..io import open_dataset

DIAGNOSIS_COLUMNS = ["case", "theta_deg", "a", "variant", "n_sections", "A", "B", "r2", "r2_quadratic",
                     "rms_residual", "y_mean", "y_range", "x_norm_zero", "x_norm_used", "note"]


def _quad_r2(x, y) -> float:
    x, y = np.asarray(x, float), np.asarray(y, float)
    if x.size < 4:
        return math.nan
    c = np.polyfit(x, y, 2)
    ss_tot = float(np.sum((y - y.mean()) ** 2))
    return 1.0 - float(np.sum((y - np.polyval(c, x)) ** 2)) / ss_tot if ss_tot > 0 else math.nan


def _fit_row(case, theta, a, variant, x, y, note="", min_sections=3) -> tuple[dict, np.ndarray]:
    x, y = np.asarray(x, float), np.asarray(y, float)
    ok = np.isfinite(x) & np.isfinite(y)
    x, y = x[ok], y[ok]
    row = {"case": case, "theta_deg": theta, "a": a, "variant": variant, "n_sections": int(x.size),
           "A": math.nan, "B": math.nan, "r2": math.nan, "r2_quadratic": math.nan, "rms_residual": math.nan,
           "y_mean": float(np.mean(y)) if y.size else math.nan,
           "y_range": float(np.ptp(y)) if y.size else math.nan, "x_norm_zero": math.nan,
           "x_norm_used": ";".join(f"{v:.2g}" for v in x), "note": note}
    resid = np.full(x.size, np.nan)
    if x.size >= min_sections:
        A, B, r2, _ = linear_fit(x, y)
        resid = y - (A * x + B)
        row.update(A=A, B=B, r2=r2, r2_quadratic=_quad_r2(x, y), rms_residual=float(np.sqrt(np.mean(resid ** 2))),
                   # where the line's (hu)_C crosses zero (eq 34 deposits nothing beyond it)
                   x_norm_zero=float(-B / A) if A != 0 else math.nan)
    return row, np.column_stack([x, y, resid]) if x.size else np.zeros((0, 3))


def _paper_critical_times(case: str) -> dict[float, float] | None:
    """Table 3's (t_s)_C / t_c by [x] for a case the paper lists, else None."""
    t3 = cases.table3()
    row = t3[t3["case_id"] == case]
    if row.empty:
        return None
    return {x: float(row[f"xM_{x}"].iloc[0]) for x in (0.2, 0.4, 0.6, 0.8)}


def diagnose_case(sections: xr.Dataset, isph: xr.Dataset | None = None, wm: xr.Dataset | None = None,
                  cfg: RegressConfig | None = None) -> tuple[list[dict], pd.DataFrame]:
    """Diagnosis rows for one case and its baseline residuals (columns case, a, theta_deg, x_norm,
    momentum_critical_norm, residual)."""
    cfg = cfg or RegressConfig()
    at = sections.attrs
    case = str(at.get("case", "run"))
    L0, H0, th, dx, x_inf = (float(at[k]) for k in ("L0", "H0", "theta_deg", "dx", "x_inf"))
    a = round(H0 / L0, 6)
    theta = math.radians(th)
    t_c, p0 = cases.characteristic_time(H0, theta), cases.momentum_scale(H0, theta)
    t_s = np.asarray(sections["time"].values, float) / t_c
    hd = np.asarray(sections["deposit_depth"].transpose("section", "time").values, float)
    h = np.asarray(sections["flow_depth"].transpose("section", "time").values, float)
    mom = np.asarray(sections["momentum"].transpose("section", "time").values, float) / p0
    xs = np.asarray(sections["x"].values, float)
    xn = np.asarray(sections["x_norm"].values, float)

    def series(name):
        return np.asarray(sections[name].transpose("section", "time").values, float) if name in sections else None
    uf, mi = series("flowing_velocity"), series("momentum_integrated")
    ns = hd.shape[0]
    onset = [onset_time(t_s, hd[k], cfg.onset_depth_factor * dx, cfg.onset_max_gap) for k in range(ns)]
    onset1 = [onset_time(t_s, hd[k], 1.0 * dx, cfg.onset_max_gap) for k in range(ns)]
    t_rule = np.array([o[0] for o in onset])
    t_fit = np.array([growth_fit(t_s, hd[k] / H0, onset[k][1], cfg.growth_end_fraction, cfg.min_fit_points)[1]
                      for k in range(ns)])
    t_one = np.array([o[0] for o in onset1])

    def at_times(m, times):
        return np.array([value_at(t_s, m[k], times[k]) for k in range(ns)])
    base = at_times(mom, t_rule)
    in01 = (xn >= cfg.fit_x_min - 1e-9) & (xn <= cfg.fit_x_max + 1e-9)
    rows = []
    r, res = _fit_row(case, th, a, "baseline", xn[in01], base[in01])
    rows.append(r)
    resid = pd.DataFrame({"case": case, "a": a, "theta_deg": th, "x_norm": res[:, 0],
                          "momentum_critical_norm": res[:, 1], "residual": res[:, 2]})
    gate = in01 & (xn > 1e-6)
    g0 = base[np.isclose(xn, 0.0)]
    rows.append(_fit_row(case, th, a, "no gate", xn[gate], base[gate],
                         note=f"gate (hu)_C/p0 = {g0[0]:.4f}" if g0.size and math.isfinite(g0[0]) else "")[0])
    inner = (xn >= 0.1 - 1e-9) & (xn <= 0.9 + 1e-9)
    rows.append(_fit_row(case, th, a, "interior [0.1, 0.9]", xn[inner], base[inner])[0])
    rows.append(_fit_row(case, th, a, "fit onset", xn[in01], at_times(mom, t_fit)[in01],
                         note="(hu)_C at the Fig-9 intercept")[0])
    rows.append(_fit_row(case, th, a, "onset 1 dx", xn[in01], at_times(mom, t_one)[in01])[0])
    if uf is not None:
        rows.append(_fit_row(case, th, a, "flowing u", xn[in01], at_times(h * uf / p0, t_rule)[in01],
                             note="u over flowing particles (|v| >= 0.1 m/s)")[0])
    if mi is not None:
        rows.append(_fit_row(case, th, a, "h_T u", xn[in01], at_times(mi / p0, t_rule)[in01])[0])
    if isph is not None and "final_front_v99" in isph:
        xv = float(isph["final_front_v99"].values)
        xn2 = (xs - L0) / (xv - L0)
        sel = (xn2 >= -1e-9) & (xn2 <= 1 + 1e-9)
        rows.append(_fit_row(case, th, a, "x_inf v99", xn2[sel], base[sel],
                             note=f"x_inf {x_inf:.3f} -> {xv:.3f} m")[0])
    paper = _paper_critical_times(case)
    if paper is not None:
        # the attribution test: (hu)_C read at the paper's Table 3 critical times, at the sections
        # nearest [x] = 0.2 ... 0.8; the baseline on the same four sections beside it
        k4 = [int(np.argmin(np.abs(xn - x))) for x in paper]
        if all(abs(xn[k] - x) < 0.05 for k, x in zip(k4, paper)):
            y = np.array([value_at(t_s, mom[k], t) for k, t in zip(k4, paper.values())])
            A4, B4 = linear_fit(xn[k4], base[k4])[:2]
            rows.append(_fit_row(case, th, a, "paper t_C", xn[k4], y,
                                 note=f"(hu)_C at Table 3's times; ours on these sections: A {A4:.4f}, B {B4:.4f}")[0])
    if wm is not None and "momentum_norm" in wm:
        for w in wm["width_factor"].values:
            if math.isclose(float(w), float(at.get("width_factor", 2.0))):
                continue
            m = np.asarray(wm["momentum_norm"].sel(width_factor=w).transpose("section", "time").values, float)
            if m.shape != mom.shape:
                LOG.warning("diagnose %s: W_M file has another section/time layout; skipped", case)
                break
            rows.append(_fit_row(case, th, a, f"W_M = {float(w):g} dx", xn[in01], at_times(m, t_rule)[in01])[0])
    return rows, resid


def diagnose(sections, isph=(), wm=(), cfg: RegressConfig | None = None) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Diagnosis table (:data:`DIAGNOSIS_COLUMNS`) and baseline residuals over every case.
    ``isph`` and ``wm`` files are matched to the sections by their ``case`` attribute."""

    def by_case(paths):
        out = {}
        for p in paths:
            ds = open_dataset(p)
            out[str(ds.attrs.get("case", ""))] = ds
        return out
    iso, wms = by_case(isph), by_case(wm)
    rows, resid = [], []
    for p in sections:
        ds = open_dataset(p)
        c = str(ds.attrs.get("case", ""))
        r, res = diagnose_case(ds, iso.get(c), wms.get(c), cfg)
        rows += r
        resid.append(res)
    table = pd.DataFrame(rows, columns=DIAGNOSIS_COLUMNS).sort_values(["theta_deg", "a", "case"], kind="stable")
    return table.reset_index(drop=True), (pd.concat(resid, ignore_index=True) if resid else pd.DataFrame())


def variant_summary(table: pd.DataFrame) -> pd.DataFrame:
    """Per variant: median and minimum R², cases with R² ≥ 0.8, and the spread of A at θ = 22°."""
    rows = []
    for v, g in table.groupby("variant", sort=False):
        r2 = g["r2"].astype(float)
        g22 = g[np.isclose(g["theta_deg"], 22.0)].sort_values("a")
        jump = np.diff(g22["A"].astype(float).to_numpy())
        rows.append({"variant": v, "cases": int(np.isfinite(r2).sum()), "r2_median": float(r2.median()),
                     "r2_min": float(r2.min()), "cases_r2_ge_0.8": int((r2 >= 0.8).sum()),
                     "r2_quadratic_median": float(g["r2_quadratic"].astype(float).median()),
                     "A_22_range": f"{g22['A'].min():.4f} .. {g22['A'].max():.4f}" if len(g22) else "",
                     "A_22_largest_step": float(np.nanmax(np.abs(jump))) if jump.size and np.isfinite(jump).any()
                     else math.nan})
    return pd.DataFrame(rows)
