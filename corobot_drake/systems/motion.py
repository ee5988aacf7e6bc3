"""Commands that complete: DriveDistance, RotateDegrees and SetPose as one state machine.

`MotionCommands` sits between the command source and the drive controller. It passes
ordinary commands (SetPower, SetSpeed, SetVelocity, AllStop, Enable) through; it turns a
DriveDistance or RotateDegrees into a stream of SetPower requests computed every control
period from the measured chassis position (GPS) and heading (compass), and reports how each
one ends on its `command_status` output. Two landing profiles:

- `seed`, the book's: full power until the goal; from the progress over the last 0.1 s (the
  book's 6 samples of 1/60 s, kept one per control period), estimate the time left and halve
  the speed when under 0.1 s (the book's 6 frames) remains; when the goal is reached, stop the
  wheels at once (no slew: the book sets the axle speed to 0) and succeed. A rotation ends when
  less than 0.005 rad is left or it overshot.
- `closed_loop`: a speed servo on the measured distance (along the start heading) or angle
  left, predicted 2 control periods ahead for the command's latency: the speed is the smallest
  of the cruise speed, sqrt(2 a left) (braking within the slew limit) and k left, never under a
  creep speed; inside the tolerance it stops, and succeeds once at rest there for
  `STILL_TIME` (it backs up if it overshot). A drive also holds the start heading.

The book's rules per 1/60 s frame are expressed per second, so the control period may be any
(the default runs on the plant's 10 ms steps: no event time falls between two steps).

Both fail `stalled` when progress stays under the scenario's stall distance/angle for its
stall time, and `disabled` when issued to a disabled drive (a newer command ending one is
recorded by the command source). A SetPose stops the wheels, waits until the Simulation has
teleported the robot (its pose matches) and succeeds after `POSE_SETTLE_TIME`.
"""

import dataclasses as dc
import math

from pydrake.common.value import Value
from pydrake.systems.framework import EventStatus, LeafSystem

from corobot_drake.config.scenario import SEED_WINDOW as SEED_WINDOW
from corobot_drake.config.scenario import (
    AllStop,
    Drive,
    DriveDistance,
    Motion,
    RotateDegrees,
    SetPose,
    SetPower,
)
from corobot_drake.robots import corobot
from corobot_drake.systems.drive import CommandStatus, DriveRequest
from corobot_drake.systems.shared_state import SharedState

# The seed profile (the book's constants, per second: it counted 1/60 s frames); its window,
# `SEED_WINDOW`, is the scenario's (a saved command's progress fills it).
SEED_DECELERATE_TIME = 6 / 60
"""s: halve the speed when less time than this is estimated to remain (the book's 6
frames)."""
SEED_ROTATION_TOLERANCE = 0.005
"""rad: a rotation ends when less than this is left (or it overshot)."""

# The closed-loop profile.
LATENCY_FRAMES = 2
"""Control periods between a measurement and the wheels acting on it (this system's update,
then the drive controller's): the distance/angle left is predicted this far ahead."""
BRAKE_FRACTION = 0.5
"""Braking uses this fraction of the slew-limited deceleration, leaving room to correct."""
DRIVE_GAIN = 3.0
"""1/s: speed per metre left near the goal."""
DRIVE_CREEP = 0.01
"""m/s: slowest approach speed."""
DRIVE_TOLERANCE = 0.0005
"""m: a drive stops inside this of the goal."""
DRIVE_STILL_SPEED = 0.002
"""m/s: at rest below this."""
HEADING_GAIN = 5.0
"""Axle rad/s added to one side and taken from the other per radian of heading error while
driving (a left-right difference of twice that)."""
HEADING_CORRECTION_LIMIT = 1.0
"""rad/s: the largest correction per side the heading hold asks for (a difference of 2)."""
TURN_GAIN = 3.0
"""1/s: yaw rate per radian left near the goal."""
TURN_CREEP = 0.05
"""rad/s: slowest approach yaw rate."""
TURN_TOLERANCE = 0.001
"""rad: a rotation stops inside this of the goal (0.057 deg; the creep turns 0.5 mrad per
10 ms update, 0.8 per 1/60 s, so it cannot step over the band)."""
TURN_STILL_RATE = 0.01
"""rad/s: at rest below this."""
STILL_TIME = 0.05
"""s in tolerance and at rest before a closed-loop command succeeds (3 frames of 1/60 s)."""
SPIN_YAW_PER_RIM_SPEED = corobot.wheels("track") / 2 / (
    (corobot.wheels("wheelbase") / 2) ** 2 + (corobot.wheels("track") / 2) ** 2)
