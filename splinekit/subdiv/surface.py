"""Limit surfaces of subdivision schemes.

:class:`SubdivisionSurface` wraps a control mesh and a scheme. It refines
(:meth:`refine`), gives exact limit positions and normals at the control
vertices from limit and tangent masks (:meth:`limit_points`,
:meth:`limit_normals`), evaluates the Catmull-Clark limit surface at
``(face, u, v)`` (:meth:`evaluate`) and converts it to bicubic patches
(:meth:`to_bsplines`).

Catmull-Clark evaluation: a quad whose four corners are smooth, interior and
of valence 4 is exactly the uniform bicubic B-spline patch of its 4 x 4
neighbourhood. Other quads are refined (the query descends into the quadrant
holding it) until it lands in such a patch; the irregular area shrinks 4x
per level. A query still irregular after ``max_level`` levels (within
``2**-max_level`` of an extraordinary vertex or a crease) is evaluated on the
sub-face's bicubic Coons patch, the same patch :meth:`to_bsplines` makes: it
interpolates the exact limit points at the sub-face's corners and edge
midpoints and shares its edges with the exact neighbouring patches, so the
evaluated surface is continuous; its error shrinks with the sub-face size
(measured in the tests). At every level, the queries still irregular go on
in the disjoint union of their faces' one-ring neighbourhoods (the limit
surface over a face depends on nothing else) whenever that union is smaller
than the level, so the refined area follows the queries: a point at an
extraordinary vertex stays irregular down to ``max_level``, and refining the
whole mesh for it would cost ``4**max_level`` times the mesh. ``max_level`` is
capped so that the whole mesh refined ``max_level + 1`` times would stay under
4 million faces; exact evaluation by Stam's eigen-analysis, which needs no
refinement, is not implemented.

Limit positions and normals at vertices come from the limit masks, which
apply once every sharpness at the vertex is 0 or infinite: a semi-sharp crease
of sharpness ``s`` changes the rules for ``ceil(s)`` levels. The limit of a
vertex depends only on its fan (the faces around it), so only the fans of the
vertices with semi-sharp features are refined, one level at a time, keeping
each child's fan (:func:`~splinekit.subdiv.fans.settled_fans`): the cost grows linearly with the
sharpness, where refining the whole mesh would grow it fourfold per unit.
"""

from __future__ import annotations

import math
from functools import cached_property

import numpy as np

from .. import limits
from .._validate import as_float_array, as_int
from ..basis.bernstein import all_bernstein
from ..errors import DomainError, MeshTopologyError, ParameterError
from ..mesh.polymesh import PolyMesh
from ..surfaces import BSplineSurface
from .fans import exact_limit_rows, fan_normals, mask_normals, neighbourhoods, settled_fans, unsettled_vertices
from .limit import limit_matrix
from .patches import (BSPLINE_TO_BEZIER, QUAD_C, QUAD_J, bezier_nets, coons_nets, eval_coons, eval_patches, patch_indices,
                      regular_faces)
from .refiner import BYTES_PER_CORNER, Refinement, scheme_named

# regular_faces, patch_indices and BSPLINE_TO_BEZIER live in splinekit.subdiv.patches; re-exported from here
__all__ = ["SubdivisionSurface", "regular_faces", "patch_indices", "BSPLINE_TO_BEZIER"]


