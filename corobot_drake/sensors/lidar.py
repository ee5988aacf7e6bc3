"""The planar lidar: a fan of rays in one plane, cast at a fixed rate, read as a LaserScan.

A lidar rides on a link of its robot (`LidarConfig.X_PB`, the chassis by default), its frame S
at the scan's centre: +x forward, the scan in S's x-y plane, angles counter-clockwise about +z
from +x (sensor_msgs/LaserScan's and REP 103's conventions). Ray i leaves at
`angle_min + i angle_increment`. A scan casts every ray exactly against every proximity
geometry but its own robot's (`raycast.RayCaster.cast_plane`: robots, world bodies, directive
models; a mesh that touches with its own surface, `collision: mesh`, as its triangles, concave
or not, any other mesh as its convex hull, as the robot touches them), all at one instant (so
`time_increment` is 0).

Each range follows REP 117: the measured distance (m) when it is in [range_min, range_max];
+inf when nothing is there within range_max; -inf when the hit is nearer than range_min (too
close to measure); NaN for a dropout (the ray came back with no valid measurement). With
`noise_std` the distance of every hit carries Gaussian noise (m), then the range limits apply;
with `dropout` each ray is lost with that probability. Both are a pure function of the
sensor's noise key and the scan index (numpy's Philox counter-based generator, the scan
index in the top word of its counter): a reset
Context replays them bit for bit, and there is no generator in the state.

Scans are discrete updates, one at initialization and then every 1 / `scan_rate_hz` s (on a
continuous plant, on the first of its steps at or after each scan time, as the IR sensors).
Everything a scan leaves is one discrete state vector (`scan_state`): [scan index, scan time,
X_WS (3x4, row-major: the sensor's world pose at the scan), ranges (N)].

`LidarKind` is what the rest of the project knows of it (`sensors/registry.KINDS`): the
scenario's `robots.<robot>.lidars.<name>` maps (none by default), the topic `scan/<name>` in
frame `lidar_<name>`, sensor_msgs/LaserScan on ROS 2 and Foxglove's LaserScan in recordings;
Meshcat draws each scan's rays and hits under `/lidar/<robot>/<name>`.
"""

import dataclasses as dc
import math

import numpy as np
from pydrake.common.schema import Transform
from pydrake.common.value import AbstractValue
from pydrake.geometry import Meshcat, QueryObject, Rgba
from pydrake.math import RigidTransform
from pydrake.perception import BaseField, Fields, PointCloud
from pydrake.systems.framework import EventStatus, LeafSystem

from corobot_drake.config.poses import mount, mount_frame
from corobot_drake.limits import RATE, Range, bounded
from corobot_drake.robots import corobot
from corobot_drake.sensors.ir_sensor import noise_key
from corobot_drake.sensors.kind import BuiltSensor, SensorKind
from corobot_drake.sensors.raycast import CasterCache, RayCaster, model_instance_geometry_ids
from corobot_drake.sensors.ticks import tick_in_step
from corobot_drake.topics import nanoseconds

# --- the config -----------------------------------------------------------------------------

SCAN_PLANE_ABOVE_BASE = 0.05
"""m: a small 2D lidar's scan plane above the surface it stands on (a 360-degree unit such
as an RPLidar A1 is about 6 cm tall, its beam about 5 cm up)."""
def default_mount() -> tuple[float, float, float]:
    """m, chassis frame: the default lidar stands on the middle of the Corobot's platform's
    top (0.22225 m up, the robot's highest part, as its model has it), so its scan clears the
    whole robot: (0, 0, 0.27225)."""
    size, centre = corobot.box("platform")
    return (0.0, 0.0, centre[2] + size[2] / 2 + SCAN_PLANE_ABOVE_BASE)

FULL_CIRCLE_TOLERANCE = 1e-3
"""rad: an angle span within this of 2 pi is a full circle (its rays spread over the whole
turn, the last one increment short of the first), and no span may exceed 2 pi by more. A
YAML `-3.1416` to `3.1416` is a full circle; a deliberate partial scan leaves more out."""

MAX_SAMPLES = 10_000
"""Rays per scan at most: the densest planar lidars give a few thousand. A 10 000-ray scan
costs 1.5 ms of CPU in the default scene and 27 ms in scenarios/corobot_lidar.yaml's room
(`tools/bench_lidar.py`); 10^7 rays would stall the run."""


