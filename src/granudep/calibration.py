"""The one declared calibration: the basal slip length L_s from the four Table 3 critical times of one
case (T22-A70 at dx = 4 mm, the ensemble mean), by a scan over L_s (docs/bed-law.md, "Calibration").

Objective (declared before any run): J(L_s) = mean over [x] = 0.2, 0.4, 0.6, 0.8 of
((t_s)_C,ours − (t_s)_C,paper)² / (t_s)_C,paper², with (t_s)_C,ours the mean over the ensemble
members at that L_s. The calibrated value is the minimiser of a parabola through the lowest scan
point and its two neighbours (the scan point itself at an end of the scan); the range is the
spread of the same minimiser computed member by member. Nothing but this case's Table 3 row is read.
"""
from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pandas as pd

from .cases import table3

X_NORMS = (0.2, 0.4, 0.6, 0.8)
_LS_DIR = re.compile(r"^ls([0-9]+(?:\.[0-9]+)?)$")
_MEMBER_DIR = re.compile(r"^m([0-9]+)$")


def paper_times(case: str) -> np.ndarray:
    """The paper's Table 3 critical times of ``case`` at :data:`X_NORMS`."""
    t = table3()
    row = t[t["case_id"] == case]
    if row.empty:
        raise ValueError(f"calibration: case {case!r} has no Table 3 row")
    return np.array([float(row[f"xM_{x}"].iloc[0]) for x in X_NORMS])


def objective(ours, paper) -> float:
    """Mean squared relative difference of the critical times (NaN if any is missing)."""
    ours, paper = np.asarray(ours, float), np.asarray(paper, float)
    if ours.shape != paper.shape or not np.all(np.isfinite(ours)):
        return math.nan
    return float(np.mean(((ours - paper) / paper) ** 2))


def parabola_minimum(x, y) -> float:
    """Minimiser of the parabola through the lowest finite point and its neighbours (the point itself
    at an end of the scan or when the three points do not curve upwards)."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    ok = np.isfinite(y)
    x, y = x[ok], y[ok]
    if x.size == 0:
        return math.nan
    order = np.argsort(x)
    x, y = x[order], y[order]
    k = int(np.argmin(y))
    if k == 0 or k == x.size - 1:
        return float(x[k])
    a, b, _ = np.polyfit(x[k - 1:k + 2], y[k - 1:k + 2], 2)
    return float(-b / (2 * a)) if a > 0 else float(x[k])


def member_times(root: Path, case: str) -> np.ndarray:
    """One member's critical times at :data:`X_NORMS` from its regression/table3_comparison.csv."""
    f = Path(root) / "regression" / "table3_comparison.csv"
    if not f.is_file():
        return np.full(len(X_NORMS), math.nan)
    t = pd.read_csv(f)
    t = t[t["case"] == case]
    return np.array([float(t.loc[np.isclose(t["x_norm"], x), "t_s_critical"].iloc[0])
                     if np.isclose(t["x_norm"], x).any() else math.nan for x in X_NORMS])


def scan_table(folder, case: str) -> pd.DataFrame:
    """Per slip length (folder ``ls{mm}``) and member (``m{k}``): the four critical times and J;
    plus one row per slip length with member = -1: the ensemble-mean times and their J."""
    paper = paper_times(case)
    rows = []
    for d in sorted(Path(folder).iterdir()):
        m = _LS_DIR.match(d.name)
        if not (m and d.is_dir()):
            continue
        ls = float(m.group(1))
        members = sorted((int(_MEMBER_DIR.match(e.name).group(1)), e) for e in d.iterdir()
                         if e.is_dir() and _MEMBER_DIR.match(e.name))
        times = []
        for k, e in members:
            t = member_times(e, case)
            times.append(t)
            rows.append({"slip_length_mm": ls, "member": k, **{f"t_{x}": v for x, v in zip(X_NORMS, t)},
                         "objective": objective(t, paper)})
        if times:
            mean = np.nanmean(np.vstack(times), axis=0) if np.all(np.isfinite(np.vstack(times))) else \
                np.full(len(X_NORMS), math.nan)
            rows.append({"slip_length_mm": ls, "member": -1, **{f"t_{x}": v for x, v in zip(X_NORMS, mean)},
                         "objective": objective(mean, paper)})
    cols = ["slip_length_mm", "member", *[f"t_{x}" for x in X_NORMS], "objective"]
    return pd.DataFrame(rows, columns=cols).sort_values(["slip_length_mm", "member"], ignore_index=True)


