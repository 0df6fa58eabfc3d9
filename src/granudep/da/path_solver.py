"""DA SPH along a path profile (issue 16): the step kernel and the driver.

The particles move along the bed; their coordinate ξ = s − s_origin is the station along the
smoothed path (``da/path.py``) from the back wall (s_origin = start of the release) or, without a
wall, from the first point of the path. Every step is the constant-θ scheme of ``solver.advance``
(same depth, gradient, XSPH passes and the same Heun/Coulomb update) with the slope quantities read
per particle from the bed table (linear interpolation in s) and the curved-bed terms of
Savage & Hutter (1991):

    du/dt = g sinθ(s) − k g cosθ(s) ∂h/∂s − g cosθ(s) ∂h_D/∂s − sgn(u) tanφ_B N⁺,
    N = g cosθ(s) + κ(s) u²,  N⁺ = max(N, 0)   (``physics.bed_normal_acceleration``)

(the centripetal term only in the normal stress, as in S&H 1991; earth pressure as in eqs 8–9).
Where N < 0 (a convex break taken faster than √(g cosθ/|κ|)) the mass would leave the bed:
free flight is not modelled, friction is zero there, and every clipped particle-stage is counted
(``diag``; the output reports the count, the largest deficit and where).

Width b(s): particles carry volume (m³; m² per unit width without a width column); the SPH sum
of eq 20 gives the cross-section A = Σ V_j W_ij, the depth is h = A/b and the pressure gradient
∂h/∂s = (∂A/∂s − h db/ds)/b (``physics.depth_from_area`` / ``depth_gradient_from_area``), so the
pressure force per unit mass is −k g cosθ ∂h/∂s as in a rectangular channel of slowly varying
width. The deposit is kept as volume per grid cell (conserved) and as volume/b (its depth × Δs,
for the bed term). With b ≡ 1, θ constant and κ = 0 every operation reduces to
``solver.advance`` bit for bit (tested).

Time step (``geometry.path.time_step``): ``absolute`` is eq 32 as in ``solver.advance``,
Δt = CFL L_s / max(|u|, √(g h)). ``relative`` (default on a path) drops the advection speed, which
no Lagrangian scheme needs for stability (particles carry their state; Monaghan's SPH CFL uses
the wave speed and the relative velocity of neighbours): Δt = CFL L_s / max(√(g h) + min(L_s |∂u/∂s|, 2 max|u|)),
plus |u| Δt ≤ CFL · ¼ σ so that a step never jumps over the bed's changes of slope (σ: the path
smoothing length). Measured effect in docs/paper-notes.md ("DA on a path profile").

Friction is integrated like the other forces (Heun): the predictor's budget is N⁺(stage 1) tanφ_B Δt,
the corrector's ½ Δt tanφ_B (N⁺₁ + N⁺₂); for a constant N this is the constant-θ budget exactly.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numba import njit

from .neighbours import insertion_sort
from .path import N_TABLE, T_A, T_B, T_COS, T_DWIDTH, T_KACT, T_KAPPA, T_KPASS, T_SIN, T_WIDTH
from .physics import (alpha_coefficient, bed_normal_acceleration, coulomb_update, critical_momentum,
                      deposition_rate, depth_from_area, depth_gradient_from_area, earth_pressure,
                      net_acceleration)
from .solver import (AT_REST, ESCAPED, F_ND, F_U, F_V, F_V0, F_H, MAX_STEPS, N_FIELDS, NONFINITE, P_CFL,
                     P_CLAMP, P_DELTA, P_DEP, P_DXG, P_G, P_L0, P_MAXSTEPS, P_MINV, P_MOM, P_QC, P_SCALE,
                     P_TANI, P_UMIN, P_UREST, P_WALL, P_XINF, P_XMAX, P_BED, P_A, P_B, RUNNING, deposit_gradient,
                     evaluate, grid_depth, parameter_vector, particle_depths, smooth_deposit, smoothing_length)

# the path's own constants (second parameter vector)
Q_ORIGIN, Q_DS, Q_CENT, Q_TANB, Q_THR, Q_DTREL, Q_LGEO = range(7)
N_Q = 7
# time_step 'relative': |u| Δt <= CFL · GEOMETRY_STEP · σ (σ the path's smoothing length)
GEOMETRY_STEP = 0.25
# rows of the envelope array: max depth, max speed, arrival time
E_H, E_U, E_T = 0, 1, 2
# diagnostics: clipped (N < 0) particle-stages, largest deficit −N/g, station of it
D_LIFT, D_DEFICIT, D_WHERE = 0, 1, 2


@njit(cache=True, inline="always")
def _locate(s, ds, ns):
    """Table cell k and weight w of station s (clamped to the table: the ends are held)."""
    f = s / ds
    if f <= 0.0:
        return 0, 0.0
    k = int(math.floor(f))
    if k >= ns - 1:
        return ns - 2, 1.0
    return k, f - k


@njit(cache=True, inline="always")
def _at(tab, row, k, w):
    a = tab[row, k]
    return a + w * (tab[row, k + 1] - a)


@njit(cache=True)
def _stage(x, u, h, dh, du, n, V, tab, q, g, s_out, c_out, f_out, k_out, diag):
    """Per-particle slope terms at stage positions x and velocities u: turns the SPH area h (in
    place) into the depth, dh into ∂h/∂s; returns g sinθ in s_out, g cosθ in c_out, the friction
    deceleration magnitude tanφ_B N⁺ in f_out, and k in k_out."""
    ds = q[Q_DS]
    ns = tab.shape[1]
    origin = q[Q_ORIGIN]
    cent = q[Q_CENT] > 0.5
    tanb = q[Q_TANB]
    for i in range(n):
        if V[i] <= 0.0:
            s_out[i] = 0.0
            c_out[i] = 0.0
            f_out[i] = 0.0
            k_out[i] = 0.0
            continue
        k, w = _locate(x[i] + origin, ds, ns)
        b = _at(tab, T_WIDTH, k, w)
        h[i] = depth_from_area(h[i], b)
        dh[i] = depth_gradient_from_area(dh[i], h[i], b, _at(tab, T_DWIDTH, k, w))
        cs = _at(tab, T_COS, k, w)
        s_out[i] = g * _at(tab, T_SIN, k, w)
        c_out[i] = g * cs
        kap = _at(tab, T_KAPPA, k, w) if cent else 0.0
        nrm = bed_normal_acceleration(g, cs, kap, u[i])
        if nrm < 0.0:
            diag[D_LIFT] += 1.0
            if -nrm / g > diag[D_DEFICIT]:
                diag[D_DEFICIT] = -nrm / g
                diag[D_WHERE] = x[i] + origin
            nrm = 0.0
        f_out[i] = tanb * nrm
        k_out[i] = earth_pressure(du[i], _at(tab, T_KACT, k, w), _at(tab, T_KPASS, k, w))


@njit(cache=True)
def mark_envelopes(env, x0, x1, h, u, V, t, dxg, thr):
    """Along-path envelopes: every grid cell between a particle's old and new position gets
    max depth, max |u|, and the first time a particle at least ``thr`` deep passed it."""
    ng = env.shape[1]
    for i in range(x1.shape[0]):
        if V[i] <= 0.0:
            continue
        a = min(x0[i], x1[i])
        b = max(x0[i], x1[i])
        c0 = max(0, int(math.floor(a / dxg)))
        c1 = min(ng - 1, int(math.floor(b / dxg)))
        hi = h[i]
        ui = abs(u[i])
        for c in range(c0, c1 + 1):
            if hi > env[E_H, c]:
                env[E_H, c] = hi
            if ui > env[E_U, c]:
                env[E_U, c] = ui
            if hi >= thr and t < env[E_T, c]:
                env[E_T, c] = t


@njit(cache=True, inline="always")
def _deposit(dep, depb, binv, xp, dv, dxg):
    """``solver.deposit_to_grid`` for both the cell volumes and volume/b (same weights)."""
    ng = dep.shape[0]
    s = xp / dxg - 0.5
    k = int(math.floor(s))
    if k < 0:
        dep[0] += dv
        depb[0] += dv * binv[0]
    elif k >= ng - 1:
        dep[ng - 1] += dv
        depb[ng - 1] += dv * binv[ng - 1]
    else:
        w = s - k
        a = dv * (1.0 - w)
        dep[k] += a
        dep[k + 1] += dv - a
        depb[k] += a * binv[k]
        depb[k + 1] += (dv - a) * binv[k + 1]


@njit(cache=True)
def advance_path(x, F, order, dep, depb, binv, env, diag, t, t_target, prm, q, tab, nsteps):
    """``solver.advance`` on the path: step from t until t_target, rest or a failure.
    Returns (t, nsteps, status, offending particle or −1, L_s, Δt of the last step)."""
    n = x.shape[0]
    g = prm[P_G]
    qc = prm[P_QC]
    wall = prm[P_WALL] > 0.5
    dep_on = prm[P_DEP] > 0.5
    eq12 = prm[P_MOM] > 0.5
    clamp = prm[P_CLAMP] > 0.5
    dxg = prm[P_DXG]
    thr = q[Q_THR]
    maxsteps = int(prm[P_MAXSTEPS])
    ds = q[Q_DS]
    ns = tab.shape[1]
    origin = q[Q_ORIGIN]
    rel = q[Q_DTREL] > 0.5
    lgeo = q[Q_LGEO]
    xe = np.empty(2 * n)
    ue = np.empty(2 * n)
    Ve = np.empty(2 * n)
    he = np.empty(2 * n)
    lo = np.empty(n, np.int64)
    hi = np.empty(n, np.int64)
    h1 = np.empty(n)
    nd = np.empty(n)
    dh1 = np.empty(n)
    du1 = np.empty(n)
    xs1 = np.empty(n)
    h2 = np.empty(n)
    nd2 = np.empty(n)
    dh2 = np.empty(n)
    du2 = np.empty(n)
    xs2 = np.empty(n)
    a1 = np.empty(n)
    ut = np.empty(n)
    xt = np.empty(n)
    un = np.empty(n)
    xn = np.empty(n)
    fr = np.zeros(n)
    fdv = np.zeros(n)
    gb1 = np.zeros(n)
    gb2 = np.zeros(n)
    gs1 = np.empty(n)
    gc1 = np.empty(n)
    fc1 = np.empty(n)
    k1 = np.empty(n)
    gs2 = np.empty(n)
    gc2 = np.empty(n)
    fc2 = np.empty(n)
    k2 = np.empty(n)
    bed = dep_on and prm[P_BED] > 0.5
    L = 0.0
    dt = 0.0
    while t < t_target:
        if nsteps >= maxsteps:
            return t, nsteps, MAX_STEPS, -1, L, dt
        insertion_sort(x, F, order)
        L = smoothing_length(F, prm)
        u = F[F_U]
        V = F[F_V]
        evaluate(x, u, V, L, qc, wall, xe, ue, Ve, he, lo, hi, h1, nd, dh1, du1, xs1)
        if bed:
            deposit_gradient(x, V, depb, dxg, L, qc, wall, gb1)
        _stage(x, u, h1, dh1, du1, n, V, tab, q, g, gs1, gc1, fc1, k1, diag)
        vmax = 0.0
        wmax = 0.0
        if rel:
            for i in range(n):
                if V[i] > 0.0 and abs(u[i]) > wmax:
                    wmax = abs(u[i])
        for i in range(n):
            F[F_H, i] = h1[i]
            if V[i] > 0.0:
                F[F_ND, i] = nd[i]
                if rel:
                    # relative velocity across the support, L |∂u/∂s|, never above 2 max|u| (an
                    # isolated or nearly emptied particle can have an ill-conditioned ∂u/∂s)
                    r = L * abs(du1[i])
                    if not r <= 2.0 * wmax:
                        r = 2.0 * wmax
                    c = math.sqrt(g * h1[i]) + r
                else:
                    c = max(abs(u[i]), math.sqrt(g * h1[i]))
                if c > vmax:
                    vmax = c
        dt = prm[P_CFL] * L / vmax
        if rel and wmax * dt > prm[P_CFL] * lgeo:
            dt = prm[P_CFL] * lgeo / wmax
        if not dt > 0.0:
            return t, nsteps, NONFINITE, -1, L, dt
        last = t + dt >= t_target
        if last:
            dt = t_target - t
        # stage 1: driving acceleration; deposition rate and momentum loss (eqs 12, 14, 34, 36)
        for i in range(n):
            fr[i] = 0.0
            fdv[i] = fc1[i] * dt
            if V[i] <= 0.0:
                a1[i] = 0.0
                continue
            a1[i] = gs1[i] - k1[i] * gc1[i] * dh1[i] - gc1[i] * gb1[i]
            if dep_on and h1[i] > 0.0:
                an = net_acceleration(a1[i], u[i], fc1[i])
                au = abs(u[i])
                if u[i] != 0.0:
                    dhu = math.copysign(1.0, u[i]) * h1[i] * an - au * h1[i] * du1[i]
                else:
                    dhu = h1[i] * abs(an)
                kk, w = _locate(x[i] + origin, ds, ns)
                huc = critical_momentum(x[i], prm[P_L0], prm[P_XINF], _at(tab, T_A, kk, w), _at(tab, T_B, kk, w),
                                        prm[P_SCALE], clamp)
                al = alpha_coefficient(au * h1[i], huc, dhu)
                if al > 0.0:
                    sd = deposition_rate(al, dhu, u[i], prm[P_UMIN])
                    f = min(1.0, -sd * dt / h1[i])
                    fr[i] = f
                    if eq12:
                        fdv[i] += g * prm[P_TANI] * f * dt
        # predictor (stage 2 state)
        for i in range(n):
            if V[i] > 0.0:
                ut[i] = coulomb_update(u[i] + dt * a1[i], fdv[i])
                xt[i] = x[i] + dt * u[i]
                if wall and xt[i] < 0.0:
                    xt[i] = -xt[i]
            else:
                ut[i] = 0.0
                xt[i] = x[i]
        evaluate(xt, ut, V, L, qc, wall, xe, ue, Ve, he, lo, hi, h2, nd2, dh2, du2, xs2)
        if bed:
            deposit_gradient(xt, V, depb, dxg, L, qc, wall, gb2)
        _stage(xt, ut, h2, dh2, du2, n, V, tab, q, g, gs2, gc2, fc2, k2, diag)
        # corrector: eqs 30, 33, 31
        for i in range(n):
            if V[i] <= 0.0:
                un[i] = 0.0
                xn[i] = x[i]
                continue
            a2 = gs2[i] - k2[i] * gc2[i] * dh2[i] - gc2[i] * gb2[i]
            budget = 0.5 * dt * (fc1[i] + fc2[i])
            if eq12 and fr[i] > 0.0:
                budget += g * prm[P_TANI] * fr[i] * dt
            un[i] = coulomb_update(u[i] + 0.5 * dt * (a1[i] + a2), budget)
            xn[i] = x[i] + dt * (0.5 * (u[i] + un[i]) + prm[P_DELTA] * xs2[i])
            if wall and xn[i] < 0.0:
                xn[i] = -xn[i]
                if un[i] < 0.0:
                    un[i] = 0.0
            if not (math.isfinite(xn[i]) and math.isfinite(un[i])):
                return t, nsteps, NONFINITE, order[i], L, dt
            if xn[i] > prm[P_XMAX] or xn[i] < 0.0:
                return t, nsteps, ESCAPED, order[i], L, dt
        t_new = t_target if last else t + dt
        mark_envelopes(env, x, xn, h1, un, V, t_new, dxg, thr)
        # commit; deposition moves volume from particles to the grid
        umax = 0.0
        for i in range(n):
            x[i] = xn[i]
            if V[i] <= 0.0:
                continue
            if fr[i] > 0.0:
                dv = fr[i] * V[i]
                rest = V[i] - dv
                if rest < prm[P_MINV] * F[F_V0, i]:
                    dv = V[i]
                    rest = 0.0
                    un[i] = 0.0
                V[i] = rest
                _deposit(dep, depb, binv, xn[i], dv, dxg)
            u[i] = un[i]
            if V[i] > 0.0 and abs(un[i]) > umax:
                umax = abs(un[i])
        t = t_new
        nsteps += 1
        if umax < prm[P_UREST]:
            return t, nsteps, AT_REST, -1, L, dt
    return t, nsteps, RUNNING, -1, L, dt


# ----------------------------------------------------------------------------------------------
# Python driver
# ----------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class PathSetup:
    """A run's bed and release, resolved once (stations s in m along the bed from the first point)."""
    bed: object            # path.Bed
    origin: float          # s of ξ = 0 (back wall, or the first point without a wall)
    s_start: float         # release from s_start ...
    s_end: float           # ... to s_end (the "gate")
    L0: float              # release length s_end − s_start
    H0: float              # release depth (column) or mean depth (polygon), bed-normal
    theta_release: float   # rad: the release zone's slope (chord)
    x0: np.ndarray         # initial ξ of the particles
    V0: np.ndarray         # initial particle volumes (m³; m² per unit width without width)
    dx0: float             # initial particle spacing

    @property
    def xi_gate(self) -> float:
        return self.s_end - self.origin

    @property
    def xi_end(self) -> float:
        return self.bed.length - self.origin


