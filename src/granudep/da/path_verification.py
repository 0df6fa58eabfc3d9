"""Verification of the DA model on a path profile: rows for ``granudep verify da``.

* straight path = constant-θ model: a straight bed with the solver's own sin θ, cos θ gives the
  constant-θ run bit for bit; a straight path read from a CSV (θ through atan of the points)
  reproduces it to round-off;
* Coulomb block on a curved path (35° easing to flat): independent particles (k = 0, no XSPH) vs
  the exact energy line with the centripetal term (``analytic.exact_energy_line``), and without it
  the reach angle tan α = tan φ_B;
* volume balance with deposition on a curved path, to round-off;
* uniform-width channel vs the same run without a width column;
* bad path files refused with one line naming the problem.
"""
from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np

from ..config import ConfigError, build
from . import analytic as an
from .config import DAConfig, resolve
from .verification_rows import row as _row
from .api import _k, run_da
from .path import straight_bed
from .path_run import path_setup
from .path_solver import bed_table, simulate_path
from .solver import Physics, simulate

TABLE5_RUN = {"case": "1D-A70", "numerics": {"n_particles": 300}, "output": {"dt_output": 0.05, "dx_grid": 2e-3}}


def write_profile(path: Path, x, z, width=None, header=None) -> Path:
    cols = header or (["x [m]", "z [m]"] + (["width [m]"] if width is not None else []))
    rows = [",".join(cols)]
    for i in range(len(x)):
        vals = [x[i], z[i]] + ([width[i]] if width is not None else [])
        rows.append(",".join(repr(float(v)) for v in vals))
    path.write_text("\n".join(rows) + "\n")
    return path


def slope_to_flat(folder: Path, theta_deg: float = 35.0, scale: float = 100.0, width=None, name="knee.csv") -> Path:
    """A θ slope over ``scale`` horizontal metres meeting a flat zone twice as long (the example's shape)."""
    t = math.tan(math.radians(theta_deg))
    x = np.array([0.0, 0.5, 1.0, 2.0, 3.0]) * scale
    z = np.array([t, 0.5 * t, 0.0, 0.0, 0.0]) * scale
    return write_profile(folder / name, x, z, None if width is None else np.full(x.size, width))


def check_straight_path(quick: bool = False):
    """1D-A70 (300 particles, deposition with x∞ = 1.5 m) on a straight path vs the constant-θ run."""
    cfg = resolve(TABLE5_RUN, deposition=True, x_inf_mode="user", x_inf=1.5)
    ka, kp = _k(cfg)
    phys = Physics(ka, kp, True, -0.0313, 0.0402, 1.5)
    ref = simulate(cfg, phys)
    with tempfile.TemporaryDirectory() as tmp:
        from .path import straight_profile_csv
        csv = straight_profile_csv(Path(tmp) / "straight.csv", 22.0, cfg.geometry.domain_end + 0.5)
        path = {"file": str(csv), "smoothing_length": 0.5, "time_step": "absolute"}
        pcfg = resolve({**TABLE5_RUN, "geometry": {"path": path}}, deposition=True, x_inf_mode="user", x_inf=1.5)
        setup = path_setup(pcfg, straight_bed(cfg.theta, cfg.geometry.domain_end, 0.01))
        rec = simulate_path(pcfg, setup, phys, bed_table(setup, ka, kp, -0.0313, 0.0402))
        bit = max(float(np.max(np.abs(np.asarray(getattr(ref, k)) - np.asarray(getattr(rec, k)))))
                  for k in ("x", "u", "volume", "deposit_depth", "front"))
        a = run_da(TABLE5_RUN, deposition=True, x_inf_mode="user", x_inf=1.5)
        b = run_da({**TABLE5_RUN, "geometry": {"path": path}, "deposition": {"ab_source": "user", "A": -0.0313,
                                                                           "B": 0.0402}},
                   deposition=True, x_inf_mode="user", x_inf=1.5)
    dx = float(np.max(np.abs(a.x.values - b.x_particle.values)))
    dL = abs(float(a.final_runout) - float(b.final_runout))
    return [
        _row("path_straight", "straight bed vs constant theta: max |difference|", bit, 0.0, bit, 0.0,
             "x, u, V, h_D, front of every output; bed with the solver's sin/cos, time_step absolute"),
        _row("path_straight", "straight CSV path: max |x - x_const| (m)", dx, 0.0, dx, 1e-9,
             "theta from atan of the CSV points (round-off), 1D-A70, 300 particles, deposition, x_inf = 1.5 m"),
        _row("path_straight", "straight CSV path: final runout (m)", float(b.final_runout), float(a.final_runout),
             dL, 1e-9, "|runout_path - runout_const| (m)"),
    ]


