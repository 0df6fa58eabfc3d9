"""Figs 5, 7 (and A3), 10: drawn from the particles of 2D ISPH runs.

* Fig 5: free surface of T22-A70 at several times (the paper overlays Farin et al. 2014 profiles,
  which are not available to us), plus the failure plane: the boundary between static and moving
  particles inside the initial column early in the collapse (`isph.analysis.failure_plane_angle`, from
  the horizontal), against Rankine's 45° + φ/2.
* Fig 7 / A3: particles coloured flowing/deposited (speed threshold 0.1 m/s, Section 2.2) with the
  F/D interface (dashed) at several t_s, one column of panels per case. The interface drawn here is
  a display estimate from the particles (top of the deposited layer under the flowing one, per
  column of width 2 dx); the eq 16 interface of the monitoring sections is overlaid as markers when
  the sections file is given.
* Fig 10: velocity profiles u_x/sqrt(g H0 cos θ) vs y/H0 at [x] = 0.2 and 0.4 (section width
  2 dx, averaged over dx-thick layers) at several t_s.
"""
from __future__ import annotations

import math

import numpy as np

from ..config import ConfigError
from ..isph.analysis import failure_plane_angle
from .common import (CRITICAL_SPEED, add_inputs, case_of, classify, colours, load, need,
                     new_figure, note, panel_label, register, scales)

PAPER_FAILURE_PLANE_DEG = 55.8   # Section 4.2.2, 2D non-DA SPH, φ = 25.5°
NO_FARIN = "Farin et al. (2014) measured free surfaces are not available to us: not shown"


def _bins(x: np.ndarray, width: float, x_max: float | None = None):
    x_max = float(np.nanmax(x)) if x_max is None else x_max
    edges = np.arange(0.0, x_max + width, width)
    return edges, np.clip(np.digitize(x, edges) - 1, 0, edges.size - 2)


def surface_profile(x: np.ndarray, y: np.ndarray, dx: float, width: float | None = None):
    """Free surface per column of ``width`` (default 2 dx): highest particle centre + dx/2."""
    width = 2 * dx if width is None else width
    edges, idx = _bins(x, width)
    top = np.full(edges.size - 1, np.nan)
    np.fmax.at(top, idx, y + 0.5 * dx)
    return 0.5 * (edges[1:] + edges[:-1]), top


def interface_profile(x: np.ndarray, y: np.ndarray, deposited: np.ndarray, dx: float, width: float | None = None):
    """Display estimate of the F/D interface per column: top of the deposited particles lying below
    the lowest flowing particle (+ dx/2); 0 where the base flows; the free surface where all rest."""
    width = 2 * dx if width is None else width
    edges, idx = _bins(x, width)
    n = edges.size - 1
    low_flow = np.full(n, np.inf)
    np.fmin.at(low_flow, idx[~deposited], y[~deposited])
    occupied = np.zeros(n, bool)
    occupied[idx] = True
    below = deposited & (y < low_flow[idx])
    top = np.zeros(n)
    np.fmax.at(top, idx[below], y[below] + 0.5 * dx)
    top[~occupied] = np.nan
    return 0.5 * (edges[1:] + edges[:-1]), top


def _time_index(time, t):
    return int(np.argmin(np.abs(np.asarray(time) - t)))


def present(ds, i: int) -> np.ndarray:
    """Particles still in the domain at time index i: those that left through the downstream
    outflow (``outflow_time`` <= t) sit frozen at the end of the bed and are not drawn."""
    n = ds.sizes["particle"]
    if "outflow_time" not in ds:
        return np.ones(n, bool)
    ot = np.asarray(ds["outflow_time"].values, float)
    return ~(ot <= float(ds["time"].values[i]))


def rest_time(ds) -> float:
    t = float(ds["time_to_rest"].values) if "time_to_rest" in ds else float("nan")
    return t if math.isfinite(t) else float(ds["time"].values[-1])


