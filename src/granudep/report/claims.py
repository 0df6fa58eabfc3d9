"""The claims scorecard: every quantitative claim of the paper, with our numbers.

One row per claim: the paper's value (from the paper's tables shipped with granudep, or from
``data/paper_claims.csv``, which names the paper's section for each), ours at paper resolution,
ours on the converged (or finest available) reference where that has been run, and a verdict:

* ``reproduced`` / ``not reproduced``: the test of the claim (``abs``: |ours − paper| ≤ tolerance;
  ``rel``: |ours − paper| ≤ tolerance·|paper|; ``lt``/``gt``: ours below/above the paper's bound),
  on the converged value where it exists, else on the paper-resolution value (column ``basis``);
* ``not checkable``: the number cannot be measured from our outputs (e.g. the run is missing).

Every "ours" number is read from an output file (named in column ``our_source``); nothing is
typed in. The tolerances are in ``data/paper_claims.csv`` and were fixed before reading our numbers
(docs/model.md, "Claims scorecard").
"""
from __future__ import annotations

import math
from importlib import resources
from pathlib import Path

import numpy as np
import pandas as pd

from ..io import open_dataset
from ..progress import LOG
from ..isph.analysis import failure_plane_angle
from ..cases import table3, table5

#: the cases of the paper's Fig 9 (h_D against t_s with trend lines)
FIG9_CASES = ("T16-A50", "T16-A120", "T22-A70", "T22-A120")

CLAIM_COLUMNS = ["claim_id", "claim", "case", "paper_value", "unit", "ours_paper_res", "ours_converged",
                 "converged_dx_mm", "verdict", "basis", "test", "tolerance", "note", "source", "our_source"]


def paper_claims() -> pd.DataFrame:
    """The paper's claims that are not table entries, with their source location and test."""
    with resources.files("granudep.data").joinpath("paper_claims.csv").open() as fh:
        return pd.read_csv(fh, dtype={"case": str}, keep_default_na=False, na_values={"paper_value": [""]})


def _f(v) -> float:
    try:
        v = float(v)
    except (TypeError, ValueError):
        return float("nan")
    return v


def verdict(ours: float, paper: float, test: str, tol: float) -> str:
    ours, paper, tol = _f(ours), _f(paper), _f(tol)
    if not math.isfinite(ours):
        return "not checkable"
    if test == "abs":
        ok = abs(ours - paper) <= tol
    elif test == "rel":
        ok = abs(ours - paper) <= tol * abs(paper)
    elif test == "lt":
        ok = ours < paper + tol if tol else ours < paper
    elif test == "gt":
        ok = ours > paper - tol if tol else ours > paper
    else:
        raise ValueError(f"claims: unknown test {test!r}")
    return "reproduced" if ok else "not reproduced"


def _row(spec, ours, converged=float("nan"), dx=float("nan"), note="", our_source="", paper=None, case=None,
         claim=None, claim_id=None) -> dict:
    paper = _f(spec["paper_value"]) if paper is None else paper
    use = converged if math.isfinite(_f(converged)) else ours
    basis = "converged" if math.isfinite(_f(converged)) else ("paper resolution" if math.isfinite(_f(ours)) else "")
    v = verdict(use, paper, spec["test"], spec["tolerance"])
    if v == "not checkable" and not note:
        note = "not run: the output it is read from is missing"
    return {"claim_id": claim_id or spec["claim_id"], "claim": claim or spec["claim"],
            "case": case if case is not None else (spec.get("case") or ""),
            "paper_value": paper, "unit": spec["unit"], "ours_paper_res": _f(ours), "ours_converged": _f(converged),
            "converged_dx_mm": _f(dx), "verdict": v, "basis": basis, "test": spec["test"],
            "tolerance": _f(spec["tolerance"]), "note": note, "source": spec["source"], "our_source": our_source}


def _read(path) -> pd.DataFrame | None:
    return pd.read_csv(path) if path is not None and Path(path).is_file() else None


def _isph_file(results: Path, case: str) -> Path:
    return results / "isph" / f"{case}.nc"


def _rest_ts(path) -> tuple[float, float]:
    """t_s by the rule the paper's text implies (Section 4.2.1: the mass "comes to rest" when the F/D
    interface has reached the free surface everywhere, i.e. every particle is deposited, < 0.1 m/s)."""
    with open_dataset(path, load=False) as ds:
        t = float(ds["time_to_rest"].values) if "time_to_rest" in ds else float("nan")
        return t / float(ds.attrs["t_c"]), float(ds.attrs.get("dx", math.nan))


