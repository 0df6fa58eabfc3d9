# 2D ISPH with the mu(I) rheology (Sections 2.1-2.2): every Table 1 case, the Table 5 geometries
# at 22 deg, any user case, and the Fig 6 column's runs. Output: results/isph/{case}.nc (particles x time).
# A run cancelled by SIGTERM (Snakemake, SLURM) writes a checkpoint next to its output
# (.{case}.ckpt); the rerun continues from it (--restart auto), bit-identically.


import re

from granudep.workflow_check import user_case_mapping


rule user_case_config:
    """A user case from config `user_cases` as the YAML file the granudep CLIs read."""
    output:
        f"{RESULTS}/user_cases/{{case}}.yaml",
    params:
        set=lambda wc: set_options(user_case_mapping(USER_CASES[wc.case])),
    log:
        f"{LOGS}/user_cases/{{case}}.log",
    benchmark:
        f"{BENCH}/user_cases/{{case}}.tsv"
    threads: 1
    shell:
        "granudep config write -o {output} {params.set} > {log} 2>&1"


rule isph_run:
    input:
        warm=WARM,
        source=lambda wc: [isph_source(wc.case)] if wc.case in USER_CASES else [],
    output:
        f"{RESULTS}/isph/{{case}}.nc",
    params:
        source=lambda wc: isph_source(wc.case),
        dx=lambda wc: isph_dx(wc.case),
        t_end=lambda wc: f"--t-end {config['isph']['t_end']}" if config["isph"].get("t_end") else "",
        set=isph_set_options(),
    log:
        f"{LOGS}/isph/{{case}}.log",
    benchmark:
        f"{BENCH}/isph/{{case}}.tsv"
    threads: config["isph"]["threads"]
    resources:
        runtime=240,
        mem_mb=4000,
    shell:
        "NUMBA_NUM_THREADS={threads} granudep isph {params.source} --dx {params.dx} {params.t_end} {params.set}"
        " --restart auto -o {output} > {log} 2>&1"


if FIG6_RUNS:

    # results/isph/{name}.nc of a Fig 6 run is this rule's, not isph_run's (whose {case} matches any name)
    ruleorder: isph_fig6 > isph_run

    rule isph_fig6:
        """The paper's Fig 6 column (config fig6): its case YAML at fig6.dx, with the scheme options of
        every 2D run (isph.set) and the run's own (fig6.runs, e.g. wall.slip: no_slip)."""
        input:
            warm=WARM,
            config=FIG6["config"],
        output:
            f"{RESULTS}/isph/{{fig6run}}.nc",
        wildcard_constraints:
            fig6run="|".join(re.escape(n) for n in FIG6_RUNS),
        params:
            dx=FIG6.get("dx", config["isph"]["dx"]),
            t_end=lambda wc: f"--t-end {config['isph']['t_end']}" if config["isph"].get("t_end") else "",
            set=lambda wc: " ".join(o for o in (isph_set_options(), set_options(FIG6_RUNS[wc.fig6run])) if o),
        log:
            f"{LOGS}/isph/{{fig6run}}.log",
        benchmark:
            f"{BENCH}/isph/{{fig6run}}.tsv"
        threads: 1
        resources:
            runtime=60,
            mem_mb=2000,
        shell:
            "NUMBA_NUM_THREADS={threads} granudep isph {input.config} --dx {params.dx} {params.t_end} {params.set}"
            " --set case={wildcards.fig6run} --restart auto -o {output} > {log} 2>&1"
