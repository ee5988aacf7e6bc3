"""The IMU alone: an `ImuSensor` whose body's pose and velocity are fixed on its inputs before
each sample, against analytic values (at rest, tilted, spinning, accelerating), its noise's
statistics and replay; then the kind's parts (config bounds, add on a small plant, the wire
messages).

Samples come every 1 / rate s (a Stepper tick: the k-th at (k - 1) / rate, the first at
initialization)."""

import dataclasses as dc
import math

import numpy as np
import pytest
from pydrake.geometry import Box, ProximityProperties
from pydrake.math import RigidTransform, RollPitchYaw, RotationMatrix
from pydrake.multibody.math import SpatialVelocity
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
from pydrake.multibody.tree import SpatialInertia
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder

from conftest import Stepper
from corobot_drake.config.poses import mount
from corobot_drake.limits import bound_of
from corobot_drake.ros2.messages import Messages
from corobot_drake.sensors.follow import MOVE_PERIOD
from corobot_drake.sensors.imu import (
    FORCE_SCALE,
    IMU,
    Imu,
    ImuConfig,
    ImuSensor,
    sample_noise,
)
from corobot_drake.sensors.site import SensorSite

G = 9.81  # m/s^2: Drake's default gravity
GRAVITY_W = (0.0, 0.0, -G)
EXACT = 1e-12  # a few roundings of numbers of order 10
IDEAL = dict(gyro_noise_density=0.0, gyro_random_walk=0.0, accel_noise_density=0.0,
             accel_random_walk=0.0)


def ideal(**changes) -> ImuConfig:
    return ImuConfig(**{**IDEAL, **changes})


class Imus(Stepper):
    """An ImuSensor on body 0 alone, its inputs set by `move` before each tick."""

    def __init__(self, config: ImuConfig, X_BS: RigidTransform | None = None, key: int = 0):
        super().__init__(ImuSensor(config, 0, X_BS or RigidTransform(), GRAVITY_W, key),
                         1.0 / config.rate_hz)
        self.move(RigidTransform(), SpatialVelocity.Zero())

    def move(self, X_WB: RigidTransform, V_WB: SpatialVelocity) -> None:
        self.fix("body_poses", [X_WB])
        self.fix("body_spatial_velocities", [V_WB])

    def reading(self) -> Imu:
        return self.output("reading")


def test_level_at_rest_reads_gravity_up_and_no_rotation():
    imus = Imus(ideal())
    imus.tick(3)
    r = imus.reading()
    assert r.time == pytest.approx(imus.last_tick_time, abs=EXACT)
    np.testing.assert_allclose(r.angular_velocity, 0.0, atol=EXACT)
    np.testing.assert_allclose(r.linear_acceleration, (0.0, 0.0, G), atol=EXACT)
    assert r.orientation == (0.0, 0.0, 0.0, 1.0)
    assert r.orientation_covariance == (0.0,) * 9  # ground truth
    assert r.angular_velocity_covariance == r.linear_acceleration_covariance == (0.0,) * 9


@pytest.mark.parametrize(("body_rpy", "mount_rpy", "expected"), [
    # Nose down by 30 deg (Drake's positive pitch): up is behind and above: -g sin, g cos.
    ((0, 30, 0), (0, 0, 0), (-G * 0.5, 0.0, G * math.sqrt(3) / 2)),
    # Level body, sensor rolled 90 deg about x: its +y is the world's up.
    ((0, 0, 0), (90, 0, 0), (0.0, G, 0.0)),
    # Yawed body, sensor yawed back: level, x and y turned, z up.
    ((0, 0, 40), (0, 0, -40), (0.0, 0.0, G)),
])
def test_a_tilted_body_or_a_rotated_mount_reads_gravity_in_the_sensor_frame(
        body_rpy, mount_rpy, expected):
    X_BS = mount((0.1, 0.02, 0.05), mount_rpy).GetDeterministicValue()
    X_WB = RigidTransform(RollPitchYaw(np.radians(body_rpy)), [1.0, 2.0, 0.3])
    imus = Imus(ideal(), X_BS)
    imus.move(X_WB, SpatialVelocity.Zero())
    imus.tick(2)
    r = imus.reading()
    np.testing.assert_allclose(r.linear_acceleration, expected, atol=EXACT)
    np.testing.assert_allclose(r.angular_velocity, 0.0, atol=EXACT)
    q = (X_WB.rotation() @ X_BS.rotation()).ToQuaternion()
    np.testing.assert_allclose(r.orientation, (q.x(), q.y(), q.z(), q.w()), atol=EXACT)