def _rest_ts_mass99(path) -> float:
    """t_s by the robust rule (99 % of the mass < 0.1 m/s; NaN for run files written before the rule existed)."""
    with open_dataset(path, load=False) as ds:
        t = float(ds["time_to_rest_mass99"].values) if "time_to_rest_mass99" in ds else float("nan")
        return t / float(ds.attrs["t_c"])


def _failure_angle(path) -> tuple[float, float]:
    """Failure-plane inclination from the *horizontal* (Rankine's θ_F = 45° + φ/2 is measured from the
    horizontal, the major principal stress in the column being vertical): the one definition of
    `isph.analysis.failure_plane_angle` (the verification table and Fig 5 use it too)."""
    with open_dataset(path) as ds:
        fp = failure_plane_angle(ds, t_norm=1.0)
        return fp["angle_horizontal_deg"], float(ds.attrs.get("dx", math.nan))


def _converged_file(converged_ref: pd.DataFrame | None, case: str) -> str | None:
    """The 2D file of the converged reference whose run case is ``case`` (column ``path``)."""
    if converged_ref is None or "path" not in converged_ref:
        return None
    for _, r in converged_ref.iterrows():
        if f"({case}," in str(r.get("provenance", "")) and Path(str(r["path"])).is_file():
            return str(r["path"])
    return None


def _converged_dx_mm(converged_ref: pd.DataFrame | None, case: str) -> float:
    """dx (mm) of the converged reference run of 2D case ``case`` (NaN if none)."""
    if converged_ref is None or "dx" not in converged_ref:
        return float("nan")
    for _, r in converged_ref.iterrows():
        if f"({case}," in str(r.get("provenance", "")):
            return 1e3 * float(r["dx"])
    return float("nan")


def acceleration_change(dep_path, nodep_path) -> float:
    """Largest |runout(dep) − runout(no dep)| up to the time the no-deposition front speed peaks,
    over the final no-deposition runout (the claim "runout does not change in the acceleration phase")."""
    with open_dataset(dep_path) as d, open_dataset(nodep_path) as n:
        tn, rn = n["time"].values, n["runout"].values
        td, rd = d["time"].values, d["runout"].values
    speed = np.gradient(rn, tn)
    k = int(np.nanargmax(speed))
    t_acc = tn[: k + 1]
    diff = np.abs(np.interp(t_acc, td, rd) - rn[: k + 1])
    return float(np.nanmax(diff) / abs(rn[-1]))


def final_runout_change(dep_path, nodep_path) -> float:
    """(final runout with deposition − without) / final runout without."""
    with open_dataset(dep_path) as d, open_dataset(nodep_path) as n:
        rn, rd = float(n["runout"].values[-1]), float(d["runout"].values[-1])
    return (rd - rn) / abs(rn)


