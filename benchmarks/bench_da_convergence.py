"""Convergence of the DA runout in the particle number N: which N gives a runout that
changes < 1 % per doubling, and how long that run takes on one core.

Two problems, each without and with deposition, N doubled from ``--n-min`` to ``--n-max``:

* ``path``: the 1 km path of ``bench_da_path.py`` (30° over 600 m easing into a 400 m flat zone,
  σ = 20 m, 50 m × 5 m release, φ_I = 32°, φ_B = 28°), runout along the bed from the release end;
* ``1D-A70``: the paper's case (θ = 22°, a = 0.7, Table 5 A, B), runout from the gate.

With deposition x∞ is fixed (``x_inf_mode: user``) at the finest no-deposition front of the same
command, so every row is one run (the self-consistent x∞ iteration would multiply each row by 2–14
runs and mix its own tolerance into the convergence). Wall and CPU seconds are after compilation
(a small warm-up run first). Prints one table per problem; ``--csv``/``--figure`` write the data
(docs/data/da_convergence.csv, docs/figures/da_convergence.png):

    NUMBA_NUM_THREADS=1 python benchmarks/bench_da_convergence.py [--cases path 1D-A70] [--n-min 125]
        [--n-max 4000] [--csv docs/data/da_convergence.csv] [--figure docs/figures/da_convergence.png]
        [--set deposition.own_deposit=include ...]

W_min/dE and the largest energy rise between outputs (``granudep.da.energy``; with deposition the
deposit's energy is booked as bed): the Coulomb friction work can be no less than μ g Σ V Δx
(horizontal displacements), so W_min / (E_0 − E_end) ≤ 1 unless the scheme created energy, and E
never rises between outputs.

docs/data/da_convergence.csv holds one ladder per ``--label``: "strain" (the default earth pressure;
``--cases 1D-A70`` then ``--cases path``, ``--n-min 1000 --n-max 8000``, about 40 CPU-min, most of it
N = 8000) and the sign-switch variants measured before it ("particle switch", "symmetric switch");
docs/da-engineer-scale.md has the tables.

Converged N: the smallest N of the ladder whose runout differs < 1 % from that of 2N, and every
later doubling too (so it needs at least two rows above it to be called); also printed: the
smallest N whose runout stays within 1 % of the finest rung's (small changes per doubling can add
up to more than 1 %).
"""
from __future__ import annotations

import argparse
import csv
import math
import os
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

TOL = 0.01


def path_config(csv_file: Path, n: int) -> dict:
    from bench_da_path import config
    cfg = config(csv_file, n, "relative", True)
    return cfg


def a70_config(n: int) -> dict:
    return {"case": "1D-A70", "numerics": {"n_particles": n}}


def _set(cfg: dict, key: str, value) -> None:
    d = cfg
    parts = key.split(".")
    for k in parts[:-1]:
        d = d.setdefault(k, {})
    d[parts[-1]] = value


def one_run(cfg: dict, deposition: bool, x_inf: float | None):
    from granudep.da.api import run_da
    cfg = {k: (dict(v) if isinstance(v, dict) else v) for k, v in cfg.items()}
    if deposition:
        dep = dict(cfg.get("deposition", {}))
        dep.update({"enabled": True, "x_inf_mode": "user", "x_inf": float(x_inf)})
        cfg["deposition"] = dep
    t0, c0 = time.perf_counter(), time.process_time()
    ds = run_da(cfg, deposition=deposition)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    from granudep.da.energy import energy_report
    front = float(ds.front_position[-1])  # station s on a path (deposition.x_inf is a station), x otherwise
    en = energy_report(ds)
    return {"energy_ratio": en["coulomb_ratio"], "energy_rise": en["largest_rise"], "n_rises": en["n_rises"],
            "runout": float(ds.final_runout), "flow_time": float(ds.flow_time), "steps": int(ds.attrs["n_steps"]),
            "wall_s": wall, "cpu_s": cpu, "at_rest": int(ds.attrs["at_rest"]), "front": front,
            "x_inf_user": front, "max_speed": float(abs(ds.u).max()),
            # the 1 % volume front's runout (constant slope only): steadier than the 2 d front on thin deposits
            "runout_v99": (float(ds.final_front_v99) - float(ds.attrs["L0"])) if "final_front_v99" in ds
            and "L0" in ds.attrs else float("nan"),
            "L_s_final": float(ds.smoothing_length[-1])}


def ladder(n_min: int, n_max: int) -> list[int]:
    out, n = [], n_min
    while n <= n_max:
        out.append(n)
        n *= 2
    return out


