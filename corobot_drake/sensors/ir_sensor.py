"""The IR distance sensors: one LeafSystem per sensor, casting a cross of rays at a fixed rate.

Each sensor is fixed to a link of its robot, the chassis by default (its
``X_PB``, :class:`corobot_drake.config.sensors.IrSensorConfig`), and reads SceneGraph's
``query_object`` port, its only input: the link's pose comes from
``QueryObject.GetPoseInWorld(link frame)`` and the rays are cast exactly against every
proximity geometry except the robot's own (:class:`corobot_drake.sensors.raycast.RayCaster`,
built on the first scan from the QueryObject's inspector, rebuilt only if the proximity geometry
changes).

Scans are discrete updates: one at initialization (so a freshly initialized simulation already
has a reading at its start time) and then every ``1 / scan_rate_hz`` s, never at every physics
step. All the sensor's memory is discrete state (replayable, cheap to copy):

one vector (written once per scan) holding

- ``reading`` = [distance, scan_time, previous_distance, changed, scan_index, true_distance,
  voltage, adc_counts];
- ``ray_origin`` (3), ``ray_end`` (3 N), ``ray_hit`` (N): where each of the N = 2 x samples rays
  started, where it stopped (its hit point, or its end at maximum_range) and whether it hit.

Output models (``model``, :mod:`corobot_drake.model.ir_models`):

``ideal``
    distance = the nearest hit, ``maximum_range`` when nothing is hit (the book's sensor).
``sharp_gp2d12``
    the ADC voltage of a Sharp GP2D12 at the true distance, with Gaussian noise, and distance =
    the distance a robot program would compute from that voltage (the inverse law, clamped to the
    usable 10-80 cm, capped at maximum_range). The noise of scan k is a pure function of
    (the sensor's noise key, k) (a splitmix64 counter-based generator), so runs are deterministic
    and a restored context replays the same noise: there is no generator object in the state.

Output ports (vectors): ``distance`` (raw, m), ``range`` (maximum_range, m), ``normalized``
(raw / range), ``scan_time`` (s), ``changed`` (1 when the reading moved by more than
``change_threshold`` since the previous scan, else 0), ``reading`` ([raw, range, normalized,
time]), ``true_distance`` (m, the geometric nearest hit capped at range), ``hit_points``
(3 N, world frame, nan for a ray that hit nothing), ``ray_origin``, ``ray_end``, ``ray_hit``,
``scan_state`` (the whole state vector above); with ``sharp_gp2d12`` also ``voltage`` (V) and
``adc_counts``.

A scan due at time t is taken when the simulator steps away from t (Drake's discrete-update
semantics): right after ``AdvanceTo(t)`` the latest reading is the previous scan's.

:class:`IrMeshcatVisualizer` draws each sensor's rays and hit points in Meshcat under
``/ir/<robot>/<sensor>`` (toggle them with the scene tree's checkboxes); the kind's
``add_meshcat`` adds them, from the station's Meshcat hook (``corobot_drake/markers.py``).
"""


from __future__ import annotations

import dataclasses as dc
import math
import zlib

import numpy as np
from pydrake.common.value import Value
from pydrake.geometry import Meshcat, Rgba, Sphere
from pydrake.math import RigidTransform
from pydrake.systems.framework import BasicVector, EventStatus, LeafSystem

from corobot_drake.config.poses import mount_frame
from corobot_drake.config.sensors import IrSensorConfig, default_ir_sensors
from corobot_drake.model.ir_models import SharpGP2D12
from corobot_drake.readings import IrReading
from corobot_drake.sensors.kind import BuiltSensor, SensorKind
from corobot_drake.sensors.raycast import (
    CasterCache,
    RayCaster,
    RayFan,
    cross_of_rays_in_sensor_frame,
    model_instance_geometry_ids,
)
from corobot_drake.sensors.site import SensorSite
from corobot_drake.sensors.ticks import tick_in_step

# --- counter-based noise -------------------------------------------------------------------

_MASK64 = (1 << 64) - 1


def _splitmix64(x: int) -> int:
    x = (x + 0x9E3779B97F4A7C15) & _MASK64
    x = ((x ^ (x >> 30)) * 0xBF58476D1CE4E5B9) & _MASK64
    x = ((x ^ (x >> 27)) * 0x94D049BB133111EB) & _MASK64
    return x ^ (x >> 31)