def scorecard(results="results", converged_regression=None) -> pd.DataFrame:
    """The scorecard table (:data:`CLAIM_COLUMNS`) from the outputs under ``results``.

    ``converged_regression``: a regression folder of the converged 2D runs (Table 3 / 5 / R² on the
    converged reference); without it those entries read "not run" in ``ours_converged``.
    """
    root = Path(results)
    specs = {r["claim_id"]: r for _, r in paper_claims().iterrows()}
    rows = []
    conv_ref = _read(root / "compare" / "reference_converged.csv")
    if conv_ref is not None and "reference_basis" in conv_ref:
        # a case whose converged reference fell back to the workflow's run has no converged value
        # (granudep reference --converged, column reference_basis)
        fell_back = conv_ref["reference_basis"].fillna("").astype(str).str.startswith("no converged run")
        conv_ref = conv_ref[~fell_back]
    creg = Path(converged_regression) if converged_regression else None

    # --- Table 3 ---------------------------------------------------------------------------------
    t3 = _read(root / "regression" / "table3_comparison.csv")
    t3c = _read(creg / "table3_comparison.csv") if creg else None
    for _, p in table3().iterrows():
        for xm in (0.2, 0.4, 0.6, 0.8):
            ours = fit = conv = float("nan")
            status = ""
            if t3 is not None:
                hit = t3[(t3["case"] == p.case_id) & np.isclose(t3["x_norm"], xm)]
                if len(hit):
                    ours, fit, status = _f(hit["t_s_critical"].iloc[0]), _f(hit["t_s_critical_fit"].iloc[0]), \
                        str(hit["status"].iloc[0])
            if t3c is not None:
                hit = t3c[(t3c["case"] == p.case_id) & np.isclose(t3c["x_norm"], xm)]
                conv = _f(hit["t_s_critical"].iloc[0]) if len(hit) else float("nan")
            paper = float(p[f"xM_{xm}"])
            note = "" if math.isfinite(ours) else ("not run: 2D run not in this workflow" if t3 is None or
                                                   not (t3["case"] == p.case_id).any() else f"no onset ({status})")
            if math.isfinite(ours):
                note = (f"onset rule; Fig 9 fit intercept {fit:.2f} ({100 * (fit - paper) / paper:+.0f} %)"
                        if math.isfinite(fit) else "onset rule; no Fig 9 fit")
            rows.append(_row(specs["table3"], ours, conv, _converged_dx_mm(conv_ref, p.case_id), note=note,
                             paper=paper, case=p.case_id,
                             claim=f"(t_s)_C at [x] = {xm}", claim_id=f"table3_{p.case_id}_x{xm}",
                             our_source="regression/table3_comparison.csv"))

    # --- Table 5 ---------------------------------------------------------------------------------
    t5 = _read(root / "regression" / "table5_comparison.csv")
    t5c = _read(creg / "table5_comparison.csv") if creg else None
    for _, p in table5().iterrows():
        for q in ("A", "B"):
            ours = conv = r2 = alt = float("nan")
            other = "B" if q == "A" else "A"
            beside = ""
            if t5 is not None and (t5["case"] == p.case_id).any():
                r = t5[t5["case"] == p.case_id].iloc[0]
                ours, r2, alt = _f(r[q]), _f(r["r2"]), _f(r[f"{q}_paper_over_p0"])
                # a slope is read with its intercept and its fit quality beside it
                beside = f"{other} {_f(r[other]):.4f} (paper {float(p[other]):.4f}); "
            if t5c is not None and (t5c["case"] == p.case_id).any():
                conv = _f(t5c[t5c["case"] == p.case_id].iloc[0][q])
            note = (f"{beside}fit R² {r2:.2f}; if the printed value were dimensional, {q}/p0 = {alt:.4f}"
                    if math.isfinite(ours) else "not run: 2D run of this geometry not in this workflow")
            run2d = f"T{p.theta_deg:g}-{p.case_id.split('-', 1)[1]}"
            rows.append(_row(specs[f"table5_{q}"], ours, conv, _converged_dx_mm(conv_ref, run2d), note=note,
                             paper=float(p[q]), case=p.case_id,
                             claim=f"{q} of eq 36 ({p.case_id}, a = {p.a:g})", claim_id=f"table5_{p.case_id}_{q}",
                             our_source="regression/table5_comparison.csv"))

    # --- failure plane, rest times (2D runs) ------------------------------------------------------
    spec = specs["failure_plane_angle"]
    f = _isph_file(root, spec["case"])
    ours = conv = dx = float("nan")
    if f.is_file():
        ours, _ = _failure_angle(f)
    cf = _converged_file(conv_ref, spec["case"])
    if cf:
        conv, dx = _failure_angle(cf)
    rows.append(_row(spec, ours, conv, 1e3 * dx, our_source=f"isph/{spec['case']}.nc" + (f"; {cf}" if cf else ""),
                     note="from the horizontal (= from the bed + θ): boundary, on the initial column, of the particles "
                          "moving faster than 0.1 m/s at t_s = 1 (the paper does not say how it measured it); "
                          "Rankine 45° + φ/2 = 57.75°"))
    for cid in [k for k in specs if k.startswith("rest_time_")]:
        spec = specs[cid]
        f = _isph_file(root, spec["case"])
        ours = conv = dx = float("nan")
        if f.is_file():
            ours, _ = _rest_ts(f)
        cf = _converged_file(conv_ref, spec["case"])
        if cf:
            conv, dx = _rest_ts(cf)
        rows.append(_row(spec, ours, conv, 1e3 * dx, our_source=f"isph/{spec['case']}.nc" + (f"; {cf}" if cf else ""),
                         note=(f"time to rest: every particle < 0.1 m/s for 0.1 s (the paper's 'comes to rest': the "
                               f"F/D interface at the free surface everywhere); 99 % of the mass < 0.1 m/s: "
                               f"{_rest_ts_mass99(f):.1f} t_c") if f.is_file()
                         else "not run: 2D run not in this workflow"))

    # --- R² of the fits ---------------------------------------------------------------------------
    crit = _read(root / "regression" / "critical.csv")
    spec = specs["fig9_growth_r2"]
    if crit is not None and "r2" in crit:
        # the claim is about every trend line of Fig 9: it holds when the smallest R² is above 0.95
        # (the share above 0.95 is 100 %); judged on the Fig 9 cases, every case's share beside it
        inside = np.isfinite(crit["r2"]) & (crit["x_norm"] >= 0.2 - 1e-9) & (crit["x_norm"] <= 0.8 + 1e-9)
        sel = crit[inside & crit["case"].isin(FIG9_CASES)]
        every = crit[inside]
        ours = float(sel["r2"].min()) if len(sel) else float("nan")
        share = float((sel["r2"] > 0.95).mean()) if len(sel) else float("nan")
        share_all = float((every["r2"] > 0.95).mean()) if len(every) else float("nan")
        rows.append(_row(spec, ours, note=f"smallest R² of the {len(sel)} growth fits of the Fig 9 cases "
                                          f"({', '.join(FIG9_CASES)}; [x] = 0.2–0.8): {100 * share:.0f} % of them "
                                          f"above 0.95 (every case: {100 * share_all:.0f} % of {len(every)})",
                         our_source="regression/critical.csv"))
    else:
        rows.append(_row(spec, float("nan")))
    spec = specs["fig12_r2"]
    co = _read(root / "regression" / "coefficients.csv")
    cco = _read(creg / "coefficients.csv") if creg else None
    if co is not None and len(co):
        r2 = co["r2"].astype(float)
        ours = float(r2.median())
        conv = float(cco["r2"].astype(float).median()) if cco is not None and len(cco) else float("nan")
        rows.append(_row(spec, ours, conv, note=f"median over {int(np.isfinite(r2).sum())} cases (range "
                                                f"{r2.min():.2f}–{r2.max():.2f}); see regression/diagnosis.csv",
                         our_source="regression/coefficients.csv"))
    else:
        rows.append(_row(spec, float("nan")))

    # --- W_M --------------------------------------------------------------------------------------
    spec = specs["wm_rms"]
    wm = sorted((root / "wm").glob("*.nc")) if (root / "wm").is_dir() else []
    if wm:
        vals = []
        for fw in wm:
            with open_dataset(fw) as ds:
                if "rms_deviation" in ds:
                    ref = float(ds.attrs.get("wm_reference", 2.0))
                    r = ds["rms_deviation"]
                    for w in r["width_factor"].values:
                        if float(w) > ref:
                            vals.append(float(np.nanmax(r.sel(width_factor=w).values)))
        ours = max(vals) if vals else float("nan")
        rows.append(_row(spec, ours, note=f"largest RMS over {len(wm)} case(s), W_M = 3, 4 dx",
                         our_source="wm/*.nc"))
    else:
        rows.append(_row(spec, float("nan")))

    # --- Fig 16 maxima and the 38 % ----------------------------------------------------------------
    mx = _read(root / "compare" / "reading_matrix_maxima.csv")
    cmp = _read(root / "compare" / "comparison.csv")
    default = None
    if cmp is not None and "reading" in cmp:
        dep = cmp[cmp["deposition"] == 1]
        default = str(dep["reading"].iloc[0]) if len(dep) else None
    for cid, q, kind in (("fig16_max_runout_nodep", "runout", "nodep"), ("fig16_max_flow_time_nodep", "flow_time", "nodep"),
                         ("fig16_max_runout_dep", "runout", "dep"), ("fig16_max_flow_time_dep", "flow_time", "dep"),
                         ("improves_38", None, None)):
        spec = specs[cid]
        if mx is None or default is None:
            rows.append(_row(spec, float("nan")))
            continue
        sel = mx[(mx["measure"] == "2d")]
        # the workflow's own 2D runs (reference_2d.csv) vs the converged/finest ones (reference_converged.csv)
        ref_own = _read(root / "compare" / "reference_2d.csv")
        own = set(ref_own["reference"]) if ref_own is not None and "reference" in ref_own else set()
        conv_labels = set(conv_ref["reference"]) if conv_ref is not None and "reference" in conv_ref else set()
        paper_ref = sel[sel["reference"].isin(own)]
        conv_rows = sel[sel["reference"].isin(conv_labels)]

        def value(frame, reading):
            g = frame[frame["reading"] == reading]
            if g.empty:
                return float("nan")
            g = g.iloc[0]
            if q is None:
                return float(np.nanmax([g["runout_max_reduction"], g["flow_time_max_reduction"]]))
            return float(g[f"max_{q}_error_{kind}"])
        ours, conv_v = value(paper_ref, default), value(conv_rows, default)
        others = ", ".join(f"{r}: {value(paper_ref, r) * 100:.0f} %" for r in sorted(set(sel["reading"])) if r != default)
        # dx of the converged run of the case where the maximum occurs (the reference may mix resolutions)
        dx = float("nan")
        if q is not None and len(conv_rows) and conv_ref is not None and "dx" in conv_ref:
            g = conv_rows[conv_rows["reading"] == default]
            at = str(g[f"max_{q}_case_{kind}"].iloc[0]) if len(g) else ""
            hit = conv_ref[conv_ref["case"] == at]
            dx = 1e3 * float(hit["dx"].iloc[0]) if len(hit) else float("nan")
        what = "reduction of the largest |error| (runout or flow time, the larger)" if q is None else \
            f"largest |{q.replace('_', ' ')} error| over the DA cases"
        rows.append(_row(spec, ours, conv_v, dx,
                         note=f"{what}; A, B reading '{default}'; other readings (paper resolution): {others}; "
                              "the paper's reference is Farin et al. (2014) measurements, ours the 2D ISPH runs",
                         our_source="compare/reading_matrix_maxima.csv"))

    # --- acceleration phase -------------------------------------------------------------------------
    spec = specs["acceleration_unchanged"]
    vals = []
    for fd in sorted((root / "da").glob("*_deposition.nc")) if (root / "da").is_dir() else []:
        fn = fd.with_name(fd.name.replace("_deposition.nc", "_nodeposition.nc"))
        if fn.is_file():
            try:
                vals.append((fd.name.split("_")[0], acceleration_change(fd, fn), final_runout_change(fd, fn)))
            except (KeyError, ValueError) as exc:
                LOG.warning("claims: acceleration phase of %s not read: %s", fd, exc)
    if vals:
        worst = max(vals, key=lambda t: t[1])
        per = ", ".join(f"{c} {100 * v:.2f} % (final runout {100 * f:+.2f} %)" for c, v, f in vals)
        tol = _f(spec["tolerance"])
        # the claim says deposition leaves the acceleration phase alone *while* it shortens the runout:
        # where deposition barely changes the final runout, an unchanged acceleration phase says nothing
        if max(abs(f) for _, _, f in vals) <= tol:
            r = _row(spec, worst[1], note=f"not checkable: deposition changes the final runout by at most "
                     f"{100 * max(abs(f) for _, _, f in vals):.2f} % (<= the tolerance {100 * tol:g} %), so an "
                     f"unchanged acceleration phase is vacuous; per case: {per} (default A, B reading '{default}')",
                     our_source="da/*_deposition.nc, *_nodeposition.nc")
            r["verdict"] = "not checkable"
            rows.append(r)
        else:
            rows.append(_row(spec, worst[1], note="per case: " + per + f" (default A, B reading '{default}')",
                             our_source="da/*_deposition.nc, *_nodeposition.nc"))
    else:
        rows.append(_row(spec, float("nan")))
    out = pd.DataFrame(rows, columns=CLAIM_COLUMNS)
    out.loc[~np.isfinite(out["ours_converged"].astype(float)), "converged_dx_mm"] = np.nan
    return out


def tally(card: pd.DataFrame) -> str:
    c = card["verdict"].value_counts()
    return ", ".join(f"{int(c.get(k, 0))} {k}" for k in VERDICTS)


#: the verdicts, in the order they are counted
VERDICTS = ("reproduced", "indeterminate", "not reproduced", "not checkable")
