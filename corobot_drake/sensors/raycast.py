"""Exact, vectorised ray casting against the proximity geometry of a Drake SceneGraph.

Drake's ``QueryObject`` has no ray-cast query, so the IR distance sensors
cast their rays here, analytically, against the shapes that ``SceneGraphInspector`` exposes,
posed by ``QueryObject.GetPoseInWorld``.

Supported shapes (all intersections are exact, closed form):

- ``Box``, ``Sphere``, ``Cylinder``, ``Capsule``, ``Ellipsoid``, ``HalfSpace``;
- ``Convex`` and ``Mesh``: the convex hull SceneGraph itself reports for the geometry
  (``SceneGraphInspector.GetConvexHull``, scale included). For ``Convex`` this is the shape;
  for a concave ``Mesh`` it is the same approximation Drake's own point-contact and
  signed-distance queries make, and it is logged (INFO) once per geometry.
- A ``Mesh`` that touches with its own surface (rigid hydroelastic proximity properties: the
  loader's ``collision: mesh``): the triangles of SceneGraph's rigid hydroelastic surface for
  it (``SceneGraphInspector.maybe_get_hydroelastic_mesh``), exactly, concave or not,
  in a planar cast (:meth:`RayCaster.cast_plane` with a ``normal``, the lidar's), which slices
  them by the scan plane into segments; other casts (``cast_fan``, the IR sensors') see its
  convex hull.

Anything else (e.g. ``MeshcatCone``, deformable geometries, a mesh whose hull can't be built) is
reported once, when the :class:`RayCaster` is built, with a ``logging`` WARNING naming the
geometry and its shape type, and is listed in :attr:`RayCaster.unsupported`.

Conventions:

- Rays are ``origin + t * direction`` with unit ``direction`` and ``0 <= t <= max_range``;
  ``t`` is therefore a distance in metres.
- Solids are closed sets. **A ray whose origin is inside (or on the surface of) a solid hits it
  at distance 0.** A half-space is the solid ``z <= 0`` of its frame.
- A ray that hits nothing within ``max_range`` reports distance ``inf``, hit point ``nan``
  and geometry index ``-1``.

A :class:`RayCaster` holds only data precomputed from the inspector at construction; a cast is a
pure function of the ``QueryObject`` and the rays, so it can run inside a LeafSystem's periodic
update (no caches, no global state).

The cast is :meth:`RayCaster.cast_fan`: rays from one origin, e.g. a sensor's :class:`RayFan`, in
plain Python floats, which for a handful of rays is several times cheaper than numpy's per-call
overhead: a bounding-sphere-in-cone test rejects geometry first, half-spaces and boxes are then
cast in scalar code, and the other shapes through the numpy kernels below. (The tests check it
against a batch caster on the same kernels, ``tests/reference_raycast.py``.)
"""

from __future__ import annotations

import copy
import dataclasses
import logging
import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass

import numpy as np
from pydrake.geometry import (
    Box,
    Capsule,
    Convex,
    Cylinder,
    Ellipsoid,
    GeometryId,
    HalfSpace,
    Mesh,
    QueryObject,
    Role,
    SceneGraphInspector,
    Sphere,
    TriangleSurfaceMesh,
)
from pydrake.math import RigidTransform

from corobot_drake.robots import corobot

_log = logging.getLogger(__name__)

DEFAULT_DISPERSION_CONE_ANGLE = corobot.sensor("ir_sensors", "front")["dispersion_cone_angle"]
"""Degrees: the IR sensor's dispersion cone (the Corobot's, its robot file's)."""


# --------------------------------------------------------------------------------------------
# Polytopes (Box, HalfSpace, Convex/Mesh hulls): Cyrus-Beck clipping against the face planes
# n . x <= h (outward normals), all polytopes of a scan in one matrix product.
#
# t = num / denom with num = h - n . o (>= 0 on the inner side) and denom = n . d. denom < 0: the
# ray enters through that plane at t; denom > 0: it leaves at t. Parallel rays need no branch:
# _TINY is added to every denominator (it changes none that isn't 0 or subnormal), so a ray
# parallel to a plane "leaves" it at t = num / _TINY, about +1e300 when inside (no constraint),
# -1e300 when outside (empty interval: a miss), and 0 when on the plane (it touches it at the
# origin only). No division by zero, no nan, no numpy warnings, for |num| < 1e8 m.
# --------------------------------------------------------------------------------------------

_TINY = 1e-300


def _polytope_distances(
    origins: np.ndarray,
    directions: np.ndarray,
    normals: np.ndarray,
    offsets: np.ndarray,
    starts: list[int],
    max_range: float,
) -> np.ndarray:
    """(N, K) first-hit distance of every ray against K polytopes, inf for a miss.

    normals (3, F) and offsets (F,) hold the world-frame face planes of all K polytopes; polytope
    k owns columns starts[k]:starts[k+1].
    """
    denom = directions @ normals + _TINY
    t = (offsets - origins @ normals) / denom
    entering = denom < 0.0
    # Entering planes bound the hit from below, leaving planes from above. Seeding the masked
    # entries with 0 and max_range folds "t >= 0" and "t <= max_range" into the reductions
    # (every polytope has a leaving plane for every ray: half-spaces get a null one).
    t_in = np.where(entering, t, 0.0)
    t_out = np.where(entering, max_range, t)
    if len(starts) > 1:
        t_in = np.maximum.reduceat(t_in, starts, axis=1)
        t_out = np.minimum.reduceat(t_out, starts, axis=1)
    else:
        t_in = t_in.max(axis=1, keepdims=True)
        t_out = t_out.min(axis=1, keepdims=True)
    return np.where(t_in <= t_out, t_in, np.inf)


