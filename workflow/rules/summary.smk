# results/summary.md: the paper-vs-ours tables (Table 3, Table 5 A/B, Fig 16 errors) and the
# verification results, all read from the outputs; then the per-rule benchmark table and every
# figure with its caption (the report's, workflow/report/NAME.rst).

# every figure of `all` as NAME=PATH (NAME: its caption workflow/report/NAME.rst), then the studies'
SUMMARY_FIGURES = (
    {n: figure_path(n) for n in ACTIVE_FIGURES}
    | EXTRA_FIGURES
    | {f"path_{c}": f"{RESULTS}/figures/path_{c}.png" for c in PATH_CASES}
)
STUDY_FIGURES = {"convergence": f"{RESULTS}/figures/convergence.png",
                 "sensitivity": f"{RESULTS}/figures/sensitivity.png"}
CAPTIONS_DIR = os.path.join(os.path.dirname(os.path.abspath(workflow.main_snakefile)), "workflow", "report")


# optional summary inputs (the studies beyond `all`): path -> the `granudep summary` option that reads it
_FINE_DX = config["convergence"].get("ensemble_dx", 0.002)
SUMMARY_OPTIONAL = {
    f"{RESULTS}/compare/da_readings.csv": "--da-readings {}",
    f"{RESULTS}/verification/isph_fine.csv": "--verification-fine {}",
    f"{RESULTS}/convergence/ensemble_table.csv": "--ensemble-convergence {}",
    f"{RESULTS}/convergence/robust_rest.csv": "--robust-rest {}",
    f"{RESULTS}/convergence/ensemble/dx{_FINE_DX}/claims_members.csv": f"--fine-ensemble {{}} --fine-dx-mm {1e3 * float(_FINE_DX):g}",
}


def _summary_figure_args(wc, input):
    """--figures NAME=PATH for every figure given to the summary (the studies' only when on disk)."""
    named = [(n, p) for n, p in SUMMARY_FIGURES.items()] + [(n, p) for n, p in STUDY_FIGURES.items()
                                                           if p in input.studies]
    # path figures share one caption (path.rst)
    return " ".join(f"{'path' if n.startswith('path_') else n}={p}" for n, p in named)


rule summary:
    input:
        regression=REGRESSION_OUTPUTS,
        compare=f"{RESULTS}/compare/comparison.csv",
        matrix=COMPARE_OUTPUTS["matrix"],
        maxima=COMPARE_OUTPUTS["maxima"],
        converged=f"{RESULTS}/compare/reference_converged.csv",
        diagnosis=DIAGNOSIS_OUTPUTS["table"],
        extra_figures=list(EXTRA_FIGURES.values()),
        converged_regression=[f"{CONVERGED_REGRESSION}/table3_comparison.csv"] if CONVERGED_RUNS else [],
        verification=[f"{RESULTS}/verification/da.csv", f"{RESULTS}/verification/isph.csv"],
        ensemble=[f"{MEMBERS}/claims_members.csv", f"{MEMBERS}/quantities.csv"] if len(MEMBER_IDS) > 1 else [],
        figures=list(SUMMARY_FIGURES.values()),
        # the studies beyond the paper are separate targets: their sections are filled when their
        # outputs exist (a later `snakemake` reruns the summary when they are newer), else the
        # summary says "not available" and names the target
        studies=lambda wc: [p for p in (f"{RESULTS}/figures/convergence.png", f"{RESULTS}/figures/sensitivity.png")
                            if os.path.exists(p)],
        # the same for the study `snakemake -j2 da_readings`, the target `verify_fine` and the
        # convergence ensembles (`snakemake -j2 convergence_ensemble`)
        optional=lambda wc: [p for p in SUMMARY_OPTIONAL if os.path.exists(p)],
    output:
        md=report(f"{RESULTS}/summary.md", category="Summary"),
        # the same text rendered: the Snakemake report shows an HTML result inline (a .md only as a download)
        html=report(f"{RESULTS}/summary.html", category="Summary"),
        # our numbers quoted by the report captions (read back in common.smk)
        captions=f"{RESULTS}/caption_numbers.json",
        # the claims scorecard (granudep.report.claims): every quantitative claim of the paper vs ours
        claims=f"{RESULTS}/claims.csv",
    params:
        regression=f"{RESULTS}/regression",
        benchmarks=BENCH,
        convergence=f"{RESULTS}/convergence",
        # the configured runs only: files left from an earlier dx / N list are not results
        convergence_dx=" ".join(str(d) for d in config["convergence"]["dx"]),
        convergence_n=" ".join(str(n) for n in config["convergence"]["da_n_particles"]),
        sensitivity=f"{RESULTS}/sensitivity/sensitivity.csv",
        results=RESULTS,
        converged=f"--converged-regression {CONVERGED_REGRESSION}" if CONVERGED_RUNS else "",
        ensemble=lambda wc, input: (f"--ensemble {input.ensemble[0]} --ensemble-quantities {input.ensemble[1]}"
                                    if input.ensemble else ""),
        optional=lambda wc, input: " ".join(SUMMARY_OPTIONAL[p].format(p) for p in input.optional),
        figures=_summary_figure_args,
        captions=os.path.relpath(CAPTIONS_DIR),
    log:
        f"{LOGS}/summary.log",
    benchmark:
        f"{BENCH}/summary.tsv"
    threads: 1
    resources:
        runtime=10,
        mem_mb=2000,
    shell:
        "granudep summary -o {output.md} --html {output.html} --regression {params.regression} --compare {input.compare}"
        " --verification {input.verification} --benchmarks {params.benchmarks}"
        " --convergence {params.convergence} --convergence-dx {params.convergence_dx}"
        " --convergence-n {params.convergence_n} --sensitivity {params.sensitivity}"
        " --caption-numbers {output.captions} --results {params.results}"
        " --matrix {input.matrix} --maxima {input.maxima} --diagnosis {input.diagnosis} {params.optional} {params.ensemble} --claims {output.claims}"
        " {params.converged} --figures {params.figures} --captions {params.captions}"
        " > {log} 2>&1"


rule benchmarks_summary:
    """Wall time and peak memory of every rule's benchmark file (Performance: <= 15 min target)."""
    input:
        [t for t in ALL_TARGETS if t != f"{BENCH}/summary.csv"],
    output:
        f"{BENCH}/summary.csv",
    params:
        bench=BENCH,
        python=sys.executable,
    log:
        f"{LOGS}/benchmarks_summary.log",
    threads: 1
    resources:
        runtime=5,
        mem_mb=1000,
    shell:
        "{params.python} benchmarks/workflow_summary.py {params.bench} -o {output} > {log} 2>&1"
