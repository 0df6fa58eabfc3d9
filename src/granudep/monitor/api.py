"""Monitoring sections of a 2D ISPH run (Section 2.2, Section 3, Appendix).

``monitor(run)`` turns a run file (dims time × particle) into section time series (dims
section × time): eq 15 velocity, eq 16 F/D interface, eq 17 depths, hu. ``monitor_wm(run)`` repeats
the analysis for several section widths (Appendix, Figs A1–A2). Definitions: ``sections.py``.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import xarray as xr

from .. import cases
from ..config import ConfigError, flat_config, to_yaml
from ..io import open_dataset, provenance, var
from ..progress import LOG, Progress
from .config import MonitorConfig
from .sections import (SOURCE_MEANINGS, depths_from_sums, divr_deposited, section_centres,
                       section_reduce)

REQUIRED_VARS = ("x", "y", "u", "v")
REQUIRED_ATTRS = ("theta_deg", "L0", "H0", "dx", "smoothing_length", "particle_volume")


def _load(run) -> xr.Dataset:
    if isinstance(run, xr.Dataset):
        if "time" in run.variables and np.issubdtype(run["time"].dtype, np.datetime64):
            raise ConfigError("run.time: decoded as dates; open the run with granudep.load(path) (or "
                              "xarray.open_dataset(path, decode_times=False)): times are seconds since release")
        return run
    path = Path(run)
    if not path.is_file():
        raise ConfigError(f"run: file not found: {path}")
    return open_dataset(path, what="run")


def _config(overrides: dict) -> MonitorConfig:
    if "wm_factors" in overrides and overrides["wm_factors"] is not None:
        overrides = {**overrides, "wm_factors": list(overrides["wm_factors"])}
    return flat_config(MonitorConfig, overrides=overrides, prefix="monitor")


def _geometry(run: xr.Dataset, cfg: MonitorConfig) -> dict:
    """Check the run against the data contract and collect the numbers the analysis needs."""
    for name in REQUIRED_VARS:
        if name not in run.variables:
            raise ConfigError(f"run.{name}: required variable is missing (need {', '.join(REQUIRED_VARS)})")
        if run[name].dims != ("time", "particle"):
            raise ConfigError(f"run.{name}: must have dims (time, particle) (got {run[name].dims})")
    for name in REQUIRED_ATTRS:
        if name not in run.attrs:
            raise ConfigError(f"run.attrs.{name}: required attribute is missing")
        value = float(run.attrs[name])
        if name != "theta_deg" and not value > 0:
            raise ConfigError(f"run.attrs.{name}: must be > 0 (got {value!r})")
    g = {k: float(run.attrs[k]) for k in REQUIRED_ATTRS}
    if not 0.0 <= g["theta_deg"] < 90.0:
        raise ConfigError(f"run.attrs.theta_deg: must be >= 0 and < 90 (got {g['theta_deg']!r})")
    front_var = "final_front_position" if cfg.x_inf_front == "position" else f"final_front_{cfg.x_inf_front}"
    if cfg.x_inf is not None:
        x_inf = float(cfg.x_inf)
    elif front_var in run.variables:
        x_inf = float(run[front_var])
    else:
        raise ConfigError(f"run.{front_var}: missing (monitor.x_inf_front: {cfg.x_inf_front}); give monitor.x_inf "
                          "(m from the back wall) or another x_inf_front")
    if not (math.isfinite(x_inf) and x_inf > g["L0"]):
        raise ConfigError(f"x_inf: must be > L0 = {g['L0']} m (got {x_inf!r}); the sections span [L0, x_inf]")
    bed_end = float(run.attrs["domain_length"]) if "domain_length" in run.attrs else \
        float(np.nanmax(np.asarray(run["x"].values, float)))
    if cfg.x_inf is not None and x_inf > bed_end:
        raise ConfigError(f"x_inf: must be <= {bed_end:.6g} m, the end of the run's bed"
                          f"{'' if 'domain_length' in run.attrs else ' (its farthest particle)'}; the sections "
                          f"span [L0, x_inf] (got {x_inf!r})")
    time_to_rest = float(run["time_to_rest"]) if "time_to_rest" in run.variables else math.nan
    status = str(run.attrs.get("status", ""))
    # the deposition record is complete once the run rested, or once every particle is deposited
    # by our own criterion (|v| < critical_speed) in the last frame
    last_speed = np.hypot(np.asarray(run["u"].values[-1], float), np.asarray(run["v"].values[-1], float))
    all_deposited = bool(np.all(last_speed[np.isfinite(last_speed)] < cfg.critical_speed))
    complete = (math.isfinite(time_to_rest) or all_deposited) and not status.lower().startswith("failed")
    if not complete and cfg.x_inf is None:
        LOG.warning("run %s did not reach rest (status: %s; time_to_rest = %s): x_inf = %s = %.4f m is not "
                    "the final runout and late onsets are cut off", run.attrs.get("case", "?"), status or "unknown",
                    time_to_rest, front_var, x_inf)
    theta = math.radians(g["theta_deg"])
    g.update(time_to_rest=time_to_rest, complete=complete, x_inf=x_inf, theta=theta, a=g["H0"] / g["L0"],
             t_c=cases.characteristic_time(g["H0"], theta), p0=cases.momentum_scale(g["H0"], theta))
    return g


def _analyse(run: xr.Dataset, cfg: MonitorConfig, g: dict, width_factors) -> dict:
    """Section quantities for each width factor: {w: {name: array (section, time)}}."""
    n_sec = cfg.n_sections
    centres = section_centres(g["L0"], g["x_inf"], n_sec)
    spacing = float(centres[1] - centres[0])
    X = np.asarray(run["x"].values, dtype=float)
    Y = np.asarray(run["y"].values, dtype=float)
    U = np.asarray(run["u"].values, dtype=float)
    V = np.asarray(run["v"].values, dtype=float)
    if "free_surface" in run.variables:
        FS = np.asarray(run["free_surface"].values) != 0
    else:
        LOG.warning("run has no free_surface flag: interface particles are limited only by the "
                    "highest flowing particle of each section")
        FS = np.zeros(X.shape, dtype=bool)
    nt = X.shape[0]
    out = {w: {} for w in width_factors}
    progress = Progress(10.0)
    for it in range(nt):
        speed = np.hypot(U[it], V[it])
        dep = speed < cfg.critical_speed
        divr = divr_deposited(X[it], Y[it], dep, g["particle_volume"], g["smoothing_length"], cfg.bed_mirror)
        cand = dep & (divr < cfg.divergence_threshold) & ~FS[it]
        for w in width_factors:
            sums = section_reduce(X[it], Y[it], U[it], dep, cand, float(centres[0]), spacing,
                                  0.5 * w * g["dx"], n_sec)
            for name, arr in depths_from_sums(sums, g["dx"]).items():
                out[w].setdefault(name, np.empty((n_sec, nt), dtype=arr.dtype))[:, it] = arr
        progress(lambda: f"monitor: frame {it + 1}/{nt}", final=it == nt - 1)
    for w in width_factors:
        q = out[w]
        q["momentum"] = q["flow_depth"] * q["velocity"]
        q["momentum_integrated"] = q["total_depth"] * q["velocity"]
    return out


_VARS = {  # name: (units, long_name)
    "velocity": ("m s-1", "depth-averaged velocity u: mean v_x of the section's particles (eq 15)"),
    "flowing_velocity": ("m s-1", "mean v_x of the section's flowing particles (|v| >= critical speed)"),
    "free_surface_height": ("m", "free surface Y_F: highest particle centre + dx/2 (bed-normal)"),
    "interface_height": ("m", "F/D interface Y_F/D: mean interface-particle centre + dx/2 (bed-normal)"),
    "total_depth": ("m", "total depth h_T = Y_F - Y_bed (bed-normal, Y_bed = 0)"),
    "flow_depth": ("m", "flowing depth h = Y_F - Y_F/D (eq 17, bed-normal)"),
    "deposit_depth": ("m", "deposit depth h_D = Y_F/D - Y_bed (eq 17, bed-normal)"),
    "momentum": ("m2 s-1", "depth-averaged momentum hu = flow_depth * velocity"),
    "momentum_norm": ("1", "normalised depth-averaged momentum hu/p0"),
    "momentum_integrated": ("m2 s-1", "depth-integrated momentum h_T * u (= integral of v_x over the depth)"),
    "interface_source": ("1", "how interface_height was found: " + SOURCE_MEANINGS),
    "n_particles": ("1", "number of particles in the section (N_M of eq 15)"),
    "n_deposited": ("1", "number of deposited particles in the section"),
    "n_interface": ("1", "number of F/D interface particles in the section (eq 16)"),
}


def _base_dataset(run: xr.Dataset, cfg: MonitorConfig, g: dict, width: float) -> xr.Dataset:
    centres = section_centres(g["L0"], g["x_inf"], cfg.n_sections)
    time = np.asarray(run["time"].values, dtype=float)
    coords = {
        "section": var(np.arange(cfg.n_sections, dtype=np.int32), ("section",), "1",
                       "monitoring section index k (x = L0 + k (x_inf - L0)/(n - 1))"),
        "time": var(time, ("time",), "s", "time since release"),
        "x": var(centres, ("section",), "m", "section centre, down-slope distance from the back wall"),
        "x_norm": var(cases.normalised_position(centres, g["L0"], g["x_inf"]), ("section",), "1",
                      "normalised section position [x] = (x - L0)/(x_inf - L0) (eq 35)"),
        "t_s": var(time / g["t_c"], ("time",), "1", "normalised time t_s = t/t_c, t_c = sqrt(H0/(g cos theta))"),
    }
    ds = xr.Dataset(coords=coords)
    for k, v in run.attrs.items():
        if isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool):
            ds.attrs[k] = v
    ds.attrs.update(theta_deg=g["theta_deg"], L0=g["L0"], H0=g["H0"], a=g["a"], dx=g["dx"],
                    smoothing_length=g["smoothing_length"], particle_volume=g["particle_volume"],
                    x_inf=g["x_inf"], t_c=g["t_c"], p0=g["p0"], n_sections=cfg.n_sections,
                    width_factor=float(width), section_width=float(width) * g["dx"],
                    critical_speed=cfg.critical_speed, divergence_threshold=cfg.divergence_threshold,
                    y_bed=0.0, depth_frame="slope-aligned: y bed-normal, no 1/cos(theta) in eq 17")
    if "title" in run.attrs:
        ds.attrs["source_title"] = str(run.attrs["title"])
    ds.attrs["run_status"] = str(run.attrs.get("status", "unknown"))
    ds.attrs["run_time_to_rest"] = g["time_to_rest"]
    ds.attrs["run_complete"] = int(g["complete"])
    return ds


def _case(run: xr.Dataset) -> str:
    return str(run.attrs.get("case", "run"))


def monitor(run, **overrides) -> xr.Dataset:
    """Section time series (section × time) of a 2D ISPH run (Dataset or path); overrides are
    MonitorConfig keys (e.g. ``width_factor=3``)."""
    cfg = _config(overrides)
    run = _load(run)
    g = _geometry(run, cfg)
    w = cfg.width_factor
    q = _analyse(run, cfg, g, [w])[w]
    q["momentum_norm"] = q["momentum"] / g["p0"]
    ds = _base_dataset(run, cfg, g, w)
    for name, (units, long_name) in _VARS.items():
        ds[name] = var(q[name], ("section", "time"), units, long_name)
    provenance(ds, case=_case(run), config_yaml=to_yaml(cfg),
               title=f"granudep monitoring sections (eqs 15-17) of 2D run {_case(run)}")
    return ds


def deceleration_mask(momentum: np.ndarray, stop_fraction: float) -> np.ndarray:
    """Per section (rows): True from the peak of ``momentum`` to the first later sample where it
    falls below ``stop_fraction`` × peak (exclusive); all False for an all-NaN or non-positive row."""
    mask = np.zeros(momentum.shape, dtype=bool)
    for k in range(momentum.shape[0]):
        row = momentum[k]
        if not np.isfinite(row).any() or not np.nanmax(row) > 0:
            continue
        i0 = int(np.nanargmax(row))
        peak = row[i0]
        after = np.flatnonzero(~(row[i0:] >= stop_fraction * peak))  # below threshold or NaN
        i1 = row.size if after.size == 0 else i0 + int(after[0])
        mask[k, i0:i1] = True
    return mask


def monitor_wm(run, **overrides) -> xr.Dataset:
    """Appendix: hu/p0 for section widths ``wm_factors``·dx and the RMS deviation of each width from
    ``wm_reference``·dx per section, over the deceleration window of the reference width."""
    cfg = _config(overrides)
    run = _load(run)
    g = _geometry(run, cfg)
    widths = list(dict.fromkeys(cfg.wm_factors))
    q = _analyse(run, cfg, g, widths)
    ds = _base_dataset(run, cfg, g, cfg.wm_reference)
    mom = np.stack([q[w]["momentum"] / g["p0"] for w in widths])
    ref = mom[widths.index(cfg.wm_reference)]
    mask = deceleration_mask(ref, cfg.wm_stop_fraction)
    diff = np.where(mask[None] & np.isfinite(mom) & np.isfinite(ref)[None], mom - ref[None], np.nan)
    n = np.isfinite(diff).sum(axis=2)
    with np.errstate(invalid="ignore", divide="ignore"):
        rms = np.sqrt(np.nansum(diff ** 2, axis=2) / np.where(n > 0, n, 1))
    rms = np.where(n > 0, rms, np.nan)
    ds = ds.assign_coords(width_factor=var(np.asarray(widths, dtype=float), ("width_factor",), "1",
                                           "section width W_M in units of the particle spacing dx"))
    ds["momentum_norm"] = var(mom, ("width_factor", "section", "time"), "1",
                              "normalised depth-averaged momentum hu/p0 for each section width")
    ds["deceleration"] = var(mask.astype(np.int8), ("section", "time"), "1",
                             "1 inside the deceleration window (peak of reference hu until it falls below "
                             f"{cfg.wm_stop_fraction} x peak)")
    ds["rms_deviation"] = var(rms, ("width_factor", "section"), "1",
                              f"RMS deviation of hu/p0 from W_M = {cfg.wm_reference} dx over the deceleration window")
    ds["n_rms"] = var(n.astype(np.int32), ("width_factor", "section"), "1",
                      "number of samples in the RMS deviation")
    ds.attrs["wm_reference"] = cfg.wm_reference
    provenance(ds, case=_case(run), config_yaml=to_yaml(cfg),
               title=f"granudep section-width sensitivity (Appendix) of 2D run {_case(run)}")
    return ds


def warmup() -> None:
    """Compile (and cache) the monitor kernels once, before parallel jobs start."""
    x = np.array([0.0, 0.001, 0.0]) + 0.0005
    y = np.array([0.0005, 0.0005, 0.0015])
    dep = np.array([True, True, False])
    divr_deposited(x, y, dep, 1e-6, 0.0013, True)
    section_reduce(x, y, np.zeros(3), dep, dep, 0.0, 0.001, 0.001, 2)
