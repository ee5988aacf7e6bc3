"""`GoToGoalEnv`: drive a robot (the Corobot, or any: `GoToGoalConfig.robot`) from a start
pose to a goal point among boxes (Gymnasium).

A thin env over `Simulation`: the diagram is built once, in the constructor, and every
`reset` puts the episode's layout (`layout.draw_layout`) into the same diagram with
`Simulation.reset` (start pose, box poses, seed). The boxes are free bodies, so their poses
are per-run values of the scenario; they are held still by Drake's `RigidBody.Lock` (a
locked body keeps its pose whatever pushes it: the robot cannot move them), locked again after
every reset since the lock lives in the Context. They float 1 mm above the ground, so they
cost the plant nothing until the robot touches them (a box resting on the ground would be a
hydroelastic contact to compute at every step).

A step is one control period (`GoToGoalConfig.control_period`, 0.1 s): the action's powers
are issued as `SetPower(left, right)` and the simulation advances. See docs/gym.md for the
spaces and the reward.
"""

from __future__ import annotations

import dataclasses as dc
import math
from typing import ClassVar

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from corobot_drake.config import scenario as sc
from corobot_drake.config.poses import ground_pose
from corobot_drake.config.sensors import FRONT_CAMERA
from corobot_drake.gym.checks import check_action, check_options, make_config, robot_path
from corobot_drake.gym.layout import Layout, draw_layout, giant_box
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.robots import robot_defaults, robot_spec
from corobot_drake.sensors.ir_sensor import scan_state_layout
from corobot_drake.simulation import Simulation, diagram_key, quiet_drake_warnings

ROBOT = "corobot"
BOX_MASS = 10.0
"""kg of each of the task's boxes (locked: the mass only shows in a contact's impulse)."""
HOVER = 0.001
"""m between a held box and the ground."""
MAX_GOAL_DISTANCE = 10.0
"""m: the observation's goal distance is clipped here (the goal is 1-1.8 m away at start)."""
MAX_SPEED = 1.0
"""m/s: forward speed is clipped to +-this in the observation (top speed 0.61 m/s)."""
MAX_YAW_RATE = 6.0
"""rad/s: yaw rate clipped to +-this (a spin at full power turns ~3.3 rad/s)."""


@dc.dataclass
class GoToGoalConfig:
    """The task: its timing, its layouts and its reward (units in each field's docstring)."""

    control_period: float = 0.1
    """s of simulation per step."""
    time_limit: float = 6.0
    """s: the episode is truncated here (60 steps)."""
    goal_radius: float = 0.2
    """m: the episode ends in success when the chassis origin is this close to the goal."""
    goal_distance: tuple[float, float] = (1.0, 1.8)
    """m: the goal's distance from the start, drawn uniformly."""
    start_spread: float = 0.2
    """m: the start's x and y are drawn in +-this around the origin; its yaw anywhere."""
    boxes: int = 3
    """Boxes besides the giant box (a fixed number of bodies: the diagram never changes)."""
    box_size: float = 0.3
    """m: edge of each (cubic) box."""
    blocking_probability: float = 0.3
    """Chance that the first box stands on the way to the goal."""
    blocking_offset: float = 0.2
    """m: how far to the side of the straight line a box on the way may stand."""
    box_area: float = 2.0
    """m: the other boxes stand in +-this around the start."""
    start_clearance: float = 0.3
    """m: free space around the start (beyond a box's half diagonal)."""
    goal_clearance: float = 0.3
    """m: free space around the goal, and between boxes and the giant box."""
    flip_tilt_deg: float = 60.0
    """Tilt from upright at which the robot counts as flipped (the episode ends)."""
    progress_reward: float = 10.0
    """Per metre of progress toward the goal (negative when moving away)."""
    time_cost: float = 0.05
    """Per step."""
    collision_penalty: float = 0.5
    """Per step ending with the robot touching a box or the giant box."""
    stall_penalty: float = 0.5
    """Per step ending stalled: wheels commanded to move, the chassis hardly moving."""
    success_reward: float = 10.0
    flip_penalty: float = 10.0
    camera: bool = False
    """Add the front camera's 240 x 320 RGB image to the observation (a Dict); a robot
    with a `front` camera only."""
    robot: str = "corobot"
    """The robot that drives: a shipped one (`robots.ROBOTS`: corobot, burger, pioneer) or a
    robot file's path. Its IR sensors' rays are the observation's (the Corobot's front then
    rear; none for a robot without IR sensors)."""


