"""The IR distance sensors, measured through the simulation (SPEC, Sensors)."""

import math

import numpy as np
import pytest

from conftest import DEFAULT_SCENARIO, SAP, make_sim
from corobot_drake.config.scenario import CENIC_PLANT, ScenarioError, load_scenario, physics_step
from corobot_drake.config.sensors import default_ir_sensors
from corobot_drake.model.ir_models import SharpGP2D12
from corobot_drake.sensors.ir_sensor import SCAN_INDEX, counter_normal
from corobot_drake.study.metrics import METRICS, RobotRun
from lab.bench import NO_CAMERA

MM = 1e-3
RANGE = 30 * 0.0254
"""m: 30 in, the Corobot's IR sensors' range."""
BOX_FACE_X = -0.7366
"""The giant box's near face (world x) in the default scene."""
IR = default_ir_sensors()
"""The Corobot's IR sensors, as its robot file mounts them."""
REAR_X = IR["rear"].X_PB.translation[0]
FRONT_X = IR["front"].X_PB.translation[0]
MOUNT_Z = IR["front"].X_PB.translation[2]
HALF_CONE = math.radians(4.0)

# The camera takes no part here: without it a simulation builds and runs faster.
_NO_CAMERA = [NO_CAMERA]


def ir_sim(*overrides: str):
    return make_sim(*_NO_CAMERA, *overrides)


def sensor(sim, name: str):
    return sim.station.robots["corobot"].ir_sensors[name]


def port(sim, name: str, port_name: str) -> np.ndarray:
    return sim.station.diagram.GetOutputPort(f"corobot.{name}.{port_name}").Eval(sim.context)


def at_pose(x: float) -> str:
    return f"robots: {{corobot: {{pose: {{translation: [{x}, 0, 0]}}}}}}"


# --- the default scene ---------------------------------------------------------------------


def test_default_scene_at_t0_rear_sees_the_box_front_sees_nothing():
    sim = ir_sim()
    robot = sim.robot()
    rear, front = robot.ir("rear"), robot.ir("front")
    assert rear.raw == pytest.approx(0.62865, abs=1 * MM)
    assert rear.time == 0.0 and rear.range == pytest.approx(RANGE)
    assert rear.normalized == pytest.approx(rear.raw / RANGE)
    assert front.raw == pytest.approx(0.762, abs=1e-12)  # nothing, not even the ground
    assert front.normalized == pytest.approx(1.0)
    assert robot.ir_distances() == {"front": front.raw, "rear": rear.raw}
    assert sim.summary()["robots"]["corobot"]["ir"] == {"front": front.raw, "rear": rear.raw}
    # Read by name as a sensor of any kind, and as JSON (the summary's, the study metric's).
    assert robot.reading("rear") == rear and robot.reading("front", kind="ir") == front
    assert robot.sensor_json("rear") == {"raw": rear.raw, "range": rear.range,
                                         "normalized": rear.normalized, "time": 0.0}
    assert sim.summary()["robots"]["corobot"]["sensors"]["ir_sensors"]["rear"] == (
        robot.sensor_json("rear"))
    sensors = METRICS["sensors"](RobotRun(sim, robot, robot.pose(), robot.heading()))
    assert sensors["ir_sensors.rear.raw"] == rear.raw
    # The exported ports agree with the API; hit points lie on the box face or are nan.
    assert port(sim, "rear", "reading") == pytest.approx([rear.raw, RANGE, rear.normalized, 0.0])
    hits = port(sim, "rear", "hit_points").reshape(-1, 3)
    hit = ~np.isnan(hits[:, 0])
    assert hit.all() and hits[:, 0] == pytest.approx(BOX_FACE_X, abs=1e-9)
    assert np.isnan(port(sim, "front", "hit_points")).all()
    with pytest.raises(KeyError, match="no IR sensor 'side'"):
        robot.ir("side")


def test_rear_reads_maximum_range_after_driving_forward_0_3_m():
    sim = ir_sim()
    robot = sim.robot()
    robot.set_power(0.5, 0.5)
    while robot.pose().x < 0.3:
        sim.advance(0.01)
    robot.all_stop()
    sim.advance(0.5)
    assert robot.pose().x > 0.3
    assert robot.ir("rear").raw == RANGE
    assert robot.ir("rear").time >= sim.time - sensor(sim, "rear").period - 1e-9