def coulomb_on_path(centripetal: bool, n: int = 8, cfl: float = 0.25, tmp: Path | None = None):
    """Independent Coulomb particles (k = 0, XSPH off, no deposition) released from rest on the
    35°-to-flat path (100 m scale, σ = 15 m, φ_B = 28°). Returns (bed, s0, trajectories s(t), u(t),
    final stations)."""
    own = tmp is None
    tdir = tempfile.TemporaryDirectory() if own else None
    folder = Path(tdir.name) if own else tmp
    try:
        csv = slope_to_flat(folder)
        data = {"case": "block", "geometry": {"L0": 20.0, "H0": 1.0, "back_wall": False,
                                              "path": {"file": str(csv), "smoothing_length": 15.0, "release_start": 5.0,
                                                       "centripetal": centripetal}},
                "material": {"phi_basal_deg": 28.0, "phi_internal_deg": 32.0},
                "numerics": {"n_particles": 20, "earth_pressure": "one", "xsph_delta": 0.0, "cfl": cfl,
                             "smoothing": "fixed", "L_s": 2.0, "t_end": 60.0, "u_rest": 1e-6},
                "deposition": {"enabled": False}, "output": {"dt_output": 0.25, "dx_grid": 0.25}}
        cfg = build(DAConfig, data)
        setup = path_setup(cfg)
        s0 = np.linspace(5.0, 25.0, n)
        tab = bed_table(setup, 0.0, 0.0, 0.0, 0.0)
        rec = simulate_path(cfg, setup, Physics(0.0, 0.0, False), tab, "block",
                            init=(s0 - setup.origin, np.full(n, 0.1), np.zeros(n)))
    finally:
        if own:
            tdir.cleanup()
    xs = np.asarray(rec.x) + setup.origin
    return setup.bed, s0, xs, np.asarray(rec.u), rec


def check_coulomb_path(quick: bool = False, cfl: float = 0.1):
    """Stop stations and u(s) of Coulomb particles on the curved path vs the exact energy line."""
    rows = []
    mu = math.tan(math.radians(28.0))
    for cent in (True, False):
        bed, s0, xs, us, rec = coulomb_on_path(cent, cfl=cfl)
        e_stop, e_u, alphas = [], [], []
        for j in range(s0.size):
            s_ex, u_ex = an.exact_energy_line(bed.s, bed.theta, bed.kappa, mu, s0[j], 0.0, cent)
            stop = xs[-1, j]
            e_stop.append(abs(stop - s_ex[-1]) / (s_ex[-1] - s0[j]))
            moving = xs[:, j] < s_ex[-1] - 1.0
            e_u.append(float(np.max(np.abs(us[moving, j] ** 2 - np.interp(xs[moving, j], s_ex, u_ex ** 2))))
                       / float(np.max(u_ex) ** 2))
            if not cent:
                x0, x1 = bed.at("x", [s0[j], stop])
                z0, z1 = bed.at("z", [s0[j], stop])
                alphas.append((z0 - z1) / (x1 - x0))
        tag = "with" if cent else "without"
        rows.append(_row("path_coulomb", f"{tag} centripetal: stop station (m), particle 1", float(xs[-1, 0]),
                         float(an.exact_energy_line(bed.s, bed.theta, bed.kappa, mu, s0[0], 0.0, cent)[0][-1]),
                         max(e_stop), 1.5e-4, "max |s_stop - s_exact| / travel over 8 particles from rest, "
                         "35 deg to flat, sigma = 15 m, phi_B = 28 deg, CFL 0.1"))
        rows.append(_row("path_coulomb", f"{tag} centripetal: max speed (m/s)", float(np.max(us)),
                         0.0, max(e_u), 1e-4, "energy along the path: max |u^2 - u_exact(s)^2| / max u_exact^2 "
                         "at the outputs, 8 particles"))
        if not cent:
            a = float(np.mean(alphas))
            rows.append(_row("path_coulomb", "without centripetal: reach H/L = tan alpha", a, mu,
                             max(abs(v - mu) for v in alphas) / mu, 1e-4,
                             "max |H/L - tan phi_B| / tan phi_B: the energy line (bed points from release to stop)"))
    return rows


