"""``run_da`` for a config with ``geometry.path``: set-up checks, A/B and k along the path, the x∞
iteration (as for the constant-θ model), and the CF dataset with the along-path fields.

Stations s are metres along the smoothed bed from the first point of the path CSV; every output
station variable carries x(s) and z(s) as auxiliary coordinates. ``deposition.x_inf`` (x_inf_mode
user) is a station s. Runout: the front station s_f (front definition as for the constant-θ model,
on h + h_D); ``final_runout`` = s_f − s_gate along the bed (s_gate = down-slope end of the
release), ``runout_horizontal`` = x(s_f) − x(s_gate); the travel (reach) angle α = atan(H/L) with
H = z(s_top) − z(s_f), L = x(s_f) − x(s_top) and s_top the up-slope end of the release on the bed.
"""
from __future__ import annotations

import math

import numpy as np
import xarray as xr

from ..cases import characteristic_time, momentum_scale
from ..config import ConfigError, to_yaml
from ..front import flow_time
from ..io import provenance, var
from ..progress import LOG, Progress
from .deposition import coefficients, find_x_inf
from .errors import DARunError
from .output import add_x_inf_history, run_attributes, run_variables
from .path import Bed, bed_of
from .physics import earth_pressure_coefficients
from .path_solver import PathSetup, bed_table, simulate_path
from .step import AT_REST, D_DEFICIT, D_LIFT, D_WHERE, E_H, E_T, E_U, RUNNING
from .solver import Physics
from ..abtable import interpolate_ab
import pandas as pd

FRONT_DEFINITION = ("down-slope edge of the farthest down-slope contiguous run of grid cells whose total depth "
                    "h + h_D (SPH depth eq 20 on the grid / width, plus deposit) is >= front_depth_threshold and "
                    "which holds >= 1 % of the material above threshold (granudep.front.main_run_front with the channel width)")
ARRIVAL_DEFINITION = "first time a particle at least front_depth_threshold deep passed the cell"


def path_setup(cfg, bed: Bed | None = None) -> PathSetup:
    """Bed and release of a path config; ConfigError (one line) if the release is off the path."""
    pc, g = cfg.geometry.path, cfg.geometry
    bed = bed_of(pc) if bed is None else bed
    n = cfg.numerics.n_particles
    if pc.release_polygon is None:
        s0, s1 = pc.release_start, pc.release_start + g.L0
        key = "geometry.path.release_start"
    else:
        s0, s1 = pc.release_polygon[0][0], pc.release_polygon[-1][0]
        key = "geometry.path.release_polygon"
    if s1 >= bed.length:
        raise ConfigError(f"{key}: the release [{s0:g}, {s1:g}] m must end before the end of the path "
                          f"(bed length {bed.length:.6g} m along the smoothed profile)")
    origin = s0 if g.back_wall else 0.0
    if pc.release_polygon is None:
        dx = g.L0 / n
        x0 = (np.arange(n) + 0.5) * dx + (s0 - origin)
        V0 = g.H0 * dx * bed.at("width", x0 + origin)
        L0, H0 = g.L0, g.H0
    else:
        L0 = s1 - s0
        dx = L0 / n
        x0 = (np.arange(n) + 0.5) * dx + (s0 - origin)
        ps = np.array([v[0] for v in pc.release_polygon])
        ph = np.array([v[1] for v in pc.release_polygon])
        depth = np.interp(x0 + origin, ps, ph)
        V0 = depth * dx * bed.at("width", x0 + origin)
        H0 = float(np.sum(depth) * dx / L0)
    sel = (bed.s >= s0) & (bed.s <= s1)
    th = bed.theta[sel] if sel.any() else bed.at("theta", [0.5 * (s0 + s1)])
    if np.ptp(th) == 0.0:
        theta_rel = float(th[0])
    else:
        z0, z1 = bed.at("z", [s0, s1])
        x0_, x1_ = bed.at("x", [s0, s1])
        theta_rel = math.atan2(z0 - z1, x1_ - x0_)
    return PathSetup(bed, origin, s0, s1, L0, H0, theta_rel, x0, V0, dx)


