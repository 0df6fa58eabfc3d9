# Analytic verification suites of the two solvers (dam breaks, Bagnold profile, conservation...),
# as tables the report and summary read.

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


rule verify_isph:
    input:
        warm=WARM,
    output:
        f"{RESULTS}/verification/isph.csv",
    params:
        quick=VERIFY_QUICK,
    log:
        f"{LOGS}/verification/isph.log",
    benchmark:
        f"{BENCH}/verification/isph.tsv"
    threads: 1
    resources:
        runtime=60,
        mem_mb=4000,
    shell:
        "NUMBA_NUM_THREADS={threads} granudep verify isph {params.quick} -o {output} > {log} 2>&1"
