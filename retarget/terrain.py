"""Terrains for performance transfer (SPEC "Performance transfer"): where is the ground?

A terrain answers one question, vectorised over many points:

* ``height(xz)`` — ``(..., 2)`` horizontal points ``(x, z)`` → ``(...,)`` ground heights;
* ``project(points)`` — ``(..., 3)`` points → ``(..., 3)`` ground points hit by a ray cast
  from each point along gravity (−y). If nothing is below a point, the ray is cast upwards
  instead, so a point under the ground is lifted onto it.

Conventions: metres, right-handed world, +y up, gravity along −y.

Three terrains share that duck-typed interface (see :class:`Terrain`):

* :class:`Flat` — a horizontal plane ``y = height``;
* :class:`HeightField` — a regular grid, ``heights[i, j]`` at ``x = x0 + j*spacing``,
  ``z = z0 + i*spacing``, bilinear in between and edge values held outside the grid;
* :class:`Mesh` — a triangle mesh. Rays are intersected with the triangles by our own
  vectorised Möller–Trumbore test; a uniform grid over the xz plane buckets the triangles
  so that each (vertical) ray only tests the triangles whose xz bounding box covers its
  cell. Where a mesh has several layers (overhangs) ``project`` keeps the closest hit
  below the point (else the closest above) and ``height`` the topmost surface. A point
  whose ray hits nothing at all (outside the mesh's xz footprint, or through a hole)
  keeps its x and z and takes the height of the mesh vertex nearest to it in xz.

OBJ files are read by :mod:`retarget.objfile` (errors name the line); trimesh is used only to
*load* other mesh files (PLY, GLB, STL…); nothing else of it.

:func:`parse_terrain` turns a command-line spec into a terrain; :func:`sample_elevation`
gives a real digital elevation model (matplotlib's bundled Jacksboro fault DEM) rescaled
to a room-sized terrain. Every bad input raises :class:`doodle.core.errors.DoodleError` with a
message that names the spec, file or field.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol, runtime_checkable

import numpy as np

from doodle.core.errors import DoodleError
from doodle.core.npz import read_npz

__all__ = [
    "Terrain",
    "Flat",
    "HeightField",
    "Mesh",
    "moller_trumbore",
    "sample_elevation",
    "parse_terrain",
    "load_mesh",
    "load_heightfield",
    "SAMPLE_NAMES",
    "SAMPLE_RELIEF_RATIO",
]

#: Gravity direction (unit vector) along which rays are cast.
GRAVITY = np.array([0.0, -1.0, 0.0])

#: Relief (max − min height) of :func:`sample_elevation` terrains, as a fraction of their size:
#: the Jacksboro DEM at true scale (840 m of relief over its 30 km: heights shrunk as much as
#: distances, so its slopes are the landscape's own — a median of about 9°, where 0.15 made a
#: field of 40–65° scarps no one can walk); the MRI slice, a bumpy test surface.
SAMPLE_RELIEF_RATIO = {"jacksboro": 0.028, "s1045": 0.15}

#: Names accepted by :func:`sample_elevation` (and as terrain specs).
SAMPLE_NAMES = ("jacksboro", "s1045")

#: How far from the origin a terrain may reach, and the finest grid spacing (metres): a room, a
#: landscape, and far more, while squares and differences of coordinates stay finite — a
#: file beyond them is corrupt, not a terrain.
MAX_METRES = 1e6
MIN_SPACING = 1e-6

# Barycentric tolerance (dimensionless): rays through a shared edge or vertex still hit.
_BARY_TOL = 1e-9
# Pairs (ray, triangle) tested at once: bounds the temporary arrays to a few hundred MB.
_MAX_PAIRS = 1 << 20


@runtime_checkable
class Terrain(Protocol):
    """The common interface of :class:`Flat`, :class:`HeightField` and :class:`Mesh`."""

    def height(self, xz) -> np.ndarray: ...

    def project(self, points) -> np.ndarray: ...


# --------------------------------------------------------------------------------------
# input checks


def _points(values, dim: int, what: str) -> tuple[np.ndarray, tuple[int, ...]]:
    """``(..., dim)`` finite floats → ``(n, dim)`` array and the leading shape."""
    try:
        arr = np.asarray(values, dtype=float)
    except (TypeError, ValueError) as exc:
        raise DoodleError(f"terrain: {what} must be numbers, shape (n, {dim}): {exc}") from None
    if arr.ndim == 0 or arr.shape[-1] != dim:
        raise DoodleError(f"terrain: {what} must have shape (n, {dim}), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise DoodleError(f"terrain: {what} contain NaN or infinite values")
    lead = arr.shape[:-1]
    return arr.reshape(-1, dim), lead


def _finite_float(value, what: str) -> float:
    try:
        out = float(value)
    except (TypeError, ValueError):
        raise DoodleError(f"terrain: {what} must be a number, got {value!r}") from None
    if not math.isfinite(out):
        raise DoodleError(f"terrain: {what} must be finite, got {value!r}")
    return out


def _readonly(arr: np.ndarray) -> np.ndarray:
    arr = np.array(arr, dtype=float, copy=True)
    arr.setflags(write=False)
    return arr


# --------------------------------------------------------------------------------------
# flat ground


@dataclass(frozen=True)
class Flat:
    """Flat ground: the plane ``y = height``."""

    height_m: float = 0.0

    def __init__(self, height: float = 0.0):
        object.__setattr__(self, "height_m", _finite_float(height, "flat ground height"))

    def height(self, xz) -> np.ndarray:
        pts, lead = _points(xz, 2, "horizontal points (x, z)")
        return np.full(lead, self.height_m)

    def project(self, points) -> np.ndarray:
        pts, lead = _points(points, 3, "points")
        out = pts.copy()
        out[:, 1] = self.height_m
        return out.reshape(lead + (3,))


# --------------------------------------------------------------------------------------
# height field


@dataclass(frozen=True, eq=False)
class HeightField:
    """A regular grid of heights, bilinear in between, edge values held outside.

    ``heights[i, j]`` is the ground height at ``x = origin[0] + j * spacing``,
    ``z = origin[1] + i * spacing``: rows run along z, columns along x.
    """

    heights: np.ndarray
    spacing: float = 1.0
    origin: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self):
        try:
            h = np.asarray(self.heights, dtype=float)
        except (TypeError, ValueError) as exc:
            raise DoodleError(f"height field: heights must be numbers: {exc}") from None
        if h.ndim != 2 or h.shape[0] < 2 or h.shape[1] < 2:
            raise DoodleError(
                f"height field: heights must be a 2-D array of at least 2×2, got shape {h.shape}"
            )
        if not np.all(np.isfinite(h)):
            bad = int(np.count_nonzero(~np.isfinite(h)))
            raise DoodleError(f"height field: heights contain {bad} NaN or infinite values")
        if np.abs(h).max() > MAX_METRES:
            raise DoodleError(f"height field: heights reach {np.abs(h).max():.3g} m; at most {MAX_METRES:g} m")
        spacing = _finite_float(self.spacing, "height field spacing")
        if spacing <= 0:
            raise DoodleError(f"height field: spacing must be > 0, got {spacing}")
        if not MIN_SPACING <= spacing * (max(h.shape) - 1) <= MAX_METRES or spacing < MIN_SPACING:
            raise DoodleError(f"height field: spacing {spacing:g} m makes a grid of {spacing * (max(h.shape) - 1):.3g} m; "
                              f"spacing at least {MIN_SPACING:g} m and a grid at most {MAX_METRES:g} m")
        try:
            origin = np.asarray(self.origin, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            raise DoodleError(f"height field: origin must be (x0, z0), got {self.origin!r}") from None
        if origin.shape != (2,) or not np.all(np.isfinite(origin)) or np.abs(origin).max() > MAX_METRES:
            raise DoodleError(f"height field: origin must be two numbers (x0, z0) within {MAX_METRES:g} m, "
                              f"got {self.origin!r}")
        object.__setattr__(self, "heights", _readonly(h))
        object.__setattr__(self, "spacing", spacing)
        object.__setattr__(self, "origin", (float(origin[0]), float(origin[1])))

    @classmethod
    def from_array(cls, heights, spacing: float = 1.0, origin=(0.0, 0.0)) -> "HeightField":
        return cls(heights, spacing, tuple(origin))

    @property
    def shape(self) -> tuple[int, int]:
        return self.heights.shape

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """``(x_min, x_max, z_min, z_max)`` of the grid nodes."""
        rows, cols = self.heights.shape
        x0, z0 = self.origin
        return (x0, x0 + (cols - 1) * self.spacing, z0, z0 + (rows - 1) * self.spacing)

    def height(self, xz) -> np.ndarray:
        pts, lead = _points(xz, 2, "horizontal points (x, z)")
        return self._bilinear(pts[:, 0], pts[:, 1]).reshape(lead)

    def _bilinear(self, x: np.ndarray, z: np.ndarray) -> np.ndarray:
        h = self.heights
        rows, cols = h.shape
        fx = np.clip((x - self.origin[0]) / self.spacing, 0.0, cols - 1)
        fz = np.clip((z - self.origin[1]) / self.spacing, 0.0, rows - 1)
        j = np.minimum(fx.astype(np.intp), cols - 2)
        i = np.minimum(fz.astype(np.intp), rows - 2)
        u = fx - j
        v = fz - i
        h00 = h[i, j]
        h01 = h[i, j + 1]
        h10 = h[i + 1, j]
        h11 = h[i + 1, j + 1]
        return (h00 * (1 - u) + h01 * u) * (1 - v) + (h10 * (1 - u) + h11 * u) * v

    def project(self, points) -> np.ndarray:
        # A height field is a function of (x, z): the vertical ray through a point meets it
        # exactly once, below the point or (for a point under the ground) above it.
        pts, lead = _points(points, 3, "points")
        out = pts.copy()
        out[:, 1] = self._bilinear(pts[:, 0], pts[:, 2])
        return out.reshape(lead + (3,))

    def to_mesh(self) -> "Mesh":
        """The grid as a triangle mesh: two triangles per cell, split along the diagonal
        from node ``(i+1, j)`` to ``(i, j+1)``, normals up (+y).

        Linear on each triangle, so it equals the bilinear field at the nodes and along
        cell edges; inside a cell the two differ by ``u*v*c`` (lower triangle) or
        ``(1-u)*(1-v)*c`` (upper), ``c = h00 - h01 - h10 + h11``: at most ``|c|/4``.
        """
        rows, cols = self.heights.shape
        x0, z0 = self.origin
        xs = x0 + np.arange(cols) * self.spacing
        zs = z0 + np.arange(rows) * self.spacing
        X, Z = np.meshgrid(xs, zs)
        vertices = np.column_stack([X.ravel(), self.heights.ravel(), Z.ravel()])
        idx = np.arange(rows * cols).reshape(rows, cols)
        a = idx[:-1, :-1].ravel()  # (i, j)
        b = idx[1:, :-1].ravel()  # (i+1, j)
        c = idx[:-1, 1:].ravel()  # (i, j+1)
        d = idx[1:, 1:].ravel()  # (i+1, j+1)
        faces = np.concatenate([np.column_stack([a, b, c]), np.column_stack([c, b, d])])
        return Mesh(vertices, faces)


# --------------------------------------------------------------------------------------
# Möller–Trumbore


def moller_trumbore(origins, direction, v0, e1, e2, tol: float = _BARY_TOL):
    """Vectorised Möller–Trumbore ray/triangle intersection (broadcasting over all inputs).

    ``origins`` and ``direction`` define the rays ``o + t d``; ``v0`` is a triangle corner
    and ``e1 = v1 - v0``, ``e2 = v2 - v0`` its edges. Returns ``(t, hit)``: the ray
    parameter of the intersection with each triangle's plane and whether it lies inside
    the triangle (barycentric tolerance ``tol``, so rays through shared edges hit). Both
    directions along the line are reported: ``t < 0`` is behind the origin. Triangles
    parallel to the ray (zero determinant) never hit.
    """
    pvec = np.cross(direction, e2)
    det = np.einsum("...k,...k->...", e1, pvec)
    scale = np.sqrt(np.einsum("...k,...k->...", e1, e1) * np.einsum("...k,...k->...", e2, e2))
    ok = np.abs(det) > 1e-12 * scale
    inv = np.divide(1.0, det, out=np.zeros_like(det), where=ok)
    tvec = origins - v0
    u = np.einsum("...k,...k->...", tvec, pvec) * inv
    qvec = np.cross(tvec, e1)
    v = np.einsum("...k,...k->...", direction * np.ones_like(qvec), qvec) * inv
    t = np.einsum("...k,...k->...", e2 * np.ones_like(qvec), qvec) * inv
    hit = ok & (u >= -tol) & (v >= -tol) & (u + v <= 1.0 + tol)
    return t, hit


def _reduce_hits(t: np.ndarray, hit: np.ndarray, tol_t: float, starts: np.ndarray):
    """Per ray (segments of ``t`` beginning at ``starts``): closest hit at or below the
    origin (smallest ``t >= -tol_t``) and closest hit above (largest ``t < -tol_t``)."""
    down = np.where(hit & (t >= -tol_t), t, np.inf)
    up = np.where(hit & (t < -tol_t), t, -np.inf)
    return np.minimum.reduceat(down, starts), np.maximum.reduceat(up, starts)


# --------------------------------------------------------------------------------------
# mesh


@dataclass(frozen=True, eq=False)
class _Grid:
    """Uniform xz grid over a mesh: ``cell_tris[start[c]:start[c+1]]`` are the triangles
    whose (padded) xz bounding box overlaps cell ``c = iz * nx + ix``."""

    x0: float
    z0: float
    hx: float
    hz: float
    nx: int
    nz: int
    start: np.ndarray
    cell_tris: np.ndarray

    def cells(self, x: np.ndarray, z: np.ndarray) -> np.ndarray:
        """Cell index of each point, −1 outside the grid."""
        fx = (x - self.x0) / self.hx
        fz = (z - self.z0) / self.hz
        inside = (fx >= 0) & (fx <= self.nx) & (fz >= 0) & (fz <= self.nz)
        ix = np.clip(np.floor(np.where(inside, fx, 0)).astype(np.intp), 0, self.nx - 1)
        iz = np.clip(np.floor(np.where(inside, fz, 0)).astype(np.intp), 0, self.nz - 1)
        return np.where(inside, iz * self.nx + ix, -1)


@dataclass(frozen=True, eq=False)
class Mesh:
    """A triangle mesh terrain: ``vertices`` (V, 3) in metres, ``faces`` (F, 3) indices.

    ``project`` and ``height`` cast vertical rays with :func:`moller_trumbore`, testing
    only the triangles bucketed in the ray's cell of a uniform xz grid (built on first use;
    ``accelerated=False`` tests every triangle instead — the brute-force reference).
    Rays that hit nothing keep x, z and take the height of the nearest vertex in xz.
    """

    vertices: np.ndarray
    faces: np.ndarray
    _cache: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    def __post_init__(self):
        try:
            v = np.asarray(self.vertices, dtype=float)
        except (TypeError, ValueError) as exc:
            raise DoodleError(f"mesh: vertices must be numbers: {exc}") from None
        if v.ndim != 2 or v.shape[1] != 3 or len(v) < 3:
            raise DoodleError(f"mesh: vertices must have shape (V, 3) with V >= 3, got {v.shape}")
        if not np.all(np.isfinite(v)):
            raise DoodleError("mesh: vertices contain NaN or infinite values")
        if np.abs(v).max() > MAX_METRES:
            raise DoodleError(f"mesh: vertices reach {np.abs(v).max():.3g} m from the origin; at most {MAX_METRES:g} m")
        f = np.asarray(self.faces)
        if f.ndim != 2 or f.shape[1] != 3 or len(f) < 1:
            raise DoodleError(f"mesh: faces must have shape (F, 3) with F >= 1, got {f.shape}")
        if not np.issubdtype(f.dtype, np.integer):
            if not np.issubdtype(f.dtype, np.floating) or not np.all(f == np.round(f)):
                raise DoodleError("mesh: faces must be integer vertex indices")
        f = f.astype(np.intp)
        if f.min() < 0 or f.max() >= len(v):
            raise DoodleError(
                f"mesh: face indices must lie in [0, {len(v) - 1}], got [{f.min()}, {f.max()}]"
            )
        object.__setattr__(self, "vertices", _readonly(v))
        f = f.copy()
        f.setflags(write=False)
        object.__setattr__(self, "faces", f)

    # -- cached geometry ------------------------------------------------------------

    def _tri(self):
        if "tri" not in self._cache:
            v0 = self.vertices[self.faces[:, 0]]
            e1 = self.vertices[self.faces[:, 1]] - v0
            e2 = self.vertices[self.faces[:, 2]] - v0
            self._cache["tri"] = (v0, e1, e2)
        return self._cache["tri"]

    def _tol_t(self) -> float:
        span = float(np.ptp(self.vertices, axis=0).max()) if len(self.vertices) else 1.0
        return 1e-9 * max(span, 1.0)

    def _nearest_vertex_height(self, xz: np.ndarray) -> np.ndarray:
        if "kdtree" not in self._cache:
            from scipy.spatial import cKDTree

            self._cache["kdtree"] = cKDTree(self.vertices[:, [0, 2]])
        _, idx = self._cache["kdtree"].query(xz)
        return self.vertices[idx, 1]

    def grid(self) -> _Grid:
        """The xz acceleration grid (built once, about two cells per triangle)."""
        if "grid" not in self._cache:
            self._cache["grid"] = self._build_grid()
        return self._cache["grid"]

    def _build_grid(self) -> _Grid:
        v0, e1, e2 = self._tri()
        # Triangles seen edge-on from above can never be hit by a vertical ray.
        area2 = np.abs(e1[:, 0] * e2[:, 2] - e1[:, 2] * e2[:, 0])
        keep = np.flatnonzero(area2 > 1e-12 * (np.linalg.norm(e1, axis=1) * np.linalg.norm(e2, axis=1)))
        xz = self.vertices[:, [0, 2]][self.faces[keep]]  # (K, 3, 2)
        lo_all = self.vertices[:, [0, 2]].min(axis=0)
        hi_all = self.vertices[:, [0, 2]].max(axis=0)
        span = np.maximum(hi_all - lo_all, 1e-9)
        pad = 1e-9 * max(float(span.max()), 1.0)
        lo = lo_all - 2 * pad
        hi = hi_all + 2 * pad
        ext = hi - lo
        target = max(2.0 * len(keep), 1.0)
        h = math.sqrt(ext[0] * ext[1] / target)
        nx = int(np.clip(math.ceil(ext[0] / h), 1, 4096))
        nz = int(np.clip(math.ceil(ext[1] / h), 1, 4096))
        hx, hz = ext[0] / nx, ext[1] / nz
        tmin = xz.min(axis=1) - pad
        tmax = xz.max(axis=1) + pad
        ix0 = np.clip(np.floor((tmin[:, 0] - lo[0]) / hx).astype(np.intp), 0, nx - 1)
        ix1 = np.clip(np.floor((tmax[:, 0] - lo[0]) / hx).astype(np.intp), 0, nx - 1)
        iz0 = np.clip(np.floor((tmin[:, 1] - lo[1]) / hz).astype(np.intp), 0, nz - 1)
        iz1 = np.clip(np.floor((tmax[:, 1] - lo[1]) / hz).astype(np.intp), 0, nz - 1)
        w = ix1 - ix0 + 1
        counts = w * (iz1 - iz0 + 1)
        total = int(counts.sum())
        owner = np.repeat(np.arange(len(keep)), counts)
        k = np.arange(total) - np.repeat(np.cumsum(counts) - counts, counts)
        cell = (iz0[owner] + k // w[owner]) * nx + ix0[owner] + k % w[owner]
        order = np.argsort(cell, kind="stable")
        cell_tris = keep[owner[order]]
        start = np.zeros(nx * nz + 1, dtype=np.intp)
        np.cumsum(np.bincount(cell, minlength=nx * nz), out=start[1:])
        return _Grid(float(lo[0]), float(lo[1]), float(hx), float(hz), nx, nz, start, cell_tris)

    # -- ray casting ----------------------------------------------------------------

    def _cast(self, origins: np.ndarray, accelerated: bool) -> tuple[np.ndarray, np.ndarray]:
        """Vertical rays from ``origins`` (n, 3): ``t`` of the closest hit below (``inf`` if
        none) and of the closest hit above (``-inf`` if none); the hit is ``y - t``."""
        n = len(origins)
        down = np.full(n, np.inf)
        up = np.full(n, -np.inf)
        if n == 0:
            return down, up
        if accelerated:
            self._cast_grid(origins, down, up)
        else:
            self._cast_brute(origins, down, up)
        return down, up

    def _cast_brute(self, origins, down, up):
        v0, e1, e2 = self._tri()
        nf = len(v0)
        tol_t = self._tol_t()
        chunk = max(1, _MAX_PAIRS // nf)
        for s in range(0, len(origins), chunk):
            o = origins[s : s + chunk]
            t, hit = moller_trumbore(o[:, None, :], GRAVITY, v0[None], e1[None], e2[None])
            starts = np.arange(0, t.size, nf)
            d, u = _reduce_hits(t.ravel(), hit.ravel(), tol_t, starts)
            down[s : s + chunk] = d
            up[s : s + chunk] = u

    def _cast_grid(self, origins, down, up):
        g = self.grid()
        v0, e1, e2 = self._tri()
        tol_t = self._tol_t()
        cell = g.cells(origins[:, 0], origins[:, 2])
        rays = np.flatnonzero(cell >= 0)
        cell = cell[rays]
        first = g.start[cell]
        counts = g.start[cell + 1] - first
        has = counts > 0
        rays, first, counts = rays[has], first[has], counts[has]
        if len(rays) == 0:
            return
        # Split the rays into chunks of at most _MAX_PAIRS (ray, triangle) pairs.
        ends = np.cumsum(counts)
        bounds = [0]
        while bounds[-1] < len(rays):
            base = ends[bounds[-1] - 1] if bounds[-1] > 0 else 0
            nxt = int(np.searchsorted(ends, base + _MAX_PAIRS, side="right"))
            bounds.append(max(nxt, bounds[-1] + 1))
        for a, b in zip(bounds[:-1], bounds[1:]):
            cnt = counts[a:b]
            offs = np.cumsum(cnt) - cnt
            total = int(cnt.sum())
            ray_of = np.repeat(np.arange(b - a), cnt)
            k = np.arange(total) - np.repeat(offs, cnt)
            tri = g.cell_tris[np.repeat(first[a:b], cnt) + k]
            t, hit = moller_trumbore(origins[rays[a:b]][ray_of], GRAVITY, v0[tri], e1[tri], e2[tri])
            d, u = _reduce_hits(t, hit, tol_t, offs)
            down[rays[a:b]] = d
            up[rays[a:b]] = u

    def project(self, points, accelerated: bool = True) -> np.ndarray:
        pts, lead = _points(points, 3, "points")
        down, up = self._cast(pts, accelerated)
        t = np.where(np.isfinite(down), down, up)
        out = pts.copy()
        ok = np.isfinite(t)
        out[ok, 1] = pts[ok, 1] - t[ok]
        if not np.all(ok):
            out[~ok, 1] = self._nearest_vertex_height(pts[~ok][:, [0, 2]])
        return out.reshape(lead + (3,))

    def height(self, xz, accelerated: bool = True) -> np.ndarray:
        """Height of the topmost surface above each (x, z) (nearest vertex height where
        the vertical line through it misses the mesh)."""
        pts, lead = _points(xz, 2, "horizontal points (x, z)")
        top = float(self.vertices[:, 1].max()) + 1.0
        origins = np.column_stack([pts[:, 0], np.full(len(pts), top), pts[:, 1]])
        return self.project(origins, accelerated=accelerated)[:, 1].reshape(lead)


# --------------------------------------------------------------------------------------
# loading


def load_mesh(path, spec: str | None = None) -> Mesh:
    """Load a triangle mesh file: OBJ by :mod:`retarget.objfile` (errors name the line), any
    other format ``trimesh.load`` reads (PLY, GLB, STL…) by trimesh."""
    where = f"terrain {spec!r}: " if spec else "terrain: "
    p = Path(path)
    if not p.is_file():
        raise DoodleError(f"{where}mesh file {str(p)!r} not found")
    if p.suffix.lower() == ".obj":
        from retarget.objfile import read_obj

        try:
            vertices, faces = read_obj(p, MAX_METRES)
        except DoodleError as exc:
            raise DoodleError(f"{where}{exc}") from None
    else:
        vertices, faces = _trimesh_load(p, where)
    if faces.ndim != 2 or len(faces) == 0 or len(vertices) < 3:
        raise DoodleError(f"{where}mesh file {str(p)!r} has no triangles")
    try:
        return Mesh(vertices, faces)
    except DoodleError as exc:
        raise DoodleError(f"{where}mesh file {str(p)!r}: {exc}") from None


def _trimesh_load(p: Path, where: str) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and faces of a mesh file trimesh reads; its warnings silenced (a broken file
    is refused with the reason, not accompanied by numpy's overflow notes)."""
    import warnings

    try:
        import trimesh
    except ImportError:
        raise DoodleError(f"{where}loading mesh {str(p)!r} needs the trimesh package (pip install trimesh)") from None
    try:
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            m = trimesh.load(str(p), force="mesh")
            vertices = np.asarray(m.vertices, dtype=float)
            faces = np.asarray(m.faces)
    except Exception as exc:  # trimesh raises many types for unreadable files
        msg = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        kind = p.suffix.lstrip(".").upper() or "mesh"
        raise DoodleError(f"{where}cannot read mesh file {str(p)!r}: not a valid {kind} file ({msg})") from None
    return vertices, faces


