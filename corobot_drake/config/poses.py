"""The scenario's one pose convention: Drake's `pydrake.common.schema.Transform`.

    pose: {translation: [x, y, z], rotation: !Rpy {deg: [roll, pitch, yaw]}}

Translation in metres; rotation as Drake's schema allows (`!Rpy {deg: [...]}`, extrinsic
x-y-z, or `!AngleAxis {angle_deg, axis}`; `{}` or omitted: none). A world body's or a
robot's `pose` is in the world (no `base_frame`); a sensor's `X_PB` is in its `base_frame`.
Poses are fixed: the loader rejects Drake's random distributions.

This module makes and reads them: `mount` and `ground_pose` build them, `transform_from`
writes a plant's pose back (`--save-scenario`), `mount_frame` finds the body a sensor rides on.
"""

import math

from pydrake.common.schema import Rotation, Transform
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.multibody.parsing import GetScopedFrameByName


def mount(position, rpy_deg, base_frame: str = "chassis") -> Transform:
    """X_PB of a sensor at `position` (m) in `base_frame`, turned by roll-pitch-yaw `rpy_deg`
    (degrees, extrinsic x-y-z: yaw about the frame's z; positive pitch looks down)."""
    return Transform(base_frame=base_frame, translation=[float(v) for v in position],
                     rotation=Rotation.Rpy(deg=[float(a) for a in rpy_deg]))


def ground_pose(x: float = 0.0, y: float = 0.0, yaw_deg: float = 0.0) -> Transform:
    """A robot standing on the ground at (x, y) m, facing `yaw_deg` (0: +x, 90: +y)."""
    return Transform(translation=[float(x), float(y), 0.0],
                     rotation=Rotation.Rpy(deg=[0.0, 0.0, float(yaw_deg)]))


def transform_from(X: RigidTransform) -> Transform:
    """The scenario pose of `X` (roll-pitch-yaw in degrees): it reads back as `X` to within
    rounding of the angles."""
    rpy = RollPitchYaw(X.rotation()).vector()
    return Transform(translation=[float(v) for v in X.translation()],
                     rotation=Rotation.Rpy(deg=[math.degrees(a) for a in rpy]))


def mount_frame(plant, instance, X_PB: Transform):
    """(body, X_BS): the plant body a sensor rides on and the sensor's pose in that body's
    frame. `X_PB.base_frame` names a frame of `instance` (a robot), a scoped `model::frame`,
    or, empty or `world`, the world."""
    name = X_PB.base_frame
    if not name or name == "world":
        frame = plant.world_frame()
    elif "::" in name:
        frame = GetScopedFrameByName(plant, name)
    else:
        frame = plant.GetFrameByName(name, instance)
    return frame.body(), frame.GetFixedPoseInBodyFrame() @ X_PB.GetDeterministicValue()
