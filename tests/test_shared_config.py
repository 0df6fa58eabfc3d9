"""Config validation at the edge: unknown keys, types, ranges, nesting — one clear line each."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import pytest

from granudep.config import ConfigError, build, load_yaml, merge, param, to_yaml


@dataclass(frozen=True)
class Geometry:
    H0: float = param(0.14, gt=0.0, unit="m")
    theta_deg: float = param(22.0, ge=0.0, lt=90.0, unit="deg")


@dataclass(frozen=True)
class Cfg:
    geometry: Geometry = field(default_factory=Geometry)
    n: int = param(100, ge=2)
    mode: Literal["a", "b"] = "a"
    flag: bool = False

    def validate(self, prefix: str) -> None:
        if self.mode == "b" and self.n < 10:
            raise ConfigError("n: must be >= 10 when mode is 'b'")


def test_defaults_and_nesting():
    cfg = build(Cfg, {"geometry": {"H0": 0.2}, "n": 5})
    assert cfg.geometry.H0 == 0.2 and cfg.geometry.theta_deg == 22.0 and cfg.n == 5


@pytest.mark.parametrize("data, message", [
    ({"geometry": {"H0": -0.1}}, "geometry.H0: must be > 0.0 (got -0.1)"),
    ({"geometry": {"theta_deg": 90}}, "geometry.theta_deg: must be >= 0.0 and < 90.0 (got 90.0)"),
    ({"geometry": {"H0": "tall"}}, "geometry.H0: must be a number (got str 'tall')"),
    ({"geometry": {"height": 1}}, "geometry.height: unknown key (allowed: H0, theta_deg)"),
    ({"n": 2.5}, "n: must be an integer (got float 2.5)"),
    ({"n": 1}, "n: must be >= 2 (got 1)"),
    ({"mode": "c"}, "mode: must be one of ['a', 'b'] (got 'c')"),
    ({"flag": "yes"}, "flag: must be true or false (got 'yes')"),
    ({"mode": "b", "n": 5}, "n: must be >= 10 when mode is 'b'"),
    ({"geometry": {"H0": float("nan")}}, "geometry.H0: must be a finite number (got nan)"),
])
def test_bad_input_one_clear_line(data, message):
    with pytest.raises(ConfigError) as exc:
        build(Cfg, data)
    assert str(exc.value) == message
    assert "\n" not in str(exc.value)


def test_bool_is_not_a_number():
    with pytest.raises(ConfigError, match="geometry.H0: must be a number"):
        build(Cfg, {"geometry": {"H0": True}})


def test_yaml_roundtrip_and_merge(tmp_path):
    cfg = build(Cfg, {"geometry": {"H0": 0.3}})
    path = tmp_path / "c.yaml"
    path.write_text(to_yaml(cfg))
    again = build(Cfg, load_yaml(path))
    assert again == cfg
    assert merge({"a": {"b": 1, "c": 2}}, {"a": {"c": 3}}) == {"a": {"b": 1, "c": 3}}


def test_load_yaml_errors(tmp_path):
    with pytest.raises(ConfigError, match="config file not found"):
        load_yaml(tmp_path / "missing.yaml")
    bad = tmp_path / "list.yaml"
    bad.write_text("- 1\n- 2\n")
    with pytest.raises(ConfigError, match="top level must be a mapping"):
        load_yaml(bad)
