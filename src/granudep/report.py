"""``results/summary.md``: the paper-vs-ours tables, verification and benchmarks, read from the outputs.

Every number in the summary comes from a file given on the command line (regression tables,
``granudep compare`` output, ``granudep verify`` outputs, benchmark files); the paper's values
come from those files too (the regression tables carry them) or from the package's copies of the
paper's tables, and the paper's stated Fig 16 maxima from :data:`granudep.da_vs_reference.PAPER_MAX_ERRORS`
(Section 4.3). A missing input gives an explicit "not available" line, never a crash.
"""
from __future__ import annotations

import csv
import math
import os
from pathlib import Path

import numpy as np
import pandas as pd

from ._version import __version__
from .da_vs_reference import PAPER_MAX_ERRORS, improvement, max_errors

FIGURE_SUFFIXES = (".png", ".pdf", ".svg")


def _fmt(v, spec: str = ".3g") -> str:
    if v is None:
        return "–"
    if isinstance(v, (bool, np.bool_)):
        return "yes" if v else "no"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    try:
        f = float(v)
    except (TypeError, ValueError):
        s = str(v)
        return s.replace("|", "\\|").replace("\n", " ") if s and s != "nan" else "–"
    return "–" if not math.isfinite(f) else format(f, spec)


def md_table(df: pd.DataFrame, columns: dict[str, tuple[str, str]]) -> str:
    """Markdown table of ``df``: columns = {column: (header, format spec)}; absent columns skipped."""
    cols = [(c, h, f) for c, (h, f) in columns.items() if c in df.columns]
    lines = ["| " + " | ".join(h for _, h, _ in cols) + " |", "|" + "|".join("---" for _ in cols) + "|"]
    for _, row in df.iterrows():
        lines.append("| " + " | ".join(_fmt(row[c], f) for c, _, f in cols) + " |")
    return "\n".join(lines)


def _missing(what: str, path) -> str:
    return f"_Not available: {what} ({'not given' if path is None else f'{path} not found'})._\n"


def _read_csv(path) -> pd.DataFrame | None:
    if path is None or not Path(path).is_file():
        return None
    return pd.read_csv(path)


def _pct_mean(s: pd.Series) -> str:
    s = pd.to_numeric(s, errors="coerce").abs()
    s = s[np.isfinite(s)]
    return f"{s.mean():.1f} %" if len(s) else "–"


def section_table3(regression) -> str:
    out = ["## Table 3: critical times (t_s)_C, paper vs ours\n"]
    path = Path(regression) / "table3_comparison.csv" if regression is not None else None
    df = _read_csv(path)
    if df is None:
        return "\n".join(out) + _missing("Table 3 comparison", path)
    out.append(f"Source: `{path}`. (t_s)_C = onset of deposition (h_D starts to grow); 'fit' = intercept of the "
               "linear fit of h_D vs t_s (the paper's Fig 9 reading).\n")
    out.append(md_table(df, {"case": ("case", ""), "x_norm": ("[x]", ".1f"),
                             "t_s_critical_paper": ("paper", ".2f"), "t_s_critical": ("ours (onset)", ".2f"),
                             "rel_diff_pct": ("rel. diff. %", "+.1f"), "t_s_critical_fit": ("ours (fit)", ".2f"),
                             "rel_diff_fit_pct": ("rel. diff. (fit) %", "+.1f"), "status": ("status", "")}))
    out.append(f"\nMean |relative difference|: onset {_pct_mean(df.get('rel_diff_pct', pd.Series(dtype=float)))}, "
               f"fit intercept {_pct_mean(df.get('rel_diff_fit_pct', pd.Series(dtype=float)))} "
               f"over {len(df)} (case, [x]) pairs.\n")
    return "\n".join(out)


def section_table5(regression) -> str:
    out = ["## Table 5: A and B of (hu)_C/p0 = A[x] + B at θ = 22°, paper vs ours\n"]
    path = Path(regression) / "table5_comparison.csv" if regression is not None else None
    df = _read_csv(path)
    if df is None:
        return "\n".join(out) + _missing("Table 5 comparison", path)
    out.append(f"Source: `{path}`.\n")
    out.append(md_table(df, {"case": ("case", ""), "run_case": ("2D run", ""), "a": ("a", ".3g"),
                             "A_paper": ("A paper", ".4f"), "A": ("A ours", ".4f"), "A_rel_diff_pct": ("A rel. diff. %", "+.0f"),
                             "B_paper": ("B paper", ".4f"), "B": ("B ours", ".4f"), "B_rel_diff_pct": ("B rel. diff. %", "+.0f"),
                             "r2": ("R²", ".3f")}))
    if {"B_paper_over_p0", "B_rel_diff_if_dimensional_pct"} <= set(df.columns):
        out.append("\nIf the printed A, B were dimensional (m²/s, i.e. (hu)_C = A[x] + B), the normalised values "
                   "would be A/p0, B/p0:\n")
        out.append(md_table(df, {"case": ("case", ""), "p0": ("p0 (m²/s)", ".4f"),
                                 "A_paper_over_p0": ("A paper/p0", ".4f"), "A_rel_diff_if_dimensional_pct": ("A rel. diff. %", "+.0f"),
                                 "B_paper_over_p0": ("B paper/p0", ".4f"), "B_rel_diff_if_dimensional_pct": ("B rel. diff. %", "+.0f")}))
    out.append("")
    return "\n".join(out)


