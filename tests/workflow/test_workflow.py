"""The Snakemake workflow schedules what the paper's method needs (dry runs, no computation).

The workflow is copied once per session into a fresh folder (wfhelp.py), so existing results or a
running workflow in the checkout cannot change the job counts; the dry runs run in the background
while the rest of the suite computes (tests/conftest.py, wfhelp.py).
"""
from __future__ import annotations

import re

import pytest
import yaml

from wfhelp import dry_run, overlay
from wfhelp import workdir as _workdir

TABLE1 = ["T10-A35", "T16-A35", "T22-A35", "T16-A50", "T22-A50", "T10-A70", "T22-A70", "T10-A100",
          "T16-A100", "T22-A100", "T10-A120", "T16-A120", "T22-A120", "T22-A150"]
TABLE5_GEOMETRIES = ["T22-A30", "T22-A45", "T22-A124"]
FIGURES = ["fig5", "fig6", "fig7", "fig8", "fig9", "fig10", "fig11", "fig12", "fig13", "fig15", "fig16",
           "fig17", "figA1", "figA2", "figA3"]

SINGLE_TARGETS = [
    ("results/isph/T22-A70.nc", {"warmup": 1, "isph_run": 1}),
    ("results/sections/T16-A50.nc", {"warmup": 1, "isph_run": 1, "monitor": 1}),
    ("results/da/1D-A70_nodeposition.nc", {"warmup": 1, "da_run": 1}),
]
STUDY_TARGETS = [
    ("convergence", "convergence_isph", 4),  # T22-A70 at 4, 3, 2, 1.4 mm
    ("sensitivity", "sensitivity_da", 11),  # baseline + 2 values x 5 parameters
]
USER_CASE = {"user_cases": [{"name": "my-column", "theta_deg": 20, "L0": 0.2, "H0": 0.12}]}
SCHEMA_REFUSALS = [
    ({"isph": {"dx": -0.004}}, "isph.dx: isph run 'T10-A35': numerics.dx: must be > 0.0 and <= 0.1 (got -0.004)"),
    ({"isph": {"cases": ["T22-A70", "bad case"]}}, "isph.cases[1]: must be a 2D ISPH case name"),
    ({"da": {"cases": ["1D-A70", "T22-A70"]}}, "da.cases[1]: must be a Table 5 DA case name"),
    ({"da": {"ab_source": "guess"}}, "da.ab_source: must be one of ['paper', 'computed'] (got 'guess')"),
    ({"user_cases": [{"name": "x", "theta_deg": 20, "L0": 0.2, "H0": 0}]},
     "user_cases[0].H0: isph run 'x': geometry.H0: must be > 0.0"),
    ({"isph": {"dxx": 0.004}}, "isph.dxx: unknown key (allowed: cases, dx, dx_per_case, set, t_end, table5_geometries, threads)"),
]
# Each of these once passed `snakemake -n` before and was refused only by the job.
ONE_LINE_REFUSALS = [
    ("isph: {dx: .nan}\n", "isph.dx: must be a finite number (got nan)"),
    ("user_cases: [{name: steep, theta_deg: 30, L0: 0.2, H0: 0.1}]\n",
     "user_cases[0].theta_deg: isph run 'steep': geometry.theta_deg: must be < material.phi_internal_deg = 25.5"),
    ("user_cases: [{name: big, theta_deg: 20, L0: 7, H0: 0.1}]\n",
     "user_cases[0].L0: isph run 'big': geometry.L0: must be > 0.0 and <= 5.0 (got 7.0)"),
    ("da: {n_particles: 500000}\n", "da.n_particles: da run '1D-A30_deposition': numerics.n_particles: "
                                      "must be >= 20 and <= 200000 (got 500000)"),
    ("user_cases: [{name: a, theta_deg: 20, L0: 0.2, H0: 0.1}, {name: a, theta_deg: 18, L0: 0.2, H0: 0.1}]\n",
     "user_cases[1].name: 'a' is already the name of user_cases[0]"),
    ("reference_tables: [measurements/none.csv]\n", "reference_tables[0]: file not found: measurements/none.csv"),
    ("sensitivity: {critical_speed: [-1.0]}\n", "sensitivity.critical_speed[0]: sensitivity monitor"),
    ("monitor: {width_factor: 80}\n", "monitor.width_factor: monitor: monitor.width_factor: must be > 0.0 and <= 50.0"),
    ("convergence: {dx: [0.2, 0.01]}\n", "convergence.dx[0]: convergence isph run dx = 0.2: numerics.dx: must be"),
    ("isph: {set: {numerics.projection: exact}}\n",
     "isph.set.numerics.projection: isph run 'T10-A35': numerics.projection: must be one of"),
    ("isph: {set: {numerics.projection: approximate, wall.coulomb_normal: projection}}\n",
     "isph.set.wall.coulomb_normal: isph run 'T10-A35': wall.coulomb_normal: projection needs"),
    # an old key name is refused, naming the new one
    ("isph: {set: {output.interval: 0.02}}\n",
     "isph.set.output.interval: isph run 'T10-A35': output.interval: renamed to output.dt_output"),
]
ISPH_SET = "isph: {set: {numerics.projection: approximate, wall.coulomb_normal: contact}}\n"
YAML_1_2 = "isph: {dx: 5e-3}\n"
NO_2D_REFERENCE = {"da": {"cases": ["1D-A70", "1D-A99"]}}