def load_heightfield(path, spacing: float | None = None, spec: str | None = None) -> HeightField:
    """Load a height field from an ``.npz`` holding ``heights`` (rows, cols) and optionally
    ``spacing`` (scalar) and ``origin`` (x0, z0). ``spacing`` given here overrides the file's."""
    where = f"terrain {spec!r}: " if spec else "terrain: "
    p = Path(path)
    if not p.is_file():
        raise DoodleError(f"{where}height field file {str(p)!r} not found")
    data = read_npz(p, f"{where}height field file {str(p)!r}")
    if "heights" not in data:
        raise DoodleError(f"{where}{str(p)!r} has no array named 'heights' (found: {', '.join(data) or 'none'})")
    heights, file_spacing, origin = data["heights"], data.get("spacing"), data.get("origin")
    for name, value in (("spacing", file_spacing), ("origin", origin)):
        if value is not None and (value.dtype.kind not in "fiu"):
            raise DoodleError(f"{where}{str(p)!r}: {name!r} must be real numbers, got dtype {value.dtype}")
    if heights.dtype.kind not in "fiu":
        raise DoodleError(f"{where}{str(p)!r}: 'heights' must be real numbers, got dtype {heights.dtype}")
    if spacing is None:
        if file_spacing is not None:
            if file_spacing.size != 1:
                raise DoodleError(f"{where}{str(p)!r}: 'spacing' must be a single number, got shape {file_spacing.shape}")
            spacing = file_spacing.reshape(-1)[0]
        else:
            spacing = 1.0
    if origin is None:
        origin = (0.0, 0.0)
    elif origin.size != 2:
        raise DoodleError(f"{where}{str(p)!r}: 'origin' must hold two numbers (x0, z0), got shape {origin.shape}")
    try:
        return HeightField(heights, spacing, tuple(np.asarray(origin).reshape(-1)))
    except DoodleError as exc:
        raise DoodleError(f"{where}{str(p)!r}: {exc}") from None


