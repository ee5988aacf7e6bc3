"""The node's /diagnostics (diagnostic_msgs/DiagnosticArray, as rqt_robot_monitor and the
diagnostic aggregator read it), once a second of wall clock: the simulation's real-time
factor and slips (the loop falling behind its rate), and each robot's drive stalls, wheel
slip and tip margin.

Live only (the real-time factor is the wall clock's): a bag has none. `sample` runs in the
simulation thread, `statuses` turns a sample into the statuses' fields, `message` into the
message (rclpy's types).
"""

from __future__ import annotations

import dataclasses as dc

TOPIC = ("diagnostics", "diagnostic_msgs/msg/DiagnosticArray")
"""Published (shared, reliable, keep last 10), once a second of wall clock while the node runs
live: the real-time factor and slips, and each robot's stalls, wheel slip and tip margin."""
PERIOD = 1.0
"""s (wall clock) between /diagnostics messages: the 1 Hz the ROS tools expect."""
SLIP_WARN = 0.5
"""|longitudinal slip ratio| over which a wheel is reported slipping (WARN): the tyre is
mostly sliding, not rolling (docs/commands.md: the contact telemetry)."""
TIP_MARGIN_WARN_DEG = 10.0
"""deg of tip margin under which the robot is reported close to tipping over (WARN; 0 or
less: ERROR)."""
OK, WARN, ERROR = 0, 1, 2
"""diagnostic_msgs/DiagnosticStatus levels."""
PREFIX = "corobot_drake: "


@dc.dataclass(frozen=True)
class Status:
    level: int
    name: str
    message: str
    values: dict


def sample(robots: list[str], sim) -> dict:
    """In the simulation thread: the simulated time (s) and, by robot, its commands that
    ended stalled, its wheels' slip ratios and its tip margin (deg)."""
    out = {"time": sim.time, "robots": {}}
    for name in robots:
        robot = sim.robot(name)
        out["robots"][name] = {
            "stalls": sum(r.reason == "stalled" for r in robot.command_log()),
            "slip": dict(robot.signal("wheel_slip_ratio")),
            "tip_margin_deg": float(robot.signal("tip_margin")),  # (the signal is in deg)
        }
    return out


PAUSED = "paused: simulated time stands still (StepSimulation, SimulateSteps or playing moves it)"
"""The simulation's status message while the runner is paused (its real-time factor is of
the time before the pause: not reported)."""


def statuses(stats: dict, values: dict, slips_before: int) -> list[Status]:
    """The statuses of a `sample` and the runner's `stats` (`paused` too: the runner's);
    `slips_before`: its slips at the last report (new ones are a WARN)."""
    factor = stats.get("recent_realtime_factor") or stats.get("realtime_factor")
    slips = int(stats.get("slips") or 0)
    common = {"rate": stats.get("rate"), "slips": slips, "time": values["time"]}
    if stats.get("paused"):
        out = [Status(OK, PREFIX + "simulation", PAUSED, {"paused": True, **common})]
    else:
        out = [Status(WARN if slips > slips_before else OK, PREFIX + "simulation",
                      f"real-time factor {factor:.2f}" if factor else "starting",
                      {"realtime_factor": factor, **common})]
    for robot, v in values["robots"].items():
        worst = max(v["slip"].values(), key=abs, default=0.0)
        margin = v["tip_margin_deg"]
        out += [
            Status(OK, f"{PREFIX}{robot} drive", f"{v['stalls']} commands ended stalled",
                   {"stalls": v["stalls"]}),
            Status(WARN if abs(worst) > SLIP_WARN else OK, f"{PREFIX}{robot} wheel slip",
                   f"largest slip ratio {worst:+.2f}", dict(v["slip"])),
            Status(ERROR if margin <= 0 else WARN if margin < TIP_MARGIN_WARN_DEG else OK,
                   f"{PREFIX}{robot} tip margin", f"{margin:.1f} deg",
                   {"tip_margin_deg": margin}),
        ]
    return out


def message(t: float, items: list[Status]):
    """diagnostic_msgs/DiagnosticArray of `items`, stamped at simulated time `t` (s)."""
    from builtin_interfaces.msg import Time
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

    ns = round(t * 1e9)
    array = DiagnosticArray()
    array.header.stamp = Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)
    array.status = [DiagnosticStatus(
        level=bytes([s.level]), name=s.name, message=s.message, hardware_id="corobot_drake",
        values=[KeyValue(key=str(k), value=_text(v)) for k, v in s.values.items()])
        for s in items]
    return array


def _text(value) -> str:
    return f"{value:.6g}" if isinstance(value, float) else str(value)