"""1/m: a skid-steer spin's yaw rate per rim speed with isotropic Coulomb friction,
b / (a^2 + b^2) of the Corobot's half track b and half wheelbase a (its robot file's;
`RobotSpec.spin_yaw_per_rim_speed` of any robot; DRAKE_NOTES: Drake matches it within 2%)."""

# SetPose.
POSE_LANDED_DISTANCE = 0.005
"""m: the robot is where a SetPose put it when this close (and within POSE_LANDED_YAW)."""
POSE_LANDED_YAW = 0.01
"""rad."""
POSE_SETTLE_TIME = 0.25
"""s after landing before a SetPose succeeds (the tyres take the load in ~0.1 s)."""
POSE_TIMEOUT = 1.0
"""s: a SetPose not applied by then fails `not_applied` (a bare Simulator cannot teleport)."""


def wrap(angle: float) -> float:
    """The angle in [-pi, pi] (rad)."""
    return math.remainder(angle, 2 * math.pi)


@dc.dataclass(frozen=True)
class ActiveCommand(SharedState):
    """A running command. Units: m, rad, s."""

    seq: int
    kind: str
    """drive, rotate or pose."""
    target: float
    """drive: |distance| m; rotate: signed angle, rad; pose: unused."""
    sign: float
    """+1 or -1: forwards/backwards, or counter-clockwise/clockwise."""
    power: float
    start: tuple[float, float, float]
    """(x, y, yaw) at the start; for a pose, the target pose."""
    start_time: float
    heading: float
    """The compass at the last update (rad, wrapped); a rotation unwraps from it."""
    progress: float = 0.0
    """drive: m towards the goal; rotate: rad turned (unwrapped, signed)."""
    samples: tuple[float, ...] = ()
    """seed: the last progress samples, oldest first."""
    scale: float = 1.0
    """seed: the fraction of `power` commanded now."""
    stall_progress: float = 0.0
    stall_time: float = 0.0
    """Progress and time when the command last made progress."""
    still_frames: int = 0


@dc.dataclass(frozen=True)
class MotionState(SharedState):
    """MotionCommands' whole memory (abstract state in the Context)."""

    handled_seq: int = 0
    """seq of the last input request acted on."""
    output: DriveRequest = dc.field(default_factory=DriveRequest)
    active: ActiveCommand | None = None
    status: CommandStatus = dc.field(default_factory=CommandStatus)
    """How the last completing command ended."""


def _count_still(a, at_goal: bool, frames: int):
    """The active command with its count of updates at rest on the goal (reset when it
    moves); True once it has held there for `frames` updates."""
    a = a.replace(still_frames=a.still_frames + 1 if at_goal else 0)
    return a, a.still_frames >= frames


