"""Level-set evolution on a regular grid: :class:`LevelSet`.

The front is the zero set of ``phi`` sampled on a grid of cubic voxels
(negative inside). :meth:`LevelSet.advance` integrates

    phi_t + F |grad phi| = b kappa |grad phi|

with ``F`` a normal speed (a constant, an array of samples or a function of
position and time; positive moves the front outward) and ``b >= 0`` the
mean-curvature coefficient (``kappa = div(grad phi / |grad phi|)``, the sum of
the principal curvatures, ``2 / r`` on a sphere of radius ``r``; ``b = 1``
with ``F = 0`` is mean-curvature flow, under which a sphere shrinks as
``r(t) = sqrt(r0^2 - 4 t)``).

Schemes
-------
* ``"godunov"``: first-order upwind one-sided differences combined by
  Godunov's rule, forward Euler in time; error ``O(h)``.
* ``"weno5"``: fifth-order WENO one-sided differences (Jiang & Peng 2000)
  with the same Godunov combination, third-order TVD Runge-Kutta in time.

The curvature term uses second-order central differences. Time steps obey
the CFL bounds ``dt <= cfl * h / max|F|`` and ``dt <= cfl * h^2 / (6 b)``.
The grid border is a zero-gradient (edge-copy) boundary: keep the front a
few voxels inside the grid.

Reinitialization (:meth:`LevelSet.reinitialize`) replaces ``phi`` by the
signed distance to its zero set: samples next to a sign change get the
distance to the linear interpolated crossings along the grid axes
(``1 / d^2 = sum_axes 1 / d_axis^2``, exact for a plane), the others solve
the upwind Eikonal equation ``|grad d| = 1`` by the fast sweeping method
(Zhao 2005): Gauss-Seidel sweeps in the 8 diagonal orderings, each sweep
vectorized over the planes ``+-i +- j +- k = const`` (a sample's upwind
neighbours lie on the previous plane).

Topology changes need no special handling: merging or splitting fronts
are simply sign patterns of ``phi``.
"""

from __future__ import annotations

import numpy as np

from ._progress import progress
from ._validate import as_float_array, as_int, as_real
from .errors import ParameterError, ResourceLimitError, SplineKitError
from .implicit._checks import origin3
from .implicit.sampled import MAX_GRID_POINTS, SampledSDF, sample

__all__ = ["MAX_STEPS", "MAX_WORK", "LevelSet"]

MAX_STEPS = 1_000_000
"""Largest number of time steps one :meth:`LevelSet.advance` may take."""

MAX_WORK = 1e9
"""Default work budget of one :meth:`LevelSet.advance`, in sample updates (time
steps x (grid samples + a fixed cost per step), x 10 for ``"weno5"``, whose three Runge-Kutta stages of
fifth-order differences cost about ten first-order updates): about a quarter
of an hour on one core at the 250-300 ns per update measured for ``"godunov"``.
Raise it per call with ``advance(..., max_work=...)``."""

_SCHEME_COST = {"godunov": 1.0, "weno5": 10.0}
_STEP_OVERHEAD = 1000
"""Fixed cost of one time step in sample updates (about 200 us of array set-up,
measured on a 5^3 grid): a tiny grid still costs this much per step."""

_SCHEMES = ("godunov", "weno5")
_TINY = 1e-12


