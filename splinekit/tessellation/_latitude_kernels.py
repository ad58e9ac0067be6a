"""Compiled (numba) kernel of the latitude strips (:func:`.latitude.mesh_rows`): rows, zips, fans,
the closed-form deviation and the normals of every face of revolution in one pass.

The numpy path is about 150 array calls per tessellation whatever the size (a filleted box's
eight corners at a coarse tolerance: ~0.9 ms of a 1.3 ms call); this kernel does the same steps
point by point. Loaded through :func:`splinekit._kernels.load` only; both paths give the same
triangles (the same zipper rule, ties to the bottom row) and the same measured deviation.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._fast_kernels import _angle, _param

BARY = np.array([[0.5, 0.5, 0.0], [0.0, 0.5, 0.5], [0.5, 0.0, 0.5], [1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0]])


@njit(cache=True, nogil=True, inline="always")
def _profile(s, psi, rho_c, z_c, p, g1, g2):
    c, sn = math.cos(psi), math.sin(psi)
    rho = rho_c[s] + p[s] * (c * g1[s, 0] + sn * g2[s, 0])
    z = z_c[s] + p[s] * (c * g1[s, 1] + sn * g2[s, 1])
    drho = p[s] * (-sn * g1[s, 0] + c * g2[s, 0])
    dz = p[s] * (-sn * g1[s, 1] + c * g2[s, 1])
    return rho, z, drho, dz


@njit(cache=True, nogil=True, inline="always")
def _point(s, phi, psi, O, ax, e1, e2, rho_c, z_c, p, g1, g2, out):
    rho, z, _, _ = _profile(s, psi, rho_c, z_c, p, g1, g2)
    c, sn = math.cos(phi), math.sin(phi)
    for d in range(3):
        out[d] = O[s, d] + z * ax[s, d] + rho * (c * e1[s, d] + sn * e2[s, d])


@njit(cache=True, nogil=True, inline="always")
def _piece(br, lo, hi, t):
    """Piece of ``t`` among the breaks ``br[lo:hi]`` and its local parameter in ``[0, 1]``."""
    a, b = lo, hi - 2
    while a < b:  # first piece whose end is >= t
        m = (a + b) // 2
        if br[m + 1] < t:
            a = m + 1
        else:
            b = m
    return a - lo, (t - br[a]) / (br[a + 1] - br[a])


@njit(cache=True, nogil=True, inline="always")
def _surface(s, u, v, nets, out):
    """The point of face ``s``'s surface at ``(u, v)`` from its rational Bézier cells (see
    :func:`.latitude.bezier_nets`) into ``out`` ``(3,)``."""
    ub, uoff, vb, voff, first, cells = nets
    i, x = _piece(ub, uoff[s], uoff[s + 1], u)
    j, y = _piece(vb, voff[s], voff[s + 1], v)
    net = cells[first[s] + i * (voff[s + 1] - voff[s] - 1) + j]
    bu = ((1.0 - x) * (1.0 - x), 2.0 * x * (1.0 - x), x * x)
    bv = ((1.0 - y) * (1.0 - y), 2.0 * y * (1.0 - y), y * y)
    h0 = h1 = h2 = h3 = 0.0
    for a in range(3):
        for b in range(3):
            w = bu[a] * bv[b]
            h0 += w * net[a, b, 0]
            h1 += w * net[a, b, 1]
            h2 += w * net[a, b, 2]
            h3 += w * net[a, b, 3]
    out[0], out[1], out[2] = h0 / h3, h1 / h3, h2 / h3


@njit(cache=True, nogil=True, inline="always")
def _vid(use, k, n, abase, use_group, use_flip, arc_of, end_vid):
    g = use_group[use]
    a = arc_of[g]
    na = n[a]
    kk = na - k if use_flip[use] else k
    if kk == 0:
        return end_vid[g, 0]
    if kk == na:
        return end_vid[g, 1]
    return abase[a] + kk - 1


@njit(cache=True, nogil=True)
def row_need(nm, psi_r, phi_r, rho_c, z_c, p, g1, g2, kappa_u, c, tol, angle_tol):
    """See :func:`.latitude._row_need` (the same operations; ``angle_tol <= 0``: none):
    ``(need (rows,) float, ok (S,) bool)``."""
    S = nm.size
    need = np.empty(int(nm.sum()) + S)
    ok = np.ones(S, np.bool_)
    r0 = 0
    for s in range(S):
        m = nm[s]
        h = (psi_r[s, 1] - psi_r[s, 0]) / m
        rho2 = np.empty(m + 1)
        mix = np.empty(m + 1)
        step = np.full(m + 1, np.inf)
        for k in range(m + 1):
            rho, _, drho, _ = _profile(s, psi_r[s, 0] + k * h, rho_c, z_c, p, g1, g2)
            rho2[k] = rho * rho * (1.0 + (1.02 * kappa_u[s]) ** 2)
            mix[k] = 2.0 * drho * drho + abs(rho * (rho_c[s] - rho))
        C = (h * h * p[s]) ** 2 - (8.0 * c[s] * tol) ** 2
        ok[s] = C < 0
        for k in range(m):
            st = 0.0
            if ok[s]:
                R2 = max(rho2[k], rho2[k + 1])
                B = 2.0 * (h * h) * max(mix[k], mix[k + 1])
                st = math.sqrt(-2.0 * C / (B + math.sqrt(max(B * B - 4.0 * R2 * C, 0.0)) + 1e-300))
            if angle_tol > 0:
                st = min(st, angle_tol)
            step[k] = min(step[k], st)
            step[k + 1] = min(step[k + 1], st)
        for k in range(m + 1):
            need[r0 + k] = math.ceil((phi_r[s, 1] - phi_r[s, 0]) / max(step[k], 1e-300) * (1.0 + 1e-9))
        r0 += m + 1
    return need, ok


@njit(cache=True, nogil=True)
def rows(nm, m, phi_r, psi_r, lo, hi, pole, uses, flip, face_of, use_group, use_flip, arc_of, end_vid, n, abase,
         V_base, n_vid, umaps, vmaps, O, ax, e1, e2, rho_c, z_c, p, g1, g2, nets):  # fmt: skip
    """See :func:`.latitude.mesh_rows`: ``(T (t, 3) vertex ids, corner_uv (t, 3, 2), face (t,),
    strip_dev (rows,), V, N, UV, VP (new vertices), fix_vid, fix_uv, fix_N, fix_face)``.
    ``umaps``, ``vmaps``: ``(akey, tkey, table, first, last, sweep, full, t0, t1)`` of the maps;
    ``nets``: the surfaces' Bézier cells (:func:`.latitude.bezier_nets`), which the deviation is
    measured on (the same surfaces as the closed form, to rounding, without its sines and cosines)."""
    ua, ut, utab, uf, ul, usw, ufull, ut0, ut1 = umaps
    va, vt, vtab, vf, vl, vsw, vfull, vt0, vt1 = vmaps
    S = nm.size
    R = m.size
    row_first = np.empty(R + 1, np.int64)  # first point of each row
    P = 0
    T_count = 0
    n_pole = 0
    r = 0
    for s in range(S):
        for k in range(nm[s] + 1):
            row_first[r] = P
            P += m[r] + 1 if m[r] > 0 else 0
            if k < nm[s]:
                T_count += m[r] + m[r + 1]  # a zip: a triangle per step; a fan: one per base segment
                if m[r] == 0 or m[r + 1] == 0:
                    n_pole += m[r] + m[r + 1]  # a pole corner per fan triangle
            r += 1
    row_first[R] = P
    NP = P + n_pole
    pu = np.empty((NP, 2))
    pvid = np.empty(NP, np.int64)
    pX = np.empty((NP, 3))
    pphi = np.empty(NP)
    ppsi = np.empty(NP)
    pslot = np.empty(NP, np.int64)
    n_new = 0
    r = 0
    for s in range(S):
        h = (psi_r[s, 1] - psi_r[s, 0]) / nm[s]
        for k in range(nm[s] + 1):
            mk = m[r]
            psi = psi_r[s, 0] + k * h
            if k == 0:
                v = lo[s, 1]
            elif k == nm[s]:
                v = hi[s, 1]
            else:
                v = _param(s, psi, va, vtab, vf, vl, vsw, vfull)
            for j in range(mk + 1 if mk > 0 else 0):
                q = row_first[r] + j
                phi = phi_r[s, 0] + j * (phi_r[s, 1] - phi_r[s, 0]) / mk
                if j == 0:
                    u = lo[s, 0]
                elif j == mk:
                    u = hi[s, 0]
                else:
                    u = _param(s, phi, ua, utab, uf, ul, usw, ufull)
                pu[q, 0], pu[q, 1] = u, v
                pphi[q], ppsi[q], pslot[q] = phi, psi, s
                if k == 0:
                    vid = _vid(uses[s, 0], j, n, abase, use_group, use_flip, arc_of, end_vid)
                elif k == nm[s]:
                    vid = _vid(uses[s, 2], mk - j, n, abase, use_group, use_flip, arc_of, end_vid)
                elif j == 0:
                    vid = _vid(uses[s, 3], nm[s] - k, n, abase, use_group, use_flip, arc_of, end_vid)
                elif j == mk:
                    vid = _vid(uses[s, 1], k, n, abase, use_group, use_flip, arc_of, end_vid)
                else:
                    vid = n_vid + n_new
                    n_new += 1
                pvid[q] = vid
                if vid < n_vid:
                    for d in range(3):
                        pX[q, d] = V_base[vid, d]
                else:
                    _point(s, phi, psi, O, ax, e1, e2, rho_c, z_c, p, g1, g2, pX[q])
            r += 1
    # triangles (point indices), counter-clockwise in (u, v); strips numbered like their bottom rows
    T = np.empty((T_count, 3), np.int64)
    tstrip = np.empty(T_count, np.int64)
    w = 0
    extra = P
    r = 0
    for s in range(S):
        for k in range(nm[s] + 1):
            if k == nm[s]:
                r += 1
                continue
            mb, mt = m[r], m[r + 1]
            b0, t0 = row_first[r], row_first[r + 1]
            if mb > 0 and mt > 0:
                i = j = 0
                while i < mb or j < mt:
                    bottom = j == mt or (i < mb and (i + 1) / mb - 1e-9 <= (j + 1) / mt)
                    T[w, 0] = b0 + i
                    if bottom:
                        T[w, 1] = b0 + i + 1
                        T[w, 2] = t0 + j
                        i += 1
                    else:
                        T[w, 1] = t0 + j + 1
                        T[w, 2] = t0 + j
                        j += 1
                    tstrip[w] = r
                    w += 1
            else:
                top = mt == 0
                base = b0 if top else t0
                mm = mb if top else mt
                use = uses[s, 2] if top else uses[s, 0]
                pole_vid = end_vid[use_group[use], 0]
                pv = hi[s, 1] if top else lo[s, 1]
                for j in range(mm):
                    a = base + j
                    pu[extra, 0], pu[extra, 1] = 0.5 * (pu[a, 0] + pu[a + 1, 0]), pv
                    pphi[extra] = _angle(s, pu[extra, 0], ut, utab, uf, ul, ut0, ut1)
                    ppsi[extra] = psi_r[s, 1] if top else psi_r[s, 0]
                    pslot[extra], pvid[extra] = s, pole_vid
                    for d in range(3):
                        pX[extra, d] = V_base[pole_vid, d]
                    if top:
                        T[w, 0], T[w, 1], T[w, 2] = a, a + 1, extra
                    else:
                        T[w, 0], T[w, 1], T[w, 2] = extra, a + 1, a
                    tstrip[w] = r
                    extra += 1
                    w += 1
            r += 1
    # the deviation in closed form at every triangle's edge midpoints and centre
    strip_dev = np.zeros(R)
    ex = np.empty(3)
    for t in range(w):
        s = pslot[T[t, 0]]
        worst = 0.0
        for b in range(4):
            u = BARY[b, 0] * pu[T[t, 0], 0] + BARY[b, 1] * pu[T[t, 1], 0] + BARY[b, 2] * pu[T[t, 2], 0]
            v = BARY[b, 0] * pu[T[t, 0], 1] + BARY[b, 1] * pu[T[t, 1], 1] + BARY[b, 2] * pu[T[t, 2], 1]
            _surface(s, u, v, nets, ex)
            d2 = 0.0
            for d in range(3):
                x = ex[d] - (BARY[b, 0] * pX[T[t, 0], d] + BARY[b, 1] * pX[T[t, 1], d] + BARY[b, 2] * pX[T[t, 2], d])
                d2 += x * x
            worst = max(worst, d2)
        strip_dev[tstrip[t]] = max(strip_dev[tstrip[t]], math.sqrt(worst))
    # outputs: triangles as vertex ids (a reversed face's flipped), new vertices, shared ones' fixes
    TV = np.empty((w, 3), np.int64)
    CUV = np.empty((w, 3, 2))
    tf = np.empty(w, np.int64)
    for t in range(w):
        s = pslot[T[t, 0]]
        tf[t] = face_of[s]
        for c in range(3):
            q = T[t, 3 - c] if flip[s] and c > 0 else T[t, c]
            TV[t, c] = pvid[q]
            CUV[t, c, 0], CUV[t, c, 1] = pu[q, 0], pu[q, 1]
    normals = np.empty((extra, 3))
    for q in range(extra):
        s = pslot[q]
        _, _, drho, dz = _profile(s, ppsi[q], rho_c, z_c, p, g1, g2)
        c, sn = math.cos(pphi[q]), math.sin(pphi[q])
        sign = -1.0 if flip[s] else 1.0
        for d in range(3):
            normals[q, d] = sign * (dz * (c * e1[s, d] + sn * e2[s, d]) - drho * ax[s, d]) / p[s]
    V = np.empty((n_new, 3))
    N = np.empty((n_new, 3))
    UV = np.empty((n_new, 2))
    VP = np.empty(n_new, np.int64)
    n_fix = 0
    for q in range(extra):
        if pvid[q] < n_vid:
            n_fix += 1
    fix_vid = np.empty(n_fix, np.int64)
    fix_uv = np.empty((n_fix, 2))
    fix_N = np.empty((n_fix, 3))
    fix_face = np.empty(n_fix, np.int64)
    f = 0
    for q in range(extra):
        i = pvid[q] - n_vid
        if i >= 0:
            V[i], N[i], UV[i], VP[i] = pX[q], normals[q], pu[q], face_of[pslot[q]]
        else:
            fix_vid[f], fix_uv[f], fix_N[f], fix_face[f] = pvid[q], pu[q], normals[q], face_of[pslot[q]]
            f += 1
    return TV, CUV, tf, strip_dev, V, N, UV, VP, fix_vid, fix_uv, fix_N, fix_face