class SubdivisionSurface:
    """The limit surface of a control mesh under a subdivision scheme.

    Parameters
    ----------
    mesh : PolyMesh
        The control mesh (3-D vertices for normals).
    scheme : ``"catmull-clark"``, ``"loop"`` or ``"doo-sabin"``
    creases, corners, boundary, crease_method
        As for :func:`splinekit.subdivide`.
    """

    def __init__(self, mesh: PolyMesh, scheme: str, creases=None, corners=None, boundary: str = "edge-and-corner",
                 crease_method: str = "uniform"):
        if not isinstance(mesh, PolyMesh):
            raise ParameterError(f"SubdivisionSurface expects a PolyMesh, got {type(mesh).__name__}")
        self.mesh = mesh
        self.scheme = scheme_named(scheme)
        self._options = dict(creases=creases, corners=corners, boundary=boundary, crease_method=crease_method)
        self._refinements: dict[int, Refinement] = {}
        self.refinement(0)  # validates creases, corners, boundary and the scheme's face type
        if self.scheme == "loop" and not mesh.is_triangle_mesh:
            raise MeshTopologyError("Loop subdivision needs a triangle mesh")

    def __repr__(self):
        return f"SubdivisionSurface({self.scheme}, {self.mesh!r})"

    # -- refinement -----------------------------------------------------------------------
    def refinement(self, levels: int) -> Refinement:
        """The (cached) :class:`Refinement` of the control mesh to ``levels``."""
        levels = as_int(levels, "levels", minimum=0)
        if levels not in self._refinements:
            self._refinements[levels] = Refinement(self.mesh, self.scheme, levels, **self._options)
        return self._refinements[levels]

    def refine(self, levels: int = 1) -> PolyMesh:
        """The control mesh subdivided ``levels`` times."""
        return self.refinement(levels).mesh(self.mesh.vertices)

    # -- limit masks ----------------------------------------------------------------------
    @cached_property
    def _mask_level(self) -> int:
        """Levels after which the limit masks apply everywhere: every finite
        sharpness has expired, and Catmull-Clark masks need quads. Used only by
        the fallback of :meth:`limit_normals` (vertices no mask covers); the
        masks themselves are applied per vertex (see :func:`settled_fans`)."""
        base = self.refinement(0)
        finite = np.concatenate([base.edge_sharpness[0], base.vertex_sharpness[0]])
        finite = finite[np.isfinite(finite)]
        levels = int(math.ceil(finite.max())) if finite.size else 0
        if self.scheme == "catmull-clark" and not self.mesh.is_quad_mesh:
            levels = max(levels, 1)
        return levels

    def _check_masks(self):
        if self.scheme == "doo-sabin":
            raise ParameterError("limit masks are implemented for catmull-clark and loop, not doo-sabin")

    @cached_property
    def limit_stencil(self):
        """Sparse ``(V, V)`` map from control vertices to their limit positions."""
        self._check_masks()
        r = self.refinement(0)
        return exact_limit_rows(r.hierarchy[0], self._options["crease_method"])

    def limit_points(self) -> np.ndarray:
        """Limit positions of the control vertices ``(V, dim)``."""
        return np.asarray(self.limit_stencil @ self.mesh.vertices)

    def limit_normals(self, levels: int = 3) -> np.ndarray:
        """Unit limit normals at the control vertices ``(V, 3)``.

        Smooth and dart vertices: exact, from the tangent masks. Crease,
        boundary and corner vertices: exact per sector between sharp edges
        (crease tangent and the across-tangent eigenvector of the sector's
        subdivision map, see :func:`splinekit.subdiv.limit.crease_normals`);
        where the surface has several sectors (an interior crease, a corner)
        the normalized sum of the sector normals. Any vertex neither covers
        (none in a manifold mesh) gets the area-weighted normal of its
        limit-point fan after ``levels`` further refinements.
        """
        self._check_masks()
        levels = as_int(levels, "levels", minimum=0)
        if self.mesh.vertices.shape[1] != 3:
            raise ParameterError("limit normals need 3-D vertices")
        V0 = self.mesh.n_vertices
        r = self.refinement(0)
        X = self.mesh.vertices
        base = r.hierarchy[0]
        n, ok = mask_normals(base, X)
        pending = np.flatnonzero(unsettled_vertices(base))
        if pending.size:
            # semi-sharp features (and non-quads): the masks apply once the fans are refined past them
            ok[pending] = False
            fans = settled_fans(base, self._options["crease_method"], pending, X)
            for fan, Y, centre, ids in fans:
                fn, fok = mask_normals(fan, Y)
                n[pending[ids]] = fn[centre]
                ok[pending[ids]] = fok[centre]
        if not ok.all():
            fine = self.refinement(self._mask_level + levels)
            P = limit_matrix(fine.finest) @ fine.apply(self.mesh.vertices)
            fan = fan_normals(fine.topology, P)
            n[~ok] = fan[:V0][~ok]
        length = np.linalg.norm(n, axis=1, keepdims=True)
        return np.divide(n, length, out=np.zeros_like(n), where=length > 0)

    # -- Catmull-Clark evaluation ---------------------------------------------------------------
    def _check_cc(self):
        if self.scheme != "catmull-clark":
            raise ParameterError(f"exact evaluation is implemented for catmull-clark, not {self.scheme}")

    EVAL_FACE_BUDGET = 4_000_000

    def _level_budget(self) -> int:
        """Most levels below the evaluation base that stay within EVAL_FACE_BUDGET faces
        if the whole mesh were refined (see the module docstring), and within the
        memory budget (:mod:`splinekit.limits`), so a deep evaluation or conversion
        asks for fewer levels rather than for more memory than the budget."""
        faces = self._level_data(self._eval_base_level)[0].n_faces
        affordable = limits.current_budget() / (4 * BYTES_PER_CORNER)
        cap = min(self.EVAL_FACE_BUDGET, affordable)
        return max(int(math.floor(math.log(max(cap / max(faces, 1), 1.0), 4))) - 1, 1)

    @cached_property
    def _eval_base_level(self) -> int:
        return 0 if self.mesh.is_quad_mesh else 1

    def _level_data(self, level: int):
        """Topology, vertices, regularity and sharpness of one level (cached)."""
        cache = self.__dict__.setdefault("_levels", {})
        if level not in cache:
            r = self.refinement(level)
            t = r.topology
            cache[level] = (t, r.apply(self.mesh.vertices), regular_faces(r.finest), r)
        return cache[level]

    def _limit_points(self, level: int, vertices: np.ndarray) -> np.ndarray:
        """Limit positions ``(k, dim)`` of ``vertices`` of refinement level ``level``.

        Computed for the vertices asked for only (and cached per level): a vertex on
        a semi-sharp crease needs its fan refined until the sharpness expires, so
        asking for the whole level would descend at every crease vertex of it.
        """
        cache = self.__dict__.setdefault("_limit_point_cache", {})
        t, X, _regular, r = self._level_data(level)
        if level not in cache:
            cache[level] = (np.zeros((t.n_vertices, X.shape[1])), np.zeros(t.n_vertices, dtype=bool))
        values, known = cache[level]
        vertices = np.asarray(vertices, dtype=np.int64)
        missing = np.unique(vertices[~known[vertices]])
        if missing.size:
            values[missing] = exact_limit_rows(r.finest, self._options["crease_method"], missing) @ X
            known[missing] = True
        return values[vertices]

    def evaluate(self, face, u, v, max_level: int = 8):
        """Limit points, first derivatives and unit normals at ``(face, u, v)``.

        ``face`` indexes the quads of the control mesh (of its first
        refinement when it has other polygons: quad ``c`` is the one at corner
        ``c`` of the flat face list); ``u, v`` in [0, 1] run along the face's
        first edge and back along its last edge. Returns ``(points, du, dv,
        normals)``, each ``(m, dim)`` (normals ``(m, 3)`` for 3-D meshes).
        """
        self._check_cc()
        max_level = min(as_int(max_level, "max_level", minimum=0), self._level_budget())
        base = self._eval_base_level
        t0 = self._level_data(base)[0]
        face = np.asarray(face)
        if face.size == 0:
            face = face.astype(np.int64)
        if face.dtype.kind not in "iu":
            raise ParameterError("face must hold integer face indices")
        face = face.astype(np.int64).ravel()
        u = as_float_array(u, "u", DomainError).ravel()
        v = as_float_array(v, "v", DomainError).ravel()
        try:
            face, u, v = np.broadcast_arrays(face, u, v)
        except ValueError:
            raise ParameterError("face, u and v must have the same length") from None
        if face.size and (face.min() < 0 or face.max() >= t0.n_faces):
            raise ParameterError(f"face index {int(face[(face < 0) | (face >= t0.n_faces)][0])} outside 0..{t0.n_faces - 1}")
        for name, x in (("u", u), ("v", v)):
            bad = ~((x >= 0) & (x <= 1))
            if bad.any():
                raise DomainError(f"{name} = {float(x[bad][0])!r} lies outside [0, 1]")
        P, Du, Dv = self._evaluate(face, u.astype(np.float64), v.astype(np.float64), max_level, base)
        normals = None
        if P.shape[1] == 3:
            nrm = np.cross(Du, Dv)
            length = np.linalg.norm(nrm, axis=1, keepdims=True)
            normals = np.divide(nrm, length, out=np.zeros_like(nrm), where=length > 0)
        return P, Du, Dv, normals

    def _evaluate(self, face, u, v, max_level, base, local=True):
        """Points and partials ``(m, dim)`` x 3 at ``(face, u, v)`` of level ``base``,
        descending at most ``max_level`` levels.

        With ``local``, the queries still irregular at a level are handed to a
        surface on the union of their faces' one-ring neighbourhoods (see
        :func:`~splinekit.subdiv.fans.neighbourhoods`) whenever that union is smaller than the level,
        so the descent refines only around the queries: a point at an
        extraordinary vertex never stops being irregular, and refining the
        whole mesh ``max_level`` (+ 1 for the Coons limit points) times for it
        costs ``4**max_level`` times the mesh.
        """
        m = face.size
        dim = self.mesh.vertices.shape[1]
        P = np.zeros((m, dim))
        Du = np.zeros((m, dim))
        Dv = np.zeros((m, dim))
        f, s, w = face.copy(), u.copy(), v.copy()
        J = np.broadcast_to(np.eye(2), (m, 2, 2)).copy()
        todo = np.arange(m)
        last = base + max_level
        for level in range(base, last + 1):
            t, X, regular, r = self._level_data(level)
            reg = regular[f]
            if reg.any():
                idx = todo[reg]
                p, ds, dt = eval_patches(t, X, f[reg], s[reg], w[reg])
                P[idx] = p
                Jr = J[reg]
                Du[idx] = ds * Jr[:, 0, 0, None] + dt * Jr[:, 1, 0, None]
                Dv[idx] = ds * Jr[:, 0, 1, None] + dt * Jr[:, 1, 1, None]
            keep = ~reg
            todo, f, s, w, J = todo[keep], f[keep], s[keep], w[keep], J[keep]
            if todo.size == 0:
                break
            found = None
            if level == last:
                found = eval_coons(self._limit_points, level, t, X, regular, f, s, w)
            elif local:
                # only with a level left below: the union's border faces are classified as
                # irregular, which matters for the Coons edges at its level 0 alone
                found = self._evaluate_in_neighbourhoods(t, X, r, f, s, w, last - level)
            if found is not None:
                p, ds, dt = found
                P[todo] = p
                Du[todo] = ds * J[:, 0, 0, None] + dt * J[:, 1, 0, None]
                Dv[todo] = ds * J[:, 0, 1, None] + dt * J[:, 1, 1, None]
                break
            # descend into the quadrant's child quad (child face = parent corner)
            q = np.where(s < 0.5, np.where(w < 0.5, 0, 3), np.where(w < 0.5, 1, 2))
            f = t.face_offsets[f] + q
            st = np.einsum("mij,mj->mi", QUAD_J[q], np.column_stack([s, w])) + QUAD_C[q]
            s, w = np.clip(st[:, 0], 0, 1), np.clip(st[:, 1], 0, 1)
            J = np.einsum("mij,mjk->mik", QUAD_J[q], J)
        return P, Du, Dv

    def _evaluate_in_neighbourhoods(self, t, X, r, face, u, v, levels):
        """Points and partials at ``(face, u, v)`` of level topology ``t`` (vertices
        ``X``, refinement ``r``), descending ``levels`` more levels on the disjoint
        union of the faces' one-ring neighbourhoods; None when that union is not
        smaller than ``t`` (refining the level itself is then no dearer)."""
        faces, where_face = np.unique(face, return_inverse=True)
        union = neighbourhoods(r.finest, X, faces, max_faces=t.n_faces - 1)
        if union is None:
            return None
        mesh, creases, corners, where = union
        inner = SubdivisionSurface(mesh, "catmull-clark", creases=creases, corners=corners, boundary="edge-only",
                                   crease_method=self._options["crease_method"])
        inner_levels = min(levels, inner._level_budget())
        return inner._evaluate(where[where_face.ravel()], u, v, inner_levels, 0, local=True)

    # -- conversion -------------------------------------------------------------------------
    def to_bsplines(self, levels: int = 2):
        """The Catmull-Clark limit surface as bicubic patches.

        Regular quads (of the control mesh, or of its first refinement when it
        has other polygons) become their exact bicubic patches. Irregular quads
        are refined ``levels`` more times; their regular sub-quads become exact
        patches too, and each sub-quad still irregular after that becomes a
        bicubic Coons patch of its four boundary curves. A boundary shared with
        an exact patch is that patch's exact edge, and any other boundary is the
        cubic through the limit points of its ends and its midpoint, so
        neighbouring patches always share their edges (C0; C2 between regular
        patches).

        Returns ``(patches, info)``: a list of clamped
        :class:`~splinekit.BSplineSurface` (Bézier form) and a dict with
        ``exact`` and ``approximate`` counts, per patch its ``kind``, ``level``,
        root ``face`` and the affine map ``(u, v) = axes @ (s, t) + origin`` from
        the patch's parameters to the root face's, and ``max_deviation``: the
        largest distance of the approximate patches from :meth:`evaluate`.
        """
        self._check_cc()
        levels = min(as_int(levels, "levels", minimum=0), self._level_budget() - 1)
        base = self._eval_base_level
        knots = np.array([0, 0, 0, 0, 1, 1, 1, 1], dtype=np.float64)
        nets, kinds, level_of, roots, maps = [], [], [], [], []
        active = np.arange(self._level_data(base)[0].n_faces)
        root = active.copy()
        A = np.broadcast_to(np.eye(2), (active.size, 2, 2)).copy()  # patch (s, t) -> root (u, v) = A (s, t) + b
        b = np.zeros((active.size, 2))
        for level in range(base, base + levels + 1):
            t, X, regular, r = self._level_data(level)
            reg = regular[active]
            last = level == base + levels
            take = np.ones_like(reg) if last else reg
            if reg.any():
                nets.append(bezier_nets(t, X, active[reg]))
            if last and (~reg).any():
                nets.append(coons_nets(self._limit_points, level, t, X, regular, active[~reg]))
            order = np.concatenate([np.flatnonzero(reg), np.flatnonzero(take & ~reg)])
            kinds += ["exact"] * int(reg.sum()) + ["coons"] * int((take & ~reg).sum())
            level_of += [level] * order.size
            roots.append(root[order])
            maps.append((A[order], b[order]))
            rest = np.flatnonzero(~reg)
            if rest.size == 0 or last:
                break
            # children of the irregular faces: one child quad per corner
            q = np.tile(np.arange(4), rest.size)
            parent = np.repeat(rest, 4)
            active = t.face_offsets[active[parent]] + q
            Jinv = np.linalg.inv(QUAD_J[q])
            A_parent = A[parent]
            b = b[parent] - np.einsum("mij,mjk,mk->mi", A_parent, Jinv, QUAD_C[q])
            A = np.einsum("mij,mjk->mik", A_parent, Jinv)
            root = root[parent]
        nets = np.concatenate(nets) if nets else np.zeros((0, 4, 4, self.mesh.vertices.shape[1]))
        patches = [BSplineSurface._trusted(3, 3, knots, knots, net, False) for net in nets]
        info = {
            "exact": kinds.count("exact"),
            "approximate": kinds.count("coons"),
            "kind": np.array(kinds),
            "level": np.array(level_of),
            "face": np.concatenate(roots),
            "axes": np.concatenate([m[0] for m in maps]),
            "origin": np.concatenate([m[1] for m in maps]),
        }
        info["max_deviation"] = self._patch_deviation(nets, info)
        return patches, info

    def _patch_deviation(self, nets, info, samples: int = 9) -> float:
        """Largest distance between the approximate patches (Bézier nets ``(n, 4, 4,
        dim)``) and :meth:`evaluate` on a ``samples x samples`` grid of each (0 when
        all patches are exact)."""
        approx = np.flatnonzero(info["kind"] == "coons")
        if approx.size == 0:
            return 0.0
        g = np.linspace(0, 1, samples)
        S, T = np.meshgrid(g, g, indexing="ij")
        st = np.column_stack([S.ravel(), T.ravel()])
        Bs, Bt = all_bernstein(3, st[:, 0]), all_bernstein(3, st[:, 1])  # (4, s*s) each
        pts = np.einsum("is,js,aijd->asd", Bs, Bt, nets[approx], optimize=True)  # (a, s*s, dim)
        uv = np.einsum("aij,sj->asi", info["axes"][approx], st) + info["origin"][approx][:, None, :]
        uv = np.clip(uv, 0.0, 1.0)
        face = np.repeat(info["face"][approx], st.shape[0])
        exact = self.evaluate(face, uv[..., 0].ravel(), uv[..., 1].ravel())[0]
        return float(np.linalg.norm(pts.reshape(exact.shape) - exact, axis=1).max())
