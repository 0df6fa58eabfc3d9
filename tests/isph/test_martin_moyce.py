"""The dam-break surge front against Martin & Moyce (1952): the data file and the comparison."""
import math

import numpy as np

from granudep.cases import G
from granudep.isph.verification import martin_moyce_1952, martin_moyce_comparison


def test_the_measured_surge_front_is_read_whole_and_advances():
    T, Z = martin_moyce_1952()
    assert T.size == Z.size == 15
    assert np.all(np.diff(T) > 0) and np.all(np.diff(Z) > 0)
    assert Z[0] > 1.0  # the front starts at the column's foot, Z = 1


def test_the_comparison_reads_a_front_10_percent_ahead_as_plus_10_percent_and_skips_unrun_times():
    T, Z = martin_moyce_1952()
    a = 0.057
    t_exp = T / math.sqrt(2.0 * G / a)
    t = np.concatenate([[0.0], t_exp])  # sampled exactly at the measured times
    z = np.concatenate([[a], Z * a])
    out = martin_moyce_comparison(t, z, 1.1 * z, a=a)
    assert out["n"] == 15
    assert abs(out["tail"]) < 1e-12 and out["tail_max"] < 1e-12
    assert abs(out["v99"] - 0.1) < 1e-12
    # a run that stopped half way is compared at the times it reached only
    half = t <= t_exp[7]
    short = martin_moyce_comparison(t[half], z[half], z[half], a=a)
    assert short["n"] == 8 and abs(short["t_max"] - T[7]) < 1e-12