def _first_hit(t_in: np.ndarray, t_out: np.ndarray, max_range: float) -> np.ndarray:
    """First hit at 0 <= t <= max_range of the line-in-solid interval [t_in, t_out] (empty when
    t_in > t_out): 0 when the origin is inside, inf when there is none."""
    t0 = np.maximum(t_in, 0.0)
    return np.where(t0 <= np.minimum(t_out, max_range), t0, np.inf)


# --------------------------------------------------------------------------------------------
# Curved shapes, one geometry at a time, in the geometry frame G.
#
# Each convex piece yields, per ray, the parameter interval [t_in, t_out] over which the line lies
# inside the solid. o and d are (M, 3) in G; d is unit length (rotations preserve it).
# --------------------------------------------------------------------------------------------


def _quadric_interval(a: np.ndarray, b: np.ndarray, c: np.ndarray):
    """Interval where a t^2 + 2 b t + c <= 0, for a > 0; empty when the discriminant is < 0."""
    disc = b * b - a * c
    root = np.sqrt(np.maximum(disc, 0.0))
    t_in = (-b - root) / a
    t_out = (-b + root) / a
    empty = disc < 0.0
    return np.where(empty, np.inf, t_in), np.where(empty, -np.inf, t_out)


def _sphere_interval(o: np.ndarray, d: np.ndarray, radius: float):
    b = (o * d).sum(axis=1)
    c = (o * o).sum(axis=1) - radius * radius
    return _quadric_interval(np.ones_like(b), b, c)


def _cylinder_interval(o: np.ndarray, d: np.ndarray, radius: float, half_length: float):
    """Cylinder about the z axis, z in [-half_length, half_length]."""
    oxy, dxy = o[:, :2], d[:, :2]
    # _TINY keeps a > 0 for a ray along the axis: its interval becomes about (-1e150, 1e150)
    # when inside the infinite cylinder, empty when outside.
    a = (dxy * dxy).sum(axis=1) + _TINY
    b = (oxy * dxy).sum(axis=1)
    c = (oxy * oxy).sum(axis=1) - radius * radius
    t_in, t_out = _quadric_interval(a, b, c)
    # The end caps: the slab |z| <= half_length (same _TINY reasoning as the polytopes).
    oz, dz = o[:, 2], d[:, 2] + _TINY
    t1 = (-half_length - oz) / dz
    t2 = (half_length - oz) / dz
    return np.maximum(t_in, np.minimum(t1, t2)), np.minimum(t_out, np.maximum(t1, t2))


def _hit_sphere(o, d, p, max_range):
    return _first_hit(*_sphere_interval(o, d, p["radius"]), max_range)


def _hit_ellipsoid(o, d, p, max_range):
    # Scale to the unit sphere; t keeps its meaning because the same t parametrises both lines.
    inv = p["inv_axes"]
    os, ds = o * inv, d * inv
    a = (ds * ds).sum(axis=1)
    b = (os * ds).sum(axis=1)
    c = (os * os).sum(axis=1) - 1.0
    return _first_hit(*_quadric_interval(a, b, c), max_range)


def _hit_cylinder(o, d, p, max_range):
    return _first_hit(*_cylinder_interval(o, d, p["radius"], p["half_length"]), max_range)


def _hit_capsule(o, d, p, max_range):
    """A capsule is the union of a cylinder and two spheres: the first hit is the nearest."""
    r, h = p["radius"], p["half_length"]
    t = _first_hit(*_cylinder_interval(o, d, r, h), max_range)
    for z in (h, -h):
        cap = _first_hit(*_sphere_interval(o - np.array([0.0, 0.0, z]), d, r), max_range)
        t = np.minimum(t, cap)
    return t


# --------------------------------------------------------------------------------------------
# Meshes that touch with their own surface, in a planar scan: the triangles are sliced by the
# scan plane into segments (O(triangles)), then every ray meets every segment (O(rays x
# segments)), all in the plane's 2D coordinates, in numpy.
#
# A vertex is "above" when its signed distance s to the plane is > 0, else below (on the plane
# counts as below): each triangle with vertices on both sides crosses the plane along one
# segment between its two crossing edges, and a triangle lying in the plane gives none (its
# neighbours' edges bound it). An edge from a (s_a) to b (s_b) crosses at a + w (b - a),
# w = s_a / (s_a - s_b), never 0 / 0 since s_a and s_b lie on either side of 0.
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Surface:
    """A triangle mesh in its geometry frame G."""

    vertices: np.ndarray
    """(V, 3) m."""
    triangles: np.ndarray
    """(T, 3) vertex indices, counter-clockwise seen from outside (the solid's)."""
    normals: np.ndarray
    """(T, 3) the triangles' outward normals (not normalised)."""
    box_center: np.ndarray
    """(3,) m, the centre of the vertices' axis-aligned bounding box."""
    box_half: np.ndarray
    """(3,) m, its half sizes."""


def _surface_of(inspector: SceneGraphInspector, gid: GeometryId) -> _Surface | None:
    """A Mesh's triangles when it touches with its own surface: the rigid hydroelastic
    surface SceneGraph built from it (Drake's contact then uses that surface, not the hull);
    None for any other geometry."""
    mesh = inspector.maybe_get_hydroelastic_mesh(gid)
    if not isinstance(mesh, TriangleSurfaceMesh) or mesh.num_triangles() == 0:
        return None
    vertices = np.array(mesh.vertices(), dtype=float).reshape(-1, 3)
    triangles = np.array([[t.vertex(i) for i in range(3)] for t in mesh.triangles()],
                         dtype=np.intp).reshape(-1, 3)
    a, b, c = (vertices[triangles[:, i]] for i in range(3))
    low, high = vertices.min(axis=0), vertices.max(axis=0)
    return _Surface(vertices, triangles, np.cross(b - a, c - a), 0.5 * (low + high),
                    0.5 * (high - low))