@dc.dataclass
class LidarConfig:
    """One planar lidar on a robot (`robots.<robot>.lidars.<name>`); the defaults are a small
    360-degree lidar (RPLidar A1-like) on top of the Corobot, looking forward."""

    X_PB: Transform = dc.field(default_factory=lambda: mount(default_mount(), (0.0, 0.0, 0.0)))
    """The sensor frame S (+x the scan's zero bearing, the scan in its x-y plane) in
    `base_frame` (default `chassis`: origin on the ground midway between the axles)."""
    angle_min: float = bounded(-math.pi, Range(-2 * math.pi, 2 * math.pi, unit="rad"))
    """rad: the first ray's bearing, counter-clockwise from S's +x."""
    angle_max: float = bounded(math.pi, Range(-2 * math.pi, 2 * math.pi, unit="rad"))
    """rad: the last ray's bearing (a full circle, 2 pi from angle_min: one increment short,
    so that no bearing is cast twice), at least angle_min."""
    samples: int = bounded(360, Range(1, MAX_SAMPLES, why="rays per scan"))
    """Rays per scan, evenly spread from angle_min to angle_max."""
    scan_rate_hz: float = bounded(10.0, RATE)
    """Scans per second (a periodic discrete update, independent of the physics step)."""
    range_min: float = bounded(0.15, Range(0.0, 1000.0, unit="m"))
    """m: nearer hits read -inf (too close to measure), below range_max."""
    range_max: float = bounded(12.0, Range(0.0, 1000.0, low_open=True, unit="m"))
    """m: farther hits, and rays that hit nothing, read +inf."""
    noise_std: float = bounded(0.0, Range(0.0, 10.0, unit="m"))
    """m: the standard deviation of the Gaussian noise on each hit's distance (0: exact)."""
    dropout: float = bounded(0.0, Range(0.0, 1.0, why="the probability a ray reads NaN"))
    """The probability that a ray returns no measurement (its range NaN), independently."""
    noise_seed: int = 0
    """Mixed with the scenario's random_seed and the robot and sensor names."""
    enabled: bool = True
    """False: no sensor."""


def check_lidar(config: LidarConfig) -> list[tuple[str, str]]:
    """What each field's own range cannot see: an inverted range or angle span, a span over
    a full circle. (field, problem) pairs."""
    problems = []
    if not config.range_min < config.range_max:
        problems.append(("range_min", f"must be below range_max ({config.range_max:g} m); "
                                      f"got {config.range_min:g}"))
    span = config.angle_max - config.angle_min
    if span < 0.0:
        problems.append(("angle_max", f"must be at least angle_min ({config.angle_min:g} "
                                      f"rad); got {config.angle_max:g}"))
    elif span > 2 * math.pi + FULL_CIRCLE_TOLERANCE:
        problems.append(("angle_max", f"must be within a full circle (2 pi rad) of angle_min "
                                      f"({config.angle_min:g} rad); got {config.angle_max:g}"))
    return problems


def scan_angles(config: LidarConfig) -> tuple[float, float]:
    """(angle_increment, angle_max) in rad as the scans report them: the rays sit at
    angle_min + i increment, i < samples, the last at the reported angle_max (a full circle's
    one increment short of the configured 2 pi; a single ray's at angle_min)."""
    n, span = config.samples, config.angle_max - config.angle_min
    if n == 1:
        return 0.0, float(config.angle_min)
    increment = 2 * math.pi / n if span >= 2 * math.pi - FULL_CIRCLE_TOLERANCE \
        else span / (n - 1)
    return increment, config.angle_min + (n - 1) * increment


# --- the reading ----------------------------------------------------------------------------


@dc.dataclass(frozen=True)
class LaserScan:
    """One scan, with sensor_msgs/LaserScan's fields: angles in rad about the sensor frame's
    +z, counter-clockwise from its +x; times in s; ranges in m (REP 117: +inf nothing within
    range_max, -inf nearer than range_min, NaN a dropout). `time`: the simulated time of the
    scan; `ranges[i]` is at bearing `angle_min + i * angle_increment`."""

    angle_min: float
    angle_max: float
    angle_increment: float
    time_increment: float
    scan_time: float
    range_min: float
    range_max: float
    ranges: tuple[float, ...]
    time: float

    def __repr__(self) -> str:
        r = np.asarray(self.ranges)
        valid = r[np.isfinite(r)]
        nearest = f"{valid.min():.4f} m" if len(valid) else "none"
        return (f"LaserScan(time={self.time:.3f} s, {len(r)} rays {self.angle_min:.4f}.."
                f"{self.angle_max:.4f} rad, {len(valid)} in range, nearest {nearest}, "
                f"{int(np.isnan(r).sum())} dropped)")

    def bearings(self) -> np.ndarray:
        """rad: each range's bearing in the sensor frame."""
        return self.angle_min + self.angle_increment * np.arange(len(self.ranges))