def fig5(run, times=None, failure_t_s: float = 1.0):
    """Free surface at several times (slope-aligned frame) with the failure plane."""
    ds = load(run)
    need(ds, ["x", "y", "dx", "L0", "H0", "theta_deg"], "fig5 2D run")
    sc = scales(ds)
    time = ds["time"].values
    if not times:
        times = np.linspace(0.0, rest_time(ds), 6)
    idx = list(dict.fromkeys(_time_index(time, t) for t in times))
    fig, axes = new_figure(1, 1, panel=(10.0, 3.4))
    ax = axes[0, 0]
    dx = float(ds.attrs["dx"])
    for c, i in zip(colours(len(idx), "plasma"), idx):
        keep = present(ds, i)
        xc, top = surface_profile(ds["x"].values[i][keep], ds["y"].values[i][keep], dx)
        ax.plot(xc, top, color=c, lw=1.5, label=f"t = {time[i]:.2f} s (t_s = {time[i] / sc['tc']:.1f})")
    ax.axvline(sc["L0"], color="0.5", lw=0.8, ls=":")
    ax.text(sc["L0"], sc["H0"] * 1.02, "gate", ha="center", va="bottom", fontsize=8, color="0.4")
    phi = math.degrees(math.atan(float(ds.attrs["mu_s"]))) if "mu_s" in ds.attrs else float("nan")
    rankine = 45.0 + phi / 2
    fp = failure_plane_angle(ds, t_norm=failure_t_s)
    angle, angle_bed, t_fp = fp["angle_horizontal_deg"], fp["angle_deg"], fp["time"]
    if math.isfinite(rankine):
        # Rankine's angle is from the horizontal; in the slope-aligned frame the plane is rankine − θ from the bed
        xr_ = np.array([sc["L0"] - sc["H0"] / math.tan(math.radians(rankine - sc["theta_deg"])), sc["L0"]])
        ax.plot(xr_, [sc["H0"], 0.0], color="k", ls="--", lw=1,
                label=f"Rankine failure plane 45° + φ/2 = {rankine:.2f}° from the horizontal (φ = atan μ_s = {phi:.1f}°)")
    if math.isfinite(angle_bed):
        # the fitted plane in the initial column (slope-aligned frame: its angle from the bed)
        xf = np.array([fp["toe_x"] - sc["H0"] / math.tan(math.radians(angle_bed)), fp["toe_x"]])
        ax.plot(xf, [sc["H0"], 0.0], color="C3", ls="-", lw=1,
                label=f"failure plane in this run: {angle:.1f}° from the horizontal")
    txt = (f"failure plane in this run: {angle:.1f}° from the horizontal ({angle_bed:.1f}° from the bed; "
           f"boundary of the particles moving faster than {CRITICAL_SPEED:g} m/s at t = {t_fp:.2f} s, "
           f"on their initial positions); paper's 2D SPH: {PAPER_FAILURE_PLANE_DEG}°, paper's Rankine value "
           f"57.75°") if math.isfinite(angle) else \
        "failure plane: no static/moving boundary found inside the column"
    ax.set_title(f"{case_of(ds)}: a = {sc['H0'] / sc['L0']:.2f}, θ = {sc['theta_deg']:g}°, dx = {dx:g} m",
                 loc="left", fontsize=10)
    ax.set_xlabel("x along the slope from the back wall (m)")
    ax.set_ylabel("bed-normal height y (m)")
    ax.set_ylim(0, sc["H0"] * 1.25)
    ax.set_xlim(0, None)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="upper right", ncol=2)
    status = str(ds.attrs.get("status", "ok"))
    warn = f" Run status: {status}." if status.lower().startswith("failed") else ""
    note(fig, f"Vertical scale exaggerated. Free surface = highest particle centre + dx/2 per column of width 2 dx. "
              f"{txt[0].upper() + txt[1:]}. {NO_FARIN}.{warn}")
    return fig


def _sections_for(sections, case):
    for s in sections:
        if case_of(s) == case:
            return s
    return None


