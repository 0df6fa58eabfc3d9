"""The bed law: what the walls (bed and back wall) do to the granular particles.

One object, chosen once from ``cfg.wall`` (:func:`bed_law`), which the step asks for everything the
law decides:

- ``predictor_terms``: the increments it adds to the implicit viscous diagonals (the walls'
  traction), and the part of the diagonals that is the walls' own, booked as wall-friction
  dissipation (``wall_du``, ``wall_dv``);
- ``needs_contact(s)``: whether the geometry stage computes the wall contact for it;
- ``wall_norm(c, wall_ns)``: the lattice norm of the viscous wall stress for it (a Navier wall's own);
- ``needs_velocity_gradient``: whether the rheology stage computes ∇u for it when the rheology does not;
- ``after_projection(s, nb)``: a change it makes to the new velocity after the projection (the
  kinetic energy before it, booked by the step as the wall's work), or None.

The laws:

- :class:`ViscousWall` (``wall.slip``: ``no_slip``, ``navier``): the wall term of the viscous
  operator (already in its matrix; a Navier wall with its slip length in metres), with the μ(I)
  wall stress re-evaluated at the bed's normal stress where ``wall.bed_stress`` asks for it;
- :class:`FrictionWall` (``coulomb``, ``mu_w_i``, ``stress_limited``): a drag from the walls' normal
  reaction, or the Coulomb drag from the contact pressure, added to the diagonals;
- :class:`NavierOverwrite` (``navier_overwrite``): the authors' discrete slip, the first layer's
  velocity overwritten after the projection;
- :class:`NoWallTerm` (``free_slip``): nothing.

The kernels are in :mod:`.walls`. Adding a bed law: a class here (the hooks it needs), its name in
``walls.SLIP_CODES`` and ``wall.slip``'s choices (the config choice), one line in :func:`bed_law`,
and its tests.
"""
from __future__ import annotations

import numpy as np

from . import walls
from .energy import kinetic_energy
from .setup import lattice_constants


class NoWallTerm:
    """No wall term in the predictor, nothing after the projection."""

    #: the rheology stage computes ∇u for this law even when the rheology does not need it
    needs_velocity_gradient = False

    def needs_contact(self, s) -> bool:
        """The geometry stage computes the wall contact (``walls.wall_contact``) for this law."""
        return False

    def wall_norm(self, c, wall_ns: float) -> float:
        """The lattice norm of the viscous wall stress the viscous operator uses with this law
        (:func:`.setup.lattice_constants`): the no-slip one, ``wall_ns``."""
        return wall_ns

    def after_projection(self, s, nb):
        """A change to the new velocity (s.u, s.v) after the projection; returns the kinetic energy
        before it (the step books the change as the wall's work), or None when there is none."""
        return None

    def predictor_terms(self, s, nb, geo, dt: float, data, indptr, diag_v):
        """(diag_v, wall_du, wall_dv): the v diagonal and the walls' own diagonal increments (None:
        nothing to book). ``data``'s diagonal (u) and ``diag_v`` may be changed in place."""
        return diag_v, None, None