def counter_normal(key: int, counter: int) -> float:
    """A standard normal sample that is a pure function of (key, counter) (splitmix64 hashes
    of the pair, Box-Muller): the noise of scan `counter` of the sensor with `key`."""
    h1 = _splitmix64((key ^ _splitmix64(2 * counter)) & _MASK64)
    h2 = _splitmix64((key ^ _splitmix64(2 * counter + 1)) & _MASK64)
    u1 = ((h1 >> 11) + 1) * 2.0**-53  # (0, 1]: log is finite
    u2 = (h2 >> 11) * 2.0**-53
    return math.sqrt(-2.0 * math.log(u1)) * math.cos(2.0 * math.pi * u2)


def noise_key(random_seed: int, robot: str, sensor: str, noise_seed: int) -> int:
    """The 64-bit noise key of a sensor: stable across runs and Python versions."""
    entropy = [random_seed & _MASK64, noise_seed & _MASK64,
               zlib.crc32(robot.encode()), zlib.crc32(sensor.encode())]
    return int(np.random.SeedSequence(entropy).generate_state(1, np.uint64)[0])


# --- the sensor system ---------------------------------------------------------------------

# Indices into the `reading` discrete state group.
DISTANCE, SCAN_TIME, PREVIOUS, CHANGED, SCAN_INDEX, TRUE_DISTANCE, VOLTAGE, ADC_COUNTS = range(8)
_READING_SIZE = 8


def scan_state_layout(num_rays: int) -> tuple[int, slice, slice, slice]:
    """(size, origin, ends, hits) of an IrSensor's state vector (`scan_state`) for `num_rays`
    rays: the reading, then the rays' origin (3), ends (3 N) and hit flags (N)."""
    ends = _READING_SIZE + 3
    hits = ends + 3 * num_rays
    return (hits + num_rays, slice(_READING_SIZE, ends), slice(ends, hits),
            slice(hits, hits + num_rays))