RENDER_MODES = ("rgb_array", "human")
FRAME_SIZE = (480, 640)
"""Height, width of an `rgb_array` frame (pixels)."""
FRAME_FOV_Y_DEG = 45.0
GOAL_COLOR = (220, 30, 30)


IR_SENSORS = ("front", "rear")
"""The sensors whose rays the observation holds, in this order."""


def robot_name(config: GoToGoalConfig) -> str:
    """The robot's name in the env's scenario: `corobot`, or its robot file's kind."""
    return ROBOT if config.robot == ROBOT else robot_spec(robot_path(config.robot)).kind


def base_scenario(config: GoToGoalConfig) -> sc.Scenario:
    """The default scene with the task's boxes, held (see the module docstring), and the
    config's robot in place of the Corobot (as its robot file has it); the camera only with
    `config.camera` (then one frame per step, rendered synchronously)."""
    scenario = sc.load_scenario(DEFAULT_SCENARIO)
    if config.robot != ROBOT:
        scenario.robots = {robot_name(config): robot_defaults(robot_path(config.robot))}
    robot = scenario.robots[robot_name(config)]
    camera = robot.cameras.get(FRONT_CAMERA)
    if camera is not None:
        camera.rgb = config.camera
    if config.camera:
        camera.fps = 1.0 / config.control_period
        camera.output_delay = 0.0
    giant = scenario.world.bodies["giant_box"]
    centre, _ = giant_box()
    giant.pose = ground_pose(*centre[:2])
    giant.pose.translation = [*centre[:2], centre[2] + HOVER]
    for i in range(config.boxes):
        # Parked in a row away from the robot until `reset` places them (a scenario the
        # Simulation checks: no body inside the robot).
        parked = ground_pose(PARKING[0] + i * (config.box_size + 0.5), PARKING[1], 0.0)
        parked.translation = [*parked.translation[:2], config.box_size / 2 + HOVER]
        scenario.world.bodies[f"box_{i}"] = sc.WorldBody(
            shape=sc.Box([config.box_size] * 3), mass=BOX_MASS, color=[0.3, 0.45, 0.7, 1.0],
            pose=parked)
    return scenario


PARKING = (3.0, 6.0)
"""m: where the first box waits, the others in a row along +x, until `reset` places them."""


