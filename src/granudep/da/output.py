"""The DA run as a CF-style ``xarray.Dataset`` (docs/data-contract.md, DA run)."""
from __future__ import annotations

import math

import numpy as np
import xarray as xr

from ..cases import characteristic_time
from ..config import to_yaml
from ..front import FRONT_MEASURE_DOC, flow_time, front_measures
from ..io import provenance, var
from .step import AT_REST

FRONT_DEFINITION = ("down-slope edge of the contiguous run of grid cells, from the deepest cell, whose total "
                    "depth h + h_D (SPH depth eq 20 on the grid plus deposit) is >= front_depth_threshold "
                    "(granudep.front.front_from_profile)")


def run_variables(rec, vol_flow, vol_dep, t_f: float, t_c: float, vunit: str = "m2", vname: str = " per unit width",
                  along: str = "") -> dict:
    """The data variables every DA run file carries, a column or a path (docs/data-contract.md, DA run):
    volumes, particle states, the time-step history, the flow time and the volume balance."""
    v0 = vol_flow[0]
    return {
        "flowing_volume": var(vol_flow, ("time",), vunit, f"flowing volume{vname}"),
        "deposited_volume": var(vol_dep, ("time",), vunit, f"deposited volume{vname}"),
        "u": var(np.asarray(rec.u), ("time", "particle"), "m s-1", f"particle depth-averaged velocity{along}"),
        "h": var(np.asarray(rec.h), ("time", "particle"), "m", "flowing depth at the particle (eq 20)"),
        "volume": var(np.asarray(rec.volume), ("time", "particle"), vunit, f"particle volume{vname}"),
        "smoothing_length": var(np.asarray(rec.smoothing_length), ("time",), "m", "smoothing length L_s (eq 25)"),
        "time_step": var(np.asarray(rec.time_step), ("time",), "s", "last time step before the output (eq 32)"),
        "steps": var(np.asarray(rec.steps, dtype=np.int64), ("time",), "1", "time steps taken"),
        "flow_time": var(t_f, (), "s", "time when the front comes to rest (granudep.front.flow_time)"),
        "flow_time_norm": var(t_f / t_c, (), "1", "flow time / t_c, t_c = sqrt(H0/(g cos theta))"),
        "volume_error": var(float(np.max(np.abs(vol_flow + vol_dep - v0)) / v0), (), "1",
                            "max |flowing + deposited - initial| / initial volume"),
    }


def run_attributes(cfg, rec, *, deposition: bool, dxg: float, x_inf: float, xinf=None, mode: str = "",
                   ab_source: str = "", t_c: float) -> dict:
    """The attributes every DA run file carries: the run's x∞ and how it was found, the numerics,
    the material and the run's status."""
    num = cfg.numerics
    return {
        "deposition": int(deposition), "front_depth_threshold": cfg.front_threshold,
        "flow_time_tolerance": cfg.output.flow_time_tolerance,
        "x_inf": float(x_inf), "x_inf_mode": mode,
        "x_inf_iterations": int(xinf.iterations) if xinf is not None else 0,
        "x_inf_residual": float(xinf.residual) if xinf is not None else 0.0,
        "x_inf_warning": getattr(xinf, "warning", "") if xinf is not None else "",
        "ab_source": ab_source, "coefficient_units": cfg.deposition.coefficient_units, "t_c": t_c,
        "earth_pressure": num.earth_pressure, "earth_pressure_switch": num.earth_pressure_switch,
        "smoothing_weight": num.smoothing_weight,
        "phi_internal_deg": cfg.material.phi_internal_deg, "phi_basal_deg": cfg.material.phi_basal_deg,
        "d": cfg.material.d, "n_particles": num.n_particles, "smoothing_B": num.smoothing_B, "cfl": num.cfl,
        "xsph_delta": num.xsph_delta, "kernel_support": num.kernel_support, "dx_grid": dxg,
        "n_steps": int(rec.n_steps), "at_rest": int(rec.status == AT_REST), "status": rec.message,
    }


def add_x_inf_history(ds: xr.Dataset, xinf, mode: str, origin: float = 0.0, what: str = "x_inf") -> xr.Dataset:
    """The x∞ iteration (self-consistent mode): every x∞ tried and the final front of its run."""
    if xinf is None or not mode.startswith("self-consistent"):
        return ds
    ds["x_inf_history"] = var(np.asarray(xinf.history_x) + origin, ("x_inf_iteration",), "m", f"{what} tried")
    ds["x_front_history"] = var(np.asarray(xinf.history_front) + origin, ("x_inf_iteration",), "m",
                                "final front of the run with that x_inf")
    return ds.assign_coords(x_inf_iteration=var(np.arange(len(xinf.history_x)), ("x_inf_iteration",), "1",
                                                "x_inf iteration"))


