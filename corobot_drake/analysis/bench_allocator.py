"""What the allocator setting buys (`python tools/bench.py --allocator`).

glibc reads its setting when a process starts, so each run is a child process of its own
(`python -m corobot_drake.analysis.bench_allocator STACK SECONDS` prints its wall and CPU
real-time factors as JSON), started with `corobot_drake.allocator`'s setting or without it,
the two in turn, `repeats` rounds: the figure of eight at the default plant setting.
"""

import json
import os
import statistics
import subprocess
import sys

from corobot_drake import allocator
from corobot_drake.analysis import bench

SETTINGS = ("glibc's default", f"tcache {allocator.TCACHE_COUNT}")
"""Column names: without and with the setting."""


def _environment(tuned: bool) -> dict[str, str]:
    environ = dict(os.environ)
    environ.pop(allocator.VARIABLE, None)  # the user's own setting would blur the comparison
    return {**environ, **allocator.tuned_environment(environ)} if tuned else environ


def child_realtime_factor(stack: str, seconds: float, tuned: bool) -> tuple[float, float]:
    """(wall, CPU) real-time factors of `stack` (`bench.STACKS`) in a new process."""
    done = subprocess.run([sys.executable, "-m", __name__, stack, str(seconds)],
                          env=_environment(tuned), capture_output=True, text=True, check=True)
    wall, cpu = json.loads(done.stdout.splitlines()[-1])
    return wall, cpu


def compare(stacks: list[str], seconds: float, repeats: int,
            progress=None) -> dict[str, dict[str, tuple[float, float]]]:
    """{stack: {`SETTINGS` name: (wall, CPU) median real-time factors}}; runs in turn."""
    runs = {stack: {name: [] for name in SETTINGS} for stack in stacks}
    for _ in range(repeats):
        for stack in stacks:
            for name, tuned in zip(SETTINGS, (False, True), strict=True):
                runs[stack][name].append(child_realtime_factor(stack, seconds, tuned))
                if progress:
                    progress()
    return {stack: {name: tuple(statistics.median(r[i] for r in values) for i in (0, 1))
                    for name, values in by_setting.items()}
            for stack, by_setting in runs.items()}


if __name__ == "__main__":
    from corobot_drake.simulation import quiet_drake_warnings

    quiet_drake_warnings()
    name, duration = sys.argv[1], float(sys.argv[2])
    print(json.dumps(bench.realtime_factor(
        [bench.PLANTS[bench.DEFAULT_PLANT], *bench.sensor_overrides(bench.ROBOT,
                                                                    **bench.STACKS[name])],
        duration)))