class GoToGoalEnv(gym.Env):
    """Drive to a goal among boxes. Observation (float32, `observation_names()`): each IR
    ray's distance (m; front then rear), the goal's distance (m) and bearing (rad, in the
    robot's frame, positive to the left), forward speed (m/s), yaw rate (rad/s). Action:
    left and right power in [-1, 1]."""

    metadata: ClassVar[dict] = {"render_modes": list(RENDER_MODES),
                                "render_fps": round(1.0 / GoToGoalConfig.control_period)}
    """Gymnasium's: the render modes (`render_mode`: `rgb_array`, `human`) and the frames per
    second of a rendered episode (one a default control period)."""

    def __init__(self, config: GoToGoalConfig | None = None, render_mode: str | None = None,
                 **overrides):
        """`overrides` replace fields of `config` (default `GoToGoalConfig()`), e.g.
        `camera=True`, as `gymnasium.make("corobot_drake/GoToGoal-v0", camera=True)`.
        `render_mode`: None, `rgb_array` (`render()` returns a picture of the scene) or
        `human` (the scene live in Meshcat, at real time)."""
        quiet_drake_warnings()
        self.config = make_config(config or GoToGoalConfig(), overrides)  # ValueError
        self.render_mode = checked_render_mode(render_mode)
        self.scenario = base_scenario(self.config)
        self.sim = Simulation(self.scenario, meshcat=_meshcat(self.render_mode))
        self._key = diagram_key(self.scenario)
        self._name = robot_name(self.config)
        self.robot = self.sim.robot(self._name)
        self._ports = _Ports(self.sim, self.scenario, self._name)
        self._lock_boxes()
        n_rays = self._ports.num_rays
        rng = self._ports.ray_range
        low = np.array([0.0] * n_rays + [0.0, -math.pi, -MAX_SPEED, -MAX_YAW_RATE], np.float32)
        high = np.array([rng] * n_rays + [MAX_GOAL_DISTANCE, math.pi, MAX_SPEED, MAX_YAW_RATE],
                        np.float32)
        state = spaces.Box(low, high, dtype=np.float32)
        if self.config.camera:
            camera = self.scenario.robots[self._name].cameras[FRONT_CAMERA]
            image = spaces.Box(0, 255, (camera.height, camera.width, 3), np.uint8)
            self.observation_space = spaces.Dict({"state": state, "image": image})
        else:
            self.observation_space = state
        self.action_space = spaces.Box(-1.0, 1.0, (2,), np.float32)
        self.layout: Layout | None = None
        self._distance = 0.0

    def observation_names(self) -> list[str]:
        """Names of the state observation's entries, in order."""
        return [*self._ports.ray_names, "goal_distance", "goal_bearing", "forward_speed",
                "yaw_rate"]

    # --- episodes -------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """A new episode: its layout drawn from the seed, or `options={"layout": Layout}`
        (ValueError for other options or a layout not of this env's shape)."""
        self._check_open()
        layout = check_options(options, self.config)
        super().reset(seed=seed)
        self.layout = layout or draw_layout(self.np_random, self.config)
        self._apply_layout(self.layout)
        # Checked (a small share of an episode): a layout may come from the caller's `options`.
        try:
            self.sim.reset(self.scenario, key=self._key)
        except sc.ScenarioError as e:  # a start or box inside another body
            self.layout = None  # no episode: step() asks for a reset
            raise ValueError(f"reset: the layout: {str(e).partition(': ')[2]}") from None
        self._lock_boxes()
        self._distance = self._goal_in_robot_frame()[0]
        _show_goal(self.sim, self.layout, self.config)
        return self._observation(), self._info(collided=False, stalled=False)

    def render(self):
        """`rgb_array`: the scene now, from above and behind the episode's start and goal (an
        H x W x 3 uint8 picture, the goal a red disc); `human`: None (Meshcat shows the run
        as it goes); no render mode: None."""
        if self.render_mode != "rgb_array" or self.layout is None:
            return None
        return render_frame(self.sim, self.layout, self.config)

    def _apply_layout(self, layout: Layout) -> None:
        x, y, yaw = layout.start
        self.scenario.robots[self._name].pose = ground_pose(x, y, math.degrees(yaw))
        # the episode's seed: the IR noise of a sharp_gp2d12 model draws from it
        self.scenario.random_seed = int(self.np_random.integers(2**31))
        half = self.config.box_size / 2 + HOVER
        for i, (bx, by, byaw) in enumerate(layout.boxes):
            pose = ground_pose(bx, by, math.degrees(byaw))
            pose.translation = [bx, by, half]
            self.scenario.world.bodies[f"box_{i}"].pose = pose

    def _lock_boxes(self) -> None:
        """Locks every world body in place (`Simulation.reset` restores the default Context,
        which unlocks them)."""
        plant = self.sim.station.plant
        plant_context = plant.GetMyMutableContextFromRoot(self.sim.context)
        for body in self.sim.station.bodies.values():
            body.Lock(plant_context)

    def step(self, action):
        """One control period (`control_period` s of simulated time) at `action`'s left and
        right power: (observation, reward, terminated: the goal reached or the robot flipped,
        truncated: `time_limit` reached, info)."""
        self._check_open()
        if self.layout is None:
            raise gym.error.ResetNeeded("call reset() before step()")
        left, right = check_action(action, self.action_space)  # ValueError
        self.robot.set_power(left, right)
        self.sim.advance(self.config.control_period)
        c = self.config
        distance, _ = self._goal_in_robot_frame()
        collided = self._ports.touching_boxes(self.sim.context)
        stalled = self._stalled()
        reward = c.progress_reward * (self._distance - distance) - c.time_cost
        reward -= c.collision_penalty * collided + c.stall_penalty * stalled
        self._distance = distance
        success = distance < c.goal_radius
        flipped = self._tilt_deg() > c.flip_tilt_deg
        if success:
            reward += c.success_reward
        if flipped:
            reward -= c.flip_penalty
        truncated = not (success or flipped) and self.sim.time >= (
            c.time_limit - 1e-9 + self.scenario.simulator_config.start_time)
        info = self._info(collided, stalled, success=success, flipped=flipped)
        return self._observation(), float(reward), bool(success or flipped), truncated, info

    def close(self) -> None:
        """Releases the simulation; `reset` and `step` then fail (idempotent)."""
        self.sim = self.robot = None

    def _check_open(self) -> None:
        if self.sim is None:
            raise gym.error.ClosedEnvironmentError("this env is closed: make a new one")

    # --- measurements ---------------------------------------------------------------------
    def _goal_in_robot_frame(self) -> tuple[float, float]:
        """(distance m, bearing rad) of the goal from the chassis origin, bearing positive to
        the robot's left."""
        pose = self.robot.pose()
        dx, dy = self.layout.goal[0] - pose.x, self.layout.goal[1] - pose.y
        bearing = math.atan2(dy, dx) - pose.yaw
        return math.hypot(dx, dy), math.atan2(math.sin(bearing), math.cos(bearing))

    def _observation(self):
        distance, bearing = self._goal_in_robot_frame()
        v = self.robot.velocity()
        state = np.concatenate([
            self._ports.ray_distances(self.sim.context),
            [min(distance, MAX_GOAL_DISTANCE), bearing,
             np.clip(v.forward, -MAX_SPEED, MAX_SPEED),
             np.clip(v.yaw_rate, -MAX_YAW_RATE, MAX_YAW_RATE)]]).astype(np.float32)
        if not self.config.camera:
            return state
        image = self.robot.camera_image()
        rgb = (np.zeros(self.observation_space["image"].shape, np.uint8) if image is None
               else np.ascontiguousarray(image[:, :, :3]))
        return {"state": state, "image": rgb}

    def _stalled(self) -> bool:
        """The drive commands at least 0.15 m/s of rim speed on average but the chassis moves
        (forward, or turning at the wheels' track) at under a fifth of it."""
        commanded = self._ports.commanded_rim_speed(self.sim.context)
        if commanded < 0.15:
            return False
        v = self.robot.velocity()
        return abs(v.forward) + abs(v.yaw_rate) * self.robot.spec.half_track < 0.2 * commanded

    def _tilt_deg(self) -> float:
        pose = self.robot.pose()
        return math.degrees(math.acos(max(-1.0, min(1.0, math.cos(pose.roll) *
                                                     math.cos(pose.pitch)))))

    def _info(self, collided: bool, stalled: bool, success: bool = False,
              flipped: bool = False) -> dict:
        return {"is_success": bool(success), "flipped": bool(flipped),
                "collided": bool(collided), "stalled": bool(stalled),
                "goal_distance": float(self._distance), "time": float(self.sim.time)}


# --- rendering and the config's checks ---------------------------------------------------

def checked_render_mode(render_mode) -> str | None:
    if render_mode is not None and render_mode not in RENDER_MODES:
        raise ValueError(f"render_mode must be None or one of {', '.join(RENDER_MODES)}, got "
                         f"{render_mode!r:.80}")
    return render_mode


def _meshcat(render_mode: str | None):
    """A Meshcat (on this machine's loopback; its URL in the log) for `human`, else None."""
    if render_mode != "human":
        return None
    from pydrake.geometry import StartMeshcat

    return StartMeshcat()


def _show_goal(sim: Simulation, layout: Layout, config: GoToGoalConfig) -> None:
    """In `human` mode: the goal as a red disc of the goal radius in Meshcat, and the run
    paced at real time (as Gymnasium's `human` mode is)."""
    meshcat = sim.station.meshcat
    if meshcat is None:
        return
    from pydrake.geometry import Cylinder, Rgba
    from pydrake.math import RigidTransform

    meshcat.SetObject("goal", Cylinder(config.goal_radius, 0.005),
                      Rgba(*(c / 255 for c in GOAL_COLOR), 0.6))
    meshcat.SetTransform("goal", RigidTransform([*layout.goal, 0.003]))
    sim.simulator.set_target_realtime_rate(1.0)


def frame_view(layout: Layout):
    """The camera of `rgb_array` frames (Drake camera pose): high above the middle of the
    start and the goal, looking down at it from the side away from the giant box (which
    would hide the way from its side), framing both and the boxes near the way."""
    from corobot_drake.sensors import render

    middle = (np.array(layout.start[:2]) + np.array(layout.goal)) / 2
    away = middle - np.array(giant_box()[0][:2])
    away /= max(np.linalg.norm(away), 1e-9)
    return render.look_at([*(middle + 1.6 * away), 4.0], [*middle, 0.0])


def render_frame(sim: Simulation, layout: Layout, config: GoToGoalConfig) -> np.ndarray:
    """The scene now from `frame_view`, the goal painted as a red disc of the goal radius."""
    from corobot_drake.sensors import render

    render.add_renderer(sim)
    height, width = FRAME_SIZE
    X_WC = frame_view(layout)
    image = render.render(sim, X_WC, width, height, FRAME_FOV_Y_DEG).copy()
    focal = (height / 2) / math.tan(math.radians(FRAME_FOV_Y_DEG) / 2)
    center = X_WC.inverse() @ np.array([*layout.goal, 0.0])
    edge = X_WC.inverse() @ np.array([layout.goal[0] + config.goal_radius, layout.goal[1], 0.0])
    if center[2] > 0:
        u, v = width / 2 + focal * center[0] / center[2], height / 2 + focal * center[1] / center[2]
        radius = max(2.0, focal * np.linalg.norm(edge[:2] / edge[2] - center[:2] / center[2]))
        rows, cols = np.ogrid[:height, :width]
        disc = (cols - u) ** 2 + (rows - v) ** 2 <= radius ** 2
        image[disc] = (0.35 * image[disc] + 0.65 * np.array(GOAL_COLOR)).astype(np.uint8)
    return image


class _Ports:
    """What the env reads from the diagram besides the Robot API: the IR rays (each sensor's
    `scan_state`), the drive's commanded axle speeds, and the plant's contacts with boxes."""

    def __init__(self, sim: Simulation, scenario: sc.Scenario, robot: str = ROBOT):
        diagram, plant = sim.station.diagram, sim.station.plant
        self._plant = plant
        self._radius = sim.robot(robot).spec.wheel_radius
        self._scans = []
        self.ray_names = []
        sensors = scenario.robots[robot].ir_sensors
        names = IR_SENSORS if robot == ROBOT else [n for n, s in sensors.items() if s.enabled]
        for name in names:
            n = 2 * sensors[name].samples
            _, origin, ends, _ = scan_state_layout(n)
            self._scans.append((diagram.GetOutputPort(f"{robot}.{name}.scan_state"), origin,
                                ends))
            self.ray_names += [f"ir_{name}_{i}" for i in range(n)]
        self.num_rays = len(self.ray_names)
        self.ray_range = max((sensors[n].maximum_range for n in names), default=0.0)
        """m: the rays' longest reach (the observation's bound)."""
        self._axle = diagram.GetOutputPort(f"{robot}.axle_speed_command")
        self._boxes = {g for body in sim.station.bodies.values()
                       for g in plant.GetCollisionGeometriesForBody(body)}

    def ray_distances(self, context) -> np.ndarray:
        """m, each ray from its origin to where it stopped (maximum_range: nothing hit)."""
        out = []
        for port, origin, ends in self._scans:
            x = port.Eval(context)
            out.append(np.linalg.norm(x[ends].reshape(-1, 3) - x[origin], axis=1))
        return np.concatenate(out) if out else np.zeros(0)

    def commanded_rim_speed(self, context) -> float:
        """m/s: the mean magnitude of the two sides' commanded axle speeds times R."""
        return float(np.mean(np.abs(self._axle.Eval(context)))) * self._radius

    def touching_boxes(self, context) -> bool:
        """Any contact with a box or the giant box (only the robot can touch them: they are
        held above the ground, apart)."""
        results = self._plant.get_contact_results_output_port().Eval(
            self._plant.GetMyContextFromRoot(context))
        for i in range(results.num_hydroelastic_contacts()):
            surface = results.hydroelastic_contact_info(i).contact_surface()
            if surface.id_M() in self._boxes or surface.id_N() in self._boxes:
                return True
        for i in range(results.num_point_pair_contacts()):
            pair = results.point_pair_contact_info(i).point_pair()
            if pair.id_A in self._boxes or pair.id_B in self._boxes:
                return True
        return False
