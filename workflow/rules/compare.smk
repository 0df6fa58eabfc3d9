# DA runs against the 2D references (Section 4.3, Figs 15-16) and the reading matrix.
# Two 2D references, same front and flow-time rules as the DA runs:
#   - paper resolution: the 2D ISPH runs of this workflow (isph.dx);
#   - converged: per case, among those runs and the files matched by compare.reference.runs (the
#     convergence ladder, the reference runs), the finest rung whose runout (compare.reference.measure,
#     the 1 % volume front) changed by at most compare.reference.tolerance (5 %) from the next coarser
#     rung (select: converged, the default); without one the workflow's run, and the row says so
#     (column reference_basis). select: finest takes the finest run on disk; a number in
#     compare.reference.dx takes the run at that dx. Labelled with its dx, row by row.
# Reading matrix: DA runs with deposition for every A, B reading in compare.readings (computed,
# paper normalised, paper dimensional), each against the no-deposition run and both references.
# Plus any CSV listed in config `reference_tables` (e.g. a user's measurements).

import glob as _glob

_CMP = config.get("compare", {})
_REF = _CMP.get("reference", {})
READINGS = list(_CMP.get("readings", ["computed", "paper", "paper-dimensional"]))
# the default chain's reading: da.ab_source, normalised (eq 36 as printed)
DEFAULT_READING = config["da"]["ab_source"]
REFERENCE_DX = _REF.get("dx")
# a run stopped by a signal or a blow-up leaves NAME.interrupted.nc / NAME.failed.nc beside its
# output: partial records, never a reference
REFERENCE_EXTRA = sorted({p for pat in _REF.get("runs", []) for p in _glob.glob(pat)
                          if not p.endswith((".interrupted.nc", ".failed.nc"))})
REFERENCE_SELECT = "dx" if REFERENCE_DX is not None else _REF.get("select", "converged")
REFERENCE_TOL = float(_REF.get("tolerance", 0.05))
REFERENCE_MEASURE = _REF.get("measure", "v99")
# the paper's resolution is dx = 4 mm (Appendix); a coarser workflow (CI) says so in its label
PAPER_REFERENCE_LABEL = "2D paper resolution" if abs(config["isph"]["dx"] - 0.004) < 1e-9 else "2D workflow resolution"
CONVERGED_REFERENCE_LABEL = {"dx": "2D converged", "converged": "2D converged",
                             "finest": "2D finest available"}[REFERENCE_SELECT]
REFERENCE_OPTIONS = {"dx": f"--dx {REFERENCE_DX}", "finest": "--finest",
                     "converged": f"--converged --tolerance {REFERENCE_TOL} --measure {REFERENCE_MEASURE}"}[REFERENCE_SELECT]


def reading_file(case, reading):
    """The DA run of one A, B reading: the default chain's own file for the default reading."""
    if reading == DEFAULT_READING and "deposition" in DA_VARIANTS:
        return f"{RESULTS}/da/{case}_deposition.nc"
    return f"{RESULTS}/da/readings/{case}_{reading}.nc"


READING_FILES = [reading_file(c, r) for c in DA_CASES for r in READINGS
                 if reading_file(c, r) != f"{RESULTS}/da/{c}_deposition.nc"]
COMPARE_OUTPUTS = {
    "comparison": f"{RESULTS}/compare/comparison.csv",
    "matrix": f"{RESULTS}/compare/reading_matrix.csv",
    "maxima": f"{RESULTS}/compare/reading_matrix_maxima.csv",
}


def _reading_inputs(wc):
    inputs = {"warm": WARM}
    if wc.reading.startswith("computed"):
        inputs["coefficients"] = f"{RESULTS}/regression/coefficients.csv"
    return inputs


def _reading_options(wc, input):
    source, _, units = wc.reading.partition("-")
    opts = f"--ab-source {source} --coefficient-units {'dimensional' if units else 'normalised'}"
    if source == "computed":
        opts += f" --coefficients {input.coefficients}"
    return opts


