"""What `GoToGoalEnv` takes from its caller, checked: its config (each field in its range, and
a task whose layouts exist), `reset`'s options (a `Layout` of the env's shape) and `step`'s
action. Each refusal is a ValueError naming the field and what is allowed.
"""

from __future__ import annotations

import dataclasses as dc
import math
import reprlib
from numbers import Real
from pathlib import Path

import numpy as np

from corobot_drake import limits
from corobot_drake.gym.layout import Layout, giant_box
from corobot_drake.limits import Range
from corobot_drake.robots import corobot

MAX_BOXES = 100
"""The most boxes an env may have: each is a body of the diagram (`base_scenario`)."""
MAX_STEPS = 1_000_000
"""The most steps an episode may last (`time_limit / control_period`)."""

CONFIG_BOUNDS = {
    "control_period": Range(corobot.drive("control_period"), 10.0, unit="s",
                            why="at least the drive's control period"),
    "time_limit": Range(0.0, 86_400.0, low_open=True, unit="s"),
    "goal_radius": Range(0.0, 10.0, low_open=True, unit="m"),
    "goal_distance": Range(0.0, 100.0, low_open=True, unit="m"),
    "start_spread": Range(0.0, 10.0, unit="m"),
    "boxes": Range(0, MAX_BOXES, why="each box is a body of the diagram"),
    "box_size": Range(0.01, 2.0, unit="m"),
    "blocking_probability": Range(0.0, 1.0),
    "blocking_offset": Range(0.0, 10.0, unit="m"),
    "box_area": Range(0.0, 100.0, unit="m"),
    "start_clearance": Range(0.0, 10.0, unit="m"),
    "goal_clearance": Range(0.0, 100.0, unit="m"),
    "flip_tilt_deg": Range(0.0, 180.0, low_open=True, unit="deg"),
    "progress_reward": Range(-1e6, 1e6),
    "time_cost": Range(-1e6, 1e6),
    "collision_penalty": Range(-1e6, 1e6),
    "stall_penalty": Range(-1e6, 1e6),
    "success_reward": Range(-1e6, 1e6),
    "flip_penalty": Range(-1e6, 1e6),
}
"""Each numeric field of `GoToGoalConfig` (`goal_distance`: each end) and its range."""

def robot_path(robot: str) -> str:
    """A shipped robot's name, or a robot file's absolute path (as the loader makes it)."""
    from corobot_drake.robots import ROBOTS

    return robot if robot in ROBOTS else str(Path(robot).resolve())


def robot_reach(spec) -> float:
    """m: the farthest a robot's footprint reaches from its base origin: the Corobot's
    the corner of the rectangle round its tyres and boxes; another's, its tyres' outer
    corners (a body wider than its wheels: the reset refuses a start inside a box in one
    line)."""
    if spec.generated:
        return _footprint_corner(spec)
    return max(math.hypot(abs(w.center[0]) + w.radius, abs(w.center[1]) + w.width / 2)
               for w in spec.wheels)



def _footprint_corner(spec) -> float:
    """m: the corner of the rectangle (square to the base frame) round a rectangular robot's
    tyres (from its stated wheelbase, track and radius, written exactly) and its box-shaped
    parts, from its base origin."""
    from pydrake.geometry import Box

    xs = [spec.wheelbase / 2 + spec.wheel_radius]
    ys = [spec.half_track + max(w.width for w in spec.wheels) / 2]
    for _, shape, X_BG in spec.shapes:
        if isinstance(shape, Box):
            xs.append(abs(X_BG.translation()[0]) + shape.size()[0] / 2)
            ys.append(abs(X_BG.translation()[1]) + shape.size()[1] / 2)
    return math.hypot(max(xs), max(ys))


def _robot(config):
    """The config's robot's `RobotSpec`; ValueError when it is no robot or lacks the front
    camera `camera` asks for."""
    from corobot_drake.config.scenario import ScenarioError
    from corobot_drake.robots import robot_spec

    if not isinstance(config.robot, str) or not config.robot:
        raise ValueError("GoToGoalConfig.robot: must be a shipped robot's name or a robot "
                         f"file's path; got {reprlib.repr(config.robot)}")
    from corobot_drake.names import unknown_robot_kind
    from corobot_drake.robots import ROBOTS

    if config.robot not in ROBOTS and not Path(config.robot).is_file():
        raise ValueError(f"GoToGoalConfig.robot: {unknown_robot_kind(config.robot, ROBOTS)}")
    try:
        spec = robot_spec(robot_path(config.robot))
    except ScenarioError as e:
        raise ValueError(f"GoToGoalConfig.robot: {e}") from None
    if config.camera and not spec.generated and "front" not in spec.sensors.get("cameras", {}):
        raise ValueError(f"GoToGoalConfig.camera: the robot {spec.kind!r} has no front camera")
    return spec


def make_config(config, overrides: dict):
    """`config` with `overrides` (field names of `GoToGoalConfig`), checked (`check_config`)."""
    if not dc.is_dataclass(config) or isinstance(config, type):
        raise ValueError(f"config: must be a GoToGoalConfig; got {reprlib.repr(config)}")
    names = {f.name for f in dc.fields(config)}
    unknown = sorted(set(overrides) - names)
    if unknown:
        raise ValueError(f"GoToGoalConfig has no field {unknown[0]!r}; fields: "
                         f"{', '.join(sorted(names))}")
    config = dc.replace(config, **overrides)
    check_config(config)
    return config


