"""No deposit where it could not rest (``deposition.steep_bed: no_deposit``).

A static deposit on a bed steeper than the basal friction angle (|tanθ| > tan φ_B) is not in
Coulomb equilibrium: it would slide. The example path's release sits on 35° with φ_B = 28°; with
``deposition.steep_bed: deposit`` its thinning tail deposited there and the flow then ran down that deposit
(docs/da-engineer-scale.md). The step-level rule is also checked against the naive twin
(``test_step_vs_naive.py``).
"""
from pathlib import Path

import pytest

from granudep.da.api import run_da

EXAMPLE = Path(__file__).resolve().parents[2] / "config" / "da" / "example_path.yaml"


def _deposit_on_steep_bed(steep_bed):
    ds = run_da(EXAMPLE, n_particles=200, progress=False,
                deposition={"steep_bed": steep_bed, "x_inf_mode": "user", "x_inf": 155.0})
    dep = ds.deposit_depth.values[-1] * float(ds.attrs["dx_grid"])     # volume per cell (m2 per unit width)
    steep = ds.bed_slope.values > 30.0                                # well above phi_B = 28 deg
    assert steep.sum() > 100
    return dep[steep].sum(), dep.sum()


@pytest.mark.parametrize("steep_bed", ["no_deposit", "deposit"])
def test_no_deposit_on_a_bed_steeper_than_the_basal_friction_angle(steep_bed):
    on_steep, total = _deposit_on_steep_bed(steep_bed)
    assert total > 10.0                                               # the run deposits (of 80 m2 released)
    if steep_bed == "no_deposit":
        assert on_steep == 0.0
    else:                                                             # the rule is what removes it
        assert on_steep > 0.01 * total
