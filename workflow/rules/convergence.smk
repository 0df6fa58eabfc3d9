# Convergence study: T22-A70 in 2D at three particle spacings (runout, flow time,
# critical times) and the DA cases at three particle counts. Target `convergence`, not in `all`.

CONV = config["convergence"]
CONV_DIR = f"{RESULTS}/convergence"


# The chain isph -> monitor -> regress and the DA runs are the main rules (isph.smk, monitor.smk,
# regress.smk, da.smk) with other file names and the spacing / particle count from the wildcards.


use rule isph_run as convergence_isph with:
    input:
        warm=WARM,
    output:
        f"{CONV_DIR}/isph/{{case}}_dx{{dx}}.nc",
    params:
        source=lambda wc: wc.case,
        dx=lambda wc: wc.dx,
    log:
        f"{LOGS}/convergence/isph/{{case}}_dx{{dx}}.log",
    benchmark:
        f"{BENCH}/convergence/isph/{{case}}_dx{{dx}}.tsv"
    resources:
        runtime=480,
        mem_mb=8000,


use rule monitor as convergence_monitor with:
    input:
        warm=WARM,
        run=f"{CONV_DIR}/isph/{{case}}_dx{{dx}}.nc",
    output:
        f"{CONV_DIR}/sections/{{case}}_dx{{dx}}.nc",
    log:
        f"{LOGS}/convergence/sections/{{case}}_dx{{dx}}.log",
    benchmark:
        f"{BENCH}/convergence/sections/{{case}}_dx{{dx}}.tsv"


use rule regress as convergence_regress with:
    input:
        sections=f"{CONV_DIR}/sections/{{case}}_dx{{dx}}.nc",
    output:
        critical=f"{CONV_DIR}/regression/{{case}}_dx{{dx}}/critical.csv",
        coefficients=f"{CONV_DIR}/regression/{{case}}_dx{{dx}}/coefficients.csv",
    params:
        outdir=f"{CONV_DIR}/regression/{{case}}_dx{{dx}}",
    log:
        f"{LOGS}/convergence/regression/{{case}}_dx{{dx}}.log",
    benchmark:
        f"{BENCH}/convergence/regression/{{case}}_dx{{dx}}.tsv"


use rule da_run as convergence_da with:
    input:
        warm=WARM,
    output:
        f"{CONV_DIR}/da/{{case}}_n{{n}}_{{variant}}.nc",
    params:
        source=lambda wc: wc.case,
        options=lambda wc: "--no-deposition" if wc.variant == "nodeposition" else "--ab-source paper",
        n_particles=lambda wc: wc.n,
    log:
        f"{LOGS}/convergence/da/{{case}}_n{{n}}_{{variant}}.log",
    benchmark:
        f"{BENCH}/convergence/da/{{case}}_n{{n}}_{{variant}}.tsv"
    threads: 1


CONVERGENCE_INPUTS = (
    expand(f"{CONV_DIR}/isph/{{case}}_dx{{dx}}.nc", case=CONV["isph_case"], dx=CONV["dx"])
    + expand(f"{CONV_DIR}/regression/{{case}}_dx{{dx}}/critical.csv", case=CONV["isph_case"], dx=CONV["dx"])
    + expand(
        f"{CONV_DIR}/da/{{case}}_n{{n}}_{{variant}}.nc",
        case=DA_CASES,
        n=CONV["da_n_particles"],
        variant=DA_VARIANTS,
    )
)


rule figure_convergence:
    input:
        CONVERGENCE_INPUTS,
    output:
        report(f"{RESULTS}/figures/convergence.png", caption="../report/convergence.rst", category="Convergence"),
    log:
        f"{LOGS}/figures/convergence.log",
    benchmark:
        f"{BENCH}/figures/convergence.tsv"
    threads: 1
    shell:
        "MPLBACKEND=Agg granudep figure convergence -o {output} {input} > {log} 2>&1"


