"""The IMU: a gyroscope and an accelerometer (and, optionally, the orientation) of a point
fixed on a link of the robot, speaking sensor_msgs/Imu.

The sensor frame S is mounted by the config's `X_PB` (on the chassis at its centre, axes
the chassis', by default). Each sample reads, in S:

- `angular_velocity` (rad/s): the link's angular velocity in the world, at the sample;
- `linear_acceleration` (m/s^2): the specific force at S, a - g, what an accelerometer reads
  (level and at rest: +9.81 on z). `a` is the mean acceleration of the point S in the world
  over the last sample period, (v_S(t_k) - v_S(t_k-1)) / (t_k - t_k-1), as a delta-velocity
  IMU integrates it: with S off the link's origin that includes the centripetal and tangential
  terms (v_S = v_Bo + w x p_BoS). It lags the instantaneous acceleration by half a period; the
  first sample (no previous one) reads a = 0;
- `orientation` (optional): S's orientation in the world (ground truth, no noise).

Why not the plant's `body_spatial_accelerations` output: on a continuous plant (the
project's default, stepped by CENIC) it is the forward dynamics of the compliant contact model
at the current state, not what CENIC's implicit step does: on the default scene, in a steady
0.3 m/s, 1 rad/s turn it read 5 m/s^2 and 40 rad/s^2 where the robot's is 0.28 m/s^2 and 0.
On SAP's discrete plant it is a step's (v_n+1 - v_n) / h, the numbers these differences give
at a rate equal to the step. The poses and velocities are right on both plants.

Noise, per axis (densities as a datasheet or Kalibr states them): white noise of standard
deviation density x sqrt(rate) on each sample, and a bias that walks by walk x sqrt(1 / rate)
per sample from 0 (its standard deviation grows as walk x sqrt(t)). The draws of sample k are a
pure function of (the sensor's noise key, k) (numpy's Philox, keyed), and the biases are
discrete state, so a reset Context replays the same readings bit for bit.
"""


import dataclasses as dc
import math

import numpy as np
from pydrake.common.eigen_geometry import Quaternion
from pydrake.common.schema import Transform
from pydrake.common.value import AbstractValue, Value
from pydrake.geometry import Rgba
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.math import SpatialVelocity
from pydrake.systems.framework import EventStatus, LeafSystem

from corobot_drake.config.poses import mount, mount_frame
from corobot_drake.limits import RATE, Range, bounded
from corobot_drake.robots import corobot
from corobot_drake.sensors.follow import ThrottledDrawing
from corobot_drake.sensors.ir_sensor import noise_key
from corobot_drake.sensors.kind import BuiltSensor, SensorKind
from corobot_drake.sensors.ticks import last_tick, tick_in_step
from corobot_drake.topics import nanoseconds

# --- the config (the scenario's `robots.<name>.imus.<sensor>`) -----------------------------


@dc.dataclass
class ImuConfig:
    """One IMU on a robot. The default noise figures are those of a MEMS IMU, the Analog
    Devices ADIS16448 of the EuRoC MAV dataset's VI-Sensor (its `imu0/sensor.yaml`)."""

    X_PB: Transform = dc.field(default_factory=lambda: mount(corobot.box("chassis")[1], (0, 0, 0)))
    """The sensor frame S in `base_frame` (default `chassis`, at the chassis box's centre,
    axes the chassis': +x forward, +z up)."""
    rate_hz: float = bounded(100.0, RATE)
    """Samples per second (each taken on the first physics step at or after its time)."""
    gyro_noise_density: float = bounded(1.6968e-4, Range(0.0, 1.0, unit="rad/s/sqrt(Hz)"))
    """rad/s/sqrt(Hz): the gyroscope's white noise (per sample: x sqrt(rate_hz)); 0: none."""
    gyro_random_walk: float = bounded(1.9393e-5, Range(0.0, 1.0, unit="rad/s^2/sqrt(Hz)"))
    """rad/s^2/sqrt(Hz): the gyroscope's bias random walk; 0: no bias."""
    accel_noise_density: float = bounded(2.0e-3, Range(0.0, 10.0, unit="m/s^2/sqrt(Hz)"))
    """m/s^2/sqrt(Hz): the accelerometer's white noise (per sample: x sqrt(rate_hz))."""
    accel_random_walk: float = bounded(3.0e-3, Range(0.0, 10.0, unit="m/s^3/sqrt(Hz)"))
    """m/s^3/sqrt(Hz): the accelerometer's bias random walk; 0: no bias."""
    orientation: bool = True
    """Whether it reports its orientation (off: orientation None, and in the message the
    orientation covariance's first element is -1, as sensor_msgs/Imu says)."""
    noise_seed: int = 0
    """Mixed with the scenario's random_seed and the robot and sensor names."""
    enabled: bool = True
    """False: no sensor."""