class LevelSet:
    """A front ``phi = 0`` on a grid of cubic voxels, evolved in time.

    Parameters
    ----------
    phi : (nx, ny, nz) finite array, each axis >= 3
        Level-set samples (negative inside), model units.
    origin : (3,)
        Position of sample ``[0, 0, 0]``.
    spacing : float
        Voxel size ``h`` > 0 (the same on every axis).
    time : float
        The current time.

    Objects are immutable: :meth:`advance` and :meth:`reinitialize` return new ones.
    """

    def __init__(self, phi, origin, spacing, time: float = 0.0):
        p = as_float_array(phi, "phi")
        if p.ndim != 3 or min(p.shape) < 3:
            raise ParameterError(f"phi must be an (nx, ny, nz) array with every axis >= 3, got shape {p.shape}")
        if p.size > MAX_GRID_POINTS:
            raise ParameterError(f"phi has {p.size} samples, more than MAX_GRID_POINTS = {MAX_GRID_POINTS}")
        if not np.isfinite(p).all():
            idx = tuple(int(i) for i in np.argwhere(~np.isfinite(p))[0])
            raise ParameterError(f"phi{list(idx)} is not finite")
        h = as_float_array(spacing, "spacing")
        if h.ndim == 1 and h.size == 3 and np.all(h == h[0]):
            h = h[0]
        if h.ndim != 0 or not (np.isfinite(h) and h > 0):
            raise ParameterError(f"spacing must be one finite number > 0 (cubic voxels), got {spacing!r}")
        self._phi = np.array(p, dtype=np.float64, order="C")
        self._phi.setflags(write=False)
        self._origin = origin3(origin)
        self._origin.setflags(write=False)
        self._h = float(h)
        with np.errstate(over="ignore"):
            far = self._origin + (np.array(p.shape) - 1) * self._h
        if not np.isfinite(far).all():
            raise ParameterError(f"a grid of shape {p.shape} with spacing {self._h!r} reaches beyond the float range")
        self._time = as_real(time, "time")

    @classmethod
    def from_implicit(cls, implicit, bounds, resolution, time: float = 0.0) -> LevelSet:
        """Sample ``implicit`` (or any callable ``(n, 3) -> (n,)``) over ``bounds``
        with ``resolution`` samples along the longest side (cubic voxels)."""
        n = as_int(resolution, "resolution", minimum=3)
        g = sample(implicit, bounds, n)
        return cls(g.values, g.origin, g.spacing, time)

    # -- properties ---------------------------------------------------------------------------
    @property
    def phi(self) -> np.ndarray:
        """``(nx, ny, nz)`` samples (read-only)."""
        return self._phi

    @property
    def origin(self) -> np.ndarray:
        return self._origin

    @property
    def spacing(self) -> float:
        return self._h

    @property
    def time(self) -> float:
        return self._time

    @property
    def shape(self) -> tuple:
        return self._phi.shape

    def __repr__(self):
        return f"LevelSet(shape={self.shape}, origin={self._origin.tolist()}, spacing={self._h!r}, time={self._time!r})"

    def points(self) -> np.ndarray:
        """Sample positions ``(nx, ny, nz, 3)``."""
        axes = [self._origin[i] + np.arange(n) * self._h for i, n in enumerate(self.shape)]
        return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)

    def _new(self, phi, time):
        out = object.__new__(LevelSet)
        phi = np.ascontiguousarray(phi)
        phi.setflags(write=False)
        out._phi, out._origin, out._h, out._time = phi, self._origin, self._h, float(time)
        return out

    # -- conversions ----------------------------------------------------------------------------------
    def to_sdf(self, interpolation: str = "linear"):
        """The samples as a :class:`~splinekit.implicit.sampled.SampledSDF`."""
        return SampledSDF(self._phi, self._origin, self._h, interpolation)

    def to_mesh(self):
        """The front as a closed triangle mesh (an
        :class:`~splinekit.implicit.meshing.ImplicitMesh`: marching tetrahedra
        straight from the samples, :meth:`SampledSDF.to_mesh
        <splinekit.implicit.sampled.SampledSDF.to_mesh>`, with its measured
        ``deviation`` from the trilinear interpolant's zero set)."""
        return self.to_sdf().to_mesh()

    # -- speeds -----------------------------------------------------------------------------------------
    def _speed(self, speed, t, pts_cache):
        if callable(speed):
            if pts_cache[0] is None:
                pts_cache[0] = self.points().reshape(-1, 3)
            try:
                F = np.asarray(speed(pts_cache[0], t), dtype=np.float64)
            except SplineKitError:
                raise
            except Exception as exc:
                raise ParameterError(f"the speed function raised {type(exc).__name__}: {exc}") from exc
            if F.shape != (pts_cache[0].shape[0],):
                raise ParameterError(f"speed(points, t) must return shape ({pts_cache[0].shape[0]},), got {F.shape}")
            F = F.reshape(self.shape)
        else:
            F = as_float_array(speed, "speed")
            if F.ndim != 0 and F.shape != self.shape:
                raise ParameterError(f"speed must be a number, an array of shape {self.shape} or callable, got shape {F.shape}")
        if not np.isfinite(F).all():
            raise ParameterError(f"speed is not finite at time {t!r}")
        return F

    # -- evolution --------------------------------------------------------------------------------------
    def advance(self, duration, speed=0.0, *, curvature: float = 0.0, scheme: str = "godunov", cfl: float = 0.5,
                max_work: float = MAX_WORK):
        """The level set evolved for ``duration`` (>= 0) time units.

        Parameters
        ----------
        duration : float
        speed : float, (nx, ny, nz) array or callable
            Normal speed ``F`` (model units per time unit, outward positive);
            a callable is ``speed(points (n, 3), t) -> (n,)``, called each step.
        curvature : float
            Coefficient ``b >= 0`` of the mean-curvature term.
        scheme : "godunov" or "weno5"
        cfl : float in (0, 1]
        max_work : float
            Work budget in sample updates (see :data:`MAX_WORK`): an evolution
            whose estimate (time steps x samples x scheme cost) exceeds it raises
            :class:`~splinekit.errors.ResourceLimitError` before the first step.

        Returns
        -------
        LevelSet
            At time ``self.time + duration``.

        A progress bar (on a terminal) counts the time steps.
        """
        T = as_real(duration, "duration")
        if T < 0:
            raise ParameterError(f"duration must be >= 0, got {T!r}")
        b = as_real(curvature, "curvature")
        if b < 0:
            raise ParameterError(f"curvature must be >= 0 (a negative coefficient is ill-posed), got {b!r}")
        if scheme not in _SCHEMES:
            raise ParameterError(f"scheme must be one of {_SCHEMES}, got {scheme!r}")
        cfl = as_real(cfl, "cfl")
        if not 0 < cfl <= 1:
            raise ParameterError(f"cfl must lie in (0, 1], got {cfl!r}")
        max_work = as_real(max_work, "max_work")
        if not max_work > 0:
            raise ParameterError(f"max_work must be > 0 sample updates, got {max_work!r}")
        h = self._h
        cache = [None]
        F0 = self._speed(speed, self._time, cache)
        fmax = float(np.max(np.abs(F0)))
        # the step count is worked out in floating point and checked before it becomes an
        # int: a huge speed or curvature makes dt underflow to 0 (and T / dt infinite)
        with np.errstate(over="ignore", divide="ignore", invalid="ignore"):  # 0 / 0 for T = 0: returned below
            dt_max = np.inf
            if fmax > 0:
                dt_max = cfl * h / fmax
            if b > 0:
                dt_max = min(dt_max, cfl * h * h / (6.0 * b))
            steps = 1.0 if not np.isfinite(dt_max) else float(np.ceil(np.float64(T) / dt_max - 1e-9))
        if T == 0 or (fmax == 0 and b == 0 and not callable(speed)):
            return self._new(self._phi.copy(), self._time + T)
        if not steps <= MAX_STEPS:
            raise ParameterError(
                f"advancing by {T!r} needs {steps:.3g} time steps (dt = {dt_max:.3g}), more than MAX_STEPS = {MAX_STEPS}"
            )
        n_steps = max(int(steps), 1)
        work = n_steps * (float(self._phi.size) + _STEP_OVERHEAD) * _SCHEME_COST[scheme]
        if work > max_work:
            raise ResourceLimitError(
                f"advancing by {T!r} needs {n_steps:,} time steps (dt = {dt_max:.3g}) on {self._phi.size:,} samples: "
                f"about {work:.3g} sample updates with {scheme}, over the work budget of {max_work:.3g}; "
                "raise it with advance(..., max_work=...), or use a coarser grid, a larger cfl or a shorter duration"
            )
        dt = T / n_steps
        phi = np.array(self._phi)
        t = self._time
        with progress(n_steps, "advancing level set") as bar:
            phi, t = self._steps(phi, t, dt, n_steps, speed, F0, fmax, b, h, cfl, scheme, cache, bar)
        if not np.isfinite(phi).all():  # cannot happen within the CFL bound; refuse rather than return NaN
            raise ParameterError("the evolution became unstable (non-finite phi); lower cfl")
        return self._new(phi, self._time + T)

    def _steps(self, phi, t, dt, n_steps, speed, F0, fmax, b, h, cfl, scheme, cache, bar):
        """``n_steps`` explicit steps of :meth:`advance` from ``phi`` at time ``t``: ``(phi, t)``."""
        for _ in range(n_steps):
            F = F0 if not callable(speed) else self._speed(speed, t, cache)
            if callable(speed):
                fm = float(np.max(np.abs(F)))
                if fm > 0 and dt > cfl * h / fm * (1 + 1e-9):
                    raise ParameterError(
                        f"the speed reached |F| = {fm:.6g} at time {t:.6g}, above the bound {fmax:.6g} the step was chosen for; "
                        "pass a speed whose largest value occurs at the start"
                    )
            if scheme == "godunov":
                phi = phi + dt * _rate(phi, F, b, h, _godunov_diffs)
            else:
                p1 = phi + dt * _rate(phi, F, b, h, _weno_diffs)
                p2 = 0.75 * phi + 0.25 * (p1 + dt * _rate(p1, F, b, h, _weno_diffs))
                phi = phi / 3.0 + 2.0 / 3.0 * (p2 + dt * _rate(p2, F, b, h, _weno_diffs))
            t += dt
            bar.advance()
        return phi, t

    # -- reinitialization -------------------------------------------------------------------------------
    def reinitialize(self, max_passes: int = 4):
        """The signed distance to the current front (module notes), same grid and time.

        ``max_passes`` bounds the rounds of 8 sweeps (each round stops early
        once no sample changes). A grid with no sign change has no front and
        raises ParameterError.
        """
        max_passes = as_int(max_passes, "max_passes", minimum=1)
        phi = self._phi
        d0 = _interface_distances(phi, self._h)
        if not np.isfinite(d0).any():
            raise ParameterError("phi has no sign change: there is no front to measure distances from")
        d = _fast_sweep(d0, self._h, max_passes)
        out = np.where(phi < 0, -d, d)
        return self._new(out, self._time)