def section_compare(compare) -> str:
    out = ["## Figs 15–16: DA runs vs references (final runout, flow time)\n"]
    df = _read_csv(compare)
    if df is None:
        return "\n".join(out) + _missing("comparison table", compare)
    if "reference" not in df.columns:
        from .da_vs_reference import source_label
        df["reference"] = [source_label(p) for p in df["provenance"]]
    out.append(f"Source: `{compare}`. Relative error = (computed − reference)/reference. Runout ΔL/L0 from the gate.\n")
    show = df.copy()
    for c in ("runout_rel_error", "flow_time_rel_error"):
        show[c] = pd.to_numeric(show[c], errors="coerce") * 100
    out.append(md_table(show, {"case": ("case", ""), "variant": ("DA variant", ""), "reference": ("reference", ""),
                               "final_runout_norm": ("ΔL/L0 DA", ".3f"), "reference_final_runout_norm": ("ΔL/L0 ref.", ".3f"),
                               "runout_rel_error": ("runout error %", "+.1f"), "flow_time": ("t_F DA (s)", ".3f"),
                               "reference_flow_time": ("t_F ref. (s)", ".3f"), "flow_time_rel_error": ("flow-time error %", "+.1f"),
                               "reference_note": ("note on the reference", "")}))
    defs = sorted({str(d) for c in ("da_front_definition", "reference_front_definition") if c in df for d in df[c]
                   if isinstance(d, str) and d})
    if defs:
        out.append("\nFront definitions: " + "; ".join(f"_{d}_" for d in defs) + ".\n")
    imp = improvement(df)
    out.append("\n**Does deposition improve the DA prediction?** (|error| with deposition < without)\n")
    if imp.empty:
        out.append("_Not available: no case has both a reference and a DA run._\n")
    else:
        for c in ("runout_error_nodep", "runout_error_dep", "flow_time_error_nodep", "flow_time_error_dep"):
            imp[c] = imp[c] * 100
        out.append(md_table(imp, {"case": ("case", ""), "reference": ("reference", ""),
                                  "runout_error_nodep": ("runout err. no dep. %", "+.1f"),
                                  "runout_error_dep": ("runout err. dep. %", "+.1f"), "runout_improved": ("runout improved", ""),
                                  "flow_time_error_nodep": ("t_F err. no dep. %", "+.1f"),
                                  "flow_time_error_dep": ("t_F err. dep. %", "+.1f"), "flow_time_improved": ("t_F improved", "")}))
    mx = max_errors(df)
    out.append("\n**Maximum |error|, ours vs the paper's stated maxima** (the paper's are against Farin et al. 2014 "
               "measurements, which are not available to us; ours are against the references above)\n")
    if mx.empty:
        out.append("_Not available._\n")
    else:
        mx = mx.assign(max_abs_rel_error=mx.max_abs_rel_error * 100, paper_max_error=mx.paper_max_error * 100)
        out.append(md_table(mx, {"variant": ("DA variant", ""), "quantity": ("quantity", ""), "reference": ("reference", ""),
                                 "max_abs_rel_error": ("ours max |error| %", ".1f"), "case": ("at case", ""),
                                 "paper_max_error": ("paper max error %", ".0f"), "paper_case_a": ("paper at a", ".3g")}))
    out.append("")
    return "\n".join(out)


