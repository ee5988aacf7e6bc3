"""Shared helpers: build a simulation of the default scene with overrides; each test's tier.

The tests live in four tiers, a folder each, and each test carries its folder's marker:
`unit` (each system, loader and geometry routine alone: the daily tier, under two minutes
on two cores), `simulation` (the robot measured through whole simulations), `service` (the
front ends as a user meets them: HTTP, browser, recording, CLI, studies, ROS 2) and
`packaging` (the wheel, the tools, the hostile corpus, the docs' blocks). `pytest` runs all;
`pytest tests/unit` (or `-m unit`) the fast tier.

`pytest` runs on every core (pytest-xdist's `--dist loadgroup`, pyproject.toml): the tests of a
module that share one of its module-scoped fixtures (a served simulation, a browser) go to one
worker, in file order, so the fixture is built once; the modules that share a session-scoped
one (`ray_head`) go to one worker together; every other test goes wherever a core is free. A
module may name its group itself (`pytestmark = pytest.mark.xdist_group(NAME)`). The tests
marked `realtime` (they wait on something running in real time: the ROS 2 nodes, one DDS graph
at a time; the Meshcat page) go to one worker and run while no other worker runs a test.

A test module must stop every process it starts: each worker checks, as each module ends, that
no child process it did not have before is still running (the session's fixtures' processes
apart), and at the session's end that none is left at all.
"""

import fcntl
import importlib.util
import os
import shutil
import tempfile
import time
from pathlib import Path

import pytest

from corobot_drake.config.scenario import CENIC_PLANT, SAP_PLANT, load_scenario
from corobot_drake.resources import DEFAULT_SCENARIO
from corobot_drake.simulation import Simulation, quiet_drake_warnings
from lab.processes import children_by_parent, descendants

REPO = Path(__file__).resolve().parent.parent


