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
each child's fan (:func:`settled_fans`): the cost grows linearly with the
sharpness, where refining the whole mesh would grow it fourfold per unit.
"""

from __future__ import annotations

import math
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from .. import limits
from .._validate import as_float_array, as_int
from ..basis.bernstein import all_bernstein
from ..errors import DomainError, MeshTopologyError, ParameterError
from ..mesh.polymesh import PolyMesh
from ..mesh.topology import Topology, ranges
from .creases import SMOOTH, vertex_rules
from .limit import crease_normals, limit_matrix, tangent_matrices
from .refiner import BYTES_PER_CORNER, Refinement, scheme_named

__all__ = ["SubdivisionSurface", "regular_faces", "patch_indices", "BSPLINE_TO_BEZIER"]

# uniform cubic B-spline segment -> cubic Bézier control points
BSPLINE_TO_BEZIER = np.array([[1, 4, 1, 0], [0, 4, 2, 0], [0, 2, 4, 0], [0, 1, 4, 1]], dtype=np.float64) / 6.0

# parent (u, v) -> child (s, t) = J (u, v) + c for the quadrant at corner i
_QUAD_J = np.array([[[2, 0], [0, 2]], [[0, 2], [-2, 0]], [[-2, 0], [0, -2]], [[0, -2], [2, 0]]], dtype=np.float64)
_QUAD_C = np.array([[0, 0], [0, 2], [2, 2], [2, 0]], dtype=np.float64)


def regular_faces(t: Topology, edge_s: np.ndarray, vertex_s: np.ndarray) -> np.ndarray:
    """Mask ``(F,)`` of quads whose limit patch is a uniform bicubic B-spline:
    four interior, smooth (no sharp incident edge or vertex) corners of valence 4."""
    rule = vertex_rules(t, edge_s, vertex_s)
    good_vertex = (t.valence == 4) & (t.vertex_face_count == 4) & ~t.boundary_vertices & (rule == SMOOTH)
    good_corner = good_vertex[t.face_indices]
    ok = np.add.reduceat(good_corner.astype(np.int64), t.face_offsets[:-1]) if t.n_faces else np.zeros(0, int)
    return (t.face_sizes == 4) & (ok == 4)


def patch_indices(t: Topology, faces: np.ndarray) -> np.ndarray:
    """``(m, 4, 4)`` vertex indices of the B-spline control net of regular quads.

    Entry ``[a, b]``: ``a`` runs along the face's first edge (u), ``b`` along
    its last edge reversed (v); the face's corners sit at ``[1, 1], [2, 1],
    [2, 2], [1, 2]``.
    """
    src, nxt, prv, tw = t.face_indices, t.next_corner, t.prev_corner, t.twin
    base = t.face_offsets[faces]
    X, Y, D, Vc = [], [], [], []
    for k in range(4):
        h = base + k
        g = tw[h]
        X.append(src[nxt[nxt[g]]])
        Y.append(src[prv[g]])
        D.append(src[prv[tw[nxt[g]]]])
        Vc.append(src[h])
    P = np.empty((len(faces), 4, 4), dtype=np.int64)
    P[:, 0, 0], P[:, 1, 0], P[:, 2, 0], P[:, 3, 0] = D[0], X[0], Y[0], D[1]
    P[:, 0, 1], P[:, 1, 1], P[:, 2, 1], P[:, 3, 1] = Y[3], Vc[0], Vc[1], X[1]
    P[:, 0, 2], P[:, 1, 2], P[:, 2, 2], P[:, 3, 2] = X[3], Vc[3], Vc[2], Y[1]
    P[:, 0, 3], P[:, 1, 3], P[:, 2, 3], P[:, 3, 3] = D[3], Y[2], X[2], D[2]
    return P


def _cubic_bspline_basis(x: np.ndarray):
    """Uniform cubic B-spline basis on one span and its derivative: two ``(m, 4)`` arrays."""
    x2, x3 = x * x, x * x * x
    B = np.stack([(1 - x) ** 3, 3 * x3 - 6 * x2 + 4, -3 * x3 + 3 * x2 + 3 * x + 1, x3], axis=-1) / 6.0
    dB = np.stack([-3 * (1 - x) ** 2, 9 * x2 - 12 * x, -9 * x2 + 6 * x + 3, 3 * x2], axis=-1) / 6.0
    return B, dB


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
        return exact_limit_rows(r.topology, r.edge_sharpness[0], r.vertex_sharpness[0], self.scheme,
                                self._options["crease_method"])

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
        t, es, vs = r.topology, r.edge_sharpness[0], r.vertex_sharpness[0]
        n, ok = _mask_normals(t, X, es, vs, self.scheme)
        pending = np.flatnonzero(unsettled_vertices(t, es, vs, self.scheme))
        if pending.size:
            # semi-sharp features (and non-quads): the masks apply once the fans are refined past them
            ok[pending] = False
            fans = settled_fans(t, es, vs, self.scheme, self._options["crease_method"], pending, X)
            for topo, fes, fvs, Y, centre, ids in fans:
                fn, fok = _mask_normals(topo, Y, fes, fvs, self.scheme)
                n[pending[ids]] = fn[centre]
                ok[pending[ids]] = fok[centre]
        if not ok.all():
            fine = self.refinement(self._mask_level + levels)
            t = fine.topology
            L = limit_matrix(t, fine.edge_sharpness[-1], fine.vertex_sharpness[-1], self.scheme)
            P = L @ fine.apply(self.mesh.vertices)
            fan = _fan_normals(t, P)
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
            cache[level] = (t, r.apply(self.mesh.vertices), regular_faces(t, r.edge_sharpness[-1], r.vertex_sharpness[-1]), r)
        return cache[level]

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
        :func:`_neighbourhoods`) whenever that union is smaller than the level,
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
                p, ds, dt = _eval_patches(t, X, f[reg], s[reg], w[reg])
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
                found = _eval_coons(self, level, t, X, regular, f, s, w)
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
            st = np.einsum("mij,mj->mi", _QUAD_J[q], np.column_stack([s, w])) + _QUAD_C[q]
            s, w = np.clip(st[:, 0], 0, 1), np.clip(st[:, 1], 0, 1)
            J = np.einsum("mij,mjk->mik", _QUAD_J[q], J)
        return P, Du, Dv

    def _evaluate_in_neighbourhoods(self, t, X, r, face, u, v, levels):
        """Points and partials at ``(face, u, v)`` of level topology ``t`` (vertices
        ``X``, refinement ``r``), descending ``levels`` more levels on the disjoint
        union of the faces' one-ring neighbourhoods; None when that union is not
        smaller than ``t`` (refining the level itself is then no dearer)."""
        faces, where_face = np.unique(face, return_inverse=True)
        union = _neighbourhoods(t, X, r, faces, max_faces=t.n_faces - 1)
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
        from ..surfaces import BSplineSurface

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
                nets.append(_bezier_nets(t, X, active[reg]))
            if last and (~reg).any():
                nets.append(_coons_nets(self, level, t, X, regular, active[~reg]))
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
            Jinv = np.linalg.inv(_QUAD_J[q])
            A_parent = A[parent]
            b = b[parent] - np.einsum("mij,mjk,mk->mi", A_parent, Jinv, _QUAD_C[q])
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


def _neighbourhoods(t: Topology, X: np.ndarray, r: Refinement, faces: np.ndarray, max_faces: int | None = None):
    """The disjoint union of the one-ring neighbourhoods (all faces sharing a
    vertex) of the distinct ``faces``, as ``(mesh, edge sharpness, vertex
    sharpness, face_in_union)``; None when it would have more than
    ``max_faces`` faces.

    Under Catmull-Clark refinement the limit surface over a face depends only
    on this neighbourhood, at every level: so refining the (small) union
    instead of the whole mesh evaluates those faces exactly, to depths the
    whole mesh could not afford. The union's own borders are outside every
    queried face's neighbourhood, so their (boundary) rules do not matter.
    """
    offsets, vface = t.vertex_faces
    sizes = t.face_sizes[faces]
    owner = np.repeat(np.arange(faces.size), sizes)
    corners = ranges(t.face_offsets[faces], sizes)
    verts = t.face_indices[corners]
    counts = offsets[verts + 1] - offsets[verts]
    own = np.repeat(owner, counts)
    pos = ranges(offsets[verts], counts)
    pair = np.unique(own * t.n_faces + vface[pos])
    if max_faces is not None and pair.size > max_faces:
        return None
    own, g = pair // t.n_faces, pair % t.n_faces
    gs = t.face_sizes[g]
    cown = np.repeat(own, gs)
    cpos = ranges(t.face_offsets[g], gs)
    keys, new_index = np.unique(cown * t.n_vertices + t.face_indices[cpos], return_inverse=True)
    vertex = keys % t.n_vertices
    union_offsets = np.concatenate([[0], np.cumsum(gs)])
    topo = Topology(keys.size, new_index.ravel(), union_offsets, check=False)
    mesh = PolyMesh.from_topology(X[vertex], topo)
    base_edges = t.find_edges(vertex[topo.edges])
    creases = np.where(base_edges >= 0, r.edge_sharpness[-1][np.maximum(base_edges, 0)], 0.0)
    corners = r.vertex_sharpness[-1][vertex]
    where = np.flatnonzero(g == faces[own])
    return mesh, creases, corners, where


def _mask_normals(t: Topology, X: np.ndarray, edge_s: np.ndarray, vertex_s: np.ndarray, scheme: str):
    """Limit normals ``(V, 3)`` (not unit) where the tangent masks (smooth and dart
    vertices) or the crease sectors (see :func:`~splinekit.subdiv.limit.crease_normals`)
    give them, and the mask ``(V,)`` of those vertices; valid where every sharpness
    at the vertex is 0 or infinite."""
    T1, T2, ok = tangent_matrices(t, edge_s, vertex_s, scheme)
    n = np.cross(T1 @ X, T2 @ X)
    if not ok.all():
        cn, covered = crease_normals(t, X, edge_s, vertex_s, scheme)
        use = ~ok & covered
        n[use] = cn[use]
        ok = ok | covered
    return n, ok


def _fan_normals(t: Topology, P: np.ndarray) -> np.ndarray:
    """Sum over the faces at each vertex of the face's vector area (Newell), ``(V, 3)``."""
    a = P[t.face_indices]
    b = P[t.halfedge_dst]
    cross = np.cross(a, b)
    face_area = np.zeros((t.n_faces, 3))
    np.add.at(face_area, t.corner_face, cross)
    out = np.zeros((t.n_vertices, 3))
    np.add.at(out, t.face_indices, face_area[t.corner_face])
    return out