def _number(name: str, value, bound: Range, whole: bool = False) -> None:
    kind = "a whole number" if whole else "a number"
    if isinstance(value, bool) or not isinstance(value, Real | np.number) or (
            whole and not isinstance(value, int | np.integer)):
        raise ValueError(f"GoToGoalConfig.{name}: must be {kind} {bound.text()}; got "
                         f"{reprlib.repr(value)}")
    try:
        x = float(value)
    except OverflowError:  # an int beyond any float
        x = math.inf if value > 0 else -math.inf
    problem = bound.problem(x)
    if problem:
        raise ValueError(f"GoToGoalConfig.{name}: {problem}")


def check_config(config) -> None:
    """Each field in its range (`CONFIG_BOUNDS`), then the task possible: episodes end, the
    start is clear of the giant box, a goal can be that clear of it."""
    for name, bound in CONFIG_BOUNDS.items():
        value = getattr(config, name)
        if name == "goal_distance":
            if not isinstance(value, tuple | list) or len(value) != 2:
                raise ValueError(f"GoToGoalConfig.goal_distance: must be (low, high) in m; "
                                 f"got {reprlib.repr(value)}")
            for end in value:
                _number(name, end, bound)
        else:
            _number(name, value, bound, whole=name == "boxes")
    if not isinstance(config.camera, bool):
        raise ValueError("GoToGoalConfig.camera: must be True or False; got "
                         f"{reprlib.repr(config.camera)}")
    reach = robot_reach(_robot(config))
    low, high = config.goal_distance
    if low > high:
        raise ValueError(f"GoToGoalConfig.goal_distance: must be (low, high) with low <= high; "
                         f"got {tuple(config.goal_distance)}")
    if config.time_limit < config.control_period or (
            config.time_limit / config.control_period > MAX_STEPS):
        raise ValueError(f"GoToGoalConfig.time_limit: must be from one to {MAX_STEPS} control "
                         f"periods ({config.control_period:g} s); got {config.time_limit:g} s")
    _check_reachable(config, reach)


def _check_reachable(config, reach: float) -> None:
    """Every start clear of the giant box (the robot reaches `reach` m from its origin);
    from every start, a goal as clear of it as `goal_clearance` asks (else `draw_layout`
    would look for one forever)."""
    nearest = _start_gap(config.start_spread)  # the start square's nearest approach
    if nearest <= reach:
        most = _start_gap(0.0) - reach
        raise ValueError(f"GoToGoalConfig.start_spread: must be under {most:.3f} m (a start "
                         f"further out may be inside the giant box); got "
                         f"{config.start_spread:g}")
    # From a start s outside a convex footprint, the farthest goal at distance d is
    # gap(s) + d away from it (straight away from its nearest point).
    farthest = nearest + config.goal_distance[1]
    if config.goal_clearance >= farthest:
        raise ValueError(f"GoToGoalConfig.goal_clearance: must be under {farthest:.3f} m (no "
                         "goal from a start near the giant box is further from it); got "
                         f"{config.goal_clearance:g}")


def _start_gap(spread: float) -> float:
    """m between the square of starts (+-`spread` around the origin) and the giant box's
    footprint."""
    (cx, cy, _), size = giant_box()
    half = size / 2
    gx = max(0.0, abs(cx) - half - spread)
    gy = max(0.0, abs(cy) - half - spread)
    return math.hypot(gx, gy)


def check_options(options, config) -> Layout | None:
    """`reset`'s options: None, or a dict with at most `layout`, a `Layout` of the env's
    number of boxes, every coordinate finite and in the world (`limits.POSITION`)."""
    if options is None:
        return None
    if not isinstance(options, dict):
        raise ValueError(f"reset(options=...): must be a dict or None; got {reprlib.repr(options)}")
    unknown = sorted(map(repr, set(options) - {"layout"}))
    if unknown:
        raise ValueError(f"reset(options=...): unknown option {unknown[0]}; the only one is "
                         "'layout'")
    layout = options.get("layout")
    if layout is None:
        return None
    if not isinstance(layout, Layout):
        raise ValueError(f"reset(options={{'layout': ...}}): must be a gym.layout.Layout; got "
                         f"{type(layout).__name__}")
    _coordinates("layout.start", layout.start, 3)
    _coordinates("layout.goal", layout.goal, 2)
    if not isinstance(layout.boxes, tuple | list) or len(layout.boxes) != config.boxes:
        count = len(layout.boxes) if isinstance(layout.boxes, tuple | list) else layout.boxes
        raise ValueError(f"layout.boxes: must hold the env's {config.boxes} boxes "
                         f"(GoToGoalConfig.boxes); got {count}")
    for i, box in enumerate(layout.boxes):
        _coordinates(f"layout.boxes[{i}]", box, 3)
    return layout


def _coordinates(name: str, values, size: int) -> None:
    """`values`: `size` numbers, x and y in `limits.POSITION` m, a yaw (third) finite."""
    if not isinstance(values, tuple | list | np.ndarray) or len(values) != size:
        what = "x, y (m), yaw (rad)" if size == 3 else "x, y (m)"
        raise ValueError(f"{name}: must be {size} numbers ({what}); got {reprlib.repr(values)}")
    for axis, value in zip("xy", values[:2], strict=False):
        limits.POSITION.check(f"{name}.{axis}", value)
    if size == 3:
        limits.number(f"{name}.yaw", values[2])


def check_action(action, space) -> tuple[float, float]:
    """`step`'s action: two finite numbers (left, right power; outside [-1, 1] clipped, as
    the action space's bounds say)."""
    try:
        array = np.asarray(action, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"action: must be {space.shape[0]} numbers (left, right power in "
                         f"[-1, 1]); got {reprlib.repr(action)}") from None
    if array.shape != space.shape or not np.all(np.isfinite(array)):
        raise ValueError(f"action: must be {space.shape[0]} finite numbers (left, right power "
                         f"in [-1, 1]); got {reprlib.repr(action)}")
    left, right = np.clip(array, space.low, space.high)
    return float(left), float(right)