def to_dataset(cfg, rec, *, deposition: bool, physics, A=float("nan"), B=float("nan"), ab_source="",
               xinf=None) -> xr.Dataset:
    """Assemble the dataset of one constant-slope run (complete or stopped early)."""
    g = cfg.geometry
    time = np.asarray(rec.time, dtype=float)
    front = np.asarray(rec.front, dtype=float)
    dxg = float(rec.x_edges[1] - rec.x_edges[0])   # the grid the run used (solver.grid_spacing)
    flow = np.asarray(rec.flow_depth)
    depo = np.asarray(rec.deposit_depth)
    total = flow + depo
    used = np.flatnonzero((total > 0.0).any(axis=0))
    ncell = min(total.shape[1], (used[-1] + 11) if used.size else total.shape[1])
    flow, depo = flow[:, :ncell], depo[:, :ncell]
    x_grid = (np.arange(ncell) + 0.5) * dxg
    vol_flow = np.asarray([np.sum(v) for v in rec.volume])
    vol_dep = np.asarray([np.sum(d) * dxg for d in rec.deposit_depth])
    t_c = characteristic_time(g.H0, cfg.theta)
    t_f = flow_time(time, front, cfg.output.flow_time_tolerance) if rec.status == AT_REST else float("nan")
    final = float(front[-1]) - g.L0 if front.size else float("nan")
    if xinf is not None:
        x_inf, mode = xinf.x_inf, xinf.mode
    else:
        x_inf, mode = float(front[-1]), "final front of this run (no deposition)"
    # the robust front measures (granudep.front.front_measures) of the total depth h + h_D on the grid,
    # per output time, exactly as the 2D run files carry them (so 2D and DA fronts are read alike)
    x_edges = np.arange(ncell + 1) * dxg
    d = float(cfg.material.d)
    measures = {k: np.full(time.size, np.nan) for k in FRONT_MEASURE_DOC}
    for i in range(time.size):
        for k, v in front_measures(x_edges, flow[i] + depo[i], d).items():
            measures[k][i] = v
    ds = xr.Dataset(
        data_vars={
            "front_position": var(front, ("time",), "m", "front position from the back wall (x = 0)",
                                  definition=FRONT_DEFINITION),
            "runout": var(front - g.L0, ("time",), "m", "runout from the gate, x_front - L0"),
            "flow_depth": var(flow, ("time", "x_grid"), "m", "flowing depth h (eq 20 on the grid)"),
            "deposit_depth": var(depo, ("time", "x_grid"), "m", "deposited depth h_D"),
            "x": var(np.asarray(rec.x), ("time", "particle"), "m", "particle position along the slope"),
            "final_runout": var(final, (), "m", "final runout from the gate, x_front - L0"),
            "final_runout_norm": var(final / g.L0, (), "1", "final runout / L0"),
            **run_variables(rec, vol_flow, vol_dep, t_f, t_c),
        },
        coords={
            "time": var(time, ("time",), "s", "time since release"),
            "particle": var(np.arange(np.asarray(rec.x).shape[1]), ("particle",), "1", "particle id"),
            "x_grid": var(x_grid, ("x_grid",), "m", "cell centre along the slope from the back wall"),
        },
    )
    for k, doc in FRONT_MEASURE_DOC.items():
        ds[k] = var(measures[k], ("time",), "m", f"front from the back wall, {doc} (profile h + h_D on the grid)")
        last = float(measures[k][-1]) if time.size else float("nan")
        ds[f"final_{k}"] = var(last, (), "m", f"final front from the back wall, {doc}")
        ds[f"final_runout_norm_{k.removeprefix('front_')}"] = var((last - g.L0) / g.L0, (), "1",
                                                               f"final runout / L0 with the front {k}")
    ds = add_x_inf_history(ds, xinf, mode)
    ds.attrs.update({
        "theta_deg": g.theta_deg, "L0": g.L0, "H0": g.H0, "a": g.H0 / g.L0, "front_definition": FRONT_DEFINITION,
        "A": float(A), "B": float(B),
        # where A[x] + B = 0: beyond it (hu)_C <= 0 and eq 34 deposits nothing (alpha = 0); a front that
        # escapes past it runs out freely, which makes F(x_inf) jump (docs/paper-notes.md, "x_inf fall-back")
        "x_norm_zero_critical": float(-B / A) if deposition and A != 0 and math.isfinite(A) else float("nan"),
        "p0": cfg.p0, "k_active": physics.k_active, "k_passive": physics.k_passive,
        **run_attributes(cfg, rec, deposition=deposition, dxg=dxg, x_inf=x_inf, xinf=xinf, mode=mode,
                         ab_source=ab_source, t_c=t_c),
    })
    return provenance(ds, case=cfg.case, config_yaml=to_yaml(cfg),
                      title=f"granudep 1D depth-averaged SPH run {cfg.case} "
                            f"({'with' if deposition else 'without'} deposition)")


def default_path(cfg, deposition: bool) -> str:
    return f"results/da/{cfg.case}_{'deposition' if deposition else 'nodeposition'}.nc"


def summary_line(ds: xr.Dataset) -> str:
    """The CLI's closing line: final runout and flow time with the front definition."""
    tf = float(ds.flow_time)
    tf_txt = f"{tf:.3f} s (t/t_c = {float(ds.flow_time_norm):.3f})" if math.isfinite(tf) else "n/a (not at rest)"
    return (f"{ds.attrs['case']} ({'with' if ds.attrs['deposition'] else 'without'} deposition): "
            f"final runout dL/L0 = {float(ds.final_runout_norm):.4f} (dL = {float(ds.final_runout):.4f} m, "
            f"N = {int(ds.attrs.get('n_particles', ds.sizes.get('particle', 0)))}), "
            f"flow time {tf_txt}; front = last cell with h + h_D >= {ds.attrs['front_depth_threshold'] * 1e3:.2f} mm, "
            f"rest = front moves < {ds.attrs['flow_time_tolerance'] * 1e3:.1f} mm")