def fig7(runs, ts=None, sections=(), n_times: int = 4):
    """Flowing/deposited particles and the F/D interface at several t_s, per case."""
    runs = [load(r) for r in runs]
    secs = [load(s) for s in sections]
    if not runs:
        raise ConfigError("fig7: at least one 2D ISPH run is needed")
    per_case = []
    for ds in runs:
        need(ds, ["x", "y", "u", "v", "dx", "H0"], "fig7 2D run")
        sc = scales(ds)
        want = list(ts) if ts else list(np.linspace(1.0, rest_time(ds) / sc["tc"], n_times))
        per_case.append((ds, sc, [_time_index(ds["time"].values, t * sc["tc"]) for t in want]))
    nt = max(len(p[2]) for p in per_case)
    ncols = min(len(runs), 2)
    blocks = math.ceil(len(runs) / ncols)
    fig, axes = new_figure(nt * blocks, ncols, panel=(6.0, 1.45))
    k = 0
    for c, (ds, sc, idx) in enumerate(per_case):
        col, block = c % ncols, c // ncols
        dx = float(ds.attrs["dx"])
        x_all = ds["x"].values
        xmax = max(float(np.nanmax(x_all[i][present(ds, i)])) for i in idx) + dx
        sec = _sections_for(secs, case_of(ds))
        for r, i in enumerate(idx):
            ax = axes[block * nt + r, col]
            keep = present(ds, i)
            x, y = x_all[i][keep], ds["y"].values[i][keep]
            dep = np.hypot(ds["u"].values[i][keep], ds["v"].values[i][keep]) < CRITICAL_SPEED
            ax.scatter(x[dep], y[dep], s=1.5, c="0.6", lw=0, rasterized=True, label="deposited (|v| < 0.1 m/s)")
            ax.scatter(x[~dep], y[~dep], s=1.5, c="C1", lw=0, rasterized=True, label="flowing")
            xc, yi = interface_profile(x, y, dep, dx)
            ax.plot(xc, yi, "k--", lw=1, label="F/D interface (particles)")
            if sec is not None:
                j = _time_index(sec["time"].values, float(ds["time"].values[i]))
                ax.plot(sec["x"].values, sec["interface_height"].values[:, j], "o", ms=3, mfc="none", mec="C3",
                        label="F/D interface, sections (eq 16)")
            ax.set_xlim(0, xmax)
            ax.set_ylim(0, sc["H0"] * 1.05)
            ax.text(0.99, 0.9, f"t_s = {ds['time'].values[i] / sc['tc']:.1f}", transform=ax.transAxes,
                    ha="right", va="top", fontsize=8)
            ax.set_ylabel("y (m)", fontsize=8)
            ax.tick_params(labelsize=7)
            if r == 0:
                panel_label(ax, c, f"{case_of(ds)}: θ = {sc['theta_deg']:g}°, a = {sc['H0'] / sc['L0']:.2f}")
            if r == len(idx) - 1:
                ax.set_xlabel("x along the slope (m)", fontsize=8)
            k += 1
    for ax in axes.ravel():
        if not ax.has_data():
            ax.set_visible(False)
    from matplotlib.lines import Line2D
    handles = [Line2D([], [], ls="none", marker="o", ms=5, color="0.6", label="deposited (speed < 0.1 m/s)"),
               Line2D([], [], ls="none", marker="o", ms=5, color="C1", label="flowing"),
               Line2D([], [], ls="--", color="k", label="F/D interface (particles)")]
    if secs:
        handles.append(Line2D([], [], ls="none", marker="o", ms=4, mfc="none", mec="C3",
                              label="F/D interface at the sections (eq 16)"))
    fig.legend(handles=handles, loc="outside upper center", ncol=4, fontsize=8)
    note(fig, "Vertical scale exaggerated. Deposited: particle speed below the critical 0.1 m/s (Section 2.2). "
              "Dashed: top of the deposited layer under the flowing one per 2 dx column (display estimate).")
    return fig


def velocity_profile(ds, x_m: float, i: int, width_factor: float = 2.0):
    """Mean u_x per dx-thick layer of the particles within the section [x_m ± W_M/2] at time index i."""
    dx = float(ds.attrs["dx"])
    x, y, u = ds["x"].values[i], ds["y"].values[i], ds["u"].values[i]
    sel = np.abs(x - x_m) <= 0.5 * width_factor * dx
    if not sel.any():
        return np.array([]), np.array([])
    layer = np.floor(y[sel] / dx).astype(int)
    n = layer.max() + 1
    cnt = np.bincount(layer, minlength=n)
    s = np.bincount(layer, weights=u[sel], minlength=n)
    ok = cnt > 0
    return (np.arange(n)[ok] + 0.5) * dx, s[ok] / cnt[ok]