def dry_run_args(item) -> list[tuple[str, ...]]:
    """The dry runs a collected test of this module asks for (tests/conftest.py prefetches them)."""
    p = getattr(item, "callspec", None)
    p = p.params if p else {}
    name = item.originalname
    cfg = ("-j2", "--configfile")
    return {
        "test_default_config_schedules_the_whole_paper": lambda: [("-j2",)],
        "test_ci_profile_runs_the_whole_chain_small": lambda: [("--profile", "profiles/ci")],
        "test_summary_is_given_every_figure_with_its_caption": lambda: [("-j2",)],
        "test_converged_reference_is_the_ladders_converged_rung": lambda: [("-j2",)],
        "test_single_targets_run_only_what_they_need": lambda: [("-j2", p["target"])],
        "test_slurm_profile_dry_runs": lambda: [("--profile", "profiles/slurm")],
        "test_extra_study_targets_dry_run": lambda: [("-j2", p["target"])],
        "test_user_case_gets_2d_and_da_runs": lambda: [(*cfg, str(overlay(USER_CASE)))],
        "test_schema_rejects_bad_config_naming_the_key": lambda: [(*cfg, str(overlay(p["content"])))],
        "test_dry_run_refuses_what_the_jobs_would_in_one_line": lambda: [(*cfg, str(overlay(p["content"])))],
        "test_dry_run_reads_yaml_1_2_numbers": lambda: [("-j2", "results/isph/T22-A70.nc", "--configfile",
                                                         str(overlay(YAML_1_2)))],
        "test_da_case_without_2d_reference_is_refused": lambda: [(*cfg, str(overlay(NO_2D_REFERENCE)))],
        "test_isph_set_reaches_every_2d_run": lambda: [("-j2", "results/isph/T22-A70.nc", "--configfile",
                                                        str(overlay(ISPH_SET)))],
    }.get(name, lambda: [])()


@pytest.fixture(scope="module")
def workdir():
    return _workdir()


def test_default_config_schedules_the_whole_paper(workdir):
    rc, out, jobs = dry_run(workdir, "-j2")
    assert rc == 0, out
    n2d = len(TABLE1) + len(TABLE5_GEOMETRIES)
    assert jobs["isph_run"] == n2d
    assert jobs["monitor"] == n2d
    assert jobs["monitor_wm"] == 6  # Table 1 cases at 22 deg (Appendix)
    assert jobs["da_run"] == 8  # 4 Table 5 cases x (deposition, nodeposition)
    for rule in ("warmup", "regress", "reference", "compare", "verify_da", "verify_isph", "summary",
                 "benchmarks_summary", "all"):
        assert jobs[rule] == 1, rule
    assert {f"figure_{f}" for f in FIGURES} <= set(jobs)
    # the extra studies are separate targets
    assert not any(r.startswith(("convergence", "sensitivity")) for r in jobs)
    # paper resolution; every 2D run gets its dx (the Table 1 / 5 runs and the two Fig 6 runs)
    assert jobs["isph_fig6"] == 2
    # the ensemble: members 1..K-1 of every paper 2D case, each monitored and regressed on its own
    k = yaml.safe_load((workdir / "config/config.yaml").read_text())["ensemble"]["members"]
    assert jobs["isph_member"] == jobs["monitor_member"] == (k - 1) * n2d and jobs["regress_member"] == k - 1
    assert jobs["ensemble"] == 1
    assert out.count("--dx 0.004") == k * n2d + 2
    # the chain is the default product: the DA runs with deposition use our computed A, B;
    # the reading matrix adds one run per case for Table 5 read as normalised and as dimensional
    for case in ("1D-A30", "1D-A45", "1D-A70", "1D-A124"):
        assert (f"granudep da {case} --ab-source computed --coefficients results/regression/coefficients.csv"
                in out)
        assert f"granudep da {case} --ab-source paper --coefficient-units normalised" in out
        assert f"granudep da {case} --ab-source paper --coefficient-units dimensional" in out
    assert jobs["da_reading"] == 8 and jobs["reference_converged"] == 1 and jobs["regress_diagnose"] == 1
    # every numba rule sets its own thread count
    assert re.search(r"NUMBA_NUM_THREADS=1 granudep isph T22-A70 ", out)