def test_a_spinning_body_reads_its_yaw_rate_and_the_centripetal_acceleration_at_an_offset():
    """The body turns about the world's z at w, its origin fixed; the sensor, r ahead of the
    origin, circles at speed w r. Its acceleration over a sample period dt (angle phi = w dt)
    is the chord of its velocity: in S at the sample, (-w r sin(phi), w r (1 - cos(phi))) /
    dt, i.e. -w^2 r (centripetal) to within phi^2 / 6 and a half-period lag."""
    w, r = 2.0, 0.3  # rad/s, m
    config = ideal()
    imus = Imus(config, RigidTransform([r, 0.0, 0.0]))
    V = SpatialVelocity([0.0, 0.0, w], [0.0, 0.0, 0.0])
    for k in range(5):  # sample k at k dt: the body yawed by w k dt
        imus.move(RigidTransform(RotationMatrix.MakeZRotation(w * k * imus.period)), V)
        imus.tick()
    reading = imus.reading()
    dt = imus.period
    phi = w * dt
    expected = (-w * r * math.sin(phi) / dt, w * r * (1 - math.cos(phi)) / dt, G)
    np.testing.assert_allclose(reading.linear_acceleration, expected, atol=1e-12)
    assert reading.linear_acceleration[0] == pytest.approx(-w * w * r, rel=phi**2 / 6 + 1e-12)
    np.testing.assert_allclose(reading.angular_velocity, (0.0, 0.0, w), atol=EXACT)
    yaw = RollPitchYaw(RotationMatrix(
        _quaternion(reading.orientation))).yaw_angle()
    assert yaw == pytest.approx(w * 4 * dt, abs=EXACT)


def _quaternion(xyzw):
    from pydrake.common.eigen_geometry import Quaternion

    x, y, z, w = xyzw
    return Quaternion(w, x, y, z)


def test_a_steady_acceleration_reads_as_the_forward_specific_force():
    """v = a t along the body's x (level, no rotation): the accelerometer reads (a, 0, g)
    from the second sample on (the first has no previous velocity: a = 0)."""
    a = 1.5  # m/s^2
    imus = Imus(ideal(rate_hz=50.0))
    for k in range(4):
        imus.move(RigidTransform(), SpatialVelocity([0, 0, 0], [a * k * imus.period, 0, 0]))
        imus.tick()
        expected = (a if k else 0.0, 0.0, G)
        np.testing.assert_allclose(imus.reading().linear_acceleration, expected, atol=1e-12)



def test_on_a_continuous_plant_it_samples_on_the_plant_steps():
    """With `step` (CENIC's 10 ms), a 30 Hz IMU samples at the first step at or after each
    k / 30 s (0.04, 0.07, 0.1, 0.14 s), and divides by the time between its samples: v = a t
    reads a."""
    a, step = 2.0, 0.01
    system = ImuSensor(ideal(rate_hz=30.0), 0, RigidTransform(), GRAVITY_W, step=step)
    simulator = Simulator(system)
    context = simulator.get_mutable_context()
    system.GetInputPort("body_poses").FixValue(context, [RigidTransform()])
    times = []
    for t in (0.04, 0.07, 0.1, 0.14):
        velocity = SpatialVelocity([0, 0, 0], [a * t, 0, 0])
        system.GetInputPort("body_spatial_velocities").FixValue(context, [velocity])
        simulator.AdvanceTo(t + step / 2)
        reading = system.GetOutputPort("reading").Eval(context)
        times.append(reading.time)
        # At 0.04 s: no change since the sample at initialization (it saw that v already).
        expected = (a, 0.0, G) if len(times) > 1 else (0.0, 0.0, G)
        np.testing.assert_allclose(reading.linear_acceleration, expected, atol=1e-9)
    np.testing.assert_allclose(times, (0.04, 0.07, 0.1, 0.14), atol=1e-12)

# --- noise ---------------------------------------------------------------------------------

