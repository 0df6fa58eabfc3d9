"""The 2D reference of the DA comparison (Figs 15-16): 2D ISPH runs of the Table 5 geometries as a
*reference table*, one row per run: ``case`` (the Table 5 name, e.g. ``1D-A70``), ``a``,
``theta_deg``, ``final_runout_norm`` (ΔL/L0 with ΔL = x_front,final − L0), ``flow_time`` [s],
``flow_time_norm`` (t_F/t_c), ``front_definition`` and ``provenance``; which run of a resolution
ladder is the reference (:func:`select_reference_runs`, :func:`select_converged_runs`); and the
loading of any reference table (a user's measurements too: :func:`load_reference` names a missing
column). The paper's Farin et al. (2014) measurements are not available to us and are never
invented nor back-computed.
"""
from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Iterable

import numpy as np
import pandas as pd
import xarray as xr

from .. import cases
from ..config import ConfigError
from ..front import flow_time as _flow_time
from ..io import open_dataset
from ..progress import LOG

#: the robust front measures (granudep.front.front_measures) carried by 2D and DA files, short names
MEASURES = ("2d", "5mm", "v99", "tail")


REFERENCE_COLUMNS = ("case", "a", "theta_deg", "final_runout_norm", "flow_time", "flow_time_norm",
                     "front_definition", "provenance", "note", "dx", "time_to_rest",
                     *[f"final_runout_norm_{m}" for m in MEASURES], "flow_time_v99", "path", "reference_basis")


#: default flow-time tolerance (m), the shared definition's default (docs/model.md)
FLOW_TIME_TOL = 1e-3


def _as_dataset(run) -> tuple[xr.Dataset, str]:
    if isinstance(run, xr.Dataset):
        return run, str(run.attrs.get("source_file", run.attrs.get("case", "dataset")))
    path = Path(run)
    if not path.exists():
        raise ConfigError(f"input: file {str(path)!r} does not exist")
    ds = open_dataset(path)
    ds.attrs.setdefault("source_file", path.name)
    return ds, path.name


def _attr(ds: xr.Dataset, name: str, where: str) -> float:
    if name not in ds.attrs:
        raise ConfigError(f"{where}: global attribute {name!r} missing (data contract)")
    return float(ds.attrs[name])


def front_definition(threshold: float | None, tol: float | None = None) -> str:
    """Human-readable front (and flow-time) definition, printed beside every runout."""
    if threshold is None or not math.isfinite(float(threshold)):
        text = "front definition not recorded"
    else:
        text = f"front: depth ≥ {1e3 * float(threshold):.2f} mm, contiguous from the main mass"
    if tol is not None:
        text += f"; flow time: front moves < {1e3 * tol:.1f} mm afterwards"
    return text


def match_table5(a: float, theta_deg: float, rel_tol: float = 0.02, theta_tol: float = 0.05) -> str | None:
    """The Table 5 case name whose (a, θ) matches, or None.

    Table 5 rounds H0 (0.113 m for a = 0.45, whose L0 = 0.25 m gives 0.452): ``rel_tol`` on a
    absorbs the rounding while keeping the four cases (a = 0.3, 0.45, 0.7, 1.24) well apart.
    """
    t5 = cases.table5()
    ok = (np.abs(t5.theta_deg - theta_deg) <= theta_tol) & (np.abs(t5.a - a) <= rel_tol * t5.a)
    if not ok.any():
        return None
    return str(t5.case_id[ok].iloc[0])


