"""Every reading of eq 36's (hu)_C carried through the DA: the runout with deposition each one gives.

`granudep regress-diagnose` refits (hu)_C/p0 = A[x] + B with one choice of the method changed at a
time (``regression/diagnosis.csv``: depth, velocity, onset rule, gate section, x∞, W_M). Each
reading's A, B of the four Table 5 geometries is fed to the DA model with deposition (A, B as
normalised, eq 36 as printed, everything else as the chain's ``granudep da`` runs) and its final
runout is compared with the 2D reference of the same chain (``compare/reference_2d.csv``, front at
2 d in both models) and with the DA run without deposition: does any reading of (hu)_C make
deposition matter (the paper: up to 38 points of runout error)?
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Callable

import pandas as pd
from ..da.api import run_da

#: the Table 5 DA cases, in the order of a/H0
DA_CASES = ("1D-A30", "1D-A45", "1D-A70", "1D-A124")


def two_d_case(row) -> str:
    """The 2D run behind a reference row: the stem of its ``path`` (``results/isph/T22-A70.nc``)."""
    path = getattr(row, "path", None)
    if not isinstance(path, str) or not path:
        raise ValueError(f"reference row {row.case}: no 'path' naming its 2D run")
    return Path(path).stem


def _run_runout(case: str, n_particles: int, deposition) -> float:
    ds = run_da(case, deposition=deposition, n_particles=n_particles, progress=False)
    return float(ds["final_runout_norm"])


def reading_runs(diagnosis: pd.DataFrame, reference: pd.DataFrame, n_particles: int,
                 runout: Callable[[str, int, object], float] = _run_runout) -> pd.DataFrame:
    """One DA run with deposition per (reading, Table 5 geometry of the reference) of ``diagnosis``
    that has finite A, B, and one without deposition per geometry. ``runout(case, n, deposition)`` returns the
    final ΔL/L0 (``deposition``: False, or the deposition section with A, B)."""
    ref = reference.set_index("case")
    present = [c for c in DA_CASES if c in ref.index]
    if not present:
        raise ValueError(f"reference: no row for any Table 5 case ({', '.join(DA_CASES)})")
    to_da = {two_d_case(r): c for c, r in zip(ref.index, ref.itertuples()) if c in DA_CASES}
    rows = []
    nodep = {c: runout(c, n_particles, False) for c in present}
    for r in diagnosis.itertuples():
        case = to_da.get(r.case)
        if case is None or not (math.isfinite(r.A) and math.isfinite(r.B)):
            continue
        dep = runout(case, n_particles, {"ab_source": "user", "A": float(r.A), "B": float(r.B)})
        ref_runout = float(ref.loc[case, "final_runout_norm"])
        rows.append({"reading": r.variant, "case": case, "run_2d": r.case, "a": r.a, "A": r.A, "B": r.B,
                     "r2": r.r2, "n_particles": n_particles, "runout_norm": dep,
                     "runout_norm_nodeposition": nodep[case], "reference_2d_runout_norm": ref_runout,
                     "runout_error": dep / ref_runout - 1.0,
                     "runout_error_nodeposition": nodep[case] / ref_runout - 1.0,
                     "shortening": 1.0 - dep / nodep[case]})
    return pd.DataFrame(rows)


def pivot_markdown(df: pd.DataFrame) -> str:
    """Reading × geometry: DA runout error against the 2D reference with deposition, and in
    brackets how much shorter than the DA without deposition."""
    cases = [c for c in DA_CASES if c in set(df.case)]
    out = ["| reading | " + " | ".join(cases) + " |", "|---|" + "---|" * len(cases)]
    for v, g in df.groupby("reading", sort=False):
        cells = []
        for c in cases:
            s = g[g.case == c]
            cells.append("–" if s.empty else
                         f"{100 * s.runout_error.iloc[0]:+.0f} % ({100 * s.shortening.iloc[0]:.1f} % shorter)")
        out.append(f"| {v} | " + " | ".join(cells) + " |")
    nd = df.drop_duplicates("case").set_index("case")
    out.append("| *no deposition* | " + " | ".join(f"{100 * nd.loc[c, 'runout_error_nodeposition']:+.0f} %"
                                                  for c in cases) + " |")
    return "\n".join(out)
