"""This checkout against another (an older commit's) on this machine, interleaved.

Each round runs every case once in a fresh process per checkout, old then new, so a change
of the host's load falls on both; the table gives each case's median over the rounds, wall
real-time factor (CPU-time one in parentheses), and new / old. The other checkout is any
directory holding a `corobot_drake` package with the same `analysis.bench` and `gym.bench`
functions, e.g. `git worktree add /tmp/old 268a52c`; it runs on this interpreter and its own
default scenario.

    python tools/bench_compare.py --old /tmp/old --rounds 5
    python tools/bench_compare.py --old /tmp/old --new-override "{plant_config: ...}"
"""

import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

from corobot_drake.arguments import ToolParser, bounded, one_line_errors
from corobot_drake.limits import Range

REPO = Path(__file__).resolve().parent.parent
IMPORT_BENCH = ("try:\n    from lab import bench\n"
                "except ImportError:  # a checkout from before the lab left the package\n"
                "    from corobot_drake.analysis import bench\n")
"""The benchmarks' module in either checkout."""
DRIVE_TEST = "20-seed drive tests per hour (3 loops, 2 Ray workers: tools/drive_test.py)"
READING = ("full stack, each camera frame read as it comes out (a consumer: looked for every "
           "10 ms, as lab.bench_camera.advance_reading)")
CASES = {
    "physics only": IMPORT_BENCH +
                    "r = bench.realtime_factor([*bench.physics_only_overrides(), *{overrides}], "
                    "{seconds})\n"
                    "print(json.dumps({{'wall': r[0], 'cpu': r[1]}}))",
    "full stack (2 IR at 20 Hz + camera at 30 Hz)":
        IMPORT_BENCH +
        "r = bench.realtime_factor([*bench.sensor_overrides(ir=True, camera=True), "
        "*{overrides}], {seconds})\n"
        "print(json.dumps({{'wall': r[0], 'cpu': r[1]}}))",
    READING:
        IMPORT_BENCH +
        "import time\n"
        "from corobot_drake.config.scenario import load_scenario\n"
        "from corobot_drake.resources import DEFAULT_SCENARIO\n"
        "from corobot_drake.simulation import Simulation\n"
        "sim = Simulation(load_scenario(DEFAULT_SCENARIO, overrides=[bench.DRIVING, "
        "*bench.sensor_overrides(ir=True, camera=True), *{overrides}]))\n"
        "robot, last = sim.robot(), None\n"
        "wall, cpu = time.perf_counter(), time.process_time()\n"
        "for _ in range(round({seconds} / 0.01)):\n"
        "    sim.advance(0.01)\n"
        "    taken = robot.camera_image_time()\n"
        "    if taken != last:\n"
        "        robot.camera_image()\n"
        "        last = taken\n"
        "print(json.dumps({{'wall': {seconds} / (time.perf_counter() - wall), "
        "'cpu': {seconds} / (time.process_time() - cpu)}}))",
    "gym env steps per s (one env, in process)":
        "import functools\nimport time\nimport corobot_drake.gym.env as gym_env\n"
        "from corobot_drake.config.scenario import load_scenario\n"
        "base = gym_env.base_scenario\n"
        "gym_env.base_scenario = lambda c: functools.reduce(\n"
        "    lambda s, text: load_scenario(data=text, defaults=s), {overrides}, base(c))\n"
        "from corobot_drake.gym.env import GoToGoalEnv\n"
        "env = GoToGoalEnv()\nenv.reset(seed=0)\nenv.action_space.seed(0)\n"
        "wall, cpu = time.perf_counter(), time.process_time()\n"
        "for _ in range({steps}):\n"
        "    _, _, terminated, truncated, _ = env.step(env.action_space.sample())\n"
        "    if terminated or truncated:\n        env.reset()\n"
        "print(json.dumps({{'wall': {steps} / (time.perf_counter() - wall), "
        "'cpu': {steps} / (time.process_time() - cpu)}}))",
    DRIVE_TEST:
        "import subprocess, sys, tempfile, time\n"
        "with tempfile.TemporaryDirectory() as out:\n"
        "    wall = time.perf_counter()\n"
        "    subprocess.run([sys.executable, 'tools/drive_test.py', '--loops', '3', '--seeds',\n"
        "                    '20', '--workers', '2', '--out', out, '--plot', out + '/d.png',\n"
        "                    *[a for o in {overrides} for a in ('--override', o)]],\n"
        "                   check=True, capture_output=True)\n"
        "print(json.dumps({{'wall': 3600 / (time.perf_counter() - wall), 'cpu': None}}))",
}
"""Case -> the Python its process runs (printing one JSON line {wall, cpu}: rates, higher is
faster; cpu None where the work is in other processes); `{overrides}`: the checkout's
scenario overrides (a list's repr)."""
DEFAULT_CASES = tuple(c for c in CASES if c != DRIVE_TEST)
"""The cases run unless `--cases` names others (the drive test takes minutes a run)."""


