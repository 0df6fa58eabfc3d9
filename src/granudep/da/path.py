"""A path profile for the DA model: read once, smoothed once, tabulated along the bed.

Input: a CSV with a header row that names each column **with its unit** — ``x [m], z [m]``
(horizontal distance, elevation) or ``s [m], z [m]`` (distance along the bed, elevation), and an
optional ``width [m]`` (channel width b). ``x (m)``, ``x_m`` and ``x/m`` are read too; the only
unit is m. Bad files are refused with one line naming the file, the line and the problem.

Smoothing (``smoothing_length`` σ): the linear spline (polyline) through the points, convolved
with a Gaussian of standard deviation σ. In closed form, with m_k the segment slopes and
Δm_k = m_k − m_{k−1} the slope change at knot x_k,

    z̃(x) = z_lin(x) + Σ_k Δm_k c_σ(x − x_k),   c_σ(d) = σ φ(d/σ) + d Φ(d/σ) − max(d, 0),
    z̃'(x) = m_0 + Σ_k Δm_k Φ((x − x_k)/σ),      z̃''(x) = Σ_k Δm_k φ((x − x_k)/σ)/σ

(φ, Φ the standard normal density and distribution). Why this and not an interpolating or a
penalised (smoothing) cubic spline: those have equivalent kernels with negative lobes and ring at
a slope break (a 35° slope meeting a flat runout zone gets a small uphill counter-slope after
the knee, where material pools); here z̃' is a positive-weight average of the segment slopes, so
it never leaves their range and changes monotonically across a break — no wiggles; z̃ is C∞,
|κ| ≤ max|Δm|/(σ √(2π)), and a straight path stays exactly straight. The price: z̃ passes within
0.4 σ |Δm_k| of a kinked point instead of through it (nothing at points on a straight run).
The end segments are extended straight (the width: constant), so the ends are not bent.
For (s, z) input the horizontal positions are x_k = Σ √(Δs² − Δz²) (chords) and the station s
is then re-measured along the smoothed bed (it differs from the input s by O(κ² Δs³)).

Along the smoothed bed, on a uniform station grid s (spacing ``ds``, s = 0 at the first point):
x(s), z(s), θ(s) = −atan z̃' (positive down-slope), κ(s) = z̃''/(1 + z̃'²)^{3/2} (> 0 where the bed
is concave, the slope easing: the normal stress ρh(g cos θ + κ u²) grows), b(s), db/ds.
The arc length is integrated with Simpson's rule on a grid of σ/200.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Literal

import numpy as np
from scipy.special import ndtr

from ..config import ConfigError, param

MAX_SLOPE_DEG = 80.0
_UNIT = re.compile(r"^\s*([A-Za-z]+)\s*(?:\[\s*([^\]]*)\s*\]|\(\s*([^)]*)\s*\)|_([A-Za-z]+)|/\s*([A-Za-z]+))\s*$")
_NAMES = ("x", "s", "z", "width")


@dataclass(frozen=True)
class PathGeometry:
    """``geometry.path``: the slope profile and the release along it (stations s in m along the bed)."""
    file: str = param(doc="CSV of x [m], z [m] (or s [m], z [m]), optional width [m]; relative to the working "
                          "directory, else to the YAML's folder")
    smoothing_length: float | None = param(None, gt=0.0, unit="m",
                                           doc="σ of the Gaussian smoothing of the polyline; null: mean point spacing")
    ds: float | None = param(None, gt=0.0, unit="m", doc="spacing of the tabulated bed (θ, κ, b); null: σ/50")
    release_start: float = param(0.0, ge=0.0, unit="m",
                                 doc="column release: station of its up-slope end (the back wall, if any); "
                                     "the column is geometry.L0 long and geometry.H0 deep (bed-normal)")
    release_polygon: list[list[float]] | None = param(
        None, doc="instead of the column: [[s, depth], ...] (m), depth linear between vertices, from the first "
                  "to the last station")
    ab_slope: Literal["release", "local"] = param(
        "release", doc="A, B of eq 36 (ab_source computed): at the release zone's (a, θ), or at the local slope")
    centripetal: bool = param(True, doc="normal stress g cosθ + κ u² (Savage & Hutter 1991); false: g cosθ")
    time_step: Literal["relative", "absolute"] = param(
        "relative", doc="CFL speed: wave speed + relative velocity (relative) or max(|u|, sqrt(g h)) as eq 32 "
                        "in the constant-theta model (absolute); path_solver.py")

    def validate(self, prefix: str) -> None:
        p = f"{prefix}." if prefix else ""
        prof = read_profile(self.file, f"{p}file")
        if self.release_polygon is not None:
            poly = self.release_polygon
            key = f"{p}release_polygon"
            if len(poly) < 2 or any(len(v) != 2 for v in poly):
                raise ConfigError(f"{key}: must be a list of at least 2 [s, depth] pairs (got {poly!r})")
            s = [v[0] for v in poly]
            h = [v[1] for v in poly]
            if any(b <= a for a, b in zip(s, s[1:])):
                raise ConfigError(f"{key}: stations s must increase strictly (got {s})")
            if min(h) < 0.0 or max(h) <= 0.0:
                raise ConfigError(f"{key}: depths must be >= 0 with at least one > 0 (got {h})")
            if s[0] < 0.0:
                raise ConfigError(f"{key}: stations must be >= 0 (got {s[0]})")
        sigma = self.sigma(prof)
        if self.ds is not None and self.ds > sigma:
            raise ConfigError(f"{p}ds: must be <= smoothing_length = {sigma:.6g} m (got {self.ds})")

    def sigma(self, prof=None) -> float:
        if self.smoothing_length is not None:
            return float(self.smoothing_length)
        prof = prof if prof is not None else read_profile(self.file, "geometry.path.file")
        return float((prof.x[-1] - prof.x[0]) / (prof.x.size - 1))


@dataclass(frozen=True)
class Profile:
    """The points of a path CSV (x horizontal, z elevation, width or None), checked."""
    x: np.ndarray
    z: np.ndarray
    width: np.ndarray | None
    source: str


def _parse_header(cells, key: str, name: str):
    cols = []
    for c in cells:
        m = _UNIT.match(c)
        if not m:
            bare = c.strip()
            if bare.lower() in _NAMES:
                raise ConfigError(f"{key}: {name}: header column {bare!r} has no unit; write e.g. '{bare} [m]' "
                                  f"(allowed columns: x or s, z, width; unit m)")
            raise ConfigError(f"{key}: {name}: header column {c.strip()!r} is not 'NAME [UNIT]' "
                              f"(allowed: x [m] or s [m], z [m], width [m])")
        col = m.group(1).lower()
        unit = next(g for g in m.groups()[1:] if g is not None).strip()
        if col not in _NAMES:
            raise ConfigError(f"{key}: {name}: unknown column {col!r} (allowed: x or s, z, width)")
        if unit != "m":
            raise ConfigError(f"{key}: {name}: column {col!r} has unit {unit!r} (allowed: m)")
        cols.append(col)
    if len(set(cols)) != len(cols) or "z" not in cols or ("x" in cols) == ("s" in cols):
        raise ConfigError(f"{key}: {name}: header must name z [m] and one of x [m] or s [m] once each, "
                          f"optionally width [m] (got {', '.join(cols)})")
    return cols


def _read_profile(path: str, key: str) -> Profile:
    p = Path(path)
    if not p.is_file():
        raise ConfigError(f"{key}: path file {path!r} not found")
    numbered = [(k, ln) for k, ln in enumerate(p.read_text().splitlines(), start=1)
                if ln.strip() and not ln.lstrip().startswith("#")]
    if not numbered:
        raise ConfigError(f"{key}: {p.name}: empty file (needs a header row and at least 3 points)")
    sep = "," if "," in numbered[0][1] else None
    cols = _parse_header(numbered[0][1].split(sep), key, p.name)
    rows = []
    lineno = []
    for k, ln in numbered[1:]:
        lineno.append(k)
        cells = ln.split(sep)
        if len(cells) != len(cols):
            raise ConfigError(f"{key}: {p.name} line {k}: {len(cells)} values, header has {len(cols)}")
        vals = []
        for col, c in zip(cols, cells):
            try:
                v = float(c)
            except ValueError:
                v = float("nan")
            if not math.isfinite(v):
                raise ConfigError(f"{key}: {p.name} line {k}: {col} = {c.strip()!r} is not a finite number")
            vals.append(v)
        rows.append(vals)
    if len(rows) < 3:
        raise ConfigError(f"{key}: {p.name}: {len(rows)} point(s); a path needs at least 3")
    a = np.asarray(rows, dtype=float)
    col = {c: a[:, i] for i, c in enumerate(cols)}
    z = col["z"]
    if "x" in col:
        x = col["x"]
        dx = np.diff(x)
        bad = np.flatnonzero(dx <= 0.0)
        if bad.size:
            i = int(bad[0])
            raise ConfigError(f"{key}: {p.name} line {lineno[i + 1]}: x must increase strictly along the path "
                              f"(x = {x[i + 1]:g} m after {x[i]:g} m)")
    else:
        s = col["s"]
        dsv, dz = np.diff(s), np.diff(z)
        bad = np.flatnonzero(dsv <= 0.0)
        if bad.size:
            i = int(bad[0])
            raise ConfigError(f"{key}: {p.name} line {lineno[i + 1]}: s must increase strictly along the path "
                              f"(s = {s[i + 1]:g} m after {s[i]:g} m)")
        bad = np.flatnonzero(np.abs(dz) >= dsv)
        if bad.size:
            i = int(bad[0])
            raise ConfigError(f"{key}: {p.name} line {lineno[i + 1]}: |dz| = {abs(dz[i]):g} m >= ds = {dsv[i]:g} m "
                              f"(s is the distance along the bed: a vertical or impossible segment)")
        dx = np.sqrt(dsv * dsv - dz * dz)
        x = s[0] + np.concatenate([[0.0], np.cumsum(dx)])
    slope = np.degrees(np.arctan(np.abs(np.diff(z)) / np.diff(x)))
    bad = np.flatnonzero(slope > MAX_SLOPE_DEG)
    if bad.size:
        i = int(bad[0])
        raise ConfigError(f"{key}: {p.name} lines {lineno[i]}-{lineno[i + 1]}: slope {slope[i]:.3g} deg > "
                          f"{MAX_SLOPE_DEG:g} deg (allowed: <= {MAX_SLOPE_DEG:g} deg; a DA model needs a shallow bed)")
    width = col.get("width")
    if width is not None:
        bad = np.flatnonzero(width <= 0.0)
        if bad.size:
            i = int(bad[0])
            raise ConfigError(f"{key}: {p.name} line {lineno[i]}: width must be > 0 m (got {width[i]:g})")
    return Profile(x - x[0], z, width, str(p))


@lru_cache(maxsize=32)
def _cached(path: str, mtime: float, key: str) -> Profile:
    return _read_profile(path, key)


def anchor_path_file(data: dict, yaml_path) -> dict:
    """A relative ``geometry.path.file`` that does not exist from the working directory but does
    next to the YAML that names it is taken from there (the YAML and its CSV travel together)."""
    pth = (data.get("geometry") or {}).get("path") if isinstance(data.get("geometry"), dict) else None
    if isinstance(pth, dict) and isinstance(pth.get("file"), str):
        f = Path(pth["file"])
        beside = Path(yaml_path).parent / f
        if not f.is_absolute() and not f.is_file() and beside.is_file():
            pth["file"] = str(beside)
    return data


def read_profile(path: str, key: str = "geometry.path.file") -> Profile:
    """The checked points of a path CSV (x shifted to start at 0); ConfigError naming the problem."""
    p = Path(path)
    mtime = p.stat().st_mtime if p.is_file() else -1.0
    return _cached(str(path), mtime, key)


# ----------------------------------------------------------------------------------------------
# smoothing: the Gaussian-smoothed linear spline, in closed form
# ----------------------------------------------------------------------------------------------

class SmoothedPolyline:
    """f(x), f'(x), f''(x) of the polyline through (xk, fk) convolved with a Gaussian of σ.

    ``extend``: 'linear' continues the end segments, 'constant' holds the end values (width)."""

    def __init__(self, xk, fk, sigma: float, extend: str = "linear"):
        self.xk = np.asarray(xk, dtype=float)
        self.fk = np.asarray(fk, dtype=float)
        self.sigma = float(sigma)
        m = np.diff(self.fk) / np.diff(self.xk)
        self.m = m
        if extend == "linear":
            m_left, m_right = m[0], m[-1]
        else:
            m_left, m_right = 0.0, 0.0
        self.m_left, self.m_right = m_left, m_right
        self.dm = np.diff(np.concatenate([[m_left], m, [m_right]]))  # at every knot

    def _poly(self, x):
        xk, fk = self.xk, self.fk
        f = np.interp(x, xk, fk)
        f = np.where(x < xk[0], fk[0] + self.m_left * (x - xk[0]), f)
        f = np.where(x > xk[-1], fk[-1] + self.m_right * (x - xk[-1]), f)
        seg = np.searchsorted(xk, x, side="right") - 1
        slopes = np.concatenate([[self.m_left], self.m, [self.m_right]])
        return f, slopes[seg + 1]

    def __call__(self, x, nu: int = 0):
        """nu-th derivative (0, 1, 2) at the points x."""
        x = np.asarray(x, dtype=float)
        f, fp = self._poly(x)
        out = [f.copy(), fp.copy(), np.zeros_like(x)][nu]
        sg = self.sigma
        for xk, dm in zip(self.xk, self.dm):
            if dm == 0.0:
                continue
            lo, hi = np.searchsorted(x, [xk - 9.0 * sg, xk + 9.0 * sg])
            if hi <= lo:
                continue
            d = x[lo:hi] - xk
            t = d / sg
            pdf = np.exp(-0.5 * t * t) / math.sqrt(2.0 * math.pi)
            if nu == 0:
                out[lo:hi] += dm * (sg * pdf + d * ndtr(t) - np.maximum(d, 0.0))
            elif nu == 1:
                out[lo:hi] += dm * (ndtr(t) - (d >= 0.0))
            else:
                out[lo:hi] += dm * pdf / sg
        return out


# rows of the bed table the kernel reads (linear interpolation in s)
T_SIN, T_COS, T_KAPPA, T_WIDTH, T_DWIDTH, T_KACT, T_KPASS, T_A, T_B = range(9)
N_TABLE = 9


@dataclass(frozen=True)
class Bed:
    """The smoothed path on a uniform station grid s (m from the first point)."""
    s: np.ndarray
    x: np.ndarray
    z: np.ndarray
    theta: np.ndarray       # rad, > 0 down-slope
    kappa: np.ndarray       # 1/m, > 0 concave (slope easing)
    width: np.ndarray       # m (1 without a width column)
    dwidth: np.ndarray      # db/ds
    has_width: bool
    sigma: float
    source: str
    sin: np.ndarray | None = None   # exact sin θ / cos θ where known (straight bed); else from θ
    cos: np.ndarray | None = None

    @property
    def ds(self) -> float:
        return float(self.s[1] - self.s[0])

    @property
    def length(self) -> float:
        return float(self.s[-1])

    def at(self, name: str, s):
        """Linear interpolation of a tabulated quantity at stations s."""
        return np.interp(s, self.s, getattr(self, name))


def build_bed(prof: Profile, sigma: float, ds: float | None = None) -> Bed:
    """Smooth the profile (σ), measure the arc length, tabulate x, z, θ, κ, b along s."""
    zf = SmoothedPolyline(prof.x, prof.z, sigma, "linear")
    hx = sigma / 200.0
    nf = int(math.ceil((prof.x[-1] - prof.x[0]) / hx)) + 1
    xf = np.linspace(prof.x[0], prof.x[-1], max(nf, 3) | 1)
    mf = zf(xf, 1)
    from scipy.integrate import cumulative_simpson
    sf = cumulative_simpson(np.sqrt(1.0 + mf * mf), x=xf, initial=0.0)
    length = float(sf[-1])
    ds = sigma / 50.0 if ds is None else ds
    ns = int(math.ceil(length / ds)) + 1
    s = np.linspace(0.0, length, ns)
    x = np.interp(s, sf, xf)
    m, m2 = zf(x, 1), zf(x, 2)
    z = zf(x, 0)
    theta = -np.arctan(m)
    kappa = m2 / (1.0 + m * m) ** 1.5
    if prof.width is not None:
        bf = SmoothedPolyline(prof.x, prof.width, sigma, "constant")
        width = bf(x, 0)
        dwidth = bf(x, 1) / np.sqrt(1.0 + m * m)  # db/ds = db/dx dx/ds
    else:
        width, dwidth = np.ones(ns), np.zeros(ns)
    return Bed(s, x, z, theta, kappa, width, dwidth, prof.width is not None, float(sigma), prof.source)


def bed_of(path_cfg: PathGeometry) -> Bed:
    prof = read_profile(path_cfg.file)
    return build_bed(prof, path_cfg.sigma(prof), path_cfg.ds)


def straight_bed(theta: float, length: float, ds: float) -> Bed:
    """A straight bed of slope θ (rad) and length along the bed, with sin θ and cos θ exactly as
    ``solver.constant_bed_table`` tabulates them: the constant-θ model as a path (bit-for-bit test)."""
    ns = int(math.ceil(length / ds)) + 1
    s = np.linspace(0.0, length, ns)
    one = np.ones(ns)
    return Bed(s, s * math.cos(theta), -s * math.sin(theta), theta * one, 0.0 * one, one.copy(), 0.0 * one,
               False, float("inf"), f"straight bed, theta = {math.degrees(theta):g} deg",
               math.sin(theta) * one, math.cos(theta) * one)


def straight_profile_csv(path: str | Path, theta_deg: float, length: float, npts: int = 5) -> Path:
    """Write a straight path (constant slope θ, ``length`` along the bed) as an x, z CSV."""
    th = math.radians(theta_deg)
    s = np.linspace(0.0, length, npts)
    lines = ["x [m],z [m]"] + [f"{float(si * math.cos(th))!r},{float(-si * math.sin(th))!r}" for si in s]
    Path(path).write_text("\n".join(lines) + "\n")
    return Path(path)
