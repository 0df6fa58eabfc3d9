# Ensembles of the 2D runs: member k = 1..K-1 of every paper 2D case starts from the lattice with
# every position moved by ensemble.jitter dx N(0, 1) (numerics.seed = k; member 0 is the chain's
# own run, results/isph/{case}.nc). Each member is monitored and regressed on its own, with the
# chain's rules; `granudep ensemble` gathers every member's numbers (claims and per-case fronts and
# rest times) into results/ensemble/, whose means and spreads the summary and claims quote.


rule isph_member:
    input:
        warm=WARM,
    output:
        f"{MEMBERS}/m{{member}}/isph/{{case}}.nc",
    params:
        dx=lambda wc: isph_dx(wc.case),
        t_end=lambda wc: f"--t-end {config['isph']['t_end']}" if config["isph"].get("t_end") else "",
        set=lambda wc: " ".join(o for o in (isph_set_options(), member_set_options(wc.member)) if o),
    log:
        f"{MEMBERS}/m{{member}}/logs/isph/{{case}}.log",
    benchmark:
        f"{BENCH}/ensemble/m{{member}}/isph/{{case}}.tsv"
    wildcard_constraints:
        case="|".join(re.escape(c) for c in PAPER_ISPH_CASES) or "^$",
    threads: config["isph"]["threads"]
    resources:
        runtime=240,
        mem_mb=4000,
    shell:
        "NUMBA_NUM_THREADS={threads} granudep isph {wildcards.case} --dx {params.dx} {params.t_end} {params.set}"
        " --restart auto -o {output} > {log} 2>&1"


use rule monitor as monitor_member with:
    input:
        warm=WARM,
        run=f"{MEMBERS}/m{{member}}/isph/{{case}}.nc",
    output:
        f"{MEMBERS}/m{{member}}/sections/{{case}}.nc",
    log:
        f"{MEMBERS}/m{{member}}/logs/sections/{{case}}.log",
    benchmark:
        f"{BENCH}/ensemble/m{{member}}/sections/{{case}}.tsv"


use rule regress as regress_member with:
    input:
        sections=lambda wc: [f"{MEMBERS}/m{wc.member}/sections/{c}.nc" for c in REGRESS_CASES],
    output:
        **{k: f"{MEMBERS}/m{{member}}/regression/{os.path.basename(v)}" for k, v in zip(
            ("critical", "coefficients", "coefficients_nc", "table3", "table5"), REGRESSION_OUTPUTS)},
    params:
        outdir=lambda wc: f"{MEMBERS}/m{wc.member}/regression",
    log:
        f"{MEMBERS}/m{{member}}/logs/regress.log",
    benchmark:
        f"{BENCH}/ensemble/m{{member}}/regress.tsv"


rule ensemble:
    """Every member's claims and per-case numbers, and their mean, min-max and std."""
    input:
        runs=[member_file(k, "isph", c) for k in MEMBER_IDS for c in PAPER_ISPH_CASES],
        regression=[f"{member_root(k)}/regression/{os.path.basename(p)}" for k in MEMBER_IDS
                    for p in REGRESSION_OUTPUTS],
        # the DA-vs-2D comparison against each member's 2D runs (compare.smk, compare_member)
        compare=[f"{member_root(k)}/compare/reading_matrix_maxima.csv" for k in MEMBER_IDS],
    output:
        claims=f"{MEMBERS}/claims_members.csv",
        quantities=f"{MEMBERS}/quantities.csv",
    params:
        roots=" ".join(member_root(k) for k in MEMBER_IDS),
        cases=" ".join(PAPER_ISPH_CASES),
    log:
        f"{LOGS}/ensemble.log",
    benchmark:
        f"{BENCH}/ensemble.tsv"
    threads: 1
    resources:
        runtime=10,
        mem_mb=2000,
    shell:
        "granudep ensemble {params.roots} --cases {params.cases} -o {output.claims} --quantities {output.quantities}"
        " > {log} 2>&1"