# -- spatial operators ---------------------------------------------------------------------------------------
def _godunov_diffs(phi, h):
    """One-sided differences ``(D-, D+)`` per axis, first order (edge-copy border)."""
    p = np.pad(phi, 1, mode="edge")
    out = []
    for ax in range(3):
        sl_c = [slice(1, -1)] * 3
        sl_m = list(sl_c)
        sl_p = list(sl_c)
        sl_m[ax] = slice(0, -2)
        sl_p[ax] = slice(2, None)
        c = p[tuple(sl_c)]
        out.append(((c - p[tuple(sl_m)]) / h, (p[tuple(sl_p)] - c) / h))
    return out


def _weno(v1, v2, v3, v4, v5):
    """Fifth-order WENO combination of the five one-sided differences."""
    s1 = 13.0 / 12.0 * (v1 - 2 * v2 + v3) ** 2 + 0.25 * (v1 - 4 * v2 + 3 * v3) ** 2
    s2 = 13.0 / 12.0 * (v2 - 2 * v3 + v4) ** 2 + 0.25 * (v2 - v4) ** 2
    s3 = 13.0 / 12.0 * (v3 - 2 * v4 + v5) ** 2 + 0.25 * (3 * v3 - 4 * v4 + v5) ** 2
    eps = 1e-6 * np.maximum.reduce([v1 * v1, v2 * v2, v3 * v3, v4 * v4, v5 * v5]) + 1e-99
    a1 = 0.1 / (s1 + eps) ** 2
    a2 = 0.6 / (s2 + eps) ** 2
    a3 = 0.3 / (s3 + eps) ** 2
    f1 = v1 / 3.0 - 7.0 * v2 / 6.0 + 11.0 * v3 / 6.0
    f2 = -v2 / 6.0 + 5.0 * v3 / 6.0 + v4 / 3.0
    f3 = v3 / 3.0 + 5.0 * v4 / 6.0 - v5 / 6.0
    return (a1 * f1 + a2 * f2 + a3 * f3) / (a1 + a2 + a3)