def test_summary_is_given_every_figure_with_its_caption(workdir):
    """A regression: `snakemake -j2` once made 17 figures and a summary saying "figures (not given)": the summary
    rule must pass every figure the run draws as NAME=PATH, NAME having its caption workflow/report/NAME.rst."""
    rc, out, jobs = dry_run(workdir, "-j2")
    assert rc == 0, out
    drawn = set(re.findall(r"^\s*output: (results/figures/\S+\.png)", out, flags=re.M))
    assert len(drawn) >= 17
    (cmd,) = [ln for ln in out.splitlines() if ln.startswith("Shell command: granudep summary ")]
    assert "--captions workflow/report" in cmd
    given = dict(tok.split("=", 1)[::-1] for tok in cmd.split("--figures", 1)[1].split(" --")[0].split())
    assert set(given) == drawn
    from granudep.report.summary import figure_caption
    for path, name in given.items():
        assert figure_caption(name, workdir / "workflow" / "report"), f"{path}: no caption {name}.rst"


def test_fig6_runs_the_case_yaml_with_and_without_slip(workdir):
    """Fig 6 (quartz sand, a = 7, horizontal plane): the case YAML at the paper's dx, once with the
    paper's slip (the YAML's bed) and once on a no-slip bed; the figure gets both and the times."""
    rc, out, jobs = dry_run(workdir, "-j2", "results/figures/fig6_fd_interface_flat.png")
    assert rc == 0, out
    assert jobs["isph_fig6"] == 2 and jobs["figure_fig6"] == 1 and "isph_run" not in jobs
    yaml_run = "granudep isph config/isph/fig6-quartz-a7.yaml --dx 0.004"
    (slip,) = [ln for ln in out.splitlines() if yaml_run in ln and "-o results/isph/fig6-quartz-a7.nc" in ln]
    (noslip,) = [ln for ln in out.splitlines() if yaml_run in ln and "-o results/isph/fig6-quartz-a7-noslip.nc" in ln]
    assert "--set wall.slip=navier" in slip and "--set wall.slip=no_slip" in noslip
    assert "--set case=fig6-quartz-a7-noslip" in noslip
    (fig,) = [ln for ln in out.splitlines() if "granudep figure fig6 " in ln]
    assert ("results/isph/fig6-quartz-a7.nc results/isph/fig6-quartz-a7-noslip.nc "
            "--times 0.416 2.288 4.16 6.032 7.904 --time-unit t_L0") in fig


def test_converged_reference_is_the_ladders_converged_rung(workdir):
    """The converged reference is chosen on the ladder's tolerance (compare.reference), the
    workflow's runs first (the fall-back), the ladder's files after --ladder."""
    rc, out, jobs = dry_run(workdir, "-j2")
    assert rc == 0, out
    (cmd,) = [ln for ln in out.splitlines() if "--label '2D converged'" in ln and ln.startswith("Shell command:")]
    assert ("granudep reference results/isph/T22-A30.nc results/isph/T22-A45.nc results/isph/T22-A70.nc "
            "results/isph/T22-A124.nc --ladder") in cmd
    assert "--converged --tolerance 0.05 --measure v99" in cmd


def test_ci_profile_runs_the_whole_chain_small(workdir):
    rc, out, jobs = dry_run(workdir, "--profile", "profiles/ci")
    assert rc == 0, out
    assert jobs["isph_run"] == 2 and jobs["monitor"] == 2 and jobs["da_run"] == 2
    assert jobs["regress"] == jobs["reference"] == jobs["compare"] == jobs["summary"] == 1
    assert {f"figure_{f}" for f in FIGURES} <= set(jobs)
    assert "granudep isph T22-A70 --dx 0.01" in out and "granudep isph T16-A50 --dx 0.01" in out
    assert jobs["isph_fig6"] == 2 and "granudep isph config/isph/fig6-quartz-a7.yaml --dx 0.0125" in out
    # the DA run with deposition takes A, B from the source the CI config names
    ci = yaml.safe_load((workdir / "config/ci.yaml").read_text())
    src = ci["da"]["ab_source"]
    expected = ("--ab-source computed --coefficients results/regression/coefficients.csv"
                if src == "computed" else "--ab-source paper")
    assert f"granudep da 1D-A70 {expected} --n-particles 200" in out
    assert "granudep verify isph --quick" in out
    # the summary also as HTML: the Snakemake report shows an .html result rendered
    assert "granudep summary -o results/summary.md --html results/summary.html" in out


