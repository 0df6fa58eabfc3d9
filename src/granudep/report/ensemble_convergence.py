"""Convergence with the spread beside it: per 2D case and quantity (fronts, both rest times), the
ensemble mean and spread at the chain's dx and at a finer dx, a single lattice run at the finest dx,
whether the dx change exceeds the spread, and the observed order where the three levels are monotone.

Each level is a ``granudep ensemble --quantities`` table (case, quantity, n, mean, min, max, std,
member0, dx). A quantity of a case is called *well-defined* at the chain's dx when both its ensemble
spread ((max − min) / |mean|, the larger of the two ensembles') and its change of the mean to the
finer ensemble are within ``threshold_pct``; otherwise the larger of the two figures is named. Among the rest measures the
*robust* one of a case is the one whose larger figure is smaller: chosen by spread and dx change,
never by agreement with the paper.
"""
from __future__ import annotations

import math
import pandas as pd

from ..richardson import observed_order
from .ensemble import QUANTITIES

#: the rest measures a robust one is chosen from (ensemble.QUANTITIES names)
REST_MEASURES = ("rest_time", "rest_time_mass99")
TABLE_COLUMNS = ["case", "quantity", "dx_coarse_mm", "n_coarse", "mean_coarse", "spread_coarse_pct", "std_coarse",
                 "dx_fine_mm", "n_fine", "mean_fine", "spread_fine_pct", "change_pct", "change_exceeds_spread",
                 "dx_single_mm", "single", "order", "extrapolated", "order_note", "verdict"]


def spread_pct(row) -> float:
    """(max − min) / |mean| in %, NaN for one member or a zero mean."""
    if not (row["n"] > 1 and math.isfinite(row["mean"]) and row["mean"] != 0.0):
        return math.nan
    return 100.0 * (row["max"] - row["min"]) / abs(row["mean"])


def _verdict(spread: float, change: float, threshold_pct: float) -> str:
    if not math.isfinite(spread):
        return "not measured (one member at the chain's dx)"
    if not math.isfinite(change):
        return (f"spread {spread:.1f} %; dx change not measured" if spread <= threshold_pct
                else f"ill-conditioned: spread {spread:.1f} % > {threshold_pct:g} %")
    if spread > threshold_pct and spread >= abs(change):
        return f"ill-conditioned: spread {spread:.1f} % > {threshold_pct:g} %"
    if abs(change) > threshold_pct:
        return f"not converged: dx change {change:+.1f} % > {threshold_pct:g} %"
    return f"well-defined (spread {spread:.1f} %, dx change {change:+.1f} %)"


def convergence_table(levels: list[pd.DataFrame], threshold_pct: float = 10.0) -> pd.DataFrame:
    """One row per (case, quantity) present at two levels at least: the coarsest level with several
    members is the chain's (``coarse``), the next finer one with several members the ``fine``
    ensemble, and the finest level with one member the ``single`` run."""
    if not levels:
        return pd.DataFrame(columns=TABLE_COLUMNS)
    t = pd.concat([lv.assign(dx=pd.to_numeric(lv["dx"], errors="coerce")) for lv in levels], ignore_index=True)
    rows = []
    for (case, q), g in t.groupby(["case", "quantity"], sort=False):
        g = g.sort_values("dx", ascending=False)
        ens = g[g["n"] > 1]
        one = g[g["n"] == 1]
        if len(ens) == 0 or len(g) < 2:
            continue
        c = ens.iloc[0]
        f = ens.iloc[1] if len(ens) > 1 else None
        s = one[one["dx"] < (f["dx"] if f is not None else c["dx"])]
        s = s.iloc[-1] if len(s) else None
        sc = spread_pct(c)
        change = 100.0 * (f["mean"] - c["mean"]) / abs(c["mean"]) if f is not None and c["mean"] else math.nan
        sf = spread_pct(f) if f is not None else math.nan
        order = {"order": math.nan, "extrapolated": math.nan, "reason": "three levels are needed"}
        if f is not None and s is not None:
            order = observed_order([s["dx"], f["dx"], c["dx"]], [s["mean"], f["mean"], c["mean"]])
            order["reason"] = (order["reason"] + "; " if order["reason"] else "") + "finest level: one lattice run"
        rows.append({"case": case, "quantity": q, "dx_coarse_mm": 1e3 * c["dx"], "n_coarse": int(c["n"]),
                     "mean_coarse": c["mean"], "spread_coarse_pct": sc, "std_coarse": c["std"],
                     "dx_fine_mm": 1e3 * f["dx"] if f is not None else math.nan,
                     "n_fine": int(f["n"]) if f is not None else 0,
                     "mean_fine": f["mean"] if f is not None else math.nan, "spread_fine_pct": sf,
                     "change_pct": change,
                     "change_exceeds_spread": bool(math.isfinite(change) and abs(change) > max(sc, sf if math.isfinite(sf) else 0.0)),
                     "dx_single_mm": 1e3 * s["dx"] if s is not None else math.nan,
                     "single": s["mean"] if s is not None else math.nan,
                     "order": order["order"], "extrapolated": order["extrapolated"], "order_note": order["reason"],
                     "verdict": _verdict(max(sc, sf) if math.isfinite(sf) else sc, change, threshold_pct)})
    return pd.DataFrame(rows, columns=TABLE_COLUMNS)