def _eval_patches(t, X, faces, u, v):
    """Points and (u, v) partials of regular patches at local parameters."""
    idx = patch_indices(t, faces)  # (m, 4, 4)
    net = X[idx]  # (m, 4, 4, dim)
    Bu, dBu = _cubic_bspline_basis(u)
    Bv, dBv = _cubic_bspline_basis(v)
    p = np.einsum("ma,mb,mabd->md", Bu, Bv, net)
    du = np.einsum("ma,mb,mabd->md", dBu, Bv, net)
    dv = np.einsum("ma,mb,mabd->md", Bu, dBv, net)
    return p, du, dv


def _limit_points(surface, level, vertices):
    """Limit positions ``(k, dim)`` of ``vertices`` of refinement level ``level``.

    Computed for the vertices asked for only (and cached per level): a vertex on
    a semi-sharp crease needs its fan refined until the sharpness expires, so
    asking for the whole level would descend at every crease vertex of it.
    """
    cache = surface.__dict__.setdefault("_limit_point_cache", {})
    t, X, _regular, r = surface._level_data(level)
    if level not in cache:
        cache[level] = (np.zeros((t.n_vertices, X.shape[1])), np.zeros(t.n_vertices, dtype=bool))
    values, known = cache[level]
    vertices = np.asarray(vertices, dtype=np.int64)
    missing = np.unique(vertices[~known[vertices]])
    if missing.size:
        L = exact_limit_rows(t, r.edge_sharpness[-1], r.vertex_sharpness[-1], surface.scheme,
                             surface._options["crease_method"], missing)
        values[missing] = L @ X
        known[missing] = True
    return values[vertices]