class FrictionWall(NoWallTerm):
    """Coulomb, μ_w(I) or stress-limited drag (``wall.slip``: coulomb, mu_w_i, stress_limited)."""

    def needs_contact(self, s) -> bool:
        """The Coulomb drag from the contact pressure (without the walls' reaction) reads the contact."""
        return not s.reaction_friction

    def predictor_terms(self, s, nb, geo, dt: float, data, indptr, diag_v):
        c, nf, rho = s.cfg, s.nf, s.rho
        diag_u = data[indptr[:-1]].copy()
        wall_du, wall_dv = diag_u.copy(), diag_v.copy()
        if s.reaction_friction:
            if s.wall_an is None or s.wall_an.shape[0] != nf:
                s.wall_an = np.zeros((nf, s.planes.shape[0]))
            self._reaction_drag(s, nb, dt, diag_u, diag_v)
        else:
            if c.wall.contact_length == "voronoi":
                clen = walls.contact_length(nb, nf, s.x, s.y, geo.contact, s.planes, s.dx)
            else:
                clen = np.full(geo.contact.shape, s.dx)
            walls.coulomb_wall_drag(nf, (s.u, s.v), s.p_rheo, geo.contact, geo.col, s.planes, (s.gx, s.gy),
                                    (s.mu_wall, rho, s.dx, dt, s.u_eps), (diag_u, diag_v), clen)
        data[indptr[:-1]] = diag_u
        wall_du = diag_u - wall_du
        wall_dv = diag_v - wall_dv
        return diag_v, wall_du, wall_dv

    def _reaction_drag(self, s, nb, dt: float, diag_u, diag_v) -> None:
        """The traction from the walls' normal reaction, added to the viscous diagonals
        (``wall.slip``: coulomb, mu_w_i or stress_limited; :mod:`.walls`)."""
        c, nf = s.cfg, s.nf
        if s.slip == walls.SLIP_COULOMB:
            walls.coulomb_drag_from_reaction(nf, s.u, s.v, s.wall_an, s.planes, s.mu_wall, dt,
                                             s.u_eps, diag_u, diag_v)
        elif s.slip == walls.SLIP_MU_W_I:
            m = c.material
            walls.mu_w_i_drag_from_reaction(nf, (s.u, s.v), s.wall_an, s.planes,
                                            (m.mu_s, m.mu_2, m.I0_standard, m.d, m.rho_s),
                                            (s.rho, s.dx, c.wall_shear_length, dt, s.u_eps), (diag_u, diag_v))
        else:
            kns = walls.viscous_wall_drag(nb, nf, (s.x, s.y), s.eta, s.wall_surface, s.planes, (walls.SLIP_NO, 0.0),
                                          (s.dx, s.rho, s.vol, s.eps2, s.lap_norm), s.wall_ns)
            walls.stress_limited_drag(nf, (s.u, s.v), kns, s.p_rheo, s.wall_an, s.planes,
                                      (s.mu_wall, s.dx, dt, s.rho, s.u_eps), (diag_u, diag_v))