def converged(rows: list[dict]) -> dict | None:
    """The smallest N whose runout changes < TOL to 2N and at every later doubling (at least two)."""
    chg = [r["change_next"] for r in rows]
    for i, r in enumerate(rows[:-2]):   # confirmed by at least two doublings above it
        if all(math.isfinite(c) and c < TOL for c in chg[i:-1]):
            return r
    return None


def near_finest(rows: list[dict]) -> dict | None:
    """The smallest N whose runout is within TOL of the finest rung's and stays there above it."""
    ref = rows[-1]["runout"]
    for i, r in enumerate(rows[:-1]):
        if all(abs(q["runout"] - ref) < TOL * abs(ref) for q in rows[i:]):
            return r
    return None


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", nargs="+", default=["path", "1D-A70"], choices=["path", "1D-A70"])
    ap.add_argument("--n-min", type=int, default=125)
    ap.add_argument("--n-max", type=int, default=4000)
    ap.add_argument("--deposition", choices=["both", "off", "on"], default="both")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="a config key for every run, e.g. deposition.own_deposit=include")
    ap.add_argument("--csv", type=Path)
    ap.add_argument("--figure", type=Path)
    ap.add_argument("--label", default="", help="a tag written in the CSV's 'variant' column")
    ap.add_argument("--x-inf", type=float, default=None,
                    help="x∞ of the deposition runs (station / from the wall); default: the finest no-deposition "
                         "front of the ladder")
    args = ap.parse_args()
    import yaml
    extra = [(k, yaml.safe_load(v)) for k, v in (s.split("=", 1) for s in args.set)]
    from granudep.da.path_verification import write_profile
    rows_all = []
    with tempfile.TemporaryDirectory() as tmp:
        t = math.tan(math.radians(30.0))
        csv_file = write_profile(Path(tmp) / "km.csv", [0.0, 300.0, 600.0, 800.0, 1000.0],
                                 [600.0 * t, 300.0 * t, 0.0, 0.0, 0.0])
        makers = {"path": lambda n: path_config(csv_file, n), "1D-A70": a70_config}
        # warm-up: compile (or load the cache of) the kernels once, outside the timings
        t0 = time.perf_counter()
        w = makers["1D-A70"](60)
        w["numerics"]["t_end"] = 0.05
        one_run(w, True, 1.0)
        print(f"warm-up (JIT or cache load): {time.perf_counter() - t0:.1f} s; NUMBA_NUM_THREADS="
              f"{os.environ.get('NUMBA_NUM_THREADS', 'unset')}, load average {os.getloadavg()[0]:.2f}", flush=True)
        for case in args.cases:
            x_inf = None
            deps = {"both": [False, True], "off": [False], "on": [True]}[args.deposition]
            if args.x_inf is not None:
                x_inf = args.x_inf
            elif True in deps and False not in deps:
                deps = [False, True]  # x∞ needs the finest no-deposition front
            for dep in deps:
                rows = []
                for n in ladder(args.n_min, args.n_max):
                    cfg = makers[case](n)
                    for k, v in extra:
                        _set(cfg, k, v)
                    if dep is False and args.deposition == "on" and n != args.n_max:
                        continue
                    r = one_run(cfg, dep, x_inf)
                    r.update(case=case, deposition=int(dep), n=n, variant=args.label)
                    rows.append(r)
                    print(f"  {case} {'dep' if dep else 'nodep'} N = {n}: runout {r['runout']:.4f} m "
                          f"(1 % volume front: {r['runout_v99']:.4f} m), flow time "
                          f"{r['flow_time']:.3f} s, {r['steps']} steps, wall {r['wall_s']:.2f} s, CPU {r['cpu_s']:.2f} s, "
                          f"energy ratio {r['energy_ratio']:.4f}, largest rise {r['energy_rise']:.2e} ({r['n_rises']} rises), max |u| {r['max_speed']:.2f} m/s"
                          f"{'' if r['at_rest'] else ' (NOT at rest)'}", flush=True)
                if not dep and args.x_inf is None:
                    x_inf = rows[-1]["x_inf_user"]
                    if args.deposition == "on":
                        continue
                for i, r in enumerate(rows):
                    nxt = rows[i + 1]["runout"] if i + 1 < len(rows) else float("nan")
                    prv = rows[i - 1]["runout"] if i > 0 else float("nan")
                    r["change_prev"] = abs(r["runout"] - prv) / abs(r["runout"]) if i > 0 else float("nan")
                    r["change_next"] = abs(nxt - r["runout"]) / abs(nxt) if i + 1 < len(rows) else float("nan")
                    r["x_inf"] = x_inf if dep else float("nan")
                c = converged(rows)
                head = f"{case}, {'with' if dep else 'without'} deposition" + (
                    f" (x_inf fixed at {x_inf:.4g} m: station / from the wall)" if dep else "")
                print(f"\n{head}\n{'N':>6} {'runout m':>10} {'chg/doubl':>9} {'flow t s':>9} {'steps':>7} "
                      f"{'wall s':>8} {'CPU s':>8} {'W_min/dE':>8} {'max|u|':>7}")
                for r in rows:
                    ch = "" if not math.isfinite(r["change_prev"]) else f"{100 * r['change_prev']:.2f} %"
                    print(f"{r['n']:>6} {r['runout']:>10.4f} {ch:>9} {r['flow_time']:>9.3f} {r['steps']:>7} "
                          f"{r['wall_s']:>8.2f} {r['cpu_s']:>8.2f} {r['energy_ratio']:>8.4f} {r['max_speed']:>7.2f}")
                if c is None:
                    print(f"converged N (< {100 * TOL:g} % per doubling from there on): not reached up to N = "
                          f"{rows[-1]['n']}")
                else:
                    print(f"converged N (< {100 * TOL:g} % per doubling from there on): {c['n']}, runout "
                          f"{c['runout']:.4f} m, wall {c['wall_s']:.2f} s, CPU {c['cpu_s']:.2f} s (target <= 10 s)")
                nf = near_finest(rows)
                if nf is not None:
                    print(f"smallest N within {100 * TOL:g} % of the finest ({rows[-1]['n']}) from there on: {nf['n']}, "
                          f"runout {nf['runout']:.4f} m, wall {nf['wall_s']:.2f} s, CPU {nf['cpu_s']:.2f} s")
                for r in rows:
                    r["converged_n"] = c["n"] if c else -1
                    r["near_finest_n"] = nf["n"] if nf else -1
                rows_all += rows
                print(flush=True)
    if args.csv:
        args.csv.parent.mkdir(parents=True, exist_ok=True)
        keys = ["variant", "case", "deposition", "n", "runout", "runout_v99", "change_prev", "flow_time", "steps", "wall_s",
                "cpu_s", "at_rest", "energy_ratio", "energy_rise", "n_rises", "max_speed", "L_s_final", "x_inf", "converged_n", "near_finest_n"]
        old_rows = []
        if args.csv.exists():  # keep the file's rows and column order (an older version of this script
            with args.csv.open(newline="") as f:  # may have written other columns, or in another order)
                rd = csv.DictReader(f)
                keys = list(rd.fieldnames) + [k for k in keys if k not in rd.fieldnames]
                old_rows = list(rd)
        with args.csv.open("w", newline="") as f:
            wr = csv.DictWriter(f, fieldnames=keys, extrasaction="ignore")
            wr.writeheader()
            wr.writerows(old_rows + rows_all)
    if args.figure:
        plot(args.csv if args.csv else None, rows_all, args.figure)


