"""The node's ROS 2 parameters, in one table: each with its default, its allowed values (a
range or a choice) and what it does, declared with a descriptor (`ros2 param describe` shows
them) and checked in one place (`problem`), at start-up (`--ros-args -p`, a params file) and
when set while the node runs.

No ROS import at module level: the bag writer reads the defaults (`Settings`) without ROS.
"""

from __future__ import annotations

import dataclasses as dc
import math

from corobot_drake.ros2.interfaces import DEADMAN_TIMEOUT


@dc.dataclass(frozen=True)
class Param:
    name: str
    default: object
    what: str
    low: float | None = None
    """A number's bounds (inclusive); None: not a number."""
    high: float | None = None
    unit: str = ""
    choices: tuple = ()
    """A string's allowed values."""
    read_only: bool = True
    """Read once, as the node starts (it shapes the topics): `-p` or a params file sets it."""

    def problem(self, value) -> str | None:
        """Why `value` is not allowed (one line naming the parameter), else None."""
        if self.low is not None:
            number = isinstance(value, int | float) and not isinstance(value, bool)
            if not (number and math.isfinite(value) and self.low <= value <= self.high):
                return (f"{self.name}: {value!r} is not a number of {self.unit} in "
                        f"[{self.low:g}, {self.high:g}]")
        elif self.choices:
            if value not in self.choices:
                return f"{self.name}: {value!r} is not one of {', '.join(self.choices)}"
        elif not isinstance(value, type(self.default)):
            return f"{self.name}: {value!r} is not a {type(self.default).__name__}"
        return None


PARAMETERS = (
    Param("cmd_vel_timeout", DEADMAN_TIMEOUT,
          "s of simulated time without a /cmd_vel message after which the robot stops (0: "
          "never)", low=0.0, high=3600.0, unit="s", read_only=False),
    Param("cmd_vel_stamped", False,
          "/cmd_vel's type: geometry_msgs/TwistStamped (true: Nav2, diff_drive_controller, "
          "teleop_twist_keyboard stamped:=true) or geometry_msgs/Twist (false)"),
    Param("sensor_qos", "reliable",
          "the sensors' topics' reliability: reliable (RViz's, image_view's and rqt's "
          "defaults see them) or best_effort (rclpy's sensor data profile)",
          choices=("reliable", "best_effort")),
    Param("odom_source", "wheel",
          "what /odom and /tf's odom -> base_link are: the wheel odometry's dead reckoning "
          "(wheel) or the simulation's ground truth (ground_truth); /ground_truth always has "
          "the ground truth, in frame world", choices=("wheel", "ground_truth")),
)
PARAMETER = {p.name: p for p in PARAMETERS}


@dc.dataclass(frozen=True)
class Settings:
    """The read-only parameters' values a run's topics are built with (a bag: the defaults)."""

    sensor_qos: str = PARAMETER["sensor_qos"].default
    odom_source: str = PARAMETER["odom_source"].default
    cmd_vel_stamped: bool = PARAMETER["cmd_vel_stamped"].default


class ParameterError(ValueError):
    """A parameter given a value it does not allow (`str`: the one line)."""


def descriptor(param: Param):
    """rcl_interfaces/ParameterDescriptor of `param`: a number's range as both a
    floating_point_range and an integer_range (it takes an integer too: `-p
    cmd_vel_timeout:=2`), `ros2 param describe` shows them."""
    from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor

    d = ParameterDescriptor(name=param.name, description=param.what,
                            read_only=param.read_only)
    # Typed by `problem` (an int is a number of s too): rclpy then applies the range of the
    # value's type, and `make_node`'s node refuses in `problem`'s line, not rclpy's words.
    d.dynamic_typing = True
    if param.low is not None:
        d.additional_constraints = f"a number of {param.unit} in [{param.low:g}, {param.high:g}]"
        d.floating_point_range = [FloatingPointRange(from_value=float(param.low),
                                                     to_value=float(param.high))]
        d.integer_range = [IntegerRange(from_value=math.ceil(param.low),
                                        to_value=math.floor(param.high))]
    elif param.choices:
        d.additional_constraints = f"one of {', '.join(param.choices)}"
    return d


def make_node(name: str, context, overrides: list = ()):
    """An rclpy node whose parameters' descriptors refuse a value in `Param.problem`'s one
    line: rclpy applies a descriptor's range before the on-set callbacks, in its own words
    ("Parameter cmd_vel_timeout out of range Min: ..."), and that is what `ros2 param set`
    would print. `overrides`: rclpy Parameters that take precedence over `--ros-args`."""
    from rclpy.node import Node

    class CheckedNode(Node):
        def __init__(self, *args, **kwargs):
            self.refusals: list[str] = []  # (`declare` reports the last)
            super().__init__(*args, **kwargs)

        # rclpy's (private) check of a value against its descriptor: the one place it
        # refuses by range, at declaration (`-p`, a params file) and at a set alike.
        def _apply_descriptor(self, parameter, descriptor=None, check_read_only=True):
            result = super()._apply_descriptor(parameter, descriptor, check_read_only)
            spec = PARAMETER.get(parameter.name)
            if result.successful or spec is None or (check_read_only and spec.read_only):
                return result  # (a read-only one set while running: rclpy's line says so)
            problem = spec.problem(parameter.value)
            if problem:
                self.refusals.append(problem)
                result.reason = problem
            return result

    return CheckedNode(name, context=context, parameter_overrides=list(overrides))


def declare(node) -> Settings:
    """Declares every parameter on `node` (its overrides: `--ros-args -p`, a params file),
    refusing a bad value: ParameterError, one line; returns the read-only ones' values."""
    from rcl_interfaces.msg import SetParametersResult

    refused: list[str] = getattr(node, "refusals", [])

    def check(parameters):
        for p in parameters:
            spec = PARAMETER.get(p.name)
            problem = spec.problem(p.value) if spec is not None else None
            if problem:
                refused.append(problem)
                return SetParametersResult(successful=False, reason=problem)
        return SetParametersResult(successful=True)

    node.add_on_set_parameters_callback(check)
    values = {}
    for param in PARAMETERS:
        try:
            values[param.name] = node.declare_parameter(param.name, param.default,
                                                        descriptor(param)).value
        except Exception as e:  # rclpy's words wrap the callback's line: that line alone
            raise ParameterError(refused[-1] if refused else _reason(e)) from None
    return Settings(**{k: v for k, v in values.items() if k in Settings.__dataclass_fields__})


def _reason(error: Exception) -> str:
    text = str(error).strip().splitlines()
    return text[-1] if text else type(error).__name__
