"""CLI of the report stage: ``reference``, ``compare``, ``da-readings``, ``summary``, ``sensitivity-table``,
``readme-status``."""
from __future__ import annotations

import argparse

from ..progress import LOG
from . import readme_status, sensitivity_table


def _cmd_reference(args) -> int:
    from .reference_2d import reference_from_isph, select_reference_runs
    from ..io import write_text
    runs, basis = list(args.runs), None
    if args.converged:
        from .reference_2d import select_converged_runs
        picked = select_converged_runs(runs, args.ladder or [], tol=args.tolerance, measure=args.measure)
        runs, basis = [p for p, _, _ in picked], [(b, c) for _, b, c in picked]
        for p, b, _ in picked:
            LOG.info("reference %s: %s (%s)", args.label or "", p, b)
    elif args.finest or args.dx is not None:
        runs = select_reference_runs(runs + list(args.ladder or []), args.dx)
        LOG.info("reference %s: %s", args.label or "", ", ".join(str(r) for r in runs))
    table = reference_from_isph(runs, tol=args.flow_time_tol, label=args.label, basis=basis)
    with __import__("pandas").option_context("display.width", 200, "display.max_colwidth", 70):
        print(table.to_string(index=False, float_format=lambda v: f"{v:.4g}"))
    write_text(table.to_csv(index=False), args.output)
    return 0


def _cmd_compare(args) -> int:
    from .da_vs_reference import compare, matrix_maxima, reading_matrix, report_text
    from ..io import write_text
    table = compare(list(args.runs) + list(args.readings or []), args.reference)
    main = table
    if args.default_reading:
        main = table[table["reading"].isin([args.default_reading, "none"])].reset_index(drop=True)
    print(report_text(main))
    write_text(main.to_csv(index=False), args.output)
    if args.matrix:
        matrix = reading_matrix(table)
        write_text(matrix.to_csv(index=False), args.matrix)
        maxima = matrix_maxima(matrix)
        with __import__("pandas").option_context("display.width", 220, "display.max_columns", 40):
            print("\nReading matrix maxima (|error|, per reference, A/B reading, front measure):")
            print(maxima.to_string(index=False, float_format=lambda v: f"{v:.3f}"))
        if args.maxima:
            write_text(maxima.to_csv(index=False), args.maxima)
    return 0


def _cmd_da_readings(args) -> int:
    import pandas as pd
    from .da_readings import pivot_markdown, reading_runs
    from ..io import write_text
    frames = {}
    for key, path in (("diagnosis", args.diagnosis), ("--reference", args.reference)):
        try:
            frames[key] = pd.read_csv(path)
        except (OSError, pd.errors.ParserError) as e:
            raise SystemExit(f"granudep da-readings: {key}: cannot read {path} ({e})")
    table = reading_runs(frames["diagnosis"], frames["--reference"], args.n_particles)
    print(f"DA runout error against the 2D reference with deposition (N = {args.n_particles}), per reading "
          "of (hu)_C; in brackets how much shorter than without deposition:\n")
    print(pivot_markdown(table))
    write_text(table.to_csv(index=False), args.output)
    return 0


def _positive_int(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text!r}")
    if not 20 <= v <= 1_000_000:
        raise argparse.ArgumentTypeError(f"must be in [20, 1000000] (got {text})")
    return v