def section_reading_matrix(matrix, maxima) -> str:
    """Reading matrix (issue 13): {A, B readings} × {deposition, none} against every reference."""
    out = ["## Reading matrix: which A, B reading, which reference (Figs 15–16)\n"]
    mt, mx = _read_csv(matrix), _read_csv(maxima)
    if mt is None or mx is None:
        return "\n".join(out) + _missing("reading matrix", matrix if mt is None else maxima)
    out.append(f"Source: `{matrix}`, `{maxima}`. Readings: `computed` = our regression (normalised, eq 36), "
               "`paper` = Table 5 read as normalised, `paper-dimensional` = Table 5 read as (hu)_C = A[x] + B in "
               "m²/s. Each deposition run is paired with the same no-deposition run. Front `2d`: attached front "
               "at 2 grain diameters (the paper's kind of front); `v99`: the point beyond which 1 % of the "
               "deposit's volume lies (does not jump when a thin tip detaches); the same rule on the 2D and the "
               "DA depth profile. Relative error = (DA − 2D)/2D.\n")
    show = mt.copy()
    for c in ("runout_error", "runout_error_nodep", "flow_time_error", "flow_time_error_nodep"):
        show[c] = pd.to_numeric(show[c], errors="coerce") * 100
    out.append(md_table(show, {"case": ("case", ""), "reference": ("reference", ""), "reading": ("A, B reading", ""),
                               "measure": ("front", ""), "A": ("A", ".4f"), "B": ("B", ".4f"),
                               "runout_error_nodep": ("runout err. no dep. %", "+.1f"),
                               "runout_error": ("runout err. dep. %", "+.1f"), "runout_improved": ("improved", ""),
                               "flow_time_error_nodep": ("t_F err. no dep. %", "+.1f"),
                               "flow_time_error": ("t_F err. dep. %", "+.1f"), "flow_time_improved": ("improved", "")}))
    out.append("\n**Largest |error| over the cases, per reading** (the paper's: 55 % / 107 % without, 17 % / 69 % "
               "with deposition, against Farin et al. 2014; reduction = the paper's \"up to 38 %\")\n")
    show = mx.copy()
    for c in [c for c in show.columns if c.startswith("max_") and "error" in c] + \
            ["runout_max_reduction", "flow_time_max_reduction"]:
        show[c] = pd.to_numeric(show[c], errors="coerce") * 100
    out.append(md_table(show, {"reference": ("reference", ""), "reading": ("A, B reading", ""), "measure": ("front", ""),
                               "max_runout_error_nodep": ("runout no dep. %", ".1f"),
                               "max_runout_error_dep": ("runout dep. %", ".1f"),
                               "runout_max_reduction": ("runout reduction (points)", "+.1f"),
                               "runout_improved_cases": ("runout improved", ""),
                               "max_flow_time_error_nodep": ("t_F no dep. %", ".1f"),
                               "max_flow_time_error_dep": ("t_F dep. %", ".1f"),
                               "flow_time_max_reduction": ("t_F reduction (points)", "+.1f"),
                               "flow_time_improved_cases": ("t_F improved", "")}))
    warn = mt[mt["x_inf_warning"].fillna("").astype(str).str.len() > 0] if "x_inf_warning" in mt else mt.iloc[:0]
    out.append("\n**x∞ (self-consistent fixed point)**: "
               + ("every deposition run reached the fixed point within its tolerance.\n" if warn.empty else
                  "**WARNING** — the fall-back rule gave x∞ for: " + "; ".join(
                      f"{r.case} ({r.reading}): {r.x_inf_warning}" for r in
                      warn.drop_duplicates(["case", "reading"]).itertuples()) + "\n"))
    return "\n".join(out)


def section_claims(card: pd.DataFrame | None) -> str:
    """The claims scorecard (granudep.claims.scorecard)."""
    from .claims import tally
    out = ["## Claims scorecard: every quantitative claim of the paper\n"]
    if card is None or card.empty:
        return "\n".join(out) + "_Not available: the scorecard was not built._\n"
    out.append(f"{tally(card)} of {len(card)} claims. Paper values from the paper's tables (Tables 3, 5) and "
               "`granudep/data/paper_claims.csv` (with the section each comes from); ours read from the output named "
               "in the last column. Verdict on the converged value where it exists (its dx in column 'dx'), else on "
               "the paper-resolution one; test and tolerance as listed (fixed before reading our numbers). "
               "'–' in 'ours converged': not run.\n")
    out.append(md_table(card, {"claim_id": ("id", ""), "claim": ("claim", ""), "case": ("case", ""),
                               "paper_value": ("paper", ".4g"), "ours_paper_res": ("ours (paper res.)", ".4g"),
                               "ours_converged": ("ours (converged)", ".4g"), "converged_dx_mm": ("dx (mm)", ".3g"),
                               "verdict": ("verdict", ""), "test": ("test", ""), "tolerance": ("tol.", ".3g"),
                               "note": ("measured cause / note", ""), "source": ("paper source", ""),
                               "our_source": ("our source", "")}))
    out.append("")
    return "\n".join(out)


