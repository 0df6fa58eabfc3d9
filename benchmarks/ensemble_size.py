"""How does an ensemble's spread settle with its size K? (Chooses config ensemble.members.)

    python benchmarks/ensemble_size.py --case T22-A70 --dx 0.004 --members 8 --workdir results/ensemble_size

Runs ``--members`` members of ``--case`` at ``--dx`` with the chain's perturbation (member 0 the
lattice, member k > 0 numerics.seed = k, numerics.jitter = ``--jitter``), two at a time, through the
``granudep isph``/``monitor``/``regress`` commands (a member already in ``--workdir`` is reused), then
prints, for K = 3, 5 and every K up to ``--members``, the mean, min-max and std of the final fronts,
both rest times and the four Table 3 critical times of the case over the first K members, and writes
the table to ``--workdir``/ensemble_size.csv.
"""
from __future__ import annotations

import argparse
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pandas as pd

from granudep.report.ensemble import run_quantities, stats


#: the sections of Table 3 ([x] = x / L_x)
TABLE3_X = (0.2, 0.4, 0.6, 0.8)


def member(workdir: Path, case: str, dx: float, k: int, jitter: float) -> Path:
    root = workdir / f"m{k}"
    run, sec, reg = root / "isph" / f"{case}.nc", root / "sections" / f"{case}.nc", root / "regression"
    sets = ["--set", f"numerics.seed={k}", "--set", f"numerics.jitter={jitter}"] if k else []
    env = {"NUMBA_NUM_THREADS": "1"}
    gd = [sys.executable, "-m", "granudep"]
    steps = [(run, [*gd, "isph", case, "--dx", str(dx), *sets, "-o", str(run)]),
             (sec, [*gd, "monitor", str(run), "-o", str(sec)]),
             (reg / "critical.csv", [*gd, "regress", str(sec), "-o", str(reg)])]
    for out, cmd in steps:
        if not out.exists():
            out.parent.mkdir(parents=True, exist_ok=True)
            with open(root / f"{out.parent.name}.log", "w") as log:
                subprocess.run(cmd, check=True, stdout=log, stderr=subprocess.STDOUT,
                               env={**__import__("os").environ, **env})
    return root


def member_numbers(root: Path, case: str) -> dict:
    q = run_quantities(root / "isph" / f"{case}.nc")
    q.pop("dx", None)
    crit = pd.read_csv(root / "regression" / "critical.csv")
    crit = crit[(crit["case"] == case) & crit["x_norm"].round(3).isin(TABLE3_X)]
    for r in crit.itertuples():
        q[f"t_crit_x{r.x_norm:g}"] = r.t_s_critical
    return q


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", default="T22-A70")
    ap.add_argument("--dx", type=float, default=0.004)
    ap.add_argument("--members", type=int, default=8)
    ap.add_argument("--jitter", type=float, default=0.01)
    ap.add_argument("--workdir", default="results/ensemble_size")
    ap.add_argument("-j", "--jobs", type=int, default=2)
    a = ap.parse_args()
    if not 3 <= a.members <= 64:
        raise SystemExit("--members: must be in [3, 64]")
    wd = Path(a.workdir)
    with ThreadPoolExecutor(a.jobs) as pool:
        roots = list(pool.map(lambda k: member(wd, a.case, a.dx, k, a.jitter), range(a.members)))
    per = pd.DataFrame([member_numbers(r, a.case) for r in roots])
    per.insert(0, "member", range(a.members))
    print(per.to_string(index=False, float_format=lambda v: f"{v:.3f}"))
    rows = []
    for K in sorted({3, 5, a.members} | set(range(3, a.members + 1))):
        for q in per.columns[1:]:
            s = stats(per[q].iloc[:K])
            rows.append({"K": K, "quantity": q, **s,
                         "spread_pct": 100 * (s["max"] - s["min"]) / abs(s["mean"]) if s["mean"] else float("nan")})
    table = pd.DataFrame(rows)
    print()
    print(table.pivot(index="quantity", columns="K", values="mean").to_string(float_format=lambda v: f"{v:.3f}"))
    print("\nspread (max - min) / mean, %:")
    print(table.pivot(index="quantity", columns="K", values="spread_pct").to_string(float_format=lambda v: f"{v:.1f}"))
    print("\nstd:")
    print(table.pivot(index="quantity", columns="K", values="std").to_string(float_format=lambda v: f"{v:.3f}"))
    table.to_csv(wd / "ensemble_size.csv", index=False)
    per.to_csv(wd / "members.csv", index=False)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
