"""``results/caption_numbers.json``: our number for each report caption (workflow/report/*.rst), read from the outputs."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from .da_vs_reference import max_errors
from .markdown import fmt, open_lazily, pct_mean, read_csv
from .studies import _study_rows_isph
from ..isph.analysis import bed_label, failure_plane_angle, final_runout


def _wm_numbers(folder: Path) -> str:
    parts = []
    for f in sorted(folder.glob("*.nc")):
        with open_lazily(f) as ds:
            if "rms_deviation" not in ds:
                continue
            r = ds["rms_deviation"]
            txt = ", ".join(f"{float(np.nanmax(r.sel(width_factor=w).values)):.3f} ({w:g} dx)"
                            for w in r["width_factor"].values if w != ds.attrs.get("wm_reference", 2.0)
                            and np.isfinite(r.sel(width_factor=w).values).any())
            parts.append(f"{ds.attrs.get('case', f.stem)}: max RMS {txt}")
    return "; ".join(parts)


def _late_depth(path: Path, t_s_from: float) -> str:
    with open_lazily(path) as ds:
        ts = ds["t_s"].values
        sel = ts > t_s_from
        if not sel.any():
            return f"{ds.attrs.get('case', path.stem)}: no output after t_s = {t_s_from:g}"
        h = ds["total_depth"].values[:, sel] / float(ds.attrs["H0"])
        last = h[:, -1]
        return (f"{ds.attrs.get('case', path.stem)} at t_s = {ts[sel][-1]:.1f}: h_T/H0 from "
                f"{np.nanmin(last):.2f} to {np.nanmax(last):.2f} along the slope")


def caption_numbers(results, convergence_dx=None) -> dict:
    """Short 'our number' sentences for the report captions (workflow/report/*.rst), read from the
    outputs under ``results``; a missing output gives "not computed yet (...)". Written by the
    summary rule to ``results/caption_numbers.json``, which the workflow reads into
    ``config["_caption_numbers"]`` when it is parsed, so ``snakemake --report`` quotes the files it
    reports on. No '|' in the text: the captions are reStructuredText."""
    root = Path(results)
    nums: dict[str, str] = {}

    def missing(what):
        return f"not computed yet ({what} missing)"

    def guard(key, fn, what):
        try:
            nums[key] = fn()
        except (OSError, KeyError, ValueError, IndexError) as exc:  # a caption never blocks the report
            nums[key] = f"{missing(what)}: {exc}"

    t3 = read_csv(root / "regression" / "table3_comparison.csv")
    if t3 is not None and len(t3):
        empty = pd.Series(dtype=float)
        nums["table3"] = (f"mean absolute (t_s)_C difference from Table 3: {pct_mean(t3.get('rel_diff_pct', empty))} "
                          f"(onset), {pct_mean(t3.get('rel_diff_fit_pct', empty))} (fit intercept) "
                          f"over {len(t3)} (case, [x]) pairs")
        row = t3[(t3["case"] == "T22-A70") & np.isclose(t3["x_norm"], 0.2)] if "x_norm" in t3 else t3.iloc[:0]
        nums["fig10"] = (f"T22-A70 at [x] = 0.2: (t_s)_C = {fmt(row['t_s_critical'].iloc[0], '.2f')} "
                         f"(paper {fmt(row['t_s_critical_paper'].iloc[0], '.2f')})" if len(row)
                         else "T22-A70 at [x] = 0.2 not in the Table 3 comparison")
    else:
        nums["table3"] = nums["fig10"] = missing("regression/table3_comparison.csv")
    t5 = read_csv(root / "regression" / "table5_comparison.csv")
    if t5 is not None and len(t5):
        nums["table5"] = "; ".join(f"a = {r.a:g}: A = {fmt(r.A, '.4f')} (paper {fmt(r.A_paper, '.4f')}), "
                                   f"B = {fmt(r.B, '.4f')} (paper {fmt(r.B_paper, '.4f')})"
                                   for r in t5.sort_values("a").itertuples())
    else:
        nums["table5"] = missing("regression/table5_comparison.csv")
    cmp = read_csv(root / "compare" / "comparison.csv")
    if cmp is not None and len(cmp):
        mx = max_errors(cmp)
        nums["fig16"] = "; ".join(f"{r.variant}, {r.quantity.replace('_', ' ')}: largest absolute error "
                                  f"{100 * r.max_abs_rel_error:.0f} % at {r.case} (paper {100 * r.paper_max_error:.0f} %)"
                                  for r in mx.itertuples()) if not mx.empty else "no comparable case"
        ref = cmp.drop_duplicates("case").sort_values("a")
        nums["fig15"] = "; ".join(f"{r.case}: 2D ΔL∞/L0 = {fmt(r.reference_final_runout_norm, '.2f')}, "
                                  f"t_F = {fmt(r.reference_flow_time, '.2f')} s" for r in ref.itertuples())
        if "reference_flow_time_norm" in ref:
            nums["fig7"] = "flow times of the 22° 2D runs t_F/t_c = " + ", ".join(
                f"{fmt(r.reference_flow_time_norm, '.1f')} (a = {r.a:g})" for r in ref.itertuples())
        dep = cmp[cmp["variant"] == "deposition"].sort_values("a")
        nums["fig17"] = "DA with deposition ΔL∞/L0 = " + ", ".join(
            f"{fmt(r.final_runout_norm, '.2f')} ({r.case})" for r in dep.itertuples())
    else:
        nums["fig16"] = nums["fig15"] = nums["fig17"] = missing("compare/comparison.csv")
    nums.setdefault("fig7", missing("compare/comparison.csv"))
    run = root / "isph" / "T22-A70.nc"
    if run.is_file():
        def fig5():
            with open_lazily(run) as ds:
                fp = failure_plane_angle(ds, t_norm=1.0)
                rest = float(ds["time_to_rest"].values)
                tc = float(ds.attrs["t_c"])
            return (f"failure plane {fp['angle_horizontal_deg']:.1f}° from the horizontal "
                    f"({fp['angle_deg']:.1f}° from the bed; particles moving at t = {fp['time']:.2f} s, on their "
                    f"initial positions); time to rest {rest:.2f} s (t_s = {rest / tc:.1f})")
        guard("fig5", fig5, "isph/T22-A70.nc")
    else:
        nums["fig5"] = missing("isph/T22-A70.nc")
    fig6_runs = sorted((root / "isph").glob("fig6-*.nc"))  # the Fig 6 column's runs (workflow config fig6.runs)
    if fig6_runs:
        def fig6():
            parts = []
            for f in fig6_runs:
                with open_lazily(f) as ds:
                    out, bed, dx = final_runout(ds), bed_label(ds), float(ds.attrs["dx"])
                rest = (f"at rest at t = {out['time_to_rest']:.2f} s" if np.isfinite(out["time_to_rest"])
                        else f"not at rest at t = {out['t_end']:.2f} s")
                parts.append(f"{bed}: final runout (x_f − L0)/L0 = {out['runout_norm']:.2f} (x_f = {out['front']:.3f} m, "
                             f"{out['measure']}), {rest}, dx = {1e3 * dx:g} mm")
            return "; ".join(parts)
        guard("fig6", fig6, "isph/fig6-*.nc")
    else:
        nums["fig6"] = missing("isph/fig6-*.nc")
    secs = [(root / "sections" / f"{c}.nc", t) for c, t in (("T16-A50", 6.0), ("T22-A70", 9.0))]
    if all(p.is_file() for p, _ in secs):
        guard("fig8", lambda: "; ".join(_late_depth(p, t) for p, t in secs), "sections")
    else:
        nums["fig8"] = missing("sections/T16-A50.nc, T22-A70.nc")
    if (root / "wm").is_dir():
        guard("figA2", lambda: _wm_numbers(root / "wm") or "no W_M file", "wm")
    else:
        nums["figA2"] = missing("wm/")
    nums["figA1"] = nums["figA2"]
    mxm = read_csv(root / "compare" / "reading_matrix_maxima.csv")
    if mxm is not None and len(mxm):
        sel = mxm[mxm["measure"] == "2d"] if "measure" in mxm else mxm
        nums["readingmatrix"] = "; ".join(
            f"{getattr(r, 'reading_label', r.reading)} vs {r.reference}: largest runout error {100 * r.max_runout_error_nodep:.0f} % without, "
            f"{100 * r.max_runout_error_dep:.0f} % with deposition; flow time {100 * r.max_flow_time_error_nodep:.0f} % "
            f"/ {100 * r.max_flow_time_error_dep:.0f} %" for r in sel.itertuples())
    else:
        nums["readingmatrix"] = missing("compare/reading_matrix_maxima.csv")
    dgs = read_csv(root / "regression" / "diagnosis_summary.csv")
    if dgs is not None and len(dgs):
        nums["diagnosis"] = "; ".join(f"{r['variant']}: median R² {fmt(r['r2_median'], '.2f')}, "
                                      f"{int(r['cases_r2_ge_0.8'])}/{int(r['cases'])} cases with R² ≥ 0.8"
                                      for _, r in dgs.iterrows())
    else:
        nums["diagnosis"] = missing("regression/diagnosis_summary.csv")
    sens = read_csv(root / "sensitivity" / "sensitivity.csv")
    if sens is not None and len(sens) and "final_runout_norm" in sens:
        parts = []
        for p, g in sens.groupby("parameter", sort=False):
            r = g["final_runout_norm"]
            parts.append(f"{p} {g['value'].min():g}–{g['value'].max():g}: DA ΔL/L0 {r.min():.2f}–{r.max():.2f}")
        nums["sensitivity"] = "; ".join(parts)
    else:
        nums["sensitivity"] = "not computed yet (sensitivity/sensitivity.csv missing: run `snakemake -j2 sensitivity`)"
    conv = root / "convergence" / "isph"
    if conv.is_dir() and any(conv.glob("*.nc")):
        def convergence():
            iso = _study_rows_isph(conv, convergence_dx).sort_values("dx_mm", ascending=False)
            return "2D ΔL∞/L0 of the 1 % volume front = " + ", ".join(
                f"{fmt(r.get('runout_front_v99', r.get('final_runout_norm')), '.2f')} (dx = {r['dx_mm']:g} mm)"
                for _, r in iso.iterrows())
        guard("convergence", convergence, "convergence/isph")
    else:
        nums["convergence"] = "not computed yet (convergence/isph missing: run `snakemake -j2 convergence`)"
    return nums
