# Shared helpers: case lists and target paths read from the validated config. No physics here.

import os
import sys

from snakemake.exceptions import WorkflowError

# Run the `granudep` of the environment Snakemake itself runs in (also when Snakemake is called as
# .venv/bin/snakemake without activating the environment).
os.environ["PATH"] = os.path.dirname(sys.executable) + os.pathsep + os.environ.get("PATH", "")

# every output under one folder (config results_dir): results, or results/variants/<name> for a
# variant chain (config/variants/*.yaml), whose scorecard the reproduction's summary shows
RESULTS = config.get("results_dir", "results")

# Our numbers quoted in the report captions (workflow/report/*.rst read
# snakemake.config["_caption_numbers"][...]): written from the outputs by the summary rule, read
# here when the workflow is parsed, so `snakemake --report` quotes the files it reports on. A
# missing or unreadable file leaves the captions saying "not computed yet"; it never stops a run.
config["_caption_numbers"] = {}
if os.path.isfile(f"{RESULTS}/caption_numbers.json"):
    import json

    try:
        with open(f"{RESULTS}/caption_numbers.json") as _fh:
            config["_caption_numbers"] = json.load(_fh)
    except (OSError, ValueError) as _exc:
        print(f"granudep: report caption numbers not read: {_exc}", file=sys.stderr)
LOGS = f"{RESULTS}/logs"
BENCH = f"{RESULTS}/benchmarks"
WARM = f"{RESULTS}/.numba_warm"

USER_CASES = {c["name"]: c for c in config.get("user_cases", [])}

# DA runs on the user's slope profiles: name -> entry {name, config, n_particles?}. The
# YAML (with geometry.path) and its path CSV are the runs' inputs; both must exist when parsing.
PATH_CASES = {c["name"]: c for c in config.get("path_cases", [])}


def _path_csv(entry):
    import yaml

    cfg_file = entry["config"]
    if not os.path.isfile(cfg_file):
        raise WorkflowError(f"config path_cases: {entry['name']}: config file {cfg_file!r} not found")
    with open(cfg_file) as fh:
        data = yaml.safe_load(fh) or {}
    csv = ((data.get("geometry") or {}).get("path") or {}).get("file")
    if not csv:
        raise WorkflowError(f"config path_cases: {entry['name']}: {cfg_file} has no geometry.path.file "
                            "(a DA config on a path profile, see config/da/example_path.yaml)")
    if not os.path.isfile(csv) and not os.path.isabs(csv):  # as granudep: else next to the YAML
        csv = os.path.join(os.path.dirname(cfg_file), csv)
    if not os.path.isfile(csv):
        raise WorkflowError(f"config path_cases: {entry['name']}: path file {csv!r} (geometry.path.file in "
                            f"{cfg_file}; relative to the repository root or to the YAML) not found")
    return csv


PATH_CSV = {name: _path_csv(entry) for name, entry in PATH_CASES.items()}
_clash = sorted(set(PATH_CASES) & set(USER_CASES))
if _clash:
    raise WorkflowError(f"config path_cases: {', '.join(_clash)} also in user_cases (names become file names)")

# 2D ISPH runs: every Table 1 case, the Table 5 geometries at 22 deg, and the user's cases.
PAPER_ISPH_CASES = list(dict.fromkeys(config["isph"]["cases"] + config["isph"]["table5_geometries"]))
ISPH_CASES = list(dict.fromkeys(PAPER_ISPH_CASES + list(USER_CASES)))
# The regression (A, B tables) uses the paper's 2D runs only.
REGRESS_CASES = PAPER_ISPH_CASES
DA_CASES = list(config["da"]["cases"])
DA_VARIANTS = list(config["da"]["variants"])
# Table 5 geometries whose 2D runs are the DA reference (only those of the DA cases that run).
_missing = [c for c in DA_CASES if c not in config["da"]["reference_2d"]]
if _missing:
    raise WorkflowError(
        f"config da.reference_2d: no 2D reference run for {', '.join(_missing)} "
        "(map each DA case to the ISPH case of the same geometry, e.g. 1D-A70: T22-A70)"
    )
REFERENCE_2D = {c: config["da"]["reference_2d"][c] for c in DA_CASES}

# The paper's Fig 6 column (config fig6): its case YAML and its runs, name -> --set options.
FIG6 = config.get("fig6", {})
FIG6_RUNS = dict(FIG6.get("runs", {}))
if FIG6_RUNS:
    if not os.path.isfile(FIG6.get("config", "")):
        raise WorkflowError(f"config fig6.config: file {FIG6.get('config')!r} not found (the Fig 6 case YAML, "
                            "e.g. config/isph/fig6-quartz-a7.yaml)")
    _clash = sorted(set(FIG6_RUNS) & (set(ISPH_CASES) | set(PATH_CASES)))
    if _clash:
        raise WorkflowError(f"config fig6.runs: {', '.join(_clash)} also a 2D case name (names become file names)")
WM_CASES = [c for c in config["monitor"]["wm_cases"] if c in ISPH_CASES]


def isph_dx(case):
    """Initial particle spacing of one 2D run (per-case override, else the global dx)."""
    return config["isph"]["dx_per_case"].get(case, config["isph"]["dx"])