SIGMAS = 4.0
"""A statistic is allowed this many of its standard errors off (a false failure one run in
~16000 per check)."""


def test_white_noise_has_the_stated_density():
    """At rest with no bias walk, reading - truth is the white noise: per axis std = density
    x sqrt(rate). N samples of 3 axes: the sample std's relative standard error is
    1 / sqrt(2 (3N - 1)); the mean's is std / sqrt(3N); neighbouring samples are
    uncorrelated (lag-1 correlation within 1 / sqrt(3N) per standard error)."""
    config = ImuConfig(rate_hz=1000.0, gyro_random_walk=0.0, accel_random_walk=0.0,
                       gyro_noise_density=2e-3, accel_noise_density=3e-2)
    imus = Imus(config, key=12345)
    gyro, accel = [], []
    n = 1500
    for _ in range(n):
        imus.tick()
        gyro.append(imus.reading().angular_velocity)
        accel.append(np.subtract(imus.reading().linear_acceleration, (0, 0, G)))
    for samples, density in ((gyro, config.gyro_noise_density),
                             (accel, config.accel_noise_density)):
        x = np.asarray(samples)
        sigma = density * math.sqrt(config.rate_hz)
        count = x.size
        assert x.std() == pytest.approx(sigma, rel=SIGMAS / math.sqrt(2 * (count - 1)))
        assert abs(x.mean()) < SIGMAS * sigma / math.sqrt(count)
        lag1 = np.mean([np.corrcoef(x[1:, i], x[:-1, i])[0, 1] for i in range(3)])
        assert abs(lag1) < SIGMAS / math.sqrt(count)
    assert imus.reading().angular_velocity_covariance[0] == pytest.approx(
        config.gyro_noise_density**2 * config.rate_hz)


def test_the_bias_walk_grows_as_the_square_root_of_time():
    """With no white noise the biases alone move the readings: over M runs (noise keys) x 3
    axes, the std of the gyro's bias at t is walk x sqrt(t) (relative standard error
    1 / sqrt(2 x 3M)); and at 4 t it is twice that at t (the sqrt(t) growth): the ratio's
    relative standard error, over 6 axes, is at most sqrt(2) / sqrt(2 x 6M) (that of two
    independent estimates; the walks at t and 4 t share their start, which lowers it)."""
    config = ImuConfig(rate_hz=100.0, gyro_noise_density=0.0, accel_noise_density=0.0,
                       gyro_random_walk=1e-3, accel_random_walk=2e-2)
    runs, quarter = 150, 10
    at = {quarter: [], 4 * quarter: []}
    for key in range(runs):
        imus = Imus(config, key=key)
        for samples in (quarter + 1, 3 * quarter):
            imus.tick(samples)
            at[imus.ticks - 1].append(imus.output("bias"))  # tick k: sample k - 1
    for k, biases in at.items():
        b = np.asarray(biases)
        t = k / config.rate_hz  # sample k: k increments of the walk
        tolerance = SIGMAS / math.sqrt(2 * 3 * runs)
        assert b[:, :3].std() == pytest.approx(config.gyro_random_walk * math.sqrt(t),
                                               rel=tolerance)
        assert b[:, 3:].std() == pytest.approx(config.accel_random_walk * math.sqrt(t),
                                               rel=tolerance)
    ratio = np.asarray(at[4 * quarter]).std(axis=0) / np.asarray(at[quarter]).std(axis=0)
    assert ratio.mean() == pytest.approx(2.0, rel=SIGMAS * math.sqrt(2 / (2 * 6 * runs)))



