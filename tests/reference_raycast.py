"""The batch ray caster the ray-cast tests read against: any rays, numpy, with hit points and
geometry indices.

The product casts fans (`RayCaster.cast_fan`, what the IR sensors call). `ReferenceRayCaster`
adds :meth:`~ReferenceRayCaster.cast`: every ray against every geometry with the same
per-geometry data and numpy kernels, but none of cast_fan's scalar paths or cone culling, so
the tests check its distances against closed forms and Drake's signed distances, and then
cast_fan against it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
from pydrake.math import RigidTransform

from corobot_drake.sensors.raycast import (
    DEFAULT_DISPERSION_CONE_ANGLE,
    RayCaster,
    _polytope_distances,
    _posed_planes,
    _Target,
    cross_of_rays_in_sensor_frame,
)


@dataclass(frozen=True)
class RayHits:
    """The result of a cast, one entry per ray. ``point`` and ``geometry_index`` are computed
    on access."""

    distance: np.ndarray
    """(N,) metres to the nearest hit, inf when nothing is hit within max_range."""
    origins: np.ndarray
    directions: np.ndarray
    _per_column: np.ndarray = field(repr=False)
    """(N, K) distance of each ray to each geometry that wasn't rejected."""
    _column_target: tuple[int, ...] = field(repr=False)
    """The geometry index of each column of _per_column."""

    @property
    def point(self) -> np.ndarray:
        """(N, 3) world-frame hit points, nan where nothing is hit."""
        t = np.where(np.isfinite(self.distance), self.distance, np.nan)
        return self.origins + t[:, None] * self.directions

    @property
    def geometry_index(self) -> np.ndarray:
        """(N,) index into RayCaster.geometry_ids of the geometry hit, -1 where none."""
        lookup = np.array((*self._column_target, -1))
        column = self._per_column.argmin(axis=1)
        return lookup[np.where(np.isfinite(self.distance), column, -1)]


class _Posed(NamedTuple):
    """A target's world-frame data for one pose (precomputed once for anchored geometry)."""

    R: np.ndarray
    p: np.ndarray
    center: list[float]
    """Bounding-sphere centre in the world frame."""
    normals: np.ndarray | None
    """Polytopes: (3, F) world-frame face normals."""
    offsets: np.ndarray | None
    plane: list[float] | None
    """Half-spaces: [nx, ny, nz, h] of the boundary plane n . x = h in the world frame."""


def _pose(target: _Target, X34: np.ndarray) -> _Posed:
    R, p = X34[:, :3], X34[:, 3]
    center = (R @ target.center + p if target.center.any() else p).tolist()
    if target.normals is None:
        return _Posed(R, p, center, None, None, None)
    normals, offsets = _posed_planes(target, X34)
    plane = None
    if target.radius == math.inf:
        plane = [*normals[:, 0].tolist(), float(offsets[0])]
    return _Posed(R, p, center, normals, offsets, plane)


class ReferenceRayCaster(RayCaster):
    """A RayCaster that also casts any batch of rays (:meth:`cast`)."""

    def __init__(self, inspector, exclude=()) -> None:
        super().__init__(inspector, exclude)
        world = inspector.world_frame_id()
        self._anchored = tuple(
            _pose(t, inspector.GetPoseInFrame(t.geometry_id).GetAsMatrix34())
            if inspector.GetFrameId(t.geometry_id) == world else None
            for t in self._targets)  # fmt: skip

    def geometry_name(self, index: int) -> str:
        """Name of the geometry with the given RayHits.geometry_index ('' for -1)."""
        return "" if index < 0 else self._targets[index].name

    def _posed_near(self, query_object, scan_center, scan_radius):
        """(index, target, posed) of the targets whose bounds meet the scan's sphere."""
        for k, target in enumerate(self._targets):
            posed = self._anchored[k]
            if posed is None:
                posed = _pose(target, query_object.GetPoseInWorld(target.geometry_id)
                              .GetAsMatrix34())
            if posed.plane is not None:  # half-space: is the scan entirely outside it?
                nx, ny, nz, h = posed.plane
                cx, cy, cz = scan_center
                if nx * cx + ny * cy + nz * cz - h > scan_radius:
                    continue
            elif math.dist(posed.center, scan_center) > scan_radius + target.radius:
                continue
            yield k, target, posed

    def cast(self, query_object, origins, directions, max_range: float) -> RayHits:
        """Nearest hit of each ray ``origins[i] + t directions[i]``, ``0 <= t <= max_range``.

        origins, directions: (N, 3) world-frame arrays; directions must be unit vectors. Poses
        of non-anchored geometries come from ``query_object.GetPoseInWorld``.
        """
        o = np.asarray(origins, dtype=float)
        d = np.asarray(directions, dtype=float)
        if o.ndim != 2 or o.shape[1] != 3 or d.shape != o.shape:
            raise ValueError(
                f"origins and directions must both be (N, 3); got {o.shape} and {d.shape}")
        if not max_range >= 0.0:
            raise ValueError(f"max_range must be >= 0, got {max_range}")
        # Bounding sphere of the whole scan (every ray segment).
        lo, hi = o.min(axis=0).tolist(), o.max(axis=0).tolist()
        scan_center = [0.5 * (a + b) for a, b in zip(lo, hi, strict=True)]
        scan_radius = 0.5 * math.dist(lo, hi) + max_range
        normals, offsets, starts, columns = [], [], [], []
        curved, curved_columns = [], []
        n_planes = 0
        for k, target, posed in self._posed_near(query_object, scan_center, scan_radius):
            if target.normals is not None:
                normals.append(posed.normals)
                offsets.append(posed.offsets)
                starts.append(n_planes)
                columns.append(k)
                n_planes += posed.offsets.shape[0]
            else:
                o_G = (o - posed.p) @ posed.R  # row-wise R^T (x - p)
                curved.append(target.hit(o_G, d @ posed.R, target.params, max_range))
                curved_columns.append(k)
        blocks = []
        if normals:
            blocks.append(_polytope_distances(o, d, np.concatenate(normals, axis=1),
                                              np.concatenate(offsets), starts, max_range))
        if curved:
            blocks.append(np.column_stack(curved))
        if not blocks:
            n = o.shape[0]
            return RayHits(np.full(n, np.inf), o, d, np.full((n, 1), np.inf), ())
        t = np.hstack(blocks)
        return RayHits(t.min(axis=1), o, d, t, (*columns, *curved_columns))


def cross_of_rays_directions(
    X_WS: RigidTransform,
    samples: int = 3,
    dispersion_cone_angle: float = DEFAULT_DISPERSION_CONE_ANGLE,
) -> np.ndarray:
    """Unit ray directions (2*samples, 3) in the world frame for a sensor posed at X_WS: the
    rows of `cross_of_rays_in_sensor_frame`, all from ``X_WS.translation()``."""
    d_S = cross_of_rays_in_sensor_frame(samples, dispersion_cone_angle)
    return d_S @ X_WS.rotation().matrix().T
