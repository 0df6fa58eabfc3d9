"""Ensembles of the 2D runs: every member's numbers, their mean and spread, and verdicts that know both
the spread and the resolution change.

A member is a results folder laid out as the chain's own (``isph/``, ``sections/``, ``regression/``):
member 0 is the chain's folder, members k > 0 start from the lattice jittered by numerics.jitter dx
(numerics.seed = k). :func:`member_claims` reads every member's claims scorecard
(:func:`claims.scorecard`), :func:`member_quantities` the per-case fronts and rest times;
:func:`ensemble_scorecard` turns them into one row per claim with the members' mean, min, max, std and
count, the change of the mean from the chain's dx to a finer ensemble where one has run, and the verdict:

* ``reproduced``: the paper's value within the tolerance of our mean, and both the spread (max − min
  of the members) and the dx change (where measured) within the tolerance;
* ``indeterminate``: the spread or the dx change exceeds the tolerance (the note gives the figure), and
  the paper's value lies within the tolerance plus that figure of our mean (the uncertainty could
  bring it within reach);
* ``not reproduced``: otherwise (also when the spread or the dx change is wide but the paper's value
  lies beyond the tolerance plus it); ``not checkable`` when no member has the number.

For the one-sided claims (``lt``/``gt``) "within the tolerance" means: every member on the same side of
the bound, and the finer mean on the same side as ours.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd

from ..io import open_dataset
from .claims import CLAIM_COLUMNS, scorecard, verdict

#: the per-case numbers of a 2D run that a user may quote: name -> (what, unit)
QUANTITIES = {
    "runout_v99": ("final 1 % volume front, ΔL/L0", "1"),
    "runout_2d": ("final front at depth 2 d, ΔL/L0", "1"),
    "rest_time": ("time to rest, every particle < 0.1 m/s, t_s", "1"),
    "rest_time_mass99": ("time to rest, 99 % of the mass < 0.1 m/s, t_s", "1"),
}
STAT_COLUMNS = ["n", "mean", "min", "max", "std"]


def run_quantities(path) -> dict:
    """The :data:`QUANTITIES` of one 2D run file (NaN where the run did not reach rest)."""
    with open_dataset(path, load=False) as ds:
        L0, tc = float(ds.attrs["L0"]), float(ds.attrs["t_c"])

        def scalar(name):
            return float(ds[name].values) if name in ds else math.nan
        return {"runout_v99": (scalar("final_front_v99") - L0) / L0, "runout_2d": (scalar("final_front_2d") - L0) / L0,
                "rest_time": scalar("time_to_rest") / tc, "rest_time_mass99": scalar("time_to_rest_mass99") / tc,
                "dx": float(ds.attrs.get("dx", math.nan))}


def member_quantities(roots, cases) -> pd.DataFrame:
    """Long table: case, quantity, member, value, dx (m) for every member folder in ``roots`` (member
    index = position in ``roots``) and every case whose run file exists."""
    rows = []
    for k, root in enumerate(roots):
        for case in cases:
            f = Path(root) / "isph" / f"{case}.nc"
            if not f.is_file():
                continue
            q = run_quantities(f)
            rows += [{"case": case, "quantity": name, "member": k, "value": q[name], "dx": q["dx"]} for name in QUANTITIES]
    return pd.DataFrame(rows, columns=["case", "quantity", "member", "value", "dx"])


def member_claims(roots, converged_regression=None) -> pd.DataFrame:
    """Long table: claim_id, case, member, value: every member's scorecard value (``ours_paper_res``)."""
    frames = []
    for k, root in enumerate(roots):
        card = scorecard(root, converged_regression if k == 0 else None)
        frames.append(pd.DataFrame({"claim_id": card["claim_id"], "case": card["case"], "member": k,
                                    "value": card["ours_paper_res"].astype(float)}))
    return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame(columns=["claim_id", "case", "member", "value"])


