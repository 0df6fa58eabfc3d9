"""The Fig-9 fit intercept is reported only where it is a reading of the onset inside the record."""
import math

import numpy as np

from granudep.regress.critical import growth_fit


def test_intercept_inside_record_is_kept():
    t = np.linspace(0.0, 10.0, 101)
    hd = np.clip(0.02 * (t - 4.0), 0.0, None)  # planted onset t_s = 4, rate 0.02
    i0 = int(np.flatnonzero(hd > 0)[0])
    rate, t_fit, r2, n = growth_fit(t, hd, i0, end_fraction=0.95, min_points=3)
    assert abs(rate - 0.02) < 1e-9 and abs(t_fit - 4.0) < 1e-6 and r2 > 0.999


def test_nearly_flat_growth_does_not_extrapolate_to_absurd_onset():
    t = np.linspace(0.0, 10.0, 101)
    hd = np.where(t >= 8.0, 0.1 + 1e-4 * (t - 8.0), 0.0)  # jump then almost flat: intercept far before t=0
    i0 = int(np.flatnonzero(hd > 0)[0])
    rate, t_fit, r2, n = growth_fit(t, hd, i0, end_fraction=1.0, min_points=3)
    assert rate > 0 and math.isnan(t_fit)
