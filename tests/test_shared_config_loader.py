"""One config loader and one override rule for every stage; one name per quantity.

``config_loader_expected.json`` holds the resolved configs that the two loaders of before
(``isph.config.load_config`` with dotted keys, ``da.config.resolve`` with section dicts) gave for
the same inputs, recorded with main's code at 4077801 and the renamed keys written with their new
names: the shared loader must give the same dataclass, value for value.
"""
from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from granudep.config import ConfigError, build, dotted_key, overrides_mapping, param, to_dict
from granudep.da.config import DAConfig, resolve
from granudep.isph.config import IsphConfig, load_config
from granudep.monitor.config import MonitorConfig

ROOT = Path(__file__).resolve().parents[1]
EXPECTED = json.loads((Path(__file__).with_name("config_loader_expected.json")).read_text())

ISPH_YAML = """case: my-column
geometry: {theta_deg: 20.0, L0: 0.25, H0: 0.1}
material: {phi_internal_deg: 27.0, mu_2: 0.8}
wall: {phi_basal_deg: 24.0, slip: coulomb}
numerics: {dx: 0.01, cfl: 0.15, t_end: 1.5e-1}
output: {dt_output: 0.02, progress_every_s: 10}
"""


@pytest.fixture()
def isph_yaml(tmp_path, monkeypatch):
    monkeypatch.chdir(ROOT)  # the DA example path CSV is anchored from the working folder
    f = tmp_path / "isph.yaml"
    f.write_text(ISPH_YAML)
    return f


def _resolved(isph_yaml) -> dict:
    return {
        "isph_case": load_config("T22-A70"),
        "isph_overrides": load_config("T22-A70", dx=0.008, **{"numerics.cfl": 0.1}, output={"rest_speed": 0.05},
                                      t_end=2.0, slip="coulomb"),
        "isph_yaml": load_config(isph_yaml),
        "isph_yaml_overrides": load_config(isph_yaml, phi_internal_deg=26.0, **{"wall.phi_basal_deg": 23.0}),
        "isph_mapping_paper": load_config({"case": "T16-A50", "numerics": {"dx": 0.01}}),
        "isph_roundtrip": load_config(load_config("T10-A35", dx=0.01), cfl=0.1),
        "da_case": resolve("1D-A70"),
        "da_overrides": resolve("1D-A70", deposition=False, n_particles=500, **{"numerics.cfl": 0.3},
                                output={"dt_output": 0.05}),
        "da_user": resolve("config/da/example_user_column.yaml", n_particles=300),
        "da_path": resolve("config/da/example_path.yaml", deposition=False),
        "da_mapping": resolve({"case": "1D-A45", "numerics": {"n_particles": 400}},
                              deposition={"x_inf_mode": "no-deposition"}),
        "da_roundtrip": resolve(resolve("1D-A30", n_particles=200), x_inf_mode="no-deposition"),
        "monitor": build(MonitorConfig, {"divergence_threshold": 1.7, "critical_speed": 0.2}, prefix="monitor"),
    }


def test_the_shared_loader_gives_the_configs_of_the_two_loaders_before(isph_yaml):
    got = {k: to_dict(v) for k, v in _resolved(isph_yaml).items()}
    assert set(got) == set(EXPECTED)
    for name, cfg in got.items():
        assert cfg == EXPECTED[name], name


@pytest.mark.parametrize("call, message", [
    (lambda: load_config("T22-A70", phi_deg=24.0),
     "phi_deg: renamed to phi_internal_deg (material.phi_internal_deg; one name per quantity across stages)"),
    (lambda: load_config("T22-A70", **{"wall.phi_wall_deg": 24.0}), "wall.phi_wall_deg: renamed to wall.phi_basal_deg"),
    (lambda: load_config({"case": "x", "output": {"interval": 0.1}}), "output.interval: renamed to output.dt_output"),
    (lambda: load_config("T22-A70", output={"progress_s": 1.0}), "output.progress_s: renamed to output.progress_every_s"),
    (lambda: load_config("T22-A70", progress_s=1.0), "progress_s: renamed to progress_every_s"),
    (lambda: build(MonitorConfig, {"interface_threshold": 1.7}, prefix="monitor"),
     "monitor.interface_threshold: renamed to monitor.divergence_threshold"),
])
def test_an_old_key_is_refused_naming_the_new_one(call, message):
    with pytest.raises(ConfigError) as exc:
        call()
    assert str(exc.value).startswith(message) and "\n" not in str(exc.value)


def test_an_old_key_in_a_yaml_file_is_refused_by_the_cli(tmp_path):
    f = tmp_path / "old.yaml"
    f.write_text("case: my-column\nmaterial: {phi_deg: 27.0}\n")
    r = subprocess.run([sys.executable, "-m", "granudep", "isph", str(f), "-o", str(tmp_path / "o.nc")],
                       capture_output=True, text=True)
    assert r.returncode == 2
    assert r.stderr.strip() == ("granudep: error: material.phi_deg: renamed to material.phi_internal_deg "
                                "(one name per quantity across stages)")
    assert not (tmp_path / "o.nc").exists()
    r = subprocess.run([sys.executable, "-m", "granudep", "monitor", str(tmp_path / "none.nc"),
                        "--interface-threshold", "1.7"], capture_output=True, text=True)
    assert r.returncode == 2 and r.stderr.strip().startswith(
        "granudep: error: --interface-threshold: renamed to --divergence-threshold")


def test_one_override_rule_for_every_stage():
    # the same bare name reaches the key of that name in each stage: the sensitivity study needs no lookup table
    assert dotted_key(IsphConfig, "phi_internal_deg") == "material.phi_internal_deg"
    assert dotted_key(DAConfig, "phi_internal_deg") == "material.phi_internal_deg"
    assert dotted_key(IsphConfig, "phi_basal_deg") == "wall.phi_basal_deg"
    assert dotted_key(DAConfig, "phi_basal_deg") == "material.phi_basal_deg"
    assert dotted_key(MonitorConfig, "divergence_threshold") == "divergence_threshold"
    assert dotted_key(IsphConfig, "critical_speed") is None
    for cls in (IsphConfig, DAConfig):
        assert overrides_mapping(cls, {"numerics": {"cfl": 0.1}, "numerics.max_steps": 5, "t_end": 1.0}) == \
            {"numerics": {"cfl": 0.1, "max_steps": 5, "t_end": 1.0}}
        with pytest.raises(ConfigError, match=r"^bogus: unknown override \(allowed: a section"):
            overrides_mapping(cls, {"bogus": 1})
    # ambiguous bare names are refused alike (DA used to call them unknown)
    with pytest.raises(ConfigError, match=r"^front_depth_threshold: ambiguous override"):
        overrides_mapping(_Both, {"front_depth_threshold": 3.0})
    # a dotted key of any depth (the DA could not reach geometry.path.* before)
    assert overrides_mapping(DAConfig, {"geometry.path.smoothing_length": 5.0}) == \
        {"geometry": {"path": {"smoothing_length": 5.0}}}


@dataclass(frozen=True)
class _A:
    front_depth_threshold: float = param(1.0)


@dataclass(frozen=True)
class _B:
    front_depth_threshold: float = param(2.0)


@dataclass(frozen=True)
class _Both:
    a: _A = field(default_factory=_A)
    b: _B = field(default_factory=_B)