def reference_row(run, tol: float = FLOW_TIME_TOL) -> dict:
    """One reference-table row from a 2D ISPH run (Dataset or path)."""
    ds, name = _as_dataset(run)
    where = f"reference {name}"
    L0, H0, theta = _attr(ds, "L0", where), _attr(ds, "H0", where), _attr(ds, "theta_deg", where)
    if "front_position" not in ds:
        raise ConfigError(f"{where}: variable 'front_position' missing (data contract)")
    time = np.asarray(ds["time"].values, dtype=float)
    front = np.asarray(ds["front_position"].values, dtype=float)
    if "final_front_position" in ds:
        x_final = float(ds["final_front_position"].values)
    else:
        x_final = float(front[np.isfinite(front)][-1])
    status = str(ds.attrs.get("status", "ok"))
    if status.lower().startswith("failed"):
        raise ConfigError(f"{where}: the 2D run did not finish ({status}); a failed run is not a reference")
    a = H0 / L0
    run_case = str(ds.attrs.get("case", Path(name).stem))
    case = match_table5(a, theta)
    if case is None:  # not a Table 5 geometry: keep the run's own name (a user's case)
        case = run_case
    tf = _flow_time(time, front, tol)
    tc = cases.characteristic_time(H0, math.radians(theta))
    # at rest: the run's own verdict when it gives one, else the front stopped before the last output
    if "time_to_rest" in ds:
        at_rest = bool(np.isfinite(float(ds["time_to_rest"].values)))
    else:
        at_rest = bool(np.isfinite(tf) and tf < time[-1])
    if not at_rest:
        LOG.warning("%s: the 2D run is not at rest at t_end = %.3g s: its runout and flow time are lower "
                    "bounds (note column)", where, time[-1])
    dx = ds.attrs.get("dx")
    dx_text = f", dx={float(dx):g} m" if dx is not None else ""
    robust = _robust_fronts(ds, time, L0, tol)
    return {**robust, "dx": float(dx) if dx is not None else float("nan"),
            "path": "" if isinstance(run, xr.Dataset) else str(run),
            "time_to_rest": float(ds["time_to_rest"].values) if "time_to_rest" in ds else float("nan"),
        "case": case, "a": a, "theta_deg": theta,
        "final_runout_norm": (x_final - L0) / L0,
        "flow_time": tf, "flow_time_norm": tf / tc,
        "front_definition": front_definition(ds.attrs.get("front_depth_threshold"), tol),
        "provenance": f"granudep 2D ISPH{dx_text} ({run_case}, file {name})",
        "note": "" if at_rest else f"not at rest at t_end = {time[-1]:.3g} s: lower bounds",
    }


def _robust_fronts(ds: xr.Dataset, time: np.ndarray, L0: float, tol: float) -> dict:
    """final_runout_norm_{2d,5mm,v99,tail} and the flow time of the 1 % volume front, from the
    ``final_front_*`` / ``front_*`` variables of a 2D or DA file (NaN where the file predates them)."""
    out = {}
    for m in MEASURES:
        name = f"final_front_{m}"
        x = float(ds[name].values) if name in ds else float("nan")
        out[f"final_runout_norm_{m}"] = (x - L0) / L0
    out["flow_time_v99"] = _flow_time(time, np.asarray(ds["front_v99"].values, float), tol) \
        if "front_v99" in ds else float("nan")
    return out


def _dx_label(dxs) -> str:
    vals = sorted({round(1e3 * float(d), 6) for d in dxs if d is not None and math.isfinite(float(d))})
    return "dx not recorded" if not vals else "dx = " + " / ".join(f"{v:g}" for v in vals) + " mm"


def reference_from_isph(runs: Iterable, tol: float = FLOW_TIME_TOL, label: str | None = None,
                        basis: Iterable[tuple[str, bool]] | None = None) -> pd.DataFrame:
    """Reference table (:data:`REFERENCE_COLUMNS`) from 2D ISPH runs.

    ``label`` names the reference source (e.g. "2D paper resolution"); the table's ``reference``
    column is then the label with the runs' dx ("2D paper resolution (dx = 4 mm)"), so every number
    read against it is labelled with its resolution. ``basis`` (one ``(sentence, converged)`` per run,
    from :func:`select_converged_runs`) fills the per-row ``reference_basis`` and qualifies the label:
    "LABEL where available" when only some cases have a converged run, "LABEL not available: workflow
    run" when none has.
    """
    rows = [reference_row(r, tol) for r in runs]
    if not rows:
        raise ConfigError("reference: no ISPH run given")
    table = pd.DataFrame(rows, columns=list(REFERENCE_COLUMNS))
    conv = None
    if basis is not None:
        basis = list(basis)
        table["reference_basis"] = [b for b, _ in basis]
        conv = [c for _, c in basis]
    if label:
        if conv is not None and not any(conv):
            label = f"{label} not available: workflow run"
        elif conv is not None and not all(conv):
            label = f"{label} where available"
        table["reference"] = f"{label} ({_dx_label(table['dx'])})"
    return table