# --- the reading -------------------------------------------------------------------------


@dc.dataclass(frozen=True)
class Imu:
    """One IMU sample, with sensor_msgs/Imu's fields, in the sensor's frame S.

    `orientation` (x, y, z, w): the quaternion of S in the world (None when the config turns
    it off); `angular_velocity` (rad/s) and `linear_acceleration` (m/s^2, the specific force
    a - g: +9.81 on z level at rest) in S; the covariances row-major 3 x 3, the white noise's
    variance per sample on the diagonal (orientation's all 0, ground truth; [-1, 0, ...] when
    off); `time` (s) the simulated time of the sample."""

    orientation: tuple[float, float, float, float] | None
    orientation_covariance: tuple[float, ...]
    angular_velocity: tuple[float, float, float]
    angular_velocity_covariance: tuple[float, ...]
    linear_acceleration: tuple[float, float, float]
    linear_acceleration_covariance: tuple[float, ...]
    time: float

    def __repr__(self) -> str:
        def vec(v, spec):
            return "None" if v is None else "(" + ", ".join(format(x, spec) for x in v) + ")"

        return (f"Imu(orientation={vec(self.orientation, '.4f')}, angular_velocity="
                f"{vec(self.angular_velocity, '.4f')} rad/s, linear_acceleration="
                f"{vec(self.linear_acceleration, '.3f')} m/s^2, time={self.time:.3f} s)")


def _diagonal(variance: float) -> tuple[float, ...]:
    return (variance, 0.0, 0.0, 0.0, variance, 0.0, 0.0, 0.0, variance)


# --- the sensor system ---------------------------------------------------------------------

# The discrete state vector: the latest sample and what the next one needs.
TIME, INDEX = 0, 1
ORIENTATION = slice(2, 6)  # x, y, z, w
GYRO = slice(6, 9)  # rad/s, in S, as read (noise and bias included)
ACCEL = slice(9, 12)  # m/s^2, in S, as read
GYRO_BIAS = slice(12, 15)  # rad/s
ACCEL_BIAS = slice(15, 18)  # m/s^2
VELOCITY = slice(18, 21)  # m/s: the point S's velocity in the world (W) at the sample
STATE_SIZE = 21


def sample_noise(key: int, index: int, bits: np.random.Philox | None = None) -> np.ndarray:
    """12 standard normal draws for sample `index` of the sensor with noise key `key`: the
    gyro's and the accelerometer's white noise, then their bias increments (3 each). A pure
    function of (key, index): Philox keyed by `key`, each sample in its own block of the
    counter space (the index in the counter's second word, so no two samples' draws
    overlap). `bits`: a Philox to reuse (its whole state is set here, nothing of it carries
    over; making one costs 5x the draws)."""
    bits = bits or np.random.Philox()
    bits.state = {"bit_generator": "Philox",
                  "state": {"counter": np.array([0, index, 0, 0], dtype=np.uint64),
                            "key": np.array([key, 0], dtype=np.uint64)},
                  "buffer": np.zeros(4, dtype=np.uint64), "buffer_pos": 4,
                  "has_uint32": 0, "uinteger": 0}
    return np.random.Generator(bits).standard_normal(12)