MAX_DESCENT = 128
"""Most levels a vertex's fan is refined for its semi-sharp features to expire. Past
that the fan has shrunk by at least ``0.7**128 < 1e-19`` of its size (the
subdominant eigenvalues of the Catmull-Clark and Loop smooth and crease-sector
maps are at most about 0.66), so the remaining finite sharpness is treated as
infinite: the difference is below rounding."""


def unsettled_vertices(t: Topology, edge_s: np.ndarray, vertex_s: np.ndarray, scheme: str) -> np.ndarray:
    """Mask ``(V,)`` of the vertices whose limit masks do not apply yet: a finite
    positive sharpness on the vertex or an incident edge (its rule will change),
    or, for Catmull-Clark, an incident face that is not a quad."""
    semi = (edge_s > 0) & np.isfinite(edge_s)
    out = np.bincount(t.edges[semi].ravel(), minlength=t.n_vertices) > 0
    out |= (vertex_s > 0) & np.isfinite(vertex_s)
    if scheme == "catmull-clark":
        odd = t.face_sizes[t.corner_face] != 4
        out[t.face_indices[odd]] = True
    return out & (t.vertex_face_count > 0)


def exact_limit_rows(t: Topology, edge_s: np.ndarray, vertex_s: np.ndarray, scheme: str,
                     crease_method: str = "uniform", vertices: np.ndarray | None = None):
    """Sparse ``(k, V)`` limit stencils of ``vertices`` (distinct; default all) of a
    mesh, semi-sharp features included.

    :func:`~splinekit.subdiv.limit.limit_matrix` rows where the masks apply
    (every sharpness at the vertex 0 or infinite); the rows of the other
    vertices come from :func:`descended_limit_rows`, which refines only their
    fans, so the cost grows linearly with the sharpness, not fourfold per unit.
    """
    vertices = np.arange(t.n_vertices) if vertices is None else np.asarray(vertices, dtype=np.int64)
    L = limit_matrix(t, edge_s, vertex_s, scheme)[vertices]
    pending = unsettled_vertices(t, edge_s, vertex_s, scheme)[vertices]
    if not pending.any():
        return L
    rows = descended_limit_rows(t, edge_s, vertex_s, scheme, crease_method, vertices[pending]).tocoo()
    keep = sp.diags((~pending).astype(np.float64)) @ L
    moved = sp.csr_matrix((rows.data, (np.flatnonzero(pending)[rows.row], rows.col)), shape=L.shape)
    return sp.csr_matrix(keep + moved)


