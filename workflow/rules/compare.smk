# DA runs against the 2D reference (Section 4.3, Figs 15-16): the 2D ISPH runs of the Table 5
# geometries give the reference runout and flow time (same front definition as the DA runs),
# plus any CSV listed in config `reference_tables` (e.g. a user's measurements).


rule reference:
    input:
        runs=[f"{RESULTS}/isph/{REFERENCE_2D[c]}.nc" for c in DA_CASES],
    output:
        f"{RESULTS}/compare/reference_2d.csv",
    log:
        f"{LOGS}/compare/reference.log",
    benchmark:
        f"{BENCH}/compare/reference.tsv"
    threads: 1
    resources:
        runtime=10,
        mem_mb=2000,
    shell:
        "granudep reference {input.runs} -o {output} > {log} 2>&1"


rule compare:
    input:
        da=expand(f"{RESULTS}/da/{{case}}_{{variant}}.nc", case=DA_CASES, variant=DA_VARIANTS),
        reference=f"{RESULTS}/compare/reference_2d.csv",
        extra=config["reference_tables"],
    output:
        f"{RESULTS}/compare/comparison.csv",
    log:
        f"{LOGS}/compare/compare.log",
    benchmark:
        f"{BENCH}/compare/compare.tsv"
    threads: 1
    resources:
        runtime=10,
        mem_mb=2000,
    shell:
        "granudep compare {input.da} --reference {input.reference} {input.extra} -o {output} > {log} 2>&1"
