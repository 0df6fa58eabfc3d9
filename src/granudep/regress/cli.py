"""``granudep regress``: critical times, deposition rates, critical DA momentum, A/B tables."""
from __future__ import annotations

import pandas as pd

from ..cliutil import parse_sets
from ..progress import LOG


def _cmd_regress(args) -> int:
    from ..io import check_output_dir
    from .api import regress, write_outputs
    check_output_dir(args.output)  # before any work
    over = {"onset_depth_factor": args.onset_depth_factor, "fit_x_min": args.fit_x_min, "fit_x_max": args.fit_x_max,
            **parse_sets(args.set)}
    result = regress(args.sections, **over)
    paths = write_outputs(result, args.output)
    with pd.option_context("display.width", 200, "display.max_columns", 30, "display.max_rows", 200):
        c = result["coefficients"]
        print("Eq 36 fits, (hu)_C/p0 = A [x] + B:")
        print(c[["case", "theta_deg", "a", "A", "B", "r2", "n_sections"]].to_string(index=False, float_format="{:.4f}".format))
        t3 = result["table3"]
        print("\nTable 3, critical times (t_s)_C: paper vs ours (rule onset; Fig-9 fit intercept):")
        if t3.empty:
            print("  (no Table 3 case among the inputs)")
        else:
            print(t3[["case", "x_norm", "t_s_critical_paper", "t_s_critical", "abs_diff", "rel_diff_pct",
                      "t_s_critical_fit", "rel_diff_fit_pct"]].to_string(index=False, float_format="{:.3f}".format))
        t5 = result["table5"]
        print("\nTable 5, A and B at theta = 22 deg: paper vs ours (normalised); printed values x p0 in m^2/s:")
        if t5.empty:
            print("  (no Table 5 geometry among the inputs: runs T22-A30, T22-A45, T22-A70, T22-A124)")
        else:
            print(t5[["case", "run_case", "A_paper", "A", "A_rel_diff_pct", "B_paper", "B", "B_rel_diff_pct",
                      "p0", "B_paper_times_p0", "B_paper_over_p0"]].to_string(index=False, float_format="{:.4f}".format))
    LOG.info("regress: wrote %s", ", ".join(str(p) for p in paths))
    return 0


def _cmd_diagnose(args) -> int:
    from ..io import write_text
    from .diagnose import diagnose, variant_summary
    table, resid = diagnose(args.sections, args.isph or [], args.wm or [])
    summary = variant_summary(table)
    with pd.option_context("display.width", 220, "display.max_columns", 30, "display.max_rows", 400):
        print(table.drop(columns=["x_norm_used"]).to_string(index=False, float_format="{:.4f}".format))
        print("\nPer variant:")
        print(summary.to_string(index=False, float_format="{:.4f}".format))
    write_text(table.to_csv(index=False), args.output)
    if args.residuals:
        write_text(resid.to_csv(index=False), args.residuals)
    if args.summary:
        write_text(summary.to_csv(index=False), args.summary)
    return 0


def register(sub) -> None:
    p = sub.add_parser("regress-diagnose", help="refit eq 36 with one method choice changed at a time (R², residuals)")
    p.add_argument("sections", nargs="+", help="sections NetCDF files")
    p.add_argument("--isph", nargs="*", help="the 2D run files (for the x_inf = 1 %% volume-front variant)")
    p.add_argument("--wm", nargs="*", help="W_M sensitivity files (granudep monitor-wm)")
    p.add_argument("-o", "--output", required=True, metavar="DIAGNOSIS.csv")
    p.add_argument("--residuals", metavar="RESIDUALS.csv", help="baseline residuals per section")
    p.add_argument("--summary", metavar="SUMMARY.csv", help="per-variant R² summary")
    p.set_defaults(func=_cmd_diagnose)

    p = sub.add_parser("regress", help="critical DA momentum regression over section files (eqs 35-36, Tables 3-5)")
    p.add_argument("sections", nargs="+", help="sections NetCDF files (results/sections/{case}.nc)")
    p.add_argument("-o", "--output", required=True, metavar="DIR",
                   help="directory for critical.csv, coefficients.csv/.nc, table3/table5_comparison.csv")
    p.add_argument("--onset-depth-factor", type=float, default=None, metavar="F",
                   help="onset when h_D crosses F x dx for the last time (default 0.5)")
    p.add_argument("--fit-x-min", type=float, default=None, help="lowest [x] in the A/B fit (default 0)")
    p.add_argument("--fit-x-max", type=float, default=None, help="highest [x] in the A/B fit (default 1)")
    p.add_argument("--set", dest="set", action="append", default=[], metavar="KEY=VALUE",
                   help="override one regression setting (repeatable), e.g. min_sections=4")
    p.set_defaults(func=_cmd_regress)