def _sample_grid(name: str) -> np.ndarray:
    from matplotlib import cbook

    if name == "jacksboro":
        with cbook.get_sample_data("jacksboro_fault_dem.npz") as data:
            return np.asarray(data["elevation"], dtype=float)
    if name == "s1045":
        with cbook.get_sample_data("s1045.ima.gz") as f:
            raw = f.read()
        return np.frombuffer(raw, dtype=np.uint16).reshape(256, 256).astype(float)
    raise DoodleError(f"terrain: unknown sample elevation {name!r} (known: {', '.join(SAMPLE_NAMES)})")


def sample_elevation(name: str = "jacksboro", size: float = 20.0) -> HeightField:
    """A real elevation grid from matplotlib's sample data, rescaled to a play area.

    * ``"jacksboro"``: the Jacksboro fault DEM (344 × 403, elevations 236–1076 m over
      about 30 km × 38 km);
    * ``"s1045"``: matplotlib's ``s1045.ima.gz``, a 256 × 256 uint16 grid (an MRI slice,
      not an elevation model — a bumpy test surface).

    Scaling: the grid's longer side spans ``size`` metres (``spacing = size / (max(rows,
    cols) - 1)``), heights are shifted so the minimum is 0 and scaled so the relief
    (max − min) is ``SAMPLE_RELIEF_RATIO[name] * size`` (0.56 m of Jacksboro for the default 20 m), and the grid
    is centred on the origin in x and z.
    """
    size = _finite_float(size, "sample elevation size")
    if not 0 < size <= MAX_METRES:
        raise DoodleError(f"terrain: sample elevation size must be > 0 and at most {MAX_METRES:g} metres, got {size}")
    if name not in SAMPLE_NAMES:
        raise DoodleError(f"terrain: unknown sample elevation {name!r} (known: {', '.join(SAMPLE_NAMES)})")
    grid = _sample_grid(name)
    rows, cols = grid.shape
    spacing = size / (max(rows, cols) - 1)
    lo, hi = float(grid.min()), float(grid.max())
    heights = (grid - lo) * (SAMPLE_RELIEF_RATIO[name] * size / (hi - lo))
    origin = (-(cols - 1) * spacing / 2.0, -(rows - 1) * spacing / 2.0)
    return HeightField(heights, spacing, origin)