def section_regression_diagnosis(path) -> str:
    out = ["## Regression diagnosis: why R² of (hu)_C/p0 = A[x] + B is low\n"]
    df = _read_csv(path)
    if df is None:
        return "\n".join(out) + _missing("regression diagnosis", path)
    out.append(f"Source: `{path}` (every variant and case). Each variant refits eq 36 with one method choice "
               "changed; residual plot `figures/fig12_residuals.png`. R² quadratic: a parabola in [x] through the "
               "same points (how much of the misfit is curvature rather than scatter).\n")
    summ = _read_csv(Path(path).with_name("diagnosis_summary.csv"))
    if summ is not None:
        out.append("**Per variant** (over the cases; A at θ = 22°: range and largest step between neighbouring a):\n")
        out.append(md_table(summ, {"variant": ("variant", ""), "cases": ("cases", ""), "r2_median": ("median R²", ".3f"),
                                   "r2_min": ("min R²", ".3f"), "cases_r2_ge_0.8": ("cases R² ≥ 0.8", ""),
                                   "r2_quadratic_median": ("median R² quadratic", ".3f"),
                                   "A_22_range": ("A at 22°", ""), "A_22_largest_step": ("largest A step", ".4f")}))
    show = df[df["variant"].isin(["baseline", "no gate"])]
    out.append("\n**Per case, baseline and without the gate section [x] = 0:**\n")
    out.append(md_table(show, {"case": ("case", ""), "a": ("a", ".3g"), "theta_deg": ("θ", ".0f"), "variant": ("variant", ""),
                               "n_sections": ("n", ""), "A": ("A", ".4f"), "B": ("B", ".4f"), "r2": ("R²", ".3f"),
                               "r2_quadratic": ("R² quadratic", ".3f"), "rms_residual": ("RMS resid.", ".4f"),
                               "y_range": ("range of (hu)_C/p0", ".4f"), "x_norm_zero": ("[x] where A[x]+B = 0", ".2f"),
                               "note": ("note", "")}))
    out.append("")
    return "\n".join(out)


def section_verification(paths) -> str:
    out = ["## Verification (analytic and conservation checks)\n"]
    if not paths:
        return "\n".join(out) + _missing("verification tables", None)
    for p in paths:
        df = _read_csv(p)
        if df is None:
            out.append(_missing("verification table", p))
            continue
        passed = df["passed"].astype(str).str.lower().isin(["true", "1", "yes"]) if "passed" in df else None
        head = f"### `{p}`"
        if passed is not None:
            head += f": {int(passed.sum())} of {len(df)} checks within tolerance"
        out.append(head + "\n")
        show = df.copy()
        if passed is not None:
            show["passed"] = np.where(passed, "yes", "**NO**")
        out.append(md_table(show, {"check": ("check", ""), "quantity": ("quantity", ""), "value": ("value", ".4g"),
                                   "reference": ("reference", ".4g"), "error": ("error", ".3g"),
                                   "tolerance": ("tolerance", ".3g"), "passed": ("passed", ""), "note": ("note", "")}))
        out.append("")
    return "\n".join(out)


def _benchmark_records(root: Path) -> pd.DataFrame:
    rows = []
    for f in sorted(root.rglob("*.tsv")):
        with f.open() as fh:
            recs = list(csv.DictReader(fh, delimiter="\t"))
        for r in recs:
            rows.append({"job": str(f.relative_to(root).with_suffix("")), "s": pd.to_numeric(r.get("s"), errors="coerce"),
                         "max_rss": pd.to_numeric(r.get("max_rss"), errors="coerce")})
    return pd.DataFrame(rows, columns=["job", "s", "max_rss"])


def section_benchmarks(benchmarks) -> str:
    out = ["## Benchmarks\n"]
    if benchmarks is None or not Path(benchmarks).exists():
        return "\n".join(out) + _missing("benchmarks", benchmarks)
    p = Path(benchmarks)
    if p.is_dir():
        df = _benchmark_records(p)
        if df.empty:
            return "\n".join(out) + f"_Not available: no benchmark .tsv file under {p}._\n"
        df = df.sort_values("s", ascending=False)
        out.append(f"Snakemake benchmark files under `{p}` (wall seconds, peak memory MB), {len(df)} jobs, "
                   f"total {df['s'].sum():.1f} s of job time (jobs may run in parallel).\n")
        out.append(md_table(df, {"job": ("job", ""), "s": ("wall time (s)", ".1f"), "max_rss": ("max RSS (MB)", ".0f")}))
    else:
        df = pd.read_csv(p)
        out.append(f"Source: `{p}`.\n")
        out.append(md_table(df, {c: (c, ".4g") for c in df.columns}))
    out.append("")
    return "\n".join(out)


