"""What each layer of the physics-only stack costs (`python tools/bench.py --layers`).

The default scene's plant and scene graph (the same world and robot model as
`station.build_station`), then the robot's own systems added one layer at a time with the
station's wiring, each diagram driving the benchmark's figure of eight (`bench.DRIVING`):

- the plant alone: the wheels' servo fed the desired state the station's drive gave it at each
  step (recorded from a run of the station, replayed by Drake's `TrajectorySource`), no project
  system: the floor Drake sets, on the station's very trajectory (bit for bit: the same
  physics, so the difference is what the robot's systems cost);
- + the drive controller (its request fixed, changed at the same times);
- + the chassis poses, encoders, compass, GPS and drive state (no events of their own: they
  cost only when something reads them);
- + the command source and motion (the script replaces the fixed request);
- + dead reckoning (Drake's shift register of the encoder counts every 10 ms, folded into
  the pose in Python every 80 ms);
- + the wheel contacts and the tip margin (read by nothing per step yet);
- + the run log (an event every 10 ms; its contact telemetry: the tip margin every row, the
  loads and slip every 0.1 s, made when the log is read on a continuous plant; the run's
  largest tilt is read from its samples);
- the station itself (`Simulation`, physics only), which the last layer should match;
- the station with one Drake-side setting changed (`VARIANTS`);
- the plant alone with as many Python updates per step as the station runs, changing nothing
  (`FLOORS`): reading nothing, reading an abstract input and two state numbers (what the
  station's updates read when they have nothing to do), reading numbers only.

Each row's cost is CPU time per simulated second; the difference from the layer before is
what that layer adds. The rows run interleaved, `repeats` rounds; medians.
"""

import dataclasses as dc
import itertools
import statistics
import time

import numpy as np
from pydrake.common.value import Value
from pydrake.common.yaml import yaml_dump_typed
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder, EventStatus, LeafSystem
from pydrake.systems.primitives import (
    ConstantValueSource,
    ConstantVectorSource,
    MatrixGain,
    TrajectorySource,
    ZeroOrderHold,
)
from pydrake.trajectories import PiecewisePolynomial

from corobot_drake.config import scenario as sc
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.robots import robot_spec
from corobot_drake.simulation import apply_simulator_config
from corobot_drake.station import add_scene
from corobot_drake.systems.contact import add_wheel_contacts
from corobot_drake.systems.dead_reckoning import DeadReckoning
from corobot_drake.systems.drive import CommandSource, DriveController, DriveRequest
from corobot_drake.systems.motion import MotionCommands
from corobot_drake.systems.odometry import add_chassis_poses, add_chassis_states, add_odometry
from corobot_drake.systems.runlog import (
    HELD_PERIOD,
    add_contact_states,
    add_run_log,
    spec_layout,
)
from corobot_drake.systems.servo import add_servo_sign, servo_velocity_sign
from corobot_drake.systems.stability import add_tip_margin
from lab import bench

LAYERS = ("plant alone (the station's desired state replayed)",
          "+ drive controller (request fixed)",
          "+ chassis poses, encoders, compass, GPS, drive state",
          "+ command source and motion (the script)", "+ dead reckoning",
          "+ wheel contacts and tip margin", "+ run log (with the contact telemetry)")
IDLE_UPDATES = 3
"""The station's Python updates per step and robot (drive controller, command source,
motion)."""
IDLE = f"plant alone + {IDLE_UPDATES} Python updates per step that do nothing"
"""A row of the floor the station's design sets: Drake's dispatch of that many Python updates."""
QUIET = (f"plant alone + {IDLE_UPDATES} Python updates per step that read an abstract input "
         "(a request's seq) and two state numbers, and change nothing")
"""The floor with what the station's updates read on their quiet path (a steady drive, a
quiet script, no motion command): Drake's dispatch and pydrake's accessors."""
NUMERIC = (f"plant alone + {IDLE_UPDATES} Python updates per step that read a vector input's "
           "number and two state numbers, and change nothing")
"""The floor of updates whose quiet path reads numbers only (vector ports, discrete state)."""
STATION = "the station (Simulation, physics only)"
VARIANTS = {
    "the station under SAP at 10 ms (the default before CENIC)": sc.SAP_PLANT % 0.01,
    "the station, 7 mm tyre mesh (22 polygons per patch, not 30)":
        f"robots: {{{bench.ROBOT}: {{contact: {{resolution_hint: 0.007}}}}}}",
    "the station, the giant box fixed (no 16-polygon patch with the ground)":
        "world: {bodies: {giant_box: {fixed: true}}}",
}
"""Station rows with one Drake-side setting changed (scenario overrides): what it would save
or cost (docs/performance.md)."""