rule da_reading:
    """One DA run with deposition for one A, B reading of the reading matrix."""
    input:
        unpack(_reading_inputs),
    output:
        f"{RESULTS}/da/readings/{{case}}_{{reading}}.nc",
    wildcard_constraints:
        reading="computed|paper|paper-dimensional|computed-dimensional",
    params:
        options=_reading_options,
        n_particles=config["da"]["n_particles"],
    log:
        f"{LOGS}/da/readings/{{case}}_{{reading}}.log",
    benchmark:
        f"{BENCH}/da/readings/{{case}}_{{reading}}.tsv"
    threads: config["da"]["threads"]
    resources:
        runtime=30,
        mem_mb=2000,
    shell:
        "NUMBA_NUM_THREADS={threads} granudep da {wildcards.case} {params.options}"
        " --n-particles {params.n_particles} -o {output} > {log} 2>&1"


rule reference:
    input:
        runs=[f"{RESULTS}/isph/{REFERENCE_2D[c]}.nc" for c in DA_CASES],
    output:
        f"{RESULTS}/compare/reference_2d.csv",
    params:
        label=PAPER_REFERENCE_LABEL,
    log:
        f"{LOGS}/compare/reference.log",
    benchmark:
        f"{BENCH}/compare/reference.tsv"
    threads: 1
    resources:
        runtime=10,
        mem_mb=2000,
    shell:
        "granudep reference {input.runs} --label '{params.label}' -o {output} > {log} 2>&1"


rule reference_converged:
    """The converged 2D reference (compare.reference), one run per case, each row labelled with its dx
    and why it was chosen (reference_basis)."""
    input:
        runs=[f"{RESULTS}/isph/{REFERENCE_2D[c]}.nc" for c in DA_CASES],
        extra=REFERENCE_EXTRA,
    output:
        f"{RESULTS}/compare/reference_converged.csv",
    params:
        label=CONVERGED_REFERENCE_LABEL,
        select=REFERENCE_OPTIONS,
    log:
        f"{LOGS}/compare/reference_converged.log",
    benchmark:
        f"{BENCH}/compare/reference_converged.tsv"
    threads: 1
    resources:
        runtime=10,
        mem_mb=2000,
    shell:
        "granudep reference {input.runs} --ladder {input.extra} {params.select} --label '{params.label}'"
        " -o {output} > {log} 2>&1"


rule compare:
    input:
        da=expand(f"{RESULTS}/da/{{case}}_{{variant}}.nc", case=DA_CASES, variant=DA_VARIANTS),
        readings=READING_FILES,
        reference=f"{RESULTS}/compare/reference_2d.csv",
        converged=f"{RESULTS}/compare/reference_converged.csv",
        extra=config["reference_tables"],
    output:
        **COMPARE_OUTPUTS,
    params:
        default_reading=DEFAULT_READING,
    log:
        f"{LOGS}/compare/compare.log",
    benchmark:
        f"{BENCH}/compare/compare.tsv"
    threads: 1
    resources:
        runtime=10,
        mem_mb=2000,
    shell:
        "granudep compare {input.da} --readings {input.readings} --default-reading {params.default_reading}"
        " --reference {input.reference} {input.converged} {input.extra} -o {output.comparison}"
        " --matrix {output.matrix} --maxima {output.maxima} > {log} 2>&1"


rule da_readings:
    """Every (hu)_C reading of the regression diagnosis through the DA with deposition, against the
    2D reference: the runout error each reading leads to (summary, 'Every (hu)_C reading')."""
    input:
        diagnosis=DIAGNOSIS_OUTPUTS["table"],
        reference=f"{RESULTS}/compare/reference_2d.csv",
        warm=WARM,
    output:
        f"{RESULTS}/compare/da_readings.csv",
    params:
        n_particles=config["da"]["n_particles"],
    log:
        f"{LOGS}/compare/da_readings.log",
    benchmark:
        f"{BENCH}/compare/da_readings.tsv"
    threads: config["da"]["threads"]
    resources:
        runtime=60,
        mem_mb=2000,
    shell:
        "NUMBA_NUM_THREADS={threads} granudep da-readings {input.diagnosis} --reference {input.reference}"
        " --n-particles {params.n_particles} -o {output} > {log} 2>&1"