def descended_limit_rows(t: Topology, edge_s: np.ndarray, vertex_s: np.ndarray, scheme: str, crease_method: str,
                         centres: np.ndarray):
    """Sparse ``(k, V)`` limit stencils of the vertices ``centres`` (distinct) of ``t``,
    from their fans refined until the masks apply (see :func:`settled_fans`)."""
    blocks, owners = [], []
    for topo, es, vs, W, centre, ids in settled_fans(t, edge_s, vertex_s, scheme, crease_method, centres):
        blocks.append(limit_matrix(topo, es, vs, scheme)[centre] @ W)
        owners.append(ids)
    order = np.argsort(np.concatenate(owners), kind="stable")
    return sp.csr_matrix(sp.vstack(blocks, format="csr")[order])


def settled_fans(t: Topology, edge_s: np.ndarray, vertex_s: np.ndarray, scheme: str, crease_method: str,
                 centres: np.ndarray, X: np.ndarray | None = None):
    """Refine the fans of the vertices ``centres`` (distinct, with faces) of ``t``
    until the limit masks apply at them.

    The limit position and tangents of a vertex depend only on its fan (the
    faces around it): the fan of its child is made of the child faces at it,
    whose corners (its vertex point, the edge points of its edges, the face
    points of its faces) come from the parent fan, and whose sharpness comes
    from its own edges (and, for Chaikin creases, the other edges at it). So
    each level refines the disjoint union of the fans still unsettled (see
    :func:`unsettled_vertices`) by one level and keeps only their child fans:
    ``ceil(s)`` levels of a few faces per vertex for sharpness ``s`` (at most
    :data:`MAX_DESCENT`), where refining the whole mesh would cost ``4**s``
    times the mesh. The union's outer border is in no centre's child fan, so
    the (boundary) rules there do not matter.

    Yields, level by level, ``(topology, edge sharpness, vertex sharpness, data,
    centre, ids)`` for the fans settled at that level: the union's topology and
    sharpness, ``data`` (see below) on the union's vertices, the settled
    centres' vertices in the union and their positions in ``centres``.
    Without ``X``, ``data`` is the sparse map from the vertices of ``t`` to the
    union's vertices. With positions ``X`` ``(V, dim)`` of ``t``, it is the
    union's positions relative to the centre of their fan: the fans shrink by
    half per level, and the tangents (differences of ring points) would drown
    in the rounding of absolute positions after a few dozen levels.
    """
    topo, vertex, centre, edge, fan = _vertex_fans(t, centres)
    es, vs = edge_s[edge], vertex_s[vertex]
    if X is None:
        data = sp.csr_matrix((np.ones(vertex.size), (np.arange(vertex.size), vertex)), shape=(vertex.size, t.n_vertices))
    else:
        data = X[vertex] - X[centres[fan]]
    ids = np.arange(centres.size)
    for depth in range(MAX_DESCENT):
        r = Refinement(topo, scheme, 1, creases=es, corners=vs, boundary="edge-only", crease_method=crease_method)
        topo, es, vs = r.topology, r.edge_sharpness[-1], r.vertex_sharpness[-1]
        data = sp.csr_matrix(r.stencils[0] @ data) if X is None else r.stencils[0] @ data
        # vertex points keep their parent's index: the centres are where they were
        done = ~unsettled_vertices(topo, es, vs, scheme)[centre]
        if depth == MAX_DESCENT - 1:
            done[:] = True
        if done.any():
            yield topo, es, vs, data, centre[done], ids[done]
        if done.all():
            return
        ids = ids[~done]
        topo, sub, centre, edge, fan = _vertex_fans(topo, centre[~done])
        es, vs, data = es[edge], vs[sub], data[sub]
        if X is not None:
            data = data - data[centre[fan]]