@dataclass
class PathRecord:
    """What a path run produced, at the output times (particle arrays indexed by particle id)."""
    time: list = field(default_factory=list)
    x: list = field(default_factory=list)
    u: list = field(default_factory=list)
    h: list = field(default_factory=list)
    volume: list = field(default_factory=list)
    flow_depth: list = field(default_factory=list)
    deposit_depth: list = field(default_factory=list)
    deposited_volume: list = field(default_factory=list)
    front: list = field(default_factory=list)
    smoothing_length: list = field(default_factory=list)
    time_step: list = field(default_factory=list)
    steps: list = field(default_factory=list)
    x_edges: np.ndarray | None = None
    envelopes: np.ndarray | None = None
    diag: np.ndarray | None = None
    status: int = RUNNING
    message: str = ""
    n_steps: int = 0
    x_inf: float = float("nan")
    A: float = float("nan")
    B: float = float("nan")
    final_deposit_volume: np.ndarray | None = None

    @property
    def final_front(self) -> float:
        return float(self.front[-1]) if self.front else float("nan")


def bed_table(setup: PathSetup, k_active, k_passive, A, B) -> np.ndarray:
    """The (N_TABLE, ns) table the kernel interpolates; k, A, B scalars or arrays over the stations."""
    bed = setup.bed
    ns = bed.s.size
    tab = np.empty((N_TABLE, ns))
    tab[T_SIN] = np.sin(bed.theta) if getattr(bed, "sin", None) is None else bed.sin
    tab[T_COS] = np.cos(bed.theta) if getattr(bed, "cos", None) is None else bed.cos
    tab[T_KAPPA] = bed.kappa
    tab[T_WIDTH] = bed.width
    tab[T_DWIDTH] = bed.dwidth
    tab[T_KACT] = k_active
    tab[T_KPASS] = k_passive
    tab[T_A] = A
    tab[T_B] = B
    return tab


