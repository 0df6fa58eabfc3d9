"""Dam breaks against exact solutions: Ritter (flat, frictionless) and Mangeney et al. 2000
(incline with Coulomb friction). Tolerances and measured errors: granudep.da.verification."""
import pytest

from granudep.da.verification import check_dam_break


@pytest.mark.parametrize("theta_deg, delta_deg", [(0.0, 0.0), (30.0, 20.0)], ids=["ritter", "mangeney"])
def test_dam_break_matches_exact_solution(theta_deg, delta_deg):
    rows = check_dam_break(theta_deg=theta_deg, delta_deg=delta_deg)
    assert len(rows) == 3
    for row in rows:
        assert row["passed"], row
