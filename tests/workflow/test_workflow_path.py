"""`path_cases:` in the workflow: dry runs only (prefetched, see wfhelp.py)."""
from __future__ import annotations

import re

import pytest

from wfhelp import dry_run, overlay
from wfhelp import workdir as _workdir

BAD_PATH_CASES = [
    ({"name": "bad name", "config": "config/da/example_path.yaml"}, "path_cases[0].name:"),
    ({"name": "p", "config": "config/da/example_path.csv"}, "path_cases[0].config:"),
    ({"name": "p", "config": "config/da/missing.yaml"}, "config path_cases: p: config file"),
    ({"name": "p", "config": "config/da/example_user_column.yaml"}, "has no geometry.path.file"),
]


def dry_run_args(item) -> list[tuple[str, ...]]:
    """The dry runs a collected test of this module asks for (tests/conftest.py prefetches them)."""
    p = item.callspec.params if getattr(item, "callspec", None) else {}
    return {
        "test_default_config_runs_the_example_path": lambda: [("-j2", "results/figures/path_example_path.png")],
        "test_ci_profile_runs_a_small_example_path": lambda: [("--profile", "profiles/ci")],
        "test_bad_path_case_refused": lambda: [("-j2", "--configfile", str(overlay({"path_cases": [p["entry"]]})))],
    }.get(item.originalname, lambda: [])()


@pytest.fixture(scope="module")
def workdir():
    return _workdir()


def test_default_config_runs_the_example_path(workdir):
    rc, out, jobs = dry_run(workdir, "-j2", "results/figures/path_example_path.png")
    assert rc == 0, out
    assert jobs["da_path_run"] == 2 and jobs["figure_path"] == 1
    assert re.search(r"granudep da config/da/example_path.yaml --no-deposition "
                     r"-o results/da_path/example_path_nodeposition.nc", out)
    assert "granudep path-figure -o results/figures/path_example_path.png" in out


def test_ci_profile_runs_a_small_example_path(workdir):
    rc, out, jobs = dry_run(workdir, "--profile", "profiles/ci")
    assert rc == 0, out
    assert jobs["da_path_run"] == 2 and jobs["figure_path"] == 1
    assert "granudep da config/da/example_path.yaml --n-particles 300" in out


@pytest.mark.parametrize("entry, key", BAD_PATH_CASES)
def test_bad_path_case_refused(workdir, entry, key):
    rc, out, jobs = dry_run(workdir, "-j2", "--configfile", str(overlay({"path_cases": [entry]})))
    assert rc != 0 and key in out, out
    assert not jobs