# --- the system -----------------------------------------------------------------------------

SCAN_INDEX, SCAN_TIME = 0, 1
POSE = slice(2, 14)
"""X_WS at the scan, its 3x4 matrix row by row."""
NEAREST, NEAREST_BEARING = 14, 15
"""The scan's nearest measured range (m; inf when no ray measured one) and its bearing in the
sensor frame (rad; NaN when none): what the run log keeps of a scan."""
RANGES_START = 16


class Lidar(LeafSystem):
    """One planar lidar (the module docstring states its frames, ranges and noise).

    .. pydrake_system::

        name: Lidar
        input_ports:
        - query_object
        output_ports:
        - reading
        - ranges
        - scan_state

    Input `query_object` (abstract QueryObject, SceneGraph's). Outputs: `reading` (abstract
    `LaserScan`, the latest scan), `ranges` (m, N: its ranges), `scan_state` (the discrete
    state: [scan index, scan time (s), X_WS (12), nearest range (m), its bearing (rad),
    ranges (N)]).

    config: as validated by the loader, trusted here; frame_id: the SceneGraph FrameId of the
    body B it is fixed to; X_BS: the sensor frame in B; exclude: the geometry ids it never
    hits (its robot's own); key: the noise key (`ir_sensor.noise_key`); step: a continuous
    plant's physics step (s; 0 on a discrete plant), whose steps the scans then fall on.
    """

    def __init__(self, config: LidarConfig, frame_id, exclude, key: int = 0,
                 X_BS: RigidTransform | None = None, step: float = 0.0):
        super().__init__()
        self.config = config
        self._frame_id = frame_id
        self._exclude = frozenset(exclude)
        self._key_index = self.DeclareAbstractParameter(AbstractValue.Make(int(key)))
        self.num_rays = n = config.samples
        self.increment, self.angle_max = scan_angles(config)
        self.period = 1.0 / config.scan_rate_hz
        X_BS = config.X_PB.GetDeterministicValue() if X_BS is None else X_BS
        self._X_BS = X_BS.GetAsMatrix34()
        angles = config.angle_min + self.increment * np.arange(n)
        # The rays in B: a scan poses them with the body's rotation alone.
        self._d_B = np.column_stack([np.cos(angles), np.sin(angles), np.zeros(n)]) \
            @ self._X_BS[:, :3].T
        self._casters = CasterCache(self._exclude)

        self._query_port = self.DeclareAbstractInputPort(
            "query_object", AbstractValue.Make(QueryObject()))
        initial = np.zeros(RANGES_START + n)
        initial[SCAN_TIME] = initial[NEAREST_BEARING] = math.nan
        initial[NEAREST] = initial[RANGES_START:] = math.inf
        self._state = self.DeclareDiscreteState(initial)
        self.DeclareInitializationDiscreteUpdateEvent(self._initial_scan)
        self._step = float(step)
        self.events = (step, 0.0) if step > 0 else (self.period, self.period)
        """(period, offset), s: the schedule of the scan events (`LidarKind.looks`)."""
        if step > 0:
            self.DeclarePeriodicDiscreteUpdateEvent(step, 0.0, self._scan_if_due)
        else:
            self.DeclarePeriodicDiscreteUpdateEvent(self.period, self.period,
                                                    self._periodic_scan)
        state = {self.discrete_state_ticket(self._state)}
        self.DeclareAbstractOutputPort(
            "reading", lambda: AbstractValue.Make(self.scan_of(initial)),
            lambda c, out: out.set_value(self.scan_of(self._all(c))),
            prerequisites_of_calc=state)
        self.DeclareVectorOutputPort(
            "ranges", n, lambda c, out: out.SetFromVector(self._all(c)[RANGES_START:]),
            prerequisites_of_calc=state)
        self.DeclareStateOutputPort("scan_state", self._state)

    def _all(self, context) -> np.ndarray:
        return context.get_discrete_state(self._state).value()

    def SetNoiseKey(self, context, key: int) -> None:
        """The noise key (`ir_sensor.noise_key`) this Context's scans draw from."""
        context.get_mutable_abstract_parameter(self._key_index).set_value(int(key))

    def scan_of(self, x: np.ndarray) -> LaserScan:
        """The LaserScan of a state vector (`scan_state`)."""
        c = self.config
        return LaserScan(
            angle_min=float(c.angle_min), angle_max=float(self.angle_max),
            angle_increment=float(self.increment), time_increment=0.0,
            scan_time=self.period, range_min=float(c.range_min), range_max=float(c.range_max),
            ranges=tuple(x[RANGES_START:].tolist()), time=float(x[SCAN_TIME]))

    def hit_points(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(origins, hits), each (3, K), m, world frame: where each ray of a state vector
        (`scan_state`) that measured a range (finite) started and landed."""
        X_WS = x[POSE].reshape(3, 4)
        r = x[RANGES_START:]
        hit = np.isfinite(r)
        R_WB = X_WS[:, :3] @ self._X_BS[:, :3].T  # the rays are kept in B
        origin = X_WS[:, 3][:, None]
        ends = origin + (self._d_B[hit] @ R_WB.T).T * r[hit]
        return np.repeat(origin, ends.shape[1], axis=1), ends

    # -- scanning ---------------------------------------------------------------------------

    def caster(self, query_object) -> RayCaster:
        """The RayCaster for the QueryObject's geometry (its robot's own excluded), built on
        first use and rebuilt only when the proximity geometry changes."""
        return self._casters.caster(query_object)

    def true_ranges(self, query_object) -> tuple[np.ndarray, np.ndarray]:
        """(X_WS 3x4, the exact distance of each ray's first hit, m; inf when none within
        range_max)."""
        X_WB = query_object.GetPoseInWorld(self._frame_id).GetAsMatrix34()
        R_WB = X_WB[:, :3]
        X_WS = np.hstack([R_WB @ self._X_BS[:, :3],
                          (R_WB @ self._X_BS[:, 3] + X_WB[:, 3])[:, None]])
        t = self.caster(query_object).cast_plane(
            query_object, X_WS[:, 3], self._d_B @ R_WB.T, self.config.range_max, X_WS[:, 2])
        return X_WS, t

    def measured(self, t: np.ndarray, key: int, index: int) -> np.ndarray:
        """The ranges scan `index` reports for true distances `t` (m): noise, dropouts and
        the range limits (REP 117), a pure function of (key, index)."""
        c = self.config
        r = t.copy()
        if c.noise_std > 0.0 or c.dropout > 0.0:
            # The scan index in the counter's top word: each scan draws from its own block
            # (counter=index would start scan k + 1 one step into scan k's stream).
            rng = np.random.Generator(np.random.Philox(key=key, counter=[0, 0, 0, index]))
            # Both draws always, in this order: a ray's noise doesn't depend on the dropout.
            r += c.noise_std * rng.standard_normal(len(t))
            r[rng.random(len(t)) < c.dropout] = math.nan
        r[r > c.range_max] = math.inf  # also every miss: inf plus noise is inf
        r[r < c.range_min] = -math.inf
        return r

    def _initial_scan(self, context, discrete_state) -> None:
        self._do_scan(context, discrete_state.get_mutable_value(), 0)

    def _periodic_scan(self, context, discrete_state) -> None:
        # The handler's output starts as the current state: the previous scan's index.
        x = discrete_state.get_mutable_value()
        self._do_scan(context, x, int(x[SCAN_INDEX]) + 1)

    def _scan_if_due(self, context, discrete_state):
        if not tick_in_step(context.get_time(), 1.0 / self.period, self.period, self._step):
            return EventStatus.DidNothing()
        self._periodic_scan(context, discrete_state)
        return EventStatus.Succeeded()

    def _do_scan(self, context, x, index: int) -> None:
        X_WS, t = self.true_ranges(self._query_port.Eval(context))
        key = context.get_abstract_parameter(self._key_index).get_value()
        x[SCAN_INDEX] = index
        x[SCAN_TIME] = context.get_time()
        x[POSE] = X_WS.ravel()
        r = x[RANGES_START:] = self.measured(t, key, index)
        x[NEAREST], x[NEAREST_BEARING] = self.nearest(r)

    def nearest(self, ranges: np.ndarray) -> tuple[float, float]:
        """(m, rad): the least measured range of a scan (finite: neither a miss, a dropout nor
        below range_min) and its ray's bearing; (inf, NaN) when none."""
        measured = np.where(np.isfinite(ranges), ranges, math.inf)
        i = int(np.argmin(measured))
        if not math.isfinite(measured[i]):
            return math.inf, math.nan
        return float(measured[i]), float(self.config.angle_min + self.increment * i)