def _vertex_fans(t: Topology, centres: np.ndarray):
    """The disjoint union of the fans (the faces at a vertex) of the distinct
    ``centres``: ``(topology, vertex of t per union vertex, the centres in the
    union, edge of t per union edge, fan (position in centres) per union vertex)``."""
    offsets, vface = t.vertex_faces
    counts = offsets[centres + 1] - offsets[centres]
    owner = np.repeat(np.arange(centres.size), counts)
    g = vface[ranges(offsets[centres], counts)]
    gs = t.face_sizes[g]
    corner_owner = np.repeat(owner, gs)
    corners = ranges(t.face_offsets[g], gs)
    keys, new_index = np.unique(corner_owner * t.n_vertices + t.face_indices[corners], return_inverse=True)
    vertex = keys % t.n_vertices
    topo = Topology(keys.size, new_index.ravel(), np.concatenate([[0], np.cumsum(gs)]), check=False)
    centre = np.searchsorted(keys, np.arange(centres.size) * t.n_vertices + centres)
    edge = t.find_edges(vertex[topo.edges])
    return topo, vertex, centre, edge, keys // t.n_vertices


def _eval_coons(surface, level, t, X, regular, faces, u, v):
    """Points and partials of the Coons patches of irregular quads (the fallback
    of :meth:`SubdivisionSurface.evaluate`, the same patches as ``to_bsplines``)."""
    nets = _coons_nets(surface, level, t, X, regular, faces)  # (m, 4, 4, dim)
    Bu = all_bernstein(3, u, order=1)  # (2, 4, m)
    Bv = all_bernstein(3, v, order=1)
    p = np.einsum("am,bm,mabd->md", Bu[0], Bv[0], nets)
    du = np.einsum("am,bm,mabd->md", Bu[1], Bv[0], nets)
    dv = np.einsum("am,bm,mabd->md", Bu[0], Bv[1], nets)
    return p, du, dv