def load_tool(name: str):
    """The module of `tools/<name>.py` (the tools are scripts, not a package)."""
    spec = importlib.util.spec_from_file_location(f"{name}_tool", REPO / "tools" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module

quiet_drake_warnings()

TIERS = ("unit", "simulation", "service", "packaging")

CHILD_EXIT_SECONDS = 15.0
"""s a module's stopped child processes get to exit before the module fails for them."""


@pytest.hookimpl(tryfirst=True)  # before pytest-xdist's, which reads the groups
def pytest_collection_modifyitems(items):
    groups = {}  # module -> its worker group (None: its tests go anywhere)
    for item in items:
        tier = item.path.parent.name
        if tier not in TIERS:
            raise pytest.UsageError(f"{item.path}: a test file belongs in one of the tiers' "
                                    f"folders: {', '.join(f'tests/{t}/' for t in TIERS)}")
        item.add_marker(tier)
        if item.get_closest_marker("realtime"):  # one worker, so one module's fixtures at a time
            item.add_marker(pytest.mark.xdist_group("realtime"))
        shared = _shared_fixtures(item)
        if shared and groups.get(item.path) is None:
            groups[item.path] = f"{tier}/{item.path.name}"
        if any(d.scope == "session" for d in shared):  # shared with other modules' tests
            groups[item.path] = next(d.argname for d in shared if d.scope == "session")
    for item in items:
        if (not item.get_closest_marker("xdist_group") and _shared_fixtures(item)
                and groups.get(item.path)):
            item.add_marker(pytest.mark.xdist_group(groups[item.path]))


def pytest_collection_finish(session):
    """A worker whose grouped tests lost their group (`--dist loadgroup` has pytest-xdist add
    `@group` to their ids) stops the run: it would share fixtures and DDS across workers."""
    if not (session.config.getoption("loadgroup", False) and session.items):
        return
    lost = [item.nodeid for item in session.items
            if item.get_closest_marker("xdist_group") and "@" not in item.nodeid]
    if lost:
        raise pytest.UsageError(f"pytest-xdist did not group {len(lost)} tests (e.g. {lost[0]}):"
                                " pytest 9.2 with pytest-xdist 3.8 (pytest-dev/pytest-xdist#1386)"
                                "; tools/setup installs a pair that works")


def _shared_fixtures(item) -> list:
    """The fixtures of the tests' own that the test uses and that outlive it (module scope
    or wider): the module's other tests share them (session scope: other modules' too)."""
    info = getattr(item, "_fixtureinfo", None)
    if info is None:
        return []
    return [defs[-1] for defs in info.name2fixturedefs.values()
            if defs[-1].scope != "function" and defs[-1].baseid.startswith("tests")
            and not defs[-1].argname.startswith("_")]


# --- real-time tests alone on the machine -----------------------------------------------


_LOCKS = "COROBOT_TEST_LOCKS"
"""Environment: the folder of the workers' lock files, made by the controller."""


def pytest_configure(config):
    if os.environ.get("PYTEST_XDIST_WORKER") is None and config.getoption("numprocesses",
                                                                           None):
        _check_grouping(config)
        os.environ[_LOCKS] = tempfile.mkdtemp(prefix="corobot-tests-")  # the workers inherit it


def _check_grouping(config) -> None:
    """pytest 9.2's structured node ids make pytest-xdist up to 3.8 group nothing under
    `--dist loadgroup` (pytest-dev/pytest-xdist#1386): modules would share fixtures and DDS
    across workers. (`pytest_collection_finish` checks what the workers got.)"""
    import xdist
    from packaging.version import Version

    if (config.getoption("dist", None) == "loadgroup"
            and Version(pytest.__version__) >= Version("9.2")
            and Version(xdist.__version__) <= Version("3.8")):
        raise pytest.UsageError(f"pytest {pytest.__version__} with pytest-xdist "
                                f"{xdist.__version__} does not group tests "
                                "(pytest-dev/pytest-xdist#1386): run tools/setup, or -n 0")


def pytest_unconfigure(config):
    if os.environ.get("PYTEST_XDIST_WORKER") is None and os.environ.get(_LOCKS):
        shutil.rmtree(os.environ.pop(_LOCKS), ignore_errors=True)


def _realtime(item) -> bool:
    return item is not None and item.get_closest_marker("realtime") is not None


@pytest.hookimpl(wrapper=True)
def pytest_runtest_protocol(item, nextitem):
    """Under pytest-xdist, a `realtime` test (one that waits on a server, a node or a browser
    running in real time) runs while no other worker runs a test: the other waits, from the
    call of the first of a run of real-time tests to the teardown of the last (their module
    fixtures start and stop beside the other worker's tests). Every other test shares the
    machine."""
    if _realtime(item):
        return (yield)
    _Machine.take(exclusive=False)
    try:
        return (yield)
    finally:
        _Machine.give_back()


@pytest.hookimpl(wrapper=True)
def pytest_runtest_call(item):
    if _realtime(item) and not _Machine.exclusive:
        _Machine.take(exclusive=True)
    return (yield)


@pytest.hookimpl(wrapper=True)
def pytest_runtest_teardown(item, nextitem):
    if _realtime(item) and not _realtime(nextitem):
        _Machine.give_back()
    return (yield)


class _Machine:
    """A readers-writer lock between the xdist workers (flock on two files): `exclusive` for
    real-time tests, shared for the rest. The turnstile keeps a waiting exclusive taker from
    being passed by shared ones. A no-op in one process."""

    exclusive = False
    _files: tuple | None = None

    @classmethod
    def take(cls, exclusive: bool) -> None:
        if cls._files is None:
            folder = os.environ.get(_LOCKS)
            if os.environ.get("PYTEST_XDIST_WORKER") is None or folder is None:
                return
            cls._files = tuple(open(Path(folder) / name, "a")  # noqa: SIM115 (kept open)
                               for name in ("turnstile", "machine"))
        turnstile, machine = cls._files
        fcntl.flock(turnstile, fcntl.LOCK_EX)
        try:
            fcntl.flock(machine, fcntl.LOCK_EX if exclusive else fcntl.LOCK_SH)
        finally:
            fcntl.flock(turnstile, fcntl.LOCK_UN)
        cls.exclusive = exclusive

    @classmethod
    def give_back(cls) -> None:
        if cls._files is not None:
            fcntl.flock(cls._files[1], fcntl.LOCK_UN)
        cls.exclusive = False


# --- no process left running ------------------------------------------------------------


SESSION_PROCESSES: set[int] = set()
"""Processes that session-scoped fixtures started (with their descendants: e.g. Ray's
workers): they stop at the session's end, not at a module's."""


def _children(skip: set[int] = frozenset()) -> dict[int, str]:
    """The running processes descended from this one (pid: command line), zombies left out,
    and the trees of `skip` left out."""
    found = {}
    for child in descendants(os.getpid(), children_by_parent(zombies=False), skip):
        try:
            command = Path(f"/proc/{child}/cmdline").read_bytes()
        except OSError:
            continue
        found[child] = command.replace(b"\0", b" ").decode(errors="replace")[:200]
    return found


def _process_helpers() -> set[int]:
    """The helpers that live as long as this process, by design: the private X server
    (`xdisplay`) and multiprocessing's resource tracker (started by a spawned child's first
    semaphore, e.g. Gymnasium's AsyncVectorEnv's)."""
    from multiprocessing import resource_tracker

    from corobot_drake.sensors import xdisplay

    helpers = {getattr(resource_tracker._resource_tracker, "_pid", None)}
    helpers.add(None if xdisplay._xvfb is None else xdisplay._xvfb.pid)
    return helpers - {None}


def _left_running(before: set[int], skip: set[int]) -> dict[int, str]:
    """The child processes not in `before` (nor in the trees of `skip`, nor the process's
    helpers) still running once they have had `CHILD_EXIT_SECONDS` to exit."""
    deadline = time.monotonic() + CHILD_EXIT_SECONDS
    while True:  # a process stopped at the end may take a moment to exit
        left = {pid: command for pid, command in _children(skip).items()
                if pid not in before and pid not in _process_helpers()}
        if not left or time.monotonic() > deadline:
            return left
        time.sleep(0.1)


def _fail_for(what: str, left: dict[int, str]) -> None:
    if left:
        pytest.fail(f"{what} left child processes running: "
                    + "; ".join(f"{pid} {command}" for pid, command in left.items()),
                    pytrace=False)


@pytest.fixture(scope="session", autouse=True)
def _no_child_process_left_at_the_end():
    """Fails the session's last test (at its teardown) if a child process of this pytest
    process is still running when every fixture has stopped what it started."""
    before = set(_children())
    yield
    _fail_for("the session", _left_running(before, set()))


@pytest.fixture(scope="module", autouse=True)
def _no_child_process_left_running(request):
    """Fails the module's last test (at its teardown) if the module left a child process of
    this pytest process running: a test stops what it starts, by its handle."""
    before = set(_children())
    yield
    _fail_for(request.node.nodeid, _left_running(before, SESSION_PROCESSES))


# --- shared by modules ------------------------------------------------------------------


@pytest.fixture(scope="session")
def ray_head():
    """A Ray head (2 CPUs, no dashboard, its own processes) for the session's tests on Ray
    (tests/service/test_study.py, tests/simulation/test_gym.py: one worker runs both). Its
    users join it by address, or connect this process, and leave it as they found it: not
    connected. Shut down through its handle at the session's end. On loopback only, as the
    study engine's own instances (`loopback_ray`, held for the session: joining it by its
    address needs it too)."""
    ray = pytest.importorskip("ray")
    from ray.cluster_utils import Cluster

    from corobot_drake.study.engine import loopback_ray

    assert not ray.is_initialized()
    # A head that ray.init did not start reports to Ray's usage server even that reports are
    # off: here to a loopback port nothing can listen on (the connection is refused).
    with loopback_ray(RAY_USAGE_STATS_REPORT_URL="http://127.0.0.1:0/"):
        before = set(_children())
        cluster = Cluster(initialize_head=True, head_node_args={
            "num_cpus": 2, "include_dashboard": False})
        started = set(_children()) - before
        SESSION_PROCESSES.update(started)
        yield cluster
        if ray.is_initialized():
            ray.shutdown()
        cluster.shutdown()
        SESSION_PROCESSES.difference_update(started)


SAP = SAP_PLANT % 0.01
"""Override: SAP's discrete plant at 10 ms, for tests of what it does that CENIC does not."""
CENIC = CENIC_PLANT % 0.01
"""Override: the default's CENIC at 10 ms, for tests that compare the two."""


def make_sim(*overrides: str, scenario: Path = DEFAULT_SCENARIO,
             camera: bool = False) -> Simulation:
    """The default scene (or `scenario`) with YAML overrides merged on top.

    The robots' cameras are off unless `camera` (rendering 30 frames per simulated second
    made the drive tests 3x slower); tests of the camera ask for it.
    """
    scenario = load_scenario(scenario, overrides=list(overrides))
    if not camera:
        for robot in scenario.robots.values():
            for config in robot.cameras.values():
                config.rgb = False
    return Simulation(scenario)


@pytest.fixture
def sim() -> Simulation:
    return make_sim()


class Stepper:
    """A Simulator on one system alone whose periodic events have period `period` from 0:
    `tick()` takes the next of them (the k-th, 1-based, happens at (k - 1) period; the
    context then stands half a period later). Fix the inputs on `context` between ticks."""

    def __init__(self, system, period: float):
        from pydrake.systems.analysis import Simulator

        self.system, self.period, self.ticks = system, period, 0
        self.simulator = Simulator(system)
        self.context = self.simulator.get_mutable_context()

    def fix(self, port_name: str, value) -> None:
        self.system.GetInputPort(port_name).FixValue(self.context, value)

    def output(self, port_name: str):
        return self.system.GetOutputPort(port_name).Eval(self.context)

    def tick(self, n: int = 1) -> None:
        self.ticks += n
        self.simulator.AdvanceTo((self.ticks - 0.5) * self.period)

    @property
    def last_tick_time(self) -> float:
        """s: when the latest tick happened."""
        return (self.ticks - 1) * self.period


TWO_CAMERAS = ("robots: {corobot: {cameras: {"
               "front: {width: 64, height: 48, output_delay: 0}, "
               "rear: {width: 64, height: 48, output_delay: 0, X_PB: {base_frame: chassis, "
               "translation: [0, 0, 0.5], rotation: !Rpy {deg: [-90, 0, 90]}}}}}}")
"""The robot with a second camera, `rear`, 0.5 m above the chassis looking back (the front
one looks forward from the chassis' front): both 64 x 48, cheap to render, each frame
rendered on the plant's steps from initialization (no output delay)."""
