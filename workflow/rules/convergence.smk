# Convergence study (issue 5): T22-A70 in 2D at three particle spacings (runout, flow time,
# critical times) and the DA cases at three particle counts. Target `convergence`, not in `all`.

CONV = config["convergence"]
CONV_DIR = f"{RESULTS}/convergence"


rule convergence_isph:
    input:
        warm=WARM,
    output:
        f"{CONV_DIR}/isph/{{case}}_dx{{dx}}.nc",
    params:
        t_end=lambda wc: f"--t-end {config['isph']['t_end']}" if config["isph"].get("t_end") else "",
    log:
        f"{LOGS}/convergence/isph/{{case}}_dx{{dx}}.log",
    benchmark:
        f"{BENCH}/convergence/isph/{{case}}_dx{{dx}}.tsv"
    threads: config["isph"]["threads"]
    resources:
        runtime=480,
        mem_mb=8000,
    shell:
        "NUMBA_NUM_THREADS={threads} granudep isph {wildcards.case} --dx {wildcards.dx} {params.t_end}"
        " -o {output} > {log} 2>&1"


rule convergence_monitor:
    input:
        warm=WARM,
        run=f"{CONV_DIR}/isph/{{case}}_dx{{dx}}.nc",
    output:
        f"{CONV_DIR}/sections/{{case}}_dx{{dx}}.nc",
    params:
        width_factor=config["monitor"]["width_factor"],
    log:
        f"{LOGS}/convergence/sections/{{case}}_dx{{dx}}.log",
    benchmark:
        f"{BENCH}/convergence/sections/{{case}}_dx{{dx}}.tsv"
    threads: 1
    shell:
        "NUMBA_NUM_THREADS={threads} granudep monitor {input.run} --width-factor {params.width_factor}"
        " -o {output} > {log} 2>&1"


rule convergence_regress:
    input:
        f"{CONV_DIR}/sections/{{case}}_dx{{dx}}.nc",
    output:
        critical=f"{CONV_DIR}/regression/{{case}}_dx{{dx}}/critical.csv",
        coefficients=f"{CONV_DIR}/regression/{{case}}_dx{{dx}}/coefficients.csv",
    params:
        outdir=f"{CONV_DIR}/regression/{{case}}_dx{{dx}}",
    log:
        f"{LOGS}/convergence/regression/{{case}}_dx{{dx}}.log",
    benchmark:
        f"{BENCH}/convergence/regression/{{case}}_dx{{dx}}.tsv"
    threads: 1
    shell:
        "granudep regress {input} -o {params.outdir} > {log} 2>&1"


rule convergence_da:
    input:
        warm=WARM,
    output:
        f"{CONV_DIR}/da/{{case}}_n{{n}}_{{variant}}.nc",
    params:
        options=lambda wc: "--no-deposition" if wc.variant == "nodeposition" else "--ab-source paper",
    log:
        f"{LOGS}/convergence/da/{{case}}_n{{n}}_{{variant}}.log",
    benchmark:
        f"{BENCH}/convergence/da/{{case}}_n{{n}}_{{variant}}.tsv"
    threads: 1
    shell:
        "NUMBA_NUM_THREADS={threads} granudep da {wildcards.case} {params.options} --n-particles {wildcards.n}"
        " -o {output} > {log} 2>&1"


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


# --- Reference runs (issue 12): the four Table 5 geometries at 22° and T22-A70 at the reference dx ---
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
