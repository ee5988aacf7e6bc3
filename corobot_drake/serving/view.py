"""Meshcat's camera: an initial view framing the scene, and a camera that follows a robot.

The initial view frames the robots and everything they can touch (SceneGraph's proximity
shapes but the ground's half-space: the giant box, a maze's walls, ...) from a fixed direction;
the follow camera then carries that view along with the robot: camera and target move by the
robot's displacement, so the robot stays where it was on the screen.
"""

import math

import numpy as np
from pydrake.geometry import Box, Convex, HalfSpace, Mesh, Role

from corobot_drake.sensors.raycast import model_instance_geometry_ids

VIEW_DIRECTION = np.array([0.6, -1.0, 0.55])
"""From the target towards the camera (world frame): in front of the robot's right side, a
little above, so a robot at the origin facing +x shows its front and the box behind it."""
MESHCAT_FOV_DEG = 75.0
"""Meshcat's default perspective camera's vertical field of view (three.js' default)."""
MARGIN = 1.1
"""The framed sphere's radius is the scene's half diagonal times this."""
FOLLOW_STEP = 0.01
"""m: the follow camera moves once the robot has moved this far (no messages at rest)."""
FOLLOW_PERIOD = 0.1
"""s (wall clock) between the follow camera's moves: each is three messages to every page,
and a page that falls behind (a slow machine, software WebGL) lags ever more."""


def _corners(shape, X_WG, inspector, gid) -> np.ndarray:
    """Points whose bounding box bounds the shape posed at X_WG (world frame), (N, 3)."""
    if isinstance(shape, Box):
        half = 0.5 * np.array([shape.width(), shape.depth(), shape.height()])
        signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
        return (X_WG @ (signs * half).T).T
    if isinstance(shape, Mesh | Convex):
        hull = inspector.GetConvexHull(gid)
        vertices = np.array([hull.vertex(i) for i in range(hull.num_vertices())])
        return (X_WG @ vertices.T).T
    # A sphere about the origin bounds the other primitives: its 6 extremes along the axes.
    r = shape_radius(shape)
    return X_WG.translation() + np.vstack([r * np.eye(3), -r * np.eye(3)])


def shape_radius(shape) -> float:
    """m: the radius of a sphere about the shape's origin that holds it (primitives)."""
    getters = {"Sphere": lambda s: s.radius(),
               "Ellipsoid": lambda s: max(s.a(), s.b(), s.c()),
               "Cylinder": lambda s: math.hypot(s.radius(), s.length() / 2),
               "Capsule": lambda s: s.radius() + s.length() / 2}
    return getters.get(type(shape).__name__, lambda s: 0.0)(shape)


def _platform(spec) -> tuple[np.ndarray, np.ndarray]:
    """(size, centre) m of the Corobot's platform box, as its model has it (base frame)."""
    for name, shape, X_BG in spec.shapes:
        if name.endswith("/platform"):
            return np.asarray(shape.size()), X_BG.translation()
    raise ValueError(f"{spec.kind}: no platform box")


def scene_points(sim) -> np.ndarray:
    """World points (N, 3) whose bounding box holds the robots and every other proximity
    shape but half-spaces, now (the Corobot by its platform's footprint and height)."""
    station = sim.station
    inspector = station.scene_graph.model_inspector()
    query = station.diagram.GetOutputPort("query_object").Eval(sim.context)
    robot_ids = set()
    points = []
    for name, parts in station.robots.items():
        if not sim.robot(name).spec.generated:
            continue  # any other robot: its own shapes, below, as every body's
        robot_ids |= model_instance_geometry_ids(station.plant, parts.model_instance)
        X_WB = sim.body_pose(parts.chassis)
        size, center = _platform(sim.robot(name).spec)
        half = np.array([size[0], size[1], 0.0]) / 2
        points += [[X_WB.x - half[0], X_WB.y - half[1], 0.0],
                   [X_WB.x + half[0], X_WB.y + half[1], center[2]]]
    for gid in inspector.GetAllGeometryIds(Role.kProximity):
        shape = inspector.GetShape(gid)
        if gid in robot_ids or isinstance(shape, HalfSpace):
            continue
        points.extend(_corners(shape, query.GetPoseInWorld(gid), inspector, gid))
    return np.array(points, dtype=float)


def framing(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(camera, target) positions (world frame, m) that frame `points` from VIEW_DIRECTION."""
    low, high = points.min(axis=0), points.max(axis=0)
    target = (low + high) / 2
    radius = MARGIN * max(float(np.linalg.norm(high - low)) / 2, 0.3)
    distance = radius / math.sin(math.radians(MESHCAT_FOV_DEG) / 2)
    return target + distance * VIEW_DIRECTION / np.linalg.norm(VIEW_DIRECTION), target


class FollowCamera:
    """Meshcat's camera: the initial view at construction, then (while `enabled`) that view
    carried along with the robot `update` is given."""

    def __init__(self, meshcat, sim, robot_position, enabled: bool = True):
        self._meshcat = meshcat
        self.camera, self.target = framing(scene_points(sim))
        """The view last sent to Meshcat (world frame, m)."""
        self._anchor = np.asarray(robot_position, dtype=float)
        """Where the robot was when the view was `camera, target`."""
        self.enabled = enabled
        self._connections = meshcat.GetNumActiveConnections()
        self._sent = -math.inf
        """Wall-clock time (s) of the last move sent."""
        meshcat.SetCameraPose(self.camera, self.target)

    def toggle(self, robot_position, now: float) -> None:
        self.enabled = not self.enabled
        self._sent = -math.inf
        self.update(robot_position, now)

    def update(self, robot_position, now: float) -> None:
        """At wall-clock time `now` (s): carries the view along if the robot has moved more
        than FOLLOW_STEP (at most every FOLLOW_PERIOD); sends it again when a page has
        connected (Meshcat replays the camera's position to a new page, not its target)."""
        connections = self._meshcat.GetNumActiveConnections()
        resend, self._connections = connections > self._connections, connections
        p = np.asarray(robot_position, dtype=float)
        step = p - self._anchor
        step[2] = 0.0  # the view stays level: bumps and tyre sink don't shake it
        if (self.enabled and np.linalg.norm(step) >= FOLLOW_STEP
                and now >= self._sent + FOLLOW_PERIOD):
            self.camera, self.target, self._anchor = self.camera + step, self.target + step, p
            self._sent = now
        elif not resend:
            return
        self._meshcat.SetCameraPose(self.camera, self.target)
