#!/usr/bin/env python3
"""Collect the sensitivity runs into the table `granudep figure sensitivity` reads.

Usage: sensitivity_table.py -o OUT.csv --baseline-values KEY=VALUE... RUN_DIR_NAME=COEFFS.csv,DA.nc...

Each run is named ``baseline`` or ``{parameter}_{value}`` (workflow/rules/sensitivity.smk). For
every run: A, B of the monitored 2D case (its coefficients.csv, one row) and the DA run's
final_runout_norm and flow_time (scalars of the DA NetCDF). The baseline run appears once per
swept parameter, at that parameter's paper value, with baseline = 1. No computation beyond reading.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import pandas as pd
import xarray as xr

from granudep.io import write_text


def one_run(coefficients: str, da: str) -> dict:
    coeffs = pd.read_csv(coefficients)
    if len(coeffs) != 1:
        raise SystemExit(f"{coefficients}: expected one case, found {len(coeffs)} rows")
    row = {"A": float(coeffs["A"].iloc[0]), "B": float(coeffs["B"].iloc[0])}
    with xr.open_dataset(da, decode_times=False) as ds:
        for name in ("final_runout_norm", "flow_time"):
            row[name] = float(ds[name].values) if name in ds else float("nan")
    return row


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--output", required=True)
    parser.add_argument("--baseline-values", nargs="+", required=True, metavar="PARAM=VALUE",
                        help="the paper value of each swept parameter (where the baseline run sits)")
    parser.add_argument("runs", nargs="+", metavar="NAME=COEFFS.csv,DA.nc")
    args = parser.parse_args(argv)
    baseline_values = {k: float(v) for k, v in (item.split("=", 1) for item in args.baseline_values)}
    rows, baseline = [], None
    for item in args.runs:
        name, files = item.split("=", 1)
        coefficients, da = files.split(",", 1)
        values = one_run(coefficients, da)
        if name == "baseline":
            baseline = values
            continue
        param, value = name.rsplit("_", 1)
        rows.append({"parameter": param, "value": float(value), "baseline": 0, **values})
    if baseline is None:
        raise SystemExit("no baseline run given")
    for param in dict.fromkeys(r["parameter"] for r in rows):
        rows.append({"parameter": param, "value": baseline_values[param], "baseline": 1, **baseline})
    table = pd.DataFrame(rows).sort_values(["parameter", "value"], kind="stable")
    print(table.to_string(index=False))
    write_text(table.to_csv(index=False), Path(args.output))
    return 0


if __name__ == "__main__":
    sys.exit(main())
