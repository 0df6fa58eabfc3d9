"""granudep.report.ensemble: the members' statistics and the verdicts that know the spread and the dx change."""
import math

import numpy as np
import pandas as pd
import pytest

from granudep.report import ensemble as ens


def test_stats_match_numpy_and_skip_missing_members():
    v = [1.0, 2.5, np.nan, 4.0]
    s = ens.stats(v)
    f = np.array([1.0, 2.5, 4.0])
    assert s["n"] == 3 and s["mean"] == pytest.approx(f.mean()) and s["std"] == pytest.approx(f.std(ddof=1))
    assert (s["min"], s["max"]) == (1.0, 4.0)
    assert math.isnan(ens.stats([3.0])["std"]) and ens.stats([])["n"] == 0


def _s(values):
    return ens.stats(values)


@pytest.mark.parametrize("values, fine, expected", [
    ([10.0, 10.2, 9.9], math.nan, "reproduced"),          # paper 10 within 10 %, spread 0.3 < 1
    ([10.0, 10.2, 9.9], 10.5, "reproduced"),              # dx change +0.47 < 1
    ([9.0, 10.5, 11.2], math.nan, "indeterminate"),       # spread 2.2 > 1
    ([10.0, 10.2, 9.9], 11.4, "indeterminate"),           # dx change +1.37 > 1
    ([13.0, 13.2, 12.9], math.nan, "not reproduced"),     # mean 13 off by 30 %, spread small
    ([11.0, 12.0, 12.6], math.nan, "indeterminate"),      # spread 1.6 > 1 and mean 11.87 within 1 + 1.6 of 10
    ([59.0, 61.0, 60.5], math.nan, "not reproduced"),     # spread 2 > 1, but 60 lies 50 away: beyond 1 + 2
    ([20.0, 20.1, 19.9], 10.2, "indeterminate"),          # 2x off, but the finer mean (dx change -9.8) is within reach
])
def test_two_sided_verdicts(values, fine, expected):
    v, why = ens.ensemble_verdict("rel", 10.0, 0.1, _s(values), values, fine)
    assert v == expected
    if expected == "indeterminate":
        assert ("spread" in why) or ("dx change" in why)


def test_one_sided_verdicts_need_every_member_on_one_side():
    assert ens.ensemble_verdict("lt", 0.03, 0.0, _s([0.01, 0.02]), [0.01, 0.02])[0] == "reproduced"
    v, why = ens.ensemble_verdict("lt", 0.03, 0.0, _s([0.01, 0.04]), [0.01, 0.04])
    assert v == "indeterminate" and "both sides" in why
    assert ens.ensemble_verdict("gt", 0.95, 0.0, _s([0.5, 0.6]), [0.5, 0.6])[0] == "not reproduced"
    assert ens.ensemble_verdict("gt", 0.95, 0.0, _s([0.97, 0.98]), [0.97, 0.98], 0.9)[0] == "indeterminate"
    assert ens.ensemble_verdict("rel", 1.0, 0.1, _s([]), [])[0] == "not checkable"


def _card0():
    from granudep.report.claims import CLAIM_COLUMNS
    rows = [{"claim_id": "a", "case": "T22-A70", "paper_value": 10.0, "ours_paper_res": 10.1, "verdict": "reproduced",
             "test": "rel", "tolerance": 0.1, "note": "first"},
            {"claim_id": "b", "case": "–", "paper_value": 0.0, "ours_paper_res": 0.0, "verdict": "not checkable",
             "test": "lt", "tolerance": 0.01, "note": "vacuous"}]
    return pd.DataFrame([{c: r.get(c, "") for c in CLAIM_COLUMNS} for r in rows])


def test_scorecard_takes_member_0_from_the_chain_and_keeps_not_checkable():
    members = pd.DataFrame({"claim_id": ["a", "a", "a", "b", "b"], "case": "x", "member": [0, 1, 2, 1, 2],
                            "value": [99.0, 10.4, 9.6, 0.0, 0.0]})  # member 0's 99 is the stale copy: card0 wins
    fine = pd.DataFrame({"claim_id": ["a", "a"], "member": [0, 1], "value": [10.8, 11.0]})
    card = ens.ensemble_scorecard(_card0(), members, fine, fine_dx_mm=2.0)
    a = card.set_index("claim_id").loc["a"]
    assert a["ours_paper_res"] == pytest.approx((10.1 + 10.4 + 9.6) / 3) and a["members"] == 3
    assert a["member0"] == 10.1 and (a["ours_min"], a["ours_max"]) == (9.6, 10.4)
    assert a["ours_fine"] == pytest.approx(10.9) and a["fine_dx_mm"] == 2.0
    assert a["dx_change"] == pytest.approx(10.9 - a["ours_paper_res"])
    assert a["verdict"] == "reproduced" and "3 member(s)" in a["note"]
    assert card.set_index("claim_id").loc["b", "verdict"] == "not checkable"
    assert list(card.columns) == ens.ENSEMBLE_COLUMNS


def test_read_member_table_names_the_option(tmp_path):
    from granudep.config import ConfigError
    bad = tmp_path / "bad.csv"
    bad.write_text("x,y\n1,2\n")
    with pytest.raises(ConfigError, match="--fine-ensemble"):
        ens.read_member_table(bad, "--fine-ensemble")
    with pytest.raises(ConfigError, match="cannot read"):
        ens.read_member_table(tmp_path / "absent.csv", "--ensemble")
