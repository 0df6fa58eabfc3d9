"""One DA time step as a recipe of named stages (Sections 2.3–2.4, Fig 4), for the constant-θ
model and the path model alike (one home for each formula).

``advance`` runs many steps inside numba; every step is

1. ``neighbours.insertion_sort`` by position, ``smoothing_length`` L_s (eq 25 generalised, or fixed);
2. stage 1 at (x^n, u^n): ``sph.evaluate_into`` (depth eq 20 with mirror ghosts, gradients eqs 21–22
   and 28–29, XSPH sum eq 33; with ``k_symmetric`` the pair-form earth-pressure gradient
   ``sph.symmetric_pressure_gradient``, with k from the strained state ``strained_k`` when
   ``k_strain`` > 0), the deposit gradient (deposit as bed), ``bed_terms`` (g sinθ, g cosθ,
   k of eqs 8–9, Coulomb friction tanφ_B N⁺ with N = g cosθ + κu², depth = area / width — all read
   from the bed table: a path, or two equal stations for a constant θ);
3. ``time_step``: eq 32 (``absolute``) or the Lagrangian ``relative`` rule of the path model;
4. ``drive_and_deposition``: driving acceleration a^n, deposition fraction (eqs 14, 34, 36) and the
   eq 12 momentum loss;
5. ``predictor``: ũ = u^n + Δt a^n (Coulomb-limited), x̃ = x^n + Δt u^n;
6. stage 2 at (x̃, ũ): the same operators and ``bed_terms``;
7. ``corrector``: RK2 eqs 30–31 with the Heun friction budget, XSPH eq 33, mirror at the wall;
   the strained k^{n+1} from the mean of the two stages' ∂u/∂s;
8. ``mark_envelopes`` (path outputs), then ``commit``: positions, velocities, and the deposited
   volume from the particles onto the grid (flowing + deposited volume conserved to round-off).

The per-particle formulas live in ``physics.py``, the SPH sums in ``sph.py``; the run constants come
as one typed record, :class:`StepParams` (a NamedTuple: numba types it field by field and
``cache=True`` keeps working, unlike a structref, whose types must be registered and boxed by hand).
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from .neighbours import insertion_sort
from .path import T_A, T_B, T_COS, T_DWIDTH, T_KACT, T_KAPPA, T_KPASS, T_SIN, T_WIDTH
from .physics import (alpha_coefficient, bed_normal_acceleration, coulomb_update, critical_momentum,
                      deposited_fraction, deposition_rate, deposition_velocity_loss, depth_from_area,
                      depth_gradient_from_area, driving_acceleration, earth_pressure, earth_pressure_strained,
                      earth_pressure_wave_factor, heun_friction_budget,
                      momentum_rate, net_acceleration, wave_speed_absolute, wave_speed_relative)
from .kernels import gauss_gradw_e, kernel_norm
from .sph import (F_H, F_K, F_ND, F_U, F_V, F_V0, S_DH, S_DU, S_FC, S_GB, S_GC, S_GS, S_H, S_K, S_KB, S_ND,
                  S_XS, deposit_gradient, deposit_to_grid, evaluate_into, new_stage, new_window,
                  symmetric_pressure_gradient)

# status codes returned by ``advance``
RUNNING, AT_REST, NONFINITE, ESCAPED, MAX_STEPS = 0, 1, 2, 3, 4
# rows of the envelope array: max depth, max speed, arrival time
E_H, E_U, E_T = 0, 1, 2
# diagnostics: clipped (N < 0) particle-stages, largest deficit −N/g, station of it
D_LIFT, D_DEFICIT, D_WHERE = 0, 1, 2


class StepParams(NamedTuple):
    """The run constants every stage reads (SI units, radians already applied)."""
    g: float                      # gravity (m/s²)
    cfl: float                    # CFL number of eq 32
    xsph_delta: float             # δ of eq 33
    kernel_support: float         # q_c: kernel cut-off in units of L_s
    smoothing_B: float            # B of eq 25
    L_fixed: float                # fixed L_s (m); 0: eq 25
    back_wall: bool               # mirror wall at x = 0
    x_min: float                  # a particle below this has left the domain (−inf: never)
    x_max: float                  # ... or above this (m)
    u_rest: float                 # at rest when every |u| < u_rest (m/s)
    max_steps: int
    deposition: bool              # deposition source term on
    deposit_as_bed: bool          # −g cosθ ∂h_D/∂x in the momentum balance
    eq12: bool                    # eq 12 momentum loss of the depositing volume
    clamp_x: bool                 # clamp [x] of eq 36 to [0, 1]
    momentum_scale: float         # p0 (normalised A, B) or 1
    L0: float                     # gate: [x] = (x − L0)/(x∞ − L0)
    x_inf: float
    u_min: float                  # regularisation of eq 14 (m/s)
    tan_phi_internal: float       # tan φ_I (eq 12)
    tan_phi_basal: float          # tan φ_B (0 without basal friction)
    min_volume_fraction: float    # a particle below this fraction of its initial volume deposits all
    dx_grid: float                # deposit / envelope grid spacing (m)
    # bed table and path options (constant θ: origin 0, a two-station table, no curvature, width 1)
    origin: float                 # station s of x = 0
    ds: float                     # station spacing of the bed table
    centripetal: bool             # κ u² in the normal stress
    has_width: bool               # deposit also kept as volume / width (bed term, h_D)
    dt_relative: bool             # time_step 'relative' (path) instead of eq 32
    geometry_step: float          # |u| Δt ≤ CFL · geometry_step (m) with dt_relative
    front_threshold: float        # arrival-time depth threshold of the envelopes (m)
    own_deposit: bool = True      # the bed term includes a particle's own deposit (False: excluded, ``own_trail``)
    deposit_max_tan: float = math.inf  # no deposition where |tanθ| exceeds this (tan φ_B: a deposit cannot rest there)
    k_symmetric: bool = False     # earth pressure in symmetric pair form (``sph.symmetric_pressure_gradient``)
    k_strain: float = 0.0         # 1/ε_k > 0: k is a particle state following the strain (``strained_k``), pair form
    smoothing_volume: bool = True  # eq 25's mean weighted by V/V0 (numerics.smoothing_weight: volume)


# ----------------------------------------------------------------------------------------------
# bed table (per station s: sinθ, cosθ, κ, b, db/ds, k_a, k_p, A, B), linear in s
# ----------------------------------------------------------------------------------------------

@njit(cache=True, inline="always")
def locate(s, ds, ns):
    """Table cell k and weight w of station s (clamped to the table: the ends are held)."""
    f = s / ds
    if f <= 0.0:
        return 0, 0.0
    k = int(math.floor(f))
    if k >= ns - 1:
        return ns - 2, 1.0
    return k, f - k


@njit(cache=True, inline="always")
def table_at(tab, row, k, w):
    """Row ``row`` of the bed table at cell k, weight w (exactly tab[row, k] where the row is constant)."""
    a = tab[row, k]
    return a + w * (tab[row, k + 1] - a)


# ----------------------------------------------------------------------------------------------
# stages
# ----------------------------------------------------------------------------------------------

@njit(cache=True, inline="always")
def deposit_smoothing_length(L, dx_grid):
    """Smoothing length of the deposit as bed: L_s, but never below the grid cell. The deposit is
    known only as volume per grid cell; a kernel narrower than a cell sees it as a comb of spikes at
    the cell centres, whose gradient −g cosθ ∂h_D/∂x throws the particles between them back and forth
    (1D-A70 at N = 16 000, L_s = 0.12 mm on the 1 mm grid: 1921 particles moving up-slope at up to
    0.6 m/s at t = 0.12 s, and eq 34 then deposited half the column within 0.02 s)."""
    return max(L, dx_grid)


@njit(cache=True)
def smoothing_length(F, p):
    """Eq 25 generalised: L_s = B N / Σ_i n_i with n_i = Σ_j W_ij over particles with volume (for equal
    volumes n_i = h_i/V_i, eq 25 exactly); with ``p.smoothing_volume`` each particle weighted by the
    fraction V/V0 of its released volume it still carries (a particle eq 34 has emptied no longer
    resolves the flow); or the fixed L_s. Without deposition V = V0 and both are the same number."""
    if p.L_fixed > 0.0:
        return p.L_fixed
    s = 0.0
    c = 0.0
    for i in range(F.shape[1]):
        if F[F_V, i] > 0.0 and F[F_ND, i] > 0.0:
            w = F[F_V, i] / F[F_V0, i] if p.smoothing_volume else 1.0
            s += w * F[F_ND, i]
            c += w
    return p.smoothing_B * c / s


@njit(cache=True)
def bed_terms(x, u, V, S, tab, p, diag):
    """Per-particle bed quantities at stage positions x and velocities u (rows of the stage matrix
    S): turns the SPH area S_H (in place) into the depth and S_DH into ∂h/∂s (width), and fills
    g sinθ (S_GS), g cosθ (S_GC), the friction deceleration tanφ_B N⁺ (S_FC; N < 0 is clipped and
    counted in ``diag``) and k (S_K). With ``p.k_symmetric`` S_DH holds Σ ½(k_i + k_j) ∂A
    (``sph.symmetric_pressure_gradient``) and S_KB the pair-mean k: S_DH becomes the k-weighted
    ∂h/∂s (width term with S_KB) and k is set to 1."""
    h, dh, du, gs, gc, fc, k, kb = S[S_H], S[S_DH], S[S_DU], S[S_GS], S[S_GC], S[S_FC], S[S_K], S[S_KB]
    ns = tab.shape[1]
    g = p.g
    for i in range(x.shape[0]):
        if V[i] <= 0.0:
            gs[i] = 0.0
            gc[i] = 0.0
            fc[i] = 0.0
            k[i] = 0.0
            continue
        kk, w = locate(x[i] + p.origin, p.ds, ns)
        b = table_at(tab, T_WIDTH, kk, w)
        h[i] = depth_from_area(h[i], b)
        if p.k_symmetric:
            dh[i] = depth_gradient_from_area(dh[i], kb[i] * h[i], b, table_at(tab, T_DWIDTH, kk, w))
        else:
            dh[i] = depth_gradient_from_area(dh[i], h[i], b, table_at(tab, T_DWIDTH, kk, w))
        cs = table_at(tab, T_COS, kk, w)
        gs[i] = g * table_at(tab, T_SIN, kk, w)
        gc[i] = g * cs
        kap = table_at(tab, T_KAPPA, kk, w) if p.centripetal else 0.0
        nrm = bed_normal_acceleration(g, cs, kap, u[i])
        if nrm < 0.0:
            diag[D_LIFT] += 1.0
            if -nrm / g > diag[D_DEFICIT]:
                diag[D_DEFICIT] = -nrm / g
                diag[D_WHERE] = x[i] + p.origin
            nrm = 0.0
        fc[i] = p.tan_phi_basal * nrm
        k[i] = 1.0 if p.k_symmetric else earth_pressure(du[i], table_at(tab, T_KACT, kk, w),
                                                           table_at(tab, T_KPASS, kk, w))


@njit(cache=True)
def particle_k(x, du, tab, p, k):
    """k of eqs 8–9 of each particle (sign of its ∂u/∂s; k_a, k_p at its station of the bed table)."""
    ns = tab.shape[1]
    for i in range(x.shape[0]):
        kk, w = locate(x[i] + p.origin, p.ds, ns)
        k[i] = earth_pressure(du[i], table_at(tab, T_KACT, kk, w), table_at(tab, T_KPASS, kk, w))


@njit(cache=True)
def strained_k(x, V, k0, du, dt, tab, p, k):
    """k of each particle after the strain −∂u/∂s Δt from k0 (``physics.earth_pressure_strained``,
    limits k_a, k_p at its station); Δt = 0 clips k0 only."""
    ns = tab.shape[1]
    for i in range(x.shape[0]):
        if V[i] <= 0.0:
            k[i] = k0[i]
            continue
        kk, w = locate(x[i] + p.origin, p.ds, ns)
        k[i] = earth_pressure_strained(k0[i], du[i], dt, table_at(tab, T_KACT, kk, w),
                                       table_at(tab, T_KPASS, kk, w), p.k_strain)


@njit(cache=True)
def stage_mean(a, b, out):
    """out = ½ a + ½ b (the Heun mean of two stages' rates)."""
    for i in range(a.shape[0]):
        out[i] = 0.5 * a[i] + 0.5 * b[i]


@njit(cache=True)
def strained_wave_factor(x, tab, p, wf):
    """c²/(g h) of the strained earth pressure at each particle's station (time step)."""
    ns = tab.shape[1]
    for i in range(x.shape[0]):
        kk, w = locate(x[i] + p.origin, p.ds, ns)
        wf[i] = earth_pressure_wave_factor(table_at(tab, T_KACT, kk, w), table_at(tab, T_KPASS, kk, w), p.k_strain)


@njit(cache=True)
def store_depths(F, h, nd):
    """Keep the stage-1 depth and (for particles with volume) the number density for eq 25."""
    V = F[F_V]
    for i in range(h.shape[0]):
        F[F_H, i] = h[i]
        if V[i] > 0.0:
            F[F_ND, i] = nd[i]


@njit(cache=True)
def time_step(u, V, h, du, L, p, wf):
    """Δt = CFL L_s / max_i c_i: c = max(|u|, √(gh)) (eq 32, ``absolute``) or √(gh) + L|∂u/∂s|
    capped at 2 max|u| (``relative``), plus |u| Δt ≤ CFL · geometry_step there. wf: c²/(gh) of the
    earth pressure per particle (1, or ``strained_wave_factor``: √(gh) becomes √(g h wf))."""
    n = u.shape[0]
    vmax = 0.0
    wmax = 0.0
    if p.dt_relative:
        for i in range(n):
            if V[i] > 0.0 and abs(u[i]) > wmax:
                wmax = abs(u[i])
    for i in range(n):
        if V[i] > 0.0:
            if p.dt_relative:
                c = wave_speed_relative(h[i] * wf[i], p.g, L, du[i], 2.0 * wmax)
            else:
                c = wave_speed_absolute(u[i], h[i] * wf[i], p.g)
            if c > vmax:
                vmax = c
    dt = p.cfl * L / vmax
    if p.dt_relative and wmax * dt > p.cfl * p.geometry_step:
        dt = p.cfl * p.geometry_step / wmax
    return dt


@njit(cache=True)
def drive_and_deposition(x, u, V, S, tab, p, dt, a, fr, fdv):
    """Stage 1 (S its stage matrix): driving acceleration a (eqs 11/27), the deposited fraction fr
    (eqs 14, 34, 36; none where the bed is steeper than ``deposit_max_tan``) and the predictor's
    Coulomb budget fdv = F Δt (+ the eq 12 loss)."""
    h, dh, du, gb, gs, gc, fc, k = S[S_H], S[S_DH], S[S_DU], S[S_GB], S[S_GS], S[S_GC], S[S_FC], S[S_K]
    ns = tab.shape[1]
    for i in range(x.shape[0]):
        fr[i] = 0.0
        fdv[i] = fc[i] * dt
        if V[i] <= 0.0:
            a[i] = 0.0
            continue
        a[i] = driving_acceleration(gs[i], k[i], gc[i], dh[i], gb[i])
        if p.deposition and h[i] > 0.0 and abs(gs[i]) <= p.deposit_max_tan * gc[i]:
            dhu = momentum_rate(h[i], u[i], net_acceleration(a[i], u[i], fc[i]), du[i])
            kk, w = locate(x[i] + p.origin, p.ds, ns)
            huc = critical_momentum(x[i], p.L0, p.x_inf, table_at(tab, T_A, kk, w), table_at(tab, T_B, kk, w),
                                    p.momentum_scale, p.clamp_x)
            al = alpha_coefficient(abs(u[i]) * h[i], huc, dhu)
            if al > 0.0:
                f = deposited_fraction(deposition_rate(al, dhu, u[i], p.u_min), dt, h[i])
                fr[i] = f
                if p.eq12:
                    fdv[i] += deposition_velocity_loss(p.g, p.tan_phi_internal, f, dt)


@njit(cache=True)
def predictor(x, u, V, a, fdv, dt, p, xt, ut):
    """Stage 2 state: ũ = u + Δt a (Coulomb-limited by fdv), x̃ = x + Δt u (mirrored at the wall)."""
    for i in range(x.shape[0]):
        if V[i] > 0.0:
            ut[i] = coulomb_update(u[i] + dt * a[i], fdv[i])
            xt[i] = x[i] + dt * u[i]
            if p.back_wall and xt[i] < 0.0:
                xt[i] = -xt[i]
        else:
            ut[i] = 0.0
            xt[i] = x[i]


@njit(cache=True)
def corrector(x, u, V, a1, S1, S2, fr, dt, p, new):
    """Eqs 30, 33, 31: u^{n+1} = u + ½Δt (a₁ + a₂) under the Heun friction budget (+ eq 12),
    x^{n+1} = x + Δt (½(u + u^{n+1}) + δ XSPH), into new = (x^{n+1}, u^{n+1}); S1, S2: the two
    stages. Returns (status, sorted index of the offending particle or −1): NONFINITE, or ESCAPED
    below x_min / above x_max."""
    xn, un = new
    fc1 = S1[S_FC]
    dh2, gb2, xs2, gs2, gc2, fc2, k2 = S2[S_DH], S2[S_GB], S2[S_XS], S2[S_GS], S2[S_GC], S2[S_FC], S2[S_K]
    for i in range(x.shape[0]):
        if V[i] <= 0.0:
            un[i] = 0.0
            xn[i] = x[i]
            continue
        a2 = driving_acceleration(gs2[i], k2[i], gc2[i], dh2[i], gb2[i])
        budget = heun_friction_budget(dt, fc1[i], fc2[i])
        if p.eq12 and fr[i] > 0.0:
            budget += deposition_velocity_loss(p.g, p.tan_phi_internal, fr[i], dt)
        un[i] = coulomb_update(u[i] + 0.5 * dt * (a1[i] + a2), budget)
        xn[i] = x[i] + dt * (0.5 * (u[i] + un[i]) + p.xsph_delta * xs2[i])
        if p.back_wall and xn[i] < 0.0:
            xn[i] = -xn[i]
            if un[i] < 0.0:
                un[i] = 0.0
        if not (math.isfinite(xn[i]) and math.isfinite(un[i])):
            return NONFINITE, i
        if xn[i] > p.x_max or xn[i] < p.x_min:
            return ESCAPED, i
    return RUNNING, -1


@njit(cache=True)
def mark_envelopes(env, x0, x1, h, u, V, t, dxg, thr):
    """Along-path envelopes: every grid cell between a particle's old and new position gets
    max depth, max |u|, and the first time a particle at least ``thr`` deep passed it
    (a zero-width ``env``: no envelopes)."""
    ng = env.shape[1]
    if ng == 0:
        return
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
def deposit_with_width(dep, depb, binv, xp, dv, dxg):
    """``sph.deposit_to_grid`` for both the cell volumes and volume/b (same weights)."""
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


# ----------------------------------------------------------------------------------------------
# a particle's own deposit (deposition.own_deposit: exclude; docs/da-engineer-scale.md)
# ----------------------------------------------------------------------------------------------

#: cells of its own deposit each particle remembers (ring buffer); older ones count as others' deposit
OWN_SLOTS = 64
#: a new deposit in one of the last OWN_MATCH slots' cells is added to that slot
OWN_MATCH = 3


def own_trail(n: int, enabled: bool = True) -> np.ndarray:
    """The per-particle record of its own deposit, indexed by particle id: row [count, cells (K),
    bed amounts (K)], K = ``OWN_SLOTS``; a (0, 0) array when the own deposit is not excluded."""
    return np.zeros((n, 1 + 2 * OWN_SLOTS)) if enabled else np.zeros((0, 0))


@njit(cache=True, inline="always")
def own_add(own, pid, cell, amount):
    """Book ``amount`` (the bed quantity put into grid cell ``cell``) as particle pid's own deposit."""
    K = OWN_SLOTS
    cnt = int(own[pid, 0])
    for back in range(1, min(cnt, OWN_MATCH) + 1):
        slot = (cnt - back) % K
        if own[pid, 1 + slot] == cell:
            own[pid, 1 + K + slot] += amount
            return
    slot = cnt % K
    own[pid, 1 + slot] = cell
    own[pid, 1 + K + slot] = amount
    own[pid, 0] = cnt + 1


@njit(cache=True)
def own_book(own, pid, xp, dv, binv, has_width, ng, dxg):
    """The cells and amounts ``sph.deposit_to_grid`` / ``deposit_with_width`` put on the bed grid
    for volume dv at xp, booked as pid's own deposit (same weights, so the exclusion is exact)."""
    s = xp / dxg - 0.5
    k = int(math.floor(s))
    if k < 0:
        own_add(own, pid, 0, dv * binv[0] if has_width else dv)
    elif k >= ng - 1:
        own_add(own, pid, ng - 1, dv * binv[ng - 1] if has_width else dv)
    else:
        a = dv * (1.0 - (s - k))
        own_add(own, pid, k, a * binv[k] if has_width else a)
        own_add(own, pid, k + 1, (dv - a) * binv[k + 1] if has_width else dv - a)


@njit(cache=True)
def exclude_own_deposit(x, V, order, own, dxg, L, qc, wall, gb):
    """gb (= −∂h_D/∂s from ``sph.deposit_gradient``) without each particle's own deposit: adds back
    Σ_own dep_k ∇W(x_i − x_k) over the remembered cells, mirrored at the wall like the full sum."""
    K = OWN_SLOTS
    norm = kernel_norm(L, qc)
    qc2 = qc * qc
    ec = math.exp(-qc2)
    g2 = 2.0 * norm / (L * L)
    radius = qc * L
    for i in range(x.shape[0]):
        if V[i] <= 0.0:
            continue
        pid = order[i]
        cnt = int(own[pid, 0])
        if cnt == 0:
            continue
        xi = x[i]
        s = 0.0
        for slot in range(min(cnt, K)):
            amt = own[pid, 1 + K + slot]
            if amt == 0.0:
                continue
            xc = (own[pid, 1 + slot] + 0.5) * dxg
            r = xi - xc
            q2 = (r / L) ** 2
            if q2 < qc2:
                s += gauss_gradw_e(amt * g2, r, math.exp(-q2), ec)
            if wall and xi < radius:
                r = xi + xc
                q2 = (r / L) ** 2
                if q2 < qc2:
                    s += gauss_gradw_e(amt * g2, r, math.exp(-q2), ec)
        gb[i] += s


@njit(cache=True)
def commit(x, F, new, fr, D, p, order):
    """x, u ← new = (x^{n+1}, u^{n+1}); the deposited fraction of each particle's volume goes onto
    the grid D = (dep, depb, binv, own) (all of it below min_volume_fraction of the initial volume:
    the particle stops), booked in ``own`` (rows by particle id ``order[i]``) when the own deposit is
    excluded. Returns max |u|."""
    xn, un = new
    dep, depb, binv, own = D
    u = F[F_U]
    V = F[F_V]
    umax = 0.0
    for i in range(x.shape[0]):
        x[i] = xn[i]
        if V[i] <= 0.0:
            continue
        if fr[i] > 0.0:
            dv = fr[i] * V[i]
            rest = V[i] - dv
            if rest < p.min_volume_fraction * F[F_V0, i]:
                dv = V[i]
                rest = 0.0
                un[i] = 0.0
            V[i] = rest
            if own.shape[0] > 0:
                own_book(own, order[i], xn[i], dv, binv, p.has_width, dep.shape[0], p.dx_grid)
            if p.has_width:
                deposit_with_width(dep, depb, binv, xn[i], dv, p.dx_grid)
            else:
                deposit_to_grid(dep, xn[i], dv, p.dx_grid)
        u[i] = un[i]
        if V[i] > 0.0 and abs(un[i]) > umax:
            umax = abs(un[i])
    return umax


# ----------------------------------------------------------------------------------------------
# the step loop
# ----------------------------------------------------------------------------------------------

@njit(cache=True)
def advance(state, D, rec, t, t_target, p, tab, nsteps):
    """Step from t until t_target (exactly), rest, or a failure. Returns
    (t, nsteps, status, id of the offending particle or −1, L_s, Δt of the last step).

    state = (x, F, order): sorted particle state (``sph.F_*`` rows); D = (dep, depb, binv, own): the
    deposited volume per grid cell, deposit / width and 1/width per cell (``p.has_width``; otherwise
    unused), and ``own_trail`` (each particle's own deposit, excluded from its bed term) or a (0, 0)
    array; rec = (env, diag): (3, n_cells) envelopes or (3, 0), lift-off diagnostics (3,); p:
    ``StepParams``; tab: bed table (``path.N_TABLE`` rows over the stations)."""
    x, F, order = state
    dep, depb, binv, own = D
    env, diag = rec
    n = x.shape[0]
    qc = p.kernel_support
    wall = p.back_wall
    bed = p.deposition and p.deposit_as_bed
    bed_dep = depb if p.has_width else dep
    mine = bed and own.shape[0] > 0 and not p.own_deposit
    W = new_window(n)
    E = np.empty(0)
    S1, S2 = new_stage(n), new_stage(n)
    a1, ut, xt, un, xn = np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    new = (xn, un)
    fr, fdv = np.zeros(n), np.zeros(n)
    kp, ke = np.empty(n), np.empty(2 * n)
    strain = p.k_symmetric and p.k_strain > 0.0
    wf, ks = np.ones(n), np.empty(n)
    L = 0.0
    dt = 0.0
    while t < t_target:
        if nsteps >= p.max_steps:
            return t, nsteps, MAX_STEPS, -1, L, dt
        insertion_sort(x, F, order)
        L = smoothing_length(F, p)
        Ld = deposit_smoothing_length(L, p.dx_grid)
        u = F[F_U]
        V = F[F_V]
        # stage 1 at (x^n, u^n)
        E = evaluate_into(x, u, V, L, qc, wall, W, S1, E)
        if strain:
            strained_k(x, V, F[F_K], S1[S_DU], 0.0, tab, p, kp)
            strained_wave_factor(x, tab, p, wf)
            symmetric_pressure_gradient(x, L, qc, wall, W, E, kp, ke, S1)
        elif p.k_symmetric:
            particle_k(x, S1[S_DU], tab, p, kp)
            symmetric_pressure_gradient(x, L, qc, wall, W, E, kp, ke, S1)
        if bed:
            deposit_gradient(x, V, bed_dep, p.dx_grid, Ld, qc, wall, S1[S_GB])
            if mine:
                exclude_own_deposit(x, V, order, own, p.dx_grid, Ld, qc, wall, S1[S_GB])
        bed_terms(x, u, V, S1, tab, p, diag)
        store_depths(F, S1[S_H], S1[S_ND])
        dt = time_step(u, V, S1[S_H], S1[S_DU], L, p, wf)
        if not dt > 0.0:
            return t, nsteps, NONFINITE, -1, L, dt
        last = t + dt >= t_target
        if last:
            dt = t_target - t
        drive_and_deposition(x, u, V, S1, tab, p, dt, a1, fr, fdv)
        predictor(x, u, V, a1, fdv, dt, p, xt, ut)
        # stage 2 at (x̃, ũ)
        E = evaluate_into(xt, ut, V, L, qc, wall, W, S2, E)
        if strain:
            strained_k(xt, V, kp, S1[S_DU], dt, tab, p, ks)
            symmetric_pressure_gradient(xt, L, qc, wall, W, E, ks, ke, S2)
        elif p.k_symmetric:
            particle_k(xt, S2[S_DU], tab, p, kp)
            symmetric_pressure_gradient(xt, L, qc, wall, W, E, kp, ke, S2)
        if bed:
            deposit_gradient(xt, V, bed_dep, p.dx_grid, Ld, qc, wall, S2[S_GB])
            if mine:
                exclude_own_deposit(xt, V, order, own, p.dx_grid, Ld, qc, wall, S2[S_GB])
        bed_terms(xt, ut, V, S2, tab, p, diag)
        status, i = corrector(x, u, V, a1, S1, S2, fr, dt, p, new)
        if status != RUNNING:
            return t, nsteps, status, order[i], L, dt
        if strain:  # k^{n+1}: the Heun mean of the two stages' strain rates
            stage_mean(S1[S_DU], S2[S_DU], ks)
            strained_k(xn, V, kp, ks, dt, tab, p, F[F_K])
        t_new = t_target if last else t + dt
        mark_envelopes(env, x, xn, S1[S_H], un, V, t_new, p.dx_grid, p.front_threshold)
        umax = commit(x, F, new, fr, D, p, order)
        t = t_new
        nsteps += 1
        if umax < p.u_rest:
            return t, nsteps, AT_REST, -1, L, dt
    return t, nsteps, RUNNING, -1, L, dt