def section_figures(figures, out_dir: Path | None) -> str:
    out = ["## Figures\n"]
    if figures is None or not Path(figures).is_dir():
        return "\n".join(out) + _missing("figures folder", figures)
    files = sorted(f for f in Path(figures).iterdir() if f.suffix.lower() in FIGURE_SUFFIXES)
    if not files:
        return "\n".join(out) + f"_Not available: no figure file in {figures}._\n"
    for f in files:
        rel = os.path.relpath(f, out_dir) if out_dir is not None else str(f)
        out.append(f"- [{f.name}]({rel}) ({f.stat().st_size / 1024:.0f} kB)")
    out.append("")
    return "\n".join(out)


def _open(path):
    """A run or sections file, lazily, in the stages' dimension order and with times in seconds."""
    from .io import open_dataset
    return open_dataset(path, load=False)


def _study_rows_isph(folder: Path, dx=None) -> pd.DataFrame:
    """One row per 2D run in ``folder``; with ``dx`` (m) only the runs at those resolutions (the
    configured list: a run left over from an earlier list is not a convergence result)."""
    import xarray as xr
    from .da_vs_reference import reference_row
    rows = []
    for f in sorted(folder.glob("*.nc")):
        with _open(f) as ds:
            if not _selected(float(ds.attrs.get("dx", math.nan)), dx):
                continue
            status = str(ds.attrs.get("status", ""))
            row = {"run": f.stem, "dx_mm": 1e3 * float(ds.attrs.get("dx", math.nan)), "status": status,
                   "time_to_rest": float(ds["time_to_rest"].values) if "time_to_rest" in ds else math.nan,
                   "n_outflow": int(ds.attrs.get("n_outflow", 0))}
            if not status.lower().startswith("failed"):
                r = reference_row(ds)
                row.update(final_runout_norm=r["final_runout_norm"], flow_time=r["flow_time"],
                           flow_time_norm=r["flow_time_norm"])
                l0 = float(ds.attrs.get("L0", math.nan))
                for k in ("front_5mm", "front_v99", "front_tail"):     # robust fronts (issue 11)
                    if f"final_{k}" in ds:
                        row[f"runout_{k}"] = (float(ds[f"final_{k}"].values) - l0) / l0
                row["energy_max_excess"] = float(ds.attrs.get("energy_max_excess", math.nan))
        rows.append(row)
    return pd.DataFrame(rows)


def _selected(value: float, wanted) -> bool:
    """True without a selection, else when ``value`` is one of ``wanted`` (to 1e-9 relative)."""
    if wanted is None:
        return True
    return any(math.isclose(value, float(w), rel_tol=1e-9) for w in wanted)


def _drift(values: pd.Series) -> str:
    """Change between the two finest resolutions (last two rows), relative to the finest."""
    v = pd.to_numeric(values, errors="coerce").to_numpy(float)
    if v.size < 2 or not np.all(np.isfinite(v[-2:])) or v[-1] == 0:
        return "–"
    return f"{100 * (v[-1] - v[-2]) / abs(v[-1]):+.1f} %"


