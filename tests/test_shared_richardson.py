import math

import pytest

from granudep.richardson import observed_order


@pytest.mark.parametrize("p", [1.0, 2.0])
def test_recovers_the_order_and_limit_of_a_power_law(p):
    h = [0.001, 0.0015, 0.002]                    # non-uniform ratios 1.5 and 1.33
    f = [3.0 + 0.7 * (x / 0.001) ** p for x in h]
    r = observed_order(h, f)
    assert r["converging"] and r["order"] == pytest.approx(p, rel=1e-6)
    assert r["extrapolated"] == pytest.approx(3.0, rel=1e-6)


def test_slow_drift_is_flagged_unreliable():
    # an early T22-A70 ladder (Coulomb bed, approximate projection): 6.78, 8.08, 9.68 at 4, 3, 2 mm: order ~0.35
    r = observed_order([0.004, 0.003, 0.002], [6.78, 8.08, 9.68])
    assert 0.2 < r["order"] < 0.5 and "unreliable" in r["reason"]


def test_divergence_like_one_over_h_has_no_positive_order():
    h = [0.002, 0.003, 0.004]
    r = observed_order(h, [1.0 / x for x in h])
    assert not r["converging"] and math.isnan(r["extrapolated"])


def test_oscillation_and_too_few_points():
    assert "oscillating" in observed_order([1, 2, 3], [1.0, 2.0, 1.5])["reason"]
    assert "three" in observed_order([1, 2], [1.0, 2.0])["reason"]
