"""``granudep sensitivity-table``: the sensitivity runs collected into the table that
``granudep figure sensitivity`` reads (workflow/rules/sensitivity.smk, rule ``sensitivity_table``).

Each run is named ``baseline`` or ``{parameter}_{value}``. For every run: A, B of the monitored 2D
case (its coefficients.csv, one row) and the DA run's final_runout_norm and flow_time (scalars of
the DA NetCDF). The baseline run appears once per swept parameter, at that parameter's paper value,
with baseline = 1. No computation beyond reading.
"""
from __future__ import annotations

import math
from pathlib import Path

import pandas as pd

from ..config import ConfigError
import xarray as xr
from ..io import check_output, write_text


def one_run(coefficients: str | Path, da: str | Path) -> dict:
    """A, B (one-row coefficients.csv) and the DA run's final_runout_norm, flow_time (NaN if absent)."""
    for f in (coefficients, da):
        if not Path(f).is_file():
            raise ConfigError(f"sensitivity-table: file not found: {f}")
    coeffs = pd.read_csv(coefficients)
    if len(coeffs) != 1:
        raise ConfigError(f"sensitivity-table: {coefficients}: expected one case, found {len(coeffs)} rows")
    row = {"A": float(coeffs["A"].iloc[0]), "B": float(coeffs["B"].iloc[0])}
    with xr.open_dataset(da, decode_times=False) as ds:
        for name in ("final_runout_norm", "flow_time"):
            row[name] = float(ds[name].values) if name in ds else math.nan
    return row


def sensitivity_table(runs: dict[str, tuple[str, str]], baseline_values: dict[str, float]) -> pd.DataFrame:
    """``runs``: name -> (coefficients.csv, DA.nc); ``baseline_values``: the paper value of each
    swept parameter (where the baseline run sits). Columns: parameter, value, baseline, A, B,
    final_runout_norm, flow_time; sorted by parameter, value."""
    rows, baseline = [], None
    for name, (coefficients, da) in runs.items():
        values = one_run(coefficients, da)
        if name == "baseline":
            baseline = values
            continue
        try:
            param, value = name.rsplit("_", 1)
            value = float(value)
        except ValueError:
            raise ConfigError(f"sensitivity-table: run name {name!r}: must be 'baseline' or PARAMETER_VALUE") from None
        rows.append({"parameter": param, "value": value, "baseline": 0, **values})
    if baseline is None:
        raise ConfigError("sensitivity-table: no baseline run given")
    for param in dict.fromkeys(r["parameter"] for r in rows):
        if param not in baseline_values:
            raise ConfigError(f"sensitivity-table: --baseline-values has no value for {param!r}")
        rows.append({"parameter": param, "value": baseline_values[param], "baseline": 1, **baseline})
    return pd.DataFrame(rows).sort_values(["parameter", "value"], kind="stable").reset_index(drop=True)


def _pairs(items: list[str], what: str) -> list[tuple[str, str]]:
    out = []
    for item in items:
        if "=" not in item:
            raise ConfigError(f"sensitivity-table: {what} {item!r}: expected NAME=...")
        out.append(tuple(item.split("=", 1)))
    return out


def _cmd(args) -> int:
    check_output(args.output, suffixes=(".csv",))
    try:
        baseline_values = {k: float(v) for k, v in _pairs(args.baseline_values, "--baseline-values")}
    except ValueError as exc:
        raise ConfigError(f"sensitivity-table: --baseline-values: {exc}") from None
    runs = {}
    for name, files in _pairs(args.runs, "run"):
        if files.count(",") != 1:
            raise ConfigError(f"sensitivity-table: run {name!r}: expected NAME=COEFFS.csv,DA.nc")
        runs[name] = tuple(files.split(","))
    table = sensitivity_table(runs, baseline_values)
    print(table.to_string(index=False))
    write_text(table.to_csv(index=False), Path(args.output))
    return 0


def register(sub) -> None:
    p = sub.add_parser("sensitivity-table", help="collect the sensitivity runs (A, B, DA runout) into one CSV",
                       description=__doc__.splitlines()[0])
    p.add_argument("-o", "--output", required=True, help="CSV: parameter, value, baseline, A, B, final_runout_norm, flow_time")
    p.add_argument("--baseline-values", nargs="+", required=True, metavar="PARAM=VALUE",
                   help="the paper value of each swept parameter (where the baseline run sits)")
    p.add_argument("runs", nargs="+", metavar="NAME=COEFFS.csv,DA.nc")
    p.set_defaults(func=_cmd)