# --- Meshcat --------------------------------------------------------------------------------

_RAY_COLOR = Rgba(0.1, 0.6, 1.0, 0.35)
_HIT_COLOR = Rgba(1.0, 0.1, 0.1, 1.0)
HIT_SIZE = 0.02
"""m: the size of the points drawn where rays land."""


class LidarMeshcatVisualizer(LeafSystem):
    """Draws a lidar's latest scan in Meshcat: a line from the sensor to each measured hit
    (`rays`) and a point there (`hits`), under `path` (`/lidar/<robot>/<sensor>`); rays that
    read inf or NaN are not drawn.

    .. pydrake_system::

        name: LidarMeshcatVisualizer
        input_ports:
        - scan_state

    Input `scan_state`: the Lidar's output of that name. It looks at every step for a new
    scan (one float comparison until a period has passed since the last one drawn) and
    redraws once per scan.
    """

    def __init__(self, meshcat: Meshcat, path: str, lidar: Lidar):
        super().__init__()
        self._meshcat, self.path, self._lidar = meshcat, path, lidar
        self._scan = self.DeclareVectorInputPort("scan_state", RANGES_START + lidar.num_rays)
        self._last = None
        self._due_after = (1.0 - 1e-9) * lidar.period
        self.draws = 0
        """How many times it has redrawn (for tests)."""
        self.DeclareInitializationPublishEvent(self._draw)
        self.DeclarePerStepPublishEvent(self._draw_if_due)

    def _draw_if_due(self, context) -> None:
        t = context.get_time()
        if self._last is not None and self._last[1] <= t <= self._last[1] + self._due_after:
            return
        self._draw(context)

    def _draw(self, context) -> None:
        x = self._scan.Eval(context)
        key = (x[SCAN_INDEX], x[SCAN_TIME])
        if key == self._last:
            return
        self._last = key
        starts, ends = self._lidar.hit_points(x)
        self._meshcat.SetLineSegments(f"{self.path}/rays", np.asfortranarray(starts),
                                      np.asfortranarray(ends), 1.0, _RAY_COLOR)
        cloud = PointCloud(ends.shape[1], Fields(BaseField.kXYZs))
        cloud.mutable_xyzs()[:] = ends
        self._meshcat.SetObject(f"{self.path}/hits", cloud, HIT_SIZE, _HIT_COLOR)
        self.draws += 1


