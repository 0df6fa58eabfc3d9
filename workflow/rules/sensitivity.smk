# Sensitivity study (beyond the paper): one parameter at a time away from its paper value
# -> its effect on A, B (eq 36) and on the DA runout. Target `sensitivity`, not in `all`.
#   phi_internal_deg, phi_basal_deg: rerun the 2D case (coarser dx) and the DA case with the angle
#   free_surface_threshold: rerun the 2D case with the ISPH free-surface ∇·r threshold (paper 1.6)
#   critical_speed, divergence_threshold: re-monitor the baseline 2D run (eq 16 threshold, 0.1 m/s)
# Each run is named {sens} = "baseline" or "{parameter}_{value}".

SENS = config["sensitivity"]
SENS_DIR = f"{RESULTS}/sensitivity"
SENS_PARAMS = ("phi_internal_deg", "phi_basal_deg", "critical_speed", "divergence_threshold", "free_surface_threshold")
SENS_RUNS = ["baseline"] + [f"{p}_{v}" for p in SENS_PARAMS for v in SENS.get(p, [])]
# A parameter is set in every stage whose config has a key of that name (one name per quantity across
# stages, granudep.config.overrides_mapping): the friction angles in the 2D and the DA runs, the ∇·r
# threshold of the free surface in the 2D run, critical_speed and divergence_threshold in the monitor.
from granudep.config import dotted_key, merge, overrides_mapping
from granudep.da.config import DAConfig
from granudep.isph.config import IsphConfig
from granudep.monitor.config import MonitorConfig


def sens_split(sens):
    """'phi_basal_deg_23.5' -> ('phi_basal_deg', 23.5); 'baseline' -> (None, None)."""
    if sens == "baseline":
        return None, None
    param, value = sens.rsplit("_", 1)
    return param, float(value)


def sens_sets(stage, sens):
    """Whether {sens} changes a key of this stage's config (IsphConfig, DAConfig, MonitorConfig)."""
    param, _ = sens_split(sens)
    return param is not None and dotted_key(stage, param) is not None


def sens_isph_run(sens):
    """The 2D run a sensitivity run monitors: its own rerun for a 2D key, else the baseline."""
    return sens if sens_sets(IsphConfig, sens) else "baseline"


def sens_override(stage, sens, case):
    """The run's config: the paper case, or, with a changed key, a run of its own name
    (a paper case name stands for the paper's geometry and material; the stages refuse it)."""
    if not sens_sets(stage, sens):
        return {"case": case}
    param, value = sens_split(sens)
    own = {"case": f"{case}-{sens}".replace(".", "p"), "geometry": PAPER_GEOMETRY[case]}
    return merge(own, overrides_mapping(stage, {param: value}))


def _paper_geometry(case):
    if case.startswith("1D-"):
        from granudep.da.config import case_mapping

        return case_mapping(case)["geometry"]
    from granudep.isph.config import case_geometry

    return case_geometry(case)


PAPER_GEOMETRY = {c: _paper_geometry(c) for c in (SENS["isph_case"], SENS["da_case"])}


wildcard_constraints:
    sens="baseline|[a-z_]+_-?[0-9]+(\\.[0-9]+)?",


rule sensitivity_config:
    """Config YAML (case + the one changed key) for the 2D (isph) or DA (da) run of {sens}."""
    output:
        f"{SENS_DIR}/config/{{stage}}_{{sens}}.yaml",
    wildcard_constraints:
        stage="isph|da",
    params:
        set=lambda wc: set_options(
            sens_override(IsphConfig, wc.sens, SENS["isph_case"])
            if wc.stage == "isph"
            else sens_override(DAConfig, wc.sens, SENS["da_case"])
        ),
    log:
        f"{LOGS}/sensitivity/config/{{stage}}_{{sens}}.log",
    benchmark:
        f"{BENCH}/sensitivity/config/{{stage}}_{{sens}}.tsv"
    threads: 1
    shell:
        "granudep config write -o {output} {params.set} > {log} 2>&1"


# The chain isph -> monitor -> regress -> da is the main rules (isph.smk, monitor.smk, regress.smk,
# da.smk) with the run's config file, the sensitivity dx and the monitor key of {sens}.


