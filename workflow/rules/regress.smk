# Critical DA momentum (Section 4.2): onset of deposition per section, (hu)_C/p0 = A[x] + B per
# case (eq 36), the A/B tables over (a, theta) and the paper-vs-ours Tables 3 and 5.


rule regress:
    input:
        sections=expand(f"{RESULTS}/sections/{{case}}.nc", case=REGRESS_CASES),
    output:
        critical=f"{RESULTS}/regression/critical.csv",
        coefficients=f"{RESULTS}/regression/coefficients.csv",
        coefficients_nc=f"{RESULTS}/regression/coefficients.nc",
        table3=f"{RESULTS}/regression/table3_comparison.csv",
        table5=f"{RESULTS}/regression/table5_comparison.csv",
    params:
        outdir=f"{RESULTS}/regression",
    log:
        f"{LOGS}/regress.log",
    benchmark:
        f"{BENCH}/regress.tsv"
    threads: 1
    resources:
        runtime=15,
        mem_mb=2000,
    shell:
        "granudep regress {input.sections} -o {params.outdir} > {log} 2>&1"


DIAGNOSIS_OUTPUTS = {
    "table": f"{RESULTS}/regression/diagnosis.csv",
    "residuals": f"{RESULTS}/regression/residuals.csv",
    "summary": f"{RESULTS}/regression/diagnosis_summary.csv",
}


rule regress_diagnose:
    """Eq 36 refitted with one method choice changed at a time (gate section, onset, velocity
    threshold, h_T u, x_inf placement, W_M): why R² is low and A, B jump."""
    input:
        sections=expand(f"{RESULTS}/sections/{{case}}.nc", case=REGRESS_CASES),
        isph=expand(f"{RESULTS}/isph/{{case}}.nc", case=REGRESS_CASES),
        wm=[f"{RESULTS}/wm/{c}.nc" for c in WM_CASES if c in REGRESS_CASES],
    output:
        **DIAGNOSIS_OUTPUTS,
    log:
        f"{LOGS}/regress_diagnose.log",
    benchmark:
        f"{BENCH}/regress_diagnose.tsv"
    threads: 1
    resources:
        runtime=15,
        mem_mb=2000,
    shell:
        "granudep regress-diagnose {input.sections} --isph {input.isph} --wm {input.wm} -o {output.table}"
        " --residuals {output.residuals} --summary {output.summary} > {log} 2>&1"
