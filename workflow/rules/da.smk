# 1D depth-averaged SPH (Sections 2.3-2.4, 4.3) with and without deposition. A and B come from
# Table 5 (`da.ab_source: paper`) or from our regression (`computed`); user cases always use the
# computed table (interpolated in (a, theta); the run refuses outside the table).
# A run cancelled by SIGTERM (Snakemake, SLURM) writes a checkpoint next to its output
# (.{case}_{variant}.ckpt); the rerun continues from it (--restart auto), bit-identically.


def da_ab_source(case):
    return "computed" if case in USER_CASES else config["da"]["ab_source"]


def da_inputs(wc):
    inputs = {"warm": WARM}
    if wc.case in USER_CASES:
        inputs["source"] = da_source(wc.case)
    if wc.variant == "deposition" and da_ab_source(wc.case) == "computed":
        inputs["coefficients"] = f"{RESULTS}/regression/coefficients.csv"
    return inputs


def da_options(wc, input):
    if wc.variant == "nodeposition":
        return "--no-deposition"
    if da_ab_source(wc.case) == "computed":
        return f"--ab-source computed --coefficients {input.coefficients}"
    return "--ab-source paper"


rule da_run:
    input:
        unpack(da_inputs),
    output:
        f"{RESULTS}/da/{{case}}_{{variant}}.nc",
    params:
        source=lambda wc: da_source(wc.case),
        options=da_options,
        n_particles=config["da"]["n_particles"],
    log:
        f"{LOGS}/da/{{case}}_{{variant}}.log",
    benchmark:
        f"{BENCH}/da/{{case}}_{{variant}}.tsv"
    threads: config["da"]["threads"]
    resources:
        runtime=30,
        mem_mb=2000,
    shell:
        "NUMBA_NUM_THREADS={threads} granudep da {params.source} {params.options}"
        " --n-particles {params.n_particles} --restart auto -o {output} > {log} 2>&1"