def test_ticks_faster_than_the_steps_walk_the_bias_for_every_tick():
    """A 1000 Hz IMU on 10 ms plant steps samples once a step, covering 10 ticks: its bias
    moves by walk x sqrt(10 / 1000) per sample (300 samples x 6 axes: relative standard
    error of the std 1 / sqrt(2 x 1800)), so it still walks as walk x sqrt(t)."""
    config = ImuConfig(rate_hz=1000.0, gyro_noise_density=0.0, accel_noise_density=0.0,
                       gyro_random_walk=1e-3, accel_random_walk=1e-3)
    step, samples = 0.01, 300
    system = ImuSensor(config, 0, RigidTransform(), GRAVITY_W, key=5, step=step)
    simulator = Simulator(system)
    context = simulator.get_mutable_context()
    system.GetInputPort("body_poses").FixValue(context, [RigidTransform()])
    system.GetInputPort("body_spatial_velocities").FixValue(context, [SpatialVelocity.Zero()])
    biases, times = [], []
    for k in range(1, samples + 1):
        simulator.AdvanceTo((k + 0.5) * step)
        biases.append(system.GetOutputPort("bias").Eval(context).copy())
        times.append(system.GetOutputPort("sample_time").Eval(context)[0])
    np.testing.assert_allclose(times, np.arange(1, samples + 1) * step, atol=1e-9)
    increments = np.diff(np.asarray(biases), axis=0)
    expected = config.gyro_random_walk * math.sqrt(step)  # 10 ticks of 1 ms
    count = increments.size
    assert increments.std() == pytest.approx(expected, rel=SIGMAS / math.sqrt(2 * count))

def test_noise_is_a_pure_function_of_key_and_sample():
    np.testing.assert_array_equal(sample_noise(7, 3), sample_noise(7, 3))
    np.testing.assert_array_equal(  # Philox keyed by 7, sample 3 in the counter's 2nd word
        sample_noise(7, 3),
        np.random.Generator(np.random.Philox(key=7, counter=3 << 64)).standard_normal(12))
    scratch = np.random.Philox()
    sample_noise(8, 5, scratch)
    np.testing.assert_array_equal(sample_noise(7, 3, scratch), sample_noise(7, 3))
    assert not np.array_equal(sample_noise(7, 3), sample_noise(8, 3))
    # Each sample has its own counter block: no draw of sample 3 is one of sample 4's.
    assert not np.isin(sample_noise(7, 3), sample_noise(7, 4)).any()


def run(imus: Imus, samples: int) -> list[Imu]:
    readings = []
    for _ in range(samples):
        imus.tick()
        readings.append(imus.reading())
    return readings


def test_a_reset_context_replays_the_same_readings_bit_for_bit():
    imus = Imus(ImuConfig(), key=99)
    first = run(imus, 20)
    imus.system.SetDefaultContext(imus.context)
    imus.context.SetTime(0.0)
    imus.simulator.Initialize()  # the first sample again
    imus.ticks = 0
    assert run(imus, 20) == first
    other = Imus(ImuConfig(), key=99)
    other.system.SetNoiseKey(other.context, 100)
    assert run(other, 20) != first


# --- the kind ------------------------------------------------------------------------------


@pytest.mark.parametrize(("field", "value"), [
    ("rate_hz", 0.0), ("rate_hz", 1e6), ("gyro_noise_density", math.nan),
    ("gyro_noise_density", -1e-4), ("accel_noise_density", -1.0),
    ("gyro_random_walk", math.nan), ("accel_random_walk", -1e-3)])
def test_the_config_refuses_a_bad_rate_or_noise(field, value):
    bound = bound_of(next(f for f in dc.fields(ImuConfig) if f.name == field))
    assert bound.problem(value) is not None
    assert bound.problem(getattr(ImuConfig(), field)) is None


def welded_chassis_site() -> SensorSite:
    """A robot `bot` that is one 0.2 m box `chassis` welded at the world origin."""
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=0.01)
    bot = plant.AddModelInstance("bot")
    chassis = plant.AddRigidBody("chassis", bot, SpatialInertia.SolidBoxWithMass(
        1.0, 0.2, 0.2, 0.2))
    plant.WeldFrames(plant.world_frame(), chassis.body_frame())
    plant.RegisterCollisionGeometry(chassis, RigidTransform(), Box(0.2, 0.2, 0.2), "chassis",
                                    ProximityProperties())
    plant.Finalize()
    return SensorSite(builder, plant, scene_graph, "bot", bot)