class ImuSensor(LeafSystem):
    """One IMU (see the module docstring for what it measures).

    .. pydrake_system::

        name: ImuSensor
        input_ports:
        - body_poses
        - body_spatial_velocities
        output_ports:
        - reading
        - angular_velocity
        - linear_acceleration
        - orientation
        - sample_time
        - bias
        - sample_state

    Inputs: the plant's `body_poses` and `body_spatial_velocities` (abstract lists, one per
    body; the sensor reads its body's). Outputs: `reading` (abstract `Imu`);
    `angular_velocity` (rad/s) and `linear_acceleration` (m/s^2) in S; `orientation` [x, y, z,
    w] (S in the world, whether or not the reading carries it); `sample_time` (s);
    `bias` [gyro (rad/s) 3, accelerometer (m/s^2) 3], the biases in the latest sample;
    `sample_state`, the whole state (`STATE_SIZE`: what the run log picks its columns from).

    A sample at initialization (index 0), then every 1 / `rate_hz` s (tick k at k / rate_hz,
    index k); with `step` (the plant's physics step, s) each sample is taken on the plant's
    steps instead, at the first at or after its tick, with the index of the last tick passed:
    on a continuous plant an event between CENIC's steps would split one and change the
    motion (as for the IR sensors); on a discrete plant a sample a rounding error off the
    plant's update time would see the state before or after that update depending on the
    rounding, and the differences of velocity would then span a step more or less. With
    ticks faster than the steps, a sample covers all the ticks since the last one (its bias
    walks for all of them). Samples are unrestricted updates: a discrete plant steps in one
    (Drake 1.58), and Drake runs those before the discrete updates due at the same time, so
    a discrete-update sample at a step's time read the state after that step; an
    unrestricted one reads the state at its time, as the plant's step does.

    config: as validated by the loader, trusted here; body_index: the plant body S is on;
    X_BS: S in that body's frame; gravity_W (m/s^2): the plant's gravity; key: the noise key.
    """

    def __init__(self, config: ImuConfig, body_index, X_BS: RigidTransform, gravity_W,
                 key: int = 0, step: float = 0.0):
        super().__init__()
        self.config = config
        self._body = int(body_index)
        self._R_BS = X_BS.rotation()
        self._p_BS = X_BS.translation().copy()
        self._g_W = np.asarray(gravity_W, dtype=float).copy()
        self.rate = float(config.rate_hz)
        self.period = 1.0 / self.rate
        root_rate = math.sqrt(self.rate)
        self._white = np.repeat([config.gyro_noise_density * root_rate,
                                 config.accel_noise_density * root_rate], 3)
        self._walk = np.repeat([config.gyro_random_walk, config.accel_random_walk], 3) / root_rate
        self._noisy = bool(self._white.any() or self._walk.any())
        self._bits = np.random.Philox()
        """Scratch for `sample_noise` (its state is set before each sample's draws)."""
        # A parameter: a reset Context may carry another run's seed.
        self._key_index = self.DeclareAbstractParameter(Value(int(key)))
        self._poses = self.DeclareAbstractInputPort(
            "body_poses", AbstractValue.Make([RigidTransform()]))
        self._velocities = self.DeclareAbstractInputPort(
            "body_spatial_velocities", AbstractValue.Make([SpatialVelocity()]))
        initial = np.zeros(STATE_SIZE)
        initial[TIME] = math.nan
        initial[ORIENTATION] = (0.0, 0.0, 0.0, 1.0)
        self._state = self.DeclareDiscreteState(initial)
        self.DeclareInitializationUnrestrictedUpdateEvent(self._first_sample)
        self._step = float(step)
        self.events = (step, 0.0) if step > 0 else (self.period, self.period)
        """(period, offset), s: the schedule of the sample events. A reader that looks on the
        same schedule sees each sample once, at the look after it (a look runs before the
        updates at its time)."""
        self.DeclarePeriodicUnrestrictedUpdateEvent(
            *self.events, self._sample_if_due if step > 0 else self._sample)
        self._declare_outputs()

    @property
    def body(self) -> int:
        """The index of the plant body S is fixed to."""
        return self._body

    @property
    def p_BS(self) -> np.ndarray:
        """m: S's origin in that body's frame."""
        return self._p_BS

    def _declare_outputs(self) -> None:
        state = {self.discrete_state_ticket(self._state)}
        self.DeclareAbstractOutputPort("reading", lambda: AbstractValue.Make(self._empty()),
                                       self._calc_reading, prerequisites_of_calc=state)
        for name, part in (("angular_velocity", GYRO), ("linear_acceleration", ACCEL),
                           ("orientation", ORIENTATION), ("sample_time", slice(TIME, TIME + 1)),
                           ("bias", slice(GYRO_BIAS.start, ACCEL_BIAS.stop))):
            self.DeclareVectorOutputPort(
                name, part.stop - part.start,
                lambda c, out, part=part: out.SetFromVector(self._x(c)[part]),
                prerequisites_of_calc=state)
        self.DeclareStateOutputPort("sample_state", self._state)

    # -- reading the state ------------------------------------------------------------------

    def _x(self, context) -> np.ndarray:
        return context.get_discrete_state(self._state).value()

    def SetNoiseKey(self, context, key: int) -> None:
        """The noise key (`ir_sensor.noise_key`) this Context's samples draw from."""
        context.get_mutable_abstract_parameter(self._key_index).set_value(int(key))

    def covariances(self) -> tuple[tuple, tuple, tuple]:
        """(orientation, angular velocity, linear acceleration) covariances, row-major 3 x 3:
        the white noise's per-sample variance (rad^2/s^2, m^2/s^4) on the diagonals."""
        white = self._white ** 2
        orientation = _diagonal(0.0)
        if not self.config.orientation:
            orientation = (-1.0, *orientation[1:])
        return orientation, _diagonal(float(white[0])), _diagonal(float(white[3]))

    def _empty(self) -> Imu:
        return self.reading_of(np.full(STATE_SIZE, math.nan))

    def reading_of(self, x: np.ndarray) -> Imu:
        """The `Imu` reading of a state vector `x`."""
        q, w, a = (tuple(float(v) for v in x[part]) for part in (ORIENTATION, GYRO, ACCEL))
        orientation, gyro, accel = self.covariances()
        return Imu(q if self.config.orientation else None, orientation, w, gyro, a, accel,
                   float(x[TIME]))

    def _calc_reading(self, context, output) -> None:
        output.set_value(self.reading_of(self._x(context)))

    # -- sampling ---------------------------------------------------------------------------

    def _vector(self, state) -> np.ndarray:
        # The handler's output starts as the current state (Drake's update contract).
        return state.get_mutable_discrete_state(self._state).get_mutable_value()

    def _first_sample(self, context, state) -> None:
        self._take(context, self._vector(state), 0)

    def _sample(self, context, state) -> None:
        x = self._vector(state)
        self._take(context, x, int(x[INDEX]) + 1)

    def sample_due(self, t: float) -> bool:
        """Whether the plant step at `t` (`step` > 0) takes a sample: a tick k / rate_hz
        (k >= 1) in (t - step, t]."""
        return tick_in_step(t, self.rate, self.period, self._step)

    def _sample_if_due(self, context, state):
        t = context.get_time()
        if not self.sample_due(t):
            return EventStatus.DidNothing()
        k, _ = last_tick(t, self.rate, 0.0)
        self._take(context, self._vector(state), k)
        return EventStatus.Succeeded()

    def _take(self, context, x: np.ndarray, index: int) -> None:
        """Samples tick `index` into the state vector `x` (the previous sample on entry)."""
        X_WB = self._poses.Eval(context)[self._body]
        V_WB = self._velocities.Eval(context)[self._body]
        R_WB = X_WB.rotation()
        R_WS = R_WB @ self._R_BS
        R_SW = R_WS.matrix().T
        w_W = V_WB.rotational()
        # The point S's velocity: the body origin's shifted (SpatialVelocity.Shift), v + w x p.
        # (By hand: numpy's cross costs more than the rest of the sample.)
        (wx, wy, wz), (px, py, pz) = w_W.tolist(), (R_WB @ self._p_BS).tolist()
        v_WS = V_WB.translational() + np.array(
            (wy * pz - wz * py, wz * px - wx * pz, wx * py - wy * px))
        t = context.get_time()
        dt = t - x[TIME] if index > 0 else 0.0
        a_W = (v_WS - x[VELOCITY]) / dt if dt > 0 else 0.0
        gyro = R_SW @ w_W
        accel = R_SW @ (a_W - self._g_W)
        if self._noisy:
            key = context.get_abstract_parameter(self._key_index).get_value()
            n = sample_noise(key, index, self._bits)
            if index > 0:  # a walk for each tick since the last sample
                x[GYRO_BIAS.start:ACCEL_BIAS.stop] += (
                    self._walk * math.sqrt(index - x[INDEX]) * n[6:])
            gyro = gyro + x[GYRO_BIAS] + self._white[:3] * n[:3]
            accel = accel + x[ACCEL_BIAS] + self._white[3:] * n[3:6]
        q = R_WS.ToQuaternion()
        x[TIME], x[INDEX] = t, index
        x[ORIENTATION] = (q.x(), q.y(), q.z(), q.w())
        x[GYRO], x[ACCEL], x[VELOCITY] = gyro, accel, v_WS


