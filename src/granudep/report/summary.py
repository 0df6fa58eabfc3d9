"""``results/summary.md``: the paper-vs-ours tables, verification and benchmarks, read from the outputs.

Every number in the summary comes from a file given on the command line (regression tables,
``granudep compare`` output, ``granudep verify`` outputs, benchmark files); the paper's values
come from those files too (the regression tables carry them) or from the package's copies of the
paper's tables, and the paper's stated Fig 16 maxima from :data:`granudep.report.da_vs_reference.PAPER_MAX_ERRORS`
(Section 4.3). A missing input gives an explicit "not available" line, never a crash.
"""
from __future__ import annotations

import csv
import os
import re
from pathlib import Path

import pandas as pd

from .._version import __version__
from .da_vs_reference import PAPER_MAX_ERRORS, improvement, max_errors
from .markdown import md_table, not_available, pct_mean, read_csv
from .studies import section_convergence, section_sensitivity
from ..verification_gate import FAIL, PASS, REPORTED, chain_dx_lines, count, statuses
from .readme_status import variant_lines
from .claims import tally
from .da_readings import pivot_markdown

FIGURE_SUFFIXES = (".png", ".pdf", ".svg")


def section_table3(regression) -> str:
    out = ["## Table 3: critical times (t_s)_C, paper vs ours\n"]
    path = Path(regression) / "table3_comparison.csv" if regression is not None else None
    df = read_csv(path)
    if df is None:
        return "\n".join(out) + not_available("Table 3 comparison", path)
    out.append(f"Source: `{path}`. (t_s)_C = onset of deposition (h_D starts to grow); 'fit' = intercept of the "
               "linear fit of h_D vs t_s (the paper's Fig 9 reading).\n")
    out.append(md_table(df, {"case": ("case", ""), "x_norm": ("[x]", ".1f"),
                             "t_s_critical_paper": ("paper", ".2f"), "t_s_critical": ("ours (onset)", ".2f"),
                             "rel_diff_pct": ("rel. diff. %", "+.1f"), "t_s_critical_fit": ("ours (fit)", ".2f"),
                             "rel_diff_fit_pct": ("rel. diff. (fit) %", "+.1f"), "status": ("status", "")}))
    out.append(f"\nMean |relative difference|: onset {pct_mean(df.get('rel_diff_pct', pd.Series(dtype=float)))}, "
               f"fit intercept {pct_mean(df.get('rel_diff_fit_pct', pd.Series(dtype=float)))} "
               f"over {len(df)} (case, [x]) pairs.\n")
    if {"case", "rel_diff_pct"} <= set(df.columns):
        from .readme_status import table3_by_angle
        signed = df["case"].astype(str).str.extract(r"^T(\d+)-")[0]
        mean_signed = ", ".join(f"{th}°: {df.loc[signed == th, 'rel_diff_pct'].mean():+.1f} %"
                                for th in sorted(signed.dropna().unique(), key=int))
        out.append(f"Per slope angle, onset: mean |difference| {table3_by_angle(df)}; mean signed difference "
                   f"{mean_signed} (positive: ours later than the paper).\n")
    return "\n".join(out)