def parse_terrain(spec: str):
    """A terrain from a spec string.

    ``flat`` · ``flat:HEIGHT`` · ``jacksboro`` / ``jacksboro:SIZE`` (also ``s1045``) ·
    ``heightfield:PATH.npz[:SPACING]`` · ``mesh:PATH`` (OBJ / PLY / GLB / STL, via trimesh).
    """
    if not isinstance(spec, str) or not spec.strip():
        raise DoodleError(
            f"terrain {spec!r}: empty spec (expected flat[:HEIGHT], jacksboro[:SIZE], "
            "heightfield:PATH.npz[:SPACING] or mesh:PATH)"
        )
    text = spec.strip()
    kind, sep, rest = text.partition(":")
    kind = kind.strip().lower()

    def number(value: str, what: str) -> float:
        try:
            out = float(value)
        except ValueError:
            raise DoodleError(f"terrain {spec!r}: {what} must be a number, got {value!r}") from None
        if not math.isfinite(out):
            raise DoodleError(f"terrain {spec!r}: {what} must be finite, got {value!r}")
        return out

    if kind == "flat":
        return Flat(number(rest, "flat height") if sep else 0.0)
    if kind in SAMPLE_NAMES:
        size = number(rest, "size in metres") if sep else 20.0
        if not 0 < size <= MAX_METRES:
            raise DoodleError(f"terrain {spec!r}: size must be > 0 and at most {MAX_METRES:g} metres, got {size}")
        return sample_elevation(kind, size)
    if kind == "heightfield":
        if not rest:
            raise DoodleError(f"terrain {spec!r}: expected heightfield:PATH.npz[:SPACING]")
        path, spacing = rest, None
        head, colon, tail = rest.rpartition(":")
        if colon and head and not Path(rest).is_file():
            spacing = number(tail, "height field spacing")
            if spacing <= 0:
                raise DoodleError(f"terrain {spec!r}: spacing must be > 0, got {spacing}")
            path = head
        return load_heightfield(path, spacing, spec=spec)
    if kind == "mesh":
        if not rest:
            raise DoodleError(f"terrain {spec!r}: expected mesh:PATH (OBJ, PLY, GLB or STL)")
        return load_mesh(rest, spec=spec)
    raise DoodleError(
        f"terrain {spec!r}: unknown kind {kind!r} (expected flat[:HEIGHT], jacksboro[:SIZE], "
        "s1045[:SIZE], heightfield:PATH.npz[:SPACING] or mesh:PATH)"
    )