def _cmd_summary(args) -> int:
    from .summary import build_summary
    from ..io import write_text
    card = None
    if args.claims:
        from .claims import scorecard, tally
        card = scorecard(args.results, args.converged_regression)
        if args.ensemble:
            from .ensemble import ensemble_scorecard, read_member_table
            card = ensemble_scorecard(card, read_member_table(args.ensemble, "--ensemble"),
                                      read_member_table(args.fine_ensemble, "--fine-ensemble")
                                      if args.fine_ensemble else None, fine_dx_mm=args.fine_dx_mm)
        write_text(card.to_csv(index=False), args.claims)
        LOG.info("claims scorecard: %s -> %s", tally(card), args.claims)
    text = build_summary(regression=args.regression, compare=args.compare,
                         verification=(args.verification or []) + ([args.verification_fine] if args.verification_fine else []),
                         benchmarks=args.benchmarks, figures=args.figures, output=args.output,
                         convergence=args.convergence, sensitivity=args.sensitivity,
                         convergence_dx=args.convergence_dx, convergence_n=args.convergence_n,
                         matrix=args.matrix, maxima=args.maxima, claims=card, diagnosis=args.diagnosis,
                         da_readings=args.da_readings, ensemble=args.ensemble_quantities,
                         ensemble_convergence=args.ensemble_convergence, robust_rest=args.robust_rest,
                         captions=args.captions, results=args.results)
    write_text(text, args.output)
    LOG.info("summary written to %s", args.output)
    if args.html:
        from .markdown_html import to_html
        write_text(to_html(text, title="granudep summary"), args.html)
        LOG.info("summary (HTML) written to %s", args.html)
    if args.caption_numbers:
        import json
        from .captions import caption_numbers
        write_text(json.dumps(caption_numbers(args.results, args.convergence_dx), indent=1, ensure_ascii=False) + "\n",
                   args.caption_numbers)
        LOG.info("report caption numbers written to %s", args.caption_numbers)
    return 0


def _positive_float(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}")
    if not v > 0:
        raise argparse.ArgumentTypeError(f"must be > 0 (got {text})")
    return v