def robust_rest_measure(table: pd.DataFrame, threshold_pct: float = 10.0) -> pd.DataFrame:
    """Per case: the rest measure (:data:`REST_MEASURES`) whose largest figure of the two spreads and
    |dx change| is smallest, with that figure of each measure."""
    rows = []
    rest = table[table["quantity"].isin(REST_MEASURES)]
    for case, g in rest.groupby("case", sort=False):
        worst = {r.quantity: max(r.spread_coarse_pct, r.spread_fine_pct if math.isfinite(r.spread_fine_pct) else 0.0,
                                 abs(r.change_pct) if math.isfinite(r.change_pct) else 0.0)
                 for r in g.itertuples()}
        worst = {k: v for k, v in worst.items() if math.isfinite(v)}
        if not worst:
            continue
        best = min(worst, key=worst.get)
        rows.append({"case": case, "robust": best, "within_threshold": bool(worst[best] <= threshold_pct),
                     **{f"worst_{k}_pct": v for k, v in worst.items()}})
    return pd.DataFrame(rows)


def read_levels(paths) -> list[pd.DataFrame]:
    from ..config import ConfigError
    out = []
    for p in paths:
        try:
            t = pd.read_csv(p, dtype={"case": str})
        except (OSError, pd.errors.ParserError, pd.errors.EmptyDataError) as exc:
            raise ConfigError(f"convergence-table: cannot read {p} ({exc})") from None
        need = {"case", "quantity", "n", "mean", "min", "max", "std", "dx"}
        if not need <= set(t.columns):
            raise ConfigError(f"convergence-table: {p} must have the columns {sorted(need)} (granudep ensemble --quantities)")
        out.append(t)
    return out


def markdown(table: pd.DataFrame) -> str:
    from .markdown import md_table
    if table.empty:
        return "No quantity at two resolutions."
    t = table.copy()
    t["quantity"] = t["quantity"].map(lambda q: QUANTITIES.get(q, (q,))[0])
    t["order_text"] = [f"{o:.2f}" if math.isfinite(o) else _short_reason(n) for o, n in zip(t["order"], t["order_note"])]
    return md_table(t, {"case": ("case", ""), "quantity": ("quantity", ""),
                        "mean_coarse": ("mean, chain dx", ".3g"), "spread_coarse_pct": ("spread %", ".1f"),
                        "dx_fine_mm": ("finer dx (mm)", ".3g"), "mean_fine": ("mean, finer", ".3g"),
                        "spread_fine_pct": ("spread %", ".1f"), "change_pct": ("dx change %", "+.1f"),
                        "single": ("single, finest", ".3g"), "dx_single_mm": ("finest dx (mm)", ".3g"),
                        "order_text": ("observed order", ""), "verdict": ("verdict", "")})


def _short_reason(note) -> str:
    """The observed-order column when there is no order: why, in a few words."""
    note = str(note)
    for key, text in (("oscillating", "none (not monotone)"), ("no positive", "none (differences do not shrink)"),
                      ("same value", "none (two levels equal)"), ("three levels", "– (two levels)")):
        if key in note:
            return text
    return "–"


def _cmd(args) -> int:
    from ..io import write_text
    table = convergence_table(read_levels(args.levels), args.threshold_pct)
    print(markdown(table))
    write_text(table.to_csv(index=False), args.output)
    if args.robust:
        write_text(robust_rest_measure(table, args.threshold_pct).to_csv(index=False), args.robust)
    return 0


def _threshold(text: str) -> float:
    import argparse
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--threshold-pct: not a number: {text!r}")
    if not 0.0 < v <= 100.0:
        raise argparse.ArgumentTypeError(f"--threshold-pct: must be in (0, 100] (got {text})")
    return v


def register(sub) -> None:
    p = sub.add_parser("convergence-table", help="ensemble means and spreads at two dx and a single finer run",
                       description=__doc__.splitlines()[0])
    p.add_argument("levels", nargs="+", metavar="QUANTITIES.csv",
                   help="granudep ensemble --quantities tables, one per dx (any order)")
    p.add_argument("-o", "--output", required=True, metavar="CSV")
    p.add_argument("--robust", metavar="CSV", help="also write the robust rest measure per case")
    p.add_argument("--threshold-pct", type=_threshold, default=10.0,
                   help="spread and dx change (%%) within which a quantity is called well-defined (default 10)")
    p.set_defaults(func=_cmd)


__all__ = ["convergence_table", "robust_rest_measure", "read_levels", "markdown"]