def stats(values) -> dict:
    """n, mean, min, max, std (sample, ddof = 1; NaN for one member) of the finite values."""
    v = np.asarray([x for x in values if math.isfinite(float(x))], float)
    if v.size == 0:
        return {"n": 0, "mean": math.nan, "min": math.nan, "max": math.nan, "std": math.nan}
    return {"n": int(v.size), "mean": float(v.mean()), "min": float(v.min()), "max": float(v.max()),
            "std": float(v.std(ddof=1)) if v.size > 1 else math.nan}


def summarise(long: pd.DataFrame, keys) -> pd.DataFrame:
    """Per ``keys`` group of a long table: :data:`STAT_COLUMNS` of ``value``, and member 0's value."""
    rows = []
    for key, g in long.groupby(list(keys), sort=False):
        key = key if isinstance(key, tuple) else (key,)
        m0 = g.loc[g["member"] == 0, "value"]
        rows.append({**dict(zip(keys, key)), **stats(g["value"]),
                     "member0": float(m0.iloc[0]) if len(m0) else math.nan})
    return pd.DataFrame(rows, columns=[*keys, *STAT_COLUMNS, "member0"])


def tolerance_width(test: str, paper: float, tol: float) -> float:
    """The tolerance as an absolute width (``rel``: tol |paper|); NaN for a one-sided test."""
    if test == "abs":
        return float(tol)
    if test == "rel":
        return float(tol) * abs(float(paper))
    return math.nan


def ensemble_verdict(test: str, paper: float, tol: float, s: dict, members, fine_mean: float = math.nan):
    """(verdict, reason) of one claim from the members' stats ``s``, their values and the finer
    ensemble's mean (NaN: no finer ensemble)."""
    if s["n"] == 0:
        return "not checkable", ""
    width = tolerance_width(test, paper, tol)
    central = verdict(s["mean"], paper, test, tol)
    change = fine_mean - s["mean"] if math.isfinite(fine_mean) else math.nan
    if math.isfinite(width):
        spread = s["max"] - s["min"] if s["n"] > 1 else 0.0
        dxc = abs(change) if math.isfinite(change) else 0.0
        if spread > width or dxc > width:
            figure = (f"spread {spread:.3g}" if spread >= dxc else f"dx change {change:+.3g}") + f" > tolerance {width:.3g}"
            distance = abs(s["mean"] - float(paper))
            if distance > width + max(spread, dxc):
                # the uncertainty is wide, but not wide enough to bring the paper's value within reach
                return "not reproduced", (f"{figure}, but the paper's value is {distance:.3g} from our mean, beyond "
                                          f"tolerance + {'spread' if spread >= dxc else 'dx change'} "
                                          f"({width + max(spread, dxc):.3g})")
            return "indeterminate", figure
        return central, ""
    sides = {verdict(v, paper, test, tol) for v in members if math.isfinite(float(v))}
    if len(sides) > 1:
        return "indeterminate", "the members fall on both sides of the bound"
    if math.isfinite(change) and verdict(fine_mean, paper, test, tol) != central:
        return "indeterminate", "the finer ensemble's mean is on the other side of the bound"
    return central, ""


ENSEMBLE_COLUMNS = CLAIM_COLUMNS[:6] + ["ours_min", "ours_max", "ours_std", "members", "member0",
                                        "ours_fine", "fine_dx_mm", "dx_change"] + CLAIM_COLUMNS[6:]