def plot(csv_path, rows, out: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import pandas as pd
    df = pd.read_csv(csv_path) if csv_path else pd.DataFrame(rows)
    df["variant"] = ["" if pd.isna(v) else str(v) for v in df["variant"]]
    cases = list(dict.fromkeys(df.case))
    fig, axes = plt.subplots(2, len(cases), figsize=(5 * len(cases), 7), squeeze=False)
    for j, case in enumerate(cases):
        for (var, dep), g in df[df.case == case].groupby(["variant", "deposition"]):
            lab = f"{'deposition' if dep else 'no deposition'}{(' ' + var) if var else ''}"
            axes[0, j].plot(g.n, g.runout, "o-", label=lab)
            axes[1, j].plot(g.n, g.cpu_s, "o-", label=lab)
        ns = sorted(set(df[df.case == case].n))
        for ax in axes[:, j]:
            ax.set_xscale("log", base=2)
            ax.set_xticks(ns, [str(n) for n in ns])
            ax.minorticks_off()
        axes[1, j].set_yscale("log")
        axes[0, j].set_title(case)
        axes[0, j].set_ylabel("final runout (m)")
        axes[1, j].set_ylabel("CPU s after JIT, one core")
        axes[1, j].axhline(10.0, color="k", lw=0.8, ls=":")
        axes[1, j].set_xlabel("particles N")
        axes[0, j].legend(fontsize=7)
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=120)


if __name__ == "__main__":
    main()