def test_backing_toward_the_box_the_reading_falls_with_the_distance():
    sim = ir_sim(at_pose(0.1))
    robot = sim.robot()
    period = sensor(sim, "rear").period
    robot.set_power(-0.3, -0.3)
    step = physics_step(sim.scenario.plant_config, sim.scenario.simulator_config)
    readings, expected = [], []
    for k in range(1, 60):
        t_scan = k * period
        sim.advance_to(t_scan)
        pose = robot.pose()  # the chassis at the scan's time
        # SceneGraph's poses come from the plant's sampled output ports (Drake's default
        # use_sampled_output_ports), which can be one physics step apart from the plant
        # context's state: allow the travel of one step on top of the 1 mm.
        tolerance = 1 * MM + abs(robot.velocity().forward) * step
        sim.advance_to(t_scan + step)  # the scan is taken
        reading = robot.ir("rear")
        assert reading.time == pytest.approx(t_scan)
        # Geometry: the rear sensor looks along -x of the chassis at the box's +x face.
        sensor_x = pose.x + REAR_X * math.cos(pose.yaw)
        readings.append(reading.raw)
        expected.append(min(RANGE, (sensor_x - BOX_FACE_X) / math.cos(pose.yaw)))
        assert reading.raw == pytest.approx(expected[-1], abs=tolerance)
    readings = np.array(readings)
    moving = readings < readings[0] - 2 * MM
    assert moving.sum() > 40, "the robot backed up"
    assert (np.diff(readings[np.argmax(moving):]) < 0).all(), "falls at every scan"
    assert readings[-1] < 0.45


# --- what the cross of rays sees -----------------------------------------------------------


def _post(angle_deg: float, distance: float = 0.5, width: float = 0.02) -> str:
    """A fixed, narrow, tall post whose near face is `distance` ahead of the front sensor and
    whose centre is `angle_deg` off the sensor's axis (to the left)."""
    y = distance * math.tan(math.radians(angle_deg))
    depth = 0.05
    x = FRONT_X + distance + depth / 2
    return (f"world: {{bodies: {{post: {{shape: !Box {{size: [{depth}, {width}, 0.4]}}, "
            f"fixed: true, pose: {{translation: [{x}, {y}, 0.2]}}}}}}}}")


def test_an_obstacle_off_axis_inside_the_cone_is_seen_outside_is_not():
    distance = 0.5
    # 3.5 deg off axis, 2 cm wide: clear of the centre ray (it spans 2.1-4.1 cm), in the 4 deg
    # ray's path: that ray hits the post's face at distance / cos(4 deg).
    inside = ir_sim(_post(3.5, distance)).robot().ir("front").raw
    assert inside == pytest.approx(distance / math.cos(HALF_CONE), abs=1e-9)
    # 6 deg off axis: outside the 8 deg cone, no ray comes near it.
    outside = ir_sim(_post(6.0, distance)).robot().ir("front").raw
    assert outside == RANGE
    # On the mirror side the -4 deg ray sees it the same way.
    mirrored = ir_sim(_post(-3.5, distance)).robot().ir("front").raw
    assert mirrored == pytest.approx(inside, abs=1e-12)


def test_the_ground_is_out_of_range_at_the_default_mount_height():
    # The lowest ray (4 deg down) from 69.85 mm meets the ground 1.0014 m away: past 0.762 m.
    ground_hit = MOUNT_Z / math.sin(HALF_CONE)
    assert ground_hit > RANGE
    assert ir_sim().robot().ir("front").raw == RANGE
    # With a longer range the same sensor does see the ground there.
    far = ir_sim("robots: {corobot: {ir_sensors: {front: {maximum_range: 1.5}}}}")
    assert far.robot().ir("front").raw == pytest.approx(ground_hit, abs=1e-9)


def test_the_robot_never_sees_itself():
    # A sensor inside the chassis, looking up through the platform: nothing of the robot counts.
    sim = ir_sim("robots: {corobot: {ir_sensors: {up: {X_PB: {translation: [0, 0, 0.07], "
                 "rotation: !Rpy {deg: [0, -90, 0]}}}}}}")
    assert sim.robot().ir("up").raw == RANGE
    assert set(sim.robot().ir_distances()) == {"front", "rear", "up"}


def test_a_sensor_can_be_disabled():
    sim = ir_sim("robots: {corobot: {ir_sensors: {front: {enabled: false}}}}")
    assert set(sim.robot().ir_distances()) == {"rear"}


# --- configuration errors ------------------------------------------------------------------


def test_samples_below_two_is_a_clear_scenario_error():
    with pytest.raises(ScenarioError) as e:
        load_scenario(DEFAULT_SCENARIO,
                      overrides=["robots: {corobot: {ir_sensors: {front: {samples: 1}}}}"])
    message = str(e.value)
    assert "robots.corobot.ir_sensors.front.samples" in message
    assert "must be in [2, 64]" in message and "got 1" in message


