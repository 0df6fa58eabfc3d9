"""The particle state of one 2D ISPH run: positions, velocities, pressure and the per-particle fields,
the time and step counters, the energy budget, and the bookkeeping that moves rows: the renumbering
(:meth:`ParticleState._reorder`), the downstream outflow (:meth:`ParticleState._remove`) and the
checks that stop a run that blew up (:meth:`ParticleState._check`).

The step recipe (:class:`granudep.isph.stepper.IsphSolver`) extends this state with the scheme's
constants and stages; the time loop (:func:`granudep.isph.run.run`) advances it and takes snapshots.
"""
from __future__ import annotations

import math

import numpy as np

from ..cases import G
from ..progress import LOG
from .config import IsphConfig
from .energy import EnergyBudget, kinetic_energy, potential_energy
from .errors import IsphBlowUp
from .profile import front_position
from .setup import Particles, build_particles

#: the per-particle state besides the positions, one row per granular particle: what the renumbering
#: (:meth:`ParticleState._reorder`) permutes and the outflow (:meth:`ParticleState._remove`) filters
PARTICLE_FIELDS = ("u", "v", "p", "eta", "gdot", "fs", "p_rheo", "visc_du", "visc_dv", "ids", "wall_an")


class ParticleState:
    """The granular particles of one configuration (the walls are fixed: ``parts``) and what moves
    with them."""

    def __init__(self, cfg: IsphConfig, particles: Particles | None = None):
        self.cfg = c = cfg
        self.parts = particles if particles is not None else build_particles(cfg)
        P = self.parts
        self.nf = nf = P.nf
        self.x = P.x.copy()
        self.y = P.y.copy()
        self.u = np.zeros(nf)
        self.v = np.zeros(nf)
        th = c.theta
        self.gx = G * math.sin(th)
        self.gy = -G * math.cos(th)
        self.rho = c.material.rho
        self.dx = c.numerics.dx
        self.vol = self.dx * self.dx
        self.m = self.rho * self.vol
        self.period = c.geometry.periodic_length
        # lithostatic initial pressure (used by the rheology of the first step only)
        self.p = np.maximum(self.rho * G * math.cos(th) * (c.geometry.H0 - self.y[:nf]), 0.0)
        self.eta = np.full(nf, c.rheology.eta_max if c.rheology.model == "mu_i" else c.rheology.viscosity)
        self.gdot = np.zeros(nf)
        self.fs = np.zeros(nf, dtype=bool)
        self.t = 0.0
        self.step_no = 0
        self.dt = 0.0
        # domain box for escape checks
        self.xmin = -0.5 * self.dx if c.geometry.back_wall else -math.inf
        self.xmax = c.domain_length if self.period <= 0 else math.inf
        self.ymin = -0.5 * self.dx
        self.ymax = c.geometry.H0 + max(1.0, 5.0 * c.geometry.H0)
        # downstream outflow: particles past x = xmax leave the computation (see _check); the
        # state arrays then hold the n_active particles still in the domain, ``ids`` their
        # original indices; snapshots keep all n0 particles (those gone frozen where they left)
        self.outflow = bool(c.geometry.outflow) and self.period <= 0
        self.n0 = nf
        self.ids = np.arange(nf)
        self.outflow_time = np.full(nf, np.nan)
        self.exit_x = np.full(nf, np.nan)
        self.exit_y = np.full(nf, np.nan)
        self.outflow_log: list[tuple] = []      # (particle, t, step, y, speed) per departure
        # particle renumbering (:meth:`_reorder`) every ``reorder_interval`` steps; ``permuted``:
        # the arrays are no longer in the original order (``ids`` maps them back)
        self.reorder_interval = c.numerics.reorder_interval
        self.x_origin = float(self.x.min()) - 0.5 * self.dx
        self.permuted = False
        self.energy = EnergyBudget(
            e0=potential_energy(self.m, self.x[:nf], self.y[:nf], self.gx, self.gy),
            e_ref=max(self.m * G * math.cos(th) * float(np.sum(self.y[:nf])), 1e-300))
        self.e_mech = self.energy.e0
        self.nf_at_energy = nf

    def mechanical_energy(self) -> float:
        """E_kin + E_pot of the particles in the domain."""
        nf = self.nf
        return (kinetic_energy(self.m, self.u, self.v)
                + potential_energy(self.m, self.x[:nf], self.y[:nf], self.gx, self.gy))

    def _take_rows(self, index) -> None:
        """Permute (an index array) or filter (a mask) every per-particle array of PARTICLE_FIELDS
        present with one row per granular particle (the positions are handled by the callers)."""
        nf = self.nf
        for name in PARTICLE_FIELDS:
            a = getattr(self, name, None)
            if a is not None and np.ndim(a) >= 1 and a.shape[0] == nf:
                setattr(self, name, a[index])

    def _reorder(self) -> None:
        """Renumber the granular particles in natural order: columns of width dx (down-slope), by
        height within a column, as the initial lattice is numbered. The flow mixes the numbering,
        which slows the (M)IC preconditioner, the triangular sweeps and the neighbour loops
        (T22-A70 at 4 mm, mid-run: 4.47 -> 3.68 ms per step with a renumbering every 10 steps);
        numbering by the 2h cells of the neighbour search instead doubled the PPE iterations.
        Every per-particle array is permuted; ``ids`` keeps the original index of each particle
        (outputs are written in that order, see :meth:`full`)."""
        nf = self.nf
        col = np.floor((self.x[:nf] - self.x_origin) / self.dx)
        perm = np.lexsort((self.y[:nf], col))
        if np.array_equal(perm, np.arange(nf)):
            return
        self.x[:nf] = self.x[:nf][perm]
        self.y[:nf] = self.y[:nf][perm]
        self._take_rows(perm)
        self.permuted = True

    def _check(self) -> None:
        """NaN anywhere, or a particle through the bed, back wall or top: IsphBlowUp. A finite
        particle past the downstream end of the bed (x > domain_length) with ``geometry.outflow``
        leaves through the outflow (:meth:`_remove`), which is not a failure."""
        nf = self.nf
        bad = ~(np.isfinite(self.u) & np.isfinite(self.v) & np.isfinite(self.p))
        if bad.any():
            k = int(np.flatnonzero(bad)[0])
            raise IsphBlowUp(f"non-finite velocity/pressure at t={self.t:.5f} s, step {self.step_no}, "
                             f"particle {int(self.ids[k])} at (x, y) = ({self.x[k]:.4f}, {self.y[k]:.4f}) m")
        x, y = self.x[:nf], self.y[:nf]
        inside_y = (y >= self.ymin) & (y <= self.ymax)
        if self.outflow:
            gone = (x > self.xmax) & np.isfinite(x) & inside_y
            if gone.any():
                self._remove(gone)
                nf = self.nf
                x, y = self.x[:nf], self.y[:nf]
        out = (x < self.xmin) | (x > self.xmax) | (y < self.ymin) | (y > self.ymax) | ~np.isfinite(x) | ~np.isfinite(y)
        if out.any():
            k = int(np.flatnonzero(out)[0])
            x, y = x.copy(), y.copy()
            k_id = int(self.ids[k])
            raise IsphBlowUp(f"particle {k_id} left the domain at t={self.t:.5f} s, step {self.step_no}: "
                             f"(x, y) = ({x[k]:.4f}, {y[k]:.4f}) m outside x in [{self.xmin:.4f}, {self.xmax:.4f}],"
                             f" y in [{self.ymin:.4f}, {self.ymax:.4f}]")

    def _remove(self, gone: np.ndarray) -> None:
        """Take the granular particles ``gone`` (mask over the active ones) out of the computation:
        they passed the downstream end of the bed. Their exit time and place are kept; the wall
        particles (stored after the granular ones) are untouched."""
        nf = self.nf
        idx = np.flatnonzero(gone)
        keep = ~gone
        orig = self.ids[idx]
        self.outflow_time[orig] = self.t
        self.exit_x[orig] = self.x[idx]
        self.exit_y[orig] = self.y[idx]
        speed = np.hypot(self.u[idx], self.v[idx])
        self.energy.outflow += (kinetic_energy(self.m, self.u[idx], self.v[idx])
                                + potential_energy(self.m, self.x[idx], self.y[idx], self.gx, self.gy))
        for k, i in enumerate(orig):
            self.outflow_log.append((int(i), self.t, self.step_no, float(self.y[idx[k]]), float(speed[k])))
            if len(self.outflow_log) <= 20:
                LOG.warning("isph %s: particle %d left through the downstream outflow (x = %.3f m) at t=%.5f s, "
                            "step %d, y = %.4f m, speed %.3f m/s", self.cfg.case, i, self.xmax, self.t,
                            self.step_no, self.y[idx[k]], speed[k])
            elif len(self.outflow_log) == 21:
                LOG.warning("isph %s: further outflow departures are counted, not logged", self.cfg.case)
        self.x = np.concatenate([self.x[:nf][keep], self.x[nf:]])
        self.y = np.concatenate([self.y[:nf][keep], self.y[nf:]])
        self._take_rows(keep)
        self.nf = int(keep.sum())

    def full(self, a: np.ndarray, fill: float = 0.0) -> np.ndarray:
        """A per-particle array of the active particles spread over all n0 original particles
        (``fill`` for those gone through the outflow)."""
        if self.nf == self.n0 and not self.permuted:
            return a
        out = np.full(self.n0, fill, dtype=a.dtype)
        out[self.ids] = a
        return out

    @property
    def n_outflow(self) -> int:
        return self.n0 - self.nf

    def kinetic_energy(self) -> float:
        return float(0.5 * self.rho * self.vol * np.sum(self.u ** 2 + self.v ** 2))

    def mass_speed(self, front: float, measure: str = "rms") -> float:
        """Max or root-mean-square speed of the granular particles behind the front (x <= front)."""
        if self.nf == 0:
            return 0.0
        sel = self.x[:self.nf] <= front if math.isfinite(front) else np.ones(self.nf, bool)
        if not sel.any():
            sel = np.ones(self.nf, bool)
        sp2 = self.u[sel] ** 2 + self.v[sel] ** 2
        return float(np.sqrt(np.max(sp2) if measure == "max" else np.mean(sp2)))

    def max_speed(self) -> float:
        return float(np.sqrt(np.max(self.u ** 2 + self.v ** 2))) if self.nf else 0.0

    def front(self) -> float:
        """Front: granular particles binned into bed-parallel cells of width dx; cell depth =
        max y + dx/2 (0 if empty; gaps of <= 2 empty cells closed); then the shared front rule
        (first cell thinner than threshold)."""
        return front_position(self.x[:self.nf], self.y[:self.nf], self.dx, self.cfg.front_depth_threshold,
                              self.cfg.domain_length)
