# Analytic verification suites of the two solvers (dam breaks, Bagnold profile, conservation...),
# as tables the report and summary read. `granudep verify` exits 1 when a checked row (one with a
# finite tolerance) fails, so the workflow, and the CI smoke run, stop on a failed verification;
# rows without a finite tolerance are reported and never stop it (`--report-only` is not used here).

VERIFY_QUICK = "--quick" if config["verify"]["quick"] else ""


rule verify_da:
    input:
        warm=WARM,
    output:
        f"{RESULTS}/verification/da.csv",
    params:
        quick=VERIFY_QUICK,
    log:
        f"{LOGS}/verification/da.log",
    benchmark:
        f"{BENCH}/verification/da.tsv"
    threads: 1
    resources:
        runtime=30,
        mem_mb=2000,
    shell:
        "NUMBA_NUM_THREADS={threads} granudep verify da {params.quick} -o {output} > {log} 2>&1"


# The ISPH suite in parts that -j2 runs side by side (the Bagnold layers take most of the time),
# merged in table order. `all` runs the cheap checked rows and the rows at the chain's dx (4 mm);
# the fine-resolution rows (0.5 mm layers, 2 mm dam break) are the `verify_fine` target's
# (results/verification/isph_fine.csv), also run by `pytest -m slow`.
VERIFY_ISPH_PARTS = {
    "steady": "hydrostatic,film_flow,navier_film,sliding_block,decelerating_layer",
    "bagnold": "bagnold",
    "navier_bagnold": "navier_bagnold",
    "transient": "dam_break,dam_break_approximate,collapse_t22a70",
}
VERIFY_ISPH_FINE_PARTS = {
    "bagnold_fine": "bagnold_fine",
    "navier_bagnold_fine": "navier_bagnold_fine",
    "other_fine": "decelerating_layer_fine,dam_break_fine",
}


rule verify_isph_part:
    input:
        warm=WARM,
    output:
        temp(f"{RESULTS}/verification/isph.{{part}}.csv"),
    params:
        quick=VERIFY_QUICK,
        checks=lambda wc: (VERIFY_ISPH_PARTS | VERIFY_ISPH_FINE_PARTS)[wc.part],
    log:
        f"{LOGS}/verification/isph.{{part}}.log",
    benchmark:
        f"{BENCH}/verification/isph.{{part}}.tsv"
    wildcard_constraints:
        part="|".join(VERIFY_ISPH_PARTS | VERIFY_ISPH_FINE_PARTS),
    # the Bagnold parts are long leaves: started first, they run beside the case runs, not after them
    priority: 50
    threads: 1
    resources:
        runtime=60,
        mem_mb=4000,
    shell:
        "NUMBA_NUM_THREADS={threads} granudep verify isph {params.quick} --checks {params.checks} -o {output} "
        "> {log} 2>&1"


rule verify_isph:
    input:
        parts=[f"{RESULTS}/verification/isph.{part}.csv" for part in VERIFY_ISPH_PARTS],
    output:
        f"{RESULTS}/verification/isph.csv",
    log:
        f"{LOGS}/verification/isph.log",
    benchmark:
        f"{BENCH}/verification/isph.tsv"
    threads: 1
    resources:
        runtime=5,
        mem_mb=1000,
    shell:
        "granudep verify isph --merge {input.parts} -o {output} > {log} 2>&1"


rule verify_isph_fine:
    """The fine-resolution rows of the ISPH suite (the 0.5 mm Bagnold and Navier-Bagnold layers, the
    2 mm reported layers, the 10 mm layer at 1 mm, the 2 mm dam break): `snakemake -j2 verify_fine`."""
    input:
        parts=[f"{RESULTS}/verification/isph.{part}.csv" for part in VERIFY_ISPH_FINE_PARTS],
    output:
        f"{RESULTS}/verification/isph_fine.csv",
    log:
        f"{LOGS}/verification/isph_fine.log",
    benchmark:
        f"{BENCH}/verification/isph_fine.tsv"
    threads: 1
    resources:
        runtime=5,
        mem_mb=1000,
    shell:
        "granudep verify isph --merge {input.parts} -o {output} > {log} 2>&1"


rule verify_fine:
    """Target: the fine-resolution verification rows (not part of `all`; the summary shows them when
    they have run)."""
    input:
        f"{RESULTS}/verification/isph_fine.csv",