def _plane_segments(surface: _Surface, Q: np.ndarray):
    """The segments where the scan plane cuts the surface: (A, E, M), each (S, 2) in the
    plane's coordinates, a segment running from A to A + E, M its outward normal there.
    Q (V, 3): every vertex in the plane's coordinates (x, y, signed distance)."""
    above = Q[:, 2] > 0.0
    up = above[surface.triangles]
    crossing = up != up[:, [1, 2, 0]]  # edges (0, 1), (1, 2), (2, 0)
    keep = crossing.any(axis=1)
    triangles, crossing = surface.triangles[keep], crossing[keep]
    rows = np.arange(len(triangles))
    ends = []
    for edge in (np.argmax(crossing, axis=1), 2 - np.argmax(crossing[:, ::-1], axis=1)):
        a = Q[triangles[rows, edge]]
        b = Q[triangles[rows, (edge + 1) % 3]]
        w = a[:, 2] / (a[:, 2] - b[:, 2])
        ends.append(a[:, :2] + w[:, None] * (b[:, :2] - a[:, :2]))
    return ends[0], ends[1] - ends[0], keep


def _surface_distances(surface: _Surface, X_WG: np.ndarray, origin: np.ndarray,
                       basis: np.ndarray, rays: _PlaneRays, max_range: float) -> np.ndarray | None:
    """(N,) first-hit distance of rays in a plane against a surface posed at X_WG, inf for a
    miss; None when the plane misses the surface's bounding box. origin (3,) world; basis (3,
    3) world columns u, v (the plane's axes) and its normal n; rays: the unit rays in u, v.
    A ray whose first hit leaves the solid (the origin is inside) reads 0."""
    R = X_WG[:, :3]
    o_G = (origin - X_WG[:, 3]) @ R
    B_G = R.T @ basis  # the plane's axes and normal in G
    n_G = B_G[:, 2]
    if abs((surface.box_center - o_G) @ n_G) > np.abs(n_G) @ surface.box_half:
        return None
    A, E, keep = _plane_segments(surface, (surface.vertices - o_G) @ B_G)
    if not len(A):
        return None
    ray, seg = rays.pairs(A, A + E)
    D, A, E = rays.D[ray], A[seg], E[seg]
    # Ray t D meets segment A + s E where t D x E = A x E and s D x E = A x D.
    den = D[:, 0] * E[:, 1] - D[:, 1] * E[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (A[:, 0] * E[:, 1] - A[:, 1] * E[:, 0]) / den
        s = (A[:, 0] * D[:, 1] - A[:, 1] * D[:, 0]) / den
    t = np.where((den != 0.0) & (s >= 0.0) & (s <= 1.0) & (t >= 0.0), t, np.inf)
    first = np.full(len(rays.D), np.inf)
    np.minimum.at(first, ray, t)
    # Leaving the solid at the first hit: the origin is inside. Where segments meet at the
    # hit (a corner), only if it leaves through all of them: a ray grazing a corner from
    # outside meets one face it enters and one it would leave.
    M = (surface.normals[keep][seg] @ B_G)[:, :2]
    entering = (t == first[ray]) & ((D * M).sum(axis=1) <= 0.0)
    leaving = np.isfinite(first)
    leaving[ray[entering]] = False
    first[leaving] = 0.0
    return np.where(first <= max_range, first, np.inf)


class _PlaneRays:
    """A planar scan's rays in the plane's axes u, v, sorted by bearing, to pair each segment
    with the rays whose bearings it spans (a ray can meet no other): a scan costs O(rays x
    the segments each ray's bearing crosses), not O(rays x segments)."""

    _MARGIN = 1e-9
    """rad: added to each segment's span, so that rounding never drops a ray that meets it."""

    def __init__(self, D: np.ndarray):
        self.D = D
        """(N, 2) the unit rays in u, v."""
        bearing = np.arctan2(D[:, 1], D[:, 0])
        self.order = np.argsort(bearing)
        sorted_bearing = bearing[self.order]
        self.bearings = np.concatenate([sorted_bearing, sorted_bearing + 2 * np.pi])
        """The sorted bearings (rad, in [-pi, pi]), then once more a turn later: a span that
        wraps past pi is one slice of it."""

    def pairs(self, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(ray, segment) indices of every ray whose bearing lies within a segment's span as
        seen from the origin (segments from a to b, (S, 2) each, relative to the origin)."""
        n = len(self.D)
        start = np.arctan2(a[:, 1], a[:, 0])
        width = np.arctan2(b[:, 1], b[:, 0]) - start
        width = np.where(width > np.pi, width - 2 * np.pi,
                         np.where(width < -np.pi, width + 2 * np.pi, width))
        start = np.where(width < 0.0, start + width, start) - self._MARGIN
        width = np.abs(width) + 2 * self._MARGIN
        # A segment through the origin, or nearly: every ray.
        everything = (width >= np.pi - self._MARGIN) | ~(
            (np.abs(a) > 1e-12).any(axis=1) & (np.abs(b) > 1e-12).any(axis=1))
        start = np.where(start < -np.pi, start + 2 * np.pi, start)
        first = np.searchsorted(self.bearings, start, side="left")
        count = np.searchsorted(self.bearings, start + width, side="right") - first
        first = np.where(everything, 0, first)
        count = np.where(everything, n, np.minimum(count, n))
        segment = np.repeat(np.arange(len(a)), count)
        offset = np.arange(len(segment)) - np.repeat(np.cumsum(count) - count, count)
        return self.order[(np.repeat(first, count) + offset) % n], segment


def _plane_basis(normal: np.ndarray) -> np.ndarray:
    """(3, 3) columns u, v, n: a right-handed orthonormal frame with n the plane's unit normal."""
    n = np.asarray(normal, dtype=float)
    helper = np.eye(3)[int(np.argmin(np.abs(n)))]
    u = np.cross(n, helper)
    u /= np.linalg.norm(u)
    return np.column_stack([u, np.cross(n, u), n])


_CurvedHit = Callable[[np.ndarray, np.ndarray, dict, float], np.ndarray]


@dataclass(frozen=True)
class _Target:
    """Precomputed data for one geometry (all in its frame G)."""

    geometry_id: GeometryId
    name: str
    shape_type: str
    center: np.ndarray
    """Bounding-sphere centre in G (for a half-space: a point on its boundary)."""
    radius: float
    """Bounding-sphere radius; inf for a half-space."""
    normals: np.ndarray | None = None
    """Polytopes: (3, F) outward face normals in G."""
    offsets: np.ndarray | None = None
    """Polytopes: (F,) plane offsets, the solid is normals.T @ x <= offsets."""
    hit: _CurvedHit | None = None
    """Curved shapes: first-hit distances of rays expressed in G."""
    params: dict | None = None
    surface: _Surface | None = None
    """A mesh touching with its own surface: its triangles (planar casts read them)."""


def _make_target(inspector: SceneGraphInspector, gid: GeometryId) -> _Target | str:
    """The target for a geometry, or a reason string when it can't be ray cast."""
    shape = inspector.GetShape(gid)
    name = inspector.GetName(gid)
    shape_type = type(shape).__name__
    zero = np.zeros(3)

    def curved(hit, params, radius):
        return _Target(gid, name, shape_type, zero, radius, hit=hit, params=params)

    def polytope(normals, offsets, center, radius):
        normals = np.ascontiguousarray(np.asarray(normals, float).T)
        center = np.asarray(center, float)
        return _Target(gid, name, shape_type, center, radius, normals, offsets)

    if isinstance(shape, Box):
        half = 0.5 * np.array([shape.width(), shape.depth(), shape.height()])
        normals = np.vstack([np.eye(3), -np.eye(3)])
        return polytope(normals, np.concatenate([half, half]), zero, float(np.linalg.norm(half)))
    if isinstance(shape, HalfSpace):
        # The boundary plane, plus a null plane (0 . x <= 1) that every ray "leaves" at ~1e300:
        # _polytope_distances needs a leaving plane in every polytope to clamp t_in at 0.
        return polytope([[0.0, 0.0, 1.0], [0.0, 0.0, 0.0]], np.array([0.0, 1.0]), zero, math.inf)
    if isinstance(shape, Sphere):
        r = shape.radius()
        return curved(_hit_sphere, {"radius": r}, r)
    if isinstance(shape, Ellipsoid):
        axes = np.array([shape.a(), shape.b(), shape.c()])
        return curved(_hit_ellipsoid, {"inv_axes": 1.0 / axes}, float(axes.max()))
    if isinstance(shape, Cylinder):
        r, h = shape.radius(), 0.5 * shape.length()
        return curved(_hit_cylinder, {"radius": r, "half_length": h}, math.hypot(r, h))
    if isinstance(shape, Capsule):
        r, h = shape.radius(), 0.5 * shape.length()
        return curved(_hit_capsule, {"radius": r, "half_length": h}, r + h)
    if isinstance(shape, (Mesh, Convex)):
        try:
            hull = inspector.GetConvexHull(gid)
        except Exception as e:  # Drake raises RuntimeError for unreadable/degenerate meshes.
            return f"its convex hull could not be computed ({e})"
        if hull is None or hull.num_faces() == 0:
            return "SceneGraph reports no convex hull for it"
        vertices = np.array([hull.vertex(i) for i in range(hull.num_vertices())])
        normals = np.array([hull.face_normal(f) for f in range(hull.num_faces())])
        offsets = np.array(
            [normals[f] @ vertices[hull.element(f).vertex(0)] for f in range(hull.num_faces())]
        )
        center = 0.5 * (vertices.min(axis=0) + vertices.max(axis=0))
        radius = float(np.linalg.norm(vertices - center, axis=1).max())
        made = polytope(normals, offsets, center, radius)
        surface = _surface_of(inspector, gid) if isinstance(shape, Mesh) else None
        if isinstance(shape, Mesh):
            _log.info(
                "RayCaster: geometry '%s' (id %s, Mesh %s) is ray cast as its convex hull "
                "(%d faces)%s.", name, gid, shape.source().description(), hull.num_faces(),
                ", as Drake's point-contact queries treat it" if surface is None else
                f" by fans, and by planar scans as its {len(surface.triangles)} triangles",
            )  # fmt: skip
        return made if surface is None else dataclasses.replace(made, surface=surface)
    return "there is no ray intersection for this shape type"


def _posed_planes(target: _Target, X34: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A polytope's world-frame face planes for the pose X34 = X_WG: (3, F) normals and (F,)
    offsets (precomputed once for anchored geometry)."""
    normals = X34[:, :3] @ target.normals
    return normals, target.offsets + X34[:, 3] @ normals


# --------------------------------------------------------------------------------------------
# One fan of rays from a single origin (an IR sensor's cross of rays): scalar Python.
#
# For a handful of rays numpy's per-call overhead (~1 us a call) outweighs the arithmetic, so
# RayCaster.cast_fan works on plain floats: a bounding-sphere-versus-cone test rejects most
# geometries with a few operations, half-spaces and boxes (the usual scene) are then cast
# exactly in scalar code, and the other shapes go through the numpy kernels above.
# --------------------------------------------------------------------------------------------

_HALF_SPACE, _BOX, _OTHER = range(3)
_MARGIN = 1e-9
"""m (and rad): added to bounding radii and cone angles so that rounding never culls a
geometry a ray grazes."""


class _FanTarget:
    """A target's data for cast_fan: plain floats, world frame when anchored."""

    __slots__ = ("R_FG", "center", "frame", "half", "index", "kind", "p_FG", "radius")

    def __init__(self, index, kind, frame, X34, center, radius, half):
        self.index = index
        self.kind = kind
        self.frame = frame
        """The FrameId whose world pose poses it; None when anchored (then X is X_WG)."""
        rows = X34.tolist()
        identity = frame is not None and np.array_equal(X34, np.eye(3, 4))
        self.R_FG = None if identity else tuple(v for row in rows for v in row[:3])
        """Row-major 3x3 rotation to the frame (the world when anchored); None: identity."""
        self.p_FG = None if identity else tuple(row[3] for row in rows)
        self.center = tuple((X34[:, :3] @ center + X34[:, 3]).tolist())
        """Bounding-sphere centre in the frame (the world when anchored)."""
        self.radius = radius + _MARGIN
        self.half = half
        """Boxes: half sizes (x, y, z) in G."""


def _make_fan_target(index: int, target: _Target, frame, X34: np.ndarray) -> _FanTarget:
    if target.radius == math.inf:
        kind, half = _HALF_SPACE, None
    elif target.shape_type == "Box":
        kind, half = _BOX, tuple(target.offsets[:3].tolist())
    else:
        kind, half = _OTHER, None
    return _FanTarget(index, kind, frame, X34, target.center, target.radius, half)


def _compose(R, p, R2, p2):
    """(R, p) o (R2, p2) for row-major 3x3 tuples and 3-tuples."""
    a0, a1, a2, a3, a4, a5, a6, a7, a8 = R
    b0, b1, b2, b3, b4, b5, b6, b7, b8 = R2
    x, y, z = p2
    return (
        (a0 * b0 + a1 * b3 + a2 * b6, a0 * b1 + a1 * b4 + a2 * b7, a0 * b2 + a1 * b5 + a2 * b8,
         a3 * b0 + a4 * b3 + a5 * b6, a3 * b1 + a4 * b4 + a5 * b7, a3 * b2 + a4 * b5 + a5 * b8,
         a6 * b0 + a7 * b3 + a8 * b6, a6 * b1 + a7 * b4 + a8 * b7, a6 * b2 + a7 * b5 + a8 * b8),
        (a0 * x + a1 * y + a2 * z + p[0], a3 * x + a4 * y + a5 * z + p[1],
         a6 * x + a7 * y + a8 * z + p[2]),
    )  # fmt: skip


def fan_cone(directions: Sequence[Sequence[float]]) -> tuple[tuple[float, float, float], float]:
    """(unit axis, half angle in rad) of a cone that holds every direction (the axis is their
    normalised mean; the half angle is pi when they don't fit in a cone narrower than that)."""
    d = np.asarray(directions, dtype=float)
    mean = d.sum(axis=0)
    norm = float(np.linalg.norm(mean))
    if norm < 1e-9:
        return (1.0, 0.0, 0.0), math.pi
    axis = mean / norm
    cosines = np.clip(d @ axis / np.linalg.norm(d, axis=1), -1.0, 1.0)
    return tuple(axis.tolist()), min(math.pi, float(np.arccos(cosines).max()) + _MARGIN)


def _box_fan(R, p, half, ox, oy, oz, directions, max_range, best) -> None:
    """Slab test of rays from (ox, oy, oz) against the box of half sizes `half` posed at
    (R row-major, p); lowers best[i] to ray i's first hit. Same conventions as
    _polytope_distances: closed solid (inside is a hit at 0); a ray parallel to a face plane
    is outside it when its origin is outside, and leaves it at 0 when its origin is on it.
    (Unrolled: this runs for every ray of every scan that a box's bounds don't reject.)"""
    r0, r1, r2, r3, r4, r5, r6, r7, r8 = R
    ux, uy, uz = ox - p[0], oy - p[1], oz - p[2]
    gx = r0 * ux + r3 * uy + r6 * uz  # the origin in G: R^T (o - p)
    gy = r1 * ux + r4 * uy + r7 * uz
    gz = r2 * ux + r5 * uy + r8 * uz
    hx, hy, hz = half
    # Slab x: lo_x <= t ex <= hi_x (and likewise for y, z).
    lo_x, hi_x, lo_y, hi_y, lo_z, hi_z = -hx - gx, hx - gx, -hy - gy, hy - gy, -hz - gz, hz - gz
    on_x, on_y, on_z = lo_x == 0.0 or hi_x == 0.0, lo_y == 0.0 or hi_y == 0.0, \
        lo_z == 0.0 or hi_z == 0.0
    inf = math.inf
    for i, (dx, dy, dz) in enumerate(directions):
        e = r0 * dx + r3 * dy + r6 * dz
        if e > 0.0:
            t0, t1 = lo_x / e, hi_x / e
        elif e < 0.0:
            t0, t1 = hi_x / e, lo_x / e
        elif lo_x > 0.0 or hi_x < 0.0:
            continue
        else:
            t0, t1 = 0.0, (0.0 if on_x else inf)
        if t0 < 0.0:
            t0 = 0.0
        if t1 > max_range:
            t1 = max_range
        e = r1 * dx + r4 * dy + r7 * dz
        if e > 0.0:
            a, b = lo_y / e, hi_y / e
        elif e < 0.0:
            a, b = hi_y / e, lo_y / e
        elif lo_y > 0.0 or hi_y < 0.0:
            continue
        else:
            a, b = 0.0, (0.0 if on_y else inf)
        if a > t0:
            t0 = a
        if b < t1:
            t1 = b
        if t0 > t1:
            continue
        e = r2 * dx + r5 * dy + r8 * dz
        if e > 0.0:
            a, b = lo_z / e, hi_z / e
        elif e < 0.0:
            a, b = hi_z / e, lo_z / e
        elif lo_z > 0.0 or hi_z < 0.0:
            continue
        else:
            a, b = 0.0, (0.0 if on_z else inf)
        if a > t0:
            t0 = a
        if b < t1:
            t1 = b
        if t0 <= t1 and t0 < best[i]:
            best[i] = t0


class RayCaster:
    """Casts fans of rays against the proximity geometries of a SceneGraph.

    Build it once (e.g. in a LeafSystem's constructor) from the SceneGraph's model inspector;
    call :meth:`cast_fan` with the current ``QueryObject`` at every scan. Rebuild it if
    proximity geometries are added, removed or reshaped after construction. Anchored geometries
    (fixed to the world frame) can't move, so their world-frame data is computed here, once;
    every other geometry is posed by ``QueryObject.GetPoseInWorld`` of its frame, once per
    frame and cast.
    """

    def __init__(
        self,
        inspector: SceneGraphInspector,
        exclude: Iterable[GeometryId] = (),
    ) -> None:
        """Precomputes per-geometry data for every proximity geometry not in ``exclude``.

        Geometries that can't be ray cast are logged (WARNING, once, here) and listed in
        :attr:`unsupported`.
        """
        excluded = set(exclude)
        targets: list[_Target] = []
        unsupported: list[tuple[GeometryId, str, str]] = []
        deformable = set(inspector.GetAllDeformableGeometryIds())
        for gid in inspector.GetAllGeometryIds(Role.kProximity):
            if gid in excluded:
                continue
            if gid in deformable:
                made: _Target | str = "it is a deformable geometry"
            else:
                made = _make_target(inspector, gid)
            if isinstance(made, str):
                name, shape_type = inspector.GetName(gid), type(inspector.GetShape(gid)).__name__
                unsupported.append((gid, name, shape_type))
                _log.warning(
                    "RayCaster: geometry '%s' (id %s, shape %s) is IGNORED by ray casting: %s.",
                    name, gid, shape_type, made,
                )  # fmt: skip
            else:
                targets.append(made)
        world = inspector.world_frame_id()
        self._targets: tuple[_Target, ...] = tuple(targets)
        self._anchored_planes: tuple[tuple[np.ndarray, np.ndarray] | None, ...] = tuple(
            _posed_planes(t, inspector.GetPoseInFrame(t.geometry_id).GetAsMatrix34())
            if t.normals is not None and inspector.GetFrameId(t.geometry_id) == world
            else None
            for t in targets
        )
        """The world-frame face planes of the anchored polytopes (None for the others)."""
        self._fan: tuple[_FanTarget, ...] = tuple(
            _make_fan_target(
                k,
                t,
                None if inspector.GetFrameId(t.geometry_id) == world
                else inspector.GetFrameId(t.geometry_id),
                inspector.GetPoseInFrame(t.geometry_id).GetAsMatrix34(),
            )
            for k, t in enumerate(targets)
        )
        """cast_fan's scalar data for every target, in the same order."""
        self.geometry_ids: tuple[GeometryId, ...] = tuple(t.geometry_id for t in targets)
        """The geometries rays are cast against."""
        self.unsupported: tuple[tuple[GeometryId, str, str], ...] = tuple(unsupported)
        """(id, name, shape type) of the proximity geometries that can't be ray cast."""
        self.excluded: frozenset[GeometryId] = frozenset(excluded)
        self._X_FG: tuple[np.ndarray, ...] = tuple(
            inspector.GetPoseInFrame(t.geometry_id).GetAsMatrix34() for t in targets)
        """Each target's pose in its frame (3x4; the world's when anchored): cast_plane's."""

    def cast_fan(
        self,
        query_object: QueryObject,
        origin: Sequence[float],
        directions: Sequence[Sequence[float]],
        max_range: float,
        cone: tuple[Sequence[float], float] | None = None,
    ) -> list[float]:
        """The nearest hit distance of each ray ``origin + t directions[i]`` from one origin
        (a sensor's fan), ``0 <= t <= max_range``, in scalar Python: a list of floats, inf for
        a miss.

        directions: unit vectors (world frame). cone: (unit axis, half angle in rad) of a cone
        about ``origin`` holding every ray (:func:`fan_cone`); a geometry whose bounding sphere
        is outside it, or farther than max_range, is rejected before any exact test. Pass it
        precomputed (e.g. :meth:`RayFan.in_world`) to save computing it here.
        """
        if not max_range >= 0.0:
            raise ValueError(f"max_range must be >= 0, got {max_range}")
        ox, oy, oz = origin
        n = len(directions)
        best = [math.inf] * n
        if not (math.isfinite(ox) and math.isfinite(oy) and math.isfinite(oz)):
            return best  # no hit from an undefined origin
        (ax, ay, az), half_angle = cone if cone is not None else fan_cone(directions)
        frame_poses: dict = {}
        others = []
        for ft in self._fan:
            frame = ft.frame
            if frame is None:  # anchored: X_WG precomputed
                R, p = ft.R_FG, ft.p_FG
                cx, cy, cz = ft.center
            else:
                X = frame_poses.get(frame)
                if X is None:
                    (r0, r1, r2, x), (r3, r4, r5, y), (r6, r7, r8, z) = (
                        query_object.GetPoseInWorld(frame).GetAsMatrix34().tolist()
                    )
                    X = frame_poses[frame] = ((r0, r1, r2, r3, r4, r5, r6, r7, r8), (x, y, z))
                R, p = X
                c0, c1, c2 = ft.center
                cx = R[0] * c0 + R[1] * c1 + R[2] * c2 + p[0]
                cy = R[3] * c0 + R[4] * c1 + R[5] * c2 + p[1]
                cz = R[6] * c0 + R[7] * c1 + R[8] * c2 + p[2]
                if ft.R_FG is not None and ft.kind != _HALF_SPACE:
                    R = None  # X_WG is composed below, only if the bounds don't reject it
            kind = ft.kind
            if kind == _HALF_SPACE:
                if frame is not None and ft.R_FG is not None:
                    R, p = _compose(R, p, ft.R_FG, ft.p_FG)
                _half_space_fan(R, p, origin, (ax, ay, az), half_angle, directions, max_range,
                                best)
                continue
            if _outside_cone(cx - ox, cy - oy, cz - oz, ft.radius, (ax, ay, az), half_angle,
                             max_range):
                continue
            if R is None:
                R, p = _compose(*X, ft.R_FG, ft.p_FG)
            if kind == _BOX:
                _box_fan(R, p, ft.half, ox, oy, oz, directions, max_range, best)
            else:
                others.append((ft.index, R, p))
        if others:
            self._cast_others(others, origin, directions, max_range, best)
        return best

    def cast_plane(
        self,
        query_object: QueryObject,
        origin: np.ndarray,
        directions: np.ndarray,
        max_range: float,
        normal: np.ndarray | None = None,
    ) -> np.ndarray:
        """The nearest hit distance of each ray ``origin + t directions[i]``,
        ``0 <= t <= max_range``, in numpy: (N,) floats, inf for a miss. For many rays from one
        origin (a lidar's scan), where cast_fan's per-ray Python costs more than numpy's
        per-call overhead.

        origin (3,) and unit directions (N, 3) in the world frame. normal: the unit normal of
        a plane through origin holding every ray (a planar scan), or None; a geometry whose
        bounding sphere misses that plane, or is farther than max_range, is skipped before
        any exact test. With a normal, a mesh that touches with its own surface is cast
        exactly, its triangles sliced by the plane; without, as its convex hull.
        """
        if not max_range >= 0.0:
            raise ValueError(f"max_range must be >= 0, got {max_range}")
        o = np.asarray(origin, dtype=float).reshape(1, 3)
        d = np.asarray(directions, dtype=float)
        best = np.full(len(d), np.inf)
        if not np.isfinite(o).all():
            return best  # no hit from an undefined origin
        frame_poses: dict = {}
        polytopes = []  # (world normals (3, F), offsets (F,)) of each polytope not skipped
        basis = rays = None  # the scan plane's axes and the rays in them, once needed
        for ft, target, X_FG, planes in zip(self._fan, self._targets, self._X_FG,
                                            self._anchored_planes, strict=True):
            if ft.frame is None:
                X_WG = X_FG
            else:
                X_WF = frame_poses.get(ft.frame)
                if X_WF is None:
                    X_WF = frame_poses[ft.frame] = query_object.GetPoseInWorld(
                        ft.frame).GetAsMatrix34()
                X_WG = np.hstack([X_WF[:, :3] @ X_FG[:, :3],
                                  (X_WF[:, :3] @ X_FG[:, 3] + X_WF[:, 3])[:, None]])
            if ft.radius != math.inf:
                v = X_WG[:, :3] @ target.center + X_WG[:, 3] - o[0]
                if float(np.linalg.norm(v)) - ft.radius > max_range or (
                        normal is not None and abs(float(v @ normal)) > ft.radius):
                    continue
            if target.surface is not None and normal is not None:
                if basis is None:
                    basis = _plane_basis(normal)
                    rays = _PlaneRays(d @ basis[:, :2])
                t = _surface_distances(target.surface, X_WG, o[0], basis, rays, max_range)
                if t is not None:
                    np.minimum(best, t, out=best)
            elif target.normals is not None:
                polytopes.append(planes or _posed_planes(target, X_WG))
            else:
                R_WG = X_WG[:, :3]
                t = target.hit((o - X_WG[:, 3]) @ R_WG, d @ R_WG, target.params, max_range)
                np.minimum(best, t, out=best)
        if polytopes:  # all in one product: a wall or a box alone is ~10 numpy calls
            starts = np.cumsum([0] + [len(h) for _, h in polytopes[:-1]]).tolist()
            t = _polytope_distances(o, d, np.hstack([n for n, _ in polytopes]),
                                    np.concatenate([h for _, h in polytopes]), starts,
                                    max_range)
            np.minimum(best, t.min(axis=1), out=best)
        return best

    def _cast_others(self, others, origin, directions, max_range: float, best: list) -> None:
        """The fan against the shapes with no scalar test (`others`: (index, R, p) of each),
        in numpy; lowers `best` where a ray hits nearer."""
        n = len(directions)
        o = np.array([origin] * n, dtype=float)
        d = np.array(directions, dtype=float)
        for k, R, p in others:
            X34 = np.array([[*R[0:3], p[0]], [*R[3:6], p[1]], [*R[6:9], p[2]]])
            target = self._targets[k]
            if target.normals is not None:
                normals, offsets = self._anchored_planes[k] or _posed_planes(target, X34)
                t = _polytope_distances(o, d, normals, offsets, [0], max_range)[:, 0]
            else:
                R_WG = X34[:, :3]
                t = target.hit((o - X34[:, 3]) @ R_WG, d @ R_WG, target.params, max_range)
            for i, v in enumerate(t.tolist()):
                if v < best[i]:
                    best[i] = v


class CasterCache:
    """A sensor's RayCaster for a QueryObject's proximity geometry (`exclude`d geometry left
    out), built on first use and rebuilt only when that geometry changes: a cache of what the
    scene graph holds, not state of the sensor's."""

    def __init__(self, exclude: Iterable[GeometryId] = ()):
        self.exclude = frozenset(exclude)
        self.current: RayCaster | None = None
        self._version = None

    def caster(self, query_object: QueryObject) -> RayCaster:
        inspector = query_object.inspector()
        version = inspector.geometry_version()
        if self.current is None or not version.IsSameAs(self._version, Role.kProximity):
            self.current = RayCaster(inspector, exclude=self.exclude)
            # A copy: the version itself is a view that keeps the inspector's Python wrapper
            # (and the Context it came from) referenced after that Context is gone.
            self._version = copy.copy(version)
        return self.current


def _half_space_fan(R, p, origin, axis, half_angle: float, directions, max_range: float,
                    best: list) -> None:
    """A fan against a half space (the solid n . x <= n . p, n the third column of R):
    lowers `best` in place; every ray 0 when the origin is inside."""
    ox, oy, oz = origin
    ax, ay, az = axis
    nx, ny, nz = R[2], R[5], R[8]
    s = nx * (ox - p[0]) + ny * (oy - p[1]) + nz * (oz - p[2])
    if s <= 0.0:  # the origin is inside: every ray hits at 0
        best[:] = [0.0] * len(best)
        return
    if s > max_range:
        return
    # The steepest descent towards the plane over the cone: -n . d <= cos(phi - a).
    phi = math.acos(max(-1.0, min(1.0, -(nx * ax + ny * ay + nz * az))))
    if max_range * math.cos(max(0.0, phi - half_angle)) + _MARGIN < s:
        return
    for i, (dx, dy, dz) in enumerate(directions):
        nd = nx * dx + ny * dy + nz * dz
        if nd < 0.0:
            t = -s / nd
            if t <= max_range and t < best[i]:
                best[i] = t


def _outside_cone(vx: float, vy: float, vz: float, r: float, axis, half_angle: float,
                  max_range: float) -> bool:
    """A bounding sphere (centre v from the fan's origin, radius r) beyond `max_range` or
    outside the cone about `axis` that holds every ray: no ray can hit what it bounds."""
    dist2 = vx * vx + vy * vy + vz * vz
    if dist2 <= r * r:
        return False
    dist = math.sqrt(dist2)
    if dist - r > max_range:
        return True
    ax, ay, az = axis
    limit = half_angle + math.asin(r / dist)
    return limit < math.pi and vx * ax + vy * ay + vz * az < dist * math.cos(limit)


# --------------------------------------------------------------------------------------------
# The IR sensor's cross of rays.
# --------------------------------------------------------------------------------------------


def cross_of_rays_in_sensor_frame(
    samples: int = 3, dispersion_cone_angle: float = DEFAULT_DISPERSION_CONE_ANGLE
) -> np.ndarray:
    """Unit ray directions (2*samples, 3) in the sensor frame S (the sensor looks along +x).

    Rows 0..samples-1: the horizontal fan (in the S x-y plane, yaw from -angle/2 to +angle/2);
    rows samples..2*samples-1: the vertical fan (in the S x-z plane, pitch up from -angle/2 to
    +angle/2). With an odd ``samples`` both fans contain the centre ray (+x): it is cast twice,
    keeping the 2 x samples rays per sensor.
    """
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or samples < 2:
        raise ValueError(
            f"IR sensor 'samples' must be an integer >= 2 (rays per fan of the cross); "
            f"got {samples!r}"
        )
    if not 0.0 <= dispersion_cone_angle < 180.0:
        raise ValueError(
            f"dispersion_cone_angle must be in [0, 180) degrees; got {dispersion_cone_angle!r}"
        )
    half = math.radians(dispersion_cone_angle) / 2.0
    angles = np.linspace(-half, half, samples)
    c, s, z = np.cos(angles), np.sin(angles), np.zeros(samples)
    horizontal = np.column_stack([c, s, z])
    vertical = np.column_stack([c, z, s])
    return np.vstack([horizontal, vertical])


class RayFan:
    """Rays from one point fixed in a body frame B (one sensor's cross of rays), for
    :meth:`RayCaster.cast_fan`: plain floats, posed with scalar arithmetic."""

    __slots__ = ("axis", "directions", "half_angle", "origin")

    def __init__(self, origin: Sequence[float], directions: Sequence[Sequence[float]]) -> None:
        """origin (3,) and unit directions (N, 3) in B."""
        self.origin: tuple[float, float, float] = tuple(float(v) for v in origin)
        self.directions: tuple[tuple[float, float, float], ...] = tuple(
            tuple(float(v) for v in d) for d in directions
        )
        axis, self.half_angle = fan_cone(self.directions)
        self.axis: tuple[float, float, float] = axis
        """A cone about origin holding every ray: unit axis (B) and half angle (rad)."""

    @staticmethod
    def cross_of_rays(
        X_BS: RigidTransform,
        samples: int = 3,
        dispersion_cone_angle: float = DEFAULT_DISPERSION_CONE_ANGLE,
    ) -> RayFan:
        """The IR cross of rays of a sensor S posed at X_BS (rows as
        :func:`cross_of_rays_in_sensor_frame`)."""
        d_S = cross_of_rays_in_sensor_frame(samples, dispersion_cone_angle)
        return RayFan(X_BS.translation(), d_S @ X_BS.rotation().matrix().T)

    def in_world(self, X_WB: Sequence[Sequence[float]]):
        """(origin, directions, (axis, half_angle)) in the world frame for the body pose X_WB
        given as the rows of its 3x4 matrix (``X_WB.GetAsMatrix34().tolist()``)."""
        (r0, r1, r2, x), (r3, r4, r5, y), (r6, r7, r8, z) = X_WB
        bx, by, bz = self.origin
        origin = (r0 * bx + r1 * by + r2 * bz + x, r3 * bx + r4 * by + r5 * bz + y,
                  r6 * bx + r7 * by + r8 * bz + z)  # fmt: skip
        directions = [
            (r0 * dx + r1 * dy + r2 * dz, r3 * dx + r4 * dy + r5 * dz, r6 * dx + r7 * dy + r8 * dz)
            for dx, dy, dz in self.directions
        ]
        ax, ay, az = self.axis
        axis = (r0 * ax + r1 * ay + r2 * az, r3 * ax + r4 * ay + r5 * az,
                r6 * ax + r7 * ay + r8 * az)  # fmt: skip
        return origin, directions, (axis, self.half_angle)


def model_instance_geometry_ids(plant, model_instance) -> set[GeometryId]:
    """The collision (proximity) geometry ids of every body of a model instance: the set a
    sensor mounted on that robot passes as ``RayCaster(..., exclude=...)``."""
    ids: set[GeometryId] = set()
    for body_index in plant.GetBodyIndices(model_instance):
        ids.update(plant.GetCollisionGeometriesForBody(plant.get_body(body_index)))
    return ids