class IrSensor(LeafSystem):
    """One IR distance sensor (see the module docstring for its state and ports).

    .. pydrake_system::

        name: IrSensor
        input_ports:
        - query_object
        output_ports:
        - distance
        - range
        - normalized
        - scan_time
        - changed
        - true_distance
        - voltage (sharp_gp2d12 only)
        - adc_counts (sharp_gp2d12 only)
        - reading
        - hit_points
        - ray_origin
        - ray_end
        - ray_hit
        - scan_state

    Input `query_object` (abstract QueryObject, SceneGraph's). Outputs (vectors): `distance`,
    `range`, `true_distance` (m); `normalized` (distance / range); `scan_time` (s; NaN before
    the first scan); `changed` (0 or 1); `voltage` (V); `adc_counts`; `reading` [distance,
    range, normalized, scan_time]; `hit_points`, `ray_origin`, `ray_end` (m, world frame;
    hit_points NaN for a ray that hit nothing); `ray_hit` (0 or 1 per ray); `scan_state` (the
    discrete state, `scan_state_layout`). The sensor frame S is fixed in the body frame B by
    X_BS; +x of S is the look direction.

    Scans every 1/`scan_rate_hz` s from then on. With `step` (a continuous plant's physics
    step, s) each scan is taken on the plant's steps instead, at the first at or after its
    time: an event between CENIC's steps splits one, and even a scan time a rounding error off
    a step's (0.05 x 3 is not 0.01 x 15) is a step of its own.

    config: as validated by the scenario loader (`config/validate.py`), trusted here;
    frame_id: the SceneGraph FrameId of the body the sensor is fixed to; X_BS: the sensor
    frame in that body's frame (default: `config.X_PB`, its base frame being the body's);
    exclude: the robot's own geometry ids (never hit); key: the noise key (sharp_gp2d12).
    """

    def __init__(self, config: IrSensorConfig, frame_id, exclude, key: int = 0,
                 name: str = "ir", X_BS: RigidTransform | None = None, step: float = 0.0):
        super().__init__()
        self.config = config
        self.sensor_name = name
        self._frame_id = frame_id
        self._exclude = frozenset(exclude)
        # A parameter: a reset Context may carry another run's seed.
        self._key_index = self.DeclareAbstractParameter(Value(int(key)))
        self._range = float(config.maximum_range)
        self._threshold = float(config.change_threshold)
        self._sharp = SharpGP2D12(noise_std=config.noise_std) if config.model == "sharp_gp2d12" \
            else None
        if X_BS is None:
            X_BS = config.X_PB.GetDeterministicValue()
        self._fan = RayFan.cross_of_rays(X_BS, config.samples, config.dispersion_cone_angle)
        self.num_rays = n = 2 * config.samples
        self.period = 1.0 / config.scan_rate_hz
        self._casters = CasterCache(self._exclude)

        self._query_port = self.DeclareAbstractInputPort(
            "query_object", self._query_model_value())
        initial = np.zeros(_READING_SIZE)
        initial[[DISTANCE, PREVIOUS, TRUE_DISTANCE]] = self._range
        initial[SCAN_TIME] = math.nan
        self.state_size, self._origin, self._end, self._hit = scan_state_layout(n)
        self._state = self.DeclareDiscreteState(
            np.concatenate([initial, np.zeros(self.state_size - _READING_SIZE)]))

        self.DeclareInitializationDiscreteUpdateEvent(self._initial_scan)
        self._step = float(step)
        self.events = (step, 0.0) if step > 0 else (self.period, self.period)
        """(period, offset), s: the schedule of the scan events. A reader that looks on the
        same schedule sees each scan once, at the look after it (a look runs before the
        updates at its time), with no stop of its own."""
        if step > 0:
            self.DeclarePeriodicDiscreteUpdateEvent(step, 0.0, self._scan_if_due)
        else:
            self.DeclarePeriodicDiscreteUpdateEvent(self.period, self.period,
                                                    self._periodic_scan)

        state = {self.discrete_state_ticket(self._state)}

        def scalar(port_name, fn):
            return self.DeclareVectorOutputPort(
                port_name, 1, lambda c, out: out.SetAtIndex(0, fn(self._value(c))),
                prerequisites_of_calc=state)

        scalar("distance", lambda r: r[DISTANCE])
        scalar("range", lambda r: self._range)
        scalar("normalized", lambda r: r[DISTANCE] / self._range)
        scalar("scan_time", lambda r: r[SCAN_TIME])
        scalar("changed", lambda r: r[CHANGED])
        scalar("true_distance", lambda r: r[TRUE_DISTANCE])
        if self._sharp is not None:
            scalar("voltage", lambda r: r[VOLTAGE])
            scalar("adc_counts", lambda r: r[ADC_COUNTS])
        self.DeclareVectorOutputPort("reading", 4, self._calc_reading,
                                     prerequisites_of_calc=state)
        self.DeclareVectorOutputPort("hit_points", 3 * n, self._calc_hit_points,
                                     prerequisites_of_calc=state)
        for port_name, part in (("ray_origin", self._origin), ("ray_end", self._end),
                                ("ray_hit", self._hit)):
            self.DeclareVectorOutputPort(
                port_name, part.stop - part.start,
                lambda c, out, part=part: out.SetFromVector(self._all(c)[part]),
                prerequisites_of_calc=state)
        self.DeclareStateOutputPort("scan_state", self._state)

    @staticmethod
    def _query_model_value():
        from pydrake.common.value import AbstractValue
        from pydrake.geometry import QueryObject

        return AbstractValue.Make(QueryObject())

    # -- reading the state ------------------------------------------------------------------

    def _all(self, context) -> np.ndarray:
        return context.get_discrete_state(self._state).value()

    def _value(self, context) -> np.ndarray:
        return self._all(context)[:_READING_SIZE]

    def SetNoiseKey(self, context, key: int) -> None:
        """The noise key (`noise_key`) this Context's scans draw from (sharp_gp2d12)."""
        context.get_mutable_abstract_parameter(self._key_index).set_value(int(key))

    @property
    def change_threshold(self) -> float:
        """m: a reading moving by more than this counts as a change (`changed`)."""
        return self._threshold

    def reading(self, context) -> IrReading:
        """The latest scan as an analog reading (context: this system's)."""
        r = self._value(context)
        return IrReading(float(r[DISTANCE]), self._range, float(r[DISTANCE] / self._range),
                         float(r[SCAN_TIME]))

    def _calc_reading(self, context, output: BasicVector) -> None:
        r = self._value(context)
        output.SetFromVector([r[DISTANCE], self._range, r[DISTANCE] / self._range, r[SCAN_TIME]])

    def _calc_hit_points(self, context, output: BasicVector) -> None:
        x = self._all(context)
        ends = x[self._end].reshape(-1, 3).copy()
        ends[x[self._hit] < 0.5] = np.nan
        output.SetFromVector(ends.ravel())

    # -- scanning ---------------------------------------------------------------------------

    def caster(self, query_object) -> RayCaster:
        """The RayCaster for the QueryObject's geometry, built on first use and rebuilt only
        when the proximity geometry changes (the robot's own geometry excluded)."""
        return self._casters.caster(query_object)

    def _cast(self, query_object):
        """(origin, directions, distances) as plain floats (the scan's hot path)."""
        X_WB = query_object.GetPoseInWorld(self._frame_id).GetAsMatrix34().tolist()
        origin, directions, cone = self._fan.in_world(X_WB)
        t = self.caster(query_object).cast_fan(query_object, origin, directions, self._range,
                                               cone)
        return origin, directions, t

    def _initial_scan(self, context, discrete_state) -> None:
        self._do_scan(context, discrete_state.get_mutable_value(), 0, self._range)

    def _periodic_scan(self, context, discrete_state) -> None:
        # Drake initialises the handler's output with the current discrete state
        # (LeafSystem::DispatchDiscreteVariableUpdateHandler: "Must initialize the output
        # argument with the current contents of the discrete state"), so the previous scan is
        # read from it: one call instead of three (it matters in place, where every pybind
        # call runs with cold caches after the physics step).
        x = discrete_state.get_mutable_value()
        self._do_scan(context, x, int(x[SCAN_INDEX]) + 1, float(x[DISTANCE]))

    def scan_due(self, t: float) -> bool:
        """Whether the plant step at `t` (`step` > 0) takes a scan: a scan time k period
        (k >= 1) in (t - step, t]."""
        return tick_in_step(t, 1.0 / self.period, self.period, self._step)

    def _scan_if_due(self, context, discrete_state):
        if not self.scan_due(context.get_time()):
            return EventStatus.DidNothing()
        self._periodic_scan(context, discrete_state)
        return EventStatus.Succeeded()

    def _do_scan(self, context, x, index: int, previous: float) -> None:
        """Scans and writes the whole state vector `x` (the handler's output, mutable)."""
        # A dozen numbers: plain Python floats are cheaper than numpy calls here.
        origin, directions, t = self._cast(self._query_port.Eval(context))
        ox, oy, oz = origin
        rng = self._range
        # One pass: the state vector's tail in `scan_state_layout` order (origin, ray ends,
        # hit flags) and the nearest hit.
        x_new = [0.0] * _READING_SIZE
        x_new += origin
        hit = []
        true_distance = rng
        for ti, (dx, dy, dz) in zip(t, directions, strict=True):
            if ti <= rng:
                hit.append(1.0)
                if ti < true_distance:
                    true_distance = ti
            else:
                ti = rng  # a miss (inf) ends at maximum_range
                hit.append(0.0)
            x_new += (ox + ti * dx, oy + ti * dy, oz + ti * dz)
        x_new += hit
        voltage = counts = 0.0
        if self._sharp is None:
            raw = true_distance
        else:
            s = self._sharp
            v = s.voltage_scalar(true_distance if 1.0 in hit else math.inf)
            if s.noise_std > 0.0:
                key = context.get_abstract_parameter(self._key_index).get_value()
                v += s.noise_std * counter_normal(key, index)
            counts = s.counts_scalar(v)
            voltage = counts * s.adc_step
            raw = min(s.distance_from_voltage_scalar(voltage), rng)
        changed = 1.0 if abs(raw - previous) > self._threshold else 0.0
        x_new[:_READING_SIZE] = (raw, context.get_time(), previous, changed, index,
                                 true_distance, voltage, counts)
        x[:] = x_new