@pytest.mark.parametrize("target, expected", SINGLE_TARGETS)
def test_single_targets_run_only_what_they_need(workdir, target, expected):
    rc, out, jobs = dry_run(workdir, "-j2", target)
    assert rc == 0, out
    assert jobs.pop("total") == sum(expected.values())
    assert jobs == expected


def test_slurm_profile_dry_runs(workdir):
    pytest.importorskip("snakemake_executor_plugin_slurm")
    rc, out, jobs = dry_run(workdir, "--profile", "profiles/slurm")
    assert rc == 0, out
    assert jobs["isph_run"] == len(TABLE1) + len(TABLE5_GEOMETRIES)
    # the profile's set-threads reach the 2D runs (without `cores` Snakemake scales them down to
    # the submitting node's core count) and SLURM is asked for as many CPUs
    isph = re.findall(r"NUMBA_NUM_THREADS=(\d+) granudep isph (?!config/isph/fig6)", out)  # the Fig 6 runs: 1 thread
    assert len(isph) == jobs["isph_run"] + jobs["isph_member"] and set(isph) == {"4"}
    assert out.count("cpus_per_task=4") >= jobs["isph_run"]


@pytest.mark.parametrize("target, rule, count", STUDY_TARGETS)
def test_extra_study_targets_dry_run(workdir, target, rule, count):
    rc, out, jobs = dry_run(workdir, "-j2", target)
    assert rc == 0, out
    assert jobs[rule] == count


def test_user_case_gets_2d_and_da_runs(workdir):
    rc, out, jobs = dry_run(workdir, "-j2", "--configfile", str(overlay(USER_CASE)))
    assert rc == 0, out
    assert jobs["isph_run"] == len(TABLE1) + len(TABLE5_GEOMETRIES) + 1
    assert jobs["user_case_config"] == 1
    assert "granudep isph results/user_cases/my-column.yaml" in out
    assert re.search(r"granudep da results/user_cases/my-column.yaml --ab-source computed", out)


@pytest.mark.parametrize("content, key", SCHEMA_REFUSALS)
def test_schema_rejects_bad_config_naming_the_key(workdir, content, key):
    path = overlay(content)
    rc, out, jobs = dry_run(workdir, "-j2", "--configfile", str(path))
    assert rc == 2, out
    assert f"granudep: {path}: {key}" in out, out
    assert not jobs  # nothing scheduled


def _refusal_lines(out: str) -> list[str]:
    return [ln for ln in out.splitlines() if ln.strip() and "is extended by additional config" not in ln]


@pytest.mark.parametrize("content, expected", ONE_LINE_REFUSALS)
def test_dry_run_refuses_what_the_jobs_would_in_one_line(workdir, content, expected):
    path = overlay(content)
    rc, out, jobs = dry_run(workdir, "-j2", "--configfile", str(path))
    assert rc == 2, out
    lines = _refusal_lines(out)
    assert len(lines) == 1, out
    assert lines[0].startswith(f"granudep: {path}: {expected}"), out
    assert not jobs


def test_isph_set_reaches_every_2d_run(workdir):
    # the scheme options of config isph.set go to the 2D runs as --set (validated at parse time)
    path = overlay(ISPH_SET)
    rc, out, jobs = dry_run(workdir, "-j2", "results/isph/T22-A70.nc", "--configfile", str(path))
    assert rc == 0, out
    assert "--set numerics.projection=approximate --set wall.coulomb_normal=contact" in out, out


def test_dry_run_reads_yaml_1_2_numbers(workdir):
    path = overlay(YAML_1_2)
    rc, out, jobs = dry_run(workdir, "-j2", "results/isph/T22-A70.nc", "--configfile", str(path))
    assert rc == 0, out
    assert "--dx 0.005" in out


def test_da_case_without_2d_reference_is_refused(workdir):
    path = overlay(NO_2D_REFERENCE)
    rc, out, jobs = dry_run(workdir, "-j2", "--configfile", str(path))
    assert rc != 0 and "da.reference_2d" in out and "1D-A99" in out, out