# --- the kind ------------------------------------------------------------------------------

# --- Meshcat --------------------------------------------------------------------------------

FORCE_SCALE = 0.02
"""m drawn per m/s^2 of specific force (at rest, gravity's 9.81 m/s^2 up: 0.196 m)."""
RATE_SCALE = 0.2
"""m drawn per rad/s of angular velocity."""
_FORCE_COLOR = Rgba(0.1, 0.75, 0.2, 1.0)
_RATE_COLOR = Rgba(0.6, 0.2, 0.9, 1.0)


class ImuMeshcat(ThrottledDrawing):
    """Draws an IMU's latest sample in Meshcat, from the sensor's origin in the world: its
    specific force (green, `FORCE_SCALE` m per m/s^2: upright at rest, leaning back as the
    robot speeds up) and its angular velocity (purple, `RATE_SCALE` m per rad/s: up in a left
    turn), under `path` (`/imu/<robot>/<sensor>`: `specific_force`, `angular_velocity`).

    .. pydrake_system::

        name: ImuMeshcat
        input_ports:
        - sample_state
        - body_poses

    Inputs: the ImuSensor's `sample_state` and the plant's `body_poses`; drawn at most every
    `follow.MOVE_PERIOD` s.
    """

    def __init__(self, meshcat, path: str, imu: ImuSensor):
        super().__init__()
        self._meshcat, self.path, self._imu = meshcat, path, imu
        self._sample = self.DeclareVectorInputPort("sample_state", STATE_SIZE)
        self._poses = self.DeclareAbstractInputPort(
            "body_poses", AbstractValue.Make([RigidTransform()]))

    def draw(self, context) -> None:
        x = self._sample.Eval(context)
        X_WB = self._poses.Eval(context)[self._imu.body]
        p_WS = X_WB.multiply(self._imu.p_BS)
        q = x[ORIENTATION]
        R_WS = RotationMatrix(Quaternion(w=q[3], x=q[0], y=q[1], z=q[2]))
        for name, vector, scale, color in (
                ("specific_force", x[ACCEL], FORCE_SCALE, _FORCE_COLOR),
                ("angular_velocity", x[GYRO], RATE_SCALE, _RATE_COLOR)):
            end = p_WS + scale * (R_WS @ vector)
            self._meshcat.SetLineSegments(f"{self.path}/{name}", p_WS.reshape(3, 1),
                                          end.reshape(3, 1), 3.0, color)


