"""Doubling study of a DA run in the particle number N: the runout and flow time at N, 2N, 4N, …,
the change per doubling, and the energy checks (``granudep.da.energy``) of each run — what says
whether the N a user picked gives the converged answer (``granudep da --convergence``)."""
from __future__ import annotations

import math
import time

import pandas as pd
from .api import run_da
from .energy import energy_report

TOL = 0.01  # < 1 % change per doubling: converged

COLUMNS = ["n", "runout_m", "change_per_doubling", "flow_time_s", "at_rest", "steps", "cpu_s", "coulomb_ratio",
           "largest_energy_rise", "n_energy_rises"]


def ladder(n_min: int, n_max: int) -> list[int]:
    """N = n_min, 2 n_min, … up to n_max."""
    if n_min < 20 or n_max < n_min:
        raise ValueError(f"convergence ladder: need 20 <= n_min <= n_max (got {n_min}, {n_max})")
    out, n = [], n_min
    while n <= n_max:
        out.append(n)
        n *= 2
    return out


def doubling_study(case_or_config, deposition, n_min: int, n_max: int, run=None, **overrides) -> pd.DataFrame:
    """One run per N of the ladder (same config otherwise); a row per N with ``COLUMNS``.
    ``run``: the run function (default ``api.run_da``), for tests."""
    run = run or run_da
    rows = []
    for n in ladder(n_min, n_max):
        c0 = time.process_time()
        ds = run(case_or_config, deposition=deposition, progress=False, **{**overrides, "n_particles": n})
        cpu = time.process_time() - c0
        en = energy_report(ds)
        rows.append({"n": n, "runout_m": float(ds.final_runout), "flow_time_s": float(ds.flow_time),
                     "at_rest": bool(ds.attrs["at_rest"]), "steps": int(ds.attrs["n_steps"]), "cpu_s": cpu,
                     "coulomb_ratio": en["coulomb_ratio"], "largest_energy_rise": en["largest_rise"],
                     "n_energy_rises": en["n_rises"]})
    df = pd.DataFrame(rows)
    prev = df.runout_m.shift(1)
    df["change_per_doubling"] = (df.runout_m - prev).abs() / df.runout_m.abs()
    return df[COLUMNS]


def converged_n(df: pd.DataFrame, tol: float = TOL) -> int | None:
    """The smallest N from which every further doubling changes the runout by < tol (at least one)."""
    ch = df.change_per_doubling.to_numpy()
    for i in range(len(df) - 1):
        later = ch[i + 1:]
        if later.size and all(math.isfinite(c) and c < tol for c in later):
            return int(df.n.iloc[i])
    return None


def format_table(df: pd.DataFrame) -> str:
    lines = [f"{'N':>7} {'runout m':>11} {'chg/doubl':>9} {'flow t s':>9} {'steps':>7} {'CPU s':>8} "
             f"{'W_min/dE':>8} {'E rises':>7} {'max rise':>9}"]
    for r in df.itertuples():
        ch = "" if not math.isfinite(r.change_per_doubling) else f"{100 * r.change_per_doubling:.2f} %"
        ft = f"{r.flow_time_s:.3f}" if math.isfinite(r.flow_time_s) else "not rest"
        ratio = f"{r.coulomb_ratio:.4f}" if math.isfinite(r.coulomb_ratio) else "-"
        rises = str(r.n_energy_rises) if r.n_energy_rises >= 0 else "-"
        top = f"{r.largest_energy_rise:.1e}" if math.isfinite(r.largest_energy_rise) else "-"
        lines.append(f"{r.n:>7} {r.runout_m:>11.4f} {ch:>9} {ft:>9} {r.steps:>7} {r.cpu_s:>8.2f} {ratio:>8} {rises:>7} "
                     f"{top:>9}")
    lines.append("W_min/dE <= 1 and no rise of E (max rise: the largest, relative to E0 - E_end) unless the scheme "
                 "created energy (granudep.da.energy)")
    c = converged_n(df)
    lines.append(f"converged N (< {100 * TOL:g} % per doubling from there on): "
                 + (f"{c}" if c is not None else f"not reached up to N = {int(df.n.iloc[-1])}"))
    return "\n".join(lines)
