"""Bad input is refused with a ConfigError naming the key, before any work."""
import pytest

from granudep.config import ConfigError
from granudep.isph.config import case_geometry, case_names, load_config


@pytest.mark.parametrize("overrides, key", [
    ({"dx": -0.01}, "numerics.dx"),
    ({"theta_deg": 75.0}, "geometry.theta_deg"),
    ({"slip": "sticky"}, "wall.slip"),
    ({"mu_2": 0.3}, "material.mu_2"),
    ({"eta_min": 1e5}, "rheology.eta_min"),
    ({"domain_length": 0.1}, "geometry.domain_length"),
    ({"cfl": 0.9}, "numerics.cfl"),
    ({"nonsense": 1}, "nonsense"),
])
def test_bad_overrides_raise_config_error_naming_the_key(overrides, key):
    with pytest.raises(ConfigError, match=key.replace(".", r"\.")):
        load_config("T22-A70", **overrides)


def test_unknown_case_and_bad_yaml(tmp_path):
    with pytest.raises(ConfigError, match="unknown case"):
        load_config("T99-A1")
    bad = tmp_path / "bad.yaml"
    bad.write_text("geometry:\n  H0: -1\n")
    with pytest.raises(ConfigError, match=r"geometry\.H0"):
        load_config(bad)


def test_named_cases_cover_table1_and_table5_geometries():
    names = case_names()
    assert "T22-A70" in names and "T10-A35" in names and len(names) == 14 + 3
    assert case_geometry("T22-A45") == {"theta_deg": 22.0, "L0": 0.25, "H0": 0.1125}
    assert case_geometry("T22-A124")["H0"] == pytest.approx(0.186)


def test_yaml_user_case(tmp_path):
    f = tmp_path / "my_case.yaml"
    f.write_text("case: my_case\ngeometry: {theta_deg: 18, L0: 0.1, H0: 0.05}\nnumerics: {dx: 0.005}\n")
    cfg = load_config(f)
    assert cfg.case == "my_case" and cfg.geometry.theta_deg == 18 and cfg.numerics.dx == 0.005


def test_density_relaxation_per_time_scales_the_weight_with_the_step():
    """per_time: the weight is γ Δt/Δt_ref (Δt_ref the gravity cap), so the relaxation rate per unit
    time does not depend on Δt; per_step: γ at any Δt."""
    from granudep.isph.stepper import IsphSolver
    s = IsphSolver(load_config("T22-A70", dx=0.02, **{"numerics.density_relaxation_form": "per_time"}))
    ref = s.gravity_step()
    assert abs(ref - 0.125 * (s.h / 9.81) ** 0.5) < 1e-15
    assert s.density_relaxation(ref) == 0.02
    assert abs(s.density_relaxation(0.25 * ref) - 0.005) < 1e-15
    assert s.density_relaxation(2.0 * ref) == 0.02
    s2 = IsphSolver(load_config("T22-A70", dx=0.02, **{"numerics.density_relaxation_form": "per_step"}))
    assert s2.density_relaxation(0.25 * ref) == 0.02