IMU_SCHEMA = {
    "title": "corobot.Imu",
    "description": "One IMU sample, with ROS sensor_msgs/Imu's fields, in the sensor's frame "
                   "(rad/s, m/s^2; linear_acceleration is the specific force, gravity "
                   "included); orientation_covariance[0] = -1: no orientation.",
    "type": "object",
    "properties": {
        "timestamp": {"type": "object", "properties": {
            "sec": {"type": "integer"}, "nsec": {"type": "integer"}}},
        "frame_id": {"type": "string"},
        **{name: {"type": "object", "properties": {a: {"type": "number"} for a in axes}}
           for name, axes in (("orientation", "xyzw"), ("angular_velocity", "xyz"),
                              ("linear_acceleration", "xyz"))},
        **{f"{name}_covariance": {"type": "array", "items": {"type": "number"},
                                  "minItems": 9, "maxItems": 9}
           for name in ("orientation", "angular_velocity", "linear_acceleration")},
    },
}
"""The JSON schema of the IMU's Foxglove channel (foxglove-sdk has no Imu message)."""

_IDENTITY = (0.0, 0.0, 0.0, 1.0)
"""The orientation a message carries when the sensor reports none (its covariance says so)."""


class ImuKind(SensorKind):
    """The IMU kind: `robots.<robot>.imus.<sensor>` (`ImuConfig`), reading `Imu`, on topic
    `imu/<sensor>` in frame `imu_<sensor>` as sensor_msgs/Imu; on Foxglove as JSON
    (`IMU_SCHEMA`, ROS's field names), foxglove-sdk having no Imu message."""

    field = "imus"
    config_type = ImuConfig
    reading_type = Imu
    topic = "imu"
    ros2_type = "sensor_msgs/msg/Imu"
    ros2_qos = "sensor"
    foxglove_schema = IMU_SCHEMA

    def new_sensor(self, name: str) -> ImuConfig:
        return ImuConfig()

    def log_columns(self, sensor: str) -> tuple[str, ...]:
        """`imu_<sensor>_wx`, `_wy`, `_wz` (rad/s) and `_ax`, `_ay`, `_az` (m/s^2): the latest
        sample's angular velocity and linear acceleration in the sensor's frame, as read."""
        return tuple(f"imu_{sensor}_{c}" for c in ("wx", "wy", "wz", "ax", "ay", "az"))

    def log_port(self, sensor: BuiltSensor):
        return sensor.system.GetOutputPort("sample_state"), (*range(GYRO.start, GYRO.stop),
                                                             *range(ACCEL.start, ACCEL.stop))

    def add(self, site, name: str, config: ImuConfig) -> BuiltSensor | None:
        """The IMU `name` on the site's robot (`<robot>.imu.<name>`), fed by the plant's body
        poses and velocities; its vector outputs exported as `<robot>.imu.<name>.<port>`."""
        if not config.enabled:
            return None
        plant, builder, robot = site.plant, site.builder, site.robot
        body, X_BS = mount_frame(plant, site.model_instance, config.X_PB)
        sensor = builder.AddNamedSystem(f"{robot}.imu.{name}", ImuSensor(
            config, body.index(), X_BS, plant.gravity_field().gravity_vector(),
            noise_key(site.random_seed, robot, name, config.noise_seed), site.physics_step))
        builder.Connect(plant.get_body_poses_output_port(), sensor.GetInputPort("body_poses"))
        builder.Connect(plant.get_body_spatial_velocities_output_port(),
                        sensor.GetInputPort("body_spatial_velocities"))
        for i in range(1, sensor.num_output_ports()):  # the vectors (0: the abstract reading)
            port = sensor.get_output_port(i)
            builder.ExportOutput(port, f"{robot}.imu.{name}.{port.get_name()}")
        return BuiltSensor(self, robot, name, config, sensor, sensor.GetOutputPort("reading"),
                           sensor.rate, config.X_PB,
                           {"body_poses": plant.get_body_poses_output_port()})

    def set_seed(self, sensor: BuiltSensor, root_context, random_seed: int,
                 config: ImuConfig) -> None:
        system = sensor.system
        system.SetNoiseKey(system.GetMyMutableContextFromRoot(root_context), noise_key(
            random_seed, sensor.robot, sensor.name, config.noise_seed))

    def add_meshcat(self, builder, meshcat, sensor: BuiltSensor) -> None:
        viz = builder.AddNamedSystem(
            f"{sensor.robot}.imu.{sensor.name}.meshcat",
            ImuMeshcat(meshcat, f"/imu/{sensor.robot}/{sensor.name}", sensor.system))
        builder.Connect(sensor.system.GetOutputPort("sample_state"),
                        viz.GetInputPort("sample_state"))
        builder.Connect(sensor.extra["body_poses"], viz.GetInputPort("body_poses"))

    def summary_json(self, reading: Imu) -> dict:
        """The vectors' components as numbers of their own (`linear_acceleration_z`, ...: a
        study's sensors metric makes a column of each number) and the time; the covariances,
        fixed by the config, left out."""
        out = {}
        for name, axes in (("orientation", "xyzw"), ("angular_velocity", "xyz"),
                           ("linear_acceleration", "xyz")):
            vector = getattr(reading, name)
            if vector is not None:
                out.update({f"{name}_{a}": v for a, v in zip(axes, vector, strict=True)})
        out["time"] = reading.time
        return {key: v if math.isfinite(v) else None for key, v in out.items()}

    def looks(self, sensor: BuiltSensor) -> tuple[float, float]:
        return sensor.system.events  # a sample and a look at one time: the look first

    def foxglove_message(self, reading: Imu, frame: str) -> dict:
        """The reading as `IMU_SCHEMA` (JSON), ROS's field names."""
        ns = nanoseconds(reading.time)
        q = reading.orientation or _IDENTITY
        return {"timestamp": {"sec": ns // 1_000_000_000, "nsec": ns % 1_000_000_000},
                "frame_id": frame,
                "orientation": dict(zip("xyzw", q, strict=True)),
                "orientation_covariance": list(reading.orientation_covariance),
                "angular_velocity": dict(zip("xyz", reading.angular_velocity, strict=True)),
                "angular_velocity_covariance": list(reading.angular_velocity_covariance),
                "linear_acceleration": dict(zip("xyz", reading.linear_acceleration,
                                                strict=True)),
                "linear_acceleration_covariance": list(reading.linear_acceleration_covariance)}

    def ros2_message(self, messages, reading: Imu, frame: str):
        T = messages.T
        q = reading.orientation or _IDENTITY
        return T["sensor_msgs/msg/Imu"](
            header=messages.header(reading.time, frame),
            orientation=T["geometry_msgs/msg/Quaternion"](x=q[0], y=q[1], z=q[2], w=q[3]),
            orientation_covariance=np.array(reading.orientation_covariance),
            angular_velocity=messages.vector3(reading.angular_velocity),
            angular_velocity_covariance=np.array(reading.angular_velocity_covariance),
            linear_acceleration=messages.vector3(reading.linear_acceleration),
            linear_acceleration_covariance=np.array(reading.linear_acceleration_covariance))


IMU = ImuKind()
"""The kind's one instance (`sensors/registry.KINDS`)."""