def _scenario(*overrides: str) -> sc.Scenario:
    return sc.load_scenario(DEFAULT_SCENARIO, overrides=[
        bench.DRIVING, *bench.physics_only_overrides(), *overrides])


def _segments(robot: sc.Robot) -> list[tuple[float, object]]:
    """(start time s, SetPower) of the figure of eight's script (its Waits give the times)."""
    segments, now = [], 0.0
    for command in robot.commands:
        if isinstance(command, sc.Wait):
            now += command.seconds
        else:
            segments.append((now, command))
    return segments


@dc.dataclass
class _Layered:
    simulator: Simulator
    set_command: object
    """set_command(root context, seq, SetPower): what the fixed inputs get at a segment."""


class _Idle(LeafSystem):
    """A Python update every `period` s that does nothing (one number of discrete state)."""

    def __init__(self, period: float):
        super().__init__()
        self.DeclareDiscreteState(1)
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, lambda context, state: None)


class _Quiet(LeafSystem):
    """A Python update every `period` s that reads what the drive's does in a steady drive
    (input `request`, an abstract `DriveRequest`: its seq; its own two numbers of discrete
    state) and reports that it changed nothing; with `numeric`, input `request` is a
    1-vector, the seq alone."""

    def __init__(self, period: float, numeric: bool = False):
        super().__init__()
        self._numeric = numeric
        self._request = (self.DeclareVectorInputPort("request", 1) if numeric
                         else self.DeclareAbstractInputPort("request", Value(DriveRequest())))
        self._mode = self.DeclareDiscreteState(2)
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._update)

    def source(self):
        """A C++ source of the input: a request that never changes."""
        return (ConstantVectorSource([0.0]) if self._numeric
                else ConstantValueSource(Value(DriveRequest())))

    def _update(self, context, discrete_state):
        seq = (self._request.EvalBasicVector(context)[0] if self._numeric
               else self._request.Eval(context).seq)
        mode = context.get_discrete_state(self._mode)
        if seq != mode[0] or mode[1] != 0.0:
            raise RuntimeError("bench_layers: a quiet update found a change")
        return EventStatus.DidNothing()


FLOORS = (IDLE, QUIET, NUMERIC)
"""The rows of the plant alone with `IDLE_UPDATES` Python updates that change nothing
(`build_layers`' `floor`)."""


def build_layers(scenario: sc.Scenario, layers: int, seconds: float = 10.0,
                 idle_updates: int = 0, floor: str = IDLE) -> _Layered:
    """The default scene's plant with the first `layers` of `LAYERS` (1: the plant alone, fed
    the station's desired state over its first `seconds`: `station_desired_state`), and
    `idle_updates` Python updates per physics step that change nothing, as the `FLOORS` row
    `floor` has them (`_Idle`, `_Quiet`)."""
    builder = DiagramBuilder()
    plant, _, _, _, added = add_scene(builder, scenario)  # the station's scene, finalized
    name, robot = next(iter(scenario.robots.items()))
    instance, chassis, joints = added[name]
    spec = robot_spec(robot.robot)
    fixed = {}
    if layers == 1:
        times, values = station_desired_state(scenario, seconds)
        step = sc.physics_step(scenario.plant_config, scenario.simulator_config)
        if sc.continuous_step(scenario.plant_config, scenario.simulator_config):
            # CENIC's step from t_k runs after the drive's update at t_k: it reads what the
            # station's plant reads at t_k+1, before that step's updates.
            values = np.column_stack([values[:, 1:], values[:, -1]])
        # A zero-order hold whose breaks sit half a step before each step: the plant's step
        # at t_k reads sample k whatever the rounding of t_k.
        replay = builder.AddSystem(TrajectorySource(PiecewisePolynomial.ZeroOrderHold(
            np.append(times - step / 2, times[-1] + step / 2),
            np.column_stack([values, values[:, -1]]))))
        builder.Connect(replay.get_output_port(), plant.get_desired_state_input_port(instance))
        if sc.continuous_step(scenario.plant_config, scenario.simulator_config):
            # CENIC steps to the next event: the station's drive ends each step at k x step
            # (Drake's periodic times) and its run log's 10 Hz samples at k x 0.1 (some a
            # rounding error off a step); C++ holds on the same grids give the plant alone
            # those stops.
            zero = builder.AddSystem(ConstantVectorSource([0.0])).get_output_port()
            for period in (step, HELD_PERIOD):
                builder.Connect(zero, builder.AddSystem(ZeroOrderHold(period, 1)).get_input_port())
    else:
        controller = builder.AddSystem(DriveController(robot.drive, spec.sides,
                                                       spec.wheel_radius))
        selector = builder.AddSystem(MatrixGain(plant.MakeStateSelectorMatrix(
            [j.index() for j in joints])))
        builder.Connect(plant.get_state_output_port(), selector.get_input_port())
        builder.Connect(selector.get_output_port(), controller.GetInputPort("wheel_state"))
        desired_state = controller.GetOutputPort("desired_state")
        sign = servo_velocity_sign(scenario.simulator_config)  # as the station: servo.py
        if sign != 1.0:
            fix = add_servo_sign(builder, "servo_sign", sign, desired_state.size())
            builder.Connect(desired_state, fix.get_input_port())
            desired_state = fix.get_output_port()
        builder.Connect(desired_state, plant.get_desired_state_input_port(instance))
        _add_robot_layers(builder, plant, name, robot, spec, chassis, joints, selector,
                          controller, layers, fixed,
                          sc.continuous_step(scenario.plant_config, scenario.simulator_config))
    period = sc.physics_step(scenario.plant_config, scenario.simulator_config)
    for _ in range(idle_updates):
        if floor == IDLE:
            builder.AddSystem(_Idle(period))
        else:
            quiet = builder.AddSystem(_Quiet(period, numeric=floor == NUMERIC))
            builder.Connect(builder.AddSystem(quiet.source()).get_output_port(),
                            quiet.get_input_port())
    diagram = builder.Build()
    simulator = Simulator(diagram)
    apply_simulator_config(scenario, simulator)
    context = simulator.get_mutable_context()

    def set_command(root, seq, command):
        if "request" in fixed:
            port = fixed["request"]
            port.FixValue(port.get_system().GetMyMutableContextFromRoot(root),
                          DriveRequest(seq, command, root.get_time()))

    set_command(context, 1, _segments(robot)[0][1])
    simulator.Initialize()
    return _Layered(simulator, set_command)