# --- Meshcat -------------------------------------------------------------------------------

HIT_RADIUS = 0.006
"""m: the radius of the spheres drawn where rays land."""
_RAY_COLOR = Rgba(1.0, 0.15, 0.1, 0.6)
_HIT_COLORS = (Rgba(1.0, 0.05, 0.05, 1.0), Rgba(1.0, 0.85, 0.1, 1.0))
"""Hit marks alternate between these on successive scans: they flash, as in the book."""


class IrMeshcatVisualizer(LeafSystem):
    """Draws one IR sensor's rays (line segments) and hit points (small spheres) in Meshcat.

    .. pydrake_system::

        name: IrMeshcatVisualizer
        input_ports:
        - scan_state

    Everything lives under ``path`` (``/ir/<robot>/<sensor>``): ``rays`` and ``hits/<i>``;
    the Meshcat scene tree's checkbox on ``/ir``, a robot or a sensor shows or hides it.
    Its input ``scan_state`` is an IrSensor's output of that name;
    it redraws once per scan, right after the scan (it checks for a new scan at every step;
    given the sensor's scan ``period``, only at steps that end more than a period after the
    last scan drawn, so most steps cost it one time comparison).
    """

    def __init__(self, meshcat: Meshcat, path: str, num_rays: int,
                 period: float | None = None):
        super().__init__()
        self._meshcat = meshcat
        self.path = path
        self._n = num_rays
        size, self._origin, self._ends, self._hits = scan_state_layout(num_rays)
        self._scan = self.DeclareVectorInputPort("scan_state", size)
        self._last_index = None
        self._last_time = None
        self.draws = 0
        """How many times it has redrawn (for tests)."""
        self.DeclareInitializationPublishEvent(self._draw)
        # Per step, not periodic: a periodic publish at the scan times would run before the
        # scan due at the same time (Drake takes that update at the start of the next step)
        # and show every scan one period late.
        self.DeclarePerStepPublishEvent(self._draw if period is None else self._draw_if_due)
        self._due_after = (1.0 - 1e-9) * period if period is not None else 0.0
        """s after the last scan drawn before the next one can be there (a hair under the
        period: the scan times are sums and products of doubles)."""
        for i in range(num_rays):
            meshcat.SetObject(f"{path}/hits/{i}", Sphere(HIT_RADIUS), _HIT_COLORS[0])
            meshcat.SetProperty(f"{path}/hits/{i}", "visible", False)
        self._visible = [False] * num_rays
        """What each hit mark's Meshcat `visible` property was last set to."""

    def _draw_if_due(self, context) -> None:
        # A scan due at t is taken at the start of the step from t, so it can only be new at
        # the end of a step past last_time + period (or after time went back: a restore).
        t = context.get_time()
        last = self._last_time
        if last is not None and last <= t <= last + self._due_after:
            return
        self._draw(context)

    def _draw(self, context) -> None:
        x = self._scan.Eval(context)
        reading = x[:_READING_SIZE]
        key = (reading[SCAN_INDEX], reading[SCAN_TIME])
        if key == (self._last_index, self._last_time):
            return
        self._last_index, self._last_time = key
        origin = x[self._origin]
        ends = x[self._ends].reshape(-1, 3)
        hits = x[self._hits] > 0.5
        starts = np.asfortranarray(np.tile(origin, (self._n, 1)).T)
        self._meshcat.SetLineSegments(f"{self.path}/rays", starts, np.asfortranarray(ends.T),
                                      2.0, _RAY_COLOR)
        color = _HIT_COLORS[int(reading[SCAN_INDEX]) % 2]
        for i in range(self._n):
            path = f"{self.path}/hits/{i}"
            if hits[i] != self._visible[i]:  # each Meshcat call is a message: send changes only
                self._meshcat.SetProperty(path, "visible", bool(hits[i]))
                self._visible[i] = bool(hits[i])
            if hits[i]:
                self._meshcat.SetTransform(path, RigidTransform(ends[i]))
                self._meshcat.SetProperty(path, "color", [color.r(), color.g(), color.b(), 1.0])
        self.draws += 1