def _bezier_nets(t, X, faces):
    """Bicubic Bézier control nets ``(m, 4, 4, dim)`` of regular quads."""
    net = X[patch_indices(t, faces)]
    return np.einsum("ia,mabd,jb->mijd", BSPLINE_TO_BEZIER, net, BSPLINE_TO_BEZIER)


def _side_curve(net, side):
    """Bézier control points ``(m, 4, dim)`` of side ``side`` (in face order) of nets ``(m, 4, 4, dim)``."""
    if side == 0:
        return net[:, :, 0]
    if side == 1:
        return net[:, 3, :]
    if side == 2:
        return net[:, ::-1, 3]
    return net[:, 0, ::-1]


def _coons_nets(surface, level, t, X, regular, faces):
    """Bicubic Coons nets ``(m, 4, 4, dim)`` for irregular quads (see ``to_bsplines``)."""
    m = faces.size
    dim = X.shape[1]
    # limit positions of the corners, and of the edge points of the next level for the midpoints
    h = t.face_offsets[faces][:, None] + np.arange(4)  # (m, 4) half-edges in face order
    ends = _limit_points(surface, level, np.stack([t.face_indices[h], t.halfedge_dst[h]]).ravel())
    ends = ends.reshape(2, m, 4, dim)
    mids = _limit_points(surface, level + 1, t.n_vertices + t.halfedge_edge[h].ravel()).reshape(m, 4, dim)
    curves = np.empty((4, m, 4, dim))
    for k in range(4):
        h = t.face_offsets[faces] + k
        a, b, mid = ends[0, :, k], ends[1, :, k], mids[:, k]
        # cubic through a, mid (at 1/2), b: the quadratic with those values, raised to degree 3
        q1 = 2 * mid - 0.5 * (a + b)
        curves[k] = np.stack([a, (a + 2 * q1) / 3, (2 * q1 + b) / 3, b], axis=1)
        g = t.twin[h]
        shared = (g >= 0) & regular[t.corner_face[np.maximum(g, 0)]]
        if shared.any():
            gf = t.corner_face[g[shared]]
            gside = g[shared] - t.face_offsets[gf]
            nets = _bezier_nets(t, X, gf)
            exact = np.empty((shared.sum(), 4, dim))
            for sd in range(4):
                sel = gside == sd
                if sel.any():
                    exact[sel] = _side_curve(nets[sel], sd)[:, ::-1]
            curves[k][shared] = exact
    # sides in face order: 0 bottom (u), 1 right (v), 2 top (reversed u), 3 left (reversed v)
    bottom, right, top, left = curves[0], curves[1], curves[2][:, ::-1], curves[3][:, ::-1]
    i = np.arange(4)[:, None, None] / 3.0
    j = np.arange(4)[None, :, None] / 3.0
    P00, P30, P33, P03 = bottom[:, 0], bottom[:, 3], top[:, 3], top[:, 0]
    return (
        (1 - i) * left[:, None, :, :] + i * right[:, None, :, :]
        + (1 - j) * bottom[:, :, None, :] + j * top[:, :, None, :]
        - ((1 - i) * (1 - j) * P00[:, None, None] + i * (1 - j) * P30[:, None, None]
           + (1 - i) * j * P03[:, None, None] + i * j * P33[:, None, None])
    )
