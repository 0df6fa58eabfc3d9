# Convergence study: T22-A70 in 2D at three particle spacings (runout, flow time,
# critical times) and the DA cases at three particle counts. Target `convergence`, not in `all`.

CONV = config["convergence"]
CONV_DIR = f"{RESULTS}/convergence"


# The chain isph -> monitor -> regress and the DA runs are the main rules (isph.smk, monitor.smk,
# regress.smk, da.smk) with other file names and the spacing / particle count from the wildcards.


use rule isph_run as convergence_isph with:
    input:
        warm=WARM,
    output:
        f"{CONV_DIR}/isph/{{case}}_dx{{dx}}.nc",
    params:
        source=lambda wc: wc.case,
        dx=lambda wc: wc.dx,
    log:
        f"{LOGS}/convergence/isph/{{case}}_dx{{dx}}.log",
    benchmark:
        f"{BENCH}/convergence/isph/{{case}}_dx{{dx}}.tsv"
    resources:
        runtime=480,
        mem_mb=8000,


use rule monitor as convergence_monitor with:
    input:
        warm=WARM,
        run=f"{CONV_DIR}/isph/{{case}}_dx{{dx}}.nc",
    output:
        f"{CONV_DIR}/sections/{{case}}_dx{{dx}}.nc",
    log:
        f"{LOGS}/convergence/sections/{{case}}_dx{{dx}}.log",
    benchmark:
        f"{BENCH}/convergence/sections/{{case}}_dx{{dx}}.tsv"


use rule regress as convergence_regress with:
    input:
        sections=f"{CONV_DIR}/sections/{{case}}_dx{{dx}}.nc",
    output:
        critical=f"{CONV_DIR}/regression/{{case}}_dx{{dx}}/critical.csv",
        coefficients=f"{CONV_DIR}/regression/{{case}}_dx{{dx}}/coefficients.csv",
    params:
        outdir=f"{CONV_DIR}/regression/{{case}}_dx{{dx}}",
    log:
        f"{LOGS}/convergence/regression/{{case}}_dx{{dx}}.log",
    benchmark:
        f"{BENCH}/convergence/regression/{{case}}_dx{{dx}}.tsv"


use rule da_run as convergence_da with:
    input:
        warm=WARM,
    output:
        f"{CONV_DIR}/da/{{case}}_n{{n}}_{{variant}}.nc",
    params:
        source=lambda wc: wc.case,
        options=lambda wc: "--no-deposition" if wc.variant == "nodeposition" else "--ab-source paper",
        n_particles=lambda wc: wc.n,
    log:
        f"{LOGS}/convergence/da/{{case}}_n{{n}}_{{variant}}.log",
    benchmark:
        f"{BENCH}/convergence/da/{{case}}_n{{n}}_{{variant}}.tsv"
    threads: 1


CONVERGENCE_INPUTS = (
    expand(f"{CONV_DIR}/isph/{{case}}_dx{{dx}}.nc", case=CONV["isph_case"], dx=CONV["dx"])
    + expand(f"{CONV_DIR}/regression/{{case}}_dx{{dx}}/critical.csv", case=CONV["isph_case"], dx=CONV["dx"])
    + expand(
        f"{CONV_DIR}/da/{{case}}_n{{n}}_{{variant}}.nc",
        case=DA_CASES,
        n=CONV["da_n_particles"],
        variant=DA_VARIANTS,
    )
)


rule figure_convergence:
    input:
        CONVERGENCE_INPUTS,
    output:
        report(f"{RESULTS}/figures/convergence.png", caption="../report/convergence.rst", category="Convergence"),
    log:
        f"{LOGS}/figures/convergence.log",
    benchmark:
        f"{BENCH}/figures/convergence.tsv"
    threads: 1
    shell:
        "MPLBACKEND=Agg granudep figure convergence -o {output} {input} > {log} 2>&1"


rule convergence:
    """Target: every convergence run and its figure."""
    input:
        f"{RESULTS}/figures/convergence.png",


# --- Reference runs: the four Table 5 geometries at 22° and T22-A70 at the reference dx ---
# `snakemake -j2 reference_runs`; compare.reference.runs picks them up as the converged reference.
REF_DX = CONV.get("reference_dx", 0.002)
REF_CASES = CONV.get("reference_cases", ["T22-A30", "T22-A45", "T22-A70", "T22-A124"])


use rule convergence_isph as reference_isph with:
    output:
        f"{RESULTS}/reference/isph/{{case}}_dx{{dx}}.nc",
    log:
        f"{LOGS}/reference/isph/{{case}}_dx{{dx}}.log",
    benchmark:
        f"{BENCH}/reference/isph/{{case}}_dx{{dx}}.tsv"


rule reference_runs:
    """Target: the 2D reference runs at convergence.reference_dx (not part of `all`)."""
    input:
        expand(f"{RESULTS}/reference/isph/{{case}}_dx{{dx}}.nc", case=REF_CASES, dx=[REF_DX]),