def select_reference_runs(runs: Iterable, dx: float | None = None) -> list:
    """Per Table 5 case (matched by (a, θ)), the run at resolution ``dx`` (m), or the finest one.

    The converged reference of the comparison: until the convergence ladder names the
    converged dx, it is the finest-resolution run available for each case. A case with no run at the
    requested ``dx`` keeps its finest run, with a warning. Returns the selected paths/datasets.
    """
    by_case: dict[str, list] = {}
    for r in runs:
        ds, name = _as_dataset(r)
        if str(ds.attrs.get("status", "ok")).lower().startswith("failed"):
            LOG.warning("reference %s: failed run skipped", name)
            continue
        a = float(ds.attrs["H0"]) / float(ds.attrs["L0"])
        case = match_table5(a, float(ds.attrs["theta_deg"])) or str(ds.attrs.get("case", name))
        by_case.setdefault(case, []).append((float(ds.attrs.get("dx", math.nan)), r))
    chosen = []
    for case, items in sorted(by_case.items()):
        items = sorted(items, key=lambda t: (not math.isfinite(t[0]), t[0]))
        pick = items[0]
        if dx is not None:
            hit = [t for t in items if math.isfinite(t[0]) and math.isclose(t[0], dx, rel_tol=1e-6)]
            if hit:
                pick = hit[0]
            else:
                LOG.warning("reference %s: no run at dx = %g m; the finest (dx = %g m) is used", case, dx, pick[0])
        chosen.append(pick[1])
    if not chosen:
        raise ConfigError("reference: no usable ISPH run given")
    return chosen


#: the ladder's tolerance: a rung is converged when its runout changed by at most 5 % from
#: the next coarser rung (README, "T22-A70 on the resolution ladder")
CONVERGENCE_TOL = 0.05


#: the runout measure the ladder checks: the 1 % volume front (``monitor.x_inf_front: v99``); the
#: 2 grain-diameter front where a file has no volume front
CONVERGENCE_MEASURE = "v99"


def _ladder_runout(row: dict, measure: str) -> tuple[float, str]:
    """(final runout ΔL/L0 of ``measure``, the measure read): the 2 d front where the file lacks it."""
    v = float(row.get(f"final_runout_norm_{measure}", math.nan)) if measure != "2d" else math.nan
    return (v, measure) if math.isfinite(v) else (float(row["final_runout_norm"]), "2d")


def select_converged_runs(workflow_runs: Iterable, ladder_runs: Iterable = (), tol: float = CONVERGENCE_TOL,
                          measure: str = CONVERGENCE_MEASURE) -> list[tuple[object, str, bool]]:
    """Per Table 5 case, the finest *converged* 2D run; else the workflow's own run.

    The rule (config ``compare.reference``): the runs of a case (``workflow_runs`` and ``ladder_runs``, failed
    runs skipped) form a ladder of distinct dx (one run per dx, the workflow's own first). Rung k is
    *converged* when its final runout ΔL/L0 (``measure``: the 1 % volume front, the 2 d front where the
    file lacks it) differs from that of the next coarser rung by at most ``tol`` relative to rung k, both
    runs at rest (a run stopped before rest gives a lower bound, never a converged value).
    The reference is the finest converged rung. Without one (a fresh clone has no ladder run; or no step
    is within ``tol``) the case keeps its workflow run (the finest run where it has none), and the
    reason says so.

    Returns ``(run, basis, converged)`` per case: ``basis`` is the sentence every row read against the
    run carries (dx, the change and the tolerance, or why it fell back).
    """
    workflow_runs = list(workflow_runs)
    by_case: dict[str, list] = {}
    for i, r in enumerate([*workflow_runs, *ladder_runs]):
        if isinstance(r, xr.Dataset):
            ds, name = r, str(r.attrs.get("case", "dataset"))
        else:  # lazily: a fine rung's particle records are never read (only the fronts and attributes)
            if not Path(r).exists():
                raise ConfigError(f"input: file {str(r)!r} does not exist")
            ds, name = open_dataset(r, load=False), Path(r).name
        try:
            if str(ds.attrs.get("status", "ok")).lower().startswith("failed"):
                LOG.warning("reference %s: failed run skipped", name)
                continue
            row = reference_row(ds)
            dx = float(ds.attrs.get("dx", math.nan))
        finally:
            if not isinstance(r, xr.Dataset):
                ds.close()
        runout, used = _ladder_runout(row, measure)
        by_case.setdefault(row["case"], []).append({"run": r, "dx": dx, "runout": runout, "measure": used,
                                                    "at_rest": not row["note"], "own": i < len(workflow_runs)})
    out = []
    for case, items in sorted(by_case.items()):
        rungs: list[dict] = []
        for it in sorted(items, key=lambda t: (-t["dx"] if math.isfinite(t["dx"]) else math.inf, not t["own"])):
            if rungs and math.isfinite(it["dx"]) and math.isclose(it["dx"], rungs[-1]["dx"], rel_tol=1e-6):
                continue  # the same rung twice (the ladder's 4 mm run beside the workflow's): keep the first
            rungs.append(it)
        rungs = [r for r in rungs if math.isfinite(r["dx"])] or rungs
        pick, basis = None, ""
        for k in range(len(rungs) - 1, 0, -1):
            fine, coarse = rungs[k], rungs[k - 1]
            change = (fine["runout"] - coarse["runout"]) / abs(fine["runout"]) if fine["runout"] else math.nan
            if math.isfinite(change) and abs(change) <= tol and fine["at_rest"] and coarse["at_rest"] \
                    and fine["measure"] == coarse["measure"]:
                pick = fine
                basis = (f"converged: dx = {1e3 * fine['dx']:g} mm, runout ({fine['measure']} front) {100 * change:+.1f} % "
                         f"on dx = {1e3 * coarse['dx']:g} mm (tolerance {100 * tol:g} %)")
                break
        if pick is not None:
            out.append((pick["run"], basis, True))
            continue
        own_rungs = [r for r in rungs if r["own"]]
        fall = own_rungs[0] if own_rungs else rungs[-1]
        which = "workflow run" if own_rungs else "finest run"
        if len(rungs) < 2:
            why = "no finer run on disk (`snakemake -j2 convergence` / `reference_runs`)"
        else:
            steps = ", ".join(f"{1e3 * rungs[k]['dx']:g} mm {100 * (rungs[k]['runout'] - rungs[k - 1]['runout']) / abs(rungs[k]['runout']):+.1f} %"
                              for k in range(1, len(rungs)) if rungs[k]["runout"])
            why = f"no rung within {100 * tol:g} % of the next coarser ({steps})"
        out.append((fall["run"], f"no converged run: {which} dx = {1e3 * fall['dx']:g} mm; {why}", False))
    if not out:
        raise ConfigError("reference: no usable ISPH run given")
    return out