def _shifted(D, n, ax, k):
    """The part of ``D`` (padded by 3) at offset ``k`` along ``ax`` from each interior sample."""
    sl = [slice(3, 3 + n[i]) for i in range(3)]
    sl[ax] = slice(3 + k, 3 + k + n[ax])
    return D[tuple(sl)]


def _weno_diffs(phi, h):
    """WENO5 one-sided differences ``(D-, D+)`` per axis (edge-copy border)."""
    p = np.pad(phi, 3, mode="edge")
    n = phi.shape
    out = []
    for ax in range(3):
        D = np.diff(p, axis=ax) / h  # D[k] = (p[k+1] - p[k]) / h: the forward difference at padded k
        sh = [_shifted(D, n, ax, k) for k in range(-3, 3)]  # sh[k + 3]: forward differences at offset k
        dm = _weno(sh[0], sh[1], sh[2], sh[3], sh[4])
        dp = _weno(sh[5], sh[4], sh[3], sh[2], sh[1])
        out.append((dm, dp))
    return out


def _upwind_norm(diffs, F):
    """Godunov's ``|grad phi|`` for the normal speed ``F`` (sign-dependent upwinding)."""
    pos = np.zeros_like(diffs[0][0])
    neg = np.zeros_like(pos)
    for dm, dp in diffs:
        pos += np.maximum(np.maximum(dm, 0) ** 2, np.minimum(dp, 0) ** 2)
        neg += np.maximum(np.minimum(dm, 0) ** 2, np.maximum(dp, 0) ** 2)
    return np.where(F > 0, np.sqrt(pos), np.sqrt(neg))