def register(sub) -> None:
    p = sub.add_parser("reference", help="2D reference runouts/flow times of the Table 5 geometries (CSV)")
    p.add_argument("runs", nargs="+", metavar="ISPH.nc", help="2D ISPH runs (e.g. T22-A30 … T22-A124)")
    p.add_argument("-o", "--output", required=True, metavar="REF.csv")
    p.add_argument("--flow-time-tol", type=_positive_float, default=1e-3, metavar="M",
                   help="flow time: front moves less than this afterwards (m, default 0.001)")
    p.add_argument("--label", metavar="TEXT",
                   help="name of this reference source; its rows read 'TEXT (dx = … mm)'")
    p.add_argument("--finest", action="store_true",
                   help="keep one run per case: the finest dx (the converged reference until the ladder names one)")
    p.add_argument("--dx", type=_positive_float, metavar="M",
                   help="keep one run per case: the one at this dx (m; finest where none)")
    p.add_argument("--converged", action="store_true",
                   help="keep one run per case: the finest rung of the ladder (RUNS and --ladder) whose runout "
                        "changed by at most --tolerance from the next coarser rung; else the case's run in RUNS "
                        "(column reference_basis says which and why)")
    p.add_argument("--ladder", nargs="*", metavar="ISPH.nc",
                   help="further runs of the same cases at other dx (e.g. results/convergence/isph/*.nc)")
    p.add_argument("--tolerance", type=_positive_float, default=0.05, metavar="REL",
                   help="--converged: largest relative runout change from the next coarser rung (default 0.05)")
    p.add_argument("--measure", choices=("v99", "2d", "5mm", "tail"), default="v99",
                   help="--converged: the runout front the ladder checks (default v99, the 1 %% volume front)")
    p.set_defaults(func=_cmd_reference)

    p = sub.add_parser("compare", help="relative errors of DA runs against reference tables (Fig 16)")
    p.add_argument("runs", nargs="+", metavar="DA.nc")
    p.add_argument("--reference", nargs="+", required=True, metavar="REF.csv",
                   help="tables with columns case, final_runout_norm, flow_time|flow_time_norm, provenance")
    p.add_argument("-o", "--output", required=True, metavar="COMPARE.csv",
                   help="the default chain's comparison (--default-reading and no deposition)")
    p.add_argument("--readings", nargs="*", metavar="DA.nc", help="DA runs of the other A, B readings")
    p.add_argument("--default-reading", metavar="NAME",
                   help="reading of the default chain (computed, paper, paper-dimensional): COMPARE.csv keeps it")
    p.add_argument("--matrix", metavar="MATRIX.csv", help="write the reading matrix (every reading x reference)")
    p.add_argument("--maxima", metavar="MAXIMA.csv", help="write the reading matrix's maxima per reading")
    p.set_defaults(func=_cmd_compare)

    p = sub.add_parser("da-readings", help="DA runout with deposition for every (hu)_C reading of the regression "
                                           "diagnosis, against the 2D reference (CSV)")
    p.add_argument("diagnosis", metavar="DIAGNOSIS.csv", help="granudep regress-diagnose table")
    p.add_argument("--reference", required=True, metavar="REF.csv",
                   help="granudep reference table of the Table 5 geometries (its 'path' names each 2D run)")
    p.add_argument("--n-particles", type=_positive_int, default=1000, metavar="N",
                   help="DA particles per run, in [20, 1000000] (the chain's da.n_particles)")
    p.add_argument("-o", "--output", required=True, metavar="READINGS.csv")
    p.set_defaults(func=_cmd_da_readings)

    p = sub.add_parser("summary", help="Markdown summary: paper-vs-ours tables, verification, figures")
    p.add_argument("-o", "--output", required=True, metavar="summary.md")
    p.add_argument("--html", metavar="summary.html",
                   help="also write the summary as a standalone HTML page (shown rendered in the Snakemake report)")
    p.add_argument("--regression", metavar="DIR", help="granudep regress output folder")
    p.add_argument("--convergence", metavar="DIR", help="convergence study folder (isph/, regression/, da/)")
    p.add_argument("--convergence-dx", nargs="+", type=_positive_float, metavar="DX",
                   help="only the 2D convergence runs at these dx (m; default: every file in the folder)")
    p.add_argument("--convergence-n", nargs="+", type=int, metavar="N",
                   help="only the DA convergence runs with these particle counts (default: every file)")
    p.add_argument("--caption-numbers", metavar="JSON",
                   help="also write our numbers for the report captions (read from --results) to this file")
    p.add_argument("--results", metavar="DIR", default="results", help="results folder for --caption-numbers")
    p.add_argument("--sensitivity", metavar="CSV", help="sensitivity study table")
    p.add_argument("--compare", metavar="CSV", help="granudep compare output")
    p.add_argument("--matrix", metavar="CSV", help="reading matrix of granudep compare --matrix")
    p.add_argument("--maxima", metavar="CSV", help="reading-matrix maxima of granudep compare --maxima")
    p.add_argument("--claims", metavar="CSV", help="build the claims scorecard from --results and write it here")
    p.add_argument("--converged-regression", metavar="DIR",
                   help="regression folder of the converged 2D runs (scorecard column 'ours converged')")
    p.add_argument("--diagnosis", metavar="CSV", help="regression diagnosis table (granudep regress-diagnose)")
    p.add_argument("--da-readings", metavar="CSV", help="DA runout per (hu)_C reading (granudep da-readings)")
    p.add_argument("--verification", nargs="*", metavar="CSV", help="granudep verify outputs")
    p.add_argument("--ensemble", metavar="CSV", help="every member's claim values (granudep ensemble -o): the "
                   "claims then quote the members' mean and spread, with the three verdicts")
    p.add_argument("--ensemble-quantities", metavar="CSV", help="per-case fronts and rest times over the members "
                   "(granudep ensemble --quantities)")
    p.add_argument("--fine-ensemble", metavar="CSV", help="the same members' claim values at a finer dx (the dx "
                   "change of each claim)")
    p.add_argument("--fine-dx-mm", type=_positive_float, default=float("nan"), help="dx of --fine-ensemble, mm")
    p.add_argument("--ensemble-convergence", metavar="CSV", help="the convergence ensembles' table "
                   "(granudep convergence-table -o)")
    p.add_argument("--robust-rest", metavar="CSV", help="the robust rest measure per case "
                   "(granudep convergence-table --robust)")
    p.add_argument("--verification-fine", metavar="CSV", help="the fine-resolution rows (target verify_fine), "
                   "shown after the others when they have run")
    p.add_argument("--benchmarks", metavar="CSV|DIR", help="benchmark CSV, or a folder of Snakemake benchmark .tsv files")
    p.add_argument("--figures", nargs="+", metavar="NAME=PATH",
                   help="the figures to list, each NAME=PATH (NAME: its caption file NAME.rst) or PATH, or a folder")
    p.add_argument("--captions", metavar="DIR", help="folder of the figure captions NAME.rst (workflow/report)")
    p.set_defaults(func=_cmd_summary)
    sensitivity_table.register(sub)
    readme_status.register(sub)
    from . import ensemble, ensemble_convergence
    ensemble.register(sub)
    ensemble_convergence.register(sub)