def section_convergence(folder, dx=None, n_particles=None) -> str:
    """Convergence target (``results/convergence``): 2D runout, flow time, critical times vs dx; DA vs N.
    ``dx`` (m) and ``n_particles`` restrict the tables to the configured runs (default: every file)."""
    import xarray as xr
    out = ["## Convergence (beyond the paper)\n"]
    root = Path(folder) if folder is not None else None
    if root is None or not (root / "isph").is_dir():
        return "\n".join(out) + _missing("convergence runs (`snakemake -j2 convergence`)", root)
    iso = _study_rows_isph(root / "isph", dx)
    if not iso.empty:
        iso = iso.sort_values("dx_mm", ascending=False)
        out.append(f"2D ISPH runs in `{root / 'isph'}` (finer to the bottom). Flow time: the front moves < 1 mm "
                   "afterwards; time to rest: every particle slower than 0.1 m/s for 0.1 s; outflow: particles "
                   "that left through the downstream end of the bed.\n")
        cols = {"run": ("run", ""), "dx_mm": ("dx (mm)", ".1f"), "final_runout_norm": ("ΔL/L0 (2 d front)", ".3f")}
        for k, lab in (("runout_front_5mm", "ΔL/L0 (5 mm front)"), ("runout_front_v99", "ΔL/L0 (1 % volume)"),
                       ("runout_front_tail", "ΔL/L0 (thin tail)")):
            if k in iso:
                cols[k] = (lab, ".3f")
        out.append(md_table(iso, {**cols, "flow_time": ("t_F (s)", ".3f"),
                                  "flow_time_norm": ("t_F/t_c", ".2f"), "time_to_rest": ("time to rest (s)", ".3f"),
                                  "n_outflow": ("outflow particles", ""),
                                  "energy_max_excess": ("max energy rise / E_ref", ".4f"), "status": ("status", "")}))
        empty = pd.Series(dtype=float)
        out.append(f"\nChange between the two finest dx: runout {_drift(iso.get('final_runout_norm', empty))}, "
                   f"flow time {_drift(iso.get('flow_time', empty))}.\n")
        from .richardson import observed_order
        for k, lab in (("final_runout_norm", "2 d front"), ("runout_front_v99", "1 % volume front")):
            if k in iso and iso[k].notna().sum() >= 3:
                r = observed_order(iso["dx_mm"], iso[k])
                txt = (f"observed order {r['order']:.2f}, Richardson estimate {r['extrapolated']:.2f}"
                       if r["converging"] else "no observed order")
                out.append(f"Runout ({lab}), three finest dx: {txt}{'; ' + r['reason'] if r['reason'] else ''}.\n")
    crit = []
    files = sorted((root / "regression").glob("*/critical.csv")) if (root / "regression").is_dir() else []
    for f in files:
        df = pd.read_csv(f)
        if {"x_norm", "t_s_critical", "dx"} <= set(df.columns) and len(df) and _selected(float(df["dx"].iloc[0]), dx):
            for xn in (0.2, 0.4, 0.6, 0.8):
                sel = df[np.isclose(df["x_norm"], xn, atol=1e-6)]
                if len(sel):
                    crit.append({"dx_mm": 1e3 * float(sel["dx"].iloc[0]), "x_norm": xn,
                                 "t_s_critical": float(sel["t_s_critical"].iloc[0])})
    if crit:
        ct = pd.DataFrame(crit).pivot(index="dx_mm", columns="x_norm", values="t_s_critical")
        ct = ct.sort_index(ascending=False).reset_index()
        ct.columns = ["dx_mm"] + [f"x{c:g}" for c in ct.columns[1:]]
        out.append("Critical times (t_s)_C (onset of deposition) at [x] = 0.2 … 0.8:\n")
        cols = {"dx_mm": ("dx (mm)", ".1f")}
        cols.update({c: (f"[x] = {c[1:]}", ".2f") for c in ct.columns[1:]})
        out.append(md_table(ct, cols))
        out.append("")
    rows = []
    for f in sorted((root / "da").glob("*.nc")) if (root / "da").is_dir() else []:
        with _open(f) as ds:
            if not _selected(float(ds.sizes.get("particle", 0)), n_particles):
                continue
            rows.append({"case": str(ds.attrs.get("case", f.stem.split("_n")[0])),
                         "variant": "deposition" if int(ds.attrs.get("deposition", 1)) else "no deposition",
                         "n": int(ds.sizes.get("particle", 0)),
                         "final_runout_norm": float(ds["final_runout_norm"].values),
                         "flow_time": float(ds["flow_time"].values)})
    if rows:
        da = pd.DataFrame(rows)
        ns = sorted(da["n"].unique())
        tab = da[["case", "variant"]].drop_duplicates().sort_values(["case", "variant"]).reset_index(drop=True)
        cols = {"case": ("case", ""), "variant": ("variant", "")}
        for q, head in (("final_runout_norm", "ΔL/L0"), ("flow_time", "t_F (s)")):
            for n in ns:
                sel = da[da["n"] == n].set_index(["case", "variant"])[q]
                tab[f"{q}{n}"] = [sel.get((c, v), math.nan) for c, v in zip(tab["case"], tab["variant"])]
                cols[f"{q}{n}"] = (f"{head} N={n}", ".3f")
        if len(ns) >= 2:
            a, b = ns[-2], ns[-1]
            tab["change"] = 100 * (tab[f"final_runout_norm{b}"] - tab[f"final_runout_norm{a}"]) / tab[
                f"final_runout_norm{b}"].abs()
            cols["change"] = (f"runout change N={a}→{b} %", "+.1f")
        out.append(f"DA runs in `{root / 'da'}`: final runout ΔL/L0 and flow time t_F per particle count N.\n")
        out.append(md_table(tab, cols))
        out.append("")
    return "\n".join(out)