def test_the_kind_adds_an_imu_on_a_link_of_the_robot():
    site = welded_chassis_site()
    config = ideal(X_PB=mount((0.1, 0.0, 0.05), (90, 0, 0)))
    sensor = IMU.add(site, "imu", config)
    assert IMU.add(site, "off", ideal(enabled=False)) is None
    diagram = site.builder.Build()
    simulator = Simulator(diagram)
    simulator.AdvanceTo(0.025)
    context = simulator.get_context()
    r = sensor.read(context)
    assert isinstance(r, IMU.reading_type)
    assert r.time == pytest.approx(0.02, abs=EXACT) and sensor.rate == 100.0
    np.testing.assert_allclose(r.linear_acceleration, (0.0, G, 0.0), atol=EXACT)
    np.testing.assert_array_equal(
        diagram.GetOutputPort("bot.imu.imu.linear_acceleration").Eval(context),
        r.linear_acceleration)
    assert sensor.system is diagram.GetSubsystemByName("bot.imu.imu")
    assert (IMU.topic_name("imu"), IMU.frame_name("imu")) == ("imu/imu", "imu_imu")


def test_the_messages_carry_the_reading_in_ros_field_names():
    imus = Imus(ImuConfig(orientation=False, rate_hz=200.0), key=1)
    imus.tick(2)
    r = imus.reading()
    assert r.orientation is None and r.orientation_covariance[0] == -1.0
    msg = IMU.ros2_message(Messages(), r, "imu_imu")
    assert msg.__msgtype__ == IMU.ros2_type
    assert (msg.header.frame_id, msg.header.stamp.nanosec) == ("imu_imu", 5_000_000)
    assert msg.orientation_covariance[0] == -1.0
    assert (msg.linear_acceleration.x, msg.linear_acceleration.z) == (
        r.linear_acceleration[0], r.linear_acceleration[2])
    np.testing.assert_array_equal(msg.angular_velocity_covariance,
                                  r.angular_velocity_covariance)
    as_json = IMU.to_json(r)
    assert as_json["orientation"] is None
    assert as_json["linear_acceleration"] == list(r.linear_acceleration)
    summary = IMU.summary_json(r)  # a number each: a study's sensors metric columns
    assert summary == {"angular_velocity_x": r.angular_velocity[0],
                       "angular_velocity_y": r.angular_velocity[1],
                       "angular_velocity_z": r.angular_velocity[2],
                       "linear_acceleration_x": r.linear_acceleration[0],
                       "linear_acceleration_y": r.linear_acceleration[1],
                       "linear_acceleration_z": r.linear_acceleration[2], "time": 0.005}
    fox = IMU.foxglove_message(r, "imu_imu")
    assert set(fox) == set(IMU.foxglove_schema["properties"])
    assert fox["angular_velocity"]["z"] == r.angular_velocity[2]
    assert fox["timestamp"] == {"sec": 0, "nsec": 5_000_000}


class LineRecorder:
    """Meshcat's SetLineSegments recorded: {path: (start, end)} of the last call (m, world)."""

    def __init__(self):
        self.lines = {}

    def SetLineSegments(self, path, starts, ends, width, color):
        self.lines[path] = (starts[:, 0].copy(), ends[:, 0].copy())


def test_meshcat_draws_the_specific_force_and_rate_from_the_sensor_in_the_world():
    """An IMU rolled 90 deg on a welded chassis, 0.1 m ahead and 0.05 m up: its specific force
    (gravity's reaction, 9.81 m/s^2 up in the world, +y in its own frame) is drawn from its
    origin straight up, `FORCE_SCALE` m per m/s^2; no rotation: a zero-length rate line. It
    redraws at most every `MOVE_PERIOD` s, not at the IMU's 100 Hz."""
    site = welded_chassis_site()
    sensor = IMU.add(site, "imu", ideal(X_PB=mount((0.1, 0.0, 0.05), (90, 0, 0))))
    meshcat = LineRecorder()
    IMU.add_meshcat(site.builder, meshcat, sensor)
    diagram = site.builder.Build()
    simulator = Simulator(diagram)
    simulator.AdvanceTo(0.5)
    start, end = meshcat.lines["/imu/bot/imu/specific_force"]
    np.testing.assert_allclose(start, (0.1, 0.0, 0.05), atol=EXACT)
    np.testing.assert_allclose(end - start, (0.0, 0.0, FORCE_SCALE * G), atol=1e-9)
    start, end = meshcat.lines["/imu/bot/imu/angular_velocity"]
    np.testing.assert_array_equal(start, end)
    viz = diagram.GetSubsystemByName("bot.imu.imu.meshcat")
    assert viz.draws == pytest.approx(0.5 / MOVE_PERIOD, abs=2)  # 51 samples; 13-16 drawn
