"""The command line's ROS 2 front end: `--ros2` (the live node), `--ros2-network`, `--rosbag`.

`Ros2Front` makes what the flags ask for (the node, the bag) and the station's `extras` that
publish on them; `run_live` runs a scenario in real time with the node taking commands (the
simulation in a `serving.runner.SimRunner`, as `--serve` runs it), `attach` joins the node to
`--serve`'s runner. Imported only when a flag asks for it.
"""

from __future__ import annotations

import contextlib
import sys
from functools import partial
from pathlib import Path

from corobot_drake.extras import install_hint

EXTRA_HINT = install_hint("ros2")
INTERFACES_HINT = "python -m corobot_drake.ros2.build (tools/setup runs it)"


def missing(flag: str, live: bool) -> str | None:
    """Why `flag` cannot run here (one line, for `error: ...`), else None: the [ros2] extra
    (rclpy and Fast DDS for the live node; rosbags for a bag) and, live, the interface
    packages built into the environment and ROS 2's environment variables
    (`graph.environment_problem`)."""
    modules = ("rclpy", "rosbags") if live else ("rosbags",)
    for module in modules:
        try:
            __import__(module)
        except ImportError:
            return f"{flag} needs the [ros2] extra: {EXTRA_HINT}"
    if live:
        for package in ("tf2_msgs", "simulation_interfaces", "corobot_interfaces"):
            try:
                __import__(f"{package}.msg")
            except ImportError:
                return f"{flag} needs the {package} interfaces built: {INTERFACES_HINT}"
        from corobot_drake.ros2.graph import environment_problem

        problem = environment_problem()
        if problem:
            return f"{flag}: {problem}"
    return None


class Ros2Front(contextlib.ExitStack):
    """The node (`args.ros2`) and the bag (`args.rosbag`) of a run, closed on leaving the
    block (the node shut down, the bag's metadata written); `extras` for the Simulation;
    `finished` once closed."""

    def __init__(self, args, robots: list[str]):
        super().__init__()
        from corobot_drake.ros2.bus import Bus
        from corobot_drake.ros2.publishers import add_ros2_topics

        self.robots = robots
        self.node = None
        self.bag = None
        self.runner = None
        sinks = []
        if args.rosbag is not None:
            from corobot_drake.ros2.bag import BagSink

            self.bag = BagSink(args.rosbag)
            self.callback(self.bag.close)
            sinks.append(self.bag)
        if args.ros2:
            from corobot_drake.ros2.node import Ros2Node

            try:
                self.node = Ros2Node(network=args.ros2_network,
                                     ros_args=getattr(args, "ros_args", ()))
            except ValueError:  # a parameter's value (one line): the bag closed too
                self.close()
                raise
            self.callback(self.node.close)
            sinks.append(self.node.sink)
        self.bus = Bus(sinks)
        settings = self.node.settings if self.node is not None else None  # a bag: defaults
        self.extras = [partial(add_ros2_topics, self.bus, settings=settings)]

    @property
    def finished(self) -> bool:
        """False when the bag could not be written whole (the disk filled: one line said so,
        and it holds what was written before)."""
        return self.bag is None or not self.bag.failed

    def attach(self, runner) -> None:
        """Joins the node to `runner` (before it starts) and starts it spinning."""
        self.runner = runner
        self.node.attach(runner, self.robots)
        self.node.start()
        self.announce()

    def realtime_factor(self, sim) -> float | None:
        """In the simulation thread: the simulated over the wall-clock seconds the runner has
        run `sim` (its pacing and pauses included: the rate the run went at, not the compute
        time's `Simulation.realtime_factor`); None before it runs."""
        import math
        import time

        runner = self.runner
        if runner is None or not math.isfinite(runner.started_wall):
            return None
        wall = time.perf_counter() - runner.started_wall  # (the runner's clock)
        return (sim.time - runner.started_sim) / wall if wall > 0 else None

    def announce(self) -> None:
        """The line that says where the node is (stderr: --serve's first stdout line is its
        URL)."""
        from corobot_drake.ros2.graph import discovery_reach

        domain = self.node.context.get_domain_id()  # rcl's, as it took it
        reach, warnings = discovery_reach(self.node.discovery)
        print(f"ROS 2: node /{self.node.node.get_name()}, ROS_DOMAIN_ID {domain}, discovery "
              f"{reach} (python -m corobot_drake.ros2 list)", file=sys.stderr, flush=True)
        for warning in warnings:
            print(warning, file=sys.stderr, flush=True)


def run_live(front: Ros2Front, make_sim, meshcat: bool, duration: float,
             run_log_window: float | None, finish, rate: float = 1.0, paused: bool = False):
    """Runs the simulation (`make_sim(meshcat or None)`, built in its thread; `make_sim(meshcat,
    scenario=...)` rebuilds it for a spawn) at `rate` x real time (`runner.MAX_RATE`: as fast
    as it can; `paused`: from a pause) with the node attached, until `duration` simulated s
    have passed (a reset starts them again) or Ctrl-C; then returns
    `finish(sim)`, called in the simulation thread (Meshcat, which a replay is written from,
    answers only the thread that made it). What building it raised is raised; a PhysicsError
once `finish` has written the run so far."""
    from corobot_drake.serving.runner import SimulationStoppedError, wait_for
    from corobot_drake.serving.serve import sim_runner
    from corobot_drake.simulation import PhysicsError

    runner = sim_runner(make_sim, meshcat, rate=rate, run_log_window=run_log_window,
                        paused=paused)
    front.attach(runner)
    sys.setswitchinterval(SWITCH_INTERVAL)
    runner.start()
    if runner.meshcat_url:
        print(f"Meshcat: {runner.meshcat_url}", flush=True)
    end = runner.sim.time + duration
    try:
        try:
            wait_for(runner.watch(lambda sim: True if sim.time >= end - 1e-9 else None))
        except KeyboardInterrupt:
            print("\nstopped", file=sys.stderr)
        if runner.alive:
            return _written(runner, finish)
    except SimulationStoppedError:
        pass  # the simulation thread ended: its error is raised below
    finally:
        runner.stop()
    if isinstance(runner.error, PhysicsError):  # a step the physics gave up on: the run so
        finish(runner.sim)  # far is written, from here (the simulation's thread has ended)
    raise runner.error or RuntimeError("the simulation stopped")


def _written(runner, finish):
    """`finish(sim)` in the simulation thread, waited for to its end: the outputs are written
    whole. A stop signal meanwhile (the first, come as the run reached its end: `cli._stop`
    raises once, then records) sets the exit status `finish` returns and is not acted on
    here (the process ending under the simulation thread would cut the files short)."""
    from corobot_drake.serving.runner import wait_for

    done = runner.submit(finish)
    while True:
        try:
            return wait_for(done)
        except KeyboardInterrupt:
            continue


SWITCH_INTERVAL = 0.001
"""s: Python's GIL hand-over interval while the node runs beside the simulation: its callbacks
wait for the GIL at every hand-over (at the default 5 ms, ~6 ms a callback; at 1 ms ~2 ms)."""


def rosbag_problem(path: str) -> str | None:
    from corobot_drake.ros2.bag import bag_problem

    return bag_problem(Path(path))
