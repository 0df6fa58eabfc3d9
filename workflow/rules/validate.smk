# Parse-time validation: every job's stage config is built here with the stage's
# own builder, from the same values the rule's shell command passes to `granudep`, so
# `snakemake -n` refuses exactly what the jobs would, in one line, before any job runs.
# (Keep each job below in step with its rule's command line.)

from granudep.workflow_check import da_job, isph_job, monitor_job, check_jobs, user_case_mapping


def _user_index(case):
    return [c["name"] for c in config["user_cases"]].index(case)


def _isph_case_key(case):
    for section in ("cases", "table5_geometries"):
        if case in config["isph"][section]:
            return ("isph", section, config["isph"][section].index(case))
    return ("user_cases", _user_index(case))


def _isph_source(case):
    return user_case_mapping(USER_CASES[case]) if case in USER_CASES else case


def _geometry_keys(case):
    return {"geometry": ("user_cases", _user_index(case), "*"), "case": ("user_cases", _user_index(case), "name")} \
        if case in USER_CASES else {}


def _isph_set_keys():
    return {k: ("isph", "set", k) for k in config["isph"].get("set", {})}


def _isph_t_end():
    return config["isph"].get("t_end") or None


def _validation_jobs():
    jobs = []
    dx_per_case = config["isph"]["dx_per_case"]
    for case in ISPH_CASES:  # rule isph_run
        keys = {"numerics.dx": ("isph", "dx_per_case", case) if case in dx_per_case else ("isph", "dx"),
                "numerics.t_end": ("isph", "t_end"), **_isph_set_keys(), **_geometry_keys(case)}
        jobs.append(isph_job(f"isph run {case!r}", _isph_source(case), _isph_case_key(case), keys,
                             dx=isph_dx(case), t_end=_isph_t_end(), **config["isph"].get("set", {})))
    for name, opts in FIG6_RUNS.items():  # rule isph_fig6
        keys = {"numerics.dx": ("fig6", "dx"), "numerics.t_end": ("isph", "t_end"), **_isph_set_keys(),
                **{k: ("fig6", "runs", name, k) for k in opts}}
        jobs.append(isph_job(f"fig6 isph run {name!r}", FIG6["config"], ("fig6", "runs", name), keys,
                             dx=FIG6.get("dx", config["isph"]["dx"]), t_end=_isph_t_end(),
                             **{**config["isph"].get("set", {}), **opts, "case": name}))
    wkeys = {"monitor.width_factor": ("monitor", "width_factor")}
    jobs.append(monitor_job("monitor", ("monitor", "width_factor"), wkeys,
                            width_factor=config["monitor"]["width_factor"]))  # rule monitor
    jobs.append(monitor_job("monitor-wm", ("monitor", "wm_cases"), {}))  # rule monitor_wm
    for case in DA_CASES + list(USER_CASES):  # rule da_run
        key = ("da", "cases", DA_CASES.index(case)) if case in DA_CASES else ("user_cases", _user_index(case))
        for variant in DA_VARIANTS:
            dep = variant == "deposition"
            src = da_ab_source(case) if dep else None
            keys = {"numerics.n_particles": ("da", "n_particles"), "deposition.ab_source": ("da", "ab_source"),
                    **_geometry_keys(case)}
            jobs.append(da_job(f"da run '{case}_{variant}'", _isph_source(case), key, keys, dep,
                               n_particles=config["da"]["n_particles"], ab_source=src,
                               coefficients=f"{RESULTS}/regression/coefficients.csv" if src == "computed" else None))
    # target `convergence`
    for j, dx in enumerate(CONV["dx"]):
        jobs.append(isph_job(f"convergence isph run dx = {dx}", CONV["isph_case"], ("convergence", "isph_case"),
                             {"numerics.dx": ("convergence", "dx", j), "numerics.t_end": ("isph", "t_end"),
                              **_isph_set_keys()},
                             dx=dx, t_end=_isph_t_end(), **config["isph"].get("set", {})))
    for j, n in enumerate(CONV["da_n_particles"]):
        for case in DA_CASES:
            for variant in DA_VARIANTS:
                dep = variant == "deposition"
                jobs.append(da_job(f"convergence da run '{case}_n{n}_{variant}'", case, ("da", "cases"),
                                   {"numerics.n_particles": ("convergence", "da_n_particles", j)}, dep,
                                   n_particles=n, ab_source="paper" if dep else None))
    # target `sensitivity`
    for sens in SENS_RUNS:
        param, _ = sens_split(sens)
        key = ("sensitivity", param, SENS[param].index(sens_split(sens)[1])) if param else ("sensitivity", "isph_case")
        if sens_sets(IsphConfig, sens) or param is None:
            jobs.append(isph_job(f"sensitivity isph run {sens!r}", sens_override(IsphConfig, sens, SENS["isph_case"]),
                                 key, {"numerics.dx": ("sensitivity", "dx"), **_isph_set_keys()}, dx=SENS["dx"],
                                 **config["isph"].get("set", {})))
        opts = {param: sens_split(sens)[1]} if sens_sets(MonitorConfig, sens) else {}
        jobs.append(monitor_job(f"sensitivity monitor {sens!r}", key, {}, width_factor=config["monitor"]["width_factor"],
                                **opts))
        jobs.append(da_job(f"sensitivity da run {sens!r}", sens_override(DAConfig, sens, SENS["da_case"]), key,
                           {"numerics.n_particles": ("da", "n_particles")}, True, n_particles=config["da"]["n_particles"],
                           ab_source="computed", coefficients=f"{SENS_DIR}/regression/{sens}/coefficients.csv"))
    return jobs


try:
    check_jobs(_validation_jobs(), CONFIG_SOURCES)
except ConfigError as _exc:
    sys.stderr.write(f"granudep: {_exc}\n")
    sys.exit(2)
