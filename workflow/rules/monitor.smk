# Monitoring sections (Section 3, eqs 15-17): 11 sections from the gate to the 2D run's final
# runout; depth-averaged velocity, flowing/deposit depth, hu per section and output time.


rule monitor:
    input:
        warm=WARM,
        run=f"{RESULTS}/isph/{{case}}.nc",
    output:
        f"{RESULTS}/sections/{{case}}.nc",
    params:
        width_factor=config["monitor"]["width_factor"],
        options="",  # extra `granudep monitor` options (the sensitivity runs set one)
    log:
        f"{LOGS}/sections/{{case}}.log",
    benchmark:
        f"{BENCH}/sections/{{case}}.tsv"
    threads: 1
    resources:
        runtime=30,
        mem_mb=4000,
    shell:
        "NUMBA_NUM_THREADS={threads} granudep monitor {input.run} --width-factor {params.width_factor}"
        " {params.options} -o {output} > {log} 2>&1"


rule monitor_wm:
    """Appendix: hu/p0 for W_M = 1..4 dx and the RMS deviation from W_M = 2 dx (Figs A1, A2)."""
    input:
        warm=WARM,
        run=f"{RESULTS}/isph/{{case}}.nc",
    output:
        f"{RESULTS}/wm/{{case}}.nc",
    log:
        f"{LOGS}/wm/{{case}}.log",
    benchmark:
        f"{BENCH}/wm/{{case}}.tsv"
    threads: 1
    resources:
        runtime=30,
        mem_mb=4000,
    shell:
        "NUMBA_NUM_THREADS={threads} granudep monitor-wm {input.run} -o {output} > {log} 2>&1"
