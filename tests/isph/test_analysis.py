"""isph.analysis.failure_plane_angle on synthetic runs whose failure plane is known.

The one failure-plane definition (verification, Fig 5, captions, claims scorecard): the boundary,
on the particles' initial positions, of those moving faster than 0.1 m/s at t = t_c.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
import xarray as xr

from granudep.cases import characteristic_time
from granudep.isph.analysis import failure_plane_angle

L0, H0, DX, THETA = 0.2, 0.14, 0.004, 22.0


def planted_run(beta_deg: float, slump: float = 0.05, theta: float = THETA, with_tc: bool = True) -> xr.Dataset:
    """A column whose particles in front of a plane through the gate foot, ``beta_deg`` from the bed,
    move at 0.5 m/s at t = t_c; by then they have slumped (moved down-slope by ``slump`` and down
    towards the bed), so only their initial positions still show the plane."""
    X, Y = np.meshgrid(np.arange(DX / 2, L0, DX), np.arange(DX / 2, H0, DX))
    x0, y0 = X.ravel(), Y.ravel()
    moving = x0 > L0 - y0 / math.tan(math.radians(beta_deg))
    tc = characteristic_time(H0, math.radians(theta))
    time = np.array([0.0, 0.5 * tc, tc, 2 * tc])
    x = np.tile(x0, (time.size, 1))
    y = np.tile(y0, (time.size, 1))
    for k in (1, 2, 3):
        x[k, moving] += slump * k + 0.3 * y0[moving]  # sheared: the current boundary is not the plane
        y[k, moving] *= 0.6
    u = np.zeros_like(x)
    u[2, moving] = 0.5
    u[1, moving] = 0.05  # below the 0.1 m/s threshold at 0.5 t_c: nothing moves yet
    attrs = {"H0": H0, "L0": L0, "dx": DX, "theta_deg": theta}
    if with_tc:
        attrs["t_c"] = tc
    return xr.Dataset({"x": (("time", "particle"), x), "y": (("time", "particle"), y),
                       "u": (("time", "particle"), u), "v": (("time", "particle"), np.zeros_like(u))},
                      coords={"time": time}, attrs=attrs)


@pytest.mark.parametrize("beta", [35.0, 42.0, 50.0])  # planes that stay inside the column (> 32°)
def test_planted_plane_is_found_from_the_initial_positions(beta):
    fp = failure_plane_angle(planted_run(beta), t_norm=1.0)
    assert fp["points"] >= 20
    assert fp["angle_deg"] == pytest.approx(beta, abs=1.0)
    # Rankine's angle is from the horizontal: from the bed + θ
    assert fp["angle_horizontal_deg"] == pytest.approx(fp["angle_deg"] + THETA)
    assert fp["toe_x"] == pytest.approx(L0, abs=2 * DX)
    assert fp["time"] == pytest.approx(characteristic_time(H0, math.radians(THETA)))


def test_t_c_from_the_geometry_when_the_file_lacks_it():
    a = failure_plane_angle(planted_run(40.0), t_norm=1.0)
    b = failure_plane_angle(planted_run(40.0, with_tc=False), t_norm=1.0)
    assert a == b


def test_nothing_moving_gives_nan():
    fp = failure_plane_angle(planted_run(40.0), t_norm=0.5)  # 0.05 m/s < 0.1 m/s everywhere
    assert fp["points"] == 0 and math.isnan(fp["angle_deg"]) and math.isnan(fp["angle_horizontal_deg"])