def section_table5(regression) -> str:
    out = ["## Table 5: A and B of (hu)_C/p0 = A[x] + B at θ = 22°, paper vs ours\n"]
    path = Path(regression) / "table5_comparison.csv" if regression is not None else None
    df = read_csv(path)
    if df is None:
        return "\n".join(out) + not_available("Table 5 comparison", path)
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
    df = read_csv(compare)
    if df is None:
        return "\n".join(out) + not_available("comparison table", compare)
    if "reference" not in df.columns:
        from .reference_2d import source_label
        df["reference"] = [source_label(p) for p in df["provenance"]]
    out.append(f"Source: `{compare}`. Relative error = (computed − reference)/reference. Runout ΔL/L0 from the gate.\n")
    show = df.copy()
    for c in ("runout_rel_error", "flow_time_rel_error"):
        show[c] = pd.to_numeric(show[c], errors="coerce") * 100
    if "reading_label" in show:  # the plain label of the A, B reading (the key where an old file lacks it)
        show["reading_label"] = show["reading_label"].where(show["reading_label"].notna(), show.get("reading"))
    if "reference_dx" in show:
        show["reference_dx"] = pd.to_numeric(show["reference_dx"], errors="coerce") * 1e3
    out.append(md_table(show, {"case": ("case", ""), "variant": ("DA variant", ""),
                               "reading_label": ("A, B reading", ""), "reference": ("reference", ""),
                               "reference_dx": ("ref. dx (mm)", ".3g"), "reference_basis": ("why this reference", ""),
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
    """Reading matrix: {A, B readings} × {deposition, none} against every reference."""
    out = ["## Reading matrix: which A, B reading, which reference (Figs 15–16)\n"]
    mt, mx = read_csv(matrix), read_csv(maxima)
    if mt is None or mx is None:
        return "\n".join(out) + not_available("reading matrix", matrix if mt is None else maxima)
    out.append(f"Source: `{matrix}`, `{maxima}`. Readings (column `reading_label`; key `reading`): computed "
               "(`computed`) = our regression (normalised, eq 36), paper normalised (`paper`) = Table 5 read as "
               "normalised, paper dimensional (`paper-dimensional`) = Table 5 read as (hu)_C = A[x] + B in m²/s. Each deposition run is paired with the same no-deposition run. Front `2d`: attached front "
               "at 2 grain diameters (the paper's kind of front); `v99`: the point beyond which 1 % of the "
               "deposit's volume lies (does not jump when a thin tip detaches); the same rule on the 2D and the "
               "DA depth profile. Relative error = (DA − 2D)/2D.\n")
    show = mt.copy()
    for c in ("runout_error", "runout_error_nodep", "flow_time_error", "flow_time_error_nodep"):
        show[c] = pd.to_numeric(show[c], errors="coerce") * 100
    lab = "reading_label" if "reading_label" in show else "reading"
    if "reference_dx" in show:
        show["reference_dx"] = pd.to_numeric(show["reference_dx"], errors="coerce") * 1e3
    out.append(md_table(show, {"case": ("case", ""), "reference": ("reference", ""),
                               "reference_dx": ("ref. dx (mm)", ".3g"), lab: ("A, B reading", ""),
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
    lab = "reading_label" if "reading_label" in show else "reading"
    out.append(md_table(show, {"reference": ("reference", ""), lab: ("A, B reading", ""), "measure": ("front", ""),
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
                      f"{r.case} ({getattr(r, 'reading_label', r.reading)}): {r.x_inf_warning}" for r in
                      warn.drop_duplicates(["case", "reading"]).itertuples()) + "\n"))
    return "\n".join(out)


def section_variants(results) -> str:
    """The variant chains' scorecards (``results/variants/<name>``, config/variants/<name>.yaml) beside
    the reproduction's; empty when no variant chain has been run."""

    if results is None:
        return ""
    lines = variant_lines(Path(results))
    if not lines:
        return ""
    return "\n".join(["## Variant chains", "",
                      "The same chain with one model choice changed (`snakemake -j2 --configfile config/config.yaml "
                      "config/variants/<name>.yaml`), read from its own outputs:", "",
                      *[f"- {line}" for line in lines], ""])


def section_ensemble(path) -> str:
    """Per 2D case: fronts and both rest times over the ensemble members (granudep ensemble --quantities)."""
    out = ["## Ensembles: fronts and rest times of every 2D case over its members\n"]
    df = read_csv(path) if path else None
    if df is None or df.empty:
        return "\n".join(out) + "Not available: one member per case (config ensemble.members = 1) or `results/ensemble/` " \
            "not built.\n"
    df = df.copy()
    df["spread_pct"] = 100 * (df["max"] - df["min"]) / df["mean"].abs()
    df["dx_mm"] = 1e3 * df["dx"]
    out.append(f"Source: `{path}`. Member 0 is the lattice, the others start with every position moved by 0.01 dx; "
               "spread = (max − min) / mean. A difference between two cases or two settings smaller than the spread "
               "is not a finding.\n")
    out.append(md_table(df, {"case": ("case", ""), "quantity": ("quantity", ""), "n": ("n", ""), "mean": ("mean", ".3f"),
                             "min": ("min", ".3f"), "max": ("max", ".3f"), "std": ("std", ".3f"),
                             "spread_pct": ("spread %", ".1f"), "member0": ("member 0", ".3f"), "dx_mm": ("dx (mm)", ".3g")}))
    out.append("")
    return "\n".join(out)


def section_ensemble_convergence(path, robust=None) -> str:
    """Per case and quantity: the ensemble mean and spread at the chain's dx and at a finer dx, the dx
    change, a single finer run and the observed order (granudep convergence-table)."""
    from .ensemble_convergence import markdown
    out = ["## Ensembles at two resolutions: the spread beside the dx change\n"]
    df = read_csv(path) if path else None
    if df is None or df.empty:
        return "\n".join(out) + "Not available: `snakemake -j2 convergence_ensemble` has not run.\n"
    out.append(f"Source: `{path}`. Spread = (max − min) / mean of the members; dx change = change of the "
               "ensemble mean from the chain's dx to the finer ensemble. A quantity is *well-defined* when both "
               "are within the threshold (`convergence.well_defined_pct`); a dx change smaller than the spread "
               "is not a finding. The observed order uses the two ensemble means and one lattice run at the "
               "finest dx.\n")
    out.append(markdown(df))
    rob = read_csv(robust) if robust else None
    if rob is not None and not rob.empty:
        out.append("")
        out.append("Robust rest measure per case (the smaller of max(spread, |dx change|), chosen by those two "
                   "figures alone): " + "; ".join(
                       f"{r.case}: " + (f"`{r.robust}`" if getattr(r, "within_threshold", True) else "neither is well-defined")
                       + " (" + ", ".join(f"{c[6:-4]} {getattr(r, c):.1f} %" for c in rob.columns
                                                          if c.startswith("worst_") and pd.notna(getattr(r, c)))
                       + ")"
                       for r in rob.itertuples()) + ".")
    out.append("")
    return "\n".join(out)


def section_claims(card: pd.DataFrame | None) -> str:
    """The claims scorecard (granudep.report.claims.scorecard)."""
    out = ["## Claims scorecard: every quantitative claim of the paper\n"]
    if card is None or card.empty:
        return "\n".join(out) + "_Not available: the scorecard was not built._\n"
    out.append(f"{tally(card)} of {len(card)} claims. Paper values from the paper's tables (Tables 3, 5) and "
               "`granudep/data/paper_claims.csv` (with the section each comes from); ours read from the output named "
               "in the last column. Verdict on the converged value where it exists (its dx in column 'dx'), else on "
               "the paper-resolution one; test and tolerance as listed (fixed before reading our numbers). "
               "'–' in 'ours converged': not run.\n")
    if "ours_std" in card:
        out.append("Ours is the **ensemble mean** over the members (column 'n'; member 0 the lattice, the others "
                   "jittered by 0.01 dx), with min–max and std. Verdict: *reproduced* when the paper's value is within "
                   "the tolerance of our mean and both the members' spread (max − min) and the change of the mean "
                   "to the finer ensemble (where one has run, column 'fine') are within it; *indeterminate* when "
                   "the spread or the dx change exceeds the tolerance; else *not reproduced*.\n")
        out.append(md_table(card, {"claim_id": ("id", ""), "case": ("case", ""), "paper_value": ("paper", ".4g"),
                                   "ours_paper_res": ("ours (mean)", ".4g"), "ours_min": ("min", ".4g"),
                                   "ours_max": ("max", ".4g"), "ours_std": ("std", ".3g"), "members": ("n", ""),
                                   "ours_fine": ("fine (mean)", ".4g"), "fine_dx_mm": ("fine dx (mm)", ".3g"),
                                   "verdict": ("verdict", ""), "test": ("test", ""), "tolerance": ("tol.", ".3g"),
                                   "note": ("measured cause / note", ""), "source": ("paper source", "")}))
        out.append("")
        return "\n".join(out)
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
    df = read_csv(path)
    if df is None:
        return "\n".join(out) + not_available("regression diagnosis", path)
    out.append(f"Source: `{path}` (every variant and case). Each variant refits eq 36 with one method choice "
               "changed; residual plot `figures/fig12_residuals.png`. R² quadratic: a parabola in [x] through the "
               "same points (how much of the misfit is curvature rather than scatter).\n")
    summ = read_csv(Path(path).with_name("diagnosis_summary.csv"))
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
        return "\n".join(out) + not_available("verification tables", None)
    for p in paths:
        df = read_csv(p)
        if df is None:
            out.append(not_available("verification table", p))
            continue
        head = f"### `{p}`"
        show = df.copy()
        if "passed" in df:
            head += f": {count(df).sentence()}"
            show["passed"] = statuses(df).map({PASS: "yes", FAIL: "**NO**", REPORTED: "reported"})
        out.append(head + "\n")
        pairs = chain_dx_lines(df)
        if pairs:
            out.append("At the chain's resolution (dx = 4 mm) beside the checked rows: " + "; ".join(pairs) + ".\n")
        cols = {"check": ("check", ""), "quantity": ("quantity", ""), "value": ("value", ".4g"),
                "reference": ("reference", ".4g"), "error": ("error", ".3g"),
                "tolerance": ("tolerance", ".3g"), "passed": ("passed", "")}
        if "chain_dx_error" in df:
            cols["chain_dx_error"] = ("error at dx = 4 mm", ".3g")
        out.append(md_table(show, cols | {"note": ("note", "")}))
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
        return "\n".join(out) + not_available("benchmarks", benchmarks)
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


def figure_caption(name: str, captions) -> str:
    """The caption of figure ``name`` (e.g. ``fig5``, ``reading-matrix``): the first paragraph of
    ``captions/NAME.rst`` (the Snakemake report's caption, workflow/report/), markup removed; or the
    entry of a mapping ``captions``. "" when there is none."""
    if captions is None:
        return ""
    if isinstance(captions, dict):
        return str(captions.get(name, "") or "")
    path = Path(captions) / f"{name}.rst"
    if not path.is_file():
        return ""
    first = path.read_text(encoding="utf-8").strip().split("\n\n", 1)[0]
    text = " ".join(first.split()).replace("**", "").replace("``", "`")
    return re.sub(r"\{\{.*?\}\}", "", text).strip()


def _figure_entries(figures) -> list[tuple[str, Path]]:
    """(name, path) of every figure given: a folder (every figure file in it, named by its stem), or a
    list of ``NAME=PATH`` / ``PATH`` entries (a PATH alone is named by its stem)."""
    if figures is None:
        return []
    if isinstance(figures, (str, Path)) and Path(figures).is_dir():
        return [(f.stem, f) for f in sorted(Path(figures).iterdir()) if f.suffix.lower() in FIGURE_SUFFIXES]
    items = [figures] if isinstance(figures, (str, Path)) else list(figures)
    out = []
    for item in items:
        if Path(item).is_dir():
            out += _figure_entries(item)
            continue
        name, sep, path = str(item).partition("=")
        out.append((name, Path(path)) if sep else (Path(item).stem, Path(item)))
    return out


def section_figures(figures, out_dir: Path | None, captions=None) -> str:
    """Every figure given (``--figures``: the workflow passes each figure as NAME=PATH), with its caption
    (``--captions``: workflow/report, the report's captions)."""
    out = ["## Figures\n"]
    entries = _figure_entries(figures)
    if not entries:
        if figures is None or (isinstance(figures, (str, Path)) and not Path(figures).exists()):
            return "\n".join(out) + not_available("figures", figures)
        return "\n".join(out) + f"_Not available: no figure file in {figures}._\n"
    out.append(f"{len(entries)} figures; captions from `{captions}` (the Snakemake report's).\n" if captions
               else f"{len(entries)} figures.\n")
    for name, f in entries:
        rel = os.path.relpath(f, out_dir) if out_dir is not None else str(f)
        size = f"{f.stat().st_size / 1024:.0f} kB" if f.is_file() else "**missing**"
        cap = figure_caption(name, captions) or f"_no caption (`{name}.rst` not found)_"
        out.append(f"- [{f.name}]({rel}) ({size}): {cap}")
    out.append("")
    return "\n".join(out)


def section_da_readings(path) -> str:
    """Every (hu)_C reading × the Table 5 geometries: A, B, R² and the DA runout error it leads to."""
    out = ["## Every (hu)_C reading through the DA: A, B, R² and the runout error with deposition\n"]
    df = read_csv(path)
    if df is None or df.empty:
        return "\n".join(out) + "A study beyond the paper, not part of `all`: `snakemake -j2 da_readings` runs it " \
            "(35 DA runs) and the next `snakemake -j2` shows its table here.\n"
    n = ", ".join(str(v) for v in sorted(set(df["n_particles"])))
    out.append(f"Source: `{path}` (`granudep da-readings`). Each row's A, B (from the regression diagnosis, "
               f"read as normalised) drive the DA with deposition (N = {n}); error = DA ΔL/L0 / 2D reference − 1 "
               "(front at 2 d in both models); shorter = 1 − runout with / without deposition. The reading "
               "the chain uses is `baseline` (flowing depth above the F/D interface, section-mean velocity, "
               "onset at the critical time, x∞ the 1 % volume front; argued from the text in "
               "docs/deposition.md), not the best fit. The paper reports deposition removing up to 38 points "
               "of runout error (against measurements we do not have).\n")
    out.append(pivot_markdown(df))
    out.append("\n**Per reading and geometry:**\n")
    out.append(md_table(df, {"reading": ("reading", ""), "case": ("case", ""), "a": ("a", ".3g"), "A": ("A", ".4f"),
                             "B": ("B", ".4f"), "r2": ("R²", ".3f"), "runout_norm": ("DA ΔL/L0", ".2f"),
                             "reference_2d_runout_norm": ("2D ΔL/L0", ".2f"), "runout_error": ("error", "+.1%"),
                             "shortening": ("shorter", ".1%")}))
    out.append("")
    return "\n".join(out)



def build_summary(regression=None, compare=None, verification=(), benchmarks=None, figures=None,
                  output=None, convergence=None, sensitivity=None, convergence_dx=None,
                  convergence_n=None, matrix=None, maxima=None, claims=None, diagnosis=None, captions=None,
                  results=None, da_readings=None, ensemble=None, ensemble_convergence=None,
                  robust_rest=None) -> str:
    """The Markdown summary text (see module docstring); ``results``: the results folder, whose
    ``variants/`` chains are shown beside the claims scorecard."""
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
        section_variants(results),
        section_ensemble(ensemble),
        section_ensemble_convergence(ensemble_convergence, robust_rest),
        section_table3(regression),
        section_table5(regression),
        section_regression_diagnosis(diagnosis),
        section_da_readings(da_readings),
        section_compare(compare),
        section_reading_matrix(matrix, maxima),
        section_verification(list(verification or [])),
        section_convergence(convergence, convergence_dx, convergence_n),
        section_sensitivity(sensitivity),
        section_benchmarks(benchmarks),
        section_figures(figures, out_dir, captions),
    ]
    return "\n".join(parts)
