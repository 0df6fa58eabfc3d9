"""One file of each stage is CF-1.10 clean (IOOS compliance-checker when installed)."""
from __future__ import annotations

import json
import sys
from pathlib import Path

import netCDF4
import pytest

import granudep
from granudep.io import CF_TIME_UNITS, write_netcdf

HERE = Path(__file__).resolve().parent


@pytest.fixture(scope="module")
def stage_files(tmp_path_factory):
    """A tiny file of each stage: 2D run, DA run, sections, regression coefficients."""
    sys.path.insert(0, str(HERE.parent / "regress"))
    from test_regress import make_sections
    from granudep.regress.api import regress, write_outputs
    d = tmp_path_factory.mktemp("cf")
    granudep.run_isph("T22-A70", dx=0.02, t_end=0.05, output=d / "isph.nc", progress=False)
    da = granudep.run_da("1D-A70", deposition=False, n_particles=40, numerics={"t_end": 0.1}, progress=False)
    write_netcdf(da, d / "da.nc")
    write_netcdf(granudep.monitor(d / "isph.nc", x_inf=0.3), d / "sections.nc")
    write_outputs(regress([make_sections()[0]]), d / "reg")
    return {"isph": d / "isph.nc", "da": d / "da.nc", "sections": d / "sections.nc",
            "regress": d / "reg" / "coefficients.nc"}


@pytest.mark.parametrize("stage", ["isph", "da", "sections", "regress"])
def test_cf_basics_without_the_checker(stage_files, stage):
    with netCDF4.Dataset(stage_files[stage]) as nc:
        assert nc.Conventions == "CF-1.10" and nc.title.startswith("granudep")
        assert nc.granudep_commit and nc.granudep_version == granudep.__version__
        names = [n.lower() for n in nc.variables]
        assert len(names) == len(set(names)), "names differing only by case"
        if "time" in nc.variables:
            t = nc["time"]
            assert t.standard_name == "time" and t.units == CF_TIME_UNITS and t.calendar == "standard"
            for name, v in nc.variables.items():  # CF 2.4: other dimensions left of T
                if "time" in v.dimensions:
                    assert v.dimensions[-1] == "time", name
        for name, v in nc.variables.items():
            assert v.dtype is not str, f"{name}: NC_STRING (crashes older checkers); char arrays wanted"


def test_open_dataset_gives_the_stages_layout_back(stage_files):
    ds = granudep.load(stage_files["isph"])
    assert ds.x.dims == ("time", "particle") and ds.time.dtype.kind == "f" and float(ds.time[0]) == 0.0
    da = granudep.load(stage_files["da"])
    assert da.flow_depth.dims == ("time", "x_grid")
    reg = granudep.load(stage_files["regress"])
    assert reg.case.dtype.kind in "UO" and "aspect_ratio" in reg and "a" not in reg


@pytest.mark.parametrize("stage", ["isph", "da", "sections", "regress"])
def test_ioos_compliance_checker_cf_1_10(stage_files, stage, tmp_path):
    pytest.importorskip("compliance_checker")
    from compliance_checker.runner import CheckSuite, ComplianceChecker
    CheckSuite().load_all_available_checkers()
    report = tmp_path / "report.json"
    ComplianceChecker.run_checker(str(stage_files[stage]), ["cf:1.10"], 0, "normal",
                                  output_filename=str(report), output_format="json")
    result = list(json.loads(report.read_text()).values())[0]
    assert not result.get("errors"), result.get("errors")
    bad = [(prio, c["name"], c["msgs"][:2]) for prio in ("high_priorities", "medium_priorities")
           for c in result.get(prio, []) if c["value"][0] < c["value"][1]]
    assert bad == [], bad
