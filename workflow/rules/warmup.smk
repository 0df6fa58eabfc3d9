# Compile and cache every numba kernel once, before parallel jobs start: two jobs writing the
# same numba cache at once can race (see ../shared/tips.md). Every numba-using rule needs WARM.
# `granudep warmup` offers da and isph; the monitor kernels are warmed through their API first
# (plumbing only, until the CLI's warmup takes `monitor` too).


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
    params:
        python=sys.executable,
    shell:
        "(export NUMBA_NUM_THREADS={threads};"
        " {params.python} -c 'from granudep.monitor.api import warmup; warmup()'"
        " && granudep warmup da isph --touch {output.touch_flag}) > {log} 2>&1"
