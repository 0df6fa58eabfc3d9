# One rule per paper figure, each with its own output results/figures/fig{N}_*.png, drawn by
# `granudep figure NAME -o OUT INPUTS...`; captions for the report live in workflow/report/.


def _isph(cases):
    return [f"{RESULTS}/isph/{c}.nc" for c in cases]


def _sections(cases):
    return [f"{RESULTS}/sections/{c}.nc" for c in cases]


_CRITICAL = f"{RESULTS}/regression/critical.csv"
_COEFFS = f"{RESULTS}/regression/coefficients.csv"

# figure -> (report category, inputs in the order `granudep figure` reads them)
FIGURE_INPUTS = {
    "fig5": ("2D ISPH", _isph(fig_cases("fig5"))),
    "fig6": ("2D ISPH", [f"{RESULTS}/isph/{n}.nc" for n in FIG6_RUNS]),
    "fig7": ("2D ISPH", _isph(fig_cases("fig7")) + _sections(fig_cases("fig7"))),
    "fig8": ("Monitoring sections", _sections(fig_cases("fig8"))),
    "fig9": ("Monitoring sections", _sections(fig_cases("fig9")) + [_CRITICAL]),
    "fig10": ("Monitoring sections", _isph(fig_cases("fig10")) + _sections(fig_cases("fig10"))),
    "fig11": ("Monitoring sections", _sections(fig_cases("fig11")) + [_CRITICAL]),
    "fig12": ("Deposition law", [_CRITICAL, _COEFFS]),
    "fig13": ("Deposition law", [_COEFFS]),
    "fig15": (
        "Depth-averaged model",
        [f"{RESULTS}/da/{c}_{v}.nc" for c in DA_CASES for v in DA_VARIANTS]
        + _isph([REFERENCE_2D[c] for c in DA_CASES])
        # the converged / finest 2D runs of compare.reference (labelled with their dx in the figure)
        + REFERENCE_EXTRA,
    ),
    "fig16": ("Depth-averaged model", [f"{RESULTS}/compare/comparison.csv"]),
    "fig17": (
        "Depth-averaged model",
        [f"{RESULTS}/da/{c}_deposition.nc" for c in DA_CASES if "deposition" in DA_VARIANTS],
    ),
    "figA1": ("Appendix", [f"{RESULTS}/wm/{c}.nc" for c in fig_cases("figA1") if c in WM_CASES]
                          or [f"{RESULTS}/wm/{c}.nc" for c in WM_CASES[:1]]),
    "figA2": ("Appendix", [f"{RESULTS}/wm/{c}.nc" for c in WM_CASES]),
    "figA3": ("Appendix", _isph(fig_cases("figA3")) + _sections(fig_cases("figA3"))),
}

# figure -> options of `granudep figure NAME` beyond its inputs (a leading space; "" for none)
FIGURE_ARGS = {
    "fig6": (" --times " + " ".join(f"{t:g}" for t in FIG6.get("times", [])) if FIG6.get("times") else "")
    + (f" --time-unit {FIG6['time_unit']}" if FIG6.get("time_unit") else ""),
}

for _name in ACTIVE_FIGURES:
    _category, _inputs = FIGURE_INPUTS[_name]

    rule:
        name:
            f"figure_{_name}"
        input:
            _inputs,
        output:
            report(figure_path(_name), caption=f"../report/{_name}.rst", category=_category),
        params:
            name=_name,
            args=FIGURE_ARGS.get(_name, ""),
        log:
            f"{LOGS}/figures/{_name}.log",
        benchmark:
            f"{BENCH}/figures/{_name}.tsv"
        threads: 1
        resources:
            runtime=10,
            mem_mb=2000,
        shell:
            "MPLBACKEND=Agg granudep figure {params.name} -o {output} {input}{params.args} > {log} 2>&1"


# Figures beyond the paper's numbering: the reading matrix and the eq-36 residuals.
EXTRA_FIGURES = {
    "reading-matrix": f"{RESULTS}/figures/reading_matrix.png",
    "fig12r": f"{RESULTS}/figures/fig12_residuals.png",
}


rule figure_reading_matrix:
    input:
        f"{RESULTS}/compare/reading_matrix.csv",
    output:
        report(EXTRA_FIGURES["reading-matrix"], caption="../report/reading-matrix.rst", category="Depth-averaged model"),
    log:
        f"{LOGS}/figures/reading_matrix.log",
    benchmark:
        f"{BENCH}/figures/reading_matrix.tsv"
    threads: 1
    resources:
        runtime=10,
        mem_mb=2000,
    shell:
        "MPLBACKEND=Agg granudep figure reading-matrix -o {output} {input} > {log} 2>&1"


rule figure_fig12_residuals:
    input:
        diagnosis=f"{RESULTS}/regression/diagnosis.csv",
        residuals=f"{RESULTS}/regression/residuals.csv",
    output:
        report(EXTRA_FIGURES["fig12r"], caption="../report/fig12r.rst", category="Deposition law"),
    log:
        f"{LOGS}/figures/fig12_residuals.log",
    benchmark:
        f"{BENCH}/figures/fig12_residuals.tsv"
    threads: 1
    resources:
        runtime=10,
        mem_mb=2000,
    shell:
        "MPLBACKEND=Agg granudep figure fig12r -o {output} {input.diagnosis} {input.residuals} > {log} 2>&1"