def _grid(setup: PathSetup, dxg: float):
    ng = int(math.ceil(setup.xi_end / dxg))
    edges = np.arange(ng + 1) * dxg
    centres = (np.arange(ng) + 0.5) * dxg
    width = setup.bed.at("width", centres + setup.origin)
    return ng, edges, centres, width


def path_vectors(cfg, setup: PathSetup, phys, ng: int, centripetal: bool):
    """(prm, q): the constant-θ parameter vector with the path's overrides, and the path vector."""
    from ..cases import G, momentum_scale
    num, mat, dep = cfg.numerics, cfg.material, cfg.deposition
    prm = parameter_vector(cfg, phys, ng)
    prm[P_XMAX] = setup.xi_end
    prm[P_L0] = setup.xi_gate
    prm[P_XINF] = phys.x_inf if phys.deposition else setup.xi_gate + 1.0
    prm[P_SCALE] = (momentum_scale(setup.H0, setup.theta_release) if dep.coefficient_units == "normalised"
                    else 1.0)
    q = np.zeros(N_Q)
    q[Q_ORIGIN] = setup.origin
    q[Q_DS] = setup.bed.ds
    q[Q_CENT] = 1.0 if centripetal else 0.0
    q[Q_TANB] = math.tan(math.radians(mat.phi_basal_deg)) if num.basal_friction else 0.0
    q[Q_THR] = cfg.front_threshold
    q[Q_DTREL] = 1.0 if cfg.geometry.path.time_step == "relative" else 0.0
    q[Q_LGEO] = GEOMETRY_STEP * setup.bed.sigma if math.isfinite(setup.bed.sigma) else 1e300
    _ = G
    return prm, q


