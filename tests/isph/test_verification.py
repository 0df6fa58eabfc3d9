"""Analytic checks of the 2D ISPH solver (the same functions `granudep verify isph` runs)."""
import pytest

from granudep.isph import verification as v


def _assert_rows(rows):
    for r in rows:
        assert r["passed"], f"{r['check']}: {r['quantity']} = {r['value']:.4g} (error {r['error']:.3g} > {r['tolerance']})"


def test_hydrostatic_layer_stays_at_rest_with_hydrostatic_base_pressure():
    # bounds: max speed < 1 mm/s after 0.5 s; base pressure within 3 % of rho g H
    _assert_rows(v.hydrostatic(quick=True))


def test_newtonian_open_channel_poiseuille_matches_analytic_profile():
    # relative L2 error <= 2 %
    _assert_rows(v.film_flow(quick=True))


def test_coulomb_wall_friction_decelerates_sliding_layer_at_analytic_rate():
    # a = g (tan(phi_B) cos(theta) - sin(theta)) within 15 %
    _assert_rows(v.sliding_block(quick=True))


@pytest.mark.slow
def test_hydrostatic_and_poiseuille_fine():
    _assert_rows(v.hydrostatic(quick=False) + v.film_flow(quick=False))
