"""Figs 8, 9, 11, A1, A2: time series at the monitoring sections (``granudep monitor`` output).

Fig 8 h_T/H0 vs t_s; Fig 9 h_D/H0 vs t_s with the linear fits and onset points of
``granudep regress`` (critical.csv); Fig 11 hu/p0 vs t_s with the critical points; Fig A1 hu/p0 for
W_M = 1..4 dx and Fig A2 the RMS deviation from W_M = 2 dx (``granudep monitor-wm`` output).
"""
from __future__ import annotations

import numpy as np

from ..config import ConfigError
from .common import (add_inputs, case_of, classify, colours, critical_for, hide_unused, load, load_table, need,
                     nearest_row, new_figure, note, panel_label, pick_sections, register, scales)

CRITICAL_COLUMNS = ("case", "x_norm", "t_s_critical")


def _grid(n, panel=(5.2, 3.6)):
    ncols = 1 if n == 1 else 2
    return new_figure(-(-n // ncols), ncols, panel=panel)


def _ts(ds):
    return ds["t_s"].values if "t_s" in ds.coords or "t_s" in ds else ds["time"].values / scales(ds)["tc"]


def _momentum_norm(ds):
    if "momentum_norm" in ds and ds["momentum_norm"].ndim == 2:
        return ds["momentum_norm"].values
    return ds["momentum"].values / scales(ds)["p0"]


def fig8(sections, x_norms=(0.0, 0.2, 0.4, 0.6, 0.8, 1.0)):
    """h_T/H0 vs t_s at the chosen sections, one panel per case."""
    secs = [load(s) for s in sections]
    if not secs:
        raise ConfigError("fig8: at least one sections file is needed")
    fig, axes = _grid(len(secs))
    for k, ds in enumerate(secs):
        need(ds, ["total_depth", "x_norm", "H0"], "fig8 sections")
        ax = axes.ravel()[k]
        ts, H0 = _ts(ds), float(ds.attrs["H0"])
        idx = pick_sections(ds["x_norm"].values, x_norms)
        for c, i in zip(colours(len(idx)), idx):
            ax.plot(ts, ds["total_depth"].values[i] / H0, color=c, lw=1.3, label=f"[x] = {ds['x_norm'].values[i]:.1f}")
        sc = scales(ds)
        panel_label(ax, k, f"{case_of(ds)}: θ = {sc['theta_deg']:g}°, a = {H0 / sc['L0']:.2f}")
        ax.set_xlabel("t_s = t/t_c (–)")
        ax.set_ylabel("h_T / H0 (–)")
        ax.set_ylim(bottom=0)
        ax.set_xlim(left=0)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    hide_unused(axes, len(secs))
    note(fig, "h_T: bed-normal total depth at each monitoring section (free surface − bed).")
    return fig


def fig9(sections, critical, x_norms=(0.2, 0.4, 0.6, 0.8)):
    """h_D/H0 vs t_s with the regression's linear fits (slope = (S_D)_s) and onset points."""
    secs = [load(s) for s in sections]
    crit = load_table(critical, CRITICAL_COLUMNS, "fig9 critical.csv") if critical is not None else None
    if not secs:
        raise ConfigError("fig9: at least one sections file is needed")
    fig, axes = _grid(len(secs))
    for k, ds in enumerate(secs):
        need(ds, ["deposit_depth", "x_norm", "H0"], "fig9 sections")
        ax = axes.ravel()[k]
        ts, H0 = _ts(ds), float(ds.attrs["H0"])
        cr = critical_for(crit, case_of(ds))
        idx = pick_sections(ds["x_norm"].values, x_norms)
        for c, i in zip(colours(len(idx)), idx):
            xn = float(ds["x_norm"].values[i])
            hd = ds["deposit_depth"].values[i] / H0
            ax.plot(ts, hd, "o", ms=2, color=c, alpha=0.6)
            row = nearest_row(cr, xn)
            label = f"[x] = {xn:.1f}"
            if row is not None:
                t_on = float(row["t_s_critical"])
                ax.plot([t_on], [0.0], "o", ms=7, mfc="none", mec=c, mew=1.5, zorder=5)
                if "deposition_rate" in row and "t_s_critical_fit" in row and np.isfinite(row["deposition_rate"]):
                    t_fit, rate = float(row["t_s_critical_fit"]), float(row["deposition_rate"])
                    # the line over the fitted growth phase only: from its t_s intercept (the Fig 9
                    # reading) to the first sample after the onset with h_D >= 95 % of the final h_D
                    hz = np.nan_to_num(hd, nan=0.0)
                    after = np.flatnonzero((ts >= t_on) & (hz >= 0.95 * hz[-1]))
                    t_end = float(ts[after[0]]) if after.size else float(ts[-1])
                    tt = np.array([t_fit, max(t_end, t_fit)])
                    ax.plot(tt, rate * (tt - t_fit), "-", color=c, lw=1.3)
                    r2 = f", R² = {float(row['r2']):.2f}" if "r2" in row else ""
                    label += f": (t_s)_C = {t_on:.2f}, (S_D)_s = {rate:.3g}{r2}"
            ax.plot([], [], "-o", ms=3, color=c, label=label)
        sc = scales(ds)
        panel_label(ax, k, f"{case_of(ds)}: θ = {sc['theta_deg']:g}°, a = {H0 / sc['L0']:.2f}")
        ax.set_xlabel("t_s = t/t_c (–)")
        ax.set_ylabel("h_D / H0 (–)")
        ax.set_ylim(bottom=0)
        ax.set_xlim(left=0)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper left")
    hide_unused(axes, len(secs))
    note(fig, "Dots: deposit depth at the sections; lines: linear fits of granudep regress (slope = normalised "
              "deposition rate (S_D)_s), drawn from their t_s intercept over the fitted growth phase only; open circles: "
              "onset of deposition (t_s)_C." +
              ("" if crit is not None else " No critical.csv given: fits and onsets not shown."))
    return fig


def fig11(sections, critical=None, x_norms=(0.0, 0.2, 0.4, 0.6, 0.8)):
    """hu/p0 vs t_s with the critical points ((t_s)_C, (hu)_C/p0)."""
    secs = [load(s) for s in sections]
    crit = load_table(critical, CRITICAL_COLUMNS, "fig11 critical.csv") if critical is not None else None
    if not secs:
        raise ConfigError("fig11: at least one sections file is needed")
    fig, axes = _grid(len(secs))
    for k, ds in enumerate(secs):
        need(ds, ["momentum", "x_norm", "H0"], "fig11 sections")
        ax = axes.ravel()[k]
        ts, mom = _ts(ds), _momentum_norm(ds)
        cr = critical_for(crit, case_of(ds))
        idx = pick_sections(ds["x_norm"].values, x_norms)
        for c, i in zip(colours(len(idx)), idx):
            xn = float(ds["x_norm"].values[i])
            ax.plot(ts, mom[i], color=c, lw=1.3, label=f"[x] = {xn:.1f}")
            row = nearest_row(cr, xn)
            if row is not None and "momentum_critical_norm" in row:
                ax.plot([float(row["t_s_critical"])], [float(row["momentum_critical_norm"])], "o", ms=7,
                        mfc="none", mec=c, mew=1.5, zorder=5)
        ax.plot([], [], "o", mfc="none", mec="k", label="critical point ((t_s)_C, (hu)_C/p0)")
        sc = scales(ds)
        panel_label(ax, k, f"{case_of(ds)}: θ = {sc['theta_deg']:g}°, a = {float(ds.attrs['H0']) / sc['L0']:.2f}")
        ax.set_xlabel("t_s = t/t_c (–)")
        ax.set_ylabel("hu / p0 (–)")
        ax.set_xlim(left=0)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    hide_unused(axes, len(secs))
    note(fig, "p0 = H0 sqrt(g H0 cos θ); h = flowing depth above the F/D interface, u = section-averaged velocity (eq 15).")
    return fig


def figA1(wm_files, x_norms=(0.2, 0.4, 0.6, 0.8)):
    """hu/p0 vs t_s for each section width W_M (panels: sections)."""
    dss = [load(w) for w in wm_files]
    if not dss:
        raise ConfigError("figA1: at least one monitor-wm file is needed")
    ds = dss[0]
    need(ds, ["momentum_norm", "width_factor", "x_norm"], "figA1 monitor-wm")
    ts = _ts(ds)
    idx = pick_sections(ds["x_norm"].values, x_norms)
    fig, axes = _grid(len(idx), panel=(4.8, 3.2))
    wf = ds["width_factor"].values
    styles = ["-", "--", "-.", ":"]
    for k, i in enumerate(idx):
        ax = axes.ravel()[k]
        for j, w in enumerate(wf):
            c = f"C{j}"
            ax.plot(ts, ds["momentum_norm"].values[j, i], color=c, ls=styles[j % 4], lw=1.3, label=f"W_M = {w:g} dx")
        if "deceleration" in ds:
            m = ds["deceleration"].values[i].astype(bool)
            if m.any():
                ax.axvspan(ts[m][0], ts[m][-1], color="0.9", zorder=0, label="deceleration window (RMS)")
        panel_label(ax, k, f"[x] = {float(ds['x_norm'].values[i]):.1f}")
        ax.set_xlabel("t_s = t/t_c (–)")
        ax.set_ylabel("hu / p0 (–)")
        ax.set_xlim(left=0)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    hide_unused(axes, len(idx))
    sc = scales(ds)
    fig.suptitle(f"{case_of(ds)}: θ = {sc['theta_deg']:g}°, a = {sc['H0'] / sc['L0']:.2f}, "
                 f"dx = {float(ds.attrs.get('dx', np.nan)):g} m", fontsize=10)
    return fig


def rms_deviation(ds, reference: float = 2.0) -> np.ndarray:
    """RMS of hu/p0 − (hu/p0)_{W_M = reference dx} per (width, section), over the deceleration
    window when the file gives it (else every time where both are finite)."""
    if "rms_deviation" in ds:
        return ds["rms_deviation"].values
    wf = list(ds["width_factor"].values)
    mom = ds["momentum_norm"].values
    ref = mom[wf.index(reference)]
    mask = ds["deceleration"].values.astype(bool) if "deceleration" in ds else np.ones(ref.shape, bool)
    diff = np.where(mask[None] & np.isfinite(mom) & np.isfinite(ref)[None], mom - ref[None], np.nan)
    n = np.isfinite(diff).sum(axis=2)
    with np.errstate(invalid="ignore"):
        return np.where(n > 0, np.sqrt(np.nansum(diff ** 2, axis=2) / np.maximum(n, 1)), np.nan)


def figA2(wm_files, reference: float = 2.0):
    """RMS deviation from W_M = 2 dx vs [x], per case and width."""
    dss = [load(w) for w in wm_files]
    if not dss:
        raise ConfigError("figA2: at least one monitor-wm file is needed")
    fig, axes = new_figure(1, 1, panel=(6.0, 3.8))
    ax = axes[0, 0]
    markers = ["o", "s", "^", "D", "v"]
    for ci, ds in enumerate(dss):
        need(ds, ["momentum_norm", "width_factor", "x_norm"], "figA2 monitor-wm")
        ref = float(ds.attrs.get("wm_reference", reference))
        rms = rms_deviation(ds, ref)
        for j, w in enumerate(ds["width_factor"].values):
            if w == ref:
                continue
            ax.plot(ds["x_norm"].values, rms[j], marker=markers[j % 5], color=f"C{ci}",
                    ls=["-", "--", "-.", ":"][j % 4], lw=1, ms=4, label=f"{case_of(ds)}, W_M = {w:g} dx")
    ax.axhline(0.03, color="k", ls=":", lw=1, label="paper: RMS < 0.03 (W_M = 3, 4 dx)")
    ax.set_xlabel("[x] = (x − L0)/(x∞ − L0) (–)")
    ax.set_ylabel(f"RMS deviation of hu/p0 from W_M = {reference:g} dx (–)")
    ax.set_ylim(bottom=0)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    note(fig, "RMS over the deceleration window of the reference width (Appendix; paper's Fig A2 at θ = 22°).")
    return fig


# ---- CLI -------------------------------------------------------------------------------------------

def _xn(p, default):
    p.add_argument("--x-norm", nargs="+", type=float, default=list(default), metavar="X",
                   help=f"sections [x] to show (nearest; default {' '.join(map(str, default))})")


def _one_csv(k, name, fig):
    if len(k[name]) > 1:
        raise ConfigError(f"{fig}: give at most one {name}.csv")
    return k[name][0] if k[name] else None


def _args8(p):
    add_inputs(p, "sections files (granudep monitor)")
    _xn(p, (0.0, 0.2, 0.4, 0.6, 0.8, 1.0))


@register("fig8", "h_T/H0 vs t_s at monitoring sections", _args8)
def _fig8(args):
    return fig8(classify(args.inputs, ("sections",), "fig8")["sections"], args.x_norm)


def _args9(p):
    add_inputs(p, "sections files and the regression's critical.csv")
    _xn(p, (0.2, 0.4, 0.6, 0.8))


@register("fig9", "h_D/H0 vs t_s with linear fits and onset points", _args9)
def _fig9(args):
    k = classify(args.inputs, ("sections", "critical"), "fig9")
    return fig9(k["sections"], _one_csv(k, "critical", "fig9"), args.x_norm)


def _args11(p):
    add_inputs(p, "sections files and the regression's critical.csv")
    _xn(p, (0.0, 0.2, 0.4, 0.6, 0.8))


@register("fig11", "hu/p0 vs t_s at sections with the critical points", _args11)
def _fig11(args):
    k = classify(args.inputs, ("sections", "critical"), "fig11")
    return fig11(k["sections"], _one_csv(k, "critical", "fig11"), args.x_norm)


def _argsA1(p):
    add_inputs(p, "a monitor-wm file (granudep monitor-wm)")
    _xn(p, (0.2, 0.4, 0.6, 0.8))


@register("figA1", "hu/p0 vs t_s for W_M = 1..4 dx", _argsA1)
def _figA1(args):
    return figA1(classify(args.inputs, ("wm",), "figA1")["wm"], args.x_norm)


def _argsA2(p):
    add_inputs(p, "monitor-wm files")


@register("figA2", "RMS deviation of hu/p0 from W_M = 2 dx vs [x]", _argsA2)
def _figA2(args):
    return figA2(classify(args.inputs, ("wm",), "figA2")["wm"])