def _curvature_term(phi, h):
    """``kappa |grad phi|`` by second-order central differences."""
    p = np.pad(phi, 1, mode="edge")
    c = p[1:-1, 1:-1, 1:-1]

    def at(dx, dy, dz):
        nx, ny, nz = phi.shape
        return p[1 + dx : 1 + dx + nx, 1 + dy : 1 + dy + ny, 1 + dz : 1 + dz + nz]

    px = (at(1, 0, 0) - at(-1, 0, 0)) / (2 * h)
    py = (at(0, 1, 0) - at(0, -1, 0)) / (2 * h)
    pz = (at(0, 0, 1) - at(0, 0, -1)) / (2 * h)
    pxx = (at(1, 0, 0) - 2 * c + at(-1, 0, 0)) / h**2
    pyy = (at(0, 1, 0) - 2 * c + at(0, -1, 0)) / h**2
    pzz = (at(0, 0, 1) - 2 * c + at(0, 0, -1)) / h**2
    pxy = (at(1, 1, 0) - at(1, -1, 0) - at(-1, 1, 0) + at(-1, -1, 0)) / (4 * h * h)
    pxz = (at(1, 0, 1) - at(1, 0, -1) - at(-1, 0, 1) + at(-1, 0, -1)) / (4 * h * h)
    pyz = (at(0, 1, 1) - at(0, 1, -1) - at(0, -1, 1) + at(0, -1, -1)) / (4 * h * h)
    g2 = px * px + py * py + pz * pz
    num = (
        pxx * (py * py + pz * pz)
        + pyy * (px * px + pz * pz)
        + pzz * (px * px + py * py)
        - 2 * (px * py * pxy + px * pz * pxz + py * pz * pyz)
    )
    # where the gradient vanishes the curvature is undefined: no motion there
    return np.where(g2 > _TINY, num / np.maximum(g2, _TINY), 0.0)


def _rate(phi, F, b, h, diffs):
    """``d phi / dt = -F |grad phi| + b kappa |grad phi|``."""
    out = np.zeros_like(phi)
    if np.any(F != 0):
        out -= F * _upwind_norm(diffs(phi, h), F)
    if b > 0:
        out += b * _curvature_term(phi, h)
    return out