def warmed_up(row: str, scenario: sc.Scenario, warm_up: float, seconds: float):
    """Builds `row` (`STATION`, a `LAYERS` row or a `FLOORS` row) of `scenario`, simulates
    `warm_up` s now, and returns a function that simulates the next `seconds` (a layer row
    keeps the figure of eight's first request: its first segment's 3 s only)."""
    if row == STATION:
        from corobot_drake.simulation import Simulation

        sim = Simulation(scenario)
        sim.advance(warm_up)
        return lambda: sim.advance(seconds)
    if row in FLOORS:
        simulator = build_layers(scenario, 1, warm_up + seconds, IDLE_UPDATES, floor=row).simulator
    else:
        simulator = build_layers(scenario, LAYERS.index(row) + 1, warm_up + seconds).simulator
    simulator.AdvanceTo(warm_up)
    return lambda: simulator.AdvanceTo(warm_up + seconds)


_RECORDED = {}
"""{(scenario YAML, seconds): `station_desired_state`}: recorded once per process."""


def station_desired_state(scenario: sc.Scenario, seconds: float) -> tuple[np.ndarray, np.ndarray]:
    """(times [n], values [8, n]): the desired state the station's plant reads at each of
    its steps over `seconds` of the scenario (its drive's output, after the servo sign), read
    between steps: the Simulator handles a step's updates at the start of the next advance."""
    key = (yaml_dump_typed(scenario, schema=sc.Scenario), seconds)
    if key not in _RECORDED:
        _RECORDED[key] = _record_desired_state(scenario, seconds)
    return _RECORDED[key]


def _record_desired_state(scenario: sc.Scenario, seconds: float):
    from corobot_drake.simulation import Simulation

    sim = Simulation(scenario)
    plant = sim.station.plant
    port = plant.get_desired_state_input_port(sim.station.robots[bench.ROBOT].model_instance)
    context = plant.GetMyContextFromRoot(sim.context)
    step = sc.physics_step(scenario.plant_config, scenario.simulator_config)
    times = np.arange(round(seconds / step) + 1) * step
    values = [port.Eval(context)]  # before the first step's updates (not an advance to 0)
    for t in times[1:]:
        sim.advance_to(t)
        values.append(port.Eval(context))
    return times, np.column_stack(values)


