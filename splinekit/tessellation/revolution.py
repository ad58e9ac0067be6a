"""Faces of revolution with a circular profile (sphere, torus pieces), recognised with exact maps.

A surface of revolution ``S(u, v)`` whose ``u``-isocurves are circles about one axis and whose
profile (the ``v``-isocurve at the start of ``u``) is a circle arc in a plane through the axis is,
with ``phi(u)`` and ``psi(v)`` the angles of its two exact circle maps (:class:`.arcs.CircleMap`)::

    S = O + z(psi) a + rho(psi) (cos(phi) e1 + sin(phi) e2)
    (rho, z)(psi) = (rho_c, z_c) + p (cos(psi) g1 + sin(psi) g2)

with ``a`` the axis, ``e1`` the profile plane's radial direction, ``p`` the profile radius and
``g1, g2`` the profile circle's frame in the ``(rho, z)`` half plane. A sphere has ``rho_c = 0``,
a torus ``rho_c`` its main radius. Spheres and tori written by OCC (``from_occ``) are such
tensor-product NURBS with ``u`` around the axis. :func:`revolution_of` recognises one and checks
the closed form against the surface's own evaluator on a grid; :class:`Revolutions` holds several
as flat arrays for one pass over all faces (points, normals, parameters at angles).
"""

from __future__ import annotations

import numpy as np

from .arcs import REL, CircleMaps, _dot, _norm

__all__ = ["Revolution", "Revolutions", "revolution_nets", "revolution_of"]

CHECK = 9
"""Grid of ``CHECK x CHECK`` parameters on which the closed form is checked against the surface."""


class Revolution:
    """One recognised face of revolution (see the module docstring): ``umap`` and ``vmap`` the
    exact angle maps of the ``u`` circle and of the profile; ``O, a, e1, e2`` ``(3,)``; ``rho_c,
    z_c, p`` floats; ``g1, g2`` ``(2,)`` (``(rho, z)`` components)."""

    __slots__ = ("umap", "vmap", "O", "a", "e1", "e2", "rho_c", "z_c", "p", "g1", "g2")


def revolution_nets(surface):
    """``((knots, P, W), (knots, P, W))`` of the two circles :func:`revolution_of` needs (the
    ``u`` isocurve at the middle ``v``; the profile, the ``v`` isocurve at the first ``u``), or
    None when ``surface`` is not rational biquadratic."""
    if surface.degree_u != 2 or surface.degree_v != 2 or surface.weights is None:
        return None
    (u0, u1), (v0, v1) = surface.domain
    kv = np.asarray(surface.knots_v)
    if kv.size == 6 and kv[0] == kv[2] and kv[3] == kv[5]:
        # one Bézier span in v (sphere and torus pieces): the middle isocurve is the de Casteljau
        # midpoint of the columns, exactly, without the general isocurve's ~0.1 ms per face
        H = np.asarray(surface.homogeneous_points)  # (nu, 3, 4)
        h = 0.25 * H[:, 0] + 0.5 * H[:, 1] + 0.25 * H[:, 2]
        middle = surface.knots_u, h[:, :3] / h[:, 3:], h[:, 3]
    else:
        c = surface.isocurve(v=0.5 * (v0 + v1))
        middle = c.knots, c.control_points, c.weights
    ku = np.asarray(surface.knots_u)
    if ku[2] == ku[0]:  # clamped: the isocurve at the first u is the first row of the net
        profile = surface.knots_v, np.asarray(surface.control_points)[0], np.asarray(surface.weights)[0]
    else:
        p = surface.isocurve(u=u0)
        profile = p.knots, p.control_points, p.weights
    return middle, profile


def revolution_of(surface, umap, vmap, scale):
    """``(r, u, v, X)``: the :class:`Revolution` ``r`` of ``surface`` (rational biquadratic) whose
    circles (:func:`revolution_nets`) have the maps ``umap`` and ``vmap`` (:class:`.arcs.CircleMap`
    or None), and its closed form's points ``X`` ``(n, 3)`` at a grid of parameters ``u, v``
    ``(n,)``, which the caller checks against the surface's own evaluator (for several faces in
    one batch); None when it is not one with ``rho >= 0`` on its domain."""
    if umap is None or vmap is None:
        return None
    (u0, u1), (v0, v1) = surface.domain
    c, pc = umap.circle, vmap.circle
    r = Revolution()
    r.umap, r.vmap = umap, vmap
    r.O, r.a, r.e1, r.e2 = c.centre, c.normal, c.e1, c.e2
    d = pc.centre - r.O
    r.rho_c, r.z_c, r.p = float(d @ r.e1), float(d @ r.a), float(pc.radius)
    r.g1 = np.array([pc.e1 @ r.e1, pc.e1 @ r.a])
    r.g2 = np.array([pc.e2 @ r.e1, pc.e2 @ r.a])
    # the profile's plane must contain the axis: its frame has no e2 component
    if max(abs(d @ r.e2), abs(pc.e1 @ r.e2), abs(pc.e2 @ r.e2)) > REL * max(scale, 1.0):
        return None
    u = np.repeat(np.linspace(u0, u1, CHECK), CHECK)
    v = np.tile(np.linspace(v0, v1, CHECK), CHECK)
    psi = vmap.angle(v)
    rho = r.rho_c + r.p * (np.cos(psi) * r.g1[0] + np.sin(psi) * r.g2[0])
    if rho.min() < -REL * scale:
        return None
    return r, u, v, point(r, umap.angle(u), psi)


