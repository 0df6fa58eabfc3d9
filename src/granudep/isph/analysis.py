"""Post-processing of ISPH runs: the initial failure plane of the column (Section 4.2.2); a run's
final runout and bed in words (Fig 6).

One definition, used by the verification table (``granudep verify isph``), Fig 5 and its caption
and the claims scorecard. The paper's failure plane is the Rankine surface that bounds "the initial
amount of flowing mass" (Section 4.2.2, θ_F = π/4 + φ/2 = 57.75° for φ = 25.5°, from the
horizontal: the major principal stress in the column is vertical). It is a *material* surface of
the initial column: it separates the particles that the collapse mobilises from those that stay in
the static block behind it. So it is measured on the particles' *initial* positions (x0, y0), not
on where they are at the time of measurement (the moving wedge has already slumped and sheared by
then), and reported from the horizontal (angle from the bed + θ). Decision and numbers:
docs/model.md, "Failure plane".
"""
from __future__ import annotations

import math

import numpy as np
import xarray as xr

from ..cases import characteristic_time

#: the paper's flow/deposit speed threshold (Section 2.2), m/s
CRITICAL_SPEED = 0.1
#: the slip length of the paper's basal slip, m (the authors' published value; docs/bed-law.md)
PAPER_SLIP_LENGTH = 0.018


def failure_plane_angle(ds: xr.Dataset, t_norm: float = 1.0, v_crit: float = CRITICAL_SPEED) -> dict:
    """Inclination of the surface separating moving and static column particles.

    At the output time nearest t = t_norm t_c the particles faster than ``v_crit`` (the paper's
    0.1 m/s flow/deposit threshold, Section 2.2) are 'moving'. In dx-thick bands of *initial*
    height y0 in [0.1, 0.9] H0, the failure surface position is the smallest initial x0 of a moving
    particle; a least-squares line x0 = c − y0 cot(β) through the band points gives β, the angle
    from the bed (slope-aligned frame); from the horizontal it is β + θ (Rankine: 45° + φ/2).

    Returns a dict: ``angle_deg`` (β, from the bed), ``angle_horizontal_deg`` (β + θ), ``time``
    (the output time used, s), ``points`` (bands in the fit) and ``toe_x`` (c, where the fitted
    plane meets the bed, m). NaN angles when fewer than 3 bands have moving particles or the
    fitted surface does not rise towards the back wall.
    """
    H0, dx = float(ds.attrs["H0"]), float(ds.attrs["dx"])
    theta = float(ds.attrs.get("theta_deg", 0.0))
    tc = float(ds.attrs["t_c"]) if "t_c" in ds.attrs else characteristic_time(H0, math.radians(theta))
    time = np.asarray(ds["time"].values, float)
    k = int(np.argmin(np.abs(time - t_norm * tc)))
    x0 = np.asarray(ds["x"].isel(time=0).values, float)
    y0 = np.asarray(ds["y"].isel(time=0).values, float)
    sp = np.hypot(np.asarray(ds["u"].isel(time=k).values, float), np.asarray(ds["v"].isel(time=k).values, float))
    moving = sp > v_crit
    ys, xs = [], []
    for lo in np.arange(0.1 * H0, 0.9 * H0, dx):
        band = (y0 >= lo) & (y0 < lo + dx) & moving
        if band.any():
            ys.append(float(np.mean(y0[band])))
            xs.append(float(np.min(x0[band])))
    nan = float("nan")
    out = {"angle_deg": nan, "angle_horizontal_deg": nan, "time": float(time[k]), "points": len(ys), "toe_x": nan}
    if len(ys) < 3:
        out["points"] = 0
        return out
    slope, intercept = np.polyfit(ys, xs, 1)  # dx0/dy0 = -cot(beta)
    if slope < 0:
        angle = math.degrees(math.atan2(1.0, -slope))
        out.update(angle_deg=angle, angle_horizontal_deg=angle + theta, toe_x=float(intercept))
    return out


def moving_share(u: np.ndarray, v: np.ndarray, speed: float = CRITICAL_SPEED) -> np.ndarray:
    """Share of the granular mass (equal-mass particles) moving at ``speed`` or faster, per snapshot
    (``u``, ``v``: time × particle)."""
    u = np.asarray(u, dtype=float)
    v = np.asarray(v, dtype=float)
    if u.size == 0:
        return np.zeros(u.shape[0])
    return np.mean(u * u + v * v >= speed * speed, axis=1)


def time_to_rest_mass_share(time: np.ndarray, u: np.ndarray, v: np.ndarray, share: float = 0.99,
                            speed: float = CRITICAL_SPEED, duration: float = 0.1) -> float:
    """The robust rest rule: the start of the first window of ``duration`` in which at
    least ``share`` of the mass moves slower than ``speed`` (at most 1 − share moves faster), after
    the flow has started (more than 1 − share of the mass once moved at ``speed``). NaN when the
    record never rests that long. Beside the every-particle rule of the run (``time_to_rest``: the
    max speed of all particles below ``speed``), which one straggler can hold back.
    """
    t = np.asarray(time, dtype=float)
    if not 0.0 < share < 1.0:
        raise ValueError(f"share: must be in (0, 1) (got {share})")
    moving = moving_share(u, v, speed) > 1.0 - share
    started = np.maximum.accumulate(moving) if moving.size else moving
    rest_since = math.nan
    tol = 1e-9 * max(1.0, float(t[-1])) if t.size else 0.0
    for k in range(t.size):
        if started[k] and not moving[k]:
            if math.isnan(rest_since):
                rest_since = float(t[k])
            if t[k] - rest_since >= duration - tol:
                return rest_since
        else:
            rest_since = math.nan
    return math.nan


def final_runout(ds: xr.Dataset) -> dict:
    """A run's final front (1 % volume front ``final_front_v99`` where stored, else
    ``final_front_position``), its runout ΔL/L0 = (x_f − L0)/L0, its status, time to rest and end
    (Fig 6 and its report caption)."""
    L0 = float(ds.attrs["L0"])
    key = "final_front_v99" if "final_front_v99" in ds else "final_front_position"
    xf = float(ds[key].values)
    rest = float(ds["time_to_rest"].values) if "time_to_rest" in ds else float("nan")
    return {"front": xf, "measure": "1 % volume front" if key == "final_front_v99" else "front",
            "runout_norm": (xf - L0) / L0, "status": str(ds.attrs.get("status", "")), "time_to_rest": rest,
            "t_end": float(ds["time"].values[-1])}


def bed_label(ds: xr.Dataset) -> str:
    """The bed condition of a run in words, from its ``wall_slip`` attribute."""
    slip = str(ds.attrs.get("wall_slip", ""))
    if slip in ("navier", "navier_overwrite"):
        ell = float(ds.attrs.get("wall_slip_length", float("nan")))
        whose = "; the paper's" if slip == "navier" and math.isclose(ell, PAPER_SLIP_LENGTH) else ""
        return f"basal slip ({slip}, slip length {1e3 * ell:g} mm{whose})"
    if slip == "no_slip":
        return "no-slip bed"
    return f"bed: {slip}" if slip else f"bed law not recorded ({ds.attrs.get('case', '?')})"