# Regression on the converged reference (claims scorecard, column "ours converged"): the runs of
# compare.reference that `granudep reference` selects (per case the finest converged rung, the run at
# compare.reference.dx, or the finest) and that are not this workflow's own run get monitoring sections and the eq-36
# regression, so Table 3 / Table 5 entries of those cases are also read at that resolution.
def _converged_runs():
    if not REFERENCE_EXTRA:
        return {}
    from granudep.report.reference_2d import select_reference_runs
    own = [f"{RESULTS}/isph/{REFERENCE_2D[c]}.nc" for c in DA_CASES]
    have = [p for p in own if os.path.exists(p)]
    if REFERENCE_SELECT == "converged":
        from granudep.report.reference_2d import select_converged_runs
        chosen = [p for p, _, ok in select_converged_runs(have, REFERENCE_EXTRA, REFERENCE_TOL, REFERENCE_MEASURE) if ok]
    else:
        chosen = select_reference_runs(REFERENCE_EXTRA + have, REFERENCE_DX)
    return {os.path.splitext(os.path.basename(p))[0]: p for p in chosen if p in REFERENCE_EXTRA}


CONVERGED_RUNS = _converged_runs()
CONVERGED_REGRESSION = f"{RESULTS}/converged/regression"


rule monitor_converged:
    input:
        run=lambda wc: CONVERGED_RUNS[wc.run],
    output:
        f"{RESULTS}/converged/sections/{{run}}.nc",
    wildcard_constraints:
        run="[A-Za-z0-9_.-]+",
    params:
        width_factor=config["monitor"]["width_factor"],
    log:
        f"{LOGS}/converged/monitor_{{run}}.log",
    benchmark:
        f"{BENCH}/converged/monitor_{{run}}.tsv"
    threads: 1
    resources:
        runtime=60,
        mem_mb=8000,
    shell:
        "NUMBA_NUM_THREADS={threads} granudep monitor {input.run} --width-factor {params.width_factor}"
        " -o {output} > {log} 2>&1"


rule regress_converged:
    input:
        sections=[f"{RESULTS}/converged/sections/{r}.nc" for r in CONVERGED_RUNS],
    output:
        table3=f"{CONVERGED_REGRESSION}/table3_comparison.csv",
        table5=f"{CONVERGED_REGRESSION}/table5_comparison.csv",
        coefficients=f"{CONVERGED_REGRESSION}/coefficients.csv",
    params:
        outdir=CONVERGED_REGRESSION,
    log:
        f"{LOGS}/converged/regress.log",
    benchmark:
        f"{BENCH}/converged/regress.tsv"
    threads: 1
    resources:
        runtime=15,
        mem_mb=2000,
    shell:
        "granudep regress {input.sections} -o {params.outdir} > {log} 2>&1"


# --- The DA-vs-2D errors per ensemble member: the same DA runs read against member k's 2D runs ---
# (member 0 is the chain's own comparison above). The ensemble rule gathers the members' Fig 16
# maxima from these, so the DA errors are quoted with the spread the 2D reference carries.
use rule reference as reference_member with:
    input:
        runs=[f"{MEMBERS}/m{{member}}/isph/{REFERENCE_2D[c]}.nc" for c in DA_CASES],
    output:
        f"{MEMBERS}/m{{member}}/compare/reference_2d.csv",
    log:
        f"{MEMBERS}/m{{member}}/logs/compare/reference.log",
    benchmark:
        f"{BENCH}/ensemble/m{{member}}/compare/reference.tsv"


use rule compare as compare_member with:
    input:
        da=expand(f"{RESULTS}/da/{{case}}_{{variant}}.nc", case=DA_CASES, variant=DA_VARIANTS),
        readings=READING_FILES,
        reference=f"{MEMBERS}/m{{member}}/compare/reference_2d.csv",
        converged=f"{RESULTS}/compare/reference_converged.csv",
        extra=config["reference_tables"],
    output:
        comparison=f"{MEMBERS}/m{{member}}/compare/comparison.csv",
        matrix=f"{MEMBERS}/m{{member}}/compare/reading_matrix.csv",
        maxima=f"{MEMBERS}/m{{member}}/compare/reading_matrix_maxima.csv",
    log:
        f"{MEMBERS}/m{{member}}/logs/compare/compare.log",
    benchmark:
        f"{BENCH}/ensemble/m{{member}}/compare/compare.tsv"
