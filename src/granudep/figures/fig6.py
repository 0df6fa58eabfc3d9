"""Fig 6: the F/D interface of a quartz-sand column (a = 7) collapsing on a horizontal plane.

The paper (Section 4.1, Fig 6) shows the computed F/D interface at five times "starting from
0.416 s", the last at 7.904 s (the final deposit), against the measurements of Lube et al. (2007) /
Doyle et al. (2007), which are not available to us. Its text names only the first and the last time;
the three between are our choice, evenly spaced (:data:`DEFAULT_TIMES`). The paper writes the times
in seconds, but a laboratory column of this kind comes to rest after about 3 sqrt(H0/g) (well under a
second), so 7.904 cannot be seconds; read as t/sqrt(L0/g) it is 7.904/sqrt(a) = 2.99 t_c, the end of
the collapse, as the paper says of its last profile (docs/fig6.md). The figure reads the times in that
unit by default (``--time-unit t_L0``); ``t_c`` (t/sqrt(H0/(g cos θ)), the paper's t_s) and ``s``
are the other readings.

The interface is the one of Figs 7/A3 (:func:`.isph2d.interface_profile`): particles slower than
the critical 0.1 m/s are deposited; per column of width 2 dx, the top of the deposited particles
below the lowest flowing one. The free surface is :func:`.isph2d.surface_profile`. One panel per run
(the paper's basal slip beside a no-slip bed), each with the final runout of its run.
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd

from ..config import ConfigError
from .common import (CRITICAL_SPEED, add_inputs, case_of, classify, colours, load, need, new_figure, note,
                     panel_label, register, scales)
from ..isph.analysis import bed_label, final_runout
from .isph2d import interface_profile, present, surface_profile

#: the times the paper states (Section 4.1): the first and the last of its five
PAPER_TIMES = (0.416, 7.904)
#: the five times drawn by default: the paper's first and last and three evenly between (our choice)
DEFAULT_TIMES = tuple(float(v) for v in np.round(np.linspace(PAPER_TIMES[0], PAPER_TIMES[1], 5), 6))
TIME_UNITS = ("t_L0", "t_c", "s")
NO_MEASURED = ("The measured F/D interfaces of Lube et al. (2007) / Doyle et al. (2007) that the paper's Fig 6 "
               "compares with are not available to us: not shown")


def time_scale(ds, unit: str) -> float:
    """Seconds per unit of the requested times: sqrt(L0/(g cos θ)) (t_L0), t_c = sqrt(H0/(g cos θ))
    (t_c) or 1 s (s)."""
    if unit not in TIME_UNITS:
        raise ConfigError(f"--time-unit: must be one of {', '.join(TIME_UNITS)} (got {unit!r})")
    sc = scales(ds)
    return {"t_L0": sc["tc"] * math.sqrt(sc["L0"] / sc["H0"]), "t_c": sc["tc"], "s": 1.0}[unit]


def snapshot_for(time: np.ndarray, t: float) -> tuple[int, bool]:
    """Index of the stored snapshot nearest to ``t`` (s), and whether ``t`` lies beyond the run's last
    snapshot by more than half an output interval (the last snapshot is then used, and flagged)."""
    time = np.asarray(time, float)
    half = 0.5 * float(np.min(np.diff(time))) if time.size > 1 else 0.0
    if t > time[-1] + half:
        return time.size - 1, True
    return int(np.argmin(np.abs(time - t))), False


def interfaces_at_times(run, times=DEFAULT_TIMES, unit: str = "t_L0", width: float | None = None) -> pd.DataFrame:
    """The F/D interface and free surface of a 2D run at each requested time, one row per occupied
    column of ``width`` (default 2 dx): ``t_request`` (in ``unit``), ``time`` (s, the snapshot used),
    ``t_s`` (= time/t_c), ``beyond_end`` (the request lies past the run's last snapshot: the last
    one is used), ``x`` (column centre, m), ``interface`` and ``surface`` (heights, m)."""
    ds = load(run)
    need(ds, ["x", "y", "u", "v", "dx", "H0", "theta_deg"], "fig6 2D run")
    scale = time_scale(ds, unit)
    tc = scales(ds)["tc"]
    dx = float(ds.attrs["dx"])
    time = np.asarray(ds["time"].values, float)
    rows = []
    for t_req in times:
        i, beyond = snapshot_for(time, float(t_req) * scale)
        keep = present(ds, i)
        x, y = ds["x"].values[i][keep], ds["y"].values[i][keep]
        dep = np.hypot(ds["u"].values[i][keep], ds["v"].values[i][keep]) < CRITICAL_SPEED
        xc, yi = interface_profile(x, y, dep, dx, width)
        _, ys = surface_profile(x, y, dx, width)
        ok = np.isfinite(ys)
        rows.append(pd.DataFrame({"t_request": float(t_req), "unit": unit, "time": time[i], "t_s": time[i] / tc,
                                  "beyond_end": beyond, "x": xc[ok], "interface": yi[ok], "surface": ys[ok]}))
    return pd.concat(rows, ignore_index=True)


def fig6(runs, times=DEFAULT_TIMES, unit: str = "t_L0"):
    """F/D interface (solid) and free surface (thin, dashed) at the requested times, one panel per run,
    side by side; each panel's title gives the run's bed and its final runout."""
    runs = [load(r) for r in runs]
    if not runs:
        raise ConfigError("fig6: at least one 2D ISPH run is needed")
    if not times:
        raise ConfigError("fig6: at least one time is needed")
    tabs = [interfaces_at_times(ds, times, unit) for ds in runs]
    outs = [final_runout(ds) for ds in runs]
    H0 = max(float(ds.attrs["H0"]) for ds in runs)
    L0 = max(float(ds.attrs["L0"]) for ds in runs)
    xmax = max(max(float(t["x"].max()) for t in tabs), max(o["front"] for o in outs)) * 1.05
    fig, axes = new_figure(1, len(runs), panel=(6.2, 4.2), sharey=True)
    cols = colours(len(times), "plasma")
    tcs = [scales(ds)["tc"] for ds in runs]
    unit_txt = {"t_L0": "sqrt(L0/g)", "t_c": "t_c", "s": "s"}[unit]
    for k, (ds, tab, out) in enumerate(zip(runs, tabs, outs)):
        ax = axes[0, k]
        ax.plot([0, L0, L0], [float(ds.attrs["H0"])] * 2 + [0], color="0.6", ls=":", lw=1, label="initial column")
        for c, t_req in zip(cols, times):
            g = tab[tab["t_request"] == float(t_req)]
            t_used, beyond = float(g["time"].iloc[0]), bool(g["beyond_end"].iloc[0])
            lab = (f"t = {t_req:g} {unit_txt} ({t_used:.3f} s)" if unit != "s" else f"t = {t_req:g} s") + \
                f", t_s = {t_used / tcs[k]:.2f}"
            if beyond:
                lab += f": past the run's end, its last state at {t_used:.2f} s"
            ax.plot(g["x"], g["interface"], color=c, lw=1.6, label=lab)
            ax.plot(g["x"], g["surface"], color=c, lw=0.8, ls="--")
        ax.axvline(out["front"], color="k", lw=0.8, ls="-.",
                   label=f"final front x_f = {out['front']:.3f} m ({out['measure']})")
        rest = (f"at rest at t = {out['time_to_rest']:.2f} s" if math.isfinite(out["time_to_rest"])
                else f"not at rest at its end, t = {out['t_end']:.2f} s ({out['status']})")
        panel_label(ax, k, f"{bed_label(ds)}\nfinal runout (x_f − L0)/L0 = {out['runout_norm']:.2f}; {rest}")
        ax.set_xlim(0, xmax)
        ax.set_ylim(0, H0 * 1.05)
        ax.set_xlabel("x from the back wall (m)")
        if k == 0:
            ax.set_ylabel("height y (m)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    sc = scales(runs[0])
    when = {"t_L0": f"times read as t/sqrt(L0/g), sqrt(L0/g) = {time_scale(runs[0], 't_L0'):.4f} s (the paper writes "
                    f"them in s, which no laboratory column of this size reaches; docs/fig6.md)",
            "t_c": f"times read as t/t_c, t_c = sqrt(H0/g) = {sc['tc']:.3f} s (the paper writes them in s)",
            "s": "times in s, as the paper writes them"}[unit]
    dx0 = float(runs[0].attrs["dx"])
    note(fig, f"{case_of(runs[0])}: a = {sc['H0'] / sc['L0']:g}, L0 = {sc['L0']:g} m, dx = {dx0:g} m. "
              f"Solid: F/D interface (top of the particles slower than {CRITICAL_SPEED:g} m/s under the flowing ones, "
              f"per 2 dx column); dashed: free surface (highest particle + dx/2). The paper states the first and last "
              f"times ({PAPER_TIMES[0]:g}, {PAPER_TIMES[1]:g}); the three between are evenly spaced (ours); {when}. "
              f"{NO_MEASURED}.")
    return fig


# ---- CLI -------------------------------------------------------------------------------------------

def _args6(p):
    add_inputs(p, "2D ISPH runs of the Fig 6 column (one panel each, e.g. the paper's slip and a no-slip bed)")
    p.add_argument("--times", nargs="+", type=float, metavar="T", default=list(DEFAULT_TIMES),
                   help="times in --time-unit (default: the paper's 0.416 and 7.904 and three evenly between)")
    p.add_argument("--time-unit", choices=TIME_UNITS, default="t_L0",
                   help="t_L0: t/sqrt(L0/g) (default); t_c: t/sqrt(H0/g), the paper's t_s; s: seconds, as the "
                        "paper writes them")


@register("fig6", "F/D interface and free surface at five times, quartz sand a = 7 on a horizontal plane", _args6)
def _fig6(args):
    k = classify(args.inputs, ("isph",), "fig6")
    return fig6(k["isph"], args.times, args.time_unit)