@pytest.mark.parametrize("override, field, words", [
    ("{rear: {model: laser}}", "rear.model", "not one of ideal, sharp_gp2d12"),
    ("{rear: {scan_rate_hz: 0}}", "rear.scan_rate_hz", "must be in (0, 1000] Hz"),
    ("{rear: {maximum_range: -1}}", "rear.maximum_range", "must be in (0, 100] m"),
    ("{rear: {X_PB: {translation: [0, 0]}}}", "rear.X_PB.translation", "needs 3 numbers"),
    ("{rear: {X_PB: {translation: [.inf, 0, 0]}}}", "rear.X_PB.translation[0]",
     "[-10000, 10000] m; got inf"),
    ("{rear: {X_PB: {rotation: !Rpy {deg: [0, 0]}}}}", "rear.X_PB.rotation.deg",
     "needs 3 numbers"),
    ("{rear: {X_PB: {rotation: !Uniform {}}}}", "rear.X_PB", "fixed pose"),
    ("{rear: {X_PB: {base_frame: wheel}}}", "rear.X_PB.base_frame", "not a link"),
    ("{rear: {position: [0, 0, 0]}}", "rear.position", "unknown field"),
    ("{rear: {dispersion_cone_angle: 200}}", "rear.dispersion_cone_angle", "[0, 180)"),
    ("{rear: {samples: 2.5}}", "rear.samples", "expected an integer"),
    ("{a.b: {}}", "a.b", "a sensor name must be letters, digits, '_', '-' or '~'"),
    ("{'a?b': {}}", "a?b", "a sensor name must be letters, digits, '_', '-' or '~'"),
])
def test_bad_ir_configuration_names_the_field(override, field, words):
    with pytest.raises(ScenarioError) as e:
        load_scenario(DEFAULT_SCENARIO,
                      overrides=[f"robots: {{corobot: {{ir_sensors: {override}}}}}"])
    assert f"robots.corobot.ir_sensors.{field}" in str(e.value)
    assert words in str(e.value)


# --- timing --------------------------------------------------------------------------------


@pytest.mark.parametrize("plant", [(), (SAP,)], ids=["cenic", "sap"])
@pytest.mark.parametrize("rate", [20.0, 7.0])
def test_scans_happen_at_scan_rate_hz_not_every_step(rate, plant):
    sim = ir_sim(*plant, f"robots: {{corobot: {{ir_sensors: {{rear: {{scan_rate_hz: {rate}}}}}}}}}")
    step = physics_step(sim.scenario.plant_config, sim.scenario.simulator_config)
    times = set()
    for k in range(1, round(1.0 / step) + 1):
        sim.advance_to(k * step)
        times.add(float(port(sim, "rear", "scan_time")[0]))
    times = np.array(sorted(times))
    # Once at initialization (t = 0), then every 1/rate s: on the dot on a discrete plant, at
    # the first step at or after it on a continuous one (a scan between its steps would
    # split one). (Drake takes a discrete update due at t at the start of the step leaving t:
    # the scan due at 1.0 is not yet taken.)
    k = np.arange(len(times))
    due = k / rate
    expected = np.ceil(due / step - 1e-9) * step if sim.continuous else due
    assert times == pytest.approx(expected, abs=1e-9)
    assert len(times) == math.ceil(rate * 1.0 - 1e-9)
    rear = sensor(sim, "rear")
    state = rear.GetMyContextFromRoot(sim.context).get_discrete_state(0).value()
    assert state[SCAN_INDEX] == len(times) - 1


def test_changed_flags_a_new_reading():
    sim = ir_sim(at_pose(0.1))
    period = sensor(sim, "rear").period
    sim.advance(2 * period + 1e-3)
    assert port(sim, "rear", "changed")[0] == 0.0  # standing still: same reading
    sim.robot().set_power(-0.5, -0.5)
    sim.advance(0.5)
    assert port(sim, "rear", "changed")[0] == 1.0  # backing up: every scan is new


# --- the datasheet mode --------------------------------------------------------------------


def _sharp(*extra: str, x: float = 0.0, noise: float = 0.0):
    return ir_sim(at_pose(x), "robots: {corobot: {ir_sensors: {rear: {model: sharp_gp2d12, "
                  f"noise_std: {noise}, maximum_range: 0.9}}}}}}}}", *extra)


@pytest.mark.parametrize("distance", [0.06, 0.10, 0.15, 0.20, 0.30, 0.40, 0.50, 0.60, 0.70, 0.80])
def test_sharp_gp2d12_reproduces_its_curve_through_the_sensor(distance):
    # Place the robot so the rear sensor is `distance` from the box face.
    sim = _sharp(x=BOX_FACE_X + distance - REAR_X)
    model = SharpGP2D12(noise_std=0.0)
    true = port(sim, "rear", "true_distance")[0]
    assert true == pytest.approx(distance, abs=1e-9)
    voltage = port(sim, "rear", "voltage")[0]
    assert voltage == pytest.approx(float(model.quantise(model.voltage(distance))), abs=1e-12)
    assert port(sim, "rear", "adc_counts")[0] == int(model.counts(model.voltage(distance)))
    assert voltage == pytest.approx(float(model.voltage(distance)), abs=model.adc_step)
    raw = sim.robot().ir("rear").raw
    if distance >= 0.10:  # the usable range: the reading is the distance, to an ADC step
        assert raw == pytest.approx(distance, rel=0.02)
    else:  # the fold-back: the voltage reads as a farther distance (the GP2D12's ambiguity)
        assert 0.10 <= raw < 0.12
    assert raw == pytest.approx(float(model.distance_from_voltage(voltage)), abs=1e-12)