def calibrate(scan: pd.DataFrame) -> dict:
    """The calibrated L_s (mm) from the ensemble-mean curve, and the range of the member-by-member minimisers."""
    mean = scan[scan["member"] == -1]
    best = parabola_minimum(mean["slip_length_mm"], mean["objective"])
    per = [parabola_minimum(g["slip_length_mm"], g["objective"]) for k, g in scan[scan["member"] >= 0].groupby("member")]
    per = [p for p in per if math.isfinite(p)]
    j = mean["objective"].to_numpy(float)
    return {"slip_length_mm": best, "range_min_mm": min(per) if per else math.nan,
            "range_max_mm": max(per) if per else math.nan, "members": len(per),
            "objective_min": float(np.nanmin(j)) if np.isfinite(j).any() else math.nan,
            "scan_points": int(mean["slip_length_mm"].nunique())}


def figure(scan: pd.DataFrame, result: dict, case: str, path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from .io import atomic_path
    fig, ax = plt.subplots(figsize=(6, 4))
    for k, g in scan[scan["member"] >= 0].groupby("member"):
        ax.plot(g["slip_length_mm"], np.sqrt(g["objective"]) * 100, "o-", color="0.7", lw=0.8, ms=3,
                label="members" if k == 0 else None)
    mean = scan[scan["member"] == -1]
    ax.plot(mean["slip_length_mm"], np.sqrt(mean["objective"]) * 100, "o-", color="C0", label="ensemble mean")
    if math.isfinite(result["slip_length_mm"]):
        ax.axvline(result["slip_length_mm"], color="C3", lw=1, label=f"calibrated {result['slip_length_mm']:.1f} mm")
        if math.isfinite(result["range_min_mm"]):
            ax.axvspan(result["range_min_mm"], result["range_max_mm"], color="C3", alpha=0.15,
                       label="member minimisers")
    ax.axvline(18.0, color="k", ls="--", lw=1, label="published 18 mm")
    ax.set_xlabel("slip length L_s (mm)")
    ax.set_ylabel("RMS relative difference of (t_s)_C (%)")
    ax.set_title(f"Calibration of L_s on the {case} row of Table 3 (dx = 4 mm)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    atomic_path(path, lambda tmp: fig.savefig(tmp, dpi=120, format="png"))
    plt.close(fig)


def _cmd(args) -> int:
    from .config import ConfigError
    from .io import write_text
    from .progress import LOG
    if not Path(args.folder).is_dir():
        raise ConfigError(f"calibration: folder not found: {args.folder}")
    scan = scan_table(args.folder, args.case)
    if scan.empty:
        raise ConfigError(f"calibration: no ls<mm>/m<k>/regression folders under {args.folder}")
    result = calibrate(scan)
    write_text(scan.to_csv(index=False), args.output)
    write_text(pd.DataFrame([{"case": args.case, **result}]).to_csv(index=False), args.result)
    if args.figure:
        figure(scan, result, args.case, args.figure)
    LOG.info("calibration on %s: L_s = %.2f mm (members %.2f-%.2f mm), RMS difference %.1f %%", args.case,
             result["slip_length_mm"], result["range_min_mm"], result["range_max_mm"],
             100 * math.sqrt(result["objective_min"]) if math.isfinite(result["objective_min"]) else math.nan)
    return 0


def register(sub) -> None:
    p = sub.add_parser("calibration", help="the slip-length calibration curve on one case's Table 3 row",
                       description=__doc__.splitlines()[0])
    p.add_argument("folder", help="folder of ls<mm>/m<k>/regression/ (the calibration target's runs)")
    p.add_argument("--case", default="T22-A70", help="the calibration case (default T22-A70)")
    p.add_argument("-o", "--output", required=True, help="CSV: the scan, per slip length and member")
    p.add_argument("--result", required=True, help="CSV: the calibrated slip length and its range")
    p.add_argument("--figure", help="PNG of the curve")
    p.set_defaults(func=_cmd)
