import pytest


@pytest.fixture(scope="session")
def small_case():
    """A quick Table 5 case: 1D-A70 with 300 particles, coarse outputs."""
    return {"case": "1D-A70", "numerics": {"n_particles": 300}, "output": {"dt_output": 0.05, "dx_grid": 2e-3}}
