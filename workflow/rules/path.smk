# DA runs on the user's slope profiles (`path_cases:` in the config): each entry's YAML
# (geometry.path, see config/da/example_path.yaml) runs with and without deposition (da.variants),
# A and B as that YAML says; then the profile figure with the deposit and the envelopes.


def path_inputs(wc):
    return {"warm": WARM, "config": PATH_CASES[wc.case]["config"], "csv": PATH_CSV[wc.case]}


def path_options(wc):
    opts = ["--no-deposition"] if wc.variant == "nodeposition" else []
    n = PATH_CASES[wc.case].get("n_particles")
    if n:
        opts.append(f"--n-particles {n}")
    return " ".join(opts)


rule da_path_run:
    input:
        unpack(path_inputs),
    output:
        f"{RESULTS}/da_path/{{case}}_{{variant}}.nc",
    params:
        options=path_options,
    log:
        f"{LOGS}/da_path/{{case}}_{{variant}}.log",
    benchmark:
        f"{BENCH}/da_path/{{case}}_{{variant}}.tsv"
    threads: config["da"]["threads"]
    resources:
        runtime=60,
        mem_mb=2000,
    shell:
        "NUMBA_NUM_THREADS={threads} granudep da {input.config} {params.options} -o {output} > {log} 2>&1"


rule figure_path:
    input:
        lambda wc: [f"{RESULTS}/da_path/{wc.case}_{v}.nc" for v in DA_VARIANTS],
    output:
        report(f"{RESULTS}/figures/path_{{case}}.png", caption="../report/path.rst",
               category="Runout on a path profile", subcategory="{case}"),
    log:
        f"{LOGS}/figures/path_{{case}}.log",
    benchmark:
        f"{BENCH}/figures/path_{{case}}.tsv"
    threads: 1
    resources:
        runtime=10,
        mem_mb=2000,
    shell:
        "MPLBACKEND=Agg granudep path-figure -o {output} {input} > {log} 2>&1"