def section_sensitivity(table) -> str:
    """Sensitivity target (``results/sensitivity/sensitivity.csv``): A, B and the DA runout per swept value."""
    out = ["## Sensitivity (beyond the paper)\n"]
    df = _read_csv(table)
    if df is None:
        return "\n".join(out) + _missing("sensitivity table (`snakemake -j2 sensitivity`)", table)
    out.append(f"Source: `{table}`. One parameter at a time away from the paper's value; changes relative to "
               "the run at the paper's value.\n")
    df = df.copy()
    if "baseline" in df:
        df["baseline"] = df["baseline"].astype(bool)
        for q in ("A", "B", "final_runout_norm", "flow_time"):
            if q not in df:
                continue
            ref = {p: float(g[q].iloc[0]) for p, g in df[df["baseline"]].groupby("parameter")}
            df[f"{q}_change"] = [100 * (v - ref[p]) / abs(ref[p]) if ref.get(p) else math.nan
                                 for p, v in zip(df["parameter"], df[q])]
    out.append(md_table(df, {"parameter": ("parameter", ""), "value": ("value", ".4g"),
                             "baseline": ("paper value", ""), "A": ("A", ".4f"), "A_change": ("ΔA %", "+.0f"),
                             "B": ("B", ".4f"), "B_change": ("ΔB %", "+.0f"),
                             "final_runout_norm": ("DA ΔL/L0", ".3f"),
                             "final_runout_norm_change": ("Δ runout %", "+.1f"),
                             "flow_time": ("DA t_F (s)", ".3f"), "flow_time_change": ("Δ t_F %", "+.1f")}))
    out.append("")
    return "\n".join(out)


def build_summary(regression=None, compare=None, verification=(), benchmarks=None, figures=None,
                  output=None, convergence=None, sensitivity=None, convergence_dx=None,
                  convergence_n=None, matrix=None, maxima=None, claims=None, diagnosis=None) -> str:
    """The Markdown summary text (see module docstring)."""
    out_dir = Path(output).parent if output is not None else None
    parts = [
        "# granudep: reproduction summary (Nikooei & Choi 2022)\n",
        f"Generated by granudep {__version__}. Every number below is read from the files named in each section; "
        "the paper's values come from the same files or from the paper's tables shipped with granudep. "
        "The paper's Fig 16 maxima (Section 4.3): without deposition "
        f"{100 * PAPER_MAX_ERRORS['no deposition']['runout']:.0f} % runout / "
        f"{100 * PAPER_MAX_ERRORS['no deposition']['flow_time']:.0f} % flow time, with deposition "
        f"{100 * PAPER_MAX_ERRORS['deposition']['runout']:.0f} % / {100 * PAPER_MAX_ERRORS['deposition']['flow_time']:.0f} %, "
        "against Farin et al. (2014) measurements, which are not available to us.\n",
        section_claims(claims),
        section_table3(regression),
        section_table5(regression),
        section_regression_diagnosis(diagnosis),
        section_compare(compare),
        section_reading_matrix(matrix, maxima),
        section_verification(list(verification or [])),
        section_convergence(convergence, convergence_dx, convergence_n),
        section_sensitivity(sensitivity),
        section_benchmarks(benchmarks),
        section_figures(figures, out_dir),
    ]
    return "\n".join(parts)



def _wm_numbers(folder: Path) -> str:
    import xarray as xr
    parts = []
    for f in sorted(folder.glob("*.nc")):
        with _open(f) as ds:
            if "rms_deviation" not in ds:
                continue
            r = ds["rms_deviation"]
            txt = ", ".join(f"{float(np.nanmax(r.sel(width_factor=w).values)):.3f} ({w:g} dx)"
                            for w in r["width_factor"].values if w != ds.attrs.get("wm_reference", 2.0)
                            and np.isfinite(r.sel(width_factor=w).values).any())
            parts.append(f"{ds.attrs.get('case', f.stem)}: max RMS {txt}")
    return "; ".join(parts)