# --- the kind -------------------------------------------------------------------------------


class LidarKind(SensorKind):
    """Planar lidars: `robots.<robot>.lidars.<name>` (`LidarConfig`; none by default, `{}`
    gives the default mount on top of the platform), read as `LaserScan` on `scan/<name>` in
    frame `lidar_<name>`."""

    field = "lidars"
    config_type = LidarConfig
    reading_type = LaserScan
    topic = "scan"
    ros2_type = "sensor_msgs/msg/LaserScan"
    foxglove_schema = "LaserScan"

    def frame_name(self, sensor: str) -> str:
        return f"lidar_{sensor}"

    def check(self, config) -> list[tuple[str, str]]:
        return check_lidar(config)

    def log_columns(self, sensor: str) -> tuple[str, ...]:
        """`lidar_<sensor>_nearest` (m; inf when nothing is in range) and
        `lidar_<sensor>_bearing` (rad in the sensor frame; NaN when none): the latest scan's
        nearest measured range and the bearing of its ray."""
        return (f"lidar_{sensor}_nearest", f"lidar_{sensor}_bearing")

    def log_port(self, sensor: BuiltSensor):
        return sensor.system.GetOutputPort("scan_state"), (NEAREST, NEAREST_BEARING)

    def add(self, site, name: str, config: LidarConfig) -> BuiltSensor | None:
        """Adds `<robot>.lidar.<name>` mounted by `config.X_PB` on a link of the site's robot,
        reading SceneGraph's query output; exports its ports as `<robot>.lidar.<name>.<port>`.
        The plant must be finalized."""
        if not config.enabled:
            return None
        plant, builder, robot = site.plant, site.builder, site.robot
        body, X_BS = mount_frame(plant, site.model_instance, config.X_PB)
        lidar = builder.AddNamedSystem(f"{robot}.lidar.{name}", Lidar(
            config, plant.GetBodyFrameIdOrThrow(body.index()),
            model_instance_geometry_ids(plant, site.model_instance),
            noise_key(site.random_seed, robot, name, config.noise_seed), X_BS,
            site.continuous_step))
        builder.Connect(site.scene_graph.get_query_output_port(), lidar.get_input_port(0))
        for i in range(lidar.num_output_ports()):
            port = lidar.get_output_port(i)
            builder.ExportOutput(port, f"{robot}.lidar.{name}.{port.get_name()}")
        return BuiltSensor(self, robot, name, config, lidar, lidar.GetOutputPort("reading"),
                           float(config.scan_rate_hz), config.X_PB)

    def set_seed(self, sensor: BuiltSensor, root_context, random_seed: int,
                 config: LidarConfig) -> None:
        system = sensor.system
        system.SetNoiseKey(system.GetMyMutableContextFromRoot(root_context), noise_key(
            random_seed, sensor.robot, sensor.name, config.noise_seed))

    def looks(self, sensor: BuiltSensor) -> tuple[float, float]:
        return sensor.system.events  # a scan and a look at one time: the look first

    def summary_json(self, reading: LaserScan) -> dict:
        """The scan in brief: its time (s), rays, how many read a range, were dropped
        (NaN) or too near (-inf), and the nearest range (m) and its bearing (rad)."""
        r = np.asarray(reading.ranges)
        valid = np.isfinite(r)
        nearest = int(np.argmin(np.where(valid, r, np.inf))) if valid.any() else None
        return {"time": reading.time, "rays": len(r), "in_range": int(valid.sum()),
                "dropped": int(np.isnan(r).sum()), "too_near": int((r == -np.inf).sum()),
                "nearest": None if nearest is None else float(r[nearest]),
                "nearest_bearing": None if nearest is None else float(
                    reading.angle_min + nearest * reading.angle_increment)}

    def add_meshcat(self, builder, meshcat, sensor: BuiltSensor) -> None:
        viz = builder.AddNamedSystem(
            f"{sensor.robot}.lidar.{sensor.name}.meshcat",
            LidarMeshcatVisualizer(meshcat, f"/lidar/{sensor.robot}/{sensor.name}",
                                   sensor.system))
        builder.Connect(sensor.system.GetOutputPort("scan_state"), viz.get_input_port())

    def foxglove_message(self, reading: LaserScan, frame: str):
        from foxglove.messages import LaserScan as FoxgloveLaserScan
        from foxglove.messages import Pose, Quaternion, Timestamp, Vector3

        ns = nanoseconds(reading.time)
        return FoxgloveLaserScan(
            timestamp=Timestamp(ns // 1_000_000_000, ns % 1_000_000_000), frame_id=frame,
            pose=Pose(position=Vector3(x=0.0, y=0.0, z=0.0),
                      orientation=Quaternion(x=0.0, y=0.0, z=0.0, w=1.0)),
            start_angle=reading.angle_min, end_angle=reading.angle_max,
            ranges=list(reading.ranges), intensities=[])

    def ros2_message(self, messages, reading: LaserScan, frame: str):
        return messages.msg("sensor_msgs/msg/LaserScan")(
            header=messages.header(reading.time, frame), angle_min=reading.angle_min,
            angle_max=reading.angle_max, angle_increment=reading.angle_increment,
            time_increment=reading.time_increment, scan_time=reading.scan_time,
            range_min=reading.range_min, range_max=reading.range_max,
            ranges=np.asarray(reading.ranges, dtype=np.float32),
            intensities=np.zeros(0, dtype=np.float32))


__all__ = ["LaserScan", "Lidar", "LidarConfig", "LidarKind", "LidarMeshcatVisualizer"]