def ensemble_scorecard(card0: pd.DataFrame, members: pd.DataFrame, fine: pd.DataFrame | None = None,
                       fine_dx_mm: float = math.nan) -> pd.DataFrame:
    """The claims scorecard with ``ours_paper_res`` the members' mean (``members``: :func:`member_claims`
    of the chain's dx), its spread, the finer ensemble's mean where one exists (``fine``: the same table
    at ``fine_dx_mm``) and the three verdicts. ``card0``: member 0's scorecard (the claim texts, paper
    values, tests, the converged column)."""
    by = {cid: g for cid, g in members.groupby("claim_id", sort=False)}
    fby = {cid: g for cid, g in fine.groupby("claim_id", sort=False)} if fine is not None and len(fine) else {}
    rows = []
    for _, r in card0.iterrows():
        g = by.get(r["claim_id"])
        # member 0 is read from ``card0`` (the summary's own scorecard, with every output of the chain)
        vals = [float(r["ours_paper_res"])] + (g.loc[g["member"] != 0, "value"].tolist() if g is not None else [])
        s = stats(vals)
        fs = stats(fby[r["claim_id"]]["value"]) if r["claim_id"] in fby else stats([])
        v, why = ensemble_verdict(r["test"], r["paper_value"], r["tolerance"], s, vals, fs["mean"])
        if r["verdict"] == "not checkable":  # a claim the chain's own card found vacuous or unmeasurable
            v, why = "not checkable", ""
        out = r.to_dict()
        note = str(out.get("note") or "")
        extra = f"{s['n']} member(s)" + (f"; {why}" if why else "")
        if not math.isfinite(fs["mean"]):
            extra += "; dx change not measured (no finer ensemble of this case)"
        out.update({"ours_paper_res": s["mean"], "ours_min": s["min"], "ours_max": s["max"], "ours_std": s["std"],
                    "members": s["n"], "member0": float(r["ours_paper_res"]), "ours_fine": fs["mean"],
                    "fine_dx_mm": fine_dx_mm if math.isfinite(fs["mean"]) else math.nan,
                    "dx_change": fs["mean"] - s["mean"] if math.isfinite(fs["mean"]) else math.nan,
                    "verdict": v, "basis": "ensemble mean" if s["n"] else "",
                    "note": (note + "; " if note else "") + extra})
        rows.append(out)
    return pd.DataFrame(rows, columns=ENSEMBLE_COLUMNS)


def read_member_table(path, key: str) -> pd.DataFrame:
    """A member table (claim_id, case, member, value); a missing or malformed file names the option."""
    from ..config import ConfigError
    try:
        t = pd.read_csv(path, dtype={"case": str}, keep_default_na=False, na_values={"value": [""]})
    except (OSError, pd.errors.ParserError, pd.errors.EmptyDataError) as exc:
        raise ConfigError(f"{key}: cannot read {path} ({exc})") from None
    if not {"claim_id", "member", "value"} <= set(t.columns):
        raise ConfigError(f"{key}: {path} must have the columns claim_id, member, value (granudep ensemble -o)")
    t["value"] = pd.to_numeric(t["value"], errors="coerce")
    return t


def _cmd(args) -> int:
    from ..io import write_text
    from ..progress import LOG
    from ..config import ConfigError
    missing = [r for r in args.roots if not Path(r).is_dir()]
    if missing:
        raise ConfigError(f"ensemble: member folder not found: {missing[0]}")
    claims = member_claims(args.roots)
    write_text(claims.to_csv(index=False), args.output)
    LOG.info("ensemble: %d member(s), %d claim values -> %s", len(args.roots), len(claims), args.output)
    if args.quantities:
        q = member_quantities(args.roots, args.cases or [])
        table = summarise(q, ["case", "quantity"])
        table = table.merge(q.groupby(["case", "quantity"], sort=False)["dx"].first().reset_index(), on=["case", "quantity"])
        write_text(table.to_csv(index=False), args.quantities)
        LOG.info("ensemble: per-case fronts and rest times of %d case(s) -> %s", len(args.cases or []), args.quantities)
        if args.members_long:
            write_text(q.to_csv(index=False), args.members_long)
    return 0


def register(sub) -> None:
    p = sub.add_parser("ensemble", help="every ensemble member's claims and per-case numbers, with their spread",
                       description=__doc__.splitlines()[0])
    p.add_argument("roots", nargs="+", help="member results folders, member 0 first (the chain's results)")
    p.add_argument("--cases", nargs="*", default=[], help="2D cases whose fronts and rest times to gather")
    p.add_argument("-o", "--output", required=True, help="CSV: claim_id, case, member, value")
    p.add_argument("--quantities", help="CSV: case, quantity, n, mean, min, max, std, member0, dx")
    p.add_argument("--members-long", help="CSV: case, quantity, member, value, dx (every member's value)")
    p.set_defaults(func=_cmd)
