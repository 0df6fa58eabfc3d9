"""Runout on a path profile: the bed with the release and the final deposit drawn on
it, the travel-angle line, and the along-path envelopes (max depth, max speed, arrival time) of
one or two DA path runs (with / without deposition). Command: ``granudep path-figure -o OUT.png
RUN.nc [RUN2.nc]`` (registered by ``granudep.da.cli``; not one of the paper's figures, so not in
``figures.FIGURES``)."""
from __future__ import annotations

import numpy as np

from .common import load, need, new_figure, note, panel_label

STYLE = {1: dict(color="C0", ls="-", label="with deposition"), 0: dict(color="C3", ls="--", label="no deposition")}
NEEDED = ("s", "x", "z", "final_deposit_depth", "max_flow_depth", "max_speed", "arrival_time", "travel_angle",
          "path_file")


def _normal(ds):
    """Unit bed normal (nx, nz) at the stations (pointing up from the bed)."""
    th = np.radians(ds.bed_slope.values)
    return np.sin(th), np.cos(th)


def path_figure(runs, exaggeration: float | None = None):
    dss = [load(r) for r in runs]
    for ds in dss:
        need(ds, NEEDED, "path figure")
    dss.sort(key=lambda d: -int(d.attrs.get("deposition", 0)))
    ref = dss[0]
    x, z = ref.x.values, ref.z.values
    relief = float(np.ptp(z)) or 1.0
    hmax = max(float(np.nanmax(d.max_flow_depth.values)) for d in dss) or 1.0
    ex = exaggeration if exaggeration else max(1.0, round(0.08 * relief / hmax))
    fig, axes = new_figure(3, 1, panel=(8.0, 2.6))
    ax = axes[0, 0]
    ax.plot(x, z, color="0.3", lw=1.2, label="bed (smoothed path)")
    nx, nz = _normal(ref)
    s0, s1 = ref.attrs["release_start"], ref.attrs["release_end"]
    rel = (ref.s.values >= s0) & (ref.s.values <= s1)
    h0 = ref.flow_depth.values[0]
    ax.fill_between(x[rel], z[rel], (z + ex * h0 * nz)[rel], color="0.7", label="release")
    for ds in dss:
        st = STYLE[int(ds.attrs["deposition"])]
        hd = ds.final_deposit_depth.values
        # each run on its own station grid (with deposition the grid follows the particles)
        xd, zd = ds.x.values, ds.z.values
        nxd, nzd = _normal(ds)
        top_x, top_z = xd + ex * hd * nxd, zd + ex * hd * nzd
        if st["ls"] == "-":
            ax.fill(np.concatenate([xd, top_x[::-1]]), np.concatenate([zd, top_z[::-1]]), color=st["color"], alpha=0.5,
                    lw=0, label=f"final deposit ({st['label']})")
        else:
            ax.plot(top_x, top_z, color=st["color"], ls=st["ls"], lw=1.0, label=f"final deposit ({st['label']})")
        xt, zt = float(np.interp(s0, ref.s.values, x)), float(np.interp(s0, ref.s.values, z))
        xf, zf = ds.attrs["final_front_x"], ds.attrs["final_front_z"]
        ax.plot([xt, xf], [zt, zf], color=st["color"], ls=":", lw=0.9,
                label=f"travel angle {float(ds.travel_angle):.1f}° ({st['label']})")
        ax.plot([xf], [zf], marker="v", color=st["color"], ms=6)
    ax.set_xlabel("horizontal distance x (m)")
    ax.set_ylabel("elevation z (m)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.legend(fontsize=7, loc="upper right")
    panel_label(ax, 0, f"profile, depths × {ex:g} (bed-normal)")
    ax = axes[1, 0]
    ax2 = ax.twinx()
    for ds in dss:
        st = STYLE[int(ds.attrs["deposition"])]
        ax.plot(ds.x.values, ds.max_flow_depth.values, color=st["color"], ls=st["ls"], label=f"max depth, {st['label']}")
        ax2.plot(ds.x.values, ds.max_speed.values, color=st["color"], ls=st["ls"], alpha=0.45, lw=0.9)
    ax.set_xlabel("horizontal distance x (m)")
    ax.set_ylabel("max flow depth (m)")
    ax2.set_ylabel("max speed (m/s), light lines")
    ax.legend(fontsize=7, loc="upper right")
    panel_label(ax, 1, "envelopes: max flow depth (dark) and max speed (light)")
    ax = axes[2, 0]
    for ds in dss:
        st = STYLE[int(ds.attrs["deposition"])]
        ax.plot(ds.x.values, ds.arrival_time.values, color=st["color"], ls=st["ls"], label=st["label"])
    ax.set_xlabel("horizontal distance x (m)")
    ax.set_ylabel("arrival time (s)")
    ax.legend(fontsize=7)
    panel_label(ax, 2, "arrival time (first particle ≥ front threshold deep)")
    lines = []
    for ds in dss:
        st = STYLE[int(ds.attrs["deposition"])]
        lift = int(ds.attrs.get("lift_off_count", 0))
        lines.append(f"{st['label']}: runout {float(ds.runout_horizontal):.1f} m horizontal "
                     f"({float(ds.final_runout):.1f} m along the bed) from the release end, travel angle "
                     f"{float(ds.travel_angle):.2f}°" + (f", normal stress clipped {lift}×" if lift else ""))
    note(fig, f"{ref.attrs['case']} on {ref.attrs['path_file']} (σ = {ref.attrs['path_smoothing_length']:g} m); "
              + "; ".join(lines) + f"; front threshold {ref.attrs['front_depth_threshold'] * 100:g} cm")
    return fig