def _add_robot_layers(builder, plant, name, robot, spec, chassis, joints, selector, controller,
                      layers, fixed, continuous_step: float) -> None:
    """Layers 3 and up of `LAYERS`, wired as `station.build_station` wires them, for the
    robot's `spec` (`robots.RobotSpec`; `continuous_step`: `scenario.continuous_step`)."""
    if layers < 3:
        fixed["request"] = controller.GetInputPort("request")
        return
    pose = add_chassis_poses(builder, plant, {name: chassis})[name]
    state = add_chassis_states(builder, plant, {name: chassis})[name]
    odometry = add_odometry(builder, name, pose, selector.get_output_port(),
                            controller.GetOutputPort("drive_status"),
                            controller.GetOutputPort("axle_speed"),
                            robot.drive.motor_torque_scaling, spec)
    if layers < 4:
        fixed["request"] = controller.GetInputPort("request")
        return
    source = builder.AddSystem(CommandSource(robot.commands, robot.drive.control_period))
    motion = builder.AddSystem(MotionCommands(robot.drive, robot.motion, spec.wheel_radius,
                                              spec.spin_yaw_per_rim_speed))
    builder.Connect(source.GetOutputPort("request"), motion.GetInputPort("request"))
    builder.Connect(odometry.position, motion.GetInputPort("position"))
    builder.Connect(odometry.heading, motion.GetInputPort("heading"))
    builder.Connect(motion.GetOutputPort("drive_request"), controller.GetInputPort("request"))
    builder.Connect(motion.GetOutputPort("command_status"), source.GetInputPort("command_status"))
    if layers >= 5:
        dead_reckoning = builder.AddSystem(DeadReckoning(
            robot.drive, robot.drive.control_period, spec.encoder_ticks_per_revolution))
        builder.Connect(odometry.encoder_ticks, dead_reckoning.GetInputPort("encoder_ticks"))
        builder.Connect(pose, dead_reckoning.GetInputPort("chassis_pose"))
    if layers >= 6:
        contacts = add_wheel_contacts(builder, name, plant, [j.child_body() for j in joints],
                                      pose, selector.get_output_port(), chassis,
                                      continuous_step, spec.wheel_radius)
        add_tip_margin(
            builder, name, plant, chassis.model_instance(), chassis,
            {w: j.child_body() for w, j in zip(spec.wheel_names, joints, strict=True)}, pose,
            spec.wheel_radius, spec.caster_points)
    if layers >= 7:
        layout = spec_layout(spec)
        add_run_log(builder, name, state, controller.GetOutputPort("drive_status"),
                    odometry.encoder_ticks,
                    {port: contacts.GetOutputPort(port) for port, _ in layout.sampled},
                    held_when_read=bool(continuous_step), layout=layout)
        if continuous_step:
            add_contact_states(builder, plant, [name])


def _cpu_seconds(layers: int | None, scenario: sc.Scenario, seconds: float,
                 idle_updates: int = 0, floor: str = IDLE) -> float:
    """CPU s to simulate `seconds` of the figure of eight with the first `layers` of `LAYERS`
    (None: the station itself) and `idle_updates`, `floor` (`build_layers`), building
    excluded."""
    if layers is None:
        from corobot_drake.simulation import Simulation

        sim = Simulation(scenario)
        start = time.process_time()
        sim.advance(seconds)
        return time.process_time() - start
    built = build_layers(scenario, layers, seconds, idle_updates, floor)
    context = built.simulator.get_mutable_context()
    segments = [*_segments(scenario.robots[bench.ROBOT]), (seconds, None)]
    start = time.process_time()
    for seq, ((t0, command), (t1, _)) in enumerate(itertools.pairwise(segments), start=1):
        if t0 >= seconds:
            break
        if seq > 1:
            built.set_command(context, seq, command)
        built.simulator.AdvanceTo(min(t1, seconds))
    return time.process_time() - start


def layer_costs(seconds: float, repeats: int, progress=None) -> dict[str, tuple[float, float]]:
    """{row (`LAYERS`, `STATION`, `VARIANTS`, `FLOORS`): (median, least) CPU ms per simulated
    second}; the rows run in turn, `repeats` rounds. The least is the run least disturbed by
    other work on a shared machine (contention only adds CPU time: cache and memory bandwidth).
    `progress()` is called after each run."""
    rows = [(name, i + 1, _scenario(), 0, IDLE) for i, name in enumerate(LAYERS)]
    rows += [(STATION, None, _scenario(), 0, IDLE)]
    rows += [(name, None, _scenario(override), 0, IDLE) for name, override in VARIANTS.items()]
    rows += [(name, 1, _scenario(), IDLE_UPDATES, name) for name in FLOORS]
    runs = {name: [] for name, *_ in rows}
    for _ in range(repeats):
        for name, layers, scenario, idle, floor in rows:
            runs[name].append(
                _cpu_seconds(layers, scenario, seconds, idle, floor) / seconds * 1000)
            if progress:
                progress()
    return {name: (statistics.median(values), min(values)) for name, values in runs.items()}