rule convergence:
    """Target: every convergence run and its figure, and the convergence ensembles' table."""
    input:
        f"{RESULTS}/figures/convergence.png",
        f"{RESULTS}/convergence/ensemble_table.csv",


# --- Reference runs: the four Table 5 geometries at 22° and T22-A70 at the reference dx ---
# `snakemake -j2 reference_runs`; compare.reference.runs picks them up as the converged reference.
REF_DX = CONV.get("reference_dx", 0.002)
REF_CASES = CONV.get("reference_cases", ["T22-A30", "T22-A45", "T22-A70", "T22-A124"])


use rule convergence_isph as reference_isph with:
    output:
        f"{RESULTS}/reference/isph/{{case}}_dx{{dx}}.nc",
    log:
        f"{LOGS}/reference/isph/{{case}}_dx{{dx}}.log",
    benchmark:
        f"{BENCH}/reference/isph/{{case}}_dx{{dx}}.tsv"


rule reference_runs:
    """Target: the 2D reference runs at convergence.reference_dx (not part of `all`)."""
    input:
        expand(f"{RESULTS}/reference/isph/{{case}}_dx{{dx}}.nc", case=REF_CASES, dx=[REF_DX]),


# --- Convergence with the spread beside it: ensembles at a finer dx and one lattice run finer still ---
# Member k of case c at dx d lives in results/convergence/ensemble/dx{d}/m{k}/ (the layout of a chain's
# results folder, so `granudep ensemble` reads it as it reads the chain's members). The chain's own
# ensembles (results/ensemble/quantities.csv) are the coarse level.
CONV_ENS_CASES = CONV.get("ensemble_cases", [])
CONV_SINGLE_CASES = CONV.get("single_cases", CONV_ENS_CASES)
CONV_ENS_DX = CONV.get("ensemble_dx", 0.002)
CONV_SINGLE_DX = CONV.get("single_dx", 0.0014)
CONV_ENS_DIR = f"{CONV_DIR}/ensemble"


def conv_member_root(dx, k):
    return f"{CONV_ENS_DIR}/dx{dx}/m{k}"


def conv_level_cases(dx):
    """The cases run at dx: every ensemble case at ensemble_dx, single_cases at single_dx."""
    return CONV_ENS_CASES if float(dx) == float(CONV_ENS_DX) else CONV_SINGLE_CASES


def conv_level_members(dx):
    """Member ids at dx: the ensemble's at ensemble_dx, member 0 alone at single_dx."""
    return MEMBER_IDS if float(dx) == float(CONV_ENS_DX) else [0]


use rule isph_member as conv_member_isph with:
    output:
        f"{CONV_ENS_DIR}/dx{{dx}}/m{{member}}/isph/{{case}}.nc",
    params:
        dx=lambda wc: wc.dx,
        t_end=lambda wc: f"--t-end {config['isph']['t_end']}" if config["isph"].get("t_end") else "",
        set=lambda wc: " ".join(o for o in (isph_set_options(), member_set_options(wc.member)) if o),
    log:
        f"{CONV_ENS_DIR}/dx{{dx}}/m{{member}}/logs/isph/{{case}}.log",
    benchmark:
        f"{BENCH}/convergence/ensemble/dx{{dx}}/m{{member}}/isph/{{case}}.tsv"
    wildcard_constraints:
        case="|".join(re.escape(c) for c in CONV_ENS_CASES) or "^$",
        dx="[0-9.]+",
        member="[0-9]+",
    resources:
        runtime=480,
        mem_mb=8000,