def _late_depth(path: Path, t_s_from: float) -> str:
    import xarray as xr
    with _open(path) as ds:
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

    t3 = _read_csv(root / "regression" / "table3_comparison.csv")
    if t3 is not None and len(t3):
        empty = pd.Series(dtype=float)
        nums["table3"] = (f"mean absolute (t_s)_C difference from Table 3: {_pct_mean(t3.get('rel_diff_pct', empty))} "
                          f"(onset), {_pct_mean(t3.get('rel_diff_fit_pct', empty))} (fit intercept) "
                          f"over {len(t3)} (case, [x]) pairs")
        row = t3[(t3["case"] == "T22-A70") & np.isclose(t3["x_norm"], 0.2)] if "x_norm" in t3 else t3.iloc[:0]
        nums["fig10"] = (f"T22-A70 at [x] = 0.2: (t_s)_C = {_fmt(row['t_s_critical'].iloc[0], '.2f')} "
                         f"(paper {_fmt(row['t_s_critical_paper'].iloc[0], '.2f')})" if len(row)
                         else "T22-A70 at [x] = 0.2 not in the Table 3 comparison")
    else:
        nums["table3"] = nums["fig10"] = missing("regression/table3_comparison.csv")
    t5 = _read_csv(root / "regression" / "table5_comparison.csv")
    if t5 is not None and len(t5):
        nums["table5"] = "; ".join(f"a = {r.a:g}: A = {_fmt(r.A, '.4f')} (paper {_fmt(r.A_paper, '.4f')}), "
                                   f"B = {_fmt(r.B, '.4f')} (paper {_fmt(r.B_paper, '.4f')})"
                                   for r in t5.sort_values("a").itertuples())
    else:
        nums["table5"] = missing("regression/table5_comparison.csv")
    cmp = _read_csv(root / "compare" / "comparison.csv")
    if cmp is not None and len(cmp):
        mx = max_errors(cmp)
        nums["fig16"] = "; ".join(f"{r.variant}, {r.quantity.replace('_', ' ')}: largest absolute error "
                                  f"{100 * r.max_abs_rel_error:.0f} % at {r.case} (paper {100 * r.paper_max_error:.0f} %)"
                                  for r in mx.itertuples()) if not mx.empty else "no comparable case"
        ref = cmp.drop_duplicates("case").sort_values("a")
        nums["fig15"] = "; ".join(f"{r.case}: 2D ΔL∞/L0 = {_fmt(r.reference_final_runout_norm, '.2f')}, "
                                  f"t_F = {_fmt(r.reference_flow_time, '.2f')} s" for r in ref.itertuples())
        if "reference_flow_time_norm" in ref:
            nums["fig7"] = "flow times of the 22° 2D runs t_F/t_c = " + ", ".join(
                f"{_fmt(r.reference_flow_time_norm, '.1f')} (a = {r.a:g})" for r in ref.itertuples())
        dep = cmp[cmp["variant"] == "deposition"].sort_values("a")
        nums["fig17"] = "DA with deposition ΔL∞/L0 = " + ", ".join(
            f"{_fmt(r.final_runout_norm, '.2f')} ({r.case})" for r in dep.itertuples())
    else:
        nums["fig16"] = nums["fig15"] = nums["fig17"] = missing("compare/comparison.csv")
    nums.setdefault("fig7", missing("compare/comparison.csv"))
    run = root / "isph" / "T22-A70.nc"
    if run.is_file():
        def fig5():
            from .isph.analysis import failure_plane_angle
            with _open(run) as ds:
                fp = failure_plane_angle(ds, t_norm=1.0)
                rest = float(ds["time_to_rest"].values)
                tc = float(ds.attrs["t_c"])
            return (f"failure plane {fp['angle_horizontal_deg']:.1f}° from the horizontal "
                    f"({fp['angle_deg']:.1f}° from the bed; particles moving at t = {fp['time']:.2f} s, on their "
                    f"initial positions); time to rest {rest:.2f} s (t_s = {rest / tc:.1f})")
        guard("fig5", fig5, "isph/T22-A70.nc")
    else:
        nums["fig5"] = missing("isph/T22-A70.nc")
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
    mxm = _read_csv(root / "compare" / "reading_matrix_maxima.csv")
    if mxm is not None and len(mxm):
        sel = mxm[mxm["measure"] == "2d"] if "measure" in mxm else mxm
        nums["readingmatrix"] = "; ".join(
            f"{r.reading} vs {r.reference}: largest runout error {100 * r.max_runout_error_nodep:.0f} % without, "
            f"{100 * r.max_runout_error_dep:.0f} % with deposition; flow time {100 * r.max_flow_time_error_nodep:.0f} % "
            f"/ {100 * r.max_flow_time_error_dep:.0f} %" for r in sel.itertuples())
    else:
        nums["readingmatrix"] = missing("compare/reading_matrix_maxima.csv")
    dgs = _read_csv(root / "regression" / "diagnosis_summary.csv")
    if dgs is not None and len(dgs):
        nums["diagnosis"] = "; ".join(f"{r['variant']}: median R² {_fmt(r['r2_median'], '.2f')}, "
                                      f"{int(r['cases_r2_ge_0.8'])}/{int(r['cases'])} cases with R² ≥ 0.8"
                                      for _, r in dgs.iterrows())
    else:
        nums["diagnosis"] = missing("regression/diagnosis_summary.csv")
    sens = _read_csv(root / "sensitivity" / "sensitivity.csv")
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
            return "2D ΔL∞/L0 = " + ", ".join(f"{_fmt(r.get('final_runout_norm'), '.2f')} (dx = {r['dx_mm']:.0f} mm)"
                                              for _, r in iso.iterrows())
        guard("convergence", convergence, "convergence/isph")
    else:
        nums["convergence"] = "not computed yet (convergence/isph missing: run `snakemake -j2 convergence`)"
    return nums
