"""`path_cases:` in the workflow (issue 16): dry runs only."""
from __future__ import annotations

import re

import pytest
import yaml

from test_workflow import dry_run, workdir  # noqa: F401  (fixture)


def test_default_config_runs_the_example_path(workdir):  # noqa: F811
    rc, out, jobs = dry_run(workdir, "-j2", "results/figures/path_example_path.png")
    assert rc == 0, out
    assert jobs["da_path_run"] == 2 and jobs["figure_path"] == 1
    assert re.search(r"granudep da config/da/example_path.yaml --no-deposition "
                     r"-o results/da_path/example_path_nodeposition.nc", out)
    assert "granudep path-figure -o results/figures/path_example_path.png" in out


def test_ci_profile_runs_a_small_example_path(workdir):  # noqa: F811
    rc, out, jobs = dry_run(workdir, "--profile", "profiles/ci")
    assert rc == 0, out
    assert jobs["da_path_run"] == 2 and jobs["figure_path"] == 1
    assert "granudep da config/da/example_path.yaml --n-particles 300" in out


@pytest.mark.parametrize("entry, key", [
    ({"name": "bad name", "config": "config/da/example_path.yaml"}, "path_cases[0].name:"),
    ({"name": "p", "config": "config/da/example_path.csv"}, "path_cases[0].config:"),
    ({"name": "p", "config": "config/da/missing.yaml"}, "config path_cases: p: config file"),
    ({"name": "p", "config": "config/da/example_user_column.yaml"}, "has no geometry.path.file"),
])
def test_bad_path_case_refused(workdir, tmp_path, entry, key):  # noqa: F811
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump({"path_cases": [entry]}))
    rc, out, jobs = dry_run(workdir, "-j2", "--configfile", str(path))
    assert rc != 0 and key in out, out
    assert not jobs
