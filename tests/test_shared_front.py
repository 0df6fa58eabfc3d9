"""The shared front and flow-time definitions (2D and DA are compared with the same rule)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from granudep import cases
from granudep.front import flow_time, front_from_profile


def test_front_stops_at_first_gap():
    edges = np.arange(11.0)
    depth = np.array([5, 5, 4, 3, 0.5, 2, 2, 0, 0, 0])
    assert front_from_profile(edges, depth, threshold=1.0) == 4.0  # detached lump at cells 5-6 ignored
    assert front_from_profile(edges, depth, threshold=0.4) == 7.0
    assert math.isnan(front_from_profile(edges, depth, threshold=10.0))


def test_front_uses_main_mass_not_first_cell():
    edges = np.arange(6.0)
    depth = np.array([0.0, 3.0, 4.0, 1.0, 0.0])
    assert front_from_profile(edges, depth, threshold=0.5) == 4.0


def test_flow_time_is_when_front_stops():
    t = np.linspace(0.0, 2.0, 201)
    front = np.minimum(t, 1.0)  # moves at 1 m/s until t = 1, then at rest
    assert flow_time(t, front, tol=1e-3) == pytest.approx(1.0, abs=0.011)
    assert flow_time(t, np.zeros_like(t), tol=1e-3) == 0.0


def test_scales_match_paper_numbers():
    theta = math.radians(22.0)
    # Section 4.3: for a = 0.3 (H0 = 0.09 m) the paper quotes p0 = 0.0814 m²/s
    assert cases.momentum_scale(0.09, theta) == pytest.approx(0.0814, abs=5e-5)
    assert cases.characteristic_time(0.14, theta) == pytest.approx(math.sqrt(0.14 / (9.81 * math.cos(theta))))


def test_case_tables():
    assert len(cases.table1()) == 14 and len(cases.table5()) == 4
    assert set(cases.table3().case_id) <= set(cases.table1().case_id)
    assert cases.material()["rho"] == 1550 and cases.material()["d"] == pytest.approx(7e-4)
    with pytest.raises(Exception, match="unknown material"):
        cases.material("sugar")
    with pytest.raises(Exception, match="not a valid case name"):
        cases.check_case_name("../etc")


def test_main_run_front_skips_a_release_heap_behind_a_trough():
    """The DA runout rule (``main_run_front``): a heap left at the back wall, deeper than the deposit
    down-slope and separated from it by a trough just below the threshold, is not the front; the
    walk from the deepest cell (``front_from_profile``) stops there."""
    from granudep.front import main_run_front
    edges = np.arange(101) * 0.01
    depth = np.full(100, 0.005)
    depth[:15] = 0.05                                   # heap at the wall
    depth[19] = 0.0013                                  # one cell just below 2 d = 1.4 mm
    depth[80:] = 0.0                                    # deposit ends at 0.8 m
    assert front_from_profile(edges, depth, 0.0014) == pytest.approx(0.19)
    assert main_run_front(edges, depth, 0.0014) == pytest.approx(0.80)
    depth[19] = 0.002                                   # no trough: both rules agree
    assert main_run_front(edges, depth, 0.0014) == front_from_profile(edges, depth, 0.0014) == pytest.approx(0.80)
    small = depth.copy()
    small[19] = 0.0013
    small[20:80] = 0.0
    small[90:92] = 0.002                                # a speck beyond a gap: < 1 % of the material
    assert main_run_front(edges, small, 0.0014) == pytest.approx(0.19)
