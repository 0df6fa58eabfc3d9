"""DA SPH time stepping (Sections 2.3–2.4, Fig 4): numba step kernels and the Python driver.

Per step (``advance`` runs many steps inside numba):

1. sort particles by x (insertion sort), smoothing length L_s from eq 25 (generalised: B over the
   mean particle number density Σ_j W_ij, which equals eq 25 for equal volumes and stays finite as
   deposition empties particles) or fixed;
2. stage 1 at (x^n, u^n): depth eq 20 (with mirror ghosts at the back wall), depth gradient
   eqs 21–22, velocity divergence eqs 28–29 (sign of eq 29 corrected), XSPH sum eq 33;
   driving acceleration g sinθ − k g cosθ ∂h/∂x (eqs 11/27, k from eqs 8–9);
   deposition rate (eqs 14, 34, 36) and the eq 12 momentum loss;
3. Δt from eq 32 (CFL);
4. predictor ũ = u^n + Δt a^n (Coulomb-limited), x̃ = x^n + Δt u^n;
5. stage 2 at (x̃, ũ): a^{n+1};
6. RK2 eqs 30–31: u^{n+1} = u^n + Δt/2 (a^n + a^{n+1}) with Coulomb friction applied as a
   velocity budget that stops but never reverses; XSPH correction eq 33; x^{n+1} = x^n + Δt/2 (u^n + u^{n+1});
7. deposition: the volume fraction −S_D Δt / h leaves each particle into the fixed grid (linear
   weights to the two nearest cells), so flowing + deposited volume is conserved to round-off.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numba import njit

from .kernels import gauss_w, kernel_norm
from .neighbours import build_extended, count_ghosts, insertion_sort, windows
from .physics import (alpha_coefficient, coulomb_update, critical_momentum, deposition_rate,
                      earth_pressure, net_acceleration)

# rows of the per-particle state matrix F (sorted order; x is kept separately)
F_U, F_V, F_V0, F_ND, F_H = 0, 1, 2, 3, 4
N_FIELDS = 5

# indices of the parameter vector
(P_G, P_SIN, P_COS, P_FRIC, P_KACT, P_KPASS, P_CFL, P_DELTA, P_QC, P_BSM, P_LFIX, P_WALL, P_XMAX,
 P_UREST, P_DEP, P_A, P_B, P_SCALE, P_L0, P_XINF, P_CLAMP, P_UMIN, P_MOM, P_TANI, P_MINV, P_DXG,
 P_MAXSTEPS, P_BED) = range(28)
N_PARAMS = 28

# fast-math for the pair passes WITHOUT 'reassoc': re-associated (vectorised) sums depend on the
# alignment of the pair buffer and made two identical runs differ in the last bit.
FASTMATH = {"nsz", "arcp", "contract", "afn"}

# the Shepard sum of eq 22 is floored: a nearly emptied particle (deposition) at the edge of a full
# particle's kernel has Σ V_j/h_j W_ij ≪ 1, and dividing by it gave accelerations of ~100 m/s² that
# shot such particles out of the domain. Full or half support gives Σ ≈ 1 or ≥ 0.5: unaffected.
SHEPARD_FLOOR = 0.5

# status codes returned by ``advance``
RUNNING, AT_REST, NONFINITE, ESCAPED, MAX_STEPS = 0, 1, 2, 3, 4


@njit(cache=True, fastmath=FASTMATH)
def depth_pass(xe, Ve, m, n, lo, hi, L, norm, qc, h, nd, E):
    """Eq 20, h_i = Σ_j V_j W_ij, and the number density Σ_j W_ij over particles with volume.
    Stores e^{−q²} of every pair in E (window of i at E[lo_i − lo_0 + …], see ``pair_offsets``)
    so the gradient pass needs no second exponential."""
    qc2 = qc * qc
    ec = math.exp(-qc2)
    p = 0
    for i in range(n):
        xi = xe[m + i]
        s = 0.0
        c = 0.0
        for j in range(lo[i], hi[i]):
            q2 = ((xi - xe[j]) / L) ** 2
            e = math.exp(-q2) if q2 < qc2 else 0.0
            E[p] = e
            p += 1
            vj = Ve[j]
            if vj > 0.0 and e > 0.0:
                w = norm * (e - ec * (1.0 + qc2 - q2))
                s += vj * w
                c += w
        h[i] = s
        nd[i] = c


@njit(cache=True, fastmath=FASTMATH)
def gradient_pass(xe, ue, Ve, he, m, n, lo, hi, L, norm, qc, E, dhdx, dudx, xsph):
    """Eqs 21–22 (∂h/∂x), eqs 28–29 (∂u/∂x, eq 29's sign corrected) and the XSPH sum of eq 33.

    With eq 24's ∇W_ij = 2 r_ij/L² W'_ij = −∂W_ij/∂x_i (r_ij = x_i − x_j, ``kernels.gauss_gradw``):
    ∂h/∂x_i = Σ V_j B1 ∇W_ij, B1 = −[Σ V_j/h_j W_ij]⁻¹ (as printed);
    ∂u/∂x_i = Σ V_j (u_j − u_i) B2 ∇W_ij, B2 = +[Σ V_j (x_j − x_i) ∇W_ij]⁻¹ (printed with a minus,
    which returns −∂u/∂x). Both are exact for linear fields where the kernel support is full; B2 is
    exact for a linear u everywhere. E holds e^{−q²} of every pair from ``depth_pass``.
    """
    qc2 = qc * qc
    ec = math.exp(-qc2)
    g2 = 2.0 * norm / (L * L)
    p = 0
    for i in range(n):
        k = m + i
        if Ve[k] <= 0.0:
            dhdx[i] = 0.0
            dudx[i] = 0.0
            xsph[i] = 0.0
            p += hi[i] - lo[i]
            continue
        xi = xe[k]
        ui = ue[k]
        hi_ = he[k]
        shep = 0.0
        gh = 0.0
        num = 0.0
        den = 0.0
        xs = 0.0
        for j in range(lo[i], hi[i]):
            e = E[p]
            p += 1
            vj = Ve[j]
            if vj <= 0.0 or e == 0.0:
                continue
            r = xi - xe[j]
            q2 = (r / L) ** 2
            w = norm * (e - ec * (1.0 + qc2 - q2))
            gw = g2 * r * (e - ec)
            hj = he[j]
            if hj > 0.0:
                shep += vj / hj * w
            gh += vj * gw
            du = ue[j] - ui
            num += vj * du * gw
            den -= vj * r * gw
            xs += 2.0 * vj / (hi_ + hj) * du * w
        dhdx[i] = -gh / max(shep, SHEPARD_FLOOR)
        dudx[i] = num / den if den != 0.0 else 0.0
        xsph[i] = xs


@njit(cache=True)
def evaluate(x, u, V, L, qc, wall, xe, ue, Ve, he, lo, hi, h, nd, dhdx, dudx, xsph):
    """Depth, gradients and XSPH sum of all particles at positions x (sorted) and velocities u."""
    n = x.shape[0]
    radius = qc * L
    norm = kernel_norm(L, qc)
    m = count_ghosts(x, radius, wall)
    build_extended(x, u, V, m, xe, ue, Ve)
    ne = m + n
    windows(xe, m, ne, radius, lo, hi)
    npairs = 0
    for i in range(n):
        npairs += hi[i] - lo[i]
    E = np.empty(npairs)
    depth_pass(xe, Ve, m, n, lo, hi, L, norm, qc, h, nd, E)
    for k in range(m):
        he[k] = h[m - 1 - k]
    for i in range(n):
        he[m + i] = h[i]
    gradient_pass(xe, ue, Ve, he, m, n, lo, hi, L, norm, qc, E, dhdx, dudx, xsph)


@njit(cache=True)
def particle_depths(x, V, L, qc, wall):
    """Eq 20 at the (sorted) particle positions."""
    n = x.shape[0]
    xe = np.empty(2 * n)
    ue = np.zeros(2 * n)
    Ve = np.empty(2 * n)
    lo = np.empty(n, np.int64)
    hi = np.empty(n, np.int64)
    h = np.empty(n)
    nd = np.empty(n)
    radius = qc * L
    m = count_ghosts(x, radius, wall)
    build_extended(x, np.zeros(n), V, m, xe, ue, Ve)
    windows(xe, m, m + n, radius, lo, hi)
    npairs = 0
    for i in range(n):
        npairs += hi[i] - lo[i]
    depth_pass(xe, Ve, m, n, lo, hi, L, kernel_norm(L, qc), qc, h, nd, np.empty(npairs))
    return h


@njit(cache=True)
def grid_depth(x, V, L, qc, wall, dxg, ng):
    """Eq 20 evaluated at the cell centres (k + ½) dxg of the fixed grid (scatter, window per particle)."""
    out = np.zeros(ng)
    norm = kernel_norm(L, qc)
    radius = qc * L
    for j in range(x.shape[0]):
        vj = V[j]
        if vj <= 0.0:
            continue
        for mirror in range(2):
            if mirror == 1 and (not wall or x[j] >= radius):
                continue
            xj = x[j] if mirror == 0 else -x[j]
            k0 = max(0, int(math.floor((xj - radius) / dxg)))
            k1 = min(ng - 1, int(math.floor((xj + radius) / dxg)) + 1)
            for k in range(k0, k1 + 1):
                out[k] += vj * gauss_w((k + 0.5) * dxg - xj, L, norm, qc)
    return out


@njit(cache=True, inline="always")
def deposit_to_grid(dep, xp, dv, dxg):
    """Put volume dv at position xp onto the grid: linear weights to the two nearest cell centres."""
    ng = dep.shape[0]
    s = xp / dxg - 0.5
    k = int(math.floor(s))
    if k < 0:
        dep[0] += dv
    elif k >= ng - 1:
        dep[ng - 1] += dv
    else:
        w = s - k
        a = dv * (1.0 - w)
        dep[k] += a
        dep[k + 1] += dv - a


@njit(cache=True)
def deposit_gradient(x, V, dep, dxg, L, qc, wall, out):
    """∂h_D/∂x at the particles: the deposit (cell depths dep/dxg at the cell centres) smoothed with
    the same kernel, ∂/∂x_i Σ_k h_D,k Δx W(x_i − x_k), mirrored at the wall like the particles."""
    ng = dep.shape[0]
    norm = kernel_norm(L, qc)
    radius = qc * L
    qc2 = qc * qc
    ec = math.exp(-qc2)
    g2 = 2.0 * norm / (L * L)
    for i in range(x.shape[0]):
        out[i] = 0.0
        if V[i] <= 0.0:
            continue
        xi = x[i]
        k0 = max(0, int(math.floor((xi - radius) / dxg)))
        k1 = min(ng - 1, int(math.floor((xi + radius) / dxg)) + 1)
        s = 0.0
        for k in range(k0, k1 + 1):
            if dep[k] == 0.0:
                continue
            r = xi - (k + 0.5) * dxg
            q2 = (r / L) ** 2
            if q2 < qc2:
                s += dep[k] * g2 * r * (math.exp(-q2) - ec)
        if wall and xi < radius:
            k1 = min(ng - 1, int(math.floor((radius - xi) / dxg)) + 1)
            for k in range(0, k1 + 1):
                if dep[k] == 0.0:
                    continue
                r = xi + (k + 0.5) * dxg
                q2 = (r / L) ** 2
                if q2 < qc2:
                    s += dep[k] * g2 * r * (math.exp(-q2) - ec)
        out[i] = -s


@njit(cache=True)
def smoothing_length(F, prm):
    """Eq 25 generalised: L_s = B N / Σ_i n_i with n_i = Σ_j W_ij over particles with volume (for equal
    volumes n_i = h_i/V_i, eq 25 exactly); or the fixed L_s."""
    if prm[P_LFIX] > 0.0:
        return prm[P_LFIX]
    s = 0.0
    c = 0
    for i in range(F.shape[1]):
        if F[F_V, i] > 0.0 and F[F_ND, i] > 0.0:
            s += F[F_ND, i]
            c += 1
    return prm[P_BSM] * c / s


@njit(cache=True)
def advance(x, F, order, dep, t, t_target, prm, nsteps):
    """Step from t until t_target (exactly), rest, or a failure. Returns
    (t, nsteps, status, index of the offending particle or −1, L_s, Δt of the last step)."""
    n = x.shape[0]
    g = prm[P_G]
    gsin = g * prm[P_SIN]
    gcos = g * prm[P_COS]
    fric = prm[P_FRIC]
    k_act = prm[P_KACT]
    k_pass = prm[P_KPASS]
    qc = prm[P_QC]
    wall = prm[P_WALL] > 0.5
    dep_on = prm[P_DEP] > 0.5
    eq12 = prm[P_MOM] > 0.5
    clamp = prm[P_CLAMP] > 0.5
    dxg = prm[P_DXG]
    maxsteps = int(prm[P_MAXSTEPS])
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
            deposit_gradient(x, V, dep, dxg, L, qc, wall, gb1)
        vmax = 0.0
        for i in range(n):
            F[F_H, i] = h1[i]
            if V[i] > 0.0:
                F[F_ND, i] = nd[i]
                c = max(abs(u[i]), math.sqrt(g * h1[i]))
                if c > vmax:
                    vmax = c
        dt = prm[P_CFL] * L / vmax
        last = t + dt >= t_target
        if last:
            dt = t_target - t
        # stage 1: driving acceleration; deposition rate and momentum loss (eqs 12, 14, 34, 36)
        for i in range(n):
            fr[i] = 0.0
            fdv[i] = fric * dt
            if V[i] <= 0.0:
                a1[i] = 0.0
                continue
            a1[i] = gsin - earth_pressure(du1[i], k_act, k_pass) * gcos * dh1[i] - gcos * gb1[i]
            if dep_on and h1[i] > 0.0:
                an = net_acceleration(a1[i], u[i], fric)
                au = abs(u[i])
                if u[i] != 0.0:
                    dhu = math.copysign(1.0, u[i]) * h1[i] * an - au * h1[i] * du1[i]
                else:
                    dhu = h1[i] * abs(an)
                huc = critical_momentum(x[i], prm[P_L0], prm[P_XINF], prm[P_A], prm[P_B], prm[P_SCALE], clamp)
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
            deposit_gradient(xt, V, dep, dxg, L, qc, wall, gb2)
        # corrector: eqs 30, 33, 31
        for i in range(n):
            if V[i] <= 0.0:
                un[i] = 0.0
                xn[i] = x[i]
                continue
            a2 = gsin - earth_pressure(du2[i], k_act, k_pass) * gcos * dh2[i] - gcos * gb2[i]
            un[i] = coulomb_update(u[i] + 0.5 * dt * (a1[i] + a2), fdv[i])
            xn[i] = x[i] + dt * (0.5 * (u[i] + un[i]) + prm[P_DELTA] * xs2[i])
            if wall and xn[i] < 0.0:
                xn[i] = -xn[i]
                if un[i] < 0.0:
                    un[i] = 0.0
            if not (math.isfinite(xn[i]) and math.isfinite(un[i])):
                return t, nsteps, NONFINITE, order[i], L, dt
            if xn[i] > prm[P_XMAX]:
                return t, nsteps, ESCAPED, order[i], L, dt
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
                deposit_to_grid(dep, xn[i], dv, dxg)
            u[i] = un[i]
            if V[i] > 0.0 and abs(un[i]) > umax:
                umax = abs(un[i])
        t = t_target if last else t + dt
        nsteps += 1
        if umax < prm[P_UREST]:
            return t, nsteps, AT_REST, -1, L, dt
    return t, nsteps, RUNNING, -1, L, dt


# ----------------------------------------------------------------------------------------------
# Python driver
# ----------------------------------------------------------------------------------------------

@dataclass
class RunRecord:
    """Everything a run produced, at the output times (arrays indexed by particle id)."""
    time: list = field(default_factory=list)
    x: list = field(default_factory=list)
    u: list = field(default_factory=list)
    h: list = field(default_factory=list)
    volume: list = field(default_factory=list)
    flow_depth: list = field(default_factory=list)
    deposit_depth: list = field(default_factory=list)
    front: list = field(default_factory=list)
    smoothing_length: list = field(default_factory=list)
    time_step: list = field(default_factory=list)
    steps: list = field(default_factory=list)
    x_edges: np.ndarray | None = None
    status: int = RUNNING
    message: str = ""
    n_steps: int = 0
    x_inf: float = float("nan")
    A: float = float("nan")
    B: float = float("nan")

    @property
    def final_front(self) -> float:
        return float(self.front[-1]) if self.front else float("nan")


@dataclass(frozen=True)
class Physics:
    """Run-level constants resolved from the config (radians, k coefficients, A/B, x∞)."""
    k_active: float
    k_passive: float
    deposition: bool
    A: float = 0.0
    B: float = 0.0
    x_inf: float = float("nan")


def parameter_vector(cfg, phys: Physics, n_grid: int) -> np.ndarray:
    """Pack the run constants into the float vector the numba kernels read."""
    from ..cases import G
    th = cfg.theta
    num, dep, mat = cfg.numerics, cfg.deposition, cfg.material
    prm = np.zeros(N_PARAMS)
    prm[P_G] = G
    prm[P_SIN] = math.sin(th)
    prm[P_COS] = math.cos(th)
    prm[P_FRIC] = G * math.cos(th) * math.tan(math.radians(mat.phi_basal_deg)) if num.basal_friction else 0.0
    prm[P_KACT] = phys.k_active
    prm[P_KPASS] = phys.k_passive
    prm[P_CFL] = num.cfl
    prm[P_DELTA] = num.xsph_delta
    prm[P_QC] = num.kernel_support
    prm[P_BSM] = num.smoothing_B
    prm[P_LFIX] = num.L_s if num.smoothing == "fixed" else 0.0
    prm[P_WALL] = 1.0 if cfg.geometry.back_wall else 0.0
    prm[P_XMAX] = cfg.geometry.domain_end
    prm[P_UREST] = num.u_rest
    prm[P_DEP] = 1.0 if phys.deposition else 0.0
    prm[P_A] = phys.A
    prm[P_B] = phys.B
    prm[P_SCALE] = cfg.p0 if dep.coefficient_units == "normalised" else 1.0
    prm[P_L0] = cfg.geometry.L0
    prm[P_XINF] = phys.x_inf if phys.deposition else cfg.geometry.L0 + 1.0
    prm[P_CLAMP] = 1.0 if dep.clamp_x else 0.0
    prm[P_UMIN] = dep.u_min
    prm[P_MOM] = 1.0 if dep.momentum_term == "eq12" else 0.0
    prm[P_TANI] = math.tan(math.radians(mat.phi_internal_deg))
    prm[P_MINV] = dep.min_volume_fraction
    prm[P_DXG] = cfg.output.dx_grid
    prm[P_MAXSTEPS] = float(num.max_steps)
    prm[P_BED] = 1.0 if dep.deposit_as_bed else 0.0
    return prm


def initial_state(cfg):
    """The column [0, L0] × [0, H0]: n equal particles at the centres of n equal cells."""
    n = cfg.numerics.n_particles
    dx = cfg.geometry.L0 / n
    x = (np.arange(n) + 0.5) * dx
    F = np.zeros((N_FIELDS, n))
    F[F_V] = cfg.geometry.H0 * dx
    F[F_V0] = F[F_V]
    F[F_ND] = 1.0 / dx  # number density of the lattice: first L_s = B dx (eq 25)
    order = np.arange(n, dtype=np.int64)
    return x, F, order


def custom_state(x, volume, u):
    """Any initial particle set (sorted positions x, volumes, velocities): for analytic checks."""
    x = np.array(x, dtype=float)
    n = x.shape[0]
    F = np.zeros((N_FIELDS, n))
    F[F_V] = volume
    F[F_V0] = volume
    F[F_U] = u
    F[F_ND] = (n - 1) / (x[-1] - x[0])
    return x, F, np.arange(n, dtype=np.int64)


def _grid(cfg):
    dxg = cfg.output.dx_grid
    ng = int(math.ceil(cfg.geometry.domain_end / dxg))
    return dxg, ng, np.arange(ng + 1) * dxg


def smooth_deposit(dep: np.ndarray, L: float, qc: float, dxg: float) -> np.ndarray:
    """Deposit depth h_D on the grid as an SPH estimate (eq 20 applied to deposited volume).

    ``dep`` holds the deposited volume per cell, put there at the depositing particle's position.
    Where the tip's particles are farther apart than the grid cells, that leaves empty cells
    between them: h + h_D then dips below the front threshold and the front jumps back although
    the material is still there (seen: 1D-A124 front 23 → 17 L0, and x∞ iterations that jump
    across the fixed point). The flow depth is a kernel estimate with smoothing length L_s, so the
    deposit is smoothed with the same Gaussian (cut at qc L_s, weights normalised on the grid) and
    reflected at the back wall x = 0: the deposited volume is conserved to round-off.
    """
    m = max(1, int(math.ceil(qc * L / dxg)))
    offs = np.arange(-m, m + 1) * dxg
    w = np.exp(-(offs / L) ** 2)
    w /= w.sum()
    padded = np.concatenate([dep[:m][::-1], dep, np.zeros(m)])
    return np.convolve(padded, w, mode="valid")[: dep.shape[0]] / dxg


def _record(rec, cfg, x, F, order, dep, t, L, dt, steps, dxg, ng, thr):
    from ..front import front_from_profile
    n = x.shape[0]
    qc = cfg.numerics.kernel_support
    wall = cfg.geometry.back_wall
    h = particle_depths(x, F[F_V], L, qc, wall)
    for name, vals in (("x", x), ("u", F[F_U]), ("h", h), ("volume", F[F_V])):
        arr = np.empty(n)
        arr[order] = vals
        getattr(rec, name).append(arr)
    flow = grid_depth(x, F[F_V], L, qc, wall, dxg, ng)
    depo = smooth_deposit(dep, L, qc, dxg)
    rec.flow_depth.append(flow)
    rec.deposit_depth.append(depo.copy())
    rec.front.append(front_from_profile(rec.x_edges, flow + depo, thr))
    rec.time.append(t)
    rec.smoothing_length.append(L)
    rec.time_step.append(dt)
    rec.steps.append(steps)


def simulate(cfg, phys: Physics, label: str = "", progress=None, init=None, checkpoint=None) -> RunRecord:
    """Run one DA simulation to rest (or t_end) and return its record.

    A failure (non-finite state, particle leaving the domain, step limit) stops the run: the record
    keeps every output written so far, with ``status`` and ``message`` saying when, at which step
    and where. ``checkpoint`` (``da.checkpoint``): its ``resume()`` gives the state to continue
    from (or None), and ``at_output(state_fn)`` is called after every output time.
    """
    dxg, ng, edges = _grid(cfg)
    prm = parameter_vector(cfg, phys, ng)
    thr = cfg.front_threshold
    dt_out, t_end = cfg.output.dt_output, cfg.numerics.t_end
    state = checkpoint.resume() if checkpoint is not None else None
    if state is not None:  # continue exactly where the checkpointed run stood after output k - 1
        x, F, order, dep, rec, t, steps, k = state
    else:
        x, F, order = initial_state(cfg) if init is None else custom_state(*init)
        dep = np.zeros(ng)
        rec = RunRecord(x_edges=edges, x_inf=phys.x_inf, A=phys.A, B=phys.B)
        L = smoothing_length(F, prm)
        _record(rec, cfg, x, F, order, dep, 0.0, L, 0.0, 0, dxg, ng, thr)
        t, steps = 0.0, 0
        k = 1
    while True:
        t_target = min(k * dt_out, t_end)
        t, steps, status, where, L, dt = advance(x, F, order, dep, t, t_target, prm, steps)
        if status in (RUNNING, AT_REST):
            _record(rec, cfg, x, F, order, dep, t, L, dt, steps, dxg, ng, thr)
        if progress is not None:
            progress(lambda: f"DA {label}: t = {t:.3f} s, step {steps}, front {rec.front[-1]:.4f} m, "
                             f"L_s = {L * 1e3:.2f} mm, dt = {dt:.2e} s")
        if status == AT_REST:
            rec.status, rec.message = AT_REST, f"at rest at t = {t:.4f} s after {steps} steps"
            break
        if status == NONFINITE or status == ESCAPED or status == MAX_STEPS:
            xs = np.empty_like(x)
            xs[order] = x
            where_txt = "" if where < 0 else f" particle {where} at x = {xs[where]:.4f} m"
            what = {NONFINITE: "non-finite velocity or position",
                    ESCAPED: f"a particle left the domain (x > x_max = {cfg.geometry.domain_end:.4g} m;"
                             f" raise geometry.x_max)",
                    MAX_STEPS: f"numerics.max_steps = {cfg.numerics.max_steps} reached"}[status]
            rec.status = status
            rec.message = f"DA run {label} stopped at t = {t:.5f} s, step {steps}: {what}{where_txt}"
            break
        if t >= t_end:
            rec.status, rec.message = RUNNING, f"not at rest at numerics.t_end = {t_end} s"
            break
        k += 1
        if checkpoint is not None:
            checkpoint.at_output(lambda: (x, F, order, dep, rec, t, steps, k))
    rec.n_steps = steps
    return rec