class ViscousWall(NoWallTerm):
    """The viscous wall term of a no-slip or Navier wall (``wall.slip``: no_slip, navier), with the
    normal stress of the μ(I) wall stress chosen by ``wall.bed_stress``."""

    def __init__(self, navier: bool = False):
        self.navier = navier

    def wall_norm(self, c, wall_ns: float) -> float:
        """A Navier wall: the norm of its own linear profile u = y + slip_length, so that its stress is
        exact for that profile (no slip: ``wall_ns``)."""
        if not self.navier:
            return wall_ns
        return lattice_constants(c.numerics.h_factor, 0.01, c.wall_layers, c.wall.slip_length / c.numerics.dx)["wall_ns"]

    def predictor_terms(self, s, nb, geo, dt: float, data, indptr, diag_v):
        c, nf, rho = s.cfg, s.nf, s.rho
        # the viscous wall term's share of the diagonal (already in the matrix), for the booking
        kns = walls.viscous_wall_drag(nb, nf, (s.x, s.y), s.eta, s.wall_surface, s.planes,
                                      (s.slip, c.wall.slip_length), (s.dx, rho, s.vol, s.eps2, s.lap_norm),
                                      s.wall_norm)
        scale = None
        if (c.wall.bed_stress == "bed" and c.rheology.model == "mu_i" and s.reaction_friction
                and s.wall_an is not None and s.wall_an.shape[0] == nf):
            # the μ(I) wall stress at the bed's normal stress p_w = ρ a_n dx, not the first
            # layer's centre pressure (a sheet one particle thick held half its weight and slid on)
            pw = rho * s.wall_an * s.dx
            scale = np.where(s.wall_an > 0.0, np.maximum(pw / np.maximum(s.p_rheo, 1e-300)[:, None], 1.0), 1.0)
        elif (c.wall.bed_stress == "wall" and c.rheology.model == "mu_i" and s.reaction_friction
                and s.wall_an is not None and s.wall_an.shape[0] == nf):
            # the μ(I) stress evaluated at the wall itself: its normal stress p_w = ρ a_n dx and
            # its own shear rate γ̇_w = τ_w/η = ρ dx (k_i/η_i) |u_t| (the wall term's geometry),
            # so that τ_w = min(μ(I_w) p_w, η_max γ̇_w) whatever the particle's own strain rate
            m, rh = c.material, c.rheology
            pw = rho * s.wall_an * s.dx
            eta_i = np.maximum(s.eta[:nf], 1e-300)[:, None]
            ut = np.abs(np.outer(s.u[:nf], s.planes[:, 1]) - np.outer(s.v[:nf], s.planes[:, 0]))
            gw = rho * s.dx * (kns / eta_i) * ut
            iw = gw * m.d / np.sqrt(np.maximum(pw, 1e-300) / m.rho_s)
            muw = m.mu_s + (m.mu_2 - m.mu_s) * iw / (m.I0_standard + iw)
            eta_w = np.where(gw > 0.0, np.clip(muw * pw / np.maximum(gw, 1e-300), rh.eta_min, rh.eta_max), rh.eta_max)
            scale = np.where((s.wall_an > 0.0) & (kns > 0.0), eta_w / eta_i, 1.0)
        elif c.wall.bed_stress == "hydrostatic" and c.rheology.model == "mu_i":
            # the first layer's pressure extrapolated to the wall plane, p_w = p_i + ρ g_n d_i
            # (d_i: the particle's distance to the plane, g_n = max(−g·n, 0)): smooth in time
            gn = np.maximum(-(s.gx * s.planes[:, 0] + s.gy * s.planes[:, 1]), 0.0)
            dist = np.maximum(np.outer(s.x[:nf], s.planes[:, 0]) + np.outer(s.y[:nf], s.planes[:, 1])
                              - s.planes[:, 2], 0.0)
            pi = np.maximum(s.p_rheo, 1e-300)[:, None]
            scale = (pi + rho * gn * dist) / pi
        if scale is not None:
            extra = kns * (scale - 1.0)
            data[indptr[:-1]] += dt * (extra @ (s.planes[:, 1] ** 2))
            diag_v = diag_v + dt * (extra @ (s.planes[:, 0] ** 2))
            kns = kns * scale
        wall_du = dt * (kns @ (s.planes[:, 1] ** 2))
        wall_dv = dt * (kns @ (s.planes[:, 0] ** 2))
        return diag_v, wall_du, wall_dv


class NavierOverwrite(NoWallTerm):
    """The authors' slip (``wall.slip: navier_overwrite``): after the projection the first layer's
    velocity is replaced by slip_length (I − n n)·γ̇·n from uⁿ's gradient (explicit; unstable for a
    slip length above 2 dx)."""

    needs_velocity_gradient = True

    def after_projection(self, s, nb):
        if s.grad is None:
            return None
        ke = kinetic_energy(s.m, s.u, s.v)
        walls.navier_overwrite(nb, s.nf, s.grad, s.u, s.v, s.wall_surface, walls.OVERWRITE_BAND * s.dx,
                               s.cfg.wall.slip_length)
        return ke


def bed_law(slip: int) -> NoWallTerm:
    """The bed law of a ``walls.SLIP_CODES`` code."""
    if slip in walls.FRICTION_LAWS:
        return FrictionWall()
    if slip in (walls.SLIP_NO, walls.SLIP_NAVIER):
        return ViscousWall(navier=slip == walls.SLIP_NAVIER)
    if slip == walls.SLIP_NAVIER_OVERWRITE:
        return NavierOverwrite()
    return NoWallTerm()