def earth_pressure_along(cfg, bed: Bed):
    """(k_active, k_passive): scalars (savage_hutter, one) or per station (paper: θ(s) under the
    root of eqs 8–9, refused where the path is steeper than φ_I)."""
    m, mode = cfg.material, cfg.numerics.earth_pressure
    phi_i, phi_b = math.radians(m.phi_internal_deg), math.radians(m.phi_basal_deg)
    if mode != "paper":
        return earth_pressure_coefficients(mode, phi_i, phi_b, 0.0)
    steep = np.abs(bed.theta) > phi_i
    if steep.any():
        j = int(np.argmax(np.abs(bed.theta)))
        raise ConfigError(
            f"numerics.earth_pressure: 'paper' (eqs 8-9 with the local slope) has no real k where the path is "
            f"steeper than material.phi_internal_deg = {m.phi_internal_deg:g} (max {math.degrees(abs(bed.theta[j])):.4g}"
            f" deg at s = {bed.s[j]:.4g} m); use 'savage_hutter' or 'one'")
    ka, kp = np.empty(bed.s.size), np.empty(bed.s.size)
    cache: dict[float, tuple] = {}
    for i, th in enumerate(bed.theta):
        if th not in cache:
            cache[th] = earth_pressure_coefficients("paper", phi_i, phi_b, abs(th))
        ka[i], kp[i] = cache[th]
    return ka, kp


def path_coefficients(cfg, setup: PathSetup):
    """(A, B, source): scalars, or arrays over the stations for ``geometry.path.ab_slope: local``."""
    dep, pc = cfg.deposition, cfg.geometry.path
    if dep.ab_source != "computed":
        if pc.ab_slope == "local":
            raise ConfigError(f"geometry.path.ab_slope: 'local' needs deposition.ab_source 'computed' (a coefficient "
                              f"table to read at each slope; got ab_source {dep.ab_source!r})")
        return coefficients(cfg)
    a = setup.H0 / setup.L0
    if pc.ab_slope == "release":
        th = math.degrees(setup.theta_release)
        try:
            A, B = interpolate_ab(dep.coefficients, a, th)
        except ConfigError as exc:
            raise ConfigError(f"geometry.path.ab_slope: 'release' reads A, B at the release zone's a = {a:.4g}, "
                              f"theta = {th:.4g} deg: {exc}") from None
        return float(A), float(B), f"computed ({dep.coefficients}, release zone a = {a:.4g}, theta = {th:.4g} deg)"
    table = pd.read_csv(dep.coefficients)
    lo, hi = float(table.theta_deg.min()), float(table.theta_deg.max())
    th = np.clip(np.degrees(setup.bed.theta), lo, hi)
    nodes = np.unique(np.round(th, 2))
    ab = np.array([interpolate_ab(table, a, float(t)) for t in nodes])
    A = np.interp(th, nodes, ab[:, 0])
    B = np.interp(th, nodes, ab[:, 1])
    return A, B, (f"computed ({dep.coefficients}, a = {a:.4g}, local slope clamped to the table's "
                  f"[{lo:g}, {hi:g}] deg)")


class _Runner:
    """Everything the x∞ iteration needs to start one run."""

    def __init__(self, cfg, setup, progress):
        self.cfg, self.setup, self.progress = cfg, setup, progress
        self.ka, self.kp = earth_pressure_along(cfg, setup.bed)

    def run(self, deposition, A=0.0, B=0.0, x_inf=float("nan"), label=""):
        phys = Physics(0.0, 0.0, deposition, float(np.mean(A)), float(np.mean(B)), x_inf)
        tab = bed_table(self.setup, self.ka, self.kp, A, B)
        return simulate_path(self.cfg, self.setup, phys, tab, label, self.progress), phys


def run_path(cfg, deposition: bool = True, bed: Bed | None = None) -> xr.Dataset:
    """The path counterpart of ``api.run_da`` (called by it when ``geometry.path`` is set)."""
    setup = path_setup(cfg, bed)
    runner = _Runner(cfg, setup, Progress(cfg.output.progress_every_s))
    label = f"{cfg.case} ({'deposition' if deposition else 'no deposition'})"

    def check(rec, ds_fn):
        if rec.status not in (RUNNING, AT_REST):
            raise DARunError(rec.message, ds_fn(rec))
        if rec.status == RUNNING:
            LOG.warning("DA %s: %s — flow time undefined; raise numerics.t_end", cfg.case, rec.message)
        lift = int(rec.diag[D_LIFT])
        if lift:
            LOG.warning("DA %s: the normal stress g cos(theta) + kappa u^2 was negative (clipped at 0: free flight "
                        "not modelled) for %d particle-stages; largest deficit %.3g g at s = %.4g m", cfg.case,
                        lift, rec.diag[D_DEFICIT], rec.diag[D_WHERE])

    if not deposition:
        rec, phys = runner.run(False, label=label)
        check(rec, lambda r: to_path_dataset(cfg, setup, r, deposition=False))
        return to_path_dataset(cfg, setup, rec, deposition=False)
    A, B, source = path_coefficients(cfg, setup)
    dep = cfg.deposition
    LOG.info("DA %s: A = %.5g, B = %.5g from %s, x_inf mode %s", cfg.case, float(np.mean(A)), float(np.mean(B)),
             source, dep.x_inf_mode)

    def run_with(x_inf):
        rec, _ = runner.run(True, A, B, x_inf, f"{label}, x_inf = s {x_inf + setup.origin:.4f} m")
        check(rec, lambda r: to_path_dataset(cfg, setup, r, deposition=True, ab_source=source))
        return rec

    def run_without():
        rec0, _ = runner.run(False, label=f"{cfg.case} (no deposition, for x_inf)")
        check(rec0, lambda r: to_path_dataset(cfg, setup, r, deposition=False))
        return rec0

    xinf = find_x_inf(dep, run_with, run_without, setup.xi_gate, cfg.case, setup.origin)
    return to_path_dataset(cfg, setup, xinf.record, deposition=True, ab_source=source, xinf=xinf)