class MotionCommands(LeafSystem):
    """DriveDistance / RotateDegrees / SetPose state machine (module docstring).

    .. pydrake_system::

        name: MotionCommands
        input_ports:
        - request
        - position
        - heading
        output_ports:
        - drive_request
        - command_status

    Inputs: `request` (DriveRequest, abstract, from the command source), `position` (3, m,
    chassis origin in the world frame, GPS), `heading` (1, rad, chassis yaw about world z,
    compass). Outputs: `drive_request` (DriveRequest, abstract, for the drive controller, its
    own seq), `command_status` (CommandStatus, abstract: how the last completing command
    ended). Abstract state `MotionState`, updated every `drive.control_period` s.
    """

    def __init__(self, drive: Drive, motion: Motion, wheel_radius: float = corobot.wheels("radius"),
                 spin_yaw_per_rim_speed: float = SPIN_YAW_PER_RIM_SPEED):
        """`wheel_radius` (m) and `spin_yaw_per_rim_speed` (1/m): the robot's
        (`RobotSpec`; the Corobot's by default)."""
        super().__init__()
        self._drive, self._motion = drive, motion
        self._radius, self._spin = wheel_radius, spin_yaw_per_rim_speed
        self._period = drive.control_period
        self._seed_samples = max(1, round(SEED_WINDOW / self._period))
        """Progress samples the seed profile keeps (one per update)."""
        self._still_frames = max(1, math.ceil(STILL_TIME / self._period - 1e-9))
        """Updates at rest on the goal before a closed-loop command succeeds."""
        self._request_port = self.DeclareAbstractInputPort("request", Value(DriveRequest()))
        self._position_port = self.DeclareVectorInputPort("position", 3)
        self._heading_port = self.DeclareVectorInputPort("heading", 1)
        self._state_index = self.DeclareAbstractState(Value(MotionState()))
        ticket = {self.abstract_state_ticket(self._state_index)}
        self.DeclareAbstractOutputPort("drive_request", lambda: Value(DriveRequest()),
                                       lambda c, o: o.set_value(self.get_state(c).output),
                                       ticket)
        self.DeclareAbstractOutputPort("command_status", lambda: Value(CommandStatus()),
                                       lambda c, o: o.set_value(self.get_state(c).status),
                                       ticket)
        self.DeclarePeriodicUnrestrictedUpdateEvent(self._period, 0.0, self._update)

    @property
    def drive_period(self) -> float:
        """s: the update period (the drive's control period)."""
        return self._period

    def get_state(self, context) -> MotionState:
        return context.get_abstract_state(self._state_index).get_value()

    def remaining_command(self, context):
        """The DriveDistance/RotateDegrees that carries the running one on from now (None if
        none), what a saved scene resumes: a drive with its distance counted from where it
        started, a turn with the angle left from its heading at the last update, both at the
        power they run at (the seed profile's halvings kept) with their progress at the last
        updates (`recent_progress`: what the speed estimates need). A request issued but
        not yet taken (it is taken at the next update) as it was issued."""
        s = self.get_state(context)
        request = self._request_port.Eval(context)
        if request.seq != s.handled_seq:  # the next update starts it (or ends the running one)
            pending = request.command
            return pending if isinstance(pending, DriveDistance | RotateDegrees) else None
        a = s.active
        if a is None or a.kind == "pose":
            return None
        power = a.power * a.scale
        x, y, yaw = a.start
        if a.kind == "drive":
            recent = a.samples if self._motion.profile == "seed" else (a.progress,)
            return DriveDistance(a.sign * a.target, power, [x, y, math.degrees(yaw)],
                                 list(recent))
        # Counted from the heading at the last update, so the progress then is 0 and the
        # next update measures the same turn since as the uninterrupted command's would.
        recent = [math.degrees(p - a.progress) for p in a.samples]
        return RotateDegrees(math.degrees(a.target - a.progress), power,
                             [x, y, math.degrees(a.heading)], recent)

    # --- the state machine ----------------------------------------------------------------
    def _update(self, context, state):
        original = self.get_state(context)
        s = original
        request = self._request_port.Eval(context)
        if request.seq == s.handled_seq and s.active is None:
            return EventStatus.DidNothing()  # nothing new, nothing running
        now = context.get_time()
        x, y = (float(v) for v in self._position_port.Eval(context)[:2])
        heading = float(self._heading_port.Eval(context)[0])
        if request.seq != s.handled_seq:
            s = s.replace(handled_seq=request.seq, active=None)
            command = request.command
            if isinstance(command, DriveDistance | RotateDegrees):
                if not request.enabled:
                    s = self._finish(s, request, request.seq, "failed", "disabled", now)
                else:
                    s = self._start(s, request, command, (x, y, heading), now)
            elif isinstance(command, SetPose):
                target = (command.x, command.y, math.radians(command.yaw_deg))
                s = s.replace(active=ActiveCommand(
                    request.seq, "pose", 0.0, 1.0, 0.0, target, now, heading))
                s = self._emit(s, AllStop(), request, now)
            else:
                s = self._emit(s, command, request, now)
        if s.active is not None:
            step = {"drive": self._step_drive, "rotate": self._step_rotate,
                    "pose": self._step_pose}[s.active.kind]
            s = step(s, request, x, y, heading, now)
        if s is original:
            return EventStatus.DidNothing()  # as `CommandSource._update`
        state.get_mutable_abstract_state(self._state_index).set_value(s)
        return EventStatus.Succeeded()

    @staticmethod
    def _emit(s: MotionState, command, request: DriveRequest, now: float,
              immediate: bool = False) -> MotionState:
        """Outputs `command` (a new seq only when it differs from the last one output);
        `immediate`: the drive skips the slew limit for it."""
        out = s.output
        if (out.seq and out.command == command and out.enabled == request.enabled
                and out.immediate == immediate):
            return s
        return s.replace(output=DriveRequest(out.seq + 1, command, now, request.enabled,
                                             immediate))

    def _finish(self, s, request, seq, status, reason, now, immediate=False) -> MotionState:
        """Ends the active command with `status`; the wheels stop (at once if `immediate`)."""
        s = s.replace(active=None, status=CommandStatus(seq, status, reason, now))
        return self._emit(s, AllStop(), request, now, immediate)

    def _start(self, s, request, command, pose, now) -> MotionState:
        seed = self._motion.profile == "seed"
        if isinstance(command, DriveDistance):
            kind, target, power = "drive", abs(command.distance), command.power
            sign = math.copysign(1.0, command.distance)
        else:
            kind, target, power = "rotate", math.radians(command.degrees), command.power
            sign = math.copysign(1.0, target)
        if target == 0.0:  # the seed profile's stop is at once (the book's)
            return self._finish(s, request, request.seq, "succeeded", "", now, immediate=seed)
        start, progress, heading, samples = pose, 0.0, pose[2], ()
        if command.start:  # counted from a given pose (a resumed command)
            x0, y0, yaw0 = command.start[0], command.start[1], math.radians(command.start[2])
            recent = command.recent_progress
            if kind == "drive":
                start = (x0, y0, yaw0)
                progress = (recent[-1] if recent
                            else self._drive_progress(start, sign, pose[0], pose[1]))
            else:  # as if the last update read the heading from which it counts
                recent = [math.radians(p) for p in recent]
                progress = recent[-1] if recent else 0.0
                heading = wrap(yaw0 + progress)
            if seed:
                samples = tuple(recent[-self._seed_samples:])
        active = ActiveCommand(request.seq, kind, target, sign, min(abs(power), 1.0), start,
                               now, heading, progress=progress, samples=samples,
                               stall_progress=progress, stall_time=now)
        return s.replace(active=active)

    def _drive_progress(self, start, sign: float, x: float, y: float) -> float:
        """m towards a drive's goal from `start` (x0, y0, yaw0): the book's straight-line
        distance (seed), or the signed distance along the start heading (closed loop: an
        overshoot shows as negative distance left)."""
        x0, y0, yaw0 = start
        dx, dy = x - x0, y - y0
        if self._motion.profile == "seed":
            return math.hypot(dx, dy)
        return sign * (dx * math.cos(yaw0) + dy * math.sin(yaw0))

    def _check_stall(self, s, a: ActiveCommand, request, now, threshold: float, moving: bool):
        """(state, active): failed `stalled` when progress < threshold for the stall time."""
        if abs(a.progress - a.stall_progress) >= threshold or not moving:
            return s, a.replace(stall_progress=a.progress, stall_time=now)
        if now - a.stall_time >= self._motion.stall_time - 1e-9:
            return self._finish(s, request, a.seq, "failed", "stalled", now), None
        return s, a

    def _set_power(self, s, request, left_axle: float, right_axle: float, now):
        k = self._drive.motor_torque_scaling
        return self._emit(s, SetPower(left_axle / k, right_axle / k), request, now)

    def _step_drive(self, s, request, x, y, heading, now) -> MotionState:
        a = s.active
        yaw0 = a.start[2]
        previous = a.progress
        seed = self._motion.profile == "seed"
        progress = self._drive_progress(a.start, a.sign, x, y)
        a = a.replace(progress=progress, heading=heading)
        remaining = a.target - progress
        cruise = a.power * self._drive.motor_torque_scaling  # axle rad/s
        if seed:
            if remaining <= 0.0:  # the book: axle speed 0 at once
                return self._finish(s, request, a.seq, "succeeded", "", now, immediate=True)
            a = self._seed_slowdown(a, remaining, progress)
            s, a = self._check_stall(s, a, request, now, self._motion.stall_distance, True)
            if a is None:
                return s
            axle = a.sign * a.scale * cruise
            return self._set_power(s.replace(active=a), request, axle, axle, now)
        speed = (progress - previous) / self._period  # m/s towards the goal
        v = self._servo(remaining, speed, DRIVE_TOLERANCE, DRIVE_STILL_SPEED,
                        BRAKE_FRACTION * self._drive.slew_rate * self._radius, DRIVE_GAIN,
                        DRIVE_CREEP, cruise * self._radius)
        a, settled = _count_still(a, v is None, self._still_frames)
        if settled:
            return self._finish(s, request, a.seq, "succeeded", "", now)
        v = 0.0 if v is None else v
        s, a = self._check_stall(s, a, request, now, self._motion.stall_distance,
                                 abs(remaining) > self._motion.stall_distance)
        if a is None:
            return s
        axle = a.sign * v / self._radius
        correction = 0.0
        if v != 0.0:
            correction = max(-HEADING_CORRECTION_LIMIT, min(
                HEADING_CORRECTION_LIMIT, HEADING_GAIN * wrap(yaw0 - heading)))
        return self._set_power(s.replace(active=a), request, axle - correction,
                               axle + correction, now)

    def _step_rotate(self, s, request, x, y, heading, now) -> MotionState:
        a = s.active
        delta = wrap(heading - a.heading)
        previous = a.progress
        progress = previous + delta
        a = a.replace(progress=progress, heading=heading)
        remaining = a.target - progress
        cruise = a.power * self._drive.motor_torque_scaling  # axle rad/s
        if self._motion.profile == "seed":
            error = remaining if a.target > 0 else -remaining
            if error < SEED_ROTATION_TOLERANCE:  # the book: axle speed 0 at once
                return self._finish(s, request, a.seq, "succeeded", "", now, immediate=True)
            if delta != 0.0:
                a = self._seed_slowdown(a, error, progress)
            s, a = self._check_stall(s, a, request, now,
                                     math.radians(self._motion.stall_angle_deg), True)
            if a is None:
                return s
            axle = a.sign * a.scale * cruise
            return self._set_power(s.replace(active=a), request, -axle, axle, now)
        rate = delta / self._period
        to_axle = 1.0 / (self._spin * self._radius)  # axle rad/s per yaw rad/s
        w = self._servo(remaining, rate, TURN_TOLERANCE, TURN_STILL_RATE,
                        BRAKE_FRACTION * self._drive.slew_rate / to_axle, TURN_GAIN, TURN_CREEP,
                        cruise / to_axle)
        a, settled = _count_still(a, w is None, self._still_frames)
        if settled:
            return self._finish(s, request, a.seq, "succeeded", "", now)
        w = 0.0 if w is None else w
        stall = math.radians(self._motion.stall_angle_deg)
        s, a = self._check_stall(s, a, request, now, stall, abs(remaining) > stall)
        if a is None:
            return s
        axle = w * to_axle
        return self._set_power(s.replace(active=a), request, -axle, axle, now)

    def _seed_slowdown(self, a: ActiveCommand, remaining: float,
                       progress: float) -> ActiveCommand:
        """The book's: from the progress over the last SEED_WINDOW, estimate the time left;
        halve the speed (and forget the samples) when less than SEED_DECELERATE_TIME
        remains."""
        samples, scale, kept = a.samples, a.scale, self._seed_samples
        if len(samples) >= kept:
            moved = progress - samples[0]
            samples = samples[1:]
            left = math.inf if moved == 0.0 else abs(remaining * kept * self._period / moved)
            if moved < 0.0 and a.kind == "drive":
                left = -left  # the book's: moving away gives a negative estimate
            if left < SEED_DECELERATE_TIME:
                scale *= 0.5
                samples = ()
        return a.replace(samples=(*samples, progress), scale=scale)

    def _servo(self, remaining, rate, tolerance, still, brake, gain, creep, cruise):
        """The closed-loop profile's speed towards the goal (signed; None: in tolerance and
        at rest, i.e. arrived). `remaining` and `rate` in m and m/s (or rad, rad/s)."""
        predicted = remaining - rate * LATENCY_FRAMES * self._period
        if abs(remaining) <= tolerance and abs(rate) < still:
            return None
        if abs(predicted) <= tolerance:
            return 0.0
        magnitude = min(cruise, math.sqrt(2.0 * brake * abs(predicted)), gain * abs(predicted))
        return math.copysign(max(creep, magnitude) if cruise > creep else cruise, predicted)

    def _step_pose(self, s, request, x, y, heading, now) -> MotionState:
        a = s.active
        tx, ty, tyaw = a.start
        landed = (math.hypot(x - tx, y - ty) < POSE_LANDED_DISTANCE
                  and abs(wrap(heading - tyaw)) < POSE_LANDED_YAW)
        if landed:
            if a.still_frames == 0:
                a = a.replace(stall_time=now)  # landing time
            if now - a.stall_time >= POSE_SETTLE_TIME - 1e-9:
                return self._finish(s, request, a.seq, "succeeded", "", now)
            return s.replace(active=a.replace(still_frames=a.still_frames + 1))
        if now - a.start_time >= POSE_TIMEOUT - 1e-9:
            return self._finish(s, request, a.seq, "failed", "not_applied", now)
        return s
