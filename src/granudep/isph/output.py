"""NetCDF dataset of a 2D ISPH run (docs/data-contract.md, 2D ISPH run): particle snapshots + front
and energy."""
from __future__ import annotations

import math

import numpy as np
import xarray as xr

from ..config import to_yaml
from ..io import provenance, var
from ..front import FRONT_MEASURE_DOC
from .analysis import moving_share, time_to_rest_mass_share
from .config import IsphConfig


def build_dataset(cfg: IsphConfig, solver, snaps, status: str, time_to_rest: float) -> xr.Dataset:
    t = np.asarray(snaps.time, dtype=float)
    nf = getattr(solver, "n0", solver.nf)
    out_t = np.asarray(getattr(solver, "outflow_time", np.full(nf, np.nan)), dtype=float)
    f = snaps.fields

    def stack(name, dtype):
        if not f[name]:
            return np.zeros((0, nf), dtype)
        return np.stack(f[name]).astype(dtype)

    out = cfg.output
    t_rest99 = time_to_rest_mass_share(t, stack("u", np.float64), stack("v", np.float64), 0.99, out.rest_speed,
                                       out.rest_duration) if t.size else float("nan")
    front = np.asarray(snaps.front, dtype=float)
    final_front = float(front[-1]) if front.size else float("nan")
    m = cfg.material
    dims = ("time", "particle")
    en = {k: np.asarray(v, float) for k, v in getattr(snaps, "energy", {}).items()}
    eb = getattr(solver, "energy", None)
    energy_vars = {}
    if en and eb is not None and en["potential"].size:
        kin = np.asarray(snaps.kinetic, float)
        resid = kin + en["potential"] + en["dissipated"] + en["outflow"] - eb.e0
        energy_vars = {
            "potential_energy": var(en["potential"], ("time",), "J m-1",
                                    "potential energy per unit width, -m sum g.r (slope frame, datum: bed and back wall)"),
            "dissipated_energy": var(en["dissipated"], ("time",), "J m-1",
                                     "cumulative work of the discrete viscous stress and wall traction, "
                                     "m sum u*.(A - I)u* over the steps"),
            "wall_friction_energy": var(en["wall_friction"], ("time",), "J m-1",
                                        "the wall traction's share of dissipated_energy (bed law: friction drag or viscous wall term)"),
            "outflow_energy": var(en["outflow"], ("time",), "J m-1",
                                  "kinetic + potential energy carried out through the downstream outflow"),
            "energy_residual": var(resid / eb.e_ref, ("time",), "1",
                                   "(E_kin + E_pot + dissipated + outflow - E_0) / E_ref: > 0 is energy the scheme "
                                   "created, < 0 numerical dissipation; E_ref = m g cos(theta) sum y(0)"),
            "energy_projection": var(en["projection"] / eb.e_ref, ("time",), "1",
                                     "cumulative pressure work of the projection on the mid-step velocity, "
                                     "m sum (u^n + u^n+1)/2.(u^n+1 - u*), / E_ref (0 in the continuum)"),
            "energy_shifting": var(en["shifting"] / eb.e_ref, ("time",), "1",
                                   "cumulative potential energy moved by particle shifting / E_ref"),
            "energy_clamps": var(en["clamps"] / eb.e_ref, ("time",), "1",
                                 "cumulative energy change of the wall clamps / E_ref"),
        }
    fr = {k: np.asarray(v, float) for k, v in getattr(snaps, "fronts", {}).items()}
    front_vars = {}
    for k, doc in FRONT_MEASURE_DOC.items():
        if k in fr and fr[k].size:
            front_vars[k] = var(fr[k], ("time",), "m", f"{doc}; from the back wall")
            front_vars[f"final_{k}"] = var(float(fr[k][-1]), (), "m", f"{k} at the end of the run")
    ds = xr.Dataset(
        data_vars={
            "x": var(stack("x", np.float32), dims, "m", "down-slope particle position from the back wall"),
            "y": var(stack("y", np.float32), dims, "m", "bed-normal particle position above the bed"),
            "u": var(stack("u", np.float32), dims, "m s-1", "down-slope particle velocity"),
            "v": var(stack("v", np.float32), dims, "m s-1", "bed-normal particle velocity"),
            "pressure": var(stack("pressure", np.float32), dims, "Pa", "pressure from the PPE"),
            "viscosity": var(stack("viscosity", np.float32), dims, "Pa s",
                             "effective viscosity mu(I) p/|gamma_dot| (capped) or Newtonian"),
            "free_surface": var(stack("free_surface", np.int8), dims, "1",
                                "free-surface flag (div r < threshold; p Dirichlet)"),
            "front_position": var(front, ("time",), "m",
                                  "front position from the back wall (first bed cell thinner than threshold)"),
            "kinetic_energy": var(np.asarray(snaps.kinetic, float), ("time",), "J m-1",
                                  "kinetic energy per unit width"),
            "area_ratio": var(np.asarray(snaps.area, float), ("time",), "1",
                              "area under the binned free surface / (N dx^2) (bulk volume conservation; 1 = exact)"),
            "max_speed": var(np.asarray(snaps.max_speed, float), ("time",), "m s-1", "maximum particle speed"),
            "step": var(np.asarray(snaps.steps, np.int64), ("time",), "1", "time steps taken"),
            "outflow_time": var(out_t, ("particle",), "s",
                                "time the particle left through the downstream outflow at x = domain_length "
                                "(NaN: it stayed in the domain); from then on it is frozen where it left"),
            "final_front_position": var(final_front, (), "m", "front position at the end of the run"),
            "time_to_rest": var(float(time_to_rest), (), "s",
                                "start of the first window of rest_duration with the max (rest_measure) speed of the mass < rest_speed"),
            "time_to_rest_mass99": var(t_rest99, (), "s",
                                       "start of the first window of rest_duration in which 99 % of the mass moves "
                                       "slower than rest_speed (isph.analysis.time_to_rest_mass_share)"),
            "moving_share": var(moving_share(stack("u", np.float64), stack("v", np.float64), out.rest_speed),
                                ("time",), "1", "share of the mass moving at rest_speed or faster"),
            **energy_vars, **front_vars,
        },
        coords={
            "time": var(t, ("time",), "s", "time since gate removal"),
            "particle": var(np.arange(nf, dtype=np.int64), ("particle",), "1", "granular particle index"),
        },
    )
    g = cfg.geometry
    st = solver.stats
    ds.attrs.update({
        "title": f"granudep 2D ISPH mu(I) run {cfg.case}",
        "status": status,
        "theta_deg": float(g.theta_deg), "L0": float(g.L0), "H0": float(g.H0), "dx": float(cfg.numerics.dx),
        "smoothing_length": float(cfg.h), "kernel": "Wendland C2 (2D), support 2h",
        "particle_volume": float(cfg.numerics.dx ** 2),
        "rho": float(m.rho), "rho_s": float(m.rho_s), "d": float(m.d), "mu_s": float(m.mu_s),
        "mu_2": float(m.mu_2), "I0": float(m.I0), "mu_s_form": m.mu_s_form, "inertial_number": m.inertial_number,
        "front_depth_threshold": float(cfg.front_depth_threshold),
        "rheology": cfg.rheology.model, "wall_slip": cfg.wall.slip, "wall_slip_length": float(cfg.wall.slip_length),
        "t_c": float(cfg.t_c),
        "domain_length": float(cfg.domain_length), "n_particles": int(nf), "n_steps": int(st.steps),
        "outflow": int(bool(cfg.geometry.outflow)),
        "n_outflow": int(np.isfinite(out_t).sum()),
        "first_outflow_time": float(np.nanmin(out_t)) if np.isfinite(out_t).any() else float("nan"),
        "last_outflow_time": float(np.nanmax(out_t)) if np.isfinite(out_t).any() else float("nan"),
        "wall_time_s": float(st.wall_s), "wall_clamps": int(st.clamped),
        "ppe_iterations": int(st.ppe_iters), "viscous_iterations": int(st.visc_iters),
        "final_area_ratio": float(snaps.area[-1]) if snaps.area else float("nan"),
        "ms_per_step": float(1e3 * st.wall_s / st.steps) if st.steps else float("nan"),
        "linear_solver_fallbacks": int(getattr(st, "fallbacks", 0)),
        "energy_e0": float(eb.e0) if eb is not None else float("nan"),
        "energy_ref": float(eb.e_ref) if eb is not None else float("nan"),
        "energy_max_excess": float(eb.max_excess) if eb is not None else float("nan"),
        "energy_max_excess_time": float(eb.max_excess_time) if eb is not None else float("nan"),
        "time_to_rest_norm": float(time_to_rest / cfg.t_c) if math.isfinite(time_to_rest) else float("nan"),
        "time_to_rest_mass99_norm": float(t_rest99 / cfg.t_c) if math.isfinite(t_rest99) else float("nan"),
    })
    return provenance(ds, case=cfg.case, config_yaml=to_yaml(cfg))