def run_case(checkout: Path, case: str, seconds: float, steps: int,
             overrides: list[str] = ()) -> dict:
    """One run of `case` in a fresh process on `checkout` (its directory first on the path),
    its scenario with `overrides` (YAML texts) merged on top."""
    code = "import json\n" + CASES[case].format(seconds=seconds, steps=steps,
                                                 overrides=repr(list(overrides)))
    env = {**os.environ, "PYTHONPATH": str(checkout)}
    done = subprocess.run([sys.executable, "-c", code], cwd=checkout, env=env,
                          capture_output=True, text=True, check=False)
    if done.returncode != 0:
        tail = (done.stderr.strip().splitlines() or ["no output"])[-1]
        raise RuntimeError(f"{case} on {checkout}: {tail}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def compare(old: Path, rounds: int, seconds: float, steps: int, cases=DEFAULT_CASES,
            new_overrides: list[str] = (), progress=None) -> dict:
    """{case: {"old": [runs], "new": [runs]}} of `cases`, `rounds` interleaved rounds; this
    checkout's runs with `new_overrides`."""
    runs = {case: {"old": [], "new": []} for case in cases}
    for _ in range(rounds):
        for case in cases:
            for label, checkout, overrides in (("old", old, ()),
                                               ("new", REPO, new_overrides)):
                runs[case][label].append(run_case(checkout, case, seconds, steps, overrides))
                if progress:
                    progress(f"{case}, {label}: {runs[case][label][-1]['wall']:.2f}")
    return runs


def _median(values: list) -> float | None:
    return None if None in values else statistics.median(values)


def _ratio(new: float | None, old: float | None) -> float | None:
    return None if new is None or old is None else new / old


def _cpu(value: float | None, unit: str = "") -> str:
    """" (CPU)" of a table cell; nothing where the case has no CPU figure."""
    return "" if value is None else f" ({value:.2f}{unit})"


def table(runs: dict) -> str:
    lines = ["| case | old, wall (CPU), median | new, wall (CPU), median | new / old, wall "
             "(CPU) |", "|---|---|---|---|"]
    for case, by in runs.items():
        median = {label: [_median([r[key] for r in by[label]]) for key in ("wall", "cpu")]
                  for label in ("old", "new")}
        o, n = median["old"], median["new"]
        lines.append(f"| {case} | {o[0]:.2f}{_cpu(o[1])} | {n[0]:.2f}{_cpu(n[1])} | "
                     f"{n[0] / o[0]:.2f}x{_cpu(_ratio(n[1], o[1]), 'x')} |")
    return "\n".join(lines)


@one_line_errors
def main(argv=None) -> int:
    parser = ToolParser(description=__doc__.splitlines()[0])
    parser.add_argument("--old", type=Path, required=True,
                        help="the other checkout (a directory with corobot_drake/)")
    parser.add_argument("--rounds", type=bounded(Range(1, 100), int), default=5,
                        help="interleaved rounds; medians")
    parser.add_argument("--seconds", type=bounded(Range(0.5, 600)), default=5.0,
                        help="simulated s per real-time-factor run")
    parser.add_argument("--steps", type=bounded(Range(10, 100000), int), default=100,
                        help="gym env steps per run")
    parser.add_argument("--cases", help="only cases containing this text (None: all)")
    parser.add_argument("--new-override", action="append", default=[],
                        help="scenario YAML merged on this checkout's runs (repeatable), e.g. "
                             "SAP: \"{plant_config: {time_step: 0.01}, simulator_config: "
                             "{integration_scheme: runge_kutta3}}\"")
    args = parser.parse_args(argv)
    if not (args.old / "corobot_drake").is_dir():
        parser.error(f"argument --old: {args.old} holds no corobot_drake/ package")
    cases = [c for c in (CASES if args.cases else DEFAULT_CASES)
             if not args.cases or args.cases in c]
    if not cases:
        parser.error(f"argument --cases: {args.cases!r} is in none of: {', '.join(CASES)}")
    runs = compare(args.old.resolve(), args.rounds, args.seconds, args.steps, cases,
                   args.new_override,
                   progress=lambda text: print(text, file=sys.stderr, flush=True))
    from lab.bench import machine

    print(f"machine: {machine()}; {args.rounds} interleaved rounds, {args.seconds:g} s per "
          f"real-time factor, {args.steps} gym steps\n")
    print(table(runs))
    return 0


if __name__ == "__main__":
    sys.exit(main())