use rule monitor as conv_member_monitor with:
    input:
        warm=WARM,
        run=f"{CONV_ENS_DIR}/dx{{dx}}/m{{member}}/isph/{{case}}.nc",
    output:
        f"{CONV_ENS_DIR}/dx{{dx}}/m{{member}}/sections/{{case}}.nc",
    log:
        f"{CONV_ENS_DIR}/dx{{dx}}/m{{member}}/logs/sections/{{case}}.log",
    benchmark:
        f"{BENCH}/convergence/ensemble/dx{{dx}}/m{{member}}/sections/{{case}}.tsv"
    wildcard_constraints:
        member="[0-9]+",  # member 0 (the lattice) has a folder of its own here


use rule regress as conv_member_regress with:
    input:
        sections=lambda wc: [f"{conv_member_root(wc.dx, wc.member)}/sections/{c}.nc" for c in conv_level_cases(wc.dx)],
    output:
        **{k: f"{CONV_ENS_DIR}/dx{{dx}}/m{{member}}/regression/{os.path.basename(v)}" for k, v in zip(
            ("critical", "coefficients", "coefficients_nc", "table3", "table5"), REGRESSION_OUTPUTS)},
    params:
        outdir=lambda wc: f"{conv_member_root(wc.dx, wc.member)}/regression",
    log:
        f"{CONV_ENS_DIR}/dx{{dx}}/m{{member}}/logs/regress.log",
    benchmark:
        f"{BENCH}/convergence/ensemble/dx{{dx}}/m{{member}}/regress.tsv"
    wildcard_constraints:
        member="[0-9]+",  # member 0 (the lattice) has a folder of its own here


rule conv_ensemble:
    """The members' claims and per-case numbers at one dx of the convergence ensembles."""
    input:
        runs=lambda wc: [f"{conv_member_root(wc.dx, k)}/isph/{c}.nc" for k in conv_level_members(wc.dx)
                         for c in conv_level_cases(wc.dx)],
        regression=lambda wc: [f"{conv_member_root(wc.dx, k)}/regression/table3_comparison.csv"
                               for k in conv_level_members(wc.dx)],
    output:
        claims=f"{CONV_ENS_DIR}/dx{{dx}}/claims_members.csv",
        quantities=f"{CONV_ENS_DIR}/dx{{dx}}/quantities.csv",
    params:
        roots=lambda wc: " ".join(conv_member_root(wc.dx, k) for k in conv_level_members(wc.dx)),
        cases=lambda wc: " ".join(conv_level_cases(wc.dx)),
    log:
        f"{LOGS}/convergence/ensemble_dx{{dx}}.log",
    benchmark:
        f"{BENCH}/convergence/ensemble_dx{{dx}}.tsv"
    wildcard_constraints:
        dx="[0-9.]+",
    threads: 1
    shell:
        "granudep ensemble {params.roots} --cases {params.cases} -o {output.claims} --quantities {output.quantities}"
        " > {log} 2>&1"


CONV_ENS_TABLE = f"{CONV_DIR}/ensemble_table.csv"
CONV_FINE_CLAIMS = f"{CONV_ENS_DIR}/dx{CONV_ENS_DX}/claims_members.csv"


rule convergence_ensemble_table:
    input:
        coarse=f"{MEMBERS}/quantities.csv",
        levels=[f"{CONV_ENS_DIR}/dx{d}/quantities.csv" for d in (CONV_ENS_DX, CONV_SINGLE_DX)],
    output:
        table=CONV_ENS_TABLE,
        robust=f"{CONV_DIR}/robust_rest.csv",
    params:
        threshold=CONV.get("well_defined_pct", 10),
    log:
        f"{LOGS}/convergence/ensemble_table.log",
    benchmark:
        f"{BENCH}/convergence/ensemble_table.tsv"
    threads: 1
    shell:
        "granudep convergence-table {input.coarse} {input.levels} -o {output.table} --robust {output.robust}"
        " --threshold-pct {params.threshold} > {log} 2>&1"


rule convergence_ensemble:
    """Target: the convergence ensembles and their table (also part of `convergence`)."""
    input:
        CONV_ENS_TABLE,
        CONV_FINE_CLAIMS,
