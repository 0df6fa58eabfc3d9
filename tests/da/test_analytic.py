"""Kerswell stop distance, Savage–Hutter parabolic cap and Coulomb block against exact solutions
(tolerances and measured errors: granudep.da.verification)."""
import pytest

from granudep.da import verification as v


@pytest.mark.parametrize("check", [v.check_kerswell, v.check_savage_hutter, v.check_coulomb_block],
                         ids=["kerswell", "savage_hutter", "coulomb_block"])
def test_matches_exact_solution(check):
    rows = check()
    assert rows
    for row in rows:
        assert row["passed"], row