def curved_lab_path(folder: Path, width=None) -> Path:
    """A lab-scale path: 30° easing to flat over ~0.3 m (σ = 0.1 m), 2 m long (deposition checks)."""
    t = math.tan(math.radians(30.0))
    x = np.array([0.0, 0.5, 1.0, 1.5, 2.5])
    z = np.array([t, 0.5 * t, 0.0, 0.0, 0.0])
    return write_profile(folder / ("lab_w.csv" if width is not None else "lab.csv"), x, z,
                         None if width is None else np.full(x.size, width))


def _lab_config(csv: Path, **path):
    return {"case": "lab_path", "geometry": {"L0": 0.2, "H0": 0.14,
                                             "path": {"file": str(csv), "smoothing_length": 0.1, **path}},
            "material": {"phi_internal_deg": 25.5, "phi_basal_deg": 25.5},
            "numerics": {"n_particles": 300, "earth_pressure": "savage_hutter", "t_end": 10.0},
            "deposition": {"ab_source": "user", "A": -0.0313, "B": 0.0402, "x_inf_mode": "user", "x_inf": 1.6},
            "output": {"dt_output": 0.05, "dx_grid": 2e-3}}


def check_path_mass_and_width(quick: bool = False):
    """Volume balance with deposition on the curved lab path; a 3 m wide uniform channel vs no width."""
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        ds = run_da(_lab_config(curved_lab_path(folder)), deposition=True)
        dw = run_da(_lab_config(curved_lab_path(folder, width=3.0)), deposition=True)
    err = float(ds.volume_error)
    frac = float(ds.deposited_volume[-1] / ds.flowing_volume[0])
    dh = float(np.max(np.abs(ds.flow_depth.values - dw.flow_depth.values))) / 0.14
    dD = float(np.max(np.abs(ds.final_deposit_depth.values - dw.final_deposit_depth.values))) / 0.14
    vr = float(dw.flowing_volume[0] / ds.flowing_volume[0])
    return [
        _row("path_mass", "volume balance with deposition", frac, 0.0, err, 1e-13,
             "max |V_flow + V_dep - V0| / V0 (value: deposited fraction at rest); 30 deg easing to flat, 300 particles"),
        _row("path_width", "uniform 3 m channel vs no width: depth", dh, 0.0, max(dh, dD), 1e-8,
             "max |h_b - h| / H0 over every output and the final deposit (round-off; measured 4.6e-10)"),
        _row("path_width", "uniform 3 m channel: volume ratio", vr, 3.0, abs(vr - 3.0) / 3.0, 1e-12,
             "V0(b = 3 m) / V0(per unit width)"),
    ]


BAD_PATHS = {
    "non-monotonic x": ("x [m],z [m]\n0,10\n5,6\n4,5\n10,0\n", "x must increase strictly"),
    "fewer than 3 points": ("x [m],z [m]\n0,10\n10,0\n", "at least 3"),
    "NaN": ("x [m],z [m]\n0,10\n5,nan\n10,0\n", "not a finite number"),
    "slope > 80 deg": ("x [m],z [m]\n0,100\n1,0\n10,0\n", "slope"),
    "unit-less header": ("x,z\n0,10\n5,5\n10,0\n", "has no unit"),
}


def bad_path_messages():
    """{problem: ConfigError message or None} for each bad file, via the config (before any work)."""
    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        for k, (text, _) in BAD_PATHS.items():
            p = Path(tmp) / "bad.csv"
            p.write_text(text)
            from .path import _cached
            _cached.cache_clear()
            try:
                resolve({"case": "bad", "geometry": {"path": {"file": str(p)}},
                         "deposition": {"ab_source": "user", "A": -0.03, "B": 0.04}})
                out[k] = None
            except ConfigError as exc:
                out[k] = str(exc)
    return out


def check_bad_paths(quick: bool = False):
    msgs = bad_path_messages()
    ok = sum(1 for k, m in msgs.items() if m and BAD_PATHS[k][1] in m and "\n" not in m
             and m.startswith("geometry.path.file:"))
    return [_row("path_input", "bad path files refused with one line", ok, len(BAD_PATHS), len(BAD_PATHS) - ok, 0,
                 "non-monotonic x, < 3 points, NaN, slope > 80 deg, unit-less header: one-line ConfigError each")]


def run_path_checks(quick: bool = False):
    rows = []
    rows += check_straight_path(quick)
    rows += check_coulomb_path(quick)
    rows += check_path_mass_and_width(quick)
    rows += check_bad_paths(quick)
    return rows
