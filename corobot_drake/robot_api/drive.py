"""A robot's drive and where it is: pose, velocity, wheels, encoders, odometry (`Robot` has
these). Per wheel values are keyed by the robot's own wheel names (`RobotSpec.wheel_names`).
"""

import math

from corobot_drake.readings import BodyPose, BodyVelocity, OdometryPose
from corobot_drake.systems.drive import DriveStatus
from corobot_drake.systems.odometry import DriveState


class RobotDrive:
    """The drive and the robot's motion: pose, velocity, axles, encoders, odometry, enable."""

    def pose(self) -> BodyPose:
        """The chassis frame's pose in the world frame now: x, y, z (m), roll, pitch, yaw
        (rad, extrinsic x-y-z), the truth (`odometry()` is the robot's own estimate)."""
        return self._sim.body_pose(self._parts.chassis)

    def velocity(self) -> BodyVelocity:
        """The chassis origin's velocity now in its heading frame (the world's, turned by
        the yaw): forward and lateral (+ left) m/s, yaw rate about world z rad/s (+ left)."""
        plant = self._sim.station.plant
        V = plant.EvalBodySpatialVelocityInWorld(self._plant_context(), self._parts.chassis)
        yaw = self.pose().yaw
        c, s = math.cos(yaw), math.sin(yaw)
        vx, vy = V.translational()[:2]
        return BodyVelocity(float(c * vx + s * vy), float(-s * vx + c * vy),
                            float(V.rotational()[2]))

    def axle_speeds(self) -> dict[str, float]:
        """Measured axle speeds, rad/s, by wheel name."""
        return self.signal("axle_speeds")

    def drive_state(self) -> DriveState:
        """The four-wheel drive state (`.two_wheel()`: the differential-drive view)."""
        return self._sim.station.diagram.GetOutputPort(f"{self.name}.drive_state").Eval(
            self._sim.context)

    def encoders(self) -> dict[str, int]:
        """Encoder counts of the encoded wheels (`RobotSpec.encoded`: the Corobot's front
        pair), `spec.encoder_ticks_per_revolution` a turn (the Corobot's 600), by wheel name."""
        return self.signal("encoders")

    def heading(self) -> float:
        """Compass: chassis yaw about world z, rad in (-pi, pi]."""
        return self.signal("heading")

    def position(self) -> tuple[float, float, float]:
        """GPS: the chassis frame's origin in the world, m."""
        return tuple(self.signal("position").values())

    def odometry(self) -> OdometryPose:
        """Dead reckoning from the encoders (`systems.dead_reckoning`, with the drive's
        effective wheel radius and track width) from the start pose: x, y m, yaw rad."""
        return OdometryPose(**self.signal("odometry"))

    def commanded_power(self) -> dict[str, float]:
        """The drive's commanded power per wheel (its side's), in [-1, 1], by wheel name."""
        return {w: float(state.commanded_power)
                for w, state in self.drive_state().wheels.items()}

    def enable_requested(self) -> bool:
        """The enable level last commanded (is_enabled() follows it at the next control tick)."""
        source = self._parts.command_source
        return source.get_state(source.GetMyContextFromRoot(self._sim.context)).request.enabled

    def is_enabled(self) -> bool:
        """Whether the drive is enabled now, as its controller has it since its last control
        tick (`enable_requested()`: the level last commanded)."""
        status = self._sim.station.diagram.GetOutputPort(f"{self.name}.drive_status").Eval(
            self._sim.context)
        return bool(DriveStatus(status).enabled)
