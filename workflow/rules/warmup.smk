# Compile and cache every numba kernel once, before parallel jobs start: two jobs writing the
# same numba cache at once can race (see ../shared/tips.md). Every numba-using rule needs WARM.


rule warmup:
    output:
        touch_flag=WARM,
    log:
        f"{LOGS}/warmup.log",
    benchmark:
        f"{BENCH}/warmup.tsv"
    threads: 1
    resources:
        runtime=30,
        mem_mb=2000,
    shell:
        "NUMBA_NUM_THREADS={threads} granudep warmup da isph monitor --touch {output.touch_flag} > {log} 2>&1"