def load_reference(table, name: str | None = None) -> pd.DataFrame:
    """Read and check a reference table (path or DataFrame).

    Required: ``case``, ``final_runout_norm``, ``flow_time`` or ``flow_time_norm``, ``provenance``.
    """
    if isinstance(table, pd.DataFrame):
        df, name = table.copy(), name or "reference table"
    else:
        path = Path(table)
        name = name or str(path)
        if not path.exists():
            raise ConfigError(f"--reference: file {name!r} does not exist")
        df = pd.read_csv(path)
    missing = [c for c in ("case", "final_runout_norm", "provenance") if c not in df.columns]
    if "flow_time" not in df.columns and "flow_time_norm" not in df.columns:
        missing.append("flow_time (or flow_time_norm)")
    if missing:
        raise ConfigError(f"--reference {name}: missing column(s) {', '.join(missing)} "
                          f"(required: case, final_runout_norm, flow_time or flow_time_norm, provenance)")
    if df["provenance"].isna().any() or (df["provenance"].astype(str).str.strip() == "").any():
        raise ConfigError(f"--reference {name}: every row needs a non-empty 'provenance'")
    if "reference" not in df.columns:
        df["reference"] = [source_label(p) for p in df["provenance"]]
    df["note"] = df["note"].astype(object).where(df["note"].notna(), "").astype(str) if "note" in df.columns else ""
    for col in ("flow_time", "flow_time_norm", "front_definition"):
        if col not in df.columns:
            df[col] = np.nan if col != "front_definition" else "not stated"
    df["case"] = df["case"].astype(str)
    df["reference_basis"] = (df["reference_basis"].astype(object).where(df["reference_basis"].notna(), "").astype(str)
                             if "reference_basis" in df.columns else "")
    return df


def source_label(provenance: str) -> str:
    """The reference *source* of a provenance string (rows of one source are grouped together).

    ``granudep reference`` writes "granudep 2D ISPH, dx=0.008 m (T22-A70, file T22-A70.nc)": the
    per-run part in parentheses is dropped so the four Table 5 runs form one source. Any other
    provenance (e.g. a user's measurements) is its own source unless the table has a
    ``reference`` column.
    """
    m = re.match(r"^(granudep 2D ISPH[^()]*?)\s*\(.*\)$", str(provenance))
    return m.group(1) if m else str(provenance)
