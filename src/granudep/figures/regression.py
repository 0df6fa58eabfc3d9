"""Figs 12, 13: critical DA momentum (hu)_C/p0 vs [x] with the fits A[x] + B (eq 36), and A, B vs a.

Inputs are ``granudep regress`` tables: critical.csv (case, theta_deg, a, x_norm,
momentum_critical_norm, ...) and coefficients.csv (case, theta_deg, a, A, B, r2). Fig 13 also
shows the paper's Table 5 values (θ = 22°, shipped with the package).
"""
from __future__ import annotations

import numpy as np

from .. import cases
from ..config import ConfigError
from .common import add_inputs, classify, hide_unused, load_table, new_figure, note, panel_label, register
import pandas as pd


def fig12(critical, coefficients=None):
    """(hu)_C/p0 vs [x] per case with the fitted line; one panel per slope angle."""
    crit = load_table(critical, ("case", "theta_deg", "a", "x_norm", "momentum_critical_norm"), "fig12 critical.csv")
    coef = load_table(coefficients, ("case", "A", "B"), "fig12 coefficients.csv") if coefficients is not None else None
    thetas = sorted(crit["theta_deg"].unique())
    if not thetas:
        raise ConfigError("fig12: critical.csv has no rows")
    fig, axes = new_figure(1, len(thetas), panel=(5.0, 3.8))
    for k, th in enumerate(thetas):
        ax = axes[0, k]
        sub = crit[crit["theta_deg"] == th].sort_values("a")
        for j, (case, g) in enumerate(sub.groupby("case", sort=False)):
            c = f"C{j % 10}"
            a = float(g["a"].iloc[0])
            ax.plot(g["x_norm"], g["momentum_critical_norm"], "o", color=c, ms=5)
            label = f"{case} (a = {a:g})"
            if coef is not None:
                row = coef[coef["case"].astype(str) == str(case)]
                if not row.empty:
                    A, B = float(row["A"].iloc[0]), float(row["B"].iloc[0])
                    # the line over the fitted data's [x] range only (no extrapolation drawn)
                    used = g[np.isfinite(g["momentum_critical_norm"].astype(float))]["x_norm"].astype(float)
                    xx = np.array([used.min(), used.max()]) if len(used) else np.array([0.0, 1.0])
                    r2 = f", R² = {float(row['r2'].iloc[0]):.2f}" if "r2" in row else ""
                    ax.plot(xx, A * xx + B, "-", color=c, lw=1.2)
                    label += f": A = {A:.4f}, B = {B:.4f}{r2}"
            ax.plot([], [], "-o", color=c, ms=4, label=label)
        panel_label(ax, k, f"θ = {th:g}°")
        ax.set_xlabel("[x] = (x − L0)/(x∞ − L0) (–)")
        ax.set_ylabel("(hu)_C / p0 (–)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    note(fig, "Dots: critical DA momentum at the onset of deposition per section; lines: (hu)_C/p0 = A[x] + B (eq 36), "
              "drawn over the [x] range of the sections in the fit only.")
    return fig