MAIN_RUN_FRACTION = 0.01


def path_front(edges, depth, thr, width, fraction: float = MAIN_RUN_FRACTION) -> float:
    """Front on a path: ``front.front_from_profile`` started in the farthest down-slope contiguous
    run of cells with h + h_D ≥ thr that holds at least ``fraction`` of the material above threshold.
    On a long path the main deposit is often separated from material left in the release zone; the
    constant-θ rule (walk from the deepest cell) would then stop at the release."""
    from ..front import front_from_profile
    above = depth >= thr
    if not above.any():
        return float("nan")
    vol = depth * width * np.diff(edges)
    starts = np.flatnonzero(above & ~np.concatenate([[False], above[:-1]]))
    ends = np.flatnonzero(above & ~np.concatenate([above[1:], [False]]))
    runs = np.array([vol[a:b + 1].sum() for a, b in zip(starts, ends)])
    main = np.flatnonzero(runs >= fraction * runs.sum())
    return front_from_profile(edges, depth, thr, start=int(starts[main[-1]]))


def _record(rec, cfg, setup, x, F, order, dep, t, L, dt, steps, dxg, ng, width_c, thr):
    n = x.shape[0]
    qc = cfg.numerics.kernel_support
    wall = cfg.geometry.back_wall
    h = particle_depths(x, F[F_V], L, qc, wall) / setup.bed.at("width", x + setup.origin)
    for name, vals in (("x", x), ("u", F[F_U]), ("h", h), ("volume", F[F_V])):
        arr = np.empty(n)
        arr[order] = vals
        getattr(rec, name).append(arr)
    flow = grid_depth(x, F[F_V], L, qc, wall, dxg, ng) / width_c
    depo = smooth_deposit(dep, L, qc, dxg) / width_c
    rec.flow_depth.append(flow)
    rec.deposit_depth.append(depo)
    rec.deposited_volume.append(float(np.sum(dep)))
    rec.front.append(path_front(rec.x_edges, flow + depo, thr, width_c))
    rec.time.append(t)
    rec.smoothing_length.append(L)
    rec.time_step.append(dt)
    rec.steps.append(steps)