def set_options(mapping, prefix=""):
    """``--set KEY=VALUE`` for every leaf of a (nested) mapping, keys dotted, values written as YAML
    scalars (a name such as '123' stays a string), quoted for the shell."""
    import shlex
    import yaml

    out = []
    for key, value in mapping.items():
        if isinstance(value, dict):
            out.append(set_options(value, f"{prefix}{key}."))
            continue
        text = yaml.safe_dump(value, default_flow_style=True).strip().removesuffix("...").strip()
        out.append(f"--set {shlex.quote(f'{prefix}{key}={text}')}")
    return " ".join(o for o in out if o)


def isph_set_options():
    """The scheme options of every 2D run (config ``isph.set``, e.g. numerics.projection: adjoint_pair)."""
    return set_options(config["isph"].get("set", {}))


def isph_source(case):
    """What `granudep isph` is given: a paper case name, or the generated YAML of a user case."""
    return f"{RESULTS}/user_cases/{case}.yaml" if case in USER_CASES else case


def da_source(case):
    return f"{RESULTS}/user_cases/{case}.yaml" if case in USER_CASES else case


def fig_cases(name):
    """Cases a figure shows: the configured list, restricted to the 2D runs this config makes."""
    return [c for c in config["figures"].get(name, []) if c in ISPH_CASES]


# Paper figure -> output file (names after the paper's figure numbers).
FIGURES = {
    "fig5": "fig5_free_surface.png",
    "fig6": "fig6_fd_interface_flat.png",
    "fig7": "fig7_fd_interface.png",
    "fig8": "fig8_total_depth.png",
    "fig9": "fig9_deposit_depth.png",
    "fig10": "fig10_velocity_profiles.png",
    "fig11": "fig11_momentum.png",
    "fig12": "fig12_critical_momentum.png",
    "fig13": "fig13_coefficients.png",
    "fig15": "fig15_runout_time.png",
    "fig16": "fig16_runout_flowtime.png",
    "fig17": "fig17_depth_profiles.png",
    "figA1": "figA1_wm_momentum.png",
    "figA2": "figA2_wm_rms.png",
    "figA3": "figA3_fd_interface_all.png",
}


def figure_path(name):
    return f"{RESULTS}/figures/{FIGURES[name]}"


# figures drawn only when their inputs exist in this configuration
ACTIVE_FIGURES = [
    name
    for name in FIGURES
    if not (name in ("figA1", "figA2") and not WM_CASES)
    and not (name in ("fig5", "fig7", "fig8", "fig9", "fig10", "fig11", "figA3") and not fig_cases(name))
    and not (name == "fig6" and not FIG6_RUNS)
]

# Ensembles (config ensemble): member 0 is the chain's own run; members 1..K-1 live under MEMBERS.
MEMBERS = f"{RESULTS}/ensemble"
ENSEMBLE = config.get("ensemble", {})
MEMBER_IDS = list(range(int(ENSEMBLE.get("members", 1))))


def member_root(k):
    """The results folder of member k: the chain's own for member 0."""
    return RESULTS if int(k) == 0 else f"{MEMBERS}/m{k}"


def member_file(k, stage, case):
    return f"{member_root(k)}/{stage}/{case}.nc"


def member_set_options(k):
    """The --set options that make member k (seed k, the configured jitter)."""
    return set_options({"numerics": {"seed": int(k), "jitter": float(ENSEMBLE.get("jitter", 0.01))}}) if int(k) else ""


REGRESSION_OUTPUTS = [
    f"{RESULTS}/regression/critical.csv",
    f"{RESULTS}/regression/coefficients.csv",
    f"{RESULTS}/regression/coefficients.nc",
    f"{RESULTS}/regression/table3_comparison.csv",
    f"{RESULTS}/regression/table5_comparison.csv",
]

ALL_TARGETS = (
    [f"{RESULTS}/isph/{c}.nc" for c in ISPH_CASES]
    + [f"{RESULTS}/isph/{n}.nc" for n in FIG6_RUNS]
    + [f"{RESULTS}/sections/{c}.nc" for c in ISPH_CASES]
    + [f"{RESULTS}/wm/{c}.nc" for c in WM_CASES]
    + REGRESSION_OUTPUTS
    + [f"{RESULTS}/da/{c}_{v}.nc" for c in DA_CASES + list(USER_CASES) for v in DA_VARIANTS]
    + [f"{RESULTS}/compare/reference_2d.csv", f"{RESULTS}/compare/comparison.csv"]
    + [f"{RESULTS}/verification/da.csv", f"{RESULTS}/verification/isph.csv"]
    + [figure_path(n) for n in ACTIVE_FIGURES]
    + ([f"{MEMBERS}/claims_members.csv", f"{MEMBERS}/quantities.csv"] if len(MEMBER_IDS) > 1 else [])
    + [f"{RESULTS}/summary.md", f"{RESULTS}/caption_numbers.json", f"{RESULTS}/benchmarks/summary.csv"]
    + [f"{RESULTS}/da_path/{c}_{v}.nc" for c in PATH_CASES for v in DA_VARIANTS]
    + [f"{RESULTS}/figures/path_{c}.png" for c in PATH_CASES]
)