def fig12_residuals(diagnosis, residuals):
    """Residual plot of eq 36: (a) baseline residuals vs [x] per case (colour: a);
    (b) R² of each refit variant per case vs a; (c) A per variant vs a at each θ."""
    diag = load_table(diagnosis, ("case", "a", "theta_deg", "variant", "A", "r2"), "fig12r diagnosis.csv")
    res = load_table(residuals, ("case", "a", "theta_deg", "x_norm", "residual"), "fig12r residuals.csv")
    fig, axes = new_figure(1, 3, panel=(4.6, 3.8))
    ax = axes[0, 0]
    amin, amax = float(res["a"].min()), float(res["a"].max())
    from matplotlib import colormaps
    cmap = colormaps["viridis"]
    for (case, th), g in res.groupby(["case", "theta_deg"], sort=False):
        a = float(g["a"].iloc[0])
        c = cmap(0.0 if amax == amin else (a - amin) / (amax - amin))
        g = g.sort_values("x_norm")
        ax.plot(g["x_norm"], g["residual"], "-o" if th >= 20 else "--s", color=c, ms=3.5, lw=0.9,
                label=f"{case}")
    ax.axhline(0, color="k", lw=0.7)
    panel_label(ax, 0, "residual of the line, baseline")
    ax.set_xlabel("[x] (–)")
    ax.set_ylabel("(hu)_C/p0 − (A[x] + B) (–)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=6, ncol=2)
    variants = list(dict.fromkeys(diag["variant"]))
    markers = "osD^v<>px*h"
    for k, q in ((1, "r2"), (2, "A")):
        ax = axes[0, k]
        for j, v in enumerate(variants):
            g = diag[diag["variant"] == v].sort_values("a")
            for th, gt in g.groupby("theta_deg"):
                ax.plot(gt["a"].astype(float), gt[q].astype(float), marker=markers[j % len(markers)],
                        ls="-" if th >= 20 else ":", color=f"C{j % 10}", ms=4, lw=0.8,
                        label=v if th == g["theta_deg"].max() else None)
        if q == "r2":
            ax.axhline(0.8, color="k", lw=0.7, ls="--")
            ax.set_ylim(min(-0.1, float(pd.to_numeric(diag["r2"], errors="coerce").min()) - 0.05), 1.02)
        panel_label(ax, k, "R² of the line per variant" if q == "r2" else "A per variant")
        ax.set_xlabel("a = H0/L0 (–)")
        ax.set_ylabel("R² (–)" if q == "r2" else "A (–)")
        ax.grid(alpha=0.3)
    axes[0, 1].legend(fontsize=6)
    note(fig, "Each variant refits (hu)_C/p0 = A[x] + B with one method choice changed (regression/diagnosis.csv). "
              "Solid: θ = 22°, dotted: other θ. Dashed line in (b): R² = 0.8.")
    return fig


def fig13(coefficients):
    """A and B vs a for each slope angle, with the paper's Table 5 values at 22°."""
    coef = load_table(coefficients, ("theta_deg", "a", "A", "B"), "fig13 coefficients.csv")
    t5 = cases.table5()
    fig, axes = new_figure(1, 2, panel=(4.8, 3.6))
    for k, q in enumerate(("A", "B")):
        ax = axes[0, k]
        for j, (th, g) in enumerate(coef.sort_values("a").groupby("theta_deg")):
            ax.plot(g["a"], g[q], "-o", color=f"C{j}", ms=5, label=f"ours, θ = {th:g}°")
        ax.plot(t5["a"], t5[q], "kx", ms=8, mew=1.5, ls="none", label="paper Table 5, θ = 22°")
        ax.axhline(0, color="0.6", lw=0.6)
        panel_label(ax, k, q)
        ax.set_xlabel("initial aspect ratio a = H0/L0 (–)")
        ax.set_ylabel(f"{q} (–)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    note(fig, "(hu)_C/p0 = A[x] + B (eq 36); ours from the linear fits of Fig 12.")
    return fig


def _args12(p):
    add_inputs(p, "critical.csv and coefficients.csv (granudep regress)")


@register("fig12", "(hu)_C/p0 vs [x] with linear fits per case (θ panels)", _args12)
def _fig12(args):
    k = classify(args.inputs, ("critical", "coefficients"), "fig12")
    if len(k["critical"]) != 1:
        raise ConfigError("fig12: give exactly one critical.csv")
    return fig12(k["critical"][0], k["coefficients"][0] if k["coefficients"] else None)


def _args12r(p):
    p.add_argument("diagnosis", help="regression/diagnosis.csv (granudep regress-diagnose)")
    p.add_argument("residuals", help="regression/residuals.csv (granudep regress-diagnose)")


@register("fig12r", "residuals and R² of the eq-36 fit per method variant (regression diagnosis)", _args12r)
def _fig12r(args):
    return fig12_residuals(args.diagnosis, args.residuals)


def _args13(p):
    add_inputs(p, "coefficients.csv (granudep regress)")


@register("fig13", "A and B vs a for each θ, with the paper's Table 5 at 22°", _args13)
def _fig13(args):
    k = classify(args.inputs, ("coefficients",), "fig13")
    if len(k["coefficients"]) != 1:
        raise ConfigError("fig13: give exactly one coefficients.csv")
    return fig13(k["coefficients"][0])


__all__ = ["fig12", "fig13", "hide_unused"]