# --- wiring into a station -----------------------------------------------------------------


def add_ir_sensor(site: SensorSite, name: str, config: IrSensorConfig) -> IrSensor | None:
    """Adds the robot's IR sensor `name` (`<robot>.ir.<name>`), mounted by its `X_PB` (on a
    link of the site's model instance, whose own geometry it does not see), reading
    SceneGraph's query output, and exports its ports as `<robot>.<name>.<port>`; returns it
    (None when `config.enabled` is false). The plant must be finalized."""
    if not config.enabled:
        return None
    plant, builder, robot = site.plant, site.builder, site.robot
    body, X_BS = mount_frame(plant, site.model_instance, config.X_PB)
    sensor = builder.AddNamedSystem(f"{robot}.ir.{name}", IrSensor(
        config, plant.GetBodyFrameIdOrThrow(body.index()),
        model_instance_geometry_ids(plant, site.model_instance),
        noise_key(site.random_seed, robot, name, config.noise_seed), name, X_BS,
        site.continuous_step))
    builder.Connect(site.scene_graph.get_query_output_port(), sensor.get_input_port(0))
    for i in range(sensor.num_output_ports()):
        port = sensor.get_output_port(i)
        builder.ExportOutput(port, f"{robot}.{name}.{port.get_name()}")
    return sensor