def runout_measures(bed: Bed, s_top: float, s_gate: float, s_front: float) -> dict:
    """Along-bed and horizontal runout, drop H, reach L and travel angle atan(H/L) (degrees)."""
    x_top, x_gate, x_f = bed.at("x", [s_top, s_gate, s_front])
    z_top, z_f = bed.at("z", [s_top, s_front])
    H, Lh = z_top - z_f, x_f - x_top
    return {"runout_along_bed": s_front - s_gate, "runout_horizontal": x_f - x_gate, "drop": H, "reach": Lh,
            "travel_angle_deg": math.degrees(math.atan2(H, Lh)) if math.isfinite(s_front) else float("nan"),
            "x_front": x_f, "z_front": z_f}


def to_path_dataset(cfg, setup: PathSetup, rec, *, deposition: bool, ab_source: str = "", xinf=None) -> xr.Dataset:
    """The CF dataset of one path run: the DA contract's time series, fields on the station grid
    s (with x, z), particle states, and the along-path envelopes and runout measures."""
    bed = setup.bed
    o = setup.origin
    time = np.asarray(rec.time, dtype=float)
    front_s = np.asarray(rec.front, dtype=float) + o
    dxg = float(rec.x_edges[1] - rec.x_edges[0])   # the grid the run used (solver.grid_spacing)
    flow = np.asarray(rec.flow_depth)
    depo = np.asarray(rec.deposit_depth)
    ng = flow.shape[1]
    s_grid = (np.arange(ng) + 0.5) * dxg + o
    vol_flow = np.asarray([np.sum(v) for v in rec.volume])
    vol_dep = np.asarray(rec.deposited_volume, dtype=float)
    t_c = characteristic_time(setup.H0, setup.theta_release)
    t_f = flow_time(time, front_s, cfg.output.flow_time_tolerance) if rec.status == AT_REST else float("nan")
    final_s = float(front_s[-1]) if front_s.size else float("nan")
    meas = runout_measures(bed, setup.s_start, setup.s_end, final_s)
    env = rec.envelopes
    arrival = np.where(np.isfinite(env[E_T]), env[E_T], np.nan)
    final_total = flow[-1] + depo[-1]
    if xinf is not None:
        x_inf, mode = xinf.x_inf + o, xinf.mode
    else:
        x_inf, mode = final_s, "final front of this run (no deposition)"
    vunit = "m3" if bed.has_width else "m2"
    vname = "" if bed.has_width else " per unit width"
    xs, zs = bed.at("x", s_grid), bed.at("z", s_grid)
    ds = xr.Dataset(
        data_vars={
            "front_position": var(front_s, ("time",), "m", "front station along the bed from the first path point",
                                  definition=FRONT_DEFINITION),
            "runout": var(front_s - setup.s_end, ("time",), "m", "runout along the bed from the release end"),
            "flow_depth": var(flow, ("time", "s"), "m", "flowing depth h (bed-normal, eq 20 / width)",
                              coordinates="x z"),
            "deposit_depth": var(depo, ("time", "s"), "m", "deposited depth h_D (bed-normal)", coordinates="x z"),
            "max_flow_depth": var(env[E_H], ("s",), "m", "maximum flowing depth over the run (envelope)",
                                  coordinates="x z"),
            "max_speed": var(env[E_U], ("s",), "m s-1", "maximum depth-averaged speed over the run (envelope)",
                             coordinates="x z"),
            "arrival_time": var(arrival, ("s",), "s", "arrival time of the flow", definition=ARRIVAL_DEFINITION,
                                coordinates="x z"),
            "final_deposit_depth": var(final_total, ("s",), "m",
                                       "final deposit depth: deposited plus flowing depth at the end (at rest)",
                                       coordinates="x z"),
            "bed_slope": var(np.degrees(bed.at("theta", s_grid)), ("s",), "degree", "bed slope angle theta(s)",
                             coordinates="x z"),
            "bed_curvature": var(bed.at("kappa", s_grid), ("s",), "m-1",
                                 "bed curvature kappa(s) (> 0 concave, slope easing)", coordinates="x z"),
            "width": var(bed.at("width", s_grid), ("s",), "m", "channel width b(s) (1 m: per unit width)",
                         coordinates="x z"),
            "x_particle": var(np.asarray(rec.x) + o, ("time", "particle"), "m", "particle station along the bed"),
            "final_runout": var(meas["runout_along_bed"], (), "m", "final runout along the bed from the release end"),
            "final_runout_norm": var(meas["runout_along_bed"] / setup.L0, (), "1", "final runout along the bed / L0"),
            "runout_horizontal": var(meas["runout_horizontal"], (), "m",
                                     "final runout, horizontal distance from the release end"),
            "travel_angle": var(meas["travel_angle_deg"], (), "degree",
                                "travel (reach) angle atan(H/L), release top to the final front"),
            "drop_height": var(meas["drop"], (), "m", "H: elevation drop from the release top to the final front"),
            "reach_length": var(meas["reach"], (), "m", "L: horizontal distance from the release top to the front"),
            **run_variables(rec, vol_flow, vol_dep, t_f, t_c, vunit, vname, " along the bed"),
        },
        coords={
            "time": var(time, ("time",), "s", "time since release"),
            "particle": var(np.arange(np.asarray(rec.x).shape[1]), ("particle",), "1", "particle id"),
            "s": var(s_grid, ("s",), "m", "station along the smoothed bed from the first path point (cell centre)",
                     axis="X"),
            "x": var(xs, ("s",), "m", "horizontal distance of the station from the first path point"),
            "z": var(zs, ("s",), "m", "bed elevation at the station", positive="up"),
        },
    )
    ds = add_x_inf_history(ds, xinf, mode, o, "x_inf (station)")
    pc = cfg.geometry.path
    ds.attrs.update({
        "path_file": pc.file, "path_smoothing_length": bed.sigma, "path_ds": bed.ds, "path_length": bed.length,
        "has_width": int(bed.has_width), "centripetal": int(pc.centripetal), "ab_slope": pc.ab_slope,
        "release_start": setup.s_start, "release_end": setup.s_end, "origin": o,
        "theta_deg": math.degrees(setup.theta_release), "L0": setup.L0, "H0": setup.H0, "a": setup.H0 / setup.L0,
        "front_definition": FRONT_DEFINITION, "arrival_definition": ARRIVAL_DEFINITION,
        "A": float(np.mean(rec.A)) if deposition else float("nan"), "B": float(np.mean(rec.B)) if deposition else
        float("nan"), "p0": momentum_scale(setup.H0, setup.theta_release),
        **run_attributes(cfg, rec, deposition=deposition, dxg=dxg, x_inf=x_inf, xinf=xinf, mode=mode,
                         ab_source=ab_source, t_c=t_c),
        "lift_off_count": int(rec.diag[D_LIFT]), "lift_off_max_deficit_g": float(rec.diag[D_DEFICIT]),
        "lift_off_station": float(rec.diag[D_WHERE]) if rec.diag[D_LIFT] else float("nan"),
        "lift_off_note": "particle-stages where g cos(theta) + kappa u^2 < 0 (convex break): the normal stress and "
                         "the friction were set to 0 there; free flight is not modelled",
        "final_front_x": meas["x_front"], "final_front_z": meas["z_front"],
    })
    return provenance(ds, case=cfg.case, config_yaml=to_yaml(cfg))


def path_summary_line(ds: xr.Dataset) -> str:
    lift = int(ds.attrs.get("lift_off_count", 0))
    return (f"{ds.attrs['case']} on path {ds.attrs['path_file']}: front at s = {float(ds.front_position[-1]):.4g} m "
            f"(x = {ds.attrs['final_front_x']:.4g} m, z = {ds.attrs['final_front_z']:.4g} m); runout "
            f"{float(ds.final_runout):.4g} m along the bed, {float(ds.runout_horizontal):.4g} m horizontal from the "
            f"release end; travel angle atan(H/L) = {float(ds.travel_angle):.3f} deg (H = {float(ds.drop_height):.4g} m,"
            f" L = {float(ds.reach_length):.4g} m)"
            + (f"; WARNING normal stress clipped at 0 (convex break, free flight not modelled) {lift} times" if lift else ""))