def initial_path_state(setup: PathSetup):
    n = setup.x0.size
    x = setup.x0.copy()
    F = np.zeros((N_FIELDS, n))
    F[F_V] = setup.V0
    F[F_V0] = F[F_V]
    F[F_ND] = 1.0 / setup.dx0
    return x, F, np.arange(n, dtype=np.int64)


def simulate_path(cfg, setup: PathSetup, phys, tab: np.ndarray, label: str = "", progress=None, init=None,
                  centripetal: bool | None = None) -> PathRecord:
    """Run one DA simulation along the path to rest (or t_end); a failure stops the run and the
    record keeps what was written, with ``status`` and ``message`` (time, step, particle, station)."""
    from .solver import custom_state
    cent = cfg.geometry.path.centripetal if centripetal is None else centripetal
    if init is None:
        x, F, order = initial_path_state(setup)
    else:
        x, F, order = custom_state(*init)
    dxg = cfg.output.dx_grid
    ng, edges, centres, width_c = _grid(setup, dxg)
    dep = np.zeros(ng)
    depb = np.zeros(ng)
    binv = 1.0 / width_c
    env = np.zeros((3, ng))
    env[E_T] = np.inf
    diag = np.zeros(3)
    prm, q = path_vectors(cfg, setup, phys, ng, cent)
    rec = PathRecord(x_edges=edges, x_inf=phys.x_inf, A=phys.A, B=phys.B, envelopes=env, diag=diag)
    thr = cfg.front_threshold
    L = smoothing_length(F, prm)
    # the release itself: depth and arrival time 0 in its cells
    h0 = particle_depths(x, F[F_V], L, cfg.numerics.kernel_support, cfg.geometry.back_wall)
    h0 = h0 / setup.bed.at("width", x + setup.origin)
    mark_envelopes(env, x, x, h0, F[F_U], F[F_V], 0.0, dxg, thr)
    _record(rec, cfg, setup, x, F, order, dep, 0.0, L, 0.0, 0, dxg, ng, width_c, thr)
    t, steps = 0.0, 0
    dt_out, t_end = cfg.output.dt_output, cfg.numerics.t_end
    k = 1
    while True:
        t_target = min(k * dt_out, t_end)
        t, steps, status, where, L, dt = advance_path(x, F, order, dep, depb, binv, env, diag, t, t_target, prm, q,
                                                      tab, steps)
        if status in (RUNNING, AT_REST):
            _record(rec, cfg, setup, x, F, order, dep, t, L, dt, steps, dxg, ng, width_c, thr)
        if progress is not None:
            progress(lambda: f"DA path {label}: t = {t:.3f} s, step {steps}, front s = "
                             f"{rec.front[-1] + setup.origin:.3f} m, L_s = {L:.3g} m, dt = {dt:.2e} s")
        if status == AT_REST:
            rec.status, rec.message = AT_REST, f"at rest at t = {t:.4f} s after {steps} steps"
            break
        if status in (NONFINITE, ESCAPED, MAX_STEPS):
            xs = np.empty_like(x)
            xs[order] = x
            where_txt = "" if where < 0 else f" particle {where} at s = {xs[where] + setup.origin:.4f} m"
            what = {NONFINITE: "non-finite velocity or position",
                    ESCAPED: f"a particle left the path (s outside [{setup.origin:.4g}, {setup.bed.length:.4g}] m;"
                             f" extend the path CSV)",
                    MAX_STEPS: f"numerics.max_steps = {cfg.numerics.max_steps} reached"}[status]
            rec.status = status
            rec.message = f"DA path run {label} stopped at t = {t:.5f} s, step {steps}: {what}{where_txt}"
            break
        if t >= t_end:
            rec.status, rec.message = RUNNING, f"not at rest at numerics.t_end = {t_end} s"
            break
        k += 1
    rec.n_steps = steps
    rec.final_deposit_volume = dep.copy()
    return rec
