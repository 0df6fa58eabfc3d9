"""a = H0/L0 computed in floating point must hit the table node it denotes."""
import pandas as pd
import pytest

from granudep.config import ConfigError
from granudep.abtable import interpolate_ab


def test_float_a_at_table_edge_node():
    table = pd.DataFrame({"case": ["T22-A70"], "theta_deg": [22.0], "a": [0.7], "A": [-0.03], "B": [0.04]})
    a = 0.14 / 0.2  # 0.7000000000000001
    assert a != 0.7
    assert interpolate_ab(table, a, 22.0) == (-0.03, 0.04)
    with pytest.raises(ConfigError, match="a: 0.71 is outside"):
        interpolate_ab(table, 0.71, 22.0)