# --- the wire formats -------------------------------------------------------------------
INFRARED = 1
"""sensor_msgs/Range's radiation_type for an infrared sensor."""

RANGE_SCHEMA = {
    "title": "corobot.Range",
    "description": "One IR scan, with ROS sensor_msgs/Range's fields (metres, radians).",
    "type": "object",
    "properties": {
        "timestamp": {"type": "object", "properties": {
            "sec": {"type": "integer"}, "nsec": {"type": "integer"}}},
        "frame_id": {"type": "string"},
        "radiation_type": {"type": "integer", "description": "1: INFRARED"},
        "field_of_view": {"type": "number", "description": "rad, the cone's full angle"},
        "min_range": {"type": "number"},
        "max_range": {"type": "number"},
        "range": {"type": "number", "description": "the reading (m); max_range: nothing"},
        "true_range": {"type": "number", "description": "the geometric nearest hit (m)"},
    },
}
"""The JSON schema of an IR scan on Foxglove (`IrSensorKind.foxglove_message`)."""


@dc.dataclass(frozen=True)
class IrScan:
    """One scan as its messages carry it (`IrSensorKind.wire_reading`): sensor_msgs/Range's
    fields in the sensor's frame (m; `field_of_view` rad, the cone's full angle), the
    geometric nearest hit, and the rays in the world (m; `hits` 1 where a ray hit)."""

    time: float
    range: float
    true_range: float
    field_of_view: float
    min_range: float
    max_range: float
    origin: np.ndarray
    ends: np.ndarray
    """N x 3."""
    hits: np.ndarray

    @staticmethod
    def of(config: IrSensorConfig, num_rays: int, scan) -> IrScan:
        """The scan in an IrSensor's state vector `scan` (`scan_state_layout`)."""
        _, origin, ends, hits = scan_state_layout(num_rays)
        return IrScan(float(scan[SCAN_TIME]), float(scan[DISTANCE]), float(scan[TRUE_DISTANCE]),
                      math.radians(config.dispersion_cone_angle),
                      SharpGP2D12.min_distance if config.model == "sharp_gp2d12" else 0.0,
                      config.maximum_range, scan[origin], np.asarray(scan[ends]).reshape(-1, 3),
                      scan[hits])


RAY_HIT_COLOR = (1.0, 0.2, 0.1, 1.0)
RAY_MISS_COLOR = (0.3, 0.8, 0.3, 0.6)
"""The IR rays drawn in Foxglove: red where a ray hit something, green where it ran out."""


def ray_lines(origin, ends: np.ndarray, hits: np.ndarray):
    """The rays of one IR scan as a Foxglove line list in the world frame: origin (3) to each
    end (N x 3, m), coloured by whether it hit (N, 0 or 1)."""
    from foxglove.messages import LinePrimitive, LinePrimitiveLineType

    from corobot_drake.recording.topics import color, point3

    points, colors = [], []
    o = point3(origin)
    for end, hit in zip(ends, hits, strict=True):
        c = color(RAY_HIT_COLOR if hit > 0.5 else RAY_MISS_COLOR)
        points += [o, point3(end)]
        colors += [c, c]
    return LinePrimitive(type=LinePrimitiveLineType.LineList, thickness=2.0,
                         scale_invariant=True, points=points, colors=colors)



# --- the kind ------------------------------------------------------------------------------