def test_sharp_gp2d12_noise_is_seeded_deterministic_and_of_the_stated_size():
    def voltages(*extra):
        sim = _sharp(*extra, x=0.0, noise=0.01)
        values = []
        for _ in range(60):
            sim.advance(sensor(sim, "rear").period)
            values.append(port(sim, "rear", "voltage")[0])
        return np.array(values)

    a, b = voltages(), voltages()
    assert (a == b).all(), "same scenario, same noise"
    c = voltages("robots: {corobot: {ir_sensors: {rear: {noise_seed: 7}}}}")
    assert not (a == c).all(), "another seed, other noise"
    clean = float(SharpGP2D12().voltage(0.62865))
    assert abs(a.mean() - clean) < 0.006
    assert 0.006 < a.std() < 0.015  # 10 mV noise, 4.9 mV ADC steps
    normals = np.array([counter_normal(12345, k) for k in range(20000)])
    assert abs(normals.mean()) < 0.03 and normals.std() == pytest.approx(1.0, abs=0.03)


# --- Meshcat -------------------------------------------------------------------------------


def test_meshcat_shows_rays_and_hit_points_under_a_toggleable_path():
    from pydrake.geometry import Meshcat

    from corobot_drake.simulation import Simulation

    meshcat = Meshcat()
    sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=_NO_CAMERA), meshcat)
    viz = sim.station.diagram.GetSubsystemByName("corobot.ir.rear.meshcat")
    assert viz.draws == 1  # at initialization
    for path in ("/ir/corobot/rear/rays", "/ir/corobot/rear/hits/0", "/ir/corobot/front/rays"):
        assert meshcat.HasPath(path), path
    sim.advance(0.5)
    assert 10 <= viz.draws <= 11  # one redraw per scan (20 Hz), not per step


def test_meshcat_draws_every_scan_right_after_it():
    """The visualizer skips its per-step check until a scan can be due, yet it has drawn
    each scan by the end of the step that took it (at any stepping of advance)."""
    from pydrake.geometry import Meshcat

    from corobot_drake.simulation import Simulation

    sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=_NO_CAMERA), Meshcat())
    viz = sim.station.diagram.GetSubsystemByName("corobot.ir.rear.meshcat")
    rear = sensor(sim, "rear")
    for step in [0.01] * 30 + [0.007] * 30 + [0.05] * 4:
        sim.advance(step)
        state = rear.GetOutputPort("scan_state").Eval(rear.GetMyContextFromRoot(sim.context))
        assert viz._last_index == state[SCAN_INDEX], sim.time
    assert viz.draws == int(state[SCAN_INDEX]) + 1


def test_under_cenic_the_ir_sensors_scan_on_the_steps_and_change_nothing_of_the_motion():
    """On a continuous plant a scan time a rounding error off a step's (3 x 0.05 s is
    0.15000000000000002, the step 0.15) would be a CENIC step of its own: the scans are taken
    on the plant's steps, so the run is the same with the sensors and without them, to the
    bit; each scan is at its step's time, every 50 ms. At 19.9 Hz (scan times between the
    steps) each is taken at the first step at or after its time."""
    cenic = CENIC_PLANT % 0.01
    drive = "robots: {corobot: {commands: [!SetPower {left: 0.8, right: 0.4}]}}"
    off = ("robots: {corobot: {ir_sensors: {front: {enabled: false}, "
           "rear: {enabled: false}}}}")
    runs = []
    for overrides in ((drive, cenic), (drive, cenic, off)):
        sim = make_sim(*overrides)
        sim.advance(1.0)
        runs.append((sim.simulator.get_num_steps_taken(), sim.robot().pose()))
    assert runs[0] == runs[1]
    sim = make_sim(drive, cenic)
    times = []
    for k in range(1, 21):
        sim.advance_to(k * 0.05 + 0.01)  # a step after each scan
        times.append(sim.robot().ir("front").time)
    assert times == [5 * k * 0.01 for k in range(1, 21)]  # the steps' own doubles
    slow = make_sim(cenic, "robots: {corobot: {ir_sensors: {front: {scan_rate_hz: 19.9}}}}")
    slow.advance_to(0.115)
    assert slow.robot().ir("front").time == pytest.approx(0.11)  # 2 / 19.9 = 0.1005 s