def point(r, phi, psi):
    """``(n, 3)`` points of one :class:`Revolution` at angles ``phi``, ``psi`` ``(n,)``."""
    cp, sp = np.cos(psi), np.sin(psi)
    rho = r.rho_c + r.p * (cp * r.g1[0] + sp * r.g2[0])
    z = r.z_c + r.p * (cp * r.g1[1] + sp * r.g2[1])
    return r.O + z[:, None] * r.a + rho[:, None] * (np.cos(phi)[:, None] * r.e1 + np.sin(phi)[:, None] * r.e2)


class Revolutions:
    """Several :class:`Revolution` as arrays indexed by ``q``: the ``u`` and profile maps as
    :class:`.arcs.CircleMaps` (``umaps``, ``vmaps``) and the frames."""

    __slots__ = ("umaps", "vmaps", "O", "a", "e1", "e2", "rho_c", "z_c", "p", "g1", "g2", "kappa_u", "kappa_v")

    def __init__(self, revs):
        self.umaps = CircleMaps([r.umap for r in revs])
        self.vmaps = CircleMaps([r.vmap for r in revs])
        for name in ("O", "a", "e1", "e2", "g1", "g2"):
            setattr(self, name, np.array([getattr(r, name) for r in revs]))
        for name in ("rho_c", "z_c", "p"):
            setattr(self, name, np.array([getattr(r, name) for r in revs], dtype=np.float64))
        self.kappa_u, self.kappa_v = self.umaps.kappa, self.vmaps.kappa

    def uv_of(self, q, X, line, arc):
        """``(n, k, 2)`` parameters of the points ``X`` ``(n, k, 3)`` of ``n`` edge uses on faces
        ``q`` ``(n,)``, each running straight in ``(u, v)`` along ``line`` ``(n, k, 2)`` (from its
        start to its end, at the samples' fractions of its pcurve's domain): along a parallel
        (``v`` constant) ``u`` from the angle about the axis, along a meridian (``u`` constant)
        ``v`` from the angle on the profile circle; a pole (``arc`` ``(n,)`` False) runs along
        ``line``. The ends are ``line``'s."""
        k = X.shape[1]
        out = np.array(line)
        uv0, uv1 = line[:, 0], line[:, -1]
        d = X - self.O[q][:, None]
        parallel = arc & (np.abs(uv1[:, 1] - uv0[:, 1]) <= np.abs(uv1[:, 0] - uv0[:, 0]))
        i = np.flatnonzero(parallel)
        if i.size:
            qi = q[i]
            phi = np.arctan2(_dot(d[i], self.e2[qi][:, None]), _dot(d[i], self.e1[qi][:, None]))
            out[i, :, 0] = self.umaps.param(np.repeat(qi, k), phi.ravel()).reshape(-1, k)
        i = np.flatnonzero(arc & ~parallel)
        if i.size:
            qi = q[i]
            a = self.a[qi][:, None]
            z = _dot(d[i], a)
            rho = _norm(d[i] - z[..., None] * a) - self.rho_c[qi][:, None]
            dz = z - self.z_c[qi][:, None]
            g1, g2 = self.g1[qi][:, None], self.g2[qi][:, None]
            psi = np.arctan2(rho * g2[..., 0] + dz * g2[..., 1], rho * g1[..., 0] + dz * g1[..., 1])
            out[i, :, 1] = self.vmaps.param(np.repeat(qi, k), psi.ravel()).reshape(-1, k)
        out[arc, 0], out[arc, -1] = uv0[arc], uv1[arc]
        return out

    def profile(self, q, psi):
        """``(rho, z, rho', z', rho'', z'')`` at profile angles ``psi`` of faces ``q`` (derivatives in ``psi``)."""
        cp, sp = np.cos(psi), np.sin(psi)
        g1, g2, p = self.g1[q], self.g2[q], self.p[q]
        rho = self.rho_c[q] + p * (cp * g1[:, 0] + sp * g2[:, 0])
        z = self.z_c[q] + p * (cp * g1[:, 1] + sp * g2[:, 1])
        drho, dz = p * (-sp * g1[:, 0] + cp * g2[:, 0]), p * (-sp * g1[:, 1] + cp * g2[:, 1])
        return rho, z, drho, dz, self.rho_c[q] - rho, self.z_c[q] - z

    def points(self, q, phi, psi):
        """``(n, 3)`` surface points of faces ``q`` at angles ``phi``, ``psi`` (all ``(n,)``)."""
        rho, z = self.profile(q, psi)[:2]
        c, s = np.cos(phi), np.sin(phi)
        return self.O[q] + z[:, None] * self.a[q] + rho[:, None] * (c[:, None] * self.e1[q] + s[:, None] * self.e2[q])

    def normals(self, q, phi, psi):
        """``(n, 3)`` unit normals along ``Su x Sv`` (``rho >= 0``; at ``rho = 0``, a pole, the
        limit along the profile) of faces ``q`` at angles ``phi``, ``psi``."""
        _, _, drho, dz = self.profile(q, psi)[:4]
        c, s = np.cos(phi), np.sin(phi)
        radial = c[:, None] * self.e1[q] + s[:, None] * self.e2[q]
        # Su x Sv is along t x (rho' r + z' a) = z' r - rho' a (t, r: tangent and radial of the u circle)
        return (dz[:, None] * radial - drho[:, None] * self.a[q]) / self.p[q][:, None]

    def evaluate(self, q, u, v):
        """``(n, 3)`` surface points of faces ``q`` at parameters ``u``, ``v``."""
        return self.points(q, self.umaps.angle(q, u), self.vmaps.angle(q, v))