class IrSensorKind(SensorKind):
    """IR distance sensors: `robots.<robot>.ir_sensors.<sensor>` (`IrSensorConfig`), one
    `IrSensor` each, read as an `IrReading` (m, s) per scan; topic `ir/<sensor>`, frame
    `ir_<sensor>` (looking along its +x)."""

    field = "ir_sensors"
    config_type = IrSensorConfig
    reading_type = IrReading
    topic = "ir"
    ros2_type = "sensor_msgs/msg/Range"

    def defaults(self) -> dict:
        return default_ir_sensors()

    def new_sensor(self, name: str) -> IrSensorConfig:
        return IrSensorConfig()

    def log_columns(self, sensor: str) -> tuple[str, ...]:
        """`ir_<sensor>`: m, the latest scan's distance (the reading's, noise and all)."""
        return (f"ir_{sensor}",)

    def log_port(self, sensor: BuiltSensor):
        return sensor.system.GetOutputPort("scan_state"), (DISTANCE,)

    def add(self, site: SensorSite, name: str, config: IrSensorConfig) -> BuiltSensor | None:
        sensor = add_ir_sensor(site, name, config)
        if sensor is None:
            return None
        return BuiltSensor(self, site.robot, name, config, sensor,
                           sensor.GetOutputPort("reading"), config.scan_rate_hz, config.X_PB)

    def set_seed(self, sensor: BuiltSensor, root_context, random_seed: int,
                 config: IrSensorConfig) -> None:
        system = sensor.system
        system.SetNoiseKey(system.GetMyMutableContextFromRoot(root_context), noise_key(
            random_seed, sensor.robot, sensor.name, config.noise_seed))

    def read(self, sensor: BuiltSensor, root_context) -> IrReading:
        system = sensor.system
        return system.reading(system.GetMyContextFromRoot(root_context))

    # --- the wire formats: one scan, on /ir/<sensor> (and its rays on /ir/<sensor>/rays) ---
    foxglove_schema = RANGE_SCHEMA

    def foxglove_channels(self) -> dict:
        return {"": RANGE_SCHEMA, "rays": "SceneUpdate"}

    def wire_ports(self, sensor: BuiltSensor) -> dict:
        return {"scan_state": sensor.system.GetOutputPort("scan_state")}

    def looks(self, sensor: BuiltSensor) -> tuple[float, float]:
        return sensor.system.events  # a scan and a look at one time: the look first

    def out_time(self, sensor: BuiltSensor, inputs) -> float:
        return float(inputs("scan_state")[SCAN_TIME])

    def wire_reading(self, sensor: BuiltSensor, inputs) -> IrScan:
        return IrScan.of(sensor.config, sensor.system.num_rays, inputs("scan_state"))

    def foxglove_message(self, reading: IrScan, frame: str) -> dict:
        """corobot.Range (JSON, `RANGE_SCHEMA`) and the rays in the world
        (foxglove.SceneUpdate, entity `frame`)."""
        from foxglove.messages import SceneEntity, SceneUpdate

        from corobot_drake.recording.topics import stamp

        ts = stamp(reading.time)
        scan = {"timestamp": {"sec": ts.sec, "nsec": ts.nsec}, "frame_id": frame,
                "radiation_type": INFRARED, "field_of_view": reading.field_of_view,
                "min_range": reading.min_range, "max_range": reading.max_range,
                "range": reading.range, "true_range": reading.true_range}
        entity = SceneEntity(timestamp=ts, frame_id="world", id=frame, lines=[
            ray_lines(reading.origin, reading.ends, reading.hits)])
        return {"": scan, "rays": SceneUpdate(entities=[entity])}

    def ros2_message(self, messages, reading: IrScan, frame: str):
        """sensor_msgs/Range, INFRARED (rad, m); nothing in range (the reading capped at
        max_range) is +Inf, as REP 117 asks."""
        nothing = reading.range >= reading.max_range
        return messages.msg("sensor_msgs/msg/Range")(
            header=messages.header(reading.time, frame), radiation_type=INFRARED,
            field_of_view=float(reading.field_of_view), min_range=float(reading.min_range),
            max_range=float(reading.max_range),
            range=math.inf if nothing else float(reading.range),
            variance=0.0)  # unknown: the sensor's noise is in volts, through a nonlinear curve

    def add_meshcat(self, builder, meshcat, sensor: BuiltSensor) -> None:
        """Its rays and hit points under /ir/<robot>/<sensor> (`IrMeshcatVisualizer`,
        `<robot>.ir.<sensor>.meshcat`)."""
        system = sensor.system
        viz = builder.AddNamedSystem(
            f"{sensor.robot}.ir.{sensor.name}.meshcat",
            IrMeshcatVisualizer(meshcat, f"/ir/{sensor.robot}/{sensor.name}", system.num_rays,
                                system.period))
        builder.Connect(system.GetOutputPort("scan_state"), viz.get_input_port())


__all__ = [
    "IrMeshcatVisualizer",
    "IrReading",
    "IrScan",
    "IrSensor",
    "IrSensorKind",
    "add_ir_sensor",
    "cross_of_rays_in_sensor_frame",
]
