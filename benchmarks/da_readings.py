"""Every reading of eq 36's (hu)_C through the DA: the DA runout with deposition each one leads to.

`granudep regress-diagnose` refits (hu)_C/p0 = A[x] + B with one choice of the method changed at a
time (`results/regression/diagnosis.csv`). This study feeds each reading's A, B of the four Table 5
geometries to the DA model (deposition on, A, B as normalised, eq 36 as printed) and compares the
final runout with the 2D reference of the same chain (`results/compare/reference_2d.csv`, front at
2 d in both models) and with the DA run without deposition. Not a test; prints a Markdown table and
writes a CSV.

    NUMBA_NUM_THREADS=1 python benchmarks/da_readings.py [--results results] [-o docs/data/da_readings.csv]
        [--n-particles 1000]
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

import pandas as pd

#: the 2D runs of the Table 5 geometries (config/config.yaml: da.reference_2d)
RUNS = {"T22-A30": "1D-A30", "T22-A45": "1D-A45", "T22-A70": "1D-A70", "T22-A124": "1D-A124"}


def study(results: Path, n_particles: int) -> pd.DataFrame:
    from granudep.da.api import run_da
    diag = pd.read_csv(results / "regression" / "diagnosis.csv")
    ref = pd.read_csv(results / "compare" / "reference_2d.csv").set_index("case")
    diag = diag[diag.case.isin(RUNS) & diag.A.notna() & diag.B.notna()]
    rows = []
    nodep = {}
    for run, case in RUNS.items():
        ds = run_da(case, deposition=False, n_particles=n_particles, progress=False)
        nodep[case] = float(ds["final_runout_norm"])
    for r in diag.itertuples():
        case = RUNS[r.case]
        ds = run_da(f"{case}", deposition={"ab_source": "user", "A": float(r.A), "B": float(r.B)},
                    n_particles=n_particles, progress=False)
        runout = float(ds["final_runout_norm"])
        ref_runout = float(ref.loc[case, "final_runout_norm"])
        rows.append({"variant": r.variant, "case": case, "a": r.a, "A": r.A, "B": r.B, "r2": r.r2,
                     "runout_norm": runout, "runout_norm_nodeposition": nodep[case],
                     "reference_2d_runout_norm": ref_runout,
                     "runout_error": runout / ref_runout - 1.0,
                     "shortening": 1.0 - runout / nodep[case]})
    return pd.DataFrame(rows)


def markdown(df: pd.DataFrame) -> str:
    cases = ["1D-A30", "1D-A45", "1D-A70", "1D-A124"]
    out = ["| reading | " + " | ".join(cases) + " |", "|---|" + "---|" * len(cases)]
    for v, g in df.groupby("variant", sort=False):
        cells = []
        for c in cases:
            s = g[g.case == c]
            cells.append("–" if s.empty else
                         f"{100 * s.runout_error.iloc[0]:+.0f} % ({100 * s.shortening.iloc[0]:.1f} % shorter)")
        out.append(f"| {v} | " + " | ".join(cells) + " |")
    return "\n".join(out)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--results", default="results", help="results folder of a finished chain")
    p.add_argument("-o", "--output", default=None, help="CSV of every (reading, case) run")
    p.add_argument("--n-particles", type=int, default=1000, help="DA particles (the workflow's 1000)")
    args = p.parse_args(argv)
    df = study(Path(args.results), args.n_particles)
    if args.output:
        df.to_csv(args.output, index=False)
    print("DA runout error against the 2D reference, with deposition (and how much shorter than "
          "without deposition), per reading of (hu)_C:\n")
    print(markdown(df))
    finite = df[df.runout_error.map(math.isfinite)]
    print(f"\n{len(finite)} runs, N = {args.n_particles}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
