# The one declared calibration (docs/bed-law.md, "Calibration of the slip length"): the basal slip
# length L_s from the four Table 3 critical times of calibration.case (T22-A70) at the chain's dx,
# ensemble mean over the members, minimising their mean squared relative difference over a scan of
# L_s (calibration.slip_lengths_mm: the scan, then its refinement). `snakemake -j2 calibration` ->
# results/calibration/{scan,result}.csv and figures/calibration.png. Not part of `all`: its value
# is carried by config/variants/calibrated.yaml. No physics here: every job calls granudep.

CAL = config.get("calibration", {})
CAL_DIR = f"{RESULTS}/calibration"
CAL_LS = [float(v) for v in CAL.get("slip_lengths_mm", [])]


def _ls_name(v):
    return f"{float(v):g}"


def cal_set_options(ls_mm, member):
    bed = {"slip": "no_slip"} if float(ls_mm) == 0.0 else {"slip": "navier", "slip_length": float(ls_mm) / 1e3}
    return " ".join(o for o in (isph_set_options(), set_options({"wall": bed}), member_set_options(member)) if o)


rule cal_isph:
    input:
        warm=WARM,
    output:
        f"{CAL_DIR}/ls{{ls}}/m{{k}}/isph/{{case}}.nc",
    params:
        dx=lambda wc: isph_dx(wc.case),
        set=lambda wc: cal_set_options(wc.ls, wc.k),
    log:
        f"{CAL_DIR}/ls{{ls}}/m{{k}}/logs/isph/{{case}}.log",
    benchmark:
        f"{BENCH}/calibration/ls{{ls}}/m{{k}}/isph/{{case}}.tsv"
    wildcard_constraints:
        ls="[0-9]+(\\.[0-9]+)?",
        k="[0-9]+",
    threads: 1
    resources:
        runtime=60,
        mem_mb=2000,
    shell:
        "NUMBA_NUM_THREADS={threads} granudep isph {wildcards.case} --dx {params.dx} {params.set}"
        " --restart auto -o {output} > {log} 2>&1"


use rule monitor as cal_monitor with:
    input:
        warm=WARM,
        run=f"{CAL_DIR}/ls{{ls}}/m{{k}}/isph/{{case}}.nc",
    output:
        f"{CAL_DIR}/ls{{ls}}/m{{k}}/sections/{{case}}.nc",
    log:
        f"{CAL_DIR}/ls{{ls}}/m{{k}}/logs/sections/{{case}}.log",
    benchmark:
        f"{BENCH}/calibration/ls{{ls}}/m{{k}}/sections/{{case}}.tsv"


use rule regress as cal_regress with:
    input:
        sections=f"{CAL_DIR}/ls{{ls}}/m{{k}}/sections/{CAL.get('case', 'T22-A70')}.nc",
    output:
        **{k: f"{CAL_DIR}/ls{{ls}}/m{{k}}/regression/{os.path.basename(v)}" for k, v in zip(
            ("critical", "coefficients", "coefficients_nc", "table3", "table5"), REGRESSION_OUTPUTS)},
    params:
        outdir=lambda wc: f"{CAL_DIR}/ls{wc.ls}/m{wc.k}/regression",
    log:
        f"{CAL_DIR}/ls{{ls}}/m{{k}}/logs/regress.log",
    benchmark:
        f"{BENCH}/calibration/ls{{ls}}/m{{k}}/regress.tsv"


rule calibration_curve:
    input:
        [f"{CAL_DIR}/ls{_ls_name(v)}/m{k}/regression/table3_comparison.csv" for v in CAL_LS for k in MEMBER_IDS],
    output:
        scan=f"{CAL_DIR}/scan.csv",
        result=f"{CAL_DIR}/result.csv",
        figure=f"{RESULTS}/figures/calibration.png",
    params:
        case=CAL.get("case", "T22-A70"),
    log:
        f"{LOGS}/calibration.log",
    benchmark:
        f"{BENCH}/calibration.tsv"
    threads: 1
    shell:
        "granudep calibration {CAL_DIR} --case {params.case} -o {output.scan} --result {output.result}"
        " --figure {output.figure} > {log} 2>&1"


rule calibration:
    """Target: the slip-length calibration curve (not part of `all`)."""
    input:
        rules.calibration_curve.output,