# -- reinitialization ----------------------------------------------------------------------------------------
def _interface_distances(phi, h):
    """Distances ``(nx, ny, nz)`` of samples next to a sign change to the front
    (from the linear crossings along each axis), ``inf`` elsewhere."""
    inv2 = np.zeros_like(phi)
    neg = phi < 0
    for ax in range(3):
        best = np.full(phi.shape, np.inf)
        for step in (1, -1):
            other = np.roll(phi, -step, axis=ax)
            oneg = np.roll(neg, -step, axis=ax)
            valid = np.ones(phi.shape, dtype=bool)
            idx = [slice(None)] * 3
            idx[ax] = slice(-1, None) if step == 1 else slice(0, 1)
            valid[tuple(idx)] = False  # np.roll wrapped around there
            cross = valid & (neg != oneg)
            with np.errstate(divide="ignore", invalid="ignore"):
                # |phi| / (|phi| + |other|) halved top and bottom: phi - other may overflow
                a, o = 0.5 * np.abs(phi), 0.5 * np.abs(other)
                t = np.where(cross, a / (a + o), np.inf)
            best = np.minimum(best, np.where(cross, np.abs(t) * h, np.inf))
        with np.errstate(divide="ignore"):
            inv2 += np.where(np.isfinite(best), 1.0 / np.maximum(best, 1e-300) ** 2, 0.0)
    out = np.full(phi.shape, np.inf)
    has = inv2 > 0
    out[has] = 1.0 / np.sqrt(inv2[has])
    return out


def _eikonal_update(a, b, c, h):
    """Upwind solution of ``sum ((u - a_k)_+ / h)^2 = 1`` for neighbour minima a, b, c."""
    s = np.sort(np.stack([a, b, c]), axis=0)
    a1, a2, a3 = s
    u = a1 + h
    with np.errstate(invalid="ignore"):
        two = u > a2
        if two.any():
            d = a1[two] - a2[two]
            u2 = 0.5 * (a1[two] + a2[two] + np.sqrt(np.maximum(2 * h * h - d * d, 0.0)))
            u[two] = u2
        three = u > a3
        if three.any():
            x, y, z = a1[three], a2[three], a3[three]
            ssum = x + y + z
            disc = ssum * ssum - 3.0 * (x * x + y * y + z * z - h * h)
            u[three] = (ssum + np.sqrt(np.maximum(disc, 0.0))) / 3.0
    return u


def _fast_sweep(d0, h, max_passes):
    """Fast sweeping from the fixed samples ``d0 < inf``: ``(nx, ny, nz)`` distances."""
    nx, ny, nz = d0.shape
    U = np.full((nx + 2, ny + 2, nz + 2), np.inf)
    U[1:-1, 1:-1, 1:-1] = d0
    Uf = U.ravel()
    s0, s1 = (ny + 2) * (nz + 2), nz + 2
    free = ~np.isfinite(d0)
    i, j, k = np.nonzero(free)
    flat = (i + 1) * s0 + (j + 1) * s1 + (k + 1)
    orders = []
    for sx in (1, -1):
        for sy in (1, -1):
            for sz in (1, -1):
                key = (i if sx > 0 else nx - 1 - i) + (j if sy > 0 else ny - 1 - j) + (k if sz > 0 else nz - 1 - k)
                order = np.argsort(key, kind="stable")
                cuts = np.flatnonzero(np.diff(key[order])) + 1
                orders.append(np.split(flat[order], cuts))
    for _ in range(max_passes):
        changed = False
        for planes in orders:
            for f in planes:
                a = np.minimum(Uf[f - s0], Uf[f + s0])
                b = np.minimum(Uf[f - s1], Uf[f + s1])
                c = np.minimum(Uf[f - 1], Uf[f + 1])
                finite = np.isfinite(a) | np.isfinite(b) | np.isfinite(c)
                if not finite.any():
                    continue
                u = np.full(f.shape, np.inf)
                u[finite] = _eikonal_update(a[finite], b[finite], c[finite], h)
                better = u < Uf[f]
                if better.any():
                    Uf[f[better]] = u[better]
                    changed = True
        if not changed:
            break
    return U[1:-1, 1:-1, 1:-1].copy()