def fig10(runs, sections=(), x_norms=(0.2, 0.4), ts=None, n_times: int = 6, width_factor: float = 2.0):
    """u_x/sqrt(g H0 cos θ) vs y/H0 at sections [x], several t_s; rows = cases, columns = [x]."""
    runs = [load(r) for r in runs]
    secs = [load(s) for s in sections]
    if not runs:
        raise ConfigError("fig10: at least one 2D ISPH run is needed")
    fig, axes = new_figure(len(runs), len(x_norms), panel=(4.2, 3.4))
    k = 0
    for r, ds in enumerate(runs):
        need(ds, ["x", "y", "u", "dx", "L0"], "fig10 2D run")
        sc = scales(ds)
        sec = _sections_for(secs, case_of(ds))
        if sec is not None and "x_inf" in sec.attrs:
            x_inf = float(sec.attrs["x_inf"])
        elif "final_front_position" in ds:
            x_inf = float(ds["final_front_position"].values)
        else:
            raise ConfigError(f"fig10: {case_of(ds)}: no x_inf (sections attrs) nor final_front_position")
        time = ds["time"].values
        for c, xn in enumerate(x_norms):
            ax = axes[r, c]
            x_m = sc["L0"] + xn * (x_inf - sc["L0"])
            # times from the arrival of the flow at the section to rest
            present = [j for j in range(time.size) if np.any(np.abs(ds["x"].values[j] - x_m) <= width_factor * float(ds.attrs["dx"]) / 2)]
            t0 = time[present[0]] if present else 0.0
            want = [t * sc["tc"] for t in ts] if ts else np.linspace(t0, rest_time(ds), n_times)
            idx = list(dict.fromkeys(_time_index(time, t) for t in want))
            for col, i in zip(colours(len(idx), "viridis"), idx):
                yy, uu = velocity_profile(ds, x_m, i, width_factor)
                if yy.size:
                    ax.plot(uu / sc["U"], yy / sc["H0"], "-o", ms=2.5, lw=1.2, color=col,
                            label=f"t_s = {time[i] / sc['tc']:.1f}")
            ax.axvline(CRITICAL_SPEED / sc["U"], color="C3", ls=":", lw=1, label="critical speed 0.1 m/s")
            ax.axvspan(min(0.0, ax.get_xlim()[0]), CRITICAL_SPEED / sc["U"], color="C3", alpha=0.07)
            ax.set_xlabel("u_x / sqrt(g H0 cos θ) (–)")
            ax.set_ylabel("y / H0 (–)")
            ax.set_ylim(bottom=0)
            ax.grid(alpha=0.3)
            panel_label(ax, k, f"{case_of(ds)}, [x] = {xn:g} (x = {x_m:.3f} m)")
            ax.legend(fontsize=7)
            k += 1
    note(fig, f"Particles within W_M = {width_factor:g} dx of the section, mean u_x per dx-thick layer; "
              "shaded: below the critical speed (deposition, Section 2.2).")
    return fig


# ---- CLI -------------------------------------------------------------------------------------------

def _args5(p):
    add_inputs(p, "one 2D ISPH run (T22-A70 in the paper)")
    p.add_argument("--times", nargs="+", type=float, metavar="T", help="times (s); default 6 up to rest")
    p.add_argument("--failure-ts", type=float, default=1.0, metavar="TS",
                   help="t_s at which the failure plane is measured (default 1)")


@register("fig5", "free surface at several times + failure plane (2D run)", _args5)
def _fig5(args):
    k = classify(args.inputs, ("isph",), "fig5")
    if len(k["isph"]) != 1:
        raise ConfigError("fig5: give exactly one 2D ISPH run")
    return fig5(k["isph"][0], args.times, args.failure_ts)


def _args7(p):
    add_inputs(p, "2D ISPH runs (one column of panels each), optionally their sections files")
    p.add_argument("--ts", nargs="+", type=float, metavar="TS", help="normalised times t_s (default 4 up to rest)")


@register("fig7", "F/D interface evolution: flowing/deposited particles + interface at several t_s", _args7)
def _fig7(args):
    k = classify(args.inputs, ("isph", "sections"), "fig7")
    return fig7(k["isph"], args.ts, k["sections"])


register("figA3", "Fig A3: F/D interface evolution for every case (same as fig7)", _args7)(_fig7)


def _args10(p):
    add_inputs(p, "2D ISPH runs, optionally their sections files (for x_inf)")
    p.add_argument("--x-norm", nargs="+", type=float, default=[0.2, 0.4], metavar="X", help="sections [x]")
    p.add_argument("--ts", nargs="+", type=float, metavar="TS", help="normalised times t_s")
    p.add_argument("--width-factor", type=float, default=2.0, metavar="W", help="section width / dx")


@register("fig10", "velocity profiles u_x/sqrt(g H0 cos θ) vs y/H0 at [x] = 0.2, 0.4", _args10)
def _fig10(args):
    k = classify(args.inputs, ("isph", "sections"), "fig10")
    return fig10(k["isph"], k["sections"], args.x_norm, args.ts, width_factor=args.width_factor)