use rule isph_run as sensitivity_isph with:
    input:
        warm=WARM,
        config=f"{SENS_DIR}/config/isph_{{sens}}.yaml",
    output:
        f"{SENS_DIR}/isph/{{sens}}.nc",
    params:
        source=lambda wc, input: input.config,
        dx=SENS["dx"],
        t_end="",
    log:
        f"{LOGS}/sensitivity/isph/{{sens}}.log",
    benchmark:
        f"{BENCH}/sensitivity/isph/{{sens}}.tsv"


def sens_monitor_options(wc):
    param, value = sens_split(wc.sens)
    return f"--set {param}={value}" if sens_sets(MonitorConfig, wc.sens) else ""


use rule monitor as sensitivity_monitor with:
    input:
        warm=WARM,
        run=lambda wc: f"{SENS_DIR}/isph/{sens_isph_run(wc.sens)}.nc",
    output:
        f"{SENS_DIR}/sections/{{sens}}.nc",
    params:
        options=sens_monitor_options,
    log:
        f"{LOGS}/sensitivity/sections/{{sens}}.log",
    benchmark:
        f"{BENCH}/sensitivity/sections/{{sens}}.tsv"


use rule regress as sensitivity_regress with:
    input:
        sections=f"{SENS_DIR}/sections/{{sens}}.nc",
    output:
        critical=f"{SENS_DIR}/regression/{{sens}}/critical.csv",
        coefficients=f"{SENS_DIR}/regression/{{sens}}/coefficients.csv",
    params:
        outdir=f"{SENS_DIR}/regression/{{sens}}",
    log:
        f"{LOGS}/sensitivity/regression/{{sens}}.log",
    benchmark:
        f"{BENCH}/sensitivity/regression/{{sens}}.tsv"


use rule da_run as sensitivity_da with:
    input:
        warm=WARM,
        config=f"{SENS_DIR}/config/da_{{sens}}.yaml",
        coefficients=f"{SENS_DIR}/regression/{{sens}}/coefficients.csv",
    output:
        f"{SENS_DIR}/da/{{sens}}.nc",
    params:
        source=lambda wc, input: input.config,
        options=lambda wc, input: f"--ab-source computed --coefficients {input.coefficients}",
    log:
        f"{LOGS}/sensitivity/da/{{sens}}.log",
    benchmark:
        f"{BENCH}/sensitivity/da/{{sens}}.tsv"
    threads: 1


rule sensitivity_table:
    """parameter, value, A, B, final_runout_norm, flow_time per run (the baseline at the paper value)."""
    input:
        coefficients=expand(f"{SENS_DIR}/regression/{{sens}}/coefficients.csv", sens=SENS_RUNS),
        da=expand(f"{SENS_DIR}/da/{{sens}}.nc", sens=SENS_RUNS),
    output:
        f"{SENS_DIR}/sensitivity.csv",
    params:
        baseline=" ".join(f"{k}={v}" for k, v in SENS["paper_values"].items()),
        runs=" ".join(
            f"{r}={SENS_DIR}/regression/{r}/coefficients.csv,{SENS_DIR}/da/{r}.nc" for r in SENS_RUNS
        ),
    log:
        f"{LOGS}/sensitivity/table.log",
    benchmark:
        f"{BENCH}/sensitivity/table.tsv"
    threads: 1
    shell:
        "granudep sensitivity-table -o {output} --baseline-values {params.baseline} -- {params.runs} > {log} 2>&1"


rule figure_sensitivity:
    input:
        f"{SENS_DIR}/sensitivity.csv",
    output:
        report(f"{RESULTS}/figures/sensitivity.png", caption="../report/sensitivity.rst", category="Sensitivity"),
    log:
        f"{LOGS}/figures/sensitivity.log",
    benchmark:
        f"{BENCH}/figures/sensitivity.tsv"
    threads: 1
    shell:
        "MPLBACKEND=Agg granudep figure sensitivity -o {output} {input} > {log} 2>&1"


rule sensitivity:
    """Target: every sensitivity run and its figure."""
    input:
        f"{RESULTS}/figures/sensitivity.png",
